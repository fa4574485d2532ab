"""Which gear with damage on both gears of a pair (a source class "chip+chip@wheel", or a record whose
pinion and wheel are both damaged): detection watches both gears of such a class, and a record
localised on a watched gear and on another gear is called the watched gear's fault and other damage
too (gearlab.kinds.detection_which_gear). Simulated PHM 2009 rig records, a few seconds each."""

import pytest
from which_gear_takes import HISTORY, flags_everything, rig_condition

from gearlab.data import which_gear as W
from gearlab.data.spec import dataset_preset
from gearlab.gearbox import order_table
from gearlab.kinds import detection_which_gear as D

SPEED = 40.0
PINION, IDLER_GEAR = "input pinion 32T (stage 1)", "idler gear 96T (stage 1)"
BOTH = [
    {"name": "chip", "gear": "input pinion", "tooth": 9, "step": 20},
    {"name": "chip", "gear": "idler gear", "tooth": 40, "step": 20},
]


@pytest.fixture(scope="module")
def target():
    files = {
        **HISTORY,
        "both": ("test", "both", BOTH, 3),
        "pinion": ("test", "fault", BOTH[:1], 4),
        "wheel": ("test", "wheel", BOTH[1:], 5),
    }
    cond, labels = rig_condition(files, SPEED, revolutions=90)
    return {"40 Hz": cond}, labels


def test_a_class_on_both_gears_of_a_pair_watches_both():
    source = dataset_preset("phm09-30").with_(faults=(("chip+chip@wheel", (20,)),), teeth=(2,), healthy=1)
    table = order_table(D.gearbox_of(source))
    assert D.watched_gears(source, table) == [PINION, IDLER_GEAR]
    assert D.watched_gears(dataset_preset("phm09-30"), table) == [PINION]


def test_a_record_damaged_on_the_watched_gear_and_another_is_called_both(target):
    conditions, labels = target
    loc = D.localise_target(dataset_preset("phm09-30"), conditions)  # watches the input pinion only
    both = loc["records"]["both"]
    flagged = [s["shaft"] for s in W.flagged_shafts(both)]
    assert sorted(flagged) == ["idler", "input"], both["summary"]
    idler = next(s for s in both["shafts"] if s["shaft"] == "idler")
    assert both["call"] == f"{D.WATCHED}: {PINION}{D.ALSO}{idler['gear']}"
    assert loc["records"]["pinion"]["call"] == f"{D.WATCHED}: {PINION}"
    assert D.is_other(loc["records"]["wheel"]["call"]), loc["records"]["wheel"]["summary"]
    assert D.decision_of(True, both["call"]) == "fault"  # the watched gear's fault, as counted in the verdict
    record = flags_everything(("both", "pinion", "wheel"))
    (called,) = D.calls_by_label(loc, [record], labels)
    assert called["watched"] == {"both": 100.0, "fault": 100.0, "wheel": 0.0}
    assert called["other"] == {"both": 100.0, "fault": 0.0, "wheel": 100.0}  # both: in both columns
    assert called["judged"] == {"both": 2, "fault": 2, "wheel": 0}
    text = D.records_md(loc, labels, D.flagged_takes([record]))
    second = idler["gear"] if both["named_shaft"] == "input" else PINION
    assert f"| 40 Hz | both | both | {both['named']}; {second} |" in text


def test_a_class_on_both_gears_calls_either_gear_its_own(target):
    conditions, _ = target
    source = dataset_preset("phm09-30").with_(faults=(("chip+chip@wheel", (20,)),), teeth=(2,), healthy=1)
    loc = D.localise_target(source, conditions)
    calls = {p: r["call"] for p, r in loc["records"].items()}
    assert all(c.startswith(D.WATCHED) and D.ALSO not in c for c in calls.values()), calls
    assert IDLER_GEAR in calls["wheel"] or "96T gear" in calls["wheel"], calls
