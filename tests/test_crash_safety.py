"""Crash safety of runs (docs/scenarios.md, runs and --resume): one process per run directory, and runs killed at
random moments resume with nothing lost, nothing repeated and the same numbers.

The runs are real `gearlab run` processes, killed with SIGKILL on their whole process group
(what an out-of-memory kill, a `kill -9` or a lost node does: no cleanup of any kind), then
resumed; what they leave must equal a run that was never interrupted.
"""

from __future__ import annotations

import fcntl
import glob
import io
import json
import os
import random
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import unrendered
from test_protocol import TINY, UNITS
from tiny import bare_dataset, run_once, stiffness

from gearlab.data import cache
from gearlab.data.spec import Dataset, DatasetSpec
from gearlab.engine import run_scenario
from gearlab.runs import LOCK_FILE

pytestmark = pytest.mark.usefixtures("one_torch_thread")

CLI = [sys.executable, "-c", "from gearlab.cli import main; main()"]

STIFFNESS = stiffness(
    512,
    ["crack", "chip", "spall", "pit"],
    (1, 6),
    tooth=5,
    cases='[[cases]]\nname = "two faults"\n'
    'faults = [{ kind = "crack", tooth = 2, step = 12 }, { kind = "pit", tooth = 9, step = 20 }]\n',
)
STIFFNESS_UNITS = 1 + 4 * 6 + 1
# test_protocol's tiny transfer scenario once (its four methods at k 0 and 2): 8 units, a kill may land in
# any kind of them; its second repetition only doubled the training of the reference and of the resume.
TINY_ONCE = TINY.replace("repetitions = 2", "repetitions = 1")
UNITS_ONCE = [unit for unit in UNITS if unit.startswith("rep0/")]
assert TINY_ONCE != TINY and len(UNITS_ONCE) == 8


# ----------------------------------------------------------------------------- helpers


def start(args: list, cwd: Path, cache_dir: Path) -> subprocess.Popen:
    """`gearlab ARGS` in its own process group (so that its workers die with it); output to
    files, which never fill up and block the process as an unread pipe would."""
    env = {**os.environ, "GEARLAB_CACHE": str(cache_dir)}
    log = cwd / f"out{len(list(cwd.glob('out*.txt')))}.txt"
    with open(log, "w") as f:
        proc = subprocess.Popen(
            [*CLI, *map(str, args)], cwd=cwd, env=env, start_new_session=True, stdout=f, stderr=subprocess.STDOUT
        )
    proc.log = log
    return proc


def output(proc: subprocess.Popen) -> str:
    return proc.log.read_text()


def holder(run: Path) -> str:
    try:
        return (run / LOCK_FILE).read_text().strip()
    except FileNotFoundError:
        return ""


def wait_until_holding(proc: subprocess.Popen, pattern: Path, timeout: float = 120.0) -> Path | None:
    """The run directory (matching the glob *pattern*) whose lock *proc* holds, once it holds it:
    past its imports and its checks, at work. None when the process ended first."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for lock in glob.glob(str(pattern / LOCK_FILE)):
            if holder(Path(lock).parent) == str(proc.pid):
                return Path(lock).parent
        if proc.poll() is not None:
            return None
        time.sleep(0.01)
    kill(proc)
    pytest.fail(f"no run started within {timeout} s:\n{output(proc)}")


def kill(proc: subprocess.Popen) -> None:
    """SIGKILL to the process and every process it started, returning once all of them are gone: a worker
    child holds the run's lock file too (inherited), and the kernel drops the flock only when the last
    holder exits; the leader reaped first, a busy machine left a child dying (the suite, 2 workers: the
    --resume after kill() refused once, 'another gearlab process ... is running')."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()
    for _ in range(1000):  # at most 10 s: SIGKILL cannot be caught; a zombie holds no file
        if not _alive_in_group(proc.pid):
            return
        time.sleep(0.01)


def _alive_in_group(pgid: int) -> bool:
    """Whether a process of group *pgid* still runs (not a zombie), from /proc (Linux; elsewhere: no)."""
    for stat in glob.glob("/proc/[0-9]*/stat"):
        try:
            fields = Path(stat).read_text().rsplit(")", 1)[1].split()
        except OSError:  # ended meanwhile
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":  # state, ppid, pgrp
            return True
    return False


def lines_of(run: Path) -> list[str]:
    return (run / "results.jsonl").read_text().splitlines(keepends=True)


def by_unit(run: Path) -> dict[str, dict]:
    return {r["unit"]: r for r in map(json.loads, lines_of(run))}


def units_done(run: Path) -> int:
    path = run / "results.jsonl"
    return path.read_bytes().count(b"\n") if path.exists() else 0


def kill_and_resume(tmp_path: Path, scenario: Path, cache_dir: Path, cli, kills: list[tuple[int, float]]) -> Path:
    """Start a run and SIGKILL it, resume it and kill it again, once per (units, seconds) of
    *kills*: the kill comes *seconds* after the run has *units* units done (0: after it took its
    run directory), wherever the run then is. Then resume it to the end (in this process,
    which saves an interpreter start). Returns the run directory."""
    runs = tmp_path / "runs"
    run = None
    moments = []
    for units, seconds in kills:
        args = ["run", scenario, "--out", runs] if run is None else ["run", "--resume", run]
        proc = start(args, tmp_path, cache_dir)
        run = wait_until_holding(proc, runs / "*" / "*" if run is None else run) or run
        if run is not None:
            while proc.poll() is None and units_done(run) < units:
                time.sleep(0.005)
        time.sleep(seconds)
        kill(proc)
        moments.append(
            f"killed {seconds:.2f} s after {units} units: {units_done(run) if run else 0} units done, "
            f"exit {proc.returncode}"
        )
    assert run is not None, moments
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GEARLAB_CACHE", str(cache_dir))
        code, out, err = cli("run", "--resume", run)
    print(*moments, sep="\n")  # after cli() read its output: shown when the test fails
    assert code == 0, "\n".join(moments) + "\n" + err
    assert out.splitlines()[-1] == f"run directory: {run}"
    return run


def assert_same_run(run: Path, reference: Path, units: list[str]) -> None:
    """Every unit exactly once, whole lines only, records and tables as in the reference run,
    and no temporary file of a killed write left in the run directory."""
    lines = lines_of(run)
    assert all(line.endswith("\n") for line in lines)
    assert sorted(json.loads(line)["unit"] for line in lines) == sorted(units)
    assert by_unit(run) == by_unit(reference)
    for name in ("table.md", "table.csv"):
        assert (run / name).read_text() == (reference / name).read_text(), name
    assert not [p for p in run.rglob("*.tmp")], "temporary files left in the run directory"


def assert_cache_whole(cache_dir: Path) -> None:
    """Every entry in the cache reads back whole (np.load checks each member's CRC)."""
    for entry in cache_dir.glob("*.npz"):
        with np.load(entry, allow_pickle=False) as data:
            for name in data.files:
                data[name]


@pytest.fixture(scope="module")
def tiny_reference(tmp_path_factory):
    """The tiny transfer scenario run without interruption, with a cache of its own (its figures
    unrendered: the runs are compared by their records and tables)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("gearlab.plots.save", unrendered)
        return run_once(tmp_path_factory.mktemp("reference"), "tiny.toml", TINY_ONCE)


@pytest.fixture(scope="module")
def stiffness_reference(tmp_path_factory):
    base = tmp_path_factory.mktemp("reference")
    (base / "stiff.toml").write_text(STIFFNESS)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("gearlab.plots.save", unrendered)  # compared by summary, records and cases
        return run_scenario(base / "stiff.toml", out=base / "runs").path


# ----------------------------------------------------------------------------- the lock


def test_second_process_in_a_run_directory_is_refused_and_a_killed_one_blocks_nothing(
    tmp_path, cli, stiffness_reference
):
    scenario = tmp_path / "stiff.toml"
    scenario.write_text(STIFFNESS)
    first = start(["run", scenario, "--out", tmp_path / "runs"], tmp_path, tmp_path / "cache")
    run = wait_until_holding(first, tmp_path / "runs" / "stiff" / "*")
    assert run is not None, output(first)
    os.killpg(first.pid, signal.SIGSTOP)  # alive, holding the lock, for as long as the test needs
    try:
        code, out, err = cli("run", "--resume", run)
        assert code == 2, err
        assert err.splitlines() == [
            f"error: {run}: another gearlab process (pid {first.pid}) is running in this "
            "run directory; wait for it to end (or stop it), then resume"
        ]
        assert holder(run) == str(first.pid)
    finally:
        kill(first)  # SIGKILL: no chance to release anything; the kernel drops the flock
    assert holder(run) == str(first.pid)  # the lock file stays behind, stale
    code, out, err = cli("run", "--resume", run)
    assert code == 0, err
    assert out.splitlines()[-1] == f"run directory: {run}"
    assert_same_run(run, stiffness_reference, list(by_unit(stiffness_reference)))
    # released at the end, its file removed: no stale lock is left
    assert not (run / LOCK_FILE).exists()


def test_lock_is_held_for_the_whole_run_in_process(tmp_path):
    """A run in this process holds the lock while its kind runs (the TUI and the CLI share this)."""
    from gearlab.kinds import stiffness

    scenario = tmp_path / "stiff.toml"
    short = STIFFNESS.replace("steps = [1, 6]", "steps = [1, 1]")  # a short run is enough here
    assert short != STIFFNESS
    scenario.write_text(short)
    seen = []
    real = stiffness.run

    def probe(scenario, run, on_event):
        with open(run.path / LOCK_FILE) as f:
            try:
                fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                seen.append("held")
        return real(scenario, run, on_event)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(stiffness, "run", probe)
        run_scenario(scenario, out=tmp_path / "runs")
    assert seen == ["held"]


# ----------------------------------------------------------------------------- kill and resume


def test_transfer_run_killed_three_times_equals_an_uninterrupted_one(tmp_path, cli, tiny_reference):
    """Killed at random moments: early (building its datasets into a cold cache, or priming),
    within a random training unit, and while it writes its summary and figures; then resumed."""
    rng = random.Random(5)
    scenario = tmp_path / "tiny.toml"
    scenario.write_text(TINY_ONCE)
    cache_dir = tmp_path / "cache"
    kills = [
        (0, rng.uniform(0.0, 1.5)),
        (rng.randint(1, len(UNITS_ONCE) - 2), rng.uniform(0.0, 0.05)),
        (len(UNITS_ONCE), rng.uniform(0.0, 1.0)),
    ]
    run = kill_and_resume(tmp_path, scenario, cache_dir, cli, kills)
    assert_same_run(run, tiny_reference, UNITS_ONCE)
    summary, reference = (json.loads((r / "summary.json").read_text()) for r in (run, tiny_reference))
    assert summary["table"] == reference["table"] and summary["units"] == len(UNITS_ONCE)
    assert_cache_whole(cache_dir)


def test_stiffness_run_killed_three_times_equals_an_uninterrupted_one(tmp_path, cli, stiffness_reference):
    rng = random.Random(11)
    scenario = tmp_path / "stiff.toml"
    scenario.write_text(STIFFNESS)
    kills = [
        (rng.randint(1, 10), rng.uniform(0.0, 0.05)),
        (rng.randint(11, STIFFNESS_UNITS - 2), rng.uniform(0.0, 0.05)),
        (STIFFNESS_UNITS, rng.uniform(0.0, 1.5)),
    ]
    run = kill_and_resume(tmp_path, scenario, tmp_path / "cache", cli, kills)
    assert_same_run(run, stiffness_reference, list(by_unit(stiffness_reference)))
    assert len(by_unit(run)) == STIFFNESS_UNITS
    summary, reference = (json.loads((r / "summary.json").read_text()) for r in (run, stiffness_reference))
    assert summary == reference
    for case in (stiffness_reference / "cases").iterdir():
        assert (run / "cases" / case.name).read_bytes() == case.read_bytes()


def test_resume_removes_temporary_files_of_killed_writes(tmp_path, stiffness_reference, cli):
    """A kill between a temporary file's write and its rename leaves the temporary file: the
    next resume (holding the lock, so no writer is alive) clears them."""
    run = tmp_path / "run"
    import shutil

    shutil.copytree(stiffness_reference, run)
    (run / LOCK_FILE).unlink(missing_ok=True)
    left = [run / ".summary.json.abc123.tmp", run / "figures" / ".rfa.png.x1.tmp", run / "cases" / ".a.csv.q.tmp"]
    for path in left:
        path.write_text("half")
    code, _, err = cli("run", "--resume", run)
    assert code == 0, err
    assert not any(p.exists() for p in left)
    assert (run / "summary.json").read_text() == (stiffness_reference / "summary.json").read_text()


# ----------------------------------------------------------------------------- the dataset cache


def small_dataset(spec: DatasetSpec) -> Dataset:
    n = 6
    X = np.arange(n * 8, dtype=np.float32).reshape(n, 8)
    return bare_dataset(X, np.zeros(n, dtype=np.int8), spec, domains=(spec.name,))


SPEC = DatasetSpec(name="tiny", model="six_dof", preset="meng2020", channel="pinion_y", healthy=6)


def test_cache_entry_appears_only_whole(tmp_path, monkeypatch):
    """The entry is written under a temporary name and renamed: while the bytes go out, the
    entry does not exist, so no reader (and no process killed mid-write) ever sees part of it."""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path))
    entry = cache.entry_path(SPEC)
    seen = []
    real_fsync = os.fsync

    def fsync(fd):
        real_fsync(fd)
        if not seen:  # the data file's fsync, before the rename
            seen.append((entry.exists(), [p.name for p in tmp_path.iterdir()]))

    monkeypatch.setattr(os, "fsync", fsync)
    cache.save(small_dataset(SPEC))
    exists, names = seen[0]
    assert not exists and len(names) == 1 and names[0].startswith(f".{entry.name}.") and names[0].endswith(".tmp")
    assert [p.name for p in tmp_path.iterdir()] == [entry.name]
    assert np.array_equal(cache.load(SPEC).X, small_dataset(SPEC).X)


@pytest.mark.parametrize("cut", [0, 10, 100, 0.5, -1])
def test_damaged_cache_entry_is_rebuilt_not_read(tmp_path, monkeypatch, cut):
    """An entry cut short (a disk full, a copy interrupted) reads as missing and is removed."""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path))
    path = cache.save(small_dataset(SPEC))
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * cut) if isinstance(cut, float) else cut])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert cache.load(SPEC) is None
    assert "unreadable" in str(caught[0].message) and not path.exists()


def test_stale_temporary_files_of_killed_cache_writes_are_removed(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path))
    entry = cache.entry_path(SPEC)
    stale, fresh = tmp_path / f".{entry.name}.old.tmp", tmp_path / f".{entry.name}.new.tmp"
    for path in (stale, fresh):
        path.write_bytes(b"partial")
    hours_ago = time.time() - 3 * 3600
    os.utime(stale, (hours_ago, hours_ago))
    cache.save(small_dataset(SPEC))
    assert not stale.exists()
    assert fresh.exists()  # may be another process writing the same entry right now
    assert io.BytesIO(entry.read_bytes()).read(2) == b"PK"
