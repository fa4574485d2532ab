"""`gearlab score` says a called take's level where the call, no gear named, may be the level's change (issue 39).

Outside user EY's month of daily takes (a 16/37 + 28/71 box, its sensor's mount loosening -0.1 dB a day) was called
by matched_filter and likelihood_ratio from day 16, at 0.83 x its history's level, no gear named; the level warning
came at 0.8 x (LEVEL_OFF) from day 21: days 16, 19 and 20 were called with nothing said of the level. The wording
now follows the call: a take called with no gear named whose level lies further off its history's than the
history's own takes do is told so, by how much. The tie's tiny run (test_score_tie) scores a take at 0.9 x, within
LEVEL_OFF, its classical rows' thresholds put under or over its scores."""

import json
import shutil

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import record, scaled_record

from gearlab.kinds import detection_scoring


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    folder = tmp_path_factory.mktemp("tie")  # the tie's scenario and records: its run, shared
    out = shared_run(scenario(folder, methods=("source_only",)), folder / "runs")
    takes = tmp_path_factory.mktemp("takes")
    record(takes / "same.zip", revolutions=41, chip=0.0, seed=11, phase=0.3)
    return out, scaled_record(takes / "low.zip", 11, 0.9, revolutions=41), takes / "same.zip"


def _scored(cli, made, monkeypatch, called: bool, take: int = 1) -> list[dict]:
    """The rows of one take (*take* 1: the low one) scored with every classical row's thresholds under (*called*)
    or over all its scores."""
    out, low, same = made
    real = detection_scoring.classical_record

    def placed(*args, **kwargs):
        got = real(*args, **kwargs)
        for units in got["test_scores"].values():
            for u, s in units.items():
                got["thresholds"][u] = float(np.min(s) - 1.0 if called else np.max(s) + 1.0)
        return got

    monkeypatch.setattr(detection_scoring, "classical_record", placed)
    mine = shutil.copytree(out, out.with_name(f"{out.name}-{called}-{take}"), dirs_exist_ok=True)
    code, stdout, err = cli("score", mine, (low, same)[take - 1], "--json")
    assert code == 0, err
    return json.loads(stdout)


def test_a_called_take_off_its_history_s_level_is_told_so_within_level_off(cli, made, monkeypatch):
    rows = _scored(cli, made, monkeypatch, called=True)
    assert any(r["decision"] == "fault" for r in rows) and not rows[0]["localised"], rows[0]
    level = rows[0]["level"]
    assert level.startswith("level 0.9 x its history's, its own takes within ") and "no gear named" in level, level
    assert {r["level"] for r in rows} == {level}  # one line a take, on each of its rows


def test_an_uncalled_take_or_one_at_the_history_s_level_is_told_nothing(cli, made, monkeypatch):
    rows = _scored(cli, made, monkeypatch, called=False)
    if not any(r["decision"] != "healthy" for r in rows):  # source_only, not placed, may call it
        assert rows[0]["level"] == "", rows[0]["level"]
    rows = _scored(cli, made, monkeypatch, called=True, take=2)  # called, its level the history's
    assert any(r["decision"] == "fault" for r in rows)
    assert "level" not in rows[0]["level"], rows[0]["level"]


def test_the_run_says_a_called_take_s_level_as_score_does(made, tmp_path):
    """The detection run's own warnings by score's rule (detection_level.called_levels): its tables said a take's
    level from LEVEL_OFF alone. The tiny run keeps each test take's level over its history's and the history's own
    spread; its healthy test take, had it been at 0.9 x and called by every method, no gear named, is told so in
    summary.json and table.md; at its own level or uncalled, not."""
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_tables import summarise
    from gearlab.runs import RunDir

    out, _, _ = made
    kept = json.loads((out / "conditions.json").read_text())
    (cond,) = kept.values()
    take = next(p for p in cond["test"] if p.endswith("h3.zip"))  # healthy: no gear named
    assert set(cond["level_ratio"]) == set(cond["test"]) and 0 <= cond["level_spread"] < 0.2, cond
    assert 0.8 < cond["level_ratio"][take] < 1.25  # within LEVEL_OFF, as its records were made
    said = f"warning: {take}: level 0.9 x its history's, its own takes within"

    def summarised(ratio: float, called: bool) -> list[str]:
        mine = shutil.copytree(out, tmp_path / f"{ratio}-{called}")
        (cond,) = (c := json.loads((mine / "conditions.json").read_text())).values()
        cond["level_ratio"][take] = ratio
        (mine / "conditions.json").write_text(json.dumps(c))
        records = [json.loads(line) for line in (mine / "results.jsonl").read_text().splitlines()]
        for r in records:  # every method's thresholds under (called) or over the take's scores
            for u, s in r["test_scores"][take].items():
                r["thresholds"][u] = float(np.min(s) - 1.0 if called else np.max(s) + 1.0)
        (mine / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
        summarise(load_scenario(out.parents[2] / "scenarios" / "det.toml"), RunDir.open(mine))
        warned = json.loads((mine / "summary.json").read_text())["warnings"]
        assert all(w in (mine / "table.md").read_text() for w in warned)
        return warned

    assert any(w.startswith(said) and "no gear named" in w for w in summarised(0.9, called=True))
    assert not any(take in w and "level" in w for w in summarised(0.9, called=False))
    assert not any(take in w and "level" in w for w in summarised(1.0, called=True))
