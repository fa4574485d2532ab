"""The commands that train no model run on one BLAS thread (gearlab.cli.one_blas_thread: OpenBLAS's second thread
spins on their small products on a busy machine), those that train as the machine gives it; the threads are given
back when the command ends."""

from __future__ import annotations

import os

import pytest
from threadpoolctl import threadpool_info

from gearlab.errors import GearlabInputError


def _blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def _seen(monkeypatch, module, name: str) -> list:
    """Replace *module*.*name* by a step that notes the BLAS threads and the variable where the command runs it."""
    seen = []

    def step(*args, **kwargs):
        seen.append((_blas_threads(), os.environ.get("OPENBLAS_NUM_THREADS")))
        raise GearlabInputError("stopped here")

    monkeypatch.setattr(module, name, step)
    return seen


def test_inspect_runs_on_one_blas_thread(tmp_path, cli, monkeypatch, blas_threads_as_started):
    import gearlab.inspect

    before = _blas_threads()
    if max(before, default=1) < 2:
        pytest.skip("BLAS starts on one thread here: nothing to limit")
    seen = _seen(monkeypatch, gearlab.inspect, "inspect_record")
    (tmp_path / "take.npz").write_bytes(b"")  # read by the step alone, which is replaced
    got, _, err = cli("inspect", tmp_path / "take.npz", "--vibration", "acc")
    assert got == 2 and "stopped here" in err, err
    assert seen == [([1] * len(before), "1")] and _blas_threads() == before


def test_a_run_keeps_the_blas_threads_it_started_with(tmp_path, cli, monkeypatch, blas_threads_as_started):
    import gearlab.cli.running

    before, variable = _blas_threads(), os.environ.get("OPENBLAS_NUM_THREADS")
    seen = _seen(monkeypatch, gearlab.cli.running, "_run")
    got, _, err = cli("run", tmp_path / "s.toml")
    assert got == 2 and "stopped here" in err, err
    assert seen == [(before, variable)]
