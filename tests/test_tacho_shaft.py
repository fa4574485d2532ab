"""A tacho on another shaft than the input ([target] tacho_shaft, else the description's [sensor]
tacho): its angle over that shaft's turns per input turn is the input's (a continuous phase, whole
or not), for the gap diagnosis's and the detection's records and `gearlab score`, as inspect's
--tacho-shaft reads it. The same recording with its tacho on the input or on the output gives the
same speed, the same TSA and the same detection figures and scores; a wrong shaft name is one line
at validate time."""

from __future__ import annotations

import csv
import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from gearboxes import described_pair, description, stage

from gearlab.errors import GearlabInputError
from gearlab.gearbox import load_gearbox
from gearlab.gearbox.orders import TachoShaft

# the records' rate: 200 samples an input turn, the chip's 1.5 kHz ring under its Nyquist; at 20 kHz their
# CSVs' writing and reading were a fifth of the file's CPU, each test's call the same
FS = 5_000.0
SPEED = 25.0
SENSITIVITY = 0.1 / 9.80665  # 100 mV/g in V per m/s²
RIG16 = Path(__file__).parents[1] / "examples" / "your_gearbox" / "rig16.toml"
# 20/50 + 22/33: the output turns 4/15 a turn per input turn, 3.75 input turns a tacho pulse
TWO_STAGE = description(stage(20, 50), stage(22, 33, module="3 mm"), name="two", speed="25 Hz", load="20 N*m")


def test_the_marks_an_input_angle_may_start_at():
    """M = N a / gcd(b, N): the input angles (1/M of a turn apart) at which a tacho of N marks per turn
    of a shaft turning a/b per input turn finds the input at a record's first mark, counted here."""
    for a, b, n in ((1, 1, 1), (1, 1, 4), (1, 3, 1), (1, 3, 2), (4, 15, 1), (4, 15, 6), (2, 5, 1), (3, 1, 1)):
        seen = {(Fraction(j * b, a * n)) % 1 for j in range(4 * a * b * n)}
        assert TachoShaft("s", a, b).marks(n) == len(seen), (a, b, n)
    assert TachoShaft("input").marks(4) == 4  # the input's own N marks: as read before
    box = load_gearbox(RIG16)
    assert TachoShaft.of(box, "output", "here").turns == Fraction(1, 3)


def _write(folder: Path, text: str) -> Path:
    path = folder / "box.toml"
    path.write_text(text)
    return path


def record(path: Path, turns: Fraction, chip=0.0, seed=0, seconds=3.0, orders=(16,), start=-0.1, wobble=0.002):
    """A record (time_s, acc_V, tacho_V) of a gearbox whose input is at *start* turns at its first
    sample, its angle swinging by *wobble* rad at 0.7 Hz (0.002: ±0.03 % of speed): mesh lines at
    *orders* of the input, modulated once per input turn, a chip's ring once per input turn (*chip*:
    its level), noise; the tacho one pulse per turn of the shaft turning *turns* per input turn, its
    rising edge's mid-level where that shaft's angle (*turns* x the input's) is 0."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    theta = 2 * np.pi * (SPEED * t + start) + wobble * np.sin(2 * np.pi * 0.7 * t)
    acc = sum(np.sin(o * theta + k) / (k + 1) for k, o in enumerate(orders)) * (1 + 0.2 * np.cos(theta))
    since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * SPEED)
    acc = acc + chip * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since) + 0.05 * rng.standard_normal(t.size)
    # each pulse rises over 4 samples (its mid-level crossing, where edges are read, at the shaft's 0)
    shaft = np.mod(theta * float(turns) + np.pi, 2 * np.pi) - np.pi
    ramp = 4 * 2 * np.pi * SPEED * float(turns) / FS
    tacho = 5.0 * np.clip(0.5 + shaft / ramp, 0, 1) * (shaft < 0.3)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time_s", "acc_V", "tacho_V"])
        # as Python floats: the same text as numpy's floats give (byte for byte), written with a quarter less CPU
        w.writerows(zip(t.tolist(), (acc * SENSITIVITY).tolist(), tacho.tolist()))
    return path


def test_a_two_stage_output_tacho_of_no_whole_input_turns_gives_the_input_revolutions(tmp_path):
    """20/50 + 22/33 (output 4/15 of the input): a tacho pulse every 3.75 input turns, read as the
    output's angle x 15/4, gives the input's speed and revolutions (the gap's and the detection's
    [target] reading, parts.measured); the records' first pulses find the input at 4 angles, a
    quarter turn apart, to which each record is turned (Target.marks: 4): the same TSA as the input
    tacho's. Without the key the output's pulses are read as the input's (speed 4/15)."""
    from gearlab.kinds.detection_records import aligned
    from gearlab.kinds.gap import target_of

    box_path = _write(tmp_path, TWO_STAGE)
    box = load_gearbox(box_path)
    orders = (20, 2 * 22 * 20 / 50)  # stage 1 at 20, stage 2 at 17.6 input orders
    for name, turns in (("in", Fraction(1)), ("out", Fraction(4, 15))):
        for i in range(3):
            # the first output pulse finds the input 0, 1/2 and 1/4 turn on
            record(tmp_path / f"{name}{i}.csv", turns, seed=i, seconds=1.2 + 0.13 * i, orders=orders, start=4 * i - 0.1)

    def target(name, **keys):
        files = [{"file": f"{name}{i}.csv", "role": "history", "label": "healthy"} for i in range(3)]
        entry = {
            "vibration": "acc_V",
            "tacho": "tacho_V",
            "pulses_per_rev": 1,
            "speed": None,
            "gearbox": "",
            "fs": None,
        }
        entry |= {"sensitivity": "100 mV/g", "unit": "", "gain": None, "transient": "none", "files": files}
        entry |= {"preset": "", "file": "", "name": "", "tacho_shaft": "", **keys}
        return target_of(entry, "s.toml: [target]", tmp_path, box).target

    on_input, on_output = target("in"), target("out", tacho_shaft="output")
    assert on_output.tacho_shaft == TachoShaft("output", 4, 15) and on_output.marks == 4
    assert on_input.tacho_shaft is None and on_input.marks == 1
    plain = target("out").read(on_output.files[0])
    assert plain.speed_hz == pytest.approx(SPEED * 4 / 15, rel=1e-3)  # the tacho's own shaft
    reference = on_input.read(on_input.files[0]).revolutions.mean(axis=0)
    for f_in, f_out in zip(on_input.files, on_output.files):
        a, b = on_input.read(f_in), on_output.read(f_out)
        assert b.speed_hz == pytest.approx(a.speed_hz, rel=2e-4) == SPEED
        assert "on the output shaft" in b.angle_source
        assert abs(a.revolutions.shape[0] - b.revolutions.shape[0]) <= 4  # starts at its first pulse
        tsa_in = aligned(reference, a.revolutions, 1, on_input.marks)[1].mean(axis=0)
        tsa_out = aligned(reference, b.revolutions, 1, on_output.marks)[1].mean(axis=0)
        assert np.linalg.norm(tsa_out - tsa_in) < 0.03 * np.linalg.norm(tsa_in)
    # the gap's history: every record turned into register with the first, one synchronous average
    from gearlab.kinds.gap_inputs import Records, read_history

    (x_in, speed_in, *_), (x_out, speed_out, *_) = (
        read_history(Records(n, t), lambda e: None) for n, t in (("i", on_input), ("o", on_output))
    )
    assert speed_out == pytest.approx(speed_in, rel=2e-4)
    assert np.linalg.norm(x_out.mean(axis=0) - x_in.mean(axis=0)) < 0.03 * np.linalg.norm(x_in.mean(axis=0))
    # a dataset's measured entry: the tacho's shaft named with its own description
    from gearlab.data.importers import MeasuredSpec, import_measured

    spec = MeasuredSpec(
        "o",
        str(tmp_path / "out1.csv"),
        "acc_V",
        "tacho_V",
        gearbox=str(box_path),
        tacho_shaft="output",
        sensitivity=SENSITIVITY,
    )
    assert import_measured(spec).meta["speed_hz"] == pytest.approx(SPEED, rel=2e-4)
    # the records' first pulses find the input a quarter turn apart: one mark (an integer ratio's
    # reading) leaves them out of register
    turned = [aligned(reference, on_output.read(f).revolutions, 1, 1)[1].mean(axis=0) for f in on_output.files]
    assert max(np.linalg.norm(x - reference) / np.linalg.norm(reference) for x in turned) > 0.2


def test_a_wrong_tacho_shaft_is_one_line_at_validate(tmp_path, cli, write_scenario):
    (tmp_path / "rig16.toml").write_text(RIG16.read_text())
    for name in ("h0", "h1", "t0", "t1"):
        record(tmp_path / f"{name}.csv", Fraction(1, 3), seconds=1.2)  # 8 units: validate reads the tachos
    text = DETECT.format(name="bad", folder=".", shaft='tacho_shaft = "outptu"')
    code, _, err = cli("validate", write_scenario(text, "bad.toml"))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert err.strip().endswith(
        "bad.toml: [target] key 'tacho_shaft': unknown shaft 'outptu' (did you mean 'output'?); "
        "the shafts are input, output"
    )
    # without a tacho; a measured file of no description: one line each. A preset's own description names
    # its shafts (B-6-ch5: input, output)
    code, _, err = cli("validate", write_scenario(text.replace('tacho = "tacho_V"', 'speed = "25 Hz"'), "no.toml"))
    assert code == 2 and err.strip().endswith("[target] key 'tacho_shaft': belongs to a tacho; no 'tacho' is given")
    preset = text.replace('gearbox = "rig16.toml"', 'preset = "B-6-ch5"').replace("outptu", "output")
    assert cli("validate", write_scenario(preset, "preset.toml"))[0] == 0
    dataset = '[scenario]\nname = "d"\nkind = "dataset"\n[[datasets]]\nfile = "h0.csv"\nvibration = "acc_V"\n'
    dataset += 'tacho = "tacho_V"\ntacho_shaft = "output"\nsensitivity = "100 mV/g"\n'
    code, _, err = cli("validate", write_scenario(dataset, "d.toml"))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "d.toml: [[datasets]] #1 key 'tacho_shaft': 'output' is a shaft of a gearbox description, and none" in err
    from gearlab.data.importers import MeasuredSpec

    with pytest.raises(GearlabInputError, match="tacho_shaft 'output': expected a tacho channel"):
        MeasuredSpec("r", str(tmp_path / "h0.csv"), "acc_V", "tacho_V", tacho_shaft="output").check()


DETECT = """[scenario]
name = "{name}"
kind = "detection"
[source]
gearbox = "rig16.toml"
teeth = [1, 2]
faults = {{ chip = [20] }}
healthy = 6
[target]
vibration = "acc_V"
tacho = "tacho_V"
{shaft}
sensitivity = "100 mV/g"
files = [
  {{ file = "{folder}/h0.csv", role = "history", label = "healthy" }},
  {{ file = "{folder}/h1.csv", role = "history", label = "healthy" }},
  {{ file = "{folder}/t0.csv", role = "test", label = "healthy" }},
  {{ file = "{folder}/t1.csv", role = "test", label = "fault" }},
]
[detection]
blocks = [5]
[[methods]]
adapter = "matched_filter"
[protocol]
batch = 4
"""


def test_detection_and_score_read_an_output_tacho_as_the_input_one(
    tmp_path, cli, run_scenario, monkeypatch, no_figures
):
    """The same 16/48 records at a steady speed, their tacho once per input turn or once per output
    turn (every third input turn, [target] tacho_shaft = "output"): the same speed, every (method,
    unit)'s AUC, detected and false-alarm figures, the same scores within 0.2 % of their range, and
    `gearlab score` the same decision and median score for a new chipped record. (At a varying speed
    the revolutions past a record's last pulse, extrapolated at the last pulse interval's speed, are
    up to 3 input turns for an output tacho, under 1 for the input's: the reading test's TSAs.)"""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "rig16.toml").write_text(RIG16.read_text())
    runs = {}
    for folder, turns, shaft in (("in", Fraction(1), ""), ("out", Fraction(1, 3), 'tacho_shaft = "output"')):
        (tmp_path / folder).mkdir()
        for i, (name, chip) in enumerate((("h0", 0), ("h1", 0), ("t0", 0), ("t1", 3.0), ("next", 3.0))):
            record(tmp_path / folder / f"{name}.csv", turns, chip=chip, seed=i, wobble=0.0)
        runs[folder] = run_scenario(DETECT.format(name=folder, folder=folder, shaft=shaft), f"{folder}.toml")
    summary = {k: json.loads((r / "summary.json").read_text()) for k, r in runs.items()}
    assert summary["out"]["target"]["tacho_shaft"] == {"name": "output", "a": 1, "b": 3}
    rows = {k: {(r["method"], r["unit"]): r for r in s["rows"]} for k, s in summary.items()}
    assert rows["in"].keys() == rows["out"].keys() and ("fm4", "record5") in rows["in"]
    for key, row in rows["in"].items():
        for figure in ("auc", "detected", "false_alarm"):
            if figure in row:
                assert rows["out"][key][figure] == pytest.approx(row[figure], abs=1e-9), (key, figure)
    assert rows["in"][("fm4", "record5")]["auc"] == 1.0
    scores = {k: _scores(r / "scores.csv") for k, r in runs.items()}
    assert scores["in"].keys() == scores["out"].keys()
    for key, s in scores["in"].items():
        spread = max(np.ptp(s), 1e-12)
        assert np.max(np.abs(scores["out"][key] - s)) < 2e-3 * spread, key
    scored = {}
    for k, r in runs.items():
        code, out, err = cli("score", r, tmp_path / k / "next.csv", "--json")
        assert code == 0, err
        scored[k] = {(x["method"], x["unit"]): x for x in json.loads(out)}
    assert scored["in"].keys() == scored["out"].keys()
    for key, x in scored["in"].items():
        y = scored["out"][key]
        assert y["decision"] == x["decision"] and y["speed_hz"] == pytest.approx(x["speed_hz"], rel=1e-4)
        assert y["median_score"] == pytest.approx(x["median_score"], rel=5e-3, abs=1e-6), key
    assert "on the output shaft" in scored["out"][("fm4", "record5")]["speed_from"]
    assert scored["in"][("fm4", "record5")]["decision"] == "fault"


def _scores(path: Path) -> dict:
    out: dict = {}
    with path.open() as f:
        for r in csv.DictReader(f):
            key = (r["method"], r["unit"])  # every file's units, in the file's order
            out.setdefault(key, []).append(float(r["score"]))
    return {k: np.array(v) for k, v in out.items()}


def _train(stages, f: float, n=60, points=4096, seed=0, harmonics=(1, 2, 3), wheel=0.2) -> np.ndarray:
    """Rows (n, points) of a train of *stages* ((z1, z2), input first) read at a tacho whose revolutions
    are *f* input turns each (1: the input's, read as such; 3: a 16/48 output tacho read as the input):
    each mesh's *harmonics*, modulated by its pinion's shaft (0.3) and its wheel's (*wheel*), noise."""
    from gearlab.gap.structure import _PairDescription
    from gearlab.gearbox import order_table

    table = order_table(_PairDescription.train(described_pair(*stages)))
    theta = 2 * np.pi * f * np.arange(n * points) / points
    x = np.zeros(theta.size)
    for k, s in enumerate(table.stages):
        mod = (
            1
            + 0.3 * np.cos(float(s.pinion_shaft_order) * theta)
            + wheel * np.cos(float(s.wheel_shaft_order) * theta + 1)
        )
        x += sum(np.cos(h * float(s.mesh) * theta + h + k) / h for h in harmonics) * mod / (k + 1)
    return (x + np.random.default_rng(seed).normal(0, 0.05, theta.size)).reshape(n, points)


def _check(rows, stages, read="input", ratio=None):
    """The gap's structure check of *rows* against *stages*, its tacho read as shaft *read*, at the
    speed read over the described *ratio* (None: no described speed)."""
    from gearlab.data.chain import Chain
    from gearlab.gap.structure import _tacho_read, later_combs, mesh_check

    pair = described_pair(*stages)
    chain = Chain(fs=1.0, speed=25.0 * (ratio or 1.0), described_speed=25.0 if ratio else None, tacho_shaft=read)
    return mesh_check(rows, pair.Z1, pair.Z2, 0, later_combs(pair), _tacho_read(chain, pair))


TRAINS = {1: [(16, 48)], 2: [(20, 50), (22, 33)], 3: [(19, 58), (25, 67), (21, 44)]}


@pytest.mark.parametrize("count", [1, 2, 3])
def test_the_gap_names_the_shaft_a_tacho_reads_when_read_as_another(count):
    """A tacho on another shaft than the one it is read as (no [target] tacho_shaft, the description's
    [sensor] tacho the input): every order reads f = o_read / o_shaft times its own (16/48's output: the
    mesh at 48, all on the 16-tooth comb, so the check passed and sensor noise 'partly explained' it).
    The structure check names the shaft and the key, at the speed 1/f of the described one; the right
    reading (f = 1) passes at every such speed ratio."""
    from gearlab.gap.structure import _PairDescription, mesh_line
    from gearlab.gearbox import order_table

    stages = TRAINS[count]
    box = _PairDescription.train(described_pair(*stages))
    orders = dict(zip(box.shafts, (float(o) for o in order_table(box).shaft_orders)))
    # the right reading's rows are the same for every shaft: made once, each speed ratio checked once (None
    # and 1.0 for every shaft alike)
    right, ratios = _train(stages, 1.0), {None: "input", 1.0: "input"}
    for name, o in orders.items():
        if name == "input":
            continue
        check = _check(_train(stages, 1 / o), stages, ratio=o)
        assert check["differs"] and check["shaft"] == name, (name, check)
        assert check["measured"] == pytest.approx(stages[0][0] / o)
        line = mesh_line(check, stages[0][0])
        assert line.startswith(f"mesh order {stages[0][0] / o:.1f} measured, {stages[0][0]} expected: ")
        assert line.endswith(f"the tacho reads the {name} shaft? give [target] tacho_shaft = '{name}')")
        # the input's tacho given as this shaft's (a wrong tacho_shaft): the input named, where the
        # mesh's 2nd harmonic lies above order 6 (a slower shaft's reading leaves no gear's lines)
        if 2 * o * stages[0][0] >= 6:
            wrong = _check(_train(stages, o), stages, read=name, ratio=1 / o)
            assert wrong["differs"] and wrong["shaft"] == "input", (name, wrong)
        ratios.setdefault(o, name)
        ratios.setdefault(1 / o, name)
    # the right reading, whatever the speed read against the described
    for ratio, name in ratios.items():
        assert not _check(right, stages, ratio=ratio)["differs"], (name, ratio)
    one = _check(_train(stages, 1 / orders["output"]), stages, ratio=None)  # no described speed
    assert one["differs"] and one["shaft"] == "output"


def test_a_mesh_at_a_multiple_of_the_pinion_s_order_is_decided_by_its_sidebands():
    """16/48: 48 = 3 x 16. A right reading whose mesh shows only its 3rd and 6th harmonics (a
    resonance) at a speed read 1/3 of the described: its wheel's sidebands 1/3 apart tell it is read
    as it is; the output's tacho read as the input (the mesh at 48 and 96 too, the output's sidebands 1
    apart and the input's 3) is called; the right reading without a wheel sideband (input sidebands 1
    apart, as the output's are in the other reading) is the output's only at the speed an output tacho
    reads (at the described speed it reads as a tacho of 1/3 the pulses: spectrally the same)."""
    stages = [(16, 48)]
    right = _train(stages, 1.0, harmonics=(3, 6), wheel=0.3)
    assert not _check(right, stages, ratio=1 / 3)["differs"]
    assert not _check(right, stages)["differs"]
    check = _check(_train(stages, 3.0), stages, ratio=1 / 3)
    assert check["differs"] and check["shaft"] == "output" and check["measured"] == 48
    bare = _train(stages, 1.0, harmonics=(3, 6), wheel=0.0)
    assert _check(bare, stages, ratio=1 / 3)["shaft"] == "output"
    assert _check(bare, stages, ratio=1.0).get("shaft") is None


def test_inspect_names_the_shaft_an_output_tacho_reads(tmp_path, cli):
    """rig16 ([sensor] tacho = 'input') and a record whose tacho pulses once per output turn: inspect
    said 'matches' (the mesh at 48, its lines all on the 16-tooth comb); now the shaft and the option.
    With --tacho-shaft output, and the input tacho's record, it matches."""
    for name, turns in (("out", Fraction(1, 3)), ("in", Fraction(1))):
        record(tmp_path / f"{name}.csv", turns, seconds=2.4, orders=(16, 32, 48), wobble=0.0)
    base = ["inspect", "--gearbox", RIG16, "--vibration", "acc_V", "--tacho", "tacho_V", "--json"]
    verdicts = {}
    for name, extra in (("out", []), ("out", ["--tacho-shaft", "output"]), ("in", [])):
        code, out, err = cli(*base[:1], tmp_path / f"{name}.csv", *base[1:], *extra)
        assert code == 0, err
        verdicts[name, bool(extra)] = json.loads(out)["verdict"]
    assert verdicts["out", False].startswith(
        "the description 'rig16' differs: stage 1: mesh order 48 measured, 16 expected (every order reads 3 x its "
        "own, as when a tacho on the output shaft is read as on the input: the tacho reads the output shaft? "
        "--tacho-shaft output"
    ), verdicts
    assert "matches" in verdicts["out", True] and "matches" in verdicts["in", False], verdicts


def test_every_kind_takes_the_description_s_pulses_per_rev_by_default(tmp_path, write_scenario):
    """[sensor] pulses_per_rev of the description (the [source]'s, or a dataset entry's 'gearbox') is
    the default of the gap's, the detection's and a dataset entry's 'pulses_per_rev', as it is
    inspect's; the key given wins (1 included). Before, these kinds read 1 by default."""
    from gearlab.engine import load_scenario

    (tmp_path / "rig16.toml").write_text(RIG16.read_text() + "pulses_per_rev = 2\n")
    for name in ("h0", "h1", "t0", "t1"):
        record(tmp_path / f"{name}.csv", Fraction(1), seconds=0.3)
    gap = DETECT.format(name="g", folder=".", shaft="{key}").replace('kind = "detection"', 'kind = "gap"')
    gap = gap.split("[detection]")[0].replace("teeth = [1, 2]\nfaults = { chip = [20] }\nhealthy = 6\n", "")
    gap = gap.replace('  { file = "./t0.csv", role = "test", label = "healthy" },\n', "")
    gap = (
        gap.replace('  { file = "./t1.csv", role = "test", label = "fault" },\n', "") + "[accuracy]\nenabled = false\n"
    )
    dataset = '[scenario]\nname = "d"\nkind = "dataset"\n[[datasets]]\nfile = "h0.csv"\nvibration = "acc_V"\n'
    dataset += 'tacho = "tacho_V"\ngearbox = "rig16.toml"\nsensitivity = "100 mV/g"\n{key}\n'
    detect = DETECT.format(name="d", folder=".", shaft="{key}")
    for key, pulses in (("", 2), ("pulses_per_rev = 1", 1), ("pulses_per_rev = 3", 3)):
        specs = {
            k: load_scenario(write_scenario(t.replace("{key}", key), f"{k}.toml")).spec
            for k, t in (("gap", gap), ("detect", detect), ("dataset", dataset))
        }
        assert specs["gap"].target.target.pulses_per_rev == pulses, key
        assert specs["detect"].target.pulses_per_rev == pulses, key
        assert specs["dataset"][0].pulses_per_rev == pulses, key
