"""The tiny detection scenario of the detection tests (tests/test_detection*.py): five records of
textrecords, two of them history, its scenario file, and `gearlab run` of it in-process."""

import contextlib
import csv
import functools
import io
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from textrecords import FS, PULSES, record
from tiny import EXECUTION, schedule

# (file, role, label, chip size): two healthy history records, a healthy and two chipped test records
FILES = [
    ("h1", "history", "healthy", 0.0),
    ("h2", "history", "healthy", 0.0),
    ("h3", "test", "healthy", 0.0),
    ("f1", "test", "fault", 4.0),
    ("f2", "test", "fault", 4.0),
]


@functools.cache
def record_bytes(chip: float, seed: int) -> bytes:
    """The zip of a 40-revolution record (textrecords.record), made once per process: the same
    recordings go into many tests' folders, and writing their text is a good part of a small run."""
    with tempfile.TemporaryDirectory() as folder:
        return record(Path(folder) / "r.zip", revolutions=40, chip=chip, seed=seed, phase=0.7 * seed).read_bytes()


def scenario(
    folder: Path, files=FILES, methods=("source_only", "mmd", "matched_filter"), extra: str = "", detection: str = ""
) -> Path:
    """A tiny detection scenario in *folder*/scenarios, its records in *folder*/data (relative paths)."""
    (folder / "data").mkdir(exist_ok=True)
    (folder / "scenarios").mkdir(exist_ok=True)
    entries = []
    for i, (name, role, label, chip) in enumerate(files):
        path = folder / "data" / f"{name}.zip"
        if not path.exists():
            path.write_bytes(record_bytes(chip, i))
        entries.append(f'  {{ path = "../data/{name}.zip", role = "{role}", label = "{label}" }},')
    methods_text = "".join(f'[[methods]]\nadapter = "{m}"\n\n' for m in methods)
    text = (
        f'[scenario]\nname = "det"\nkind = "detection"\n\n'
        '[source]\npreset = "B-6-ch5"\nteeth = [1, 2, 3]\nfaults = { chip = [20] }\nhealthy = 9\n\n'
        f'[target]\nvibration = 0\ntacho = "2"\npulses_per_rev = {PULSES}\nsensitivity = "10 mV/g"\n'
        f'fs = "{FS} Hz"\nfiles = [\n' + "\n".join(entries) + "\n]\n\n"
        f"[classical]\nmesh_orders = [32]\n\n[detection]\nblocks = [5, 10]\n{detection}\n"
        f'[network]\nname = "fast"\n\n{methods_text}[protocol]\n{schedule(2)}\n{EXECUTION}\n{extra}'
    )
    path = folder / "scenarios" / "det.toml"
    path.write_text(text)
    return path


def run(cli, path: Path, out: Path) -> Path:
    code, stdout, err = cli("run", path, "--out", out)
    assert code == 0, err
    return Path(stdout.strip().splitlines()[-1].split(": ", 1)[1])


def without_figures(monkeypatch) -> None:
    """The report's figures not drawn (2-3 s of a tiny run's 5): they are drawn from the run's files after
    every score is written, and the tests that read them, or only need them drawn for a setup of their
    own (test_the_report_draws..., the first run of test_test_labels..., test_a_corrected_source_trains...,
    test_pinion_sync_runs_end_to_end...), keep them."""
    monkeypatch.setattr("gearlab.kinds.detection.draw_figures", lambda run: None)


def run_in_module(
    path: Path, out: Path, cwd: Path | None = None, figures: bool = True, events: Path | None = None
) -> Path:
    """`gearlab run` in-process as run() does, for a module's fixture (the cli fixture is a test's own),
    from the folder *cwd* if given, without the report's figures unless *figures*. *events*: run with
    `--events` (as the TUI starts a run) and its event lines written there, for a TUI test to replay."""
    import json

    from gearlab.cli import main

    stdout, stderr = io.StringIO(), io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        mp.setattr(sys, "argv", ["gearlab", "run", str(path), "--out", str(out), *(["--events"] if events else [])])
        if cwd:
            mp.chdir(cwd)
        if not figures:
            without_figures(mp)
        try:
            main()
        except SystemExit as exc:
            assert not exc.code, stderr.getvalue()
    if events is None:
        return Path(stdout.getvalue().strip().splitlines()[-1].split(": ", 1)[1])
    lines = stdout.getvalue().splitlines()
    events.write_text("\n".join(lines) + "\n")
    (made,) = [json.loads(x)["message"] for x in lines if x.startswith("{") and json.loads(x)["kind"] == "run"]
    return Path(cwd or ".") / made


def shared_run(path: Path, out: Path) -> Path:
    """run_in_module's run of the scenario *path* (without figures), made once in the test session for its
    folder's content: 12 test files that score new takes against the tiny run each ran the same scenario on
    the same records (0.7 s of CPU a run, and its datasets in each module's cache). The first to ask runs it
    and stores its run directory
    in the session's folder (conftest.SHARED_RUNS); the others get a copy under *out*, every mention of the
    first one's folder in its text files turned into theirs, as if run there. The key is the scenario's
    text and every file in its folder (path.parent.parent, *out* apart) at the time of the call; a
    test that watches the run itself (a spy, an event) runs it with run_in_module. A lock keeps two test
    processes from running the same scenario at once."""
    import hashlib
    import os
    import shutil

    try:
        import fcntl
    except ImportError:  # no POSIX file locks (Windows): each test runs its own
        return run_in_module(path, out, figures=False)
    folder = path.parent.parent
    key = hashlib.sha256(str(path.relative_to(folder)).encode())
    for file in sorted(p for p in folder.rglob("*") if p.is_file() and out not in p.parents):
        key.update(f"{file.relative_to(folder)}\0".encode())
        key.update(hashlib.sha256(file.read_bytes()).digest())
    store = Path(os.environ["GEARLAB_TEST_RUNS"]) / key.hexdigest()[:32]
    with open(f"{store}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not store.exists():
            made = run_in_module(path, out, figures=False)
            work = store.with_suffix(".part")
            shutil.copytree(made, work / made.relative_to(out))
            (work / "folder").write_text(str(folder))
            work.rename(store)
            return made
    (made,) = [p for p in store.glob("*/*") if p.is_dir()]
    run = shutil.copytree(made, out / made.relative_to(store))
    origin = (store / "folder").read_text()
    for file in run.rglob("*"):
        if file.suffix in TEXT_FILES and origin in (text := file.read_text()):
            file.write_text(text.replace(origin, str(folder)))
    left = [f.name for f in run.rglob("*") if f.is_file() and origin.encode() in f.read_bytes()]
    assert not left, f"{left} of the shared run still name {origin}"
    return run


TEXT_FILES = {".json", ".jsonl", ".html", ".md", ".csv", ".toml", ".txt"}  # what a run writes as text


# two healthy history takes; test: a healthy take at twice the gain (h3), one at the history's (h4), two chipped, one
# of them (f2) at twice the gain (tests/test_detection_level_change.py, test_score_level_measure.py)
GAIN_FILES = [
    ("h1", "history", "healthy", 0.0),
    ("h2", "history", "healthy", 0.0),
    ("h3", "test", "healthy", 0.0),
    ("h4", "test", "healthy", 0.0),
    ("f1", "test", "fault", 4.0),
    ("f2", "test", "fault", 4.0),
]
DOUBLED = {"h3": (0.0, 2), "f2": (4.0, 5)}  # name: (chip, seed)


def gain_run(folder: Path) -> Path:
    """The finished run of the tiny scenario with GAIN_FILES in *folder* (shared_run: one per process)."""
    from textrecords import signals, text, write_zip

    (folder / "data").mkdir(exist_ok=True)
    for name, (chip, seed) in DOUBLED.items():
        vib, tacho = signals(revolutions=40, chip=chip, seed=seed, phase=0.7 * seed)
        write_zip(folder / "data" / f"{name}.zip", text(2.0 * vib, tacho))
    return shared_run(scenario(folder, files=GAIN_FILES, methods=("source_only",)), folder / "runs")


def scores(run_dir: Path) -> list[dict]:
    with (run_dir / "scores.csv").open() as f:
        return list(csv.DictReader(f))


def flipped(files, signals: bool = False):
    """The test files' labels swapped (and, with *signals*, other recordings under the same names)."""
    out = []
    for name, role, label, chip in files:
        if role == "test":
            label = {"healthy": "fault", "fault": "healthy"}[label]
            if signals:
                chip = 4.0 - chip
        out.append((name, role, label, chip))
    return out


def training_spy(monkeypatch) -> list:
    """The target rows every training of this test is handed: a spy on the protocol's train_method,
    set with *monkeypatch* (the test's, which removes it)."""
    import gearlab.learn.protocol as P

    seen = []
    train_method = P.train_method

    def spy(protocol, method, source, source_val, target, *args, **kwargs):
        seen.append(np.array(target[0], copy=True))
        return train_method(protocol, method, source, source_val, target, *args, **kwargs)

    monkeypatch.setattr(P, "train_method", spy)
    return seen


def call_every_row(monkeypatch) -> None:
    """`gearlab score` in-process with every classical row's thresholds put under its scores: each row calls."""
    from gearlab.kinds import detection_scoring

    real = detection_scoring.classical_record

    def placed(*args, **kwargs):
        got = real(*args, **kwargs)
        for units in got["test_scores"].values():
            for u, s in units.items():
                got["thresholds"][u] = float(np.min(s) - 1.0)
        return got

    monkeypatch.setattr(detection_scoring, "classical_record", placed)
