"""Outside user AF's 23/59 + 19/67 box at 31 Hz (issue 39): recordings of gearlab's own simulator whose tacho
carried a timing error (its angle resampled: 1.5-9 mrad at 5 and 10 Hz) read 'the wheel shows 71 teeth, 59
described' in inspect and 'structure differs' in the gap diagnosis. The vibration holds no 10 Hz; a tacho's timing
error phase-modulates every line of order k by k phi, and the comb of its 2nd sidebands (0.322) was read as the
intermediate shaft's order. Here AF's take: the box at 31 Hz, 4 s at 25.6 kHz, its tacho 2.5 - 2.5 cos of the
simulator's shaft angle resampled as the vibration is. (A DAQ-sampled TTL tacho's edges on the sample grid did the
same; angle_from_pulses now reads such edges smoothed to their quantisation: tests/test_outside_ak.py.)"""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import AF_BOX, described_pair

FS, SPEED, SECONDS = 25_600.0, 31.0, 4.0
BOX = AF_BOX


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    """The box simulated at 200 kHz, 0.2 s settled, resampled to 25.6 kHz, 30 dB noise; AF's tacho: the simulator's
    input-shaft angle resampled to 25.6 kHz (a timing error of a few mrad, cycling at 5 and 10 Hz), one cosine pulse
    a turn."""
    from scipy.signal import resample_poly

    import gearlab

    where = tmp_path_factory.mktemp("ah")
    (where / "gb.toml").write_text(BOX)
    sim = gearlab.simulate_signals(gearbox=where / "gb.toml", duration=0.2 + SECONDS + 0.05, fs=200e3)
    acc = resample_poly(sim.channels["casing_x"][sim.t >= 0.2], 16, 125)[: int(SECONDS * FS)]
    acc = acc + np.random.default_rng(39).standard_normal(acc.size) * acc.std() * 10 ** (-30 / 20)
    theta = resample_poly(np.unwrap(sim.tacho[sim.t >= 0.2]), 16, 125)[: acc.size]
    tacho = 2.5 - 2.5 * np.cos(theta)
    np.savez(where / "take.npz", acc=acc, tacho=tacho, fs=FS)
    return where, acc, tacho


def test_a_tacho_s_timing_modulation_is_no_shaft_order_in_inspect(take):
    import gearlab

    where, _, _ = take
    report = gearlab.inspect_recording(
        where / "take.npz", where / "gb.toml", vibration="acc", tacho="tacho", unit="m/s^2"
    )
    check = report["check"]
    assert check["differences"] == [], check["differences"]
    assert report["matches"] is True
    assert any("a modulation 0.161" in u and "not that shaft's order" in u for u in check["unresolved"]), check


def test_a_wrong_count_on_that_shaft_is_still_called_out(take):
    # the same take described with a 58-tooth first wheel: no second mesh at 23 x 19 / 58 = 7.534 (it is at 7.407)
    import gearlab

    where, _, _ = take
    (where / "gb58.toml").write_text(BOX.replace("z = 59", "z = 58"))
    report = gearlab.inspect_recording(
        where / "take.npz", where / "gb58.toml", vibration="acc", tacho="tacho", unit="m/s^2"
    )
    assert report["matches"] is False
    assert any("stage 2" in d and "7.534" in d for d in report["check"]["differences"]), report["check"]


def test_the_gap_s_structure_check_searches_effects_on_such_a_take(take):
    """The gap's structure line (first_difference's) on the take's revolutions, cut at the tacho as the importer
    cuts them: no tooth-count difference; the count said unchecked."""
    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line
    from gearlab.signals import angle_from_pulses, resample_revolutions

    _, acc, tacho = take
    rows = resample_revolutions(acc, angle_from_pulses(tacho, FS), points=1024)
    record: dict = {}
    chain = Chain(fs=FS, speed=SPEED, tacho_shaft="input")
    line = structure_line(rows, described_pair((23, 59), (19, 67)), 400, chain, None, record)
    assert line is None, line
    assert "a modulation" in str(record.get("unchecked")), record
