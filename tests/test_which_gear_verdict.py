"""The detection verdict once the damaged gear is named (gearlab.kinds.detection_which_gear): a flag on a
record whose change lies on another gear is other damage, neither a detection nor a false alarm of the
watched gear (issue 39: "a record with damage on another gear ... is not called a fault of the watched
gear")."""

from gearlab.kinds.detection_verdict import detection_lines, watched_calls


def _row(method, auc, det, fa):
    return {"condition": "12 Hz", "unit": "record30", "method": method, "auc": auc, "detection": det, "false_alarm": fa}


def _call(method, watched, other):
    return {
        "condition": "12 Hz",
        "method": method,
        "unit": "record30",
        "watched": watched,
        "other": other,
        "units": {"fault": 9, "healthy": 9, "wheel_damage": 9},
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
    assert abs(watched_calls(rows[1], summary)["false_alarm"] - 11.1 / 2) < 1e-9
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
