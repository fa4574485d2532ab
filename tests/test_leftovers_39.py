"""Issue 39's leftovers of the last session: the gap's structure line read outward from a tacho on
any shaft, inspect's caveats carried into the gap's verdict, summary.json's structure reading, the
no-tacho input pinion's tooth caveat, records with and without a tacho in one target, and `gearlab
score` reading new files with the run's own test-file keys."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gearboxes import described_pair
from test_outside_round9 import _train

TWO = ((38, 89), (49, 95))
THREE = ((19, 47), (23, 59), (29, 71))


def _rows(train, described, tacho: str, n: int = 600, points: int = 512) -> tuple:
    """*train*'s input revolutions as the gap cuts them against *described* with the tacho on the input
    or the output (the output tacho's angle times the described ratio), and the chain that says so."""
    from gearlab.data.chain import Chain

    f, ratio, said = 30.0, math.prod(a / b for a, b in train), math.prod(a / b for a, b in described)
    scale = 1.0 if tacho == "input" else said / ratio
    cut = 2 * np.pi * np.arange(n * points) / points * scale
    chain = Chain(fs=points * f / scale, speed=f / scale, tacho_shaft=tacho)
    return _train(cut, train, seed=1).reshape(n, points), chain


def _one_off(train, k: int, gear: str) -> tuple:
    described = [list(s) for s in train]
    described[k][gear == "wheel"] -= 1
    return tuple(map(tuple, described))


@pytest.mark.parametrize("tacho", ["input", "output"])
@pytest.mark.parametrize(
    "train, k, gear",
    [(TWO, k, g) for k in range(2) for g in ("pinion", "wheel")]
    + [(THREE, k, g) for k in range(3) for g in ("pinion", "wheel")],
)
def test_a_tooth_count_one_off_reads_alike_whichever_shaft_carries_the_tacho(train, k, gear, tacho):
    # a 38/89 + 48/95 described for 49/95 with the tacho on the input read 'stage 2: mesh order 20.92
    # measured, 20.49 expected: ... (the target's mesh is 49.0 such teeth: a tooth count of stage 2, or a
    # wheel upstream, differs)' where the output tacho's line said 'stage 2 pinion: 49 teeth fit the
    # recording, 48 described'; a first pinion one off with an input tacho read 'mesh orders 38 and 20.92
    # measured ... another gear train', stage 1 unnamed
    from gearlab.gap.structure import structure_line

    described = _one_off(train, k, gear)
    rows, chain = _rows(train, described, tacho)
    line = structure_line(rows, described_pair(*described), 200, chain, None, {})
    true, said = train[k][gear == "wheel"], described[k][gear == "wheel"]
    head = f"stage {k + 1} {gear}: {true} teeth fit the recording, {said} described; read outward from the tacho on "
    assert line is not None and line.startswith(head + f"the {tacho} shaft"), line
    assert f"the {gear} shows {true}.0" in line and "wheel upstream" not in line, line


@pytest.mark.parametrize("tacho", ["input", "output"])
@pytest.mark.parametrize("train", [TWO, THREE])
def test_the_right_counts_pass_whichever_shaft_carries_the_tacho(train, tacho):
    from gearlab.gap.structure import structure_line

    rows, chain = _rows(train, train, tacho)
    record: dict = {}
    assert structure_line(rows, described_pair(*train), 200, chain, None, record) is None
    assert "unchecked" not in record, record


def test_a_shaft_no_sideband_shows_is_said_in_the_gap_s_verdict_as_inspect_says_it():
    # a 38/89 + 49/95 record whose intermediate shaft modulates neither mesh: inspect said 'no sideband shows
    # the order of the intermediate shaft, so a wheel on it is checked only through a later stage's mesh
    # order, if any'; the gap's structure passed with nothing said (summary.json, CLI and report alike)
    from gearlab.data.chain import Chain
    from gearlab.gap.structure import _lines, _PairDescription, structure_line
    from gearlab.gearbox.match import check_description, unchecked
    from gearlab.kinds.gap_verdict import gap_lines

    n, points, o = 300, 512, 38 / 89
    theta = 2 * np.pi * np.arange(n * points) / points
    x = (1 + 0.15 * np.cos(theta + 0.4)) * np.cos(38 * theta)
    x = x + 0.7 * (1 + 0.1 * np.cos(o * 49 / 95 * theta + 1.0)) * np.cos(49 * o * theta + 1.0)
    rows = (x + np.random.default_rng(1).normal(0, 0.06, x.size)).reshape(n, points)
    pair, record = described_pair(*TWO), {}
    assert (
        structure_line(rows, pair, 200, Chain(fs=points * 30.0, speed=30.0, tacho_shaft="input"), None, record) is None
    )
    box = _PairDescription.train(pair)
    inspected = unchecked(check_description(_lines(rows, 200), box, n, True, 0), box, None)
    said = "no sideband shows the order of the intermediate shaft, so a wheel on it is checked only through a later"
    assert any(u.startswith(said) for u in inspected), inspected  # inspect's caveat ...
    assert record["unchecked"]["items"] == inspected, record  # ... is the gap's, word for word
    summary = {"gap_before": 12.0, "gap_after": 12.0, "p_before": 0.4, "p_after": 0.4, "views": {"mesh": {}}}
    summary |= {"verdict": "no significant gap", "effects": [], "structure": record}
    lines = gap_lines(summary)
    assert any(line.startswith("Structure not fully checked: " + said) for line in lines), lines


@pytest.mark.parametrize("turns", [(52, 52, 53), (150, 150, 160)])
def test_the_structure_s_mesh_record_is_the_reading_the_line_was_decided_on(turns):
    # three takes of a 43/89 record (input tacho) described with 88 teeth: the line reads the wheel within the
    # longest take ('89.0 ± 1.8 ... need 103'), but summary.json's structure.mesh (first_difference's record,
    # written as it is) showed the takes laid end to end, their output shafts out of register: 88.2 ± 0.7,
    # as if the wrong description held
    import re

    from test_gap_structure_short import Z1, records

    from gearlab.gap.structure import structure_line

    rows, chain = records(turns)
    record: dict = {}
    line = structure_line(rows, described_pair((Z1, 88)), 400, chain, None, record)
    said = line or record["unchecked"]["line"]
    z, spread = map(float, re.search(r"(\d+\.\d) ± (\d+\.\d)", said).groups())
    mesh = record["mesh"]
    assert mesh["read_on"] == "the longest of 3 records" and mesh["revolutions"] == max(turns), mesh
    assert round(mesh["inspect"]["z2_seen"], 1) == z == 89.0, (mesh["inspect"], said)
    assert round(mesh["inspect"]["z2_resolution"], 1) == spread, (mesh["inspect"], said)
    one, chain = records((max(turns),))
    record = {}
    structure_line(one, described_pair((Z1, 89)), 400, chain, None, record)
    assert record["mesh"]["read_on"] == "all revolutions" and record["mesh"]["revolutions"] == max(turns)


def test_without_a_tacho_the_input_pinion_s_tooth_says_it_holds_in_this_take_only(tmp_path):
    # no tacho: a take's angle zero is its first sample, so no gear's tooth is fixed across takes; the slower
    # shafts said so (6c7d616), the input pinion read "tooth 16 of 19" plainly, a number no one can act on
    from gearboxes import description, stage
    from test_which_gear_parity import TEETH, take

    from gearlab.gearbox import resolve_gearbox
    from gearlab.inspect import InspectOptions
    from gearlab.inspect_history import localisation
    from gearlab.signals.localise import THIS_TAKE

    (tmp_path / "b.toml").write_text(description(*(stage(*z) for z in TEETH), name="nt", speed="20 Hz", near="input"))
    history = [str(take(tmp_path / f"h{k}.npz", None, 11 + k, 0.010 + 0.002 * k)) for k in range(3)]
    damaged = take(tmp_path / "in.npz", (0, "pinion", 7), 15, 0.013)
    box = resolve_gearbox(str(tmp_path / "b.toml"))
    found = localisation(str(damaged), history, box, InspectOptions(vibration="acc"))
    assert found["named"] == "input pinion 19T (stage 1)", found["summary"]
    tooth = next(s for s in found["shafts"] if s["shaft"] == "input")["tooth"]["input pinion 19T (stage 1)"]
    said = f"tooth {tooth['tooth']} of 19 ({THIS_TAKE}; this shaft's angle at a take's start is not known)"
    assert said in found["summary"], found["summary"]


def _h5(path, chip: float, seed: int) -> None:
    """A textrecords record as an HDF5 file: datasets 'vib' (V) and 'tach' (V), its rate an attribute."""
    import h5py
    from textrecords import FS, SENSITIVITY, signals

    vib, tacho = signals(revolutions=40, chip=chip, seed=seed, phase=0.7 * seed)
    with h5py.File(path, "w") as f:
        f.create_dataset("vib", data=vib * SENSITIVITY).attrs["fs"] = FS
        f.create_dataset("tach", data=tacho)


def test_score_reads_a_new_file_with_the_keys_of_the_run_s_files_of_its_format(cli, tmp_path, monkeypatch):
    # history in zipped text (channel 0, tacho column 2), tests in HDF5 ('vib', 'tach': their entries' own keys);
    # `gearlab score RUN next.h5` read it with the [target]'s keys: "no channel 0", unless --key was given again
    import json

    from detection_scenario import run, scenario, without_figures

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    without_figures(monkeypatch)
    files = [("h1", "history", "healthy", 0.0), ("h2", "history", "healthy", 0.0)]
    path = scenario(tmp_path, files=files, methods=("matched_filter",))
    tests = [("t_ok", "healthy", 0.0, 2), ("t_f1", "fault", 4.0, 3), ("t_f2", "fault", 4.0, 4)]
    entries = ""
    for name, label, chip, seed in tests:
        _h5(tmp_path / "data" / f"{name}.h5", chip, seed)
        own = 'vibration = "vib", tacho = "tach"'
        entries += f'  {{ path = "../data/{name}.h5", role = "test", label = "{label}", {own} }},\n'
    text = path.read_text().replace('label = "healthy" },\n]', 'label = "healthy" },\n' + entries + "]")
    path.write_text(text)
    out = run(cli, path, tmp_path / "runs")
    _h5(tmp_path / "next_ok.h5", 0.0, 11)
    _h5(tmp_path / "next_chip.h5", 4.0, 12)
    code, stdout, err = cli("score", out, tmp_path / "next_ok.h5", tmp_path / "next_chip.h5", "--json")
    assert code == 0, err
    by = {(r["file"].rsplit("/", 1)[-1], r["method"], r["unit"]): r["decision"] for r in json.loads(stdout)}
    assert by[("next_chip.h5", "fm4", "record10")] == "fault", by
    assert by[("next_ok.h5", "fm4", "record10")] == "healthy", by
    # a file in the history's format is read with the [target]'s keys; --key still overrides the remembered ones
    code, _, err = cli("score", out, tmp_path / "data" / "h1.zip")
    assert code == 0, err
    code, _, err = cli("score", out, tmp_path / "next_ok.h5", "--key", "vibration=nothing")
    assert code == 2 and "nothing" in err, err


@pytest.mark.parametrize("without", ["history", "test"])
def test_records_with_and_without_a_tacho_run_in_one_detection_target(cli, tmp_path, monkeypatch, without):
    # a history logged without a tacho and tests with one (or the reverse): "[target] key 'files' entry 1 key
    # 'tacho': a file's tacho names the [target]'s tacho channel in that file; expected a channel", exit 2.
    # Each record is now cut at its own tacho's angle, or at the declared speed, and all are aligned as
    # records without a tacho are (by correlation with the first history record's mean revolution)
    import json

    from detection_scenario import FILES, run, scenario, without_figures

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    without_figures(monkeypatch)
    path = scenario(tmp_path, methods=("matched_filter",))
    text = path.read_text().replace('fs = "', 'speed = "16 Hz"\nfs = "')  # for the records without a tacho
    for name, role, _, _ in FILES:
        if role == without:
            text = text.replace(f'{name}.zip", role', f'{name}.zip", tacho = "", role')
    path.write_text(text)
    out = run(cli, path, tmp_path / "runs")
    rows = json.loads((out / "summary.json").read_text())["rows"]
    fm4 = next(r for r in rows if r["method"] == "fm4" and r["unit"] == "record10")
    assert fm4["auc"] == 1.0, fm4
    table = (out / "table.md").read_text()  # each record's speed from its own tacho or the declared speed
    assert "| nominal speed 16 Hz |" in table and "| tacho '2' (10 pulses per revolution) |" in table, table
    scoring = json.loads((out / "scoring.json").read_text())
    assert scoring["tacho_records"] == "some"
    code, stdout, err = cli("score", out, tmp_path / "data" / "f1.zip", "--json")  # aligned as the run's were
    assert code == 0, err
    assert {r["decision"] for r in json.loads(stdout) if (r["method"], r["unit"]) == ("fm4", "record10")} == {"fault"}
    # the gap compares one acquisition chain: a history of both is one line, exit 2
    gap = tmp_path / "scenarios" / "gap.toml"
    gap.write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\npreset = "B-6-ch5"\n[target]\nvibration = 0\ntacho = "2"\n'
        'pulses_per_rev = 10\nsensitivity = "10 mV/g"\nfs = "8192 Hz"\nspeed = "16 Hz"\nfiles = [\n'
        '  { path = "../data/h1.zip", role = "history", label = "healthy" },\n'
        '  { path = "../data/h2.zip", role = "history", label = "healthy", tacho = "" },\n]\n'
    )
    code, _, err = cli("validate", gap)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "h1.zip has a tacho, ../data/h2.zip none; the gap compares one acquisition chain" in err, err


def test_a_last_wheel_no_sideband_shows_is_said_unchecked_not_checked_through_a_later_mesh():
    # a one-stage box's output shaft without sidebands read "so a wheel on it is checked only through a later
    # stage's mesh order, if any": there is none (the guide's 16/48 gap run said it after 'explained')
    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line

    n, points = 300, 512
    theta = 2 * np.pi * np.arange(n * points) / points
    x = (1 + 0.15 * np.cos(theta + 0.4)) * np.cos(38 * theta) + 0.3 * np.cos(76 * theta + 1.0)
    rows = (x + np.random.default_rng(2).normal(0, 0.06, x.size)).reshape(n, points)
    record: dict = {}
    chain = Chain(fs=points * 30.0, speed=30.0, tacho_shaft="input")
    assert structure_line(rows, described_pair((38, 89)), 200, chain, None, record) is None
    said = "no sideband shows the order of the output shaft, so the tooth count of its 89-tooth wheel is not checked"
    assert said in record["unchecked"]["items"], record["unchecked"]
    assert "later stage" not in record["unchecked"]["line"], record["unchecked"]
