"""A worker's warning reads as the command line's: one line 'warning: MESSAGE', not Python's
'FILE:LINE: UserWarning: MESSAGE' followed by the echoed source line (the simulator's step warning
at a record's rate, printed so in each process-pool worker). Run in a process of its own: a pool's
forkserver started earlier in the test session writes to the stderr it was started with."""

import os
import subprocess
import sys

import pytest

MESSAGE = "fs = 200368 Hz gives fewer than 10 steps per period; results will be inaccurate"
POOL = f"""
import functools, warnings
from gearlab.executors import LocalExecutor
with LocalExecutor(2) as pool:
    pool.map(functools.partial(warnings.warn, {MESSAGE!r}, UserWarning), [1, 2])
"""


def test_a_workers_warning_is_one_line():
    err = subprocess.run([sys.executable, "-c", POOL], capture_output=True, text=True, timeout=120, check=True).stderr
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines and all(line == f"warning: {MESSAGE}" for line in lines), err
    assert "UserWarning" not in err


ONCE = f"""
import functools, warnings
from gearlab.executors import LocalExecutor
with LocalExecutor(2) as pool:
    pool.map(functools.partial(warnings.warn, {MESSAGE!r}, UserWarning), range(6))
    pool.map(functools.partial(warnings.warn, "another message", UserWarning), range(4))
    pool.map(functools.partial(warnings.warn, {MESSAGE!r}, UserWarning), range(4))  # the same run: not again
"""


def test_a_warning_every_worker_raises_is_shown_once_a_run():
    # the simulator's step warning was printed once in each worker (two lines for 2 workers, 16 for 16 cores)
    err = subprocess.run([sys.executable, "-c", ONCE], capture_output=True, text=True, check=True).stderr
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines == [f"warning: {MESSAGE}", "warning: another message"], err


UNITS = """
import warnings

_imported = False


def unit(i):
    global _imported
    if not _imported:  # as a module a unit imports first sets its filters, once a process
        warnings.filterwarnings("ignore", message="quiet")
        _imported = True
    warnings.warn("quiet", UserWarning)
    warnings.warn("loud", UserWarning)
"""


def test_a_filter_set_in_a_unit_stays_for_the_next_units(tmp_path):
    # recorded per unit under catch_warnings, the filter a unit's import set was undone after it, and the
    # warnings it silences showed from the next units on
    (tmp_path / "units_module.py").write_text(UNITS)
    code = "from gearlab.executors import LocalExecutor\nimport units_module\n"
    code += "with LocalExecutor(2) as pool:\n    pool.map(units_module.unit, range(8))\n"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    err = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env).stderr
    assert [line for line in err.splitlines() if line.strip()] == ["warning: loud"], err


class _FakeRay:
    """What RayExecutor.map asks of Ray, each task run here at once (its warnings kept as a worker's)."""

    class exceptions:  # noqa: N801 (as ray.exceptions)
        class RayError(Exception):
            pass

        class RayTaskError(RayError):
            pass

    def remote(self, fn):
        return _FakeTask(fn)

    def options(self, **_):
        return self

    def cluster_resources(self):
        return {"CPU": 2.0}

    def wait(self, pending, num_returns=1):
        return pending[:num_returns], pending[num_returns:]

    def get(self, ref):
        return ref.value

    def cancel(self, ref):
        pass

    def is_initialized(self):
        return True


class _FakeTask:
    def __init__(self, fn):
        self.fn = fn

    def options(self, **_):
        return self

    def remote(self, *args):
        return _FakeRef(self.fn(*args))


class _FakeRef:
    def __init__(self, value):
        self.value = value


def test_the_ray_executor_shows_each_task_warning_once_a_run(monkeypatch, capsys):
    # the session keeps the Ray workers' output from the driver (log_to_driver = False): a task's warning
    # was shown nowhere; shown by each worker, once per worker
    import functools
    import warnings

    from gearlab import executors

    fake = _FakeRay()
    monkeypatch.setattr(executors, "import_ray", lambda: fake)
    monkeypatch.setattr(executors, "_open_session", lambda address, workers: fake)
    monkeypatch.setattr(executors, "_board", lambda ray: None)
    with warnings.catch_warnings():  # the showwarning a task sets (once a worker) is undone after the test
        warnings.simplefilter("always")  # every unit raises it, as each of many workers would
        with executors.RayExecutor(workers=2) as ray_pool:
            assert ray_pool.map(functools.partial(warnings.warn, MESSAGE, UserWarning), range(6)) == [None] * 6
            ray_pool.map(functools.partial(warnings.warn, "another message", UserWarning), range(4))
            ray_pool.map(functools.partial(warnings.warn, MESSAGE, UserWarning), range(4))  # the same run: not again
            assert ray_pool.map(abs, [-2, 3]) == [2, 3]  # results as before
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert lines == [f"warning: {MESSAGE}", "warning: another message"], lines


RAY = f"""
import functools, warnings
from gearlab.executors import RayExecutor
with RayExecutor(workers=2) as pool:
    pool.map(functools.partial(warnings.warn, {MESSAGE!r}, UserWarning), range(6))
    pool.map(functools.partial(warnings.warn, "another message", UserWarning), range(4))
    pool.map(functools.partial(warnings.warn, {MESSAGE!r}, UserWarning), range(4))
"""


@pytest.mark.slow  # 15 s, 10 of them Ray starting (load 3); the fake above checks the same path in 0.1 s
def test_a_local_ray_instance_shows_each_task_warning_once_a_run():
    pytest.importorskip("ray")
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}  # a local instance of its own
    err = subprocess.run([sys.executable, "-c", RAY], capture_output=True, text=True, check=True, env=env).stderr
    lines = [line for line in err.splitlines() if MESSAGE in line or "another message" in line]
    assert lines == [f"warning: {MESSAGE}", "warning: another message"], err
