"""The detection verdict once the damaged gear is named (gearlab.kinds.detection_which_gear): a flag on a
record whose change lies on another gear is other damage, neither a detection nor a false alarm of the
watched gear (issue 39: "a record with damage on another gear ... is not called a fault of the watched
gear")."""

from gearlab.kinds.detection_verdict import detection_lines, watched_calls


def _row(method, auc, det, fa):
    return {"condition": "12 Hz", "unit": "record30", "method": method, "auc": auc, "detection": det, "false_alarm": fa}


def _call(method, watched, other, judged=None):
    return {
        "condition": "12 Hz",
        "method": method,
        "unit": "record30",
        "watched": watched,
        "other": other,
        "units": {"fault": 9, "healthy": 9, "wheel_damage": 9},
        "judged": judged or {"fault": 9, "healthy": 9, "wheel_damage": 0},
    }


def test_flags_on_other_damage_are_not_false_alarms_of_the_watched_gear():
    # an outside user's conveyor 31/97: the chip found on every record30 unit, the output-gear damage
    # flagged on every unit too but localised on the 97T gear ("other damage"): 100 / 50 % counted raw
    rows = [_row("likelihood_ratio", 1.0, 100.0, 50.0), _row("na4", 1.0, 100.0, 33.0)]
    calls = [
        _call("likelihood_ratio", {"fault": 100.0, "healthy": 0.0, "wheel_damage": 0.0}, {"wheel_damage": 100.0}),
        # na4 also flags a healthy unit as the watched gear's fault: a false alarm it keeps
        _call("na4", {"fault": 100.0, "healthy": 11.1, "wheel_damage": 0.0}, {"wheel_damage": 66.7}),
    ]
    summary = {"rows": rows, "target": {"positive": "fault"}, "which_gear": {"calls": calls}}
    assert watched_calls(rows[0], summary)["false_alarm"] == 0.0
    # the wheel-damage take's units are neither: na4's false alarms are the healthy take's 11.1 %, not
    # diluted by the other-damage take's units (11.1 / 2 counted over both takes)
    assert abs(watched_calls(rows[1], summary)["false_alarm"] - 11.1) < 1e-9
    # a summary from before 'judged' counts every unit, as it did
    old = {**summary, "which_gear": {"calls": [{k: v for k, v in c.items() if k != "judged"} for c in calls]}}
    assert abs(watched_calls(rows[1], old)["false_alarm"] - 11.1 / 2) < 1e-9
    lines = detection_lines(summary, "record30")
    assert "being other damage, neither" in lines[0]
    assert lines[1] == "12 Hz: goal met by likelihood_ratio."
    # without localisation the rows count as they are: no row meets the goal
    assert detection_lines({"rows": rows}, "record30")[1].startswith("12 Hz: goal met by no row")


def test_a_chip_localised_on_another_gear_is_not_a_detection_of_the_watched_gear():
    rows = [_row("fm4", 1.0, 100.0, 0.0)]
    calls = [_call("fm4", {"fault": 40.0, "healthy": 0.0, "wheel_damage": 0.0}, {"fault": 60.0})]
    summary = {"rows": rows, "target": {"positive": "fault"}, "which_gear": {"calls": calls}}
    assert watched_calls(rows[0], summary)["detection"] == 40.0
    assert detection_lines(summary, "record30")[1].startswith("12 Hz: goal met by no row")


def test_calls_by_label_counts_the_units_a_false_alarm_is_judged_of():
    """Per label: the % called the watched gear's fault and other damage, every unit, and the units of
    records not called other damage (the false alarms' denominator)."""
    from gearlab.kinds.detection_which_gear import OTHER, WATCHED, calls_by_label

    loc = {
        "records": {
            "ok.csv": {"call": "nothing localised"},
            "wheel.csv": {"call": f"{OTHER}: output gear 55T (stage 1)"},
            "chip.csv": {"call": f"{WATCHED}: input pinion 17T (stage 1)"},
        }
    }
    scores = {"ok.csv": [0.0, 2.0, 0.0, 0.0], "wheel.csv": [2.0, 2.0, 0.0, 0.0], "chip.csv": [2.0, 2.0, 2.0, 0.0]}
    record = {
        "condition": "12 Hz",
        "method": "fm4",
        "thresholds": {"record10": 1.0},
        "test_scores": {p: {"record10": s} for p, s in scores.items()},
    }
    labels = {"ok.csv": "healthy", "wheel.csv": "broken55", "chip.csv": "fault"}
    (call,) = calls_by_label(loc, [record], labels)
    assert call["watched"] == {"healthy": 25.0, "broken55": 0.0, "fault": 75.0}
    assert call["other"] == {"healthy": 0.0, "broken55": 50.0, "fault": 0.0}
    assert call["units"] == {"healthy": 4, "broken55": 4, "fault": 4}
    assert call["judged"] == {"healthy": 4, "broken55": 0, "fault": 4}
    row = {
        "condition": "12 Hz",
        "unit": "record10",
        "method": "fm4",
        "auc": 1.0,
        "detection": 75.0,
        "false_alarm": 12.5,
    }
    summary = {"target": {"positive": "fault"}, "which_gear": {"calls": [call]}}
    assert watched_calls(row, summary)["false_alarm"] == 25.0  # the healthy take's one unit in four
