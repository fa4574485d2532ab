"""A square (TTL) tacho sampled at the vibration's rate (issue 39): each rising edge falls between a low and a high
sample, and the crossing interpolated between them is always mid-way, a timing error uniform on ±0.5 sample in a
pattern set by the fraction of samples per turn. Read through those edges, every order line carried sidebands at
the pattern's spacing, and inspect read them as a shaft's order: on the 23/59 + 19/67 box at 28 Hz, 4 s at 25.6 kHz,
'the wheel on the intermediate shaft shows 80.5 teeth, 59 described'. angle_from_pulses now smooths such edge
times to the quantisation's own variance (1/12 sample²); edges with a sample in the middle of the swing keep
their interpolated times."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import AF_BOX

import gearlab.signals.angle as angle

FS, SPEED, SECONDS = 25_600.0, 28.0, 4.0
BOX = AF_BOX


def ttl(theta: np.ndarray) -> np.ndarray:
    """0/5 V, high for the first tenth of each turn, as a DAQ samples it: the edges on the sample grid."""
    return np.where(np.mod(theta, 2 * np.pi) < 0.2 * np.pi, 5.0, 0.0)


def raw_edges(monkeypatch) -> None:
    """angle_from_pulses as before: the interpolated edge times, unsmoothed."""
    monkeypatch.setattr(angle, "_dequantised", lambda edges, step: edges)


def angle_error(theta: np.ndarray, read: np.ndarray) -> float:
    """rms (rad) of the read angle against the true one, its constant offset removed, away from the ends."""
    err = (read - (theta - theta[0]))[2000:-2000]
    return float(np.std(err))


@pytest.mark.parametrize("speed", [28.0, 35.0, 43.0])
def test_quantised_edges_are_smoothed_to_the_true_angle(speed, monkeypatch):
    theta = 2 * np.pi * speed * (0.2 + np.arange(int(SECONDS * FS)) / FS)
    after = angle_error(theta, angle.angle_from_pulses(ttl(theta), FS))
    raw_edges(monkeypatch)
    before = angle_error(theta, angle.angle_from_pulses(ttl(theta), FS))
    # measured: 1.56 / 1.83 / 2.25 mrad before, 0.29 / 0.35 / 0.06 after
    assert before > 1.4e-3
    assert after < 0.25 * before, (before, after)


def swing(order: float, share: float = 0.02):
    """Time -> turns·(1/33 Hz) of a shaft at 33 Hz whose speed swings by *share* at *order* (per input turn)."""
    w = order * 2 * np.pi * 33.0
    return lambda t: t + share / w * np.sin(w * t)


@pytest.mark.parametrize(
    "course",
    [
        pytest.param(lambda t: t + 0.1 * (t - 0.2) ** 2 / (2 * SECONDS), id="run-up 10 %"),
        pytest.param(swing(0.3), id="2 % at 0.3 order"),
        pytest.param(swing(0.05), id="2 % at 0.05 order"),
    ],
)
def test_a_real_speed_course_is_still_followed(course, monkeypatch):
    """A run-up and real speed swings, 10-50 times the quantisation, are kept: the angle's error is no larger than
    with the raw edges (the 0.3-order swing is as far off between edges with exact edges: 14 mrad, one mark a turn)."""
    theta = 2 * np.pi * 33.0 * course(0.2 + np.arange(int(SECONDS * FS)) / FS)
    after = angle_error(theta, angle.angle_from_pulses(ttl(theta), FS))
    raw_edges(monkeypatch)
    before = angle_error(theta, angle.angle_from_pulses(ttl(theta), FS))
    # measured: run-up 2.10 -> 0.72 mrad, 0.3 order 14.24 -> 14.87, 0.05 order 3.22 -> 3.24
    assert after < 1.06 * before, (before, after)


@pytest.mark.parametrize("kind", ["cosine", "ramped"])
def test_edges_with_a_sample_mid_swing_keep_their_interpolated_times(kind, monkeypatch):
    """A cosine tacho, and the simulator's pulses (a two-sample ramp through the mid-level), are read as before:
    the smoothing is not reached, so the angle is the interpolated one bit for bit."""
    from gearlab.data.simulated import tacho_pulses

    def never(edges, step):
        raise AssertionError("smoothed edges that are not quantised")

    monkeypatch.setattr(angle, "_dequantised", never)
    theta = 2 * np.pi * 33.0 * (0.2 + np.arange(int(SECONDS * FS)) / FS)
    pulses = 2.5 - 2.5 * np.cos(theta) if kind == "cosine" else tacho_pulses(theta, 2 * np.pi * 33.0 / FS)
    assert angle_error(theta, angle.angle_from_pulses(pulses, FS)) < 1e-4


def test_a_tacho_of_several_marks_a_turn_keeps_its_interpolated_edges(monkeypatch):
    """Several marks a turn off equal spacing (the PHM rig's 10, here 2 % of a mark's pitch: 1.6 samples) keep their
    quantised edges: smoothed each mark apart, the rig's eccentric-idler take at 40 Hz low load scored above its
    chipped takes (angle_from_pulses). Equally spaced marks' are smoothed as one sequence
    (test_which_gear_square_tacho), and a once-a-turn tacho's."""
    calls = []
    monkeypatch.setattr(angle, "_dequantised", lambda edges, step: calls.append(edges.size) or edges)
    theta = 2 * np.pi * 33.0 * (0.2 + np.arange(int(SECONDS * FS)) / FS)
    nearest = np.mod(np.floor(10 * theta / (2 * np.pi) + 0.5), 10)  # the mark nearest: changed mid-way, pulse low
    angle.angle_from_pulses(ttl(10 * theta - 2 * np.pi * 0.02 * (np.mod(nearest, 3) - 1)), FS, marks=10)
    assert calls == []
    angle.angle_from_pulses(ttl(10 * theta), FS, marks=10)
    assert calls == [1319], calls
    angle.angle_from_pulses(ttl(theta), FS)
    assert calls == [1319, 132], calls


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    """The box simulated at 28 Hz, 200 kHz, 0.2 s settled, resampled to 25.6 kHz, 30 dB noise, with a TTL tacho."""
    from scipy.signal import resample_poly

    import gearlab

    where = tmp_path_factory.mktemp("ak")
    (where / "gb.toml").write_text(BOX)
    sim = gearlab.simulate_signals(gearbox=where / "gb.toml", duration=0.2 + SECONDS + 0.05, fs=200e3, speed=SPEED)
    acc = resample_poly(sim.channels["casing_x"][sim.t >= 0.2], 16, 125)[: int(SECONDS * FS)]
    acc = acc + np.random.default_rng(28).standard_normal(acc.size) * acc.std() * 10 ** (-30 / 20)
    theta = 2 * np.pi * SPEED * (0.2 + np.arange(acc.size) / FS)
    np.savez(where / "take.npz", acc=acc, tacho=ttl(theta), fs=FS)
    return where


def inspect(where, box="gb.toml"):
    import gearlab

    return gearlab.inspect_recording(where / "take.npz", where / box, vibration="acc", tacho="tacho", unit="m/s^2")


def test_a_ttl_take_read_as_another_wheel_count_now_matches(take, monkeypatch):
    report = inspect(take)
    assert report["check"]["differences"] == [], report["check"]["differences"]
    assert report["matches"] is True
    raw_edges(monkeypatch)  # the same take through the raw edges: the 'wheel of 80 teeth' this file is about
    before = inspect(take)
    assert before["matches"] is False
    assert any("wheel on the intermediate shaft shows 80" in d for d in before["check"]["differences"]), before


@pytest.mark.parametrize(("old", "new"), [("z = 23", "z = 22"), ("z = 59", "z = 58")])
def test_a_count_one_tooth_off_is_still_called_out(take, old, new):
    (take / "off.toml").write_text(BOX.replace(old, new))
    report = inspect(take, "off.toml")
    assert report["matches"] is False
    assert report["check"]["differences"], report["check"]


@pytest.mark.parametrize("teeth", [((23, 59), (19, 67)), ((22, 59), (19, 67)), ((23, 58), (19, 67))])
def test_the_gap_s_structure_check_reads_the_take_alike(take, teeth, monkeypatch):
    """The gap's structure line on the take's revolutions, cut at the tacho as the importer cuts them: the true
    counts pass (the raw edges made a difference of them), one tooth off on the pinion or the first wheel does not."""
    from gearboxes import described_pair

    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line
    from gearlab.signals import resample_revolutions

    take_file = np.load(take / "take.npz")

    def line():
        rows = resample_revolutions(take_file["acc"], angle.angle_from_pulses(take_file["tacho"], FS), points=1024)
        chain = Chain(fs=FS, speed=SPEED, tacho_shaft="input")
        return structure_line(rows, described_pair(*teeth), 400, chain, None, {})

    true = teeth == ((23, 59), (19, 67))
    assert (line() is None) == true
    raw_edges(monkeypatch)
    assert line() is not None
