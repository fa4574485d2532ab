"""A detection run's main-process work that no training waits for (the classical indicators, the
sources' bounds, the localisation) is made aside while the trainings run, and its records read in
the local pool (issue 42: phm09_chip's main process held 27 s of CPU before its first training,
with a core idle); results.jsonl keeps the order of a run that made them first."""

import json
import threading

import numpy as np
import pytest
from detection_scenario import run, scenario, without_figures

from gearlab.executors import Aside, LocalExecutor


@pytest.fixture
def cache(module_cache):
    """One dataset cache for the module (as tests/test_detection.py's)."""
    return module_cache


def test_aside_runs_its_steps_in_order_in_a_thread_with_one_blas_thread(blas_threads_as_started):
    from threadpoolctl import threadpool_info

    np.ones(3) @ np.ones(3)  # numpy's BLAS loaded
    seen = []

    def blas():
        return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]

    def step(name):
        def work():
            seen.append((name, threading.current_thread().name, blas()))
            return name.upper()

        return work

    before = blas()
    aside = Aside({"a": step("a"), "b": step("b")})
    assert (aside.get("b"), aside.get("a")) == ("B", "A")
    assert aside.ready("a") and aside.ready("b")
    assert [s[0] for s in seen] == ["a", "b"]
    assert {s[1] for s in seen} == {"gearlab-aside"}
    assert all(n == 1 for s in seen for n in s[2])
    aside.close()
    assert blas() == before


def test_an_aside_steps_error_is_raised_where_its_value_is_asked_for():
    def broken():
        raise ValueError("no such indicator")

    aside = Aside({"first": lambda: 1, "broken": broken, "after": lambda: 3})
    assert aside.get("first") == 1
    with pytest.raises(ValueError, match="no such indicator"):
        aside.get("broken")
    with pytest.raises(ValueError):  # a later step is not made
        aside.get("after")
    aside.close()


def test_the_classical_indicators_are_made_while_the_trainings_run_and_come_first(cli, tmp_path, cache, monkeypatch):
    """The tiny scenario trains in this process (one worker); the classical indicators, made in the
    aside thread meanwhile, wait for a training to end, and results.jsonl still lists them first
    (table.md's rows follow it). The bounds and localisation.json too."""
    import gearlab.kinds.detection as D

    without_figures(monkeypatch)
    events, one_trained = [], threading.Event()
    classical_record, train_unit = D.classical_record, D.train_unit

    def slow_classical(*args, **kwargs):
        events.append(("classical", threading.current_thread().name, one_trained.wait(timeout=60)))
        return classical_record(*args, **kwargs)

    def training(task):
        record = train_unit(task)
        events.append(("trained", threading.current_thread().name, True))
        one_trained.set()
        return record

    monkeypatch.setattr(D, "classical_record", slow_classical)
    monkeypatch.setattr(D, "train_unit", training)
    path = scenario(tmp_path, methods=("source_only", "matched_filter"))
    out = run(cli, path, tmp_path / "runs")
    made = [e for e in events if e[0] == "classical"]
    trained = [e for e in events if e[0] == "trained"]
    assert made and trained
    assert {e[1] for e in made} == {"gearlab-aside"}
    assert all(e[2] for e in made)  # side by side: a training ended while they were made
    units = [json.loads(line)["unit"] for line in (out / "results.jsonl").read_text().splitlines()]
    first = units[: len(made)]
    assert all(u.split("/")[1] in ("fm4", "na4", "tooth_energy") for u in first), units
    assert len(set(units)) == len(units)
    conditions = json.loads((out / "conditions.json").read_text())
    assert all("source_bound" in c for c in conditions.values())


def test_a_presets_structure_check_is_made_aside_and_its_warning_still_told(cli, tmp_path, cache, monkeypatch):
    """A built-in preset's rig checked against the history (check_structure: 4.4 s of phm09_chip's main
    thread while both workers stood idle) is checked in the aside thread while the trainings run; what
    it finds is still told (a user's own description is still checked before any work: it refuses)."""
    import gearlab.kinds.detection as D

    without_figures(monkeypatch)
    checked = []

    def check(*args):
        checked.append(threading.current_thread().name)
        return "the history of condition 'c': the rig's pinion shows 21 teeth, 20 expected"

    monkeypatch.setattr(D, "check_structure", check)
    code, out, err = cli("run", scenario(tmp_path, methods=("matched_filter",)), "--out", tmp_path / "runs")
    assert code == 0, err
    assert checked == ["gearlab-aside"]
    assert "warning: the history of condition 'c': the rig's pinion shows 21 teeth" in out + err


def test_a_local_pool_reads_the_records_and_reads_them_alike(tmp_path):
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import read_target

    path = scenario(tmp_path)
    spec = load_scenario(path).spec
    mapped = []

    class Spy(LocalExecutor):
        def map(self, fn, items, on_done=None, gpu=False):
            mapped.append(getattr(fn, "__name__", fn))
            return super().map(fn, items, on_done, gpu)

    with Spy(2) as pool:
        pooled = read_target(spec.target, spec.detection.blocks, lambda e: None, executor=pool)
    here = read_target(spec.target, spec.detection.blocks, lambda e: None)
    assert mapped == ["read"]
    assert pooled.keys() == here.keys()
    for name, cond in here.items():
        for role in ("history", "test"):
            for (f, revs), (g, pooled_revs) in zip(cond[role], pooled[name][role]):
                assert f.path == g.path
                np.testing.assert_array_equal(revs, pooled_revs)
        assert cond["speeds"] == pooled[name]["speeds"]
