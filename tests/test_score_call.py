"""`gearlab score`'s `call` of a take says what was decided: a healthy take no method calls, nothing localised,
read 'watched-gear fault (not localised)', a flag's name beside every 'healthy' decision; it reads
detection_which_gear.NOT_CALLED, in the JSON rows, the stored history and the printout alike."""

from __future__ import annotations

import json

from detection_scenario import scenario, shared_run

from gearlab.kinds.detection_which_gear import NOT_CALLED, NOT_LOCALISED
from gearlab.parts import scoring
from gearlab.runs import RunDir


def test_a_take_no_method_calls_is_called_nothing(tmp_path, cli, module_cache):
    files = [("h1", "history", "healthy", 0.0), ("h2", "history", "healthy", 0.0), ("f1", "test", "fault", 4.0)]
    run = shared_run(scenario(tmp_path, files=files, methods=("source_only",)), tmp_path / "runs")
    code, out, err = cli("score", run, tmp_path / "data" / "h1.zip", tmp_path / "data" / "f1.zip", "--json")
    assert code == 0, err
    rows = json.loads(out)
    calls = {(r["file"].rsplit("/", 1)[-1], r["decision"]): r["call"] for r in rows}
    assert {c for (f, _), c in calls.items() if f == "h1.zip"} == {NOT_CALLED}, calls
    assert calls[("f1.zip", "fault")] == "watched-gear fault: input pinion 25T (stage 1)", calls  # called: as before
    # the stored history the trend reads holds it too, and the printout says no gear for it
    history = [r for r in scoring.read_history(RunDir.open(run)) if r["file"].endswith("h1.zip")]
    assert history and {r["call"] for r in history} == {NOT_CALLED} and NOT_LOCALISED != NOT_CALLED
    code, out, err = cli("score", run, tmp_path / "data" / "h1.zip")
    assert code == 0 and "which gear: nothing" in out and "not localised" not in out, out
