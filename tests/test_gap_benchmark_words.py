"""Issue 41, the gap benchmark's table.md (report, TUI, terminal): a run with no null trial said
'null trials with no significant gap:  (by format: );' (tests/tui_scenarios/tbench.toml)."""

from gearlab.kinds.gap_benchmark import table_md

SUMMARY = {
    "trials": 1,
    "by_kind": {"single": 1, "withheld": 0},
    "per_effect": {},
    "top1": None,
    "top3": None,
    "median_shrink": None,
    "median_param_error": None,
    "out_of_library_unexplained": None,
    "null_correct": None,
    "null_correct_by_format": {},
    "too_weak": 1,
    "right_answer": 1.0,
}


def test_no_null_trial_is_said_so_not_as_an_empty_share():
    text = table_md(SUMMARY)
    assert "null trials with no significant gap: none run;" in text and "(by format: )" not in text


def test_null_trials_keep_their_share_and_formats():
    text = table_md({**SUMMARY, "null_correct": 0.75, "null_correct_by_format": {"csv": 1.0, "wav": 0.5}})
    assert "null trials with no significant gap: 75 % (by format: csv 100 %, wav 50 %);" in text
