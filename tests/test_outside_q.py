"""Short takes in `gearlab score` (issue 39 outside check Q): a take too short for a piece of the which-gear evidence
says so in one phrase and localises nothing it cannot support (never nan, no numpy warning); the trend of a scoring
history whose takes are too short for the longest unit kind shows the kind that was scored, and says why. The takes
are made here by plain numpy (tests/textrecords' mesh tone and noise; a 25/52 + 16/81 box's two meshes)."""

from __future__ import annotations

import json
import shutil
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import record

from gearlab.data import which_gear as W
from gearlab.errors import GearlabInputError
from gearlab.gearbox.orders import order_table
from gearlab.kinds import detection_scoring as S
from gearlab.kinds import detection_which_gear as D
from gearlab.runs import RunDir
from gearlab.signals import nonsync as NS

POINTS = 256  # samples per input revolution of the box-B takes


def box_b():
    """The order table of a 25/52 + 16/81 reducer (helper H's box B): its output turns 0.095 times an input turn."""
    gear = SimpleNamespace
    stages = [gear(index=1, pinion=gear(z=25), wheel=gear(z=52)), gear(index=2, pinion=gear(z=16), wheel=gear(z=81))]
    return order_table(SimpleNamespace(stages=stages, shafts=("input", "intermediate", "output")))


def takes(table, revolutions: int, count: int, seed: int) -> list[np.ndarray]:
    """*count* healthy takes of *revolutions* input revolutions (R, POINTS): both meshes, each shaft's first order,
    noise; a grand period of 4212 input turns, so every take is read whole."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        theta = 2 * np.pi * (rng.uniform() + np.arange(revolutions * POINTS) / POINTS)
        y = sum(np.sin(float(st.mesh) * theta + k) for k, st in enumerate(table.stages))
        y += sum(0.2 * np.sin(float(o) * theta + k) for k, o in enumerate(table.shaft_orders))
        out.append((y + 0.5 * rng.standard_normal(theta.size)).reshape(revolutions, POINTS))
    return out


@pytest.fixture(scope="module")
def box():
    table = box_b()
    return table, takes(table, 300, 3, seed=1)


def test_a_take_too_short_for_the_residual_says_so_never_nan(box):
    table, history = box
    hist = NS.history(history, table)
    (short,) = takes(table, 29, 1, seed=2)  # a steady 1.2 s take at 25 Hz: 2.75 output turns
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no 'invalid value encountered in divide'
        with pytest.raises(GearlabInputError) as exc:
            NS.nonsync(short, hist, table)
        said = str(exc.value)
        assert said == (
            "too short for the non-synchronous check: 2.75 output-shaft turns (29 input revolutions), it needs 8"
        )
        ns = D.nonsync_of(short, hist, table)
        assert ns == {"note": said, "changed": False} and D.nonsync_words(ns) == said
        assert D.call_of({"named": None, "shafts": []}, ["input pinion 25T (stage 1)"], ns) == D.NOT_LOCALISED
        assert "nan" not in D._nonsync_cell(ns)
        # fewer input revolutions than a block: the same kind of phrase
        assert D.nonsync_of(short[:12], hist, table)["note"].endswith(": 12 input revolutions, it needs 16")
        # long enough (TURNS output turns and more): read, z finite and under the threshold
        (enough,) = takes(table, 96, 1, seed=3)
        found = NS.nonsync(enough, hist, table)
    assert np.isfinite(found.z) and not found.changed, found
    assert NS.too_short(96, table) is None and NS.too_short(84, table) is not None  # 84 input turns: 7.98 output


def test_a_take_too_short_for_the_shafts_averages_names_no_gear(box):
    table, history = box
    hist = W.history_of([W.Take(h, 0, 25.0, 25.0 * POINTS) for h in history], table, max_order=60.0)
    assert hist.layout.mode == "shafts"
    (short,) = takes(table, 29, 1, seed=4)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        found = W.which_gear(W.Take(short, 0, 25.0, 25.0 * POINTS), hist, table, None)
    assert found["named"] is None and found["shafts"] == []
    said = "too short for the which-gear check: 2.75 output-shaft turns (29 input revolutions), it needs 8"
    said += " (a take of 3.4 s or more)"  # 8 output turns at 25 Hz: 84 input revolutions
    assert found["summary"] == f"not localised: {said}"
    ns = D.nonsync_of(short, NS.history(history, table), table)
    # the evidence line says why, once each, and starts with no stray separator ('nothing (; non-synchronous ...')
    assert D.evidence(found, ns) == f"not localised: {said}; {ns['note']}"


@pytest.fixture(scope="module")
def finished(tmp_path_factory, module_cache):
    """A small finished detection run (tests/detection_scenario: units revolution, record5 and record10, the
    matched filter beside the classical rows) and its folder for new takes."""
    folder = tmp_path_factory.mktemp("q")
    path = scenario(folder, methods=("matched_filter",))
    out = shared_run(path, folder / "runs")
    shutil.copytree(out, folder / "unscored")  # before any test scores with it: a history of one test's takes
    return out, folder


def test_a_short_steady_take_is_scored_with_its_which_gear_line_saying_why(cli, finished, quiet):
    out, folder = finished
    take = record(folder / "short.zip", revolutions=13, chip=0.0, seed=31, phase=0.4)  # 12 whole revolutions
    code, stdout, err = cli("score", out, take)
    assert code == 0, err
    assert "invalid value" not in err and "nan" not in stdout, (stdout, err)
    line = next(x for x in stdout.splitlines() if x.startswith("which gear:"))
    assert "(;" not in line and "too short for the non-synchronous check: 12 input revolutions, it needs 16" in line


def test_the_trend_of_takes_too_short_for_the_longest_unit_shows_what_was_scored(cli, finished, quiet, tmp_path):
    _, folder = finished
    run = tmp_path / "run"
    shutil.copytree(folder / "unscored", run)  # a history of its own: short takes only
    files = [record(folder / f"s{i}.zip", revolutions=9, chip=0.0, seed=40 + i, phase=0.3 * i) for i in range(3)]
    code, stdout, err = cli("score", run, *files, "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    assert {r["decision"] for r in rows if r["unit"] == "record10"} == {"not scored"}, rows
    charts = S.score_trends(RunDir.open(run))
    assert len(charts) == 1 and charts[0].curves, charts  # was none: record10's points were all missing
    title = charts[0].title
    assert ", record5 (" in title and "record10: not scored" in title, title
    assert all(len(c.x) == 3 for c in charts[0].curves)
