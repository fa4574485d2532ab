"""Executors: the map contract (input order, a callback per finished item, errors as raised)
for the local pool and Ray, address resolution, and the same transfer records whichever
executor runs the units.

The Ray tests start one local Ray instance (2 CPUs) for the whole module and skip, saying
why, when Ray is not installed.
"""

import functools
import inspect
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pool_units
import pytest
from pool_units import (
    divide,
    first_is_slow,
    mark_then_wait,
    module_loaded,
    read_shared,
    refuse_three,
    square,
    sum_then_spoil,
    waited_for,
    worker_pid,
)
from tiny import BASELINES_AND_MMD, records, transfer

from gearlab import executors
from gearlab.errors import GearlabInputError
from gearlab.executors import LocalExecutor, RayExecutor, Shared, make_executor, ray_address, unshared

# The functions mapped on local pools are pool_units': a worker imports the module of the function it
# is sent, and this one imports pytest and tests/tiny.py (a second of CPU at each worker's start).

pytestmark = pytest.mark.usefixtures("one_torch_thread")

NO_RAY = "Ray is not installed (pip install 'gearlab[ray]')"


def gpu_ids(x: int) -> list:
    import ray

    return ray.get_gpu_ids()


@pytest.fixture(scope="module")
def ray_session():
    """One local Ray instance for the module; closed at its end so other modules do not pay for it."""
    ray = pytest.importorskip("ray", reason=NO_RAY)
    # Ray workers cannot import these test modules by name (not a package): send their functions by value.
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    ray.cloudpickle.register_pickle_by_value(pool_units)
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("RAY_ADDRESS", raising=False)
        # The instance declares one GPU (Ray does not check that it exists), so that the GPU
        # requests of training tasks are exercised on machines without one. Its workers stay while
        # idle: Ray ends a worker idle for 1 s, and between this module's Ray tests (local ones run
        # in between) it ended and started 11 workers, 0.6 s of CPU each that no test's time shows.
        real_init = ray.init
        idle = {"idle_worker_killing_time_threshold_ms": 600_000}
        mp.setattr(ray, "init", lambda **options: real_init(num_gpus=1, _system_config=idle, **options))
        # Nor does it start the head's autoscaler monitor (a fixed local instance never scales), its log
        # monitor (the session sends no worker's output to the driver: log_to_driver=False) or its API server
        # (job submission and the state API, which gearlab does not use; Ray goes on without it, as when it
        # fails to start): three Python processes that ray.init has no option to leave out. The start took
        # 6.2 s of CPU, not 10.1, and 9.7 s on 2 busy cores, not 23 (medians of 2).
        # These are Ray's internals (ray>=2.9 is not pinned): where a release moves them, the session
        # starts in full, as a user's does, rather than failing the module.
        params = getattr(getattr(ray._private, "parameter", None), "RayParams", None)
        services = getattr(ray._private, "services", None)
        if params is not None and {"no_monitor", "include_log_monitor"} <= set(inspect.signature(params).parameters):
            real_params = params.__init__

            def head_alone(self, *args, **options):
                real_params(self, *args, **{**options, "no_monitor": True, "include_log_monitor": False})

            mp.setattr(params, "__init__", head_alone)
        if hasattr(services, "start_api_server"):
            mp.setattr(services, "start_api_server", lambda *args, **options: (None, None))
        executors._open_session(None, 2)
    yield ray
    executors._close_session()


@pytest.fixture(scope="module")
def two_local_workers():
    """One pool of two workers for the map contract's tests, as a run's maps share theirs (a failed
    map replaces it: test_the_local_pool_is_kept_across_maps_and_closed_at_the_end): a pool per test
    started two processes each time, 0.7-1.6 s of the test's time on a busy machine."""
    with LocalExecutor(2) as pool:
        yield pool


@pytest.fixture(params=["local-1", "local-2", "ray"])
def executor(request):
    if request.param == "ray":
        request.getfixturevalue("ray_session")
        return RayExecutor(workers=2)
    if request.param == "local-2":
        return request.getfixturevalue("two_local_workers")
    return LocalExecutor(1)


# ----------------------------------------------------------------------------- the map contract


def test_results_keep_the_input_order_and_every_item_is_reported_once(executor, tmp_path):
    seen = []
    marks = tmp_path if executor.workers != 1 else None

    def heard(i: int, result: int) -> None:
        seen.append((i, result))
        (tmp_path / f"heard-{i}").touch()

    results = executor.map(functools.partial(first_is_slow, marks), range(5), heard)
    assert results == [0, 1, 4, 9, 16]
    assert sorted(seen) == [(i, i * i) for i in range(5)]
    if executor.workers != 1:
        assert seen[0][0] != 0, "on_done should hear of each item as it finishes, not in input order"


def test_no_items_no_work(executor):
    assert executor.map(square, [], lambda i, r: pytest.fail("nothing to report")) == []


def test_gpu_request_changes_no_result(executor):
    """Local executors ignore it; a Ray cluster without GPUs asks for none."""
    assert executor.map(square, range(4), gpu=True) == [0, 1, 4, 9]


def a_shared_value():
    import numpy as np

    X = np.linspace(0.0, 1.0, 1_000_000)  # 8 MB
    return Shared((X, {"r": np.arange(1000)})), float(X.sum()) + float(np.arange(1000).sum())


def test_a_shared_value_reaches_every_unit_as_itself(executor):
    shared, total = a_shared_value()
    assert executor.map(read_shared, [(i, shared) for i in range(3)]) == [(i, total) for i in range(3)]


# The maps that fail come last: a failed map stops the pool the local-2 tests share (two_local_workers),
# and the next map starts its two workers again (0.8 s of CPU, 2.1-2.6 s of wall time at a load of 6).


def test_a_gearlab_input_error_arrives_as_itself(executor):
    with pytest.raises(GearlabInputError, match="item 3 is not allowed") as info:
        executor.map(refuse_three, range(5))
    assert type(info.value) is GearlabInputError  # not a Ray wrapper class


def test_other_errors_keep_their_type(executor):
    with pytest.raises(ZeroDivisionError):
        executor.map(divide, [1, 0, 2])


def test_a_failing_callback_stops_the_map(executor):
    def stop(i, r):
        raise RuntimeError("cancelled")

    with pytest.raises(RuntimeError, match="cancelled"):
        executor.map(square, range(4), stop)


def test_the_local_pool_sends_a_shared_value_once_and_each_unit_has_its_own(monkeypatch, tmp_path):
    """Issue 42 (phm09_chip): a value every unit took (a condition's training arrays) travelled in each
    unit's pickle, 3.45 GB through the pool's pipes for 112 units. Shared, it is written once to a file
    of the pool's, which its workers map: the queue carries a few hundred bytes a unit. A unit may still
    change its arrays (copy-on-write): the next unit on its worker reads the values, as with a copy.
    The file goes with the pool."""
    import multiprocessing.queues as queues

    sent = []
    real = queues._ForkingPickler.dumps

    def dumps(obj, protocol=None):
        data = real(obj, protocol)
        sent.append(len(data))
        return data

    monkeypatch.setattr(queues._ForkingPickler, "dumps", dumps)
    monkeypatch.setattr(executors.tempfile, "tempdir", str(tmp_path))
    shared, total = a_shared_value()
    with LocalExecutor(2) as pool:
        results = pool.map(sum_then_spoil, [(i, shared) for i in range(6)])
        assert [p.name for p in tmp_path.iterdir()] == [pool._folder.rsplit("/", 1)[1]]
    assert results == [(i, total) for i in range(6)]  # (6 units on 2 workers: 4 followed a spoiling one)
    assert 0 < sum(sent) < 100_000  # 6 x 8 MB before
    assert not list(tmp_path.iterdir())
    assert unshared(shared)[0][0] == 0.0  # the caller's own value untouched


def test_a_warmed_local_pool_has_loaded_the_modules_before_its_units_ask(tmp_path):
    """Issue 42: each worker's first training imported torch and scipy.stats (2.7 s of CPU) while
    the run's process had left both idle preparing the trainings; warm() has them loaded meanwhile.
    Both warm-ups are queued before the items, so a worker that took one has it loaded before its
    first item, and each worker takes an item (module_loaded)."""
    cold, warmed = tmp_path / "cold", tmp_path / "warmed"
    with LocalExecutor(2) as pool:
        cold.mkdir()
        assert not any(pool.map(functools.partial(module_loaded, cold), ["tabnanny"] * 4))
    with LocalExecutor(2) as pool:
        pool.warm(("tabnanny",))
        warmed.mkdir()
        assert any(pool.map(functools.partial(module_loaded, warmed), ["tabnanny"] * 4))
    with LocalExecutor(1) as one:
        one.warm(("tabnanny",))
        assert one._pool is None  # one worker: the units run in this process


LOADED_IN = """
import functools, json, math, tempfile
from pathlib import Path
from gearlab.executors import LocalExecutor
from pool_units import loaded_in
if {before}:  # a run before, which warmed nothing, started the process's forkserver
    with LocalExecutor(2) as pool:
        pool.map(math.sqrt, [1.0, 4.0])
with LocalExecutor(2) as pool, tempfile.TemporaryDirectory() as marks:
    pool.warm(("pool_units",))
    print(json.dumps(pool.map(functools.partial(loaded_in, Path(marks)), range(2))))
"""


@pytest.mark.parametrize("before", [False, True])
def test_a_warm_before_the_first_pool_has_the_forkserver_load_the_modules_once(before):
    """Issue 42: each worker imported torch (2-3 s of CPU) itself; a warm before the process's first pool
    has its forkserver import the modules, and each worker is forked with them loaded. The forkserver
    is started once a process: a warm after a run that warmed nothing has its workers load them (in a
    process of its own: the test session's forkserver is long started)."""
    # the path through the environment: Python 3.11's forkserver takes no sys.path of its parent's
    path = os.pathsep.join([str(Path(__file__).parent), *filter(None, [os.environ.get("PYTHONPATH")])])
    script = LOADED_IN.format(before=before)
    env = {**os.environ, "PYTHONPATH": path}
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    (loaded_0, worker_0, server_0), (loaded_1, worker_1, server_1) = json.loads(out.stdout)
    assert worker_0 != worker_1 and server_0 == server_1  # two workers of one forkserver
    if before:
        assert (loaded_0, loaded_1) == (worker_0, worker_1)
    else:
        assert loaded_0 == loaded_1 == server_0


def test_ray_tasks_that_want_a_gpu_get_a_share_of_one(ray_session):
    """One GPU and two CPUs: each training task takes half the GPU, so two still run at once."""
    executor = RayExecutor(workers=2)
    assert executor.map(gpu_ids, range(2)) == [[], []]
    assert executor.map(gpu_ids, range(2), gpu=True) == [[0], [0]]
    assert executors._gpu_request(True, ray_session.cluster_resources()) == 0.5
    assert executors._gpu_request(0.25, {"GPU": 4.0, "CPU": 8.0}) == 0.25
    assert executors._gpu_request(True, {"GPU": 1.0, "CPU": 3.0}) == 0.3333
    assert executors._gpu_request(True, {"GPU": 8.0, "CPU": 4.0}) == 1.0
    assert executors._gpu_request(True, {"CPU": 4.0}) == 0.0  # no GPUs: CPU tasks


@pytest.mark.parametrize("workers", [0, -1, True, 1.5, "2"])
@pytest.mark.parametrize("name", ["local", "ray"])
def test_bad_worker_counts_are_refused(name, workers):
    with pytest.raises(GearlabInputError, match="workers must be a whole number >= 1"):
        make_executor(name, workers)


def test_no_worker_count_means_one_local_worker_per_core(monkeypatch):
    """[execution] workers = 0, the default, is a worker per core (conftest runs the scenarios of
    the tests' own processes on one: this checks the real default)."""
    monkeypatch.setattr(executors.os, "cpu_count", lambda: 7)
    executor = LocalExecutor.__new__(LocalExecutor)
    LocalExecutor.__init__.every_core(executor, None)
    assert executor.workers == 7
    assert LocalExecutor().workers == 1 and LocalExecutor(3).workers == 3  # conftest's, for the tests


def test_unknown_executor_is_refused():
    with pytest.raises(GearlabInputError, match="unknown executor 'dask'; known: local, ray"):
        make_executor("dask")


@pytest.mark.parametrize("gpu", [-1, 2, 1.5])
def test_bad_gpu_share_is_refused(gpu):
    with pytest.raises(GearlabInputError, match="gpu must be"):
        make_executor("local", 1).map(square, [1], gpu=gpu)


# ----------------------------------------------------------------------------- without Ray


@pytest.fixture
def no_ray(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` now raises ImportError


def test_without_ray_the_ray_executor_says_how_to_get_it(no_ray):
    with pytest.raises(GearlabInputError) as info:
        make_executor("ray")
    assert str(info.value) == "executor 'ray' needs the optional extra: pip install 'gearlab[ray]'"


def test_without_ray_a_ray_scenario_is_refused_with_exit_code_2(no_ray, tmp_path, monkeypatch, cli):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "tiny.toml"
    path.write_text(TINY.replace("[execution]", '[execution]\nexecutor = "ray"'))
    code, _, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 2
    assert "pip install 'gearlab[ray]'" in err and "Traceback" not in err
    assert not list((tmp_path / "runs").glob("*/*"))  # refused before any work: no run left behind


def test_the_local_executor_never_imports_ray(no_ray):
    assert make_executor("local", 1).map(square, [2]) == [4]


# ----------------------------------------------------------------------------- address


def test_address_precedence(monkeypatch):
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    assert ray_address() is None  # start a local instance
    assert ray_address(scenario="scen:6379") == "scen:6379"
    monkeypatch.setenv("RAY_ADDRESS", "env:6379")
    assert ray_address(scenario="scen:6379") == "env:6379"
    assert ray_address("cli:6379", scenario="scen:6379") == "cli:6379"


def test_the_scenario_address_reaches_the_ray_executor(tmp_path, monkeypatch):
    from gearlab.engine import load_scenario
    from gearlab.kinds.common import executor_for

    monkeypatch.setattr(executors, "import_ray", lambda: None)  # no session is opened here
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    path = tmp_path / "tiny.toml"
    path.write_text(TINY.replace("[execution]", '[execution]\nexecutor = "ray"\naddress = "scen:6379"'))
    scenario = load_scenario(path)
    assert executor_for(scenario).address == "scen:6379"
    assert executor_for(scenario, address="cli:6379").address == "cli:6379"
    monkeypatch.setenv("RAY_ADDRESS", "env:6379")
    assert executor_for(scenario).address == "env:6379"
    path.write_text(TINY.replace("[execution]", '[execution]\nexecutor = "ray"'))
    monkeypatch.delenv("RAY_ADDRESS")
    assert executor_for(load_scenario(path)).address is None


def test_a_ray_run_opens_its_session_as_a_stage_of_its_own(tmp_path, monkeypatch):
    """Starting a local Ray instance (15-30 s on 2 busy cores) passed under the kind's first bar, at 0
    and with no word of Ray (issue 41): it is a stage of its own, before the kind's first."""
    from gearlab.engine import run_scenario
    from gearlab.events import Event
    from gearlab.kinds import transfer as kind

    opened, told = [], []
    monkeypatch.setattr(executors, "import_ray", lambda: None)  # no session is opened here
    monkeypatch.setattr(executors, "_open_session", lambda address, workers: opened.append((address, workers)))
    monkeypatch.setattr(RayExecutor, "unit_lines", lambda self, space: None)  # no session: no board
    monkeypatch.delenv("RAY_ADDRESS", raising=False)

    def first_stage(scenario, run, on_event):
        on_event(Event("stage", stage="datasets", total=2, message="datasets"))
        raise GearlabInputError("enough")  # before any unit: no run directory is left

    monkeypatch.setattr(kind, "run", first_stage)
    path = tmp_path / "tiny.toml"
    cases = [("", "starting a local instance"), ('\naddress = "far:6379"', "connecting to the cluster at far:6379")]
    for execution, where in cases:
        path.write_text(TINY.replace("[execution]", f'[execution]\nexecutor = "ray"{execution}'))
        told.clear()
        with pytest.raises(GearlabInputError, match="enough"):
            run_scenario(path, out=tmp_path / "runs", on_event=told.append)
        stages = [(e.kind, e.stage, e.done, e.message) for e in told if e.kind in ("stage", "advance")]
        ray = [("stage", "ray", 0, f"Ray: {where}"), ("advance", "ray", 1, "")]
        assert stages == ray + [("stage", "datasets", 0, "datasets")]
        lines = [e.message for e in told if e.kind == "unit" and e.stage == "ray"]
        assert lines == ["waiting for Ray to answer", ""]  # after 3 s, for how long
    assert opened == [(None, 1), ("far:6379", 1)]


def test_one_ray_session_per_process(ray_session):
    assert executors._open_session(None, 2) is ray_session  # reused, not started again
    with pytest.raises(GearlabInputError, match="already uses the Ray cluster 'local'"):
        executors._open_session("elsewhere:6379", None)


# ----------------------------------------------------------------------------- same records


TINY = transfer(BASELINES_AND_MMD)


def holding_epochs(said, seen: Path | None):
    """UnitProgress.__call__ that holds a unit's first epoch line until the driver has seen it (it
    marks that in the folder *seen*, SeenEpochs): however fast the machine trains, the driver sees
    every training's epoch line. No folder: nothing is held."""

    def say(self, text):
        said(self, text)
        if seen is not None and text.startswith("epoch ") and not getattr(self, "held", False):
            self.held = True
            assert waited_for(seen, self.unit.replace("/", "__")), f"the driver never saw {self.unit}'s epochs"

    return say


class SeenEpochs:
    """The driver's sink that marks in *folder* each unit whose epoch line it was told (holding_epochs)."""

    def __init__(self, told: list, folder: Path):
        self.told, self.folder = told, folder
        folder.mkdir()

    def __call__(self, event) -> None:
        self.told.append(event)
        if event.kind == "unit" and event.message.startswith("epoch "):
            (self.folder / event.stage.replace("/", "__")).touch()


class ProgressElsewhere:
    """A unit as another machine of a cluster runs it, as far as progress goes: what it writes into
    the run directory's progress/ folder lands on its own node's disk (here: is dropped), never
    where the driver's ProgressWatcher reads. (Its other files, the dataset cache and the shared
    states, are kept: this simulates the progress folder alone.) Its first epoch line is held."""

    def __init__(self, fn, seen: Path | None):
        self.fn, self.seen = fn, seen

    def __call__(self, item):
        from gearlab.confined import Confined
        from gearlab.events import PROGRESS, UnitProgress

        real = Confined.write, Confined.unlink, UnitProgress.__call__

        def write(self, data, **options):
            return None if self.parts[:1] == (PROGRESS,) else real[0](self, data, **options)

        def unlink(self, missing_ok=True):
            return None if self.parts[:1] == (PROGRESS,) else real[1](self, missing_ok)

        Confined.write, Confined.unlink, UnitProgress.__call__ = write, unlink, holding_epochs(real[2], self.seen)
        try:
            return self.fn(item)
        finally:
            Confined.write, Confined.unlink, UnitProgress.__call__ = real


class FarProgressRay(RayExecutor):
    """A Ray cluster whose workers share no progress/ folder with this process; *seen*: the driver's
    marks of the epoch lines it saw (holding_epochs)."""

    seen: Path | None = None

    def map(self, fn, items, on_done=None, gpu=False):
        return super().map(ProgressElsewhere(fn, self.seen), items, on_done, gpu)


@pytest.fixture(scope="module")
def tiny_runs(ray_session, tmp_path_factory):
    """The tiny transfer scenario run with one local worker and on Ray tasks that share no progress/
    folder with this process: {executor: (records, events)}. The Ray run builds its datasets itself
    (its own cache), so simulation units run on Ray too. The engine's watcher looks every 0.05 s, and
    a unit's first epoch line is held until the driver saw it (holding_epochs), wherever it ran."""
    from functools import partial

    from gearlab import engine
    from gearlab.events import UnitProgress

    tmp_path = tmp_path_factory.mktemp("tiny_runs")
    runs = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("RAY_ADDRESS", raising=False)
        mp.setattr(executors, "RayExecutor", FarProgressRay)
        mp.setattr(engine, "ProgressWatcher", partial(engine.ProgressWatcher, every=0.05))
        said = UnitProgress.__call__
        for name, cache, execution in [
            ("local-1", "cache", "workers = 1"),
            ("ray", "ray-cache", 'executor = "ray"\nworkers = 2'),
        ]:
            mp.setenv("GEARLAB_CACHE", str(tmp_path / cache))
            path = tmp_path / f"{name}.toml"
            path.write_text(TINY.replace("workers = 1", execution))
            told, seen = [], tmp_path / f"seen-{name}"
            mp.setattr(FarProgressRay, "seen", seen)
            mp.setattr(UnitProgress, "__call__", holding_epochs(said, seen))  # this process's units
            run = engine.run_scenario(path, out=tmp_path / name, on_event=SeenEpochs(told, seen))
            runs[name] = records(run.path), told
    return runs


def test_local_and_ray_give_the_same_records(tiny_runs):
    """One worker and Ray: the same units, the same numbers. (Two local workers against one:
    test_protocol.test_two_workers_give_the_records_of_one, on twice the units; here it paid a
    second pool's imports for the same check.)"""
    assert len(tiny_runs["local-1"][0]) == 6
    assert tiny_runs["ray"][0] == tiny_runs["local-1"][0]


def test_units_on_other_machines_show_their_progress_at_the_driver(tiny_runs):
    """Issue 41: a unit reported its progress through a file in the run directory's progress/ folder,
    which a cluster's other nodes do not share: a cluster run showed no training's line. On Ray the
    lines come back through an actor of the session: the trainings show their epochs as in the
    local run, and each unit's line goes when it ends."""
    trained = {}
    for name, (recorded, told) in tiny_runs.items():
        lines: dict[str, list[str]] = {}
        for event in told:
            if event.kind == "unit" and event.stage in recorded:
                lines.setdefault(event.stage, []).append(event.message)
        assert all(said[-1] == "" and all(said[:-1]) for said in lines.values()), (name, lines)
        trained[name] = {unit for unit, said in lines.items() if any(m.startswith("epoch ") for m in said)}
    assert len(trained["local-1"]) >= 3 and trained["ray"] == trained["local-1"], trained


def trial(task: tuple) -> int:
    """A gap-benchmark trial's stand-in: a stage of 3 steps on the trial's line; after its first step
    it runs on until the driver has seen that step counted (the driver marks it in the task's folder)."""
    from gearlab.events import Event, stages_to_unit

    folder, i = task
    stages_to_unit(Event("stage", stage="fits", total=3, message="gap: round 1, fitting 3 effects"))
    for n in range(1, 4):
        stages_to_unit(Event("advance", stage="fits", done=n, total=3))
        if n == 1:
            assert waited_for(Path(folder), f"seen-{i}"), "the driver never saw the trial's count"
    return i


def test_a_trials_line_on_another_machine_counts_with_its_eta_at_the_driver(ray_session, tmp_path):
    """A benchmark trial on a cluster's node (told_unit, as gearlab.kinds.gap_benchmark's trial_task):
    its line, with its count and ETA, reaches the driver's watcher as a local trial's file does."""
    from gearlab.engine import ProgressWatcher
    from gearlab.events import told_unit
    from gearlab.runs import RunDir

    counted = re.compile(r"gap: round 1, fitting 3 effects: [12] of 3, ETA 0:0\d")
    told = []

    def tell(event) -> None:
        told.append(event)
        if counted.fullmatch(event.message):
            (tmp_path / f"seen-{int(event.stage[-3:])}").touch()

    watcher = ProgressWatcher(RunDir(tmp_path), tell, every=0.05)
    executor = FarProgressRay(workers=2)
    watcher.elsewhere = executor.unit_lines(str(tmp_path))
    watcher.start()
    try:
        told_trial = told_unit(lambda task: (task[0], f"trial_{task[1]:03d}"))(trial)
        assert executor.map(told_trial, [(tmp_path, i) for i in range(2)]) == [0, 1]
    finally:
        watcher.stop()
    lines: dict[str, list[str]] = {}
    for event in told:
        lines.setdefault(event.stage, []).append(event.message)
    assert set(lines) == {"trial_000", "trial_001"}
    assert all(said[-1] == "" and any(map(counted.fullmatch, said)) for said in lines.values()), lines


def test_a_session_opened_again_gets_a_board_of_its_own(monkeypatch):
    """A Ray session someone else opened (a notebook's), closed and opened again: the units' board
    of the old one is gone with it, so the new session's tasks get a new one (not a dead handle)."""
    from types import SimpleNamespace

    jobs, made = iter(["01000000", "01000000", "02000000"]), []

    class Remote:
        def remote(self):
            made.append(object())
            return made[-1]

    fake = SimpleNamespace(
        get_runtime_context=lambda: SimpleNamespace(get_job_id=lambda: next(jobs)),
        remote=lambda **options: lambda cls: Remote(),
    )
    monkeypatch.setitem(executors._session, "board", None)
    first, again, reopened = (executors._board(fake) for _ in range(3))
    assert first is again is made[0] and reopened is made[1]


def test_a_watcher_whose_lines_from_elsewhere_fail_ends_quietly(tmp_path):
    """A Ray session that broke mid-run: the run's own error says so; the watcher's reader of its
    units' lines drops them (their ends sent) and its stop raises nothing in the way."""
    from gearlab.engine import ProgressWatcher
    from gearlab.executors import UnitLines
    from gearlab.runs import RunDir

    class Broken(UnitLines):
        calls = 0

        def __call__(self, final=False):
            Broken.calls += 1
            if Broken.calls > 1:
                raise RuntimeError("the Ray session is gone")
            return {"rep0/k0/mmd-unsup": "epoch 3"}

        def close(self):
            raise RuntimeError("the Ray session is gone")

    told = []
    watcher = ProgressWatcher(RunDir(tmp_path), told.append, every=3600.0)
    watcher.elsewhere = Broken()
    shown = watcher.scan({})
    watcher.scan(shown)
    watcher.start()
    watcher.stop()
    assert [(e.stage, e.message) for e in told] == [("rep0/k0/mmd-unsup", "epoch 3"), ("rep0/k0/mmd-unsup", "")]


def counting(item: tuple[int, Path | None]) -> int:
    """A gap fit's stand-in: n score evaluations; with *seen* (a folder), it then runs until the
    driver's line has counted evaluations (the driver marks that there)."""
    from gearlab.gap import tally
    from gearlab.gap.tally import counted

    n, seen = item
    if seen is None:
        for _ in range(n):
            counted()
        return n
    every, tally.WRITE_EVERY = tally.WRITE_EVERY, 0.0  # each evaluation reported: all come within 0.5 s
    try:
        for _ in range(n):
            counted()
        assert waited_for(seen, "counted"), "the driver's line never counted the evaluations"
    finally:
        tally.WRITE_EVERY = every
    return n


class Elsewhere:
    """A unit as another machine of a cluster runs it: a file it writes into a folder of this
    machine's lands on its own disk (here: is dropped), never where this process reads."""

    def __init__(self, fn):
        self.fn = fn

    def __call__(self, item):
        import os

        real = os.replace
        os.replace = lambda src, dst: os.unlink(src)
        try:
            return self.fn(item)
        finally:
            os.replace = real


class FarRay(RayExecutor):
    """A Ray cluster whose workers share no disk with this process."""

    def map(self, fn, items, on_done=None, gpu=False):
        return super().map(Elsewhere(fn), items, on_done, gpu)


def test_a_gap_fits_evaluations_come_back_from_ray_tasks_on_other_machines(ray_session, tmp_path):
    """Issue 41: a fit's score evaluations reached the run's process through files in a temporary
    folder of its machine's, which a cluster's other nodes do not share: the diagnosis's total missed
    them (a transfer benchmark's correction, a gap run on Ray) and its line said 'fitting' alone. Ray
    tasks now report to the executor's actor and return their counts with their results: the total
    of serial fits, and a line that counts (the second batch's fits run until the driver's line has
    counted: the line is looked at each 0.05 s here, not each second)."""
    from types import SimpleNamespace

    from gearlab import events
    from gearlab.gap import tally
    from gearlab.gap.diagnose import run_fits

    counted = re.compile(r"fitting: (\d+) evaluations, ")

    def fits(executor, seen: Path | None) -> tuple[int, list[str]]:
        told, first = [], tally.so_far()

        def tell(event) -> None:
            told.append(event)
            if seen is not None and counted.match(event.message):
                (seen / "counted").touch()

        run = SimpleNamespace(on_event=tell, executor=executor)
        tasks = [(n, seen) for n in (10, 20, 30, 40, 50, 60)]
        assert run_fits(run, "gap round 1", counting, tasks, None) == [10, 20, 30, 40, 50, 60]
        return tally.so_far() - first, [e.message for e in told]

    serial, _ = fits(LocalExecutor(1), None)
    with pytest.MonkeyPatch.context() as mp, FarRay(workers=2) as executor:
        mp.setattr(events, "_next_look", lambda done: done.wait(0.05))
        batches = [fits(executor, seen) for seen in (None, tmp_path)]
    assert serial == 210 and [total for total, _ in batches] == [210, 210]
    said = batches[1][1]
    counts = [int(m.group(1)) for m in map(counted.match, said) if m]
    assert counts and 0 < counts[-1] <= 210, said


@pytest.mark.slow
def test_a_real_diagnosis_on_ray_counts_what_it_counts_serially(ray_session):
    """A gap diagnosis whose fits run on Ray tasks that share no disk with this process (a transfer
    benchmark's correction, a gap run on a cluster): the same total of score evaluations as serial
    fits, the same effects. (Development check, B-6-ch5 against sensor noise 5 dB, seed 11: 200 and
    200; 5 before the counts came back by Ray, the driver's own evaluations alone.)"""
    from gearlab.data.builder import build_dataset
    from gearlab.data.spec import dataset_preset
    from gearlab.effects import effect_spec
    from gearlab.gap.diagnose import Settings, diagnose
    from gearlab.gap.views import healthy_rows

    source = dataset_preset("B-6-ch5").with_(faults=(), healthy=16)
    noisy = source.with_(effects=(effect_spec("sensor_noise", kind="laplace", snr_db=5),), seed=11)
    target = healthy_rows(build_dataset(noisy))
    settings = Settings(
        candidates=("sensor_noise", "interference_tone", "mesh_damping"),
        max_effects=1,
        healthy=16,
        bootstrap=20,
        permutations=99,
        budget=4,
        seed=0,
    )
    serial = diagnose(source, target, settings)
    with FarRay(workers=2) as executor:
        far = diagnose(source, target, settings, executor=executor)
    assert far["effects"] == serial["effects"] and far["evaluations"] == serial["evaluations"] > 20


def gone(pid: int) -> bool:
    """Whether process *pid* ended within a minute."""
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.01)
    return False


def test_a_failed_unit_stops_the_local_pool_at_once(tmp_path):
    """No queued unit starts after a failure (or a Ctrl-C), and the running ones are stopped: their
    processes end, where unstopped they would run on (a minute) and mark that they ended."""
    with pytest.raises(GearlabInputError, match="unit 0 is bad"):
        LocalExecutor(2).map(mark_then_wait, [(tmp_path, i) for i in range(5)])
    started = list(tmp_path.glob("started-*"))
    assert started and all(gone(int(p.read_text())) for p in started)
    marks = sorted(p.name for p in tmp_path.iterdir())
    assert not any(m.startswith("ended") for m in marks)
    assert len(marks) < 3  # the queued units were dropped (the worker freed by unit 0 may take one)


def test_the_local_pool_is_kept_across_maps_and_closed_at_the_end(tmp_path):
    """A run maps several times (datasets, then training): the workers started for the first map
    serve the next ones (their imports and compiled loops are paid once), and leaving the
    ``with`` block stops them. A failed map replaces the pool for the next one."""

    def pids(name: str) -> set[int]:
        (tmp_path / name).mkdir()
        return set(executor.map(functools.partial(worker_pid, tmp_path / name), range(4)))

    with LocalExecutor(2) as executor:
        first = pids("first")
        processes = list(executor._pool._processes.values())
        second = pids("second")
        workers = {p.pid for p in processes}
        assert first == second == workers and len(workers) == 2
        assert {p.pid for p in executor._pool._processes.values()} == workers
        with pytest.raises(ZeroDivisionError):
            executor.map(divide, [1, 0, 2])
        assert pids("after").isdisjoint(workers)
    assert executor._pool is None
    assert not any(p.is_alive() for p in processes)
