"""`gearlab score` of a take whose level is off its history's by a factor, called with no gear localised: a level
change, its own call, not damage (issue 39).

An outside user swapped a 100 mV/g sensor for one of 50 mV/g on day 4 and kept the scenario: days 4 and 5 were called
'fault' by matched_filter on every record30 unit, the history recording 'watched-gear fault (not localised)' while
the printout's own level line said 0.5 x its history's and no gear was localised. A take off by more than LEVEL_OFF
with nothing localised is now 'level changed by a factor of 0.50 (...): record a new history' in its rows, its call,
the stored history and `--exit-code` (3); a take whose change is localised on a gear stays a fault at any level."""

from __future__ import annotations

import json
import shutil

import pytest
from detection_scenario import call_every_row, scenario, shared_run
from textrecords import signals, text, write_zip

from gearlab.kinds.detection_which_gear import NOT_LOCALISED, decision_of, is_level_change
from gearlab.parts import scoring
from gearlab.runs import RunDir

FILES = [("h1", "history", "healthy", 0.0), ("h2", "history", "healthy", 0.0), ("f1", "test", "fault", 4.0)]


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    folder = tmp_path_factory.mktemp("level")
    run = shared_run(scenario(folder, files=FILES, methods=("source_only",)), folder / "runs")
    takes = tmp_path_factory.mktemp("takes")
    half = {}
    for name, chip, seed in (("healthy", 0.0, 0), ("chipped", 4.0, 2)):  # a sensor of half the sensitivity
        vib, tacho = signals(revolutions=40, chip=chip, seed=seed, phase=0.7 * seed)
        half[name] = write_zip(takes / f"{name}_half.zip", text(0.5 * vib, tacho))
    return run, half


def _scored(cli, made, monkeypatch, name: str, *flags) -> tuple[int, list[dict] | str, RunDir]:
    """A take of *made* scored with every classical row's thresholds under its scores (each row called)."""
    run, half = made
    call_every_row(monkeypatch)
    mine = shutil.copytree(run, run.with_name(f"{run.name}-{name}-{len(flags)}"), dirs_exist_ok=True)
    code, out, err = cli("score", mine, half[name], *flags)
    return code, (json.loads(out) if "--json" in flags else out + err), RunDir.open(mine)


def test_the_rule_a_level_off_with_nothing_localised_is_a_level_change():
    said = decision_of(True, NOT_LOCALISED, 0.5)
    assert said == "level changed by a factor of 0.50 (sensor, gain or load changed?): record a new history", said
    assert is_level_change(said) and not is_level_change("fault")
    assert decision_of(True, NOT_LOCALISED, 1.1) == "fault"  # within LEVEL_OFF: the watched gear's, not localised
    assert decision_of(True, NOT_LOCALISED, None) == "fault"  # no level read
    assert decision_of(False, NOT_LOCALISED, 0.5) == "healthy"
    # a gear localised: a fault whatever its level
    assert decision_of(True, "watched-gear fault: input pinion 25T (stage 1)", 0.5) == "fault"


def test_a_healthy_take_at_half_the_level_is_a_level_change_not_damage(cli, made, monkeypatch):
    code, rows, run = _scored(cli, made, monkeypatch, "healthy", "--json")
    assert code == 0, rows
    assert not rows[0]["localised"], rows[0]
    called = [r for r in rows if r["decision"] != "healthy"]
    assert called and all(is_level_change(r["decision"]) for r in called), {r["decision"] for r in rows}
    assert called[0]["decision"].startswith("level changed by a factor of 0.5"), called[0]["decision"]
    assert not any(r["decision"] == "fault" for r in rows)
    # its call, in the rows and the stored history, is the level change, not 'watched-gear fault (not localised)'
    assert {r["call"] for r in rows} == {called[0]["decision"]}, {r["call"] for r in rows}
    assert {r["call"] for r in scoring.read_history(run)} == {called[0]["decision"]}
    code, out, _ = _scored(cli, made, monkeypatch, "healthy", "--exit-code")
    assert code == 3 and "level changed by a factor of 0.5" in out, (code, out)


def test_a_chipped_take_at_half_the_level_stays_a_fault(cli, made, monkeypatch):
    code, rows, _ = _scored(cli, made, monkeypatch, "chipped", "--json")
    assert code == 0, rows
    assert rows[0]["localised"], rows[0]  # the chip named on a gear
    assert "level 0.5" in rows[0]["level"], rows[0]["level"]  # its level said all the same
    assert any(r["decision"] == "fault" for r in rows) and not any(is_level_change(r["decision"]) for r in rows)
    assert rows[0]["call"].startswith("watched-gear fault: "), rows[0]["call"]
    code, _, _ = _scored(cli, made, monkeypatch, "chipped", "--exit-code")
    assert code == 1
