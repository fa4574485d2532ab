"""A detection run's tables call a test take at another gain with nothing localised a level change, as `gearlab score`
does (issue 39): the healthy take of the tiny scenario recorded at twice the gain was counted a false alarm of the
watched gear by NA4 (a size: every unit over its threshold), in the verdict's rates and its take line ('the watched
gear's fault by the run's rule'), while the run's own warning said 'level 2 x its history's'. The take's call is now
'level changed by a factor of 2.0 ...: record a new history' (level_call, the rule score decides by),
set aside from the rates the verdict quotes and counted there; the raw rates stay in the table. A chipped take at the
same gain is localised on the pinion and stays the watched gear's fault."""

from __future__ import annotations

import json

import pytest
from detection_scenario import gain_run

from gearlab.kinds.detection_summary import verdict
from gearlab.kinds.detection_verdict import watched_calls
from gearlab.kinds.detection_which_gear import NOT_LOCALISED, WATCHED, decision_of, is_level_change, level_call


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    folder = tmp_path_factory.mktemp("gain")
    run = gain_run(folder)
    return run, json.loads((run / "summary.json").read_text())


def test_the_rule_is_one_for_score_and_the_run():
    said = level_call(NOT_LOCALISED, 2.0)
    assert said == "level changed by a factor of 2.00 (sensor, gain or load changed?): record a new history", said
    assert level_call(NOT_LOCALISED, 1.1) == NOT_LOCALISED  # within LEVEL_OFF
    assert level_call(NOT_LOCALISED, None) == NOT_LOCALISED  # no level read
    localised = f"{WATCHED}: input pinion 25T (stage 1)"
    assert level_call(localised, 2.0) == localised  # a gear localised: its damage at any level
    assert level_call("other damage: output gear 71T (stage 1)", 0.5).startswith("other damage")
    assert decision_of(True, NOT_LOCALISED, 2.0) == said  # score's decision by the same rule


def test_a_healthy_take_at_twice_the_gain_is_a_level_change_in_the_run_s_tables(made):
    run, summary = made
    takes = summary["which_gear"]["records"]
    h3 = takes["../data/h3.zip"]["call"]
    assert is_level_change(h3) and h3.startswith("level changed by a factor of 2.0"), h3
    assert takes["../data/f2.zip"]["call"].startswith(f"{WATCHED}: input pinion"), takes["../data/f2.zip"]
    table = (run / "table.md").read_text()
    row = next(line for line in table.splitlines() if line.startswith("| 16 Hz | ../data/h3.zip | healthy | nothing"))
    assert row.endswith(f"| {h3} |"), row  # the which-gear table's 'a flag would be called'
    # both rates, where the labels are known: the raw 'det % / FA %' and 'called %' tables, and the which-gear one with
    # the level change set aside, counted
    assert "watched / other / level change %" in table and "| 16 Hz | na4 | 100 / 0 / 0 | 0 / 0 / 50 |" in table, table
    assert "| 16 Hz | na4 | 100 | 50 |" in table, table
    assert "Set aside as a level change: 1 take: ../data/h3.zip (2.00 x)" in table, table


def test_its_flags_are_set_aside_from_the_verdict_s_rates_the_raw_ones_kept(made):
    _, summary = made
    rows = {r["method"]: r for r in summary["rows"] if r["unit"] == "record10"}
    raw = rows["na4"]
    assert raw["false_alarm"] == 50.0 and raw["called_by_label"]["healthy"] == 50.0, raw  # h3's 3 units of 6
    (calls,) = [c for c in summary["which_gear"]["calls"] if c["method"] == "na4"]
    assert calls["level"] == {"fault": 0.0, "healthy": 50.0}, calls
    assert calls["watched"]["healthy"] == 0.0 and calls["judged"]["healthy"] == 3, calls
    assert calls["level_changes"] == {"../data/h3.zip": summary["which_gear"]["records"]["../data/h3.zip"]["call"]}
    assert watched_calls(raw, summary)["false_alarm"] == 0.0
    assert watched_calls(rows["fm4"], summary)["detection"] == 100.0  # the chipped take at twice the gain: detected


def test_the_verdict_calls_it_a_level_change_and_counts_what_it_set_aside(made):
    run, summary = made
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines() if line.strip()]
    lines = verdict(summary, records)
    take = next(line for line in lines if line.startswith("take h3.zip: "))
    assert "level changed by a factor of 2.0" in take and "called by 1 of 3 methods" in take, take
    assert "the watched gear's fault by the run's rule" not in take, take
    f2 = next(line for line in lines if line.startswith("take f2.zip: "))
    assert "damage on the input pinion" in f2 and "level changed" not in f2, f2
    said = "\n".join(lines)
    assert "set aside as a level change: 1 take (h3.zip, 2.00 x: " in said, said
    # the two rates of na4 said side by side: the table's raw, the verdict's with the level change set aside
    assert "16 Hz na4 50 % in the table, 0 % here" in said, said
