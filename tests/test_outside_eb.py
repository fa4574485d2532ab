"""An outside user's (helper EB's) leftovers from a 42/63 + 23/71 box: the verdict's words for a mains-hum take."""

from __future__ import annotations

from gearlab.kinds.detection_verdict import left_out

HUM_CALL = "not a gear fault: mains hum at 50.0 Hz (order 2.08; the 50 Hz mains: electrical pickup)"


def _summary(calls: dict) -> dict:
    return {"which_gear": {"calls": [{"condition": "24 Hz", "unit": "record30", "left_out": calls}]}}


def test_verdict_says_a_mains_hum_take_is_no_gear_fault_not_other_damage():
    summary = _summary({"hum.csv": HUM_CALL, "out71.csv": "other damage: output gear 71T (stage 2)"})
    words = left_out(summary, "24 Hz", "record30")
    assert "as other damage: out71.csv (other damage: output gear 71T (stage 2))" in words
    assert "hum.csv" not in words.split("as other damage:")[1].split(";")[0]
    assert f"as no gear fault: hum.csv ({HUM_CALL})" in words
    # the hum alone: no "other damage" said at all
    alone = left_out(_summary({"hum.csv": HUM_CALL}), "24 Hz", "record30")
    assert "other damage" not in alone and alone.startswith("; left out of its AUC and false alarms as no gear fault")
