"""The rows a learned method trains on for damage on a slower shaft's gear: the [corrected] source's
TSA rows of that shaft (the PHM 2009 recipe, `tsa` noisy revolutions averaged as a record unit is).

A fault on the 50T output gear of a 20/30 + 20/50 reducer repeats every 15 input turns. Its steady
cycle was cut to 14 revolutions (rows.turned: 2π·15 / 2π floors to 14.999999999999998 turns, so
the last revolution was not "complete"; cycles of 11, 15, 22, 30 ... turns), and a TSA of 10 output
revolutions (43 input turns) wrapped that cut cycle: the output shaft's angle jumped at each wrap
and the damage was smeared over the turn. On takes simulated by gearlab itself (dev seeds 101-109,
25 dB) the corrected source's networks learned that smear (source AUC 1.00) and scored the chipped
output gear's record10 units at AUC 0.52-0.55; likelihood_ratio and matched_filter built on it
0.42 / 0.46, where the same detectors built on the plain source (one revolution a row) had 0.98 /
0.94."""

from __future__ import annotations

import numpy as np
from gearboxes import SLOW_BOX as BOX
from gearboxes import two_file_detection

from gearlab.data.rows import turned
from gearlab.data.spec import POINTS


def test_a_cycle_of_any_number_of_turns_keeps_all_of_them():
    """turned() makes `revolutions` rows of POINTS from a steady cycle, for every cycle length (before:
    11, 15, 22, 30 turns gave one fewer)."""
    per_rev = 64
    for revolutions in range(1, 41):
        periodic = np.sin(2 * np.pi * np.arange(revolutions * per_rev) / per_rev / revolutions)
        out = turned(periodic, revolutions, 0)
        assert out.size == revolutions * POINTS, (revolutions, out.size / POINTS)


SCENARIO = two_file_detection("slow_rows", 'faults = { "chip@output gear" = [12] }\nteeth = [1, 7, 13]\nhealthy = 2\n')


def test_an_output_gear_chip_keeps_its_shape_in_the_tsa_of_output_revolutions(tmp_path):
    """Noise-free, the TSA of 10 output-shaft revolutions of a chipped output gear differs from its
    first revolution by what the other shafts' turns add, not by the chip: the fault rows less the
    healthy rows (the chip's signature) keep their size and their tooth's angle (before: 0.0023 ->
    0.40 RMS, its peak 3,000 points from the tooth's)."""
    from gearlab.data.builder import build_dataset
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import unit_shaft

    (tmp_path / "box.toml").write_text(BOX)
    for name in ("a.csv", "b.csv"):  # not read: the source alone is built
        (tmp_path / name).write_text("t,acc,tacho\n0,0,0\n")
    (tmp_path / "s.toml").write_text(SCENARIO)
    source = load_scenario(str(tmp_path / "s.toml")).spec.source
    shaft = unit_shaft(source)
    plain = source.with_(unit_shaft=(shaft.ratio.numerator, shaft.ratio.denominator), speed_hz=30.0)
    signatures = {}
    for j in (1, 10):
        ds = build_dataset(plain if j == 1 else plain.with_(tsa=True, revolutions=j))
        fault = ds.fault.astype(bool)
        signatures[j] = ds.X[fault] - ds.X[~fault].mean(axis=0)
    rms = {j: np.sqrt(np.mean(s**2, axis=1)) for j, s in signatures.items()}
    assert np.all(rms[10] < 2 * rms[1]) and np.all(rms[10] > 0.5 * rms[1]), rms
    peaks = {j: np.argmax(np.abs(s), axis=1) for j, s in signatures.items()}
    apart = np.abs((peaks[10] - peaks[1] + POINTS // 2) % POINTS - POINTS // 2)
    assert np.all(apart <= POINTS // 100), peaks  # within 1 % of a turn (a tooth is 2 %)
