"""A user's tacho moved to the OUTPUT shaft, 2 marks a turn, on a 21/59 box at 25 Hz, inspected with a description
that defaults to a 1-mark input tacho (issue 39, item 3): every order reads 59/42 = 1.405 x its own, the mesh at 29.5,
and `gearlab inspect take.csv --gearbox box.toml` said only 'stage 1: no line at mesh order 21': check_description
gave stage 1 no line, and inspect_tacho.misread, which read each stage's mesh among the stages' measured orders
alone, found nothing. The gap diagnosis said 'a 21-tooth pinion (not a whole number of teeth ...)', a detection run
the same of its history. All three now name the tacho's shaft and marks and the keys that read it; the other ways a
1-mark input tacho is misread (the output's 1 mark, the input's 2 or 3), on a 27/73 box, name theirs alone.
The records are made here with numpy: CSV (time_s, acc_V at 100 mV/g, tacho_V), as the user's."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.gearbox import load_gearbox
from gearlab.inspect import InspectOptions, inspect_record

FS, SPEED = 12_800.0, 25.0
SENSITIVITY = 0.1 / 9.80665  # 100 mV/g in V per m/s²
BOTH = "the tacho reads the output shaft? with 2 pulse(s) per revolution, not 1? (--tacho-shaft output "
BOTH += "--pulses-per-rev 2, keys 'tacho_shaft' and 'pulses_per_rev' in a scenario)"
# a run (gap, detection) has no inspect options: the keys of the table that holds its records, with their values
RUN_BOTH = "the tacho reads the output shaft? with 2 pulse(s) per revolution, not 1? ([target] tacho_shaft = 'output', "
RUN_BOTH += "pulses_per_rev = 2)"


def _record(path, z1: int, z2: int, shaft: str, marks: int, seconds=4.0, seed=0) -> float:
    """A z1/z2 box's housing acceleration as volts: mesh harmonics 1-3, amplitude- and phase-modulated at both shafts'
    orders (their sidebands), the speed drifting 0.5 % about 25 Hz, noise; a tacho of *marks* pulses a turn of the
    *shaft* ('input' or 'output'). The input's mean speed (Hz)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    f = SPEED * (1 + 0.005 * np.sin(2 * np.pi * t / 3.1))
    a_in = 2 * np.pi * np.cumsum(f) / FS
    a_out = a_in * z1 / z2
    am = 1 + 0.15 * np.cos(a_in) + 0.1 * np.cos(a_out)
    pm = 0.2 * np.cos(a_in) + 0.1 * np.sin(a_out)
    acc = rng.normal(0, 0.2, t.size)
    for h, a in ((1, 2.0), (2, 0.8), (3, 0.35)):
        acc += a * am * np.cos(h * (z1 * a_in + pm) + rng.uniform(0, 2 * np.pi))
    angle = a_in if shaft == "input" else a_out
    tacho = np.where(np.mod(marks * angle, 2 * np.pi) < 0.5, 5.0, 0.0)
    with open(path, "w", newline="") as out:
        w = csv.writer(out)
        w.writerow(["time_s", "acc_V", "tacho_V"])
        w.writerows(zip(t.tolist(), (acc * SENSITIVITY).tolist(), tacho.tolist()))
    return float(f.mean())


def _box(path, z1: int, z2: int):
    """The description as the user wrote it: [sensor] tacho on the input, pulses_per_rev left to its default 1."""
    path.write_text(description(stage(z1, z2), name="box", speed="25 Hz", load="10 N*m", near="input", tacho="input"))
    return path


def _options(**keys) -> InspectOptions:
    return InspectOptions("acc_V", "tacho_V", sensitivity=SENSITIVITY, **keys)


def test_inspect_of_a_2_mark_output_tacho_names_its_shaft_and_marks(tmp_path, cli):
    """The user's command: the verdict is the tacho's line alone, not 'no line at mesh order 21', no tooth count."""
    _record(tmp_path / "take.csv", 21, 59, "output", 2)
    _box(tmp_path / "box.toml", 21, 59)
    args = ("--vibration", "acc_V", "--tacho", "tacho_V", "--sensitivity", "100 mV/g", "--json")
    code, out, err = cli("inspect", tmp_path / "take.csv", "--gearbox", tmp_path / "box.toml", *args)
    assert code == 0, out + err
    report = json.loads(out)
    verdict = report["verdict"]
    assert report["matches"] is False, verdict
    assert verdict.startswith("the description 'box' differs: stage 1: mesh order 29.5 measured, 21 expected"), verdict
    assert "every order reads 1.405 x its own" in verdict and BOTH in verdict, verdict
    assert report["check"]["differences"] == [verdict.split("differs: ", 1)[1]], verdict
    assert "no line" not in verdict and "teeth" not in verdict, verdict
    code, out, err = cli(
        "inspect", tmp_path / "take.csv", "--gearbox", tmp_path / "box.toml", *args, "--tacho-shaft", "output",
        "--pulses-per-rev", "2",
    )  # fmt: skip
    assert code == 0, out + err
    right = json.loads(out)
    assert right["matches"], right["verdict"]
    assert right["check"]["stages"][0]["measured_order"] == pytest.approx(21.0, abs=0.05)


@pytest.mark.parametrize(
    ("shaft", "marks", "said", "right"),
    [
        ("output", 2, BOTH, {"tacho_shaft": "output", "pulses_per_rev": 2}),
        (
            "output",
            1,
            "the tacho reads the output shaft? --tacho-shaft output, key 'tacho_shaft' in a scenario",
            {"tacho_shaft": "output"},
        ),
        (
            "input",
            2,
            "the tacho gives 2 pulse(s) per revolution, not 1? (--pulses-per-rev 2, key 'pulses_per_rev'",
            {"pulses_per_rev": 2},
        ),
        (
            "input",
            3,
            "the tacho gives 3 pulse(s) per revolution, not 1? (--pulses-per-rev 3, key 'pulses_per_rev'",
            {"pulses_per_rev": 3},
        ),
    ],
    ids=["output-2", "output-1", "input-2", "input-3"],
)
def test_every_misread_of_a_1_mark_input_tacho_is_named_alone(tmp_path, shaft, marks, said, right):
    """A 27/73 box (a pair no other test uses): each misread told in one line, no tooth count; read with the keys it
    names, the description matches and the input's speed is within 0.5 %."""
    mean_hz = _record(tmp_path / "take.csv", 27, 73, shaft, marks, seed=marks)
    box = load_gearbox(_box(tmp_path / "box.toml", 27, 73))
    report = inspect_record(str(tmp_path / "take.csv"), box, _options())
    verdict = report["verdict"]
    assert report["matches"] is False, verdict
    assert report["check"]["differences"] == [verdict.split("differs: ", 1)[1]], verdict
    assert said in verdict and "no line" not in verdict and "teeth" not in verdict, verdict
    read = inspect_record(str(tmp_path / "take.csv"), box, _options(**right))
    assert read["matches"], read["verdict"]
    assert read["speed"]["mean_hz"] == pytest.approx(mean_hz, rel=0.005)
    assert read["check"]["stages"][0]["measured_order"] == pytest.approx(27.0, abs=0.05)


def _takes(tmp_path) -> str:
    _box(tmp_path / "box.toml", 21, 59)
    for i, name in enumerate(("h1", "h2", "t1", "t2")):
        _record(tmp_path / f"{name}.csv", 21, 59, "output", 2, seconds=3.0, seed=10 + i)
    return '[target]\nvibration = "acc_V"\ntacho = "tacho_V"\nsensitivity = "100 mV/g"\nfiles = [\n'


def _files(*rows) -> str:
    entries = (f'  {{ file = "{n}.csv", role = "{role}", label = "{label}" }},\n' for n, role, label in rows)
    return "".join(entries) + "]\n"


def _gap_run(tmp_path, cli, gearbox: str, target: str) -> dict:
    """summary.json of a quick gap run of *gearbox* against the *target* table's files."""
    path = tmp_path / "gap.toml"
    path.write_text(
        f'[scenario]\nname = "bo_gap"\nkind = "gap"\n[source]\ngearbox = "{gearbox}"\n' + target
        + '[diagnosis]\ncandidates = ["sensor_noise", "sensor_bandwidth", "casing_path"]\n[accuracy]\nenabled = false\n'
    )  # fmt: skip
    code, out, err = cli("run", path, "--out", tmp_path / "runs", "--quick")
    assert code == 0, out + err
    (summary,) = (tmp_path / "runs").rglob("summary.json")
    return json.loads(summary.read_text())


def test_the_gap_diagnosis_of_a_2_mark_output_tacho_names_it(tmp_path, cli):
    target = _takes(tmp_path) + _files(("h1", "history", "healthy"), ("h2", "history", "healthy"))
    result = _gap_run(tmp_path, cli, "box.toml", target)
    verdict = result["verdict"]
    assert verdict.startswith("structure differs: stage 1: mesh order 29.5 measured, 21 expected"), verdict
    assert RUN_BOTH in verdict and "teeth" not in verdict, verdict
    tacho = result["structure"]["tacho"]
    assert tacho["shaft"] == "output" and tacho["marks_read_over_given"] == 0.5, tacho
    assert tacho["factor"] == pytest.approx(59 / 42, rel=1e-9), tacho


def test_a_detection_run_on_a_2_mark_output_tacho_names_it(tmp_path, cli):
    rows = (("h1", "history", "healthy"), ("h2", "history", "healthy"))
    rows += (("t1", "test", "healthy"), ("t2", "test", "fault"))
    path = tmp_path / "detect.toml"
    path.write_text(
        '[scenario]\nname = "bo_det"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "chip@input pinion" = [18] }\nhealthy = 8\n[protocol]\nbatch = 8\n'
        + _takes(tmp_path) + _files(*rows) + '[[methods]]\nadapter = "matched_filter"\n'
    )  # fmt: skip
    code, out, err = cli("run", path, "--out", tmp_path / "runs", "--quick")
    assert code == 2, out + err
    (line,) = [x for x in err.strip().splitlines() if x.startswith("error:")]
    assert "[source] key 'gearbox': the history of condition" in line, line
    assert "stage 1: mesh order 29.5 measured, 21 expected" in line and RUN_BOTH in line, line
    assert "teeth" not in line, line


def _reducer(tmp_path):
    from test_inspect_tacho_misread import STAGES

    path = tmp_path / "reducer.toml"
    stages = stage(*STAGES[0]), stage(*STAGES[1], module="3 mm")
    text = description(*stages, name="reducer", speed="2400 rpm", load="80 N*m")
    path.write_text(text + '[sensor]\ntacho = "input"\n')
    return path


def test_a_2_mark_output_tacho_of_a_two_stage_reducer_is_named(tmp_path):
    """A 19/47 + 29/71 reducer (tests/test_inspect_tacho_misread.py's record): every order 3.028 x its own; stage 2's
    mesh at 35.5 was explained as its 3rd harmonic's sideband (35.17 + 0.40) and stage 2 given a line at 4.43, so both
    stages were told ('no line at mesh order 19', 'a 11-tooth pinion on the intermediate shaft?'), not the tacho."""
    from test_inspect_tacho_misread import _record as reducer_record

    box = load_gearbox(_reducer(tmp_path))
    rec, mean_hz = reducer_record(tmp_path / "take.npz", tacho_shaft=2, marks=2)
    report = inspect_record(str(rec), box, InspectOptions("acc_ms2", "tach"))
    verdict = report["verdict"]
    assert verdict.startswith("the description 'reducer' differs: stage 1: mesh order 57.53 measured"), verdict
    assert "every order reads 3.028 x its own" in verdict and BOTH in verdict, verdict
    assert "no line" not in verdict and "-tooth pinion on" not in verdict and ";" not in verdict, verdict
    read = inspect_record(str(rec), box, InspectOptions("acc_ms2", "tach", tacho_shaft="output", pulses_per_rev=2))
    assert read["matches"], read["verdict"]
    assert read["speed"]["mean_hz"] == pytest.approx(mean_hz, rel=0.005)


def test_the_gap_diagnosis_of_a_two_stage_reducer_s_2_mark_output_tacho_names_it(tmp_path, cli):
    """The same reducer's takes in the gap diagnosis: 'the target shows 2 meshes: another gear train' before."""
    from test_inspect_tacho_misread import _record as reducer_record

    _reducer(tmp_path)
    for i, name in enumerate(("h1", "h2")):
        reducer_record(tmp_path / f"{name}.npz", tacho_shaft=2, marks=2, seed=20 + i)
    files = "".join(f'  {{ file = "{n}.npz", role = "history", label = "healthy" }},\n' for n in ("h1", "h2"))
    target = f'[target]\nvibration = "acc_ms2"\ntacho = "tach"\nfiles = [\n{files}]\n'
    result = _gap_run(tmp_path, cli, "reducer.toml", target)
    verdict = result["verdict"]
    assert verdict.startswith("structure differs: stage 1: mesh order 57.53 measured, 19 expected"), verdict
    assert RUN_BOTH in verdict and "meshes" not in verdict and "teeth" not in verdict, verdict
    assert result["structure"]["tacho"]["factor"] == pytest.approx(3.028, abs=0.001), result["structure"]
