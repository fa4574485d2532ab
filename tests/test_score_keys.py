"""The keys a recording is read with, the same everywhere (issue 39, items 2 and 6): `gearlab score
--key` takes every key a [target] 'files' entry takes (parts.measured.ACQUISITION, declared once), and
a 'files' entry its own tacho_shaft as the [target] does, each bad value one line naming where it was
given. A take whose tacho was moved to the output shaft, 2 marks a turn, of a 21/59 box (a pair no
other test uses) scores as the same signal read at a 1-mark input tacho."""

from __future__ import annotations

import csv
import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.errors import GearlabInputError
from gearlab.gearbox import load_gearbox
from gearlab.gearbox.orders import TachoShaft
from gearlab.kinds.detection_scoring import reading_keys
from gearlab.parts import scoring
from gearlab.parts.measured import ACQUISITION
from gearlab.runs import RunDir

# the records' rate: 200 samples an input turn, the chip's 1.5 kHz ring under its Nyquist; at 20 kHz writing
# and reading their CSVs was a fifth of the file's CPU. The moved tacho's medians (seeded): within 1.36 standard
# errors of the input's (1.03 at 20 kHz; 2 allowed)
FS, SPEED = 5_000.0, 25.0
SENSITIVITY = 0.1 / 9.80665  # 100 mV/g in V per m/s²
OUTPUT = Fraction(21, 59)  # the output's turns per input turn
BOX = description(stage(21, 59), name="fan2159", speed="25 Hz", load="10 N*m", near="input", tacho="input")


def record(path: Path, turns=Fraction(1), marks=1, chip=0.0, seed=0, seconds=3.0, start=-0.1, teeth=21, speed=SPEED):
    """A record (time_s, acc_V, tacho_V) of the 21/59 box at 25 Hz (or a pinion of *teeth* at *speed*): its mesh
    modulated once an input turn, a chip's ring once an input turn (*chip*: its level), noise of *seed*; the tacho
    *marks* pulses a turn of the shaft turning *turns* per input turn, each rising where that shaft's angle x
    *marks* is 0 (the input at *start* turns at the first sample)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    theta = 2 * np.pi * (speed * t + start)
    acc = np.sin(teeth * theta) * (1 + 0.2 * np.cos(theta)) + 0.05 * rng.standard_normal(t.size)
    since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * speed)
    acc += chip * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
    shaft = np.mod(theta * float(turns) * marks + np.pi, 2 * np.pi) - np.pi
    ramp = 4 * 2 * np.pi * speed * float(turns) * marks / FS  # each pulse rises over 4 samples
    tacho = 5.0 * np.clip(0.5 + shaft / ramp, 0, 1) * (shaft < 0.3)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time_s", "acc_V", "tacho_V"])
        w.writerows(zip(t.tolist(), (acc * SENSITIVITY).tolist(), tacho.tolist()))
    return path


def _meta(tacho="tacho_V") -> dict:
    target = {k: None for k in ("sensitivity", "gain", "unit", "fs")}
    target |= {"vibration": "acc_V", "tacho": tacho, "pulses_per_rev": 1, "speed_hz": None if tacho else 25.0}
    return {"target": target, "conditions": {"25 Hz": {"speed_hz": 25.0}}}


def test_score_key_takes_every_key_of_a_files_entry(tmp_path):
    """Every key of a 'files' entry, given as --key text: a tacho_shaft of the run's description (its
    turns per input turn), marks a turn as a whole number; the input angles the take's first mark finds."""
    from gearlab.kinds.detection_scoring import _marks

    (tmp_path / "box.toml").write_text(BOX)
    box = load_gearbox(tmp_path / "box.toml")
    given = {"vibration": "vib", "tacho": "tach", "tacho_shaft": "output", "pulses_per_rev": "2"}
    given |= {"sensitivity": "100 mV/g", "gain": "2", "unit": "V", "fs": "25.6 kHz"}
    assert set(given) == set(ACQUISITION)
    keys = reading_keys(_meta(), None, given, box=box)
    assert keys["tacho_shaft"] == TachoShaft("output", 21, 59) and keys["pulses_per_rev"] == 2
    assert (keys["vibration"], keys["tacho"], keys["unit"], keys["fs"]) == ("vib", "tach", "V", 25_600.0)
    assert _marks(keys) == 42  # 2 marks a turn of a shaft at 21/59: the input found 1/42 of a turn apart
    assert _marks(reading_keys(_meta(), None, {}, box=box)) == 1  # the run's input tacho, as before
    assert reading_keys(_meta(), None, {"tacho_shaft": "input"})["tacho_shaft"] == TachoShaft("input")


@pytest.mark.parametrize(
    ("key", "value", "line"),
    [
        ("tacho_shaft", "middle", "--key tacho_shaft: unknown shaft 'middle'; the shafts are input, output"),
        ("pulses_per_rev", "0", "--key pulses_per_rev: 0 is outside [1, 10000]"),
        ("pulses_per_rev", "two", "--key pulses_per_rev: expected an integer, got str 'two'"),
        ("pulses_per_rev", "", "--key pulses_per_rev=: expected a value (without --key pulses_per_rev, the run's is"),
        ("tacho_shat", "output", f"--key tacho_shat=output: expected KEY=VALUE, KEY one of {', '.join(ACQUISITION)} ("),
    ],
)
def test_a_bad_score_key_is_one_line(tmp_path, key, value, line):
    (tmp_path / "box.toml").write_text(BOX)
    with pytest.raises(GearlabInputError) as found:
        reading_keys(_meta(), None, {key: value}, box=load_gearbox(tmp_path / "box.toml"))
    assert str(found.value).startswith(line) and "\n" not in str(found.value), str(found.value)


def test_a_score_key_of_a_tacho_is_refused_where_the_run_had_none_or_no_description():
    for key in ("tacho_shaft", "pulses_per_rev"):
        with pytest.raises(GearlabInputError, match=rf"^--key {key}: the run read its records without a tacho"):
            reading_keys({**_meta(None), "tacho_records": "none"}, None, {key: "2" if "p" in key[:1] else "output"})
    with pytest.raises(GearlabInputError, match=r"^--key tacho_shaft=output: a shaft of a gearbox description, and"):
        reading_keys(_meta(), None, {"tacho_shaft": "output"})


def _entry(files, **keys) -> dict:
    """A [target] table as the gap and the detection read it (every key given, as validate fills them)."""
    entry = {"vibration": "acc_V", "tacho": "tacho_V", "pulses_per_rev": 1, "speed": None, "gearbox": "", "fs": None}
    entry |= {"sensitivity": "100 mV/g", "unit": "", "gain": None, "transient": "none", "positive": "fault"}
    return entry | {"preset": "", "file": "", "name": "", "tacho_shaft": "", "files": files, **keys}


def test_a_files_entry_reads_its_own_tacho_shaft_as_the_target_does(tmp_path):
    """A history file's own tacho_shaft = "output" (2 marks a turn) reads the input's speed and revolutions
    as the [target]'s key does, the same numbers; a file's own "input" in a [target] of the output reads
    its input tacho; the detection's files may mix shafts (aligned at the marks of them all), the gap's
    history may not (one acquisition chain)."""
    from gearlab.kinds.gap import target_of
    from gearlab.parts.measured import ROLES, aligned, target_spec

    (tmp_path / "box.toml").write_text(BOX)
    box = load_gearbox(tmp_path / "box.toml")
    for i in range(2):
        record(tmp_path / f"in{i}.csv", seed=i, seconds=1.5, start=i / 3 - 0.1)
        record(tmp_path / f"out{i}.csv", OUTPUT, marks=2, seed=i, seconds=1.5, start=i / 3 - 0.1)
    out = {"tacho_shaft": "output", "pulses_per_rev": 2}

    def files(name, role="history", **own):
        return [{"file": f"{name}{i}.csv", "role": role, "label": "healthy", **own} for i in range(2)]

    def gap(files, **keys):
        return target_of(_entry(files, **keys), "s.toml: [target]", tmp_path, box).target

    own, table = gap(files("out", **out)), gap(files("out"), **out)
    assert dict(own.files[0].keys)["tacho_shaft"] == TachoShaft("output", 21, 59) == table.tacho_shaft
    assert own.marks == table.marks == 42 and own.read_as == table.read_as == "output"
    inputs = gap(files("in"))
    reference = inputs.read(inputs.files[0]).revolutions.mean(axis=0)
    for f_own, f_table, f_in in zip(own.files, table.files, inputs.files):
        a, b, c = own.read(f_own), table.read(f_table), inputs.read(f_in)
        assert a.speed_hz == b.speed_hz == pytest.approx(SPEED, rel=2e-4) and "on the output shaft" in a.angle_source
        assert np.array_equal(a.revolutions, b.revolutions)
        # the second take's first output mark finds the input 0.4 turn on: turned to one of 42 angles, as a run does
        tsa_out = aligned(reference, a.revolutions, 1, own.marks)[1].mean(axis=0)
        tsa_in = aligned(reference, c.revolutions, 1, inputs.marks)[1].mean(axis=0)
        assert np.linalg.norm(tsa_out - tsa_in) < 0.05 * np.linalg.norm(tsa_in)
    back = gap(files("in", tacho_shaft="input", pulses_per_rev=1), **out)  # a file's own wins
    assert back.read_as == "input" and back.read(back.files[0]).speed_hz == pytest.approx(SPEED, rel=2e-4)
    with pytest.raises(GearlabInputError) as found:
        gap([*files("in"), *files("out", **out)][1:3])
    line = str(found.value)
    assert line.startswith("s.toml: [target] key 'files': in1.csv reads its tacho on the input shaft, out0.csv on")
    assert "one acquisition chain" in line and "\n" not in line
    mixed = target_spec(_entry([*files("in"), *files("out", "test", **out)]), "s.toml: [target]", tmp_path, ROLES, box)
    assert mixed.marks == 42 and mixed.read_as == "input"


@pytest.mark.parametrize(
    ("own", "said"),
    [
        ('tacho_shaft = "middle"', "key 'tacho_shaft': unknown shaft 'middle'; the shafts are input, output"),
        ("tacho_shaft = 3", "key 'tacho_shaft': expected a string, got int 3"),
        ("pulses_per_rev = 0", "key 'pulses_per_rev': 0 is outside [1, 10000]"),
        ('tacho = "", tacho_shaft = "output"', "key 'tacho_shaft': belongs to a tacho; no 'tacho' is given"),
        ("", None),
    ],
)
def test_validate_names_a_files_entry_s_bad_tacho_shaft_or_marks(tmp_path, cli, write_scenario, own, said):
    (tmp_path / "box.toml").write_text(BOX)
    for name in ("h", "t"):
        record(tmp_path / f"{name}.csv", seconds=0.5)  # a history long enough for its units: validate reads its tacho
    entry = '{ file = "t.csv", role = "test", label = "fault", ' + (own or 'tacho_shaft = "output"') + " }"
    history = '{ file = "h.csv", role = "history", label = "healthy" }'
    code, out, err = cli("validate", write_scenario(DETECT.format(files=f"{history}, {entry}")))
    if said is None:
        assert code == 0, err
        return
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert f"s.toml: [target] key 'files' entry 2 {said}" in err, err


DETECT = """[scenario]
name = "fan"
kind = "detection"
[source]
gearbox = "box.toml"
teeth = [1, 2]
faults = {{ chip = [20] }}
healthy = 6
[target]
vibration = "acc_V"
tacho = "tacho_V"
sensitivity = "100 mV/g"
files = [{files}]
[detection]
blocks = [5]
[[methods]]
adapter = "matched_filter"
[protocol]
batch = 4
"""


def test_score_reads_a_take_whose_tacho_moved_to_the_output_as_the_input_s(
    tmp_path, cli, run_scenario, monkeypatch, no_figures
):
    """docs/your_gearbox.md's steps 5 and 7 with a 21/59 box: a run trained on input-tacho records, one test
    take read at its own output tacho of 2 marks (its 'files' entry's tacho_shaft and pulses_per_rev), then
    next week's takes scored with --key tacho_shaft=output --key pulses_per_rev=2: each scores as the same
    signal read at the input tacho (the same decision, the median score within noise); without the keys the
    output's pulses are read as the input's (17.8 Hz, no condition's speed), one line that names the keys."""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "box.toml").write_text(BOX)
    for folder in ("in", "out"):
        (tmp_path / folder).mkdir()
    for i, (name, chip) in enumerate((("h0", 0), ("h1", 0), ("t0", 0), ("t1", 3.0), ("next", 3.0), ("ok", 0))):
        # next week's takes: the output's first mark 0.405 input turn past the input's, found among its 42 angles
        start = 0.233 if name in ("next", "ok") else -0.1
        record(tmp_path / "in" / f"{name}.csv", chip=chip, seed=i, start=start)
        if name in ("t1", "next", "ok"):
            record(tmp_path / "out" / f"{name}.csv", OUTPUT, marks=2, chip=chip, seed=i, start=start)
    files = ", ".join(f'{{ file = "in/{n}.csv", role = "history", label = "healthy" }}' for n in ("h0", "h1"))
    files += ', { file = "in/t0.csv", role = "test", label = "healthy" }, '
    files += '{ file = "out/t1.csv", role = "test", label = "fault", tacho_shaft = "output", pulses_per_rev = 2 }'
    run = run_scenario(DETECT.format(files=files), "detect.toml")
    own: dict = {}
    with (run / "scores.csv").open() as f:
        for r in csv.DictReader(f):
            if r["file"] == "out/t1.csv":
                own.setdefault((r["method"], r["unit"]), []).append(float(r["score"]))
    assert {k[0] for k in own} == {"matched_filter", "fm4", "na4"}

    def scored(*args):
        code, out, err = cli("score", run, *args, "--json")
        assert code == 0, err
        return {(Path(x["file"]).name, x["method"], x["unit"]): x for x in json.loads(out)}

    again = scored(tmp_path / "in" / "t1.csv")  # the run's own output-tacho take, read at the input tacho
    for (method, unit), scores in own.items():
        assert again[("t1.csv", method, unit)]["median_score"] == pytest.approx(np.median(scores), rel=5e-3, abs=1e-6)
    takes = [tmp_path / "out" / n for n in ("next.csv", "ok.csv")]
    moved = scored(*takes, "--key", "tacho_shaft=output", "--key", "pulses_per_rev=2")
    plain = scored(tmp_path / "in" / "next.csv", tmp_path / "in" / "ok.csv")
    assert moved.keys() == plain.keys() and len(plain) == 12
    history = [r for r in scoring.read_history(RunDir.open(run)) if Path(r["file"]).parent.name == "in"]
    units = {(Path(r["file"]).name, r["method"], r["unit"]): r["scores"] for r in history}  # the input takes' units
    for key, x in plain.items():
        y = moved[key]
        assert y["decision"] == x["decision"] and y["speed_hz"] == pytest.approx(x["speed_hz"], rel=1e-4), key
        # revolutions cut 0.405 turn apart: the median moves within 2 standard errors of the input take's (1.03 seen)
        noise = 1.2533 * np.std(units[key], ddof=1) / np.sqrt(len(units[key]))
        assert abs(y["median_score"] - x["median_score"]) < 2 * noise and y["threshold"] == x["threshold"], key
        assert "(2 pulses per revolution) on the output shaft" in y["speed_from"]
    assert plain[("next.csv", "fm4", "record5")]["decision"] == "fault"
    assert plain[("ok.csv", "fm4", "record5")]["decision"] == "healthy"
    code, _, err = cli("score", run, takes[0])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "17.80 Hz is more than 5%" in err, err
    # the one shaft and count of marks at which it runs at the condition's speed, its mesh lines then the description's
    said = "or its tacho reads the output shaft, 2 pulses per revolution: it then runs at 25.00 Hz, the speed of "
    assert f"{said}condition '25 Hz' (gearlab score RUN FILE --key tacho_shaft=output --key pulses_per_rev=2)" in err
    # a 23-tooth pinion's take at that speed, its input tacho read right: read so its mesh is no 21: no keys named
    other = record(tmp_path / "other.csv", teeth=23, speed=SPEED * 42 / 59, seed=9)
    code, _, err = cli("score", run, other)
    assert code == 2 and "17.80 Hz is more than 5%" in err and "--key" not in err, err
