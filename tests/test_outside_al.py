"""Where the revolutions start must not change the structure check (issue 39). gearlab's own 23/59 + 19/67 box at
43 Hz, 4 s at 25.6 kHz, 30 dB noise, read through an exact cosine tacho: with the mark at some shaft angles inspect
said 'the pinion on the intermediate shaft shows 25.1 teeth, 19 described', with others the description matched.
The record carries a weak line at order 29.333 (1261 Hz), 0.2949 under stage 2's 4th mesh harmonic, 14.4-15.3 dB
over the floor: which 171 turns the mark cuts put it over the 15 dB threshold or not, and over it that one line
was a comb (sideband_combs.lone), where 9 lines lie the described 0.3898 off the meshes on that shaft. At 37 Hz,
at every phase, a pair 15.0 Hz either side of the first mesh (17 dB) read 'the wheel shows 56.7 teeth'."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import AF_BOX

from gearlab.gearbox.sideband_combs import lone
from gearlab.gearbox.speed import Lines

FS, SPEED, SECONDS = 25_600.0, 43.0, 4.0
BOX = AF_BOX
# the mark's shaft angles: 0 and pi read 'matches' before, pi/2, 3 pi/4 and 5 pi/4 '25.1 teeth'
PHASES = (0.0, np.pi / 2, 3 * np.pi / 4, 5 * np.pi / 4)


def simulated(where, speed: float) -> np.ndarray:
    """The box simulated at 200 kHz, 0.2 s settled, resampled to 25.6 kHz, 30 dB noise (AK's generator)."""
    from scipy.signal import resample_poly

    import gearlab

    sim = gearlab.simulate_signals(gearbox=where / "gb.toml", duration=SECONDS + 0.25, fs=200e3, speed=speed)
    acc = resample_poly(sim.channels["casing_x"][sim.t >= 0.2], 16, 125)[: int(SECONDS * FS)]
    return acc + np.random.default_rng(int(speed)).standard_normal(acc.size) * acc.std() * 10 ** (-30 / 20)


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    where = tmp_path_factory.mktemp("al")
    (where / "gb.toml").write_text(BOX)
    return where, simulated(where, SPEED)


def inspected(where, acc: np.ndarray, phase: float, box: str = "gb.toml", speed: float = SPEED) -> dict:
    """inspect's report of the take, its tacho an exact cosine whose mark is *phase* off the shaft's zero."""
    import gearlab

    theta = 2 * np.pi * speed * (0.2 + np.arange(acc.size) / FS)
    np.savez(where / "take.npz", acc=acc, tacho=2.5 - 2.5 * np.cos(theta + phase), fs=FS)
    return gearlab.inspect_recording(where / "take.npz", where / box, vibration="acc", tacho="tacho", unit="m/s^2")


@pytest.mark.parametrize("phase", PHASES)
def test_the_description_matches_wherever_the_mark_is(take, phase):
    where, acc = take
    report = inspected(where, acc, phase)
    assert report["check"]["differences"] == [], report["check"]["differences"]
    assert report["matches"] is True


@pytest.mark.parametrize("phase", PHASES[:2])
def test_a_tooth_off_is_still_called_out(take, phase):
    where, acc = take
    (where / "p22.toml").write_text(BOX.replace("z = 23", "z = 22"))
    (where / "w58.toml").write_text(BOX.replace("z = 59", "z = 58"))
    pinion = inspected(where, acc, phase, "p22.toml")
    assert pinion["matches"] is False
    assert any("stage 1" in d and "23 measured, 22 expected" in d for d in pinion["check"]["differences"])
    wheel = inspected(where, acc, phase, "w58.toml")
    assert wheel["matches"] is False
    assert any("stage 2" in d and "7.534" in d for d in wheel["check"]["differences"])


def test_a_pair_of_weak_lines_off_one_mesh_is_no_shaft_order(take):
    where, _ = take
    acc = simulated(where, 37.0)
    report = inspected(where, acc, 0.0, speed=37.0)
    assert report["check"]["differences"] == [], report["check"]["differences"]
    (where / "w58.toml").write_text(BOX.replace("z = 59", "z = 58"))
    wheel = inspected(where, acc, 0.0, "w58.toml", speed=37.0)
    assert wheel["matches"] is False


def comb_lines(extra: list[tuple[float, float]]) -> Lines:
    """A carrier at 29.627 (72 dB), a line 0.2949 under it (15 dB), and *extra* (order, dB) lines."""
    at = np.array([29.627, 29.627 - 0.2949] + [a for a, _ in extra])
    db = np.array([72.0, 15.0] + [d for _, d in extra])
    return Lines(at, 10 ** (db / 20), db)


def test_one_line_outweighed_by_the_described_sidebands_is_no_comb():
    bin_ = 1 / 171
    found = (0.2949, 0.003, 1, {1: 1}, 1.0)  # comb's tuple: one line, the 2nd
    described = [(29.627 - 2 * 0.3898, 22.6), (29.627 + 0.3898, 30.0), (29.627 + 2 * 0.3898, 25.0)]
    assert lone(comb_lines(described), {0}, found, 0.3898, bin_)
    # two described lines are as many as chance puts near any spacing; a comb of three lines is a comb
    assert not lone(comb_lines(described[:2]), {0}, found, 0.3898, bin_)
    assert not lone(comb_lines(described), {0}, (0.2949, 0.003, 3, {1: 1, 2: 2, 3: 3}, 1.0), 0.3898, bin_)
    # ... and the described lines must stand well over the comb's line
    weak = [(a, 18.0) for a, _ in described]
    assert not lone(comb_lines(weak), {0}, found, 0.3898, bin_)
