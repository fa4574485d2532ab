"""Issue 39, outside users' leftovers (helper AB): a run-up test take cut to its revolutions at its
condition's history speed in a detection run as `gearlab score` cuts it (a); the verdict's AUC over the
takes its detected and false-alarm figures count (b). The detection run and `gearlab score` naming the same
gear of a two-gear shaft on the same take (c): tests/test_box_b_takes.py, beside the other box B takes."""

from __future__ import annotations

import numpy as np
import pytest
from detection_scenario import scenario
from test_outside_n import runup

from gearlab.errors import GearlabInputError
from gearlab.kinds import detection_scoring as D
from gearlab.kinds.detection_records import read_target
from gearlab.kinds.detection_verdict import detection_lines, watched_calls
from gearlab.kinds.detection_which_gear import OTHER, WATCHED, calls_by_label
from gearlab.parts.roc import auc


def test_the_verdicts_auc_leaves_out_the_takes_its_false_alarms_leave_out():
    # box T's run (helper O): the broken 58T output gear's take, labelled 'other', flagged on every unit and
    # localised on the 58T (a gear the run does not watch): out of the false alarms, yet ranked as a negative
    loc = {
        "records": {
            "healthy.csv": {"call": f"{WATCHED} (not localised)"},
            "broken.tsv": {"call": f"{OTHER}: output gear 58T (stage 3)"},
            "spall.mat": {"call": f"{WATCHED}: intermediate 1 pinion 24T (stage 2)"},
        }
    }
    scores = {
        "healthy.csv": [0.1, 0.2, 0.0, 0.3],
        "broken.tsv": [5.0, 6.0, 7.0, 8.0],
        "spall.mat": [2.0, 3.0, 2.5, 0.9],
    }
    labels = {"healthy.csv": "healthy", "broken.tsv": "other", "spall.mat": "fault"}
    record = {
        "condition": "45 Hz",
        "method": "fm4",
        "thresholds": {"record30": 1.0},
        "test_scores": {p: {"record30": s} for p, s in scores.items()},
    }
    (call,) = calls_by_label(loc, [record], labels, "fault")
    raw = auc(np.r_[scores["healthy.csv"], scores["broken.tsv"]], np.asarray(scores["spall.mat"]))
    assert raw == 0.5  # the broken take's units outrank every spall unit
    assert call["auc"] == 1.0 == auc(np.asarray(scores["healthy.csv"]), np.asarray(scores["spall.mat"]))
    assert call["left_out"] == {"broken.tsv": f"{OTHER}: output gear 58T (stage 3)"}
    row = {"condition": "45 Hz", "unit": "record30", "method": "fm4", "auc": raw, "detection": 75.0}
    row["false_alarm"] = 50.0  # the table's, every take counted
    summary = {"rows": [row], "target": {"positive": "fault"}, "which_gear": {"calls": [call]}}
    judged = watched_calls(row, summary)
    assert (judged["auc"], judged["detection"], judged["false_alarm"]) == (1.0, 75.0, 0.0)
    line = detection_lines(summary, "record30")[1]
    assert line.startswith("45 Hz: goal met by no row")  # 75 % detected: the AUC alone does not meet it
    assert "left out of its AUC and false alarms as other damage: broken.tsv (other damage: output gear 58T" in line
    # a summary from before the judged AUC: the row's, as it was
    old = {**summary, "which_gear": {"calls": [{k: v for k, v in call.items() if k not in ("auc", "left_out")}]}}
    assert watched_calls(row, old)["auc"] == raw


def _runup_file(folder, role: str, start: float, end: float, seconds: float):
    """The tiny detection scenario (tests/detection_scenario: 16 Hz takes, blocks 5 and 10) with a take running up
    *start* -> *end* Hz over *seconds* (test_outside_n.runup) as a *role* take; its file and the run-up's turns."""
    (folder / "data").mkdir(exist_ok=True)
    turns = runup(folder / "data" / "up.zip", start, end, seconds, chip_outside=4.0)
    files = [("h1", "history", "healthy", 0.0), ("up", role, "healthy", 0.0)]
    files.insert(1, ("h2", "test" if role == "history" else "history", "healthy", 0.0))
    return scenario(folder, files=files, methods=("matched_filter",)), turns


def _runup_scenario(folder, role: str, start: float, end: float, seconds: float):
    """_runup_file's scenario read: its spec and the run-up's turns."""
    from gearlab.notebook import load_scenario

    path, turns = _runup_file(folder, role, start, end, seconds)
    return load_scenario(path).spec, turns


def test_a_run_up_test_take_is_cut_to_its_revolutions_at_the_history_speed_as_score_cuts_it(tmp_path):
    # 14 -> 19 Hz over 12 s, its mean speed 16.5 Hz within 5 % of the 16 Hz history's: before, grouped there and
    # scored whole (all ~200 revolutions, the chipped ones outside the band too); gearlab score scored ~30 of them
    spec, turns = _runup_scenario(tmp_path, "test", 14.0, 19.0, 12.0)
    (name, cond), *others = read_target(spec.target, spec.detection.blocks, lambda e: None, "here").items()
    assert not others
    cut = dict(cond["test"])
    (f,) = [f for f in cut if f.path.endswith("up.zip")]
    centre = float(np.median(list(cond["speeds"][h.path] for h, _ in cond["history"])))
    rec = spec.target.read(f)
    _, part, words = D.in_band({"conditions": {name: {"speed_hz": centre}}}, f.path, rec, None)
    assert len(cut[f]) == len(part.revolutions) < len(rec.revolutions) // 4, (len(cut[f]), len(rec.revolutions))
    inside = int(np.sum(np.abs(turns - 16.0) <= D.IN_BAND * 16.0))
    assert abs(len(cut[f]) - inside) <= 2
    assert words.startswith(f"scored on {len(cut[f])} of {len(rec.revolutions)} revolutions at ")
    assert cond["speed_from"][f.path].endswith(words) and D.VARIES_WORDS in cond["speed_from"][f.path]
    assert cond["speeds"][f.path] == pytest.approx(16.0, rel=D.IN_BAND)
    assert f"{f.path}: 14.08 Hz .. 18.92 Hz {D.VARIES_WORDS} a run-up; {words}" in cond["warnings"], cond["warnings"]
    assert cond["raw"][f.path][0].shape == part.revolutions.shape  # the which-gear check reads the same part


def test_a_run_up_too_short_at_the_history_speed_is_refused_in_one_line(tmp_path):
    # 14 -> 19 Hz over 3 s: ~8 revolutions within 2.5 % of 16 Hz, a record10 unit needs 10
    spec, _ = _runup_scenario(tmp_path, "test", 14.0, 19.0, 3.0)
    with pytest.raises(GearlabInputError) as got:
        read_target(spec.target, spec.detection.blocks, lambda e: None, "det.toml: [target] key 'files'")
    line = str(got.value)
    assert len(line.splitlines()) == 1 and line.startswith("det.toml: [target] key 'files': ../data/up.zip ("), line
    assert "its longest run within 2.5% of the history's 16.00 Hz ('16 Hz') holds " in line, line
    assert "a unit of every kind needs 10" in line and line.count("expected") == 1, line


def test_a_run_up_in_the_history_is_refused_at_run_time_in_one_line(tmp_path, cli, monkeypatch):
    # 14 -> 19 Hz over 2 s: 7 revolutions within 2.5 % of its own median speed, a record10 unit needs 10 (over 6 s,
    # ~16: a history take's steady part is used, tests/test_outside_ae)
    path, _ = _runup_file(tmp_path, "history", 14.0, 19.0, 2.0)
    monkeypatch.chdir(tmp_path / "scenarios")
    code, _, err = cli("run", path, "--out", tmp_path / "runs")
    last = err.strip().splitlines()[-1]
    assert code == 2 and "[target] key 'files': ../data/up.zip (history; " in last, err[-1500:]
    assert "a history take must run steady" in last and D.VARIES_WORDS in last, last
    # its tacho tells it as the scenario is read: validate refuses it in the same line
    code, _, err = cli("validate", path)
    assert code == 2 and err.strip() == last, (err, last)
