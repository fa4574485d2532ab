"""A take too short for the which-gear check that no method calls is an ordinary unflagged take: its call is
detection_which_gear.NOT_CALLED in `gearlab score` (rows, stored history, printout) and the run's verdict lists it
with the takes where nothing was found; 'fault, gear not determined' is said of a flagged take only."""

from __future__ import annotations

import json

import pytest
from detection_scenario import scenario, shared_run
from textrecords import signals, text, write_zip

from gearlab.kinds.detection_summary import take_lines
from gearlab.kinds.detection_which_gear import NOT_CALLED, UNDETERMINED, flagged_takes
from gearlab.parts import scoring
from gearlab.runs import RunDir

SHORT = f"{UNDETERMINED}: 7.5 turns of the output shaft, 10 needed"


def _summary(path: str) -> dict:
    take = {
        "condition": "16 Hz",
        "named": None,
        "call": SHORT,
        "summary": "not localised: too short for the which-gear check: 7.5 output-shaft turns, it needs 10",
        "nonsync": None,
    }
    return {"which_gear": {"records": {path: take}}}


@pytest.mark.parametrize(("scores", "called"), [([0.5, 0.6, 0.4], False), ([2.0, 3.0, 0.5], True)])
def test_the_verdict_says_gear_not_determined_of_a_called_short_take_only(scores, called):
    # a healthy 2 s take under every threshold opened the verdict with 'take short.csv: fault, gear not determined:
    # ...; called by 0 of 1 methods at record30': an alarm's words on a take no method called
    records = [
        {"condition": "16 Hz", "method": "fm4", "thresholds": {"record30": 1.0},
         "test_scores": {"rec/short.csv": {"record30": scores}}},
    ]  # fmt: skip
    lines = take_lines(_summary("rec/short.csv"), records, "record30")
    text = "\n".join(lines)
    if called:
        assert lines[0].startswith(f"take short.csv: {SHORT}; called by 1 of 1 methods at record30"), lines
    else:
        assert UNDETERMINED not in text and lines == [
            "nothing found (no method calls it, no gear localised, level as its history's): short.csv."
        ], lines


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, module_cache):
    """The tiny detection run (tests/detection_scenario) with the matched filter beside FM4 and NA4, and a healthy take
    of 10 input revolutions (7.5 output turns: the which-gear check needs 10)."""
    folder = tmp_path_factory.mktemp("short")
    run = shared_run(scenario(folder, methods=("matched_filter",)), folder / "runs")
    vib, tacho = signals(revolutions=10, seed=12, phase=0.3)
    return run, write_zip(folder / "short.zip", text(vib, tacho))


def test_gearlab_score_calls_an_unflagged_short_take_nothing(cli, tiny, quiet):
    run, short = tiny
    code, out, err = cli("score", run, short, "--json")
    assert code == 0, err
    rows = json.loads(out)
    # no method calls it (its units too short for the longest TSA: not scored there)
    assert {r["decision"] for r in rows} == {"healthy", "not scored"}, rows
    assert {r["call"] for r in rows} == {NOT_CALLED}, {r["call"] for r in rows}
    history = [r for r in scoring.read_history(RunDir.open(run)) if r["file"] == str(short)]
    assert history and {r["call"] for r in history} == {NOT_CALLED}, history
    code, out, err = cli("score", run, short)
    assert code == 0 and "not determined" not in out, out
    assert "which gear: not read: too short for the which-gear check" in out, out


def test_a_run_s_report_and_table_say_no_alarm_of_an_unflagged_short_take(tmp_path_factory, module_cache):
    # the run's own test take too short for the which-gear check, under every threshold: its verdict line, table and
    # report carry no 'gear not determined' (the table's call column: not flagged)
    from detection_scenario import FILES

    folder = tmp_path_factory.mktemp("run")
    (folder / "data").mkdir()
    vib, tacho = signals(revolutions=10, seed=12, phase=0.3)
    write_zip(folder / "data" / "s1.zip", text(vib, tacho))
    files = [*FILES, ("s1", "test", "healthy", 0.0)]
    run = shared_run(scenario(folder, files=files, methods=("matched_filter",)), folder / "runs")
    loc = json.loads((run / "localisation.json").read_text())
    (short,) = [r for p, r in loc["records"].items() if p.endswith("s1.zip")]
    assert short["call"].startswith(UNDETERMINED), short  # what a flag on it would be called
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines() if line.strip()]
    assert not any(p.endswith("s1.zip") for p in flagged_takes(records)), "a method flags the short take"
    for page in ("table.md", "report.html"):
        said = (run / page).read_text()
        assert UNDETERMINED not in said, [line for line in said.splitlines() if UNDETERMINED in line]
        assert "s1.zip" in said, page
