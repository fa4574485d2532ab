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
