"""A logger's file of several takes one after another, a column marking each sample's take (issue 39, an outside
user's mixer logger): `takes = "segment"` reads each take as a recording of its own, named "file.csv[segment=3]" in
a run's scores and in `gearlab score`; a time that restarts without it names the key to write."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from detection_scenario import run_in_module
from textrecords import FS, PULSES, SENSITIVITY, signals
from tiny import EXECUTION, schedule


def _log(path: Path, column: str, takes: list[tuple], restart: bool = True, revolutions: int = 40) -> Path:
    """A CSV of takes (chip, seed[, revolutions]) one after another under *column*: time (restarting at each take
    or running on), the accelerometer in V and a tacho of PULSES marks a turn."""
    rows = []
    for k, (chip, seed, *turns) in enumerate(takes, start=1):  # a take's own revolutions, where given
        vib, tacho = signals(revolutions=(turns or [revolutions])[0], chip=chip, seed=seed, phase=0.7 * seed)
        t = np.arange(vib.size) / FS + (0 if restart else len(rows) and rows[-1][1] + 1 / FS)
        rows += zip([k] * vib.size, t, vib * SENSITIVITY, tacho)
    path.write_text(f"{column},time_s,acc,tacho\n" + "".join(f"{k},{t:.7f},{v:.7e},{p:.2f}\n" for k, t, v, p in rows))
    return path


def test_a_take_s_name_reads_its_rows_alone_at_its_own_time(tmp_path):
    from gearlab.data.recordings import read_recording

    log = _log(tmp_path / "log.csv", "take", [(0.0, 1), (0.0, 2), (0.0, 3)], revolutions=8)
    rec = read_recording(f"{log}[take=2]", "acc", "tacho", sensitivity=SENSITIVITY)
    want, _ = signals(revolutions=8, seed=2, phase=1.4)
    assert rec.path.endswith("log.csv[take=2]") and rec.fs == pytest.approx(FS, rel=1e-6)
    assert rec.signal.size == want.size and np.allclose(rec.signal, want, atol=1e-5)


def test_a_time_that_restarts_names_the_key_to_write(tmp_path, cli):
    log = _log(tmp_path / "log.csv", "segment", [(0.0, 1), (0.0, 2)], revolutions=8)
    code, _, err = cli("inspect", log, "--vibration", "acc", "--tacho", "tacho", "--sensitivity", "10 mV/g")
    line = err.strip()
    assert code == 2 and "\n" not in line and "the time restarts at sample 4096" in line, err
    assert "takes = 'segment'" in line and "log.csv[segment=1]" in line and "one file per take" in line, line
    # one take by its name: inspected as a recording of its own
    tacho = ("--tacho", "tacho", "--pulses-per-rev", str(PULSES))
    code, out, err = cli("inspect", f"{log}[segment=2]", "--vibration", "acc", *tacho, "--json")
    got = json.loads(out)
    assert code == 0 and got["file"].endswith("log.csv[segment=2]") and got["revolutions"] in (7, 8), err


def _scenario(folder: Path, takes: str = "takes = 'take'") -> Path:
    _log(folder / "hist.csv", "take", [(0.0, 0), (0.0, 1)])
    _log(folder / "ok.csv", "segment", [(0.0, 2), (0.0, 5)], restart=False)
    _log(folder / "chip.csv", "segment", [(4.0, 3), (4.0, 4)], restart=False)
    text = (
        '[scenario]\nname = "det"\nkind = "detection"\n\n'
        '[source]\npreset = "B-6-ch5"\nteeth = [1, 2, 3]\nfaults = { chip = [20] }\nhealthy = 9\n\n'
        f'[target]\nvibration = "acc"\ntacho = "tacho"\npulses_per_rev = {PULSES}\nsensitivity = "10 mV/g"\n{takes}\n'
        'files = [\n  { file = "hist.csv", role = "history", label = "healthy" },\n'
        '  { file = "ok.csv", role = "test", label = "healthy", takes = "segment" },\n'
        '  { file = "chip.csv", role = "test", label = "fault", takes = "segment" },\n]\n\n'
        '[classical]\nmesh_orders = [32]\n\n[detection]\nblocks = [5, 10]\n\n[network]\nname = "fast"\n\n'
        f'[[methods]]\nadapter = "matched_filter"\n\n[protocol]\n{schedule(2)}\n{EXECUTION}'
    )
    path = folder / "det.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def takes_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("takes")
    return folder, run_in_module(_scenario(folder), folder / "runs", figures=False)


def test_each_take_of_a_file_is_a_record_of_a_detection_run(takes_run):
    import csv

    _, run = takes_run
    with (run / "scores.csv").open() as f:
        rows = list(csv.DictReader(f))
    named = {r["file"] for r in rows}
    assert named == {"ok.csv[segment=1]", "ok.csv[segment=2]", "chip.csv[segment=1]", "chip.csv[segment=2]"}, named
    # the chipped takes scored over the healthy ones by fm4 (a record's decision 1: called)
    called = {r["file"] for r in rows if r["method"] == "fm4" and r["unit"] == "record10" and r["decision"] == "1"}
    assert called == {"chip.csv[segment=1]", "chip.csv[segment=2]"}, called


def test_score_scores_each_take_of_a_new_file(takes_run, cli):
    folder, run = takes_run
    new = _log(folder / "today.csv", "segment", [(0.0, 7), (4.0, 8)])
    code, out, err = cli("score", run, new, "--key", "takes=segment", "--json")
    assert code == 0, err
    rows = json.loads(out)
    decided = {r["file"].rsplit("/", 1)[-1]: r["decision"] for r in rows if r["method"] == "fm4"}
    assert decided == {"today.csv[segment=1]": "healthy", "today.csv[segment=2]": "fault"}, decided
    assert "today.csv[segment=2]" in (run / "scoring" / "history.jsonl").read_text()
    # without --key, a file with a column the run's files were split by ('take', 'segment') is split so too
    later = _log(folder / "later.csv", "take", [(0.0, 9), (4.0, 10)])
    code, out, err = cli("score", run, later, "--json")
    decided = {r["file"].rsplit("/", 1)[-1]: r["decision"] for r in json.loads(out) if r["method"] == "fm4"}
    assert code == 0 and decided == {"later.csv[take=1]": "healthy", "later.csv[take=2]": "fault"}, (decided, err)
    # the column missing: one line naming the option, the vibration-like columns offered
    code, _, err = cli("score", run, new, "--key", "takes=segmnt")
    assert code == 2 and "--key takes" in err and "did you mean 'segment'" in err and "\n" not in err.strip(), err


def test_validate_checks_the_takes_column_and_a_short_take_is_said_as_a_short_file(tmp_path, cli):
    code, out, err = cli("validate", _scenario(tmp_path))
    assert code == 0 and "'hist.csv': 2 takes ('take'), 'ok.csv': 2 takes ('segment')" in out, (out, err)
    path = _scenario(tmp_path, "takes = 'tke'")
    code, _, err = cli("validate", path)
    line = err.strip()
    assert code == 2 and "\n" not in line and "[target] key 'takes'" in line and "hist.csv" in line, err
    assert "has no column 'tke'" in line and "did you mean 'take'" in line, line
    # a take of a single revolution: refused as a file of one revolution is, naming the take
    _log(tmp_path / "hist.csv", "take", [(0.0, 0), (0.0, 1, 1)])
    path.write_text(path.read_text().replace("takes = 'tke'", "takes = 'take'"))
    code, _, err = cli("run", path, "--out", tmp_path / "runs")
    line = err.strip().splitlines()[-1]
    assert code == 2 and "entry 1 key 'file'" in line and "hist.csv[take=2]:" in line, err
    assert "the record shows 0.998 revolutions in 512 samples" in line and "expected at least 2" in line, line


def test_inspect_reads_a_history_file_s_takes_each_a_history_record(tmp_path, cli):
    # the healthy history logged as two takes in one file (the time restarting): --history-key takes=take
    from gearlab.data.simulated import simulated_record

    recs = [simulated_record(f, speed_hz=40.0, revolutions=80, snr_db=30.0, seed=s) for f, s in (([], 1), ([], 2))]
    rows = [
        f"{k},{i / r.fs:.8f},{v:.6e},{p:.3f}\n"
        for k, r in enumerate(recs, 1)
        for i, (v, p) in enumerate(zip(r.vibration, r.tacho))
    ]
    (tmp_path / "hist.csv").write_text("take,time_s,acc,tacho\n" + "".join(rows))
    crack = simulated_record(
        [{"name": "crack", "gear": "output gear", "tooth": 30, "step": 20}],
        speed_hz=40.0,
        revolutions=80,
        snr_db=30.0,
        seed=3,
    )
    np.savez(tmp_path / "cracked.npz", acc=crack.vibration, tacho=crack.tacho, fs=crack.fs)
    common = ["--gearbox", "phm09", "--vibration", "acc", "--tacho", "tacho", "--pulses-per-rev", "1"]
    history = ["--history", tmp_path / "hist.csv", "--history-key", "takes=take", "--json"]
    code, out, err = cli("inspect", tmp_path / "cracked.npz", *common, *history)
    loc = json.loads(out)["localisation"] if code == 0 else {}
    assert code == 0 and [Path(h).name for h in loc["history"]] == ["hist.csv[take=1]", "hist.csv[take=2]"], err
    assert loc["named"] == "output gear 80T (stage 2)", loc["summary"]


def test_a_gap_diagnosis_reads_its_history_take_by_take(tmp_path, cli):
    # the gap's [target] is read by the same keys: its history file's takes, each a history record
    _log(tmp_path / "hist.csv", "take", [(0.0, 0), (0.0, 1)])
    text = (
        '[scenario]\nname = "g"\nkind = "gap"\n\n[source]\npreset = "B-6-ch5"\n\n'
        f'[target]\nvibration = "acc"\ntacho = "tacho"\npulses_per_rev = {PULSES}\nsensitivity = "10 mV/g"\n'
        'takes = "take"\nfiles = [{ file = "hist.csv", role = "history", label = "healthy" }]\n'
    )
    (tmp_path / "gap.toml").write_text(text)
    code, out, err = cli("validate", tmp_path / "gap.toml")
    assert code == 0 and "2 measured history records ('hist.csv': 2 takes ('take'))" in out, (out, err)
    # a dataset's 'file' is one recording: its takes refused in one line naming the take to write
    (tmp_path / "ds.toml").write_text(
        '[scenario]\nname = "d"\nkind = "dataset"\n\n[[datasets]]\nfile = "hist.csv"\nvibration = "acc"\n'
        'tacho = "tacho"\nsensitivity = "10 mV/g"\ntakes = "take"\n'
    )
    code, _, err = cli("validate", tmp_path / "ds.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "key 'takes'" in line and "file = 'hist.csv[take=1]'" in line, err
    (tmp_path / "ds.toml").write_text(
        (tmp_path / "ds.toml").read_text().replace('"hist.csv"', '"hist.csv[take=2]"').replace('takes = "take"\n', "")
    )
    code, out, err = cli("validate", tmp_path / "ds.toml")
    assert code == 0 and "hist[take=2] (measured)" in out, (out, err)


def test_a_take_column_whose_takes_interleave_is_refused_naming_the_take(tmp_path):
    # marks 1, 2, 1: not takes one after another (a channel number, a state): one line, the take that comes back
    from gearlab.data.takes import take_paths
    from gearlab.errors import GearlabInputError

    rows = "".join(f"{k},{i / 100:.2f},0.1\n" for i, k in enumerate([1] * 5 + [2] * 5 + [1] * 5))
    (tmp_path / "mixed.csv").write_text("run,time_s,acc\n" + rows)
    with pytest.raises(GearlabInputError, match=r"column 'run': take '1' comes back after another take") as got:
        take_paths(tmp_path / "mixed.csv", "run", "[target] key 'takes'")
    assert str(got.value).startswith("[target] key 'takes': ") and "\n" not in str(got.value)
    # a take column of marks written as decimals (1.0, 2.0): named as whole numbers
    rows = "".join(f"{k:.1f},{i / 100:.2f},0.1\n" for i, k in enumerate([1] * 5 + [2] * 5))
    (tmp_path / "float.csv").write_text("run,time_s,acc\n" + rows)
    assert take_paths(tmp_path / "float.csv", "run", "x", "float.csv") == ["float.csv[run=1]", "float.csv[run=2]"]
