"""Issue 39, outside users' leftovers (helper AB): a run-up test take cut to its revolutions at its
condition's history speed in a detection run as `gearlab score` cuts it (a); the verdict's AUC over the
takes its detected and false-alarm figures count (b); the detection run and `gearlab score` name the same
gear of a two-gear shaft on the same take (c)."""

from __future__ import annotations

import numpy as np

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
