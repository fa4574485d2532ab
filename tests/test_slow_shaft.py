"""Damage on a slower shaft's gear is detected, not only localised: the detection kind's units are
revolutions (and TSAs) of the watched gear's shaft. A once-per-turn event of a shaft turning 4/15
of the input lands at another input angle every input revolution and an input-shaft TSA averages
it away (before: matched_filter's record10 AUC 0.40 on the takes below, 5 % detected); cut on the
output shaft's angle it comes back to one angle every unit.

The takes are gearlab's simulation of a 20/30 + 20/50 reducer (tacho on the input) with a chip on
tooth 7 of the 50T output gear, step 12, at 25 dB: the records and the source are one simulator,
so the only question is which shaft the units follow. No test here reads the report's figures
(no_figures: 1-2 s of CPU a run, matplotlib's layout and PNGs)."""

from __future__ import annotations

import json
import re
from fractions import Fraction

import numpy as np
import pytest
from gearboxes import SLOW_BOX as BOX

from gearlab.data.simulated import simulated_record

# name: (chip step on the output gear's tooth 7 or None, seed, input revolutions)
TAKES = {
    "hist1": (None, 1, 200),
    "hist2": (None, 2, 200),
    "hist3": (None, 6, 200),
    "test_ok": (None, 3, 200),
    "test_chip": (12, 4, 200),
    "short": (None, 5, 30),  # 8 output revolutions: fewer than record10's 10
}
# Without a tacho on the output shaft its angle is found by turning the history's mean revolution
# onto the source's healthy one, whose meshes (50 and 75 output orders) repeat every 1/25 turn: the
# detectors' shapes are turned by each 1/25 turn (2 teeth). From every other tooth (tooth 1 alone
# and its turns: AUC 0.88, each tooth's response is its own).
TEETH = list(range(1, 51, 2))
DETECT = """\
[scenario]
name = "slow_chip"
kind = "detection"

[source]
gearbox = "box.toml"
faults = {{ "chip@output gear" = [12] }}
teeth = {teeth}
healthy = 40

[target]
vibration = "acc"
tacho = "tacho"
files = [
  {{ file = "hist1.npz", role = "history", label = "healthy" }},
  {{ file = "hist2.npz", role = "history", label = "healthy" }},
  {{ file = "hist3.npz", role = "history", label = "healthy" }},
  {{ file = "test_ok.npz", role = "test", label = "healthy" }},
  {{ file = "{test}.npz", role = "test", label = "fault" }},
]

[detection]
blocks = [10]

[[methods]]
adapter = "matched_filter"
"""


@pytest.fixture(scope="module")
def slow_box(tmp_path_factory):
    folder = tmp_path_factory.mktemp("slowbox")
    (folder / "box.toml").write_text(BOX)
    for name, (chip, seed, revolutions) in TAKES.items():
        faults = [] if chip is None else [{"name": "chip", "gear": "output gear", "tooth": 7, "step": chip}]
        rec = simulated_record(
            faults,
            gearbox=str(folder / "box.toml"),
            revolutions=float(revolutions),
            snr_db=25.0,
            seed=seed,
            fs=12_800.0,
            sim_fs=200e3,
        )
        # NPZ, not CSV: the question here is the units' shaft, not a format (CSV's are read in their own
        # tests); writing the six takes as text and parsing them again in each of the module's four runs
        # and its score was about 1 s of the module's CPU
        np.savez(folder / f"{name}.npz", acc=rec.vibration, tacho=rec.tacho, fs=rec.fs)
    (folder / "detect.toml").write_text(DETECT.format(test="test_chip", teeth=TEETH))
    (folder / "short.toml").write_text(DETECT.format(test="short", teeth=TEETH))
    # no tacho: each take's speed from the description's mesh lines
    no_tacho = DETECT.format(test="test_chip", teeth=TEETH).replace('tacho = "tacho"', 'gearbox = "box.toml"')
    (folder / "detect_nt.toml").write_text(no_tacho.replace('name = "slow_chip"', 'name = "slow_chip_nt"'))
    return folder


def test_an_event_once_per_turn_of_a_slow_shaft_survives_its_tsa_not_the_inputs():
    """A dip once per turn of a shaft turning 26/73 of the input (a 26/73 reducer's intermediate shaft)
    at the shaft's angle 0.3: the input TSA of 30 revolutions holds a tenth of it, the shaft's TSA all
    of it, at its angle."""
    from gearlab.signals.shaft import shaft_revolutions

    points, ratio = 1024, Fraction(26, 73)
    u = np.arange(120 * points) / points  # input turns
    turn = np.mod(0.25 + float(ratio) * u, 1.0)  # the shaft at 0.25 turns at the first sample
    x = np.exp(-0.5 * ((turn - 0.3) / 0.004) ** 2)
    revs = x.reshape(120, points)
    on_input = revs[:30].mean(axis=0)
    on_shaft = shaft_revolutions(revs, float(ratio), phase=0.25, points=points)
    assert on_shaft.shape == (41, points)  # 0.25 + 120 x 26/73 = 42.99 turns: whole ones from 1 to 42
    tsa = on_shaft[:30].mean(axis=0)
    assert np.argmax(tsa) == round(0.3 * points)
    assert tsa.max() > 0.95 and on_input.max() < 0.2, (tsa.max(), on_input.max())


def test_a_take_whose_first_input_turns_are_left_out_is_cut_into_the_same_shaft_turns():
    """The units' shaft's turns are counted from the take's angle zero, not from its first kept revolution:
    a take whose first 9 input turns are left out (a run-up's part, a start-up; 9 x 4/15 = 2.4 output
    turns, no whole number) gives the whole take's units from output turn 3 on, the dip at its angle.
    Before, counted from the first kept revolution, each unit was 0.4 of a turn off the whole take's."""
    from gearlab.kinds.detection_records import unit_revolutions

    points, (p, q), cut = 1024, (4, 15), 9
    u = np.arange(120 * points) / points  # input turns from the take's zero
    x = np.exp(-0.5 * ((np.mod(p / q * u, 1.0) - 0.3) / 0.004) ** 2)
    revs = x.reshape(120, points)
    whole = unit_revolutions(revs, p, q, None)
    part = unit_revolutions(revs[cut:], p, q, None, first=cut)
    assert len(whole) == 31 and len(part) == 28  # 2.4 + 111 x 4/15 = 32: turns 3 to 30 (the last ends at the end)
    assert np.argmax(part.mean(axis=0)) == round(0.3 * points)
    assert np.max(np.abs(part - whole[3:])) < 1e-5  # before: 1.0, the dip 0.4 turn away


def test_units_of_the_input_shaft_are_as_before():
    """A source watching the input pinion keeps the input shaft's units (no unit_shaft), and the
    dataset key of a spec that does not set it is the one it had before the key existed."""
    from gearlab.data.spec import dataset_preset
    from gearlab.kinds.detection_records import unit_shaft

    spec = dataset_preset("B-6-ch5")
    assert unit_shaft(spec) is None
    assert "unit_shaft" not in spec.canonical()
    assert spec.with_(unit_shaft=(1, 5)).key() != spec.key()


def test_output_gear_damage_is_detected_on_the_output_shafts_units(slow_box, gearlab, no_figures):
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import shaft_symmetry, unit_shaft

    source = load_scenario(str(slow_box / "detect.toml")).spec.source
    shaft = unit_shaft(source)
    assert (shaft.name, shaft.ratio) == ("output", Fraction(4, 15))
    # every other tooth simulated: the 1/25 turns are there already; one tooth: its shapes are turned
    assert shaft_symmetry(source, shaft) == 1 and shaft_symmetry(source.with_(teeth=(1,)), shaft) == 25
    code, out = gearlab(slow_box, "run", "detect.toml", "--quick")
    assert code == 0, out
    run = slow_box / re.findall(r"^run directory: (.+)$", out, re.M)[-1].strip()
    summary = json.loads((run / "summary.json").read_text())
    r = next(r for r in summary["rows"] if r["method"] == "matched_filter" and r["unit"] == "record10")
    # before (input-shaft units): AUC 0.40, 5 % detected at 5 % false alarms; now 1.00, 40 % at 0 %
    assert r["auc"] >= 0.9 and r["detection"] >= 20 and r["false_alarm"] <= 20, r
    assert "units: revolutions and TSAs of the output shaft" in out, out
    ((_, cond),) = summary["conditions"].items()
    assert cond["unit_shaft"] == "output"
    assert "(units: the output shaft's revolutions)" in (run / "table.md").read_text()
    # gearlab score cuts a new record on the same shaft: the run's own scores of the chipped take again
    code, out = gearlab(slow_box, "score", str(run), "test_chip.npz", "--json")
    assert code == 0, out
    (scored,) = [s for s in json.loads(out) if s["method"] == "matched_filter" and s["unit"] == "record10"]
    made = next(
        json.loads(line)
        for line in (run / "results.jsonl").read_text().splitlines()
        if json.loads(line)["method"] == "matched_filter"
    )["test_scores"]["test_chip.npz"]["record10"]
    assert scored["units"] == len(made) and scored["median_score"] == pytest.approx(np.median(made), abs=1e-6)


def test_a_record_too_short_for_a_block_of_the_slow_shaft_is_one_line(slow_box, gearlab):
    code, out = gearlab(slow_box, "run", "short.toml", "--quick")
    assert code == 2, out
    line = out.strip().splitlines()[-1]
    assert re.search(r"short\.npz gives [1-9] output-shaft revolutions, fewer than record10's 10", line), out
    assert "[detection] key 'blocks'" in line, out


def test_the_detectors_shapes_are_turned_by_each_turn_the_frame_cannot_tell():
    """A fault row's damage at every 1/g of the shaft's turn (g = 4 here), healthy rows as they are:
    the angle a record is turned to by its healthy mean is known to 1/g turn only (a 27/88 + 22/65
    hoist's output shaft: g = 65, its meshes 65 and 260; before, 4 simulated teeth of 65 gave
    matched_filter a record30 AUC of 0.50 on the outside L takes, 1.00 with the turns)."""
    from gearlab.kinds.detection_records import turned_faults

    X = np.zeros((2, 64), dtype=np.float32)
    X[0, 5], X[1, 3] = 1.0, 1.0  # a healthy row, a fault row
    y = np.array([0, 1])
    Xt, yt = turned_faults(X, y, 4)
    assert Xt.dtype == X.dtype and list(yt) == [0, 1, 1, 1, 1]
    assert np.array_equal(Xt[:2], X)
    assert [int(np.argmax(r)) for r in Xt[1:]] == [3, 19, 35, 51]
    assert np.allclose(Xt[2:].max(axis=1), 1.0, atol=1e-5)
    assert turned_faults(X, y, 1)[0] is X


def test_without_a_tacho_the_output_shafts_units_come_from_the_mesh_lines(slow_box, gearlab, no_figures):
    code, out = gearlab(slow_box, "run", "detect_nt.toml", "--quick")
    assert code == 0, out
    run = slow_box / re.findall(r"^run directory: (.+)$", out, re.M)[-1].strip()
    summary = json.loads((run / "summary.json").read_text())
    ((_, cond),) = summary["conditions"].items()
    assert cond["unit_shaft"] == "output" and all("mesh" in how for how in cond["speed_from"].values()), cond
    r = next(r for r in summary["rows"] if r["method"] == "matched_filter" and r["unit"] == "record10")
    # before (input-shaft units): AUC 0.65, 0 % detected; now 1.00, 60 % at 0 % false alarms
    assert r["auc"] >= 0.9 and r["detection"] >= 20 and r["false_alarm"] <= 20, r


def test_a_take_whose_first_input_turns_are_left_out_scores_its_turns_as_whole(
    slow_box, gearlab, no_figures, monkeypatch
):
    """The chipped take scored by `gearlab score` (detection_scoring) and in a run (read_target) with its first 36
    input turns left out, as a run-up's part is (detection_in_band): 36 x 4/15 = 9.6 output turns, so its units
    start at output turn 10, the run's second record10 unit of the whole take, and they score as the whole take's
    units from the second on (within 0.07 %: each record's band-limited reading, of its own length). Before, the
    output's turns were counted from the first kept revolution, each unit 0.4 turn off the whole take's: 1.3 % off
    in the median score, 3 % in a unit (each record's turn by correlation takes up the rest)."""
    from gearlab.kinds import detection_in_band, detection_records, detection_scoring

    def later(rec):
        return detection_in_band._cut(rec, slice(36, len(rec.revolutions)))

    def scores(run):
        lines = (run / "results.jsonl").read_text().splitlines()
        made = next(json.loads(x) for x in lines if json.loads(x)["method"] == "matched_filter")
        return np.array(made["test_scores"]["test_chip.npz"]["record10"])

    code, out = gearlab(slow_box, "run", "detect.toml", "--quick")
    assert code == 0, out
    run = re.findall(r"^run directory: (.+)$", out, re.M)[-1].strip()
    whole = scores(slow_box / run)
    read = detection_scoring.cut_recording
    monkeypatch.setattr(detection_scoring, "cut_recording", lambda *a, **k: later(read(*a, **k)))
    code, out = gearlab(slow_box, "score", run, "test_chip.npz", "--json")
    assert code == 0, out
    (scored,) = [s for s in json.loads(out) if s["method"] == "matched_filter" and s["unit"] == "record10"]
    assert scored["units"] == len(whole) - 1
    assert scored["median_score"] == pytest.approx(np.median(whole[1:]), rel=2e-3), (scored, whole)

    def chip_cut(files, records, *args):
        for f in files:
            if f.path == "test_chip.npz":
                records[f.path] = later(records[f.path])
        return cut_run_ups(files, records, *args)

    cut_run_ups = detection_records.cut_run_ups
    monkeypatch.setattr(detection_records, "cut_run_ups", chip_cut)
    code, out = gearlab(slow_box, "run", "detect.toml", "--quick")
    assert code == 0, out
    part = scores(slow_box / re.findall(r"^run directory: (.+)$", out, re.M)[-1].strip())
    assert part == pytest.approx(whole[1:], rel=2e-3), (part, whole)
