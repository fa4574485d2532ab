"""`gearlab score` measures a take's level over its history's as the detection run does (issue 39): one ratio, the
take's standard deviation over the median of its history takes' (detection_level.run_levels), the median kept in
scoring.json ('level_reference'). Score divided by the standardiser's pooled standard deviation instead, so a take near
LEVEL_OFF could be a level change in the run's table and a fault in score, or the reverse. A run saved before the
reference was kept still scores, off its stored history, and says so in each row's level words."""

from __future__ import annotations

import json
import shutil

import pytest
from detection_scenario import gain_run

from gearlab.kinds.detection_level import OLD_LEVEL
from gearlab.kinds.detection_which_gear import is_level_change
from gearlab.parts import scoring


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    folder = tmp_path_factory.mktemp("gain")
    run = gain_run(folder)
    return folder, run


def _scored(cli, run, take, name: str) -> list[dict]:
    mine = shutil.copytree(run, run.with_name(f"{run.name}-{name}"))
    code, out, err = cli("score", mine, take, "--json")
    assert code == 0, err
    return json.loads(out)


@pytest.mark.parametrize("take", ["h3", "h4"])
def test_score_reads_a_take_s_level_as_the_run_s_table_does(cli, made, take):
    folder, run = made
    (cond,) = json.loads((run / "conditions.json").read_text()).values()
    path = f"../data/{take}.zip"
    table = json.loads((run / "summary.json").read_text())["which_gear"]["records"][path]["call"]
    rows = _scored(cli, run, folder / "data" / f"{take}.zip", take)
    assert {r["level_ratio"] for r in rows} == {rows[0]["level_ratio"]}
    assert rows[0]["level_ratio"] == pytest.approx(cond["level_ratio"][path], rel=1e-9, abs=0), take
    assert is_level_change(rows[0]["call"]) == is_level_change(table), (rows[0]["call"], table)
    assert is_level_change(table) == (take == "h3"), table  # twice the gain: a level change; h4 at the history's


def test_a_run_saved_before_the_reference_was_kept_scores_off_its_history_and_says_so(cli, made):
    folder, run = made
    old = shutil.copytree(run, run.with_name(f"{run.name}-old"))
    meta = json.loads((old / scoring.SCORING_FILE).read_text())
    for c in meta["conditions"].values():
        del c["level_reference"]
    (old / scoring.SCORING_FILE).write_text(json.dumps(meta))
    (cond,) = json.loads((run / "conditions.json").read_text()).values()
    rows = _scored(cli, old, folder / "data" / "h3.zip", "h3-old")
    assert all(OLD_LEVEL in r["level"] for r in rows), rows[0]["level"]  # in its rows, the printout and the history
    # the stored history: standardised in float32, its takes' median level the run's within that rounding
    assert rows[0]["level_ratio"] == pytest.approx(cond["level_ratio"]["../data/h3.zip"], rel=1e-5)
    assert is_level_change(rows[0]["call"]), rows[0]["call"]
