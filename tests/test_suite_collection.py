"""The suite's own start (tests/conftest.py): in a fresh clone a second xdist worker rewrites the
test files' asserts into pytest's cache from the last file back, so that each file is rewritten
once, not once per worker; Textual's pilot waits for the app's idle in short slices (issue 42)."""

from __future__ import annotations

import asyncio
import sys
import types
from pathlib import Path
from types import SimpleNamespace

import conftest
import pytest
from _pytest.assertion import rewrite


class Args:
    """The running pytest's config, collecting *args* instead."""

    def __init__(self, config, args):
        self._config, self.args = config, args

    def __getattr__(self, name):
        return getattr(self._config, name)


def beside(file_path) -> Path:
    """pytest's own place for a rewritten test module (no sys.pycache_prefix): its folder's __pycache__."""
    return Path(file_path).parent / "__pycache__"


def cached(folder) -> list[str]:
    return sorted(p.name.split(".")[0] for p in (folder / "__pycache__").glob(f"*{rewrite.PYC_TAIL}"))


@pytest.mark.parametrize("worker, ahead", [("gw1", ["test_c", "test_d"]), ("gw0", [])])
def test_a_second_worker_rewrites_from_the_last_file_back_to_one_already_cached(
    request, tmp_path, monkeypatch, worker, ahead
):
    if request.config.getoption("assertmode") != "rewrite":
        pytest.skip("asserts are not rewritten in this run")
    for name in "abcd":
        (tmp_path / f"test_{name}.py").write_text(f"def test_{name}():\n    assert {name!r} * 2 == {name * 2!r}\n")
    monkeypatch.setattr(sys, "dont_write_bytecode", False)
    monkeypatch.setenv("PYTEST_XDIST_WORKER", worker)
    # a session that writes no bytecode shares its rewritten modules in a folder of its own (conftest.
    # rewritten_in_shared_folder): this test's files are cached beside them, as in a session that writes
    monkeypatch.delenv(conftest.REWRITTEN, raising=False)
    monkeypatch.setattr(rewrite, "get_cache_dir", beside)
    config = Args(request.config, [str(tmp_path)])
    state = config.stash[rewrite.assertstate_key]
    # gw0 got as far as test_b: the worker writes test_d, then test_c, and stops there
    rewrite.try_makedirs(tmp_path / "__pycache__")
    stat, code = rewrite._rewrite_test(tmp_path / "test_b.py", config)
    rewrite._write_pyc(state, code, stat, tmp_path / "__pycache__" / f"test_b{rewrite.PYC_TAIL}")
    conftest.rewrite_ahead(SimpleNamespace(config=config))
    assert cached(tmp_path) == sorted(["test_b", *ahead])
    for name in ahead:  # what pytest reads later: the asserts rewritten (a failure explains itself)
        code = rewrite._read_pyc(tmp_path / f"{name}.py", tmp_path / "__pycache__" / f"{name}{rewrite.PYC_TAIL}")
        (test,) = [c for c in code.co_consts if isinstance(c, types.CodeType)]
        assert any(v.startswith("@py_assert") for v in test.co_varnames)
    monkeypatch.setattr(sys, "dont_write_bytecode", True)  # PYTHONDONTWRITEBYTECODE: nothing written
    (tmp_path / "test_e.py").write_text("def test_e():\n    assert True\n")
    conftest.rewrite_ahead(SimpleNamespace(config=config))
    assert "test_e" not in cached(tmp_path)


def test_without_bytecode_the_workers_rewrite_into_the_sessions_folder(request, tmp_path, monkeypatch):
    """PYTHONDONTWRITEBYTECODE (the fresh clone the README's test command is timed in): the rewritten
    modules go to the session's folder (conftest.REWRITTEN), gw0 writing ahead from the first file too,
    and nothing beside the sources."""
    if request.config.getoption("assertmode") != "rewrite":
        pytest.skip("asserts are not rewritten in this run")
    for name in "abc":
        (tmp_path / f"test_{name}.py").write_text(f"def test_{name}():\n    assert {name!r} == {name!r}\n")
    shared = tmp_path / "session"
    monkeypatch.setattr(sys, "dont_write_bytecode", True)
    monkeypatch.setenv(conftest.REWRITTEN, str(shared))
    monkeypatch.setenv("PYTEST_XDIST_WORKER", "gw0")
    monkeypatch.setattr(rewrite, "get_cache_dir", rewrite.get_cache_dir)  # put back after the test
    conftest.rewritten_in_shared_folder()
    conftest.rewrite_ahead(SimpleNamespace(config=Args(request.config, [str(tmp_path)])))
    folder = rewrite.get_cache_dir(tmp_path / "test_a.py")
    assert folder.is_relative_to(shared)
    assert sorted(p.name.split(".")[0] for p in folder.glob(f"*{rewrite.PYC_TAIL}")) == ["test_a", "test_b", "test_c"]
    assert not (tmp_path / "__pycache__").exists()


def test_the_pilot_waits_for_an_idle_app_in_short_slices(monkeypatch):
    """Each key a TUI test presses waits for idle at least twice (textual._wait.wait_for_idle, a slice
    of sleep each, the core idle meanwhile): in the tests a slice is conftest.PILOT_SLICE, not 20 ms.
    The slices asked for are read, not timed (a busy machine wakes a sleeper late)."""
    from textual import _wait

    slept: list[float] = []

    async def sleep(seconds: float) -> None:
        slept.append(seconds)

    monkeypatch.setattr(_wait, "sleep", sleep)
    asyncio.run(_wait.wait_for_idle(0))
    assert slept and set(slept) == {conftest.PILOT_SLICE} and conftest.PILOT_SLICE < 0.02
    assert _wait.SLEEP_IDLE == conftest.PILOT_SLICE / 20  # idle: under a twentieth of a slice used
