"""`gearlab run` options that set [execution] keys, and `gearlab gap` on the wrong inputs."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import pytest
from tiny import domains, stiffness

STIFFNESS = stiffness(256, ["crack"], (1, 3))


@pytest.fixture
def scenario(tmp_path) -> Path:
    path = tmp_path / "stiff.toml"
    path.write_text(STIFFNESS)
    return path


def refused(code, err, *parts):
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for part in parts:
        assert part in lines[0], lines[0]


@pytest.mark.parametrize("option, value, key", [("--executor", "slurm", "executor"), ("--device", "gpu", "device")])
def test_bad_execution_options_are_refused_like_bad_scenario_keys(cli, scenario, tmp_path, option, value, key):
    code, _, err = cli("run", scenario, option, value, "--out", tmp_path / "runs")
    refused(code, err, f"[execution] key '{key}'", f"'{value}'")
    assert not (tmp_path / "runs").exists()


def test_options_reach_the_resolved_scenario_and_a_resume_may_change_them(cli, scenario, tmp_path, unrendered_figures):
    code, out, err = cli("run", scenario, "--executor", "local", "--device", "cpu", "--out", tmp_path / "runs")
    assert code == 0, err
    run = Path(out.strip().splitlines()[-1].removeprefix("run directory: "))
    assert 'device = "cpu"' in (run / "scenario.toml").read_text()
    # where units run is not what they compute: resuming with another device is allowed
    code, out, err = cli("run", "--resume", run, "--device", "auto")
    assert code == 0, err
    assert json.loads((run / "summary.json").read_text())["kind"] == "stiffness"


def test_a_resume_reads_the_keys_its_start_set_on_the_command_line(scenario, tmp_path, unrendered_figures):
    """`gearlab transfer-benchmark --seed S` sets [benchmark] over the scenario file: a resume
    without them continues that run (it was refused as "differs from the scenario"); with other
    values it is refused, naming the run."""
    from gearlab.engine import run_scenario
    from gearlab.errors import GearlabInputError

    given = {"scenario": {"description": "set on the command line"}}
    run = run_scenario(scenario, out=tmp_path / "runs", overrides=given).path
    assert run_scenario(resume=run).path == run
    with pytest.raises(GearlabInputError, match=str(run)):
        run_scenario(resume=run, overrides={"scenario": {"description": "another"}})


def test_gap_refuses_a_scenario_of_another_kind(cli, scenario):
    code, _, err = cli("gap", scenario)
    refused(code, err, str(scenario), "[scenario] key 'kind'", '"gap"', "gearlab run")


def test_gap_refuses_the_transfer_benchmark_though_it_diagnoses_too(cli):
    """`gearlab gap` runs the kinds gearlab.kinds.GAP_COMMAND_KINDS names, not every kind with a
    [diagnosis] table (the transfer benchmark diagnoses each target on the way)."""
    shipped = Path(__file__).resolve().parents[1] / "scenarios" / "transfer_benchmark.toml"
    code, _, err = cli("gap", shipped)
    refused(code, err, "[scenario] key 'kind'", '"gap"', '"transfer_benchmark"', "gearlab run")


def test_gap_scenario_refuses_benchmark_options(cli, scenario):
    code, _, err = cli("gap", scenario, "--trials", "3")
    refused(code, err, "--trials and --seed belong to `gearlab gap benchmark`")


def test_gap_benchmark_checks_its_overrides(cli, tmp_path, monkeypatch):
    monkeypatch.chdir(Path(__file__).resolve().parents[1])
    code, _, err = cli("gap", "benchmark", "--trials", "0", "--out", tmp_path / "runs")
    refused(code, err, "gap_benchmark.toml", "[benchmark] key 'trials'")
    assert not (tmp_path / "runs").exists()


def told(events: list, count: int) -> None:
    """Wait until *events* holds *count* events (a minute: a hung watcher's bound, not a speed)."""
    deadline = time.monotonic() + 60.0
    while len(events) < count:
        assert time.monotonic() < deadline, f"the watcher told {events} in a minute, not {count} events"
        time.sleep(0.005)


def test_units_in_progress_become_unit_events(tmp_path):
    """A unit reports through a file in the run directory (so any worker process or cluster node
    can); the engine's watcher turns it into 'unit' events, and an empty one when it ends."""
    from gearlab.engine import ProgressWatcher
    from gearlab.events import UnitProgress
    from gearlab.runs import RunDir

    events = []
    watcher = ProgressWatcher(RunDir(tmp_path), events.append, every=0.05)
    watcher.start()
    with UnitProgress(tmp_path, "rep0/k4/mmd-unsup", every=0.0) as progress:
        progress("epoch 1")
        told(events, 1)
        progress("epoch 2")
        told(events, 2)
    told(events, 3)  # the watcher's own look, before the stop's last one
    watcher.stop()
    seen = [(e.kind, e.stage, e.message) for e in events]
    assert seen == [
        ("unit", "rep0/k4/mmd-unsup", "epoch 1"),
        ("unit", "rep0/k4/mmd-unsup", "epoch 2"),
        ("unit", "rep0/k4/mmd-unsup", ""),
    ]
    assert not (tmp_path / "progress").exists()  # a run keeps no progress/ folder once it ends


def test_a_unit_that_ends_just_before_the_run_stops_is_still_reported_ended(tmp_path):
    """The watcher looks every few tenths of a second; a unit whose file goes between its last
    look and the end of the run gets its 'ended' event from a last look at stop."""
    import threading

    from gearlab.engine import ProgressWatcher
    from gearlab.events import UnitProgress
    from gearlab.runs import RunDir

    class Stopped(threading.Event):
        """The watcher's stop, which notes when the watcher waits for it an hour (no look till then)."""

        def __init__(self):
            super().__init__()
            self.hour = threading.Event()

        def wait(self, timeout=None):
            if timeout == 3600.0:
                self.hour.set()
            return super().wait(timeout)

    events = []
    watcher = ProgressWatcher(RunDir(tmp_path), events.append, every=0.05)
    watcher.stopped = Stopped()
    watcher.start()
    with UnitProgress(tmp_path, "rep0/k0/mmd-unsup", every=0.0) as progress:
        progress("epoch 1")
        told(events, 1)
        watcher.every = 3600.0  # the next look only at stop
        assert watcher.stopped.hour.wait(60.0)  # its look in flight made (whenever its thread woke)
    watcher.stop()
    assert [e.message for e in events] == ["epoch 1", ""]


@pytest.fixture(scope="module")
def domains_cache(tmp_path_factory):
    """One dataset cache for the two runs below: the same tiny domains, simulated once."""
    return tmp_path_factory.mktemp("cache")


def mmd_run(ks: list[int], repetitions: int, epochs: int, workers: int) -> str:
    """A transfer scenario of the tiny domains whose one method (mmd) trains exactly *epochs* epochs."""
    return (
        '[scenario]\nname = "t"\nkind = "transfer"\n\n'
        + domains()
        + f"""
[network]
name = "fast"

[[methods]]
adapter = "mmd"

[protocol]
ks = {ks}
repetitions = {repetitions}
target_train = 8
batch = 4
prime_epochs = 2
patience = {epochs}
min_epochs = {epochs}
max_epochs = {epochs}

[execution]
workers = {workers}
device = "cpu"
"""
    )


def test_transfer_units_report_their_epochs(cli, tmp_path, monkeypatch, domains_cache, unrendered_figures):
    monkeypatch.setenv("GEARLAB_CACHE", str(domains_cache))
    from gearlab.engine import ProgressWatcher
    from gearlab.events import UnitProgress

    # the epoch line must stand until the watcher has looked at it, on any machine: 200 epochs of
    # `fast` took 1.5 s on one machine and under the watcher's half-second period on CI's (no epoch
    # line was seen), and 1.5 s of standing is a guess too: the first epoch's report stands until seen
    said, scan, seen = UnitProgress.__call__, ProgressWatcher.scan, threading.Event()

    def standing_epoch(self, text: str) -> None:
        said(self, text)
        if text.split(",")[0] == "epoch 1":
            assert seen.wait(60.0), "the watcher never saw the epoch line"

    def looking(self, shown, final=False):
        now = scan(self, shown, final)
        if any(text.startswith("epoch ") for text in now.values()):
            seen.set()
        return now

    monkeypatch.setattr(UnitProgress, "__call__", standing_epoch)
    monkeypatch.setattr(ProgressWatcher, "scan", looking)
    path = tmp_path / "t.toml"
    path.write_text(mmd_run(ks=[0], repetitions=1, epochs=5, workers=1))
    code, out, err = cli("run", path, "--events", "--out", tmp_path / "runs")
    assert code == 0, err
    units = [json.loads(line) for line in out.splitlines() if line.startswith("{") and '"unit"' in line]
    reports = [e for e in units if e["kind"] == "unit"]
    assert any(e["message"].startswith("epoch ") for e in reports), reports
    assert reports[-1]["message"] == ""  # it ended


def test_a_terminated_run_leaves_no_worker_behind(tmp_path, domains_cache):
    """kill (SIGTERM) of `gearlab run` stops its worker processes too: none is left computing."""
    import os
    import signal
    import subprocess
    import sys
    import time

    path = tmp_path / "t.toml"
    path.write_text(mmd_run(ks=[0, 2], repetitions=2, epochs=100000, workers=2))
    env = {**os.environ, "GEARLAB_CACHE": str(domains_cache)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "gearlab", "run", str(path), "--events", "--out", str(tmp_path / "runs")],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        env=env,
        start_new_session=True,
        text=True,
    )
    for line in proc.stdout:  # wait until units train in the workers
        if '"kind": "unit"' in line:
            break
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=60) == 128 + signal.SIGTERM
    for _ in range(100):  # the workers go within moments
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGKILL)
    raise AssertionError("worker processes outlived the terminated run")
