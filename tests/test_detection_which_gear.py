"""Which gear in the detection kind (gearlab.kinds.detection_which_gear): on simulated PHM 2009 rig
records (gearlab.data.simulated), a flag on a record whose change is localised on another gear than
the source's faulty one (the 32T input pinion of phm09_chip) is other damage, not that fault."""

from pathlib import Path

import numpy as np
import pytest
from which_gear_takes import HISTORY, RIG_TESTS, flags_everything, rig_condition

from gearlab.data.simulated import simulated_record
from gearlab.data.spec import dataset_preset
from gearlab.kinds import detection_which_gear as D

SPEED = 40.0


@pytest.fixture(scope="module")
def target():
    files = {**HISTORY, **RIG_TESTS}
    cond, labels = rig_condition(files, SPEED, revolutions=80)
    source = dataset_preset("phm09-30")
    return source, {"40 Hz": cond}, labels


def test_the_watched_gear_is_the_sources_faulty_one(target):
    source, _, _ = target
    box = D.gearbox_of(source)
    assert box.name == "phm09"
    from gearlab.gearbox import order_table

    assert D.watched_gears(source, order_table(box)) == ["input pinion 32T (stage 1)"]


def test_a_flag_on_damage_elsewhere_is_other_damage(target):
    source, conditions, labels = target
    loc = D.localise_target(source, conditions)
    calls = {p: r["call"] for p, r in loc["records"].items()}
    assert calls == {
        "wheel": "other damage: output gear 80T (stage 2)",
        "pinion": "watched-gear fault: input pinion 32T (stage 1)",
        "ok": "watched-gear fault (not localised)",
    }, {p: r["summary"] for p, r in loc["records"].items()}
    # a method that flags every unit of every test record: the output gear's flags are other damage
    record = flags_everything(("wheel", "pinion", "ok"))
    (called,) = D.calls_by_label(loc, [record], labels)
    assert called["unit"] == "record30"
    assert called["watched"] == {"broken output tooth": 0.0, "fault": 100.0, "healthy": 100.0}
    assert called["other"] == {"broken output tooth": 100.0, "fault": 0.0, "healthy": 0.0}
    text = D.records_md(loc, labels, D.flagged_takes([record])) + D.calls_md([called])
    assert "| 40 Hz | wheel | broken output tooth | output gear 80T (stage 2) |" in text
    assert "other damage: output gear 80T (stage 2) |" in text
    assert "| 40 Hz | flags everything | 0 / 100 | 100 / 0 | 100 / 0 |" in text


def test_a_source_without_a_gearbox_description_localises_nothing():
    source = dataset_preset("phm09-30").with_(preset="no such description")
    assert D.gearbox_of(source) is None
    assert D.localise_target(source, {}) is None


def test_a_detection_run_reports_flags_on_other_damage_as_such(cli, tmp_path, monkeypatch, no_figures):
    """The detection kind end to end on simulated rig records (source: the rig simulator with a
    chipped input pinion, as phm09_chip's): localisation.json names each test record's gear,
    table.md and report.html carry the which-gear tables, and a flag on the record with a cracked
    output-gear tooth is counted as other damage, never as a fault of the watched input pinion."""
    import json

    from tiny import EXECUTION, schedule

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    data = tmp_path / "data"
    data.mkdir()
    files = {
        **HISTORY,
        "wheel": ("test", "output gear", [{"name": "crack", "gear": "output gear", "tooth": 3, "step": 20}], 3),
        "pinion": ("test", "fault", [{"name": "crack", "gear": "input pinion", "tooth": 9, "step": 20}], 4),
        "ok": ("test", "healthy", [], 5),
    }
    entries = []
    for name, (role, label, faults, seed) in files.items():
        rec = simulated_record(faults, speed_hz=30.0, revolutions=80, snr_db=30.0, seed=seed)
        np.savez(data / f"{name}.npz", acc=rec.vibration, tacho=rec.tacho, fs=rec.fs)
        entries.append(f'  {{ file = "../data/{name}.npz", role = "{role}", label = "{label}" }},')
    (tmp_path / "scenarios").mkdir()
    path = tmp_path / "scenarios" / "which.toml"
    path.write_text(
        '[scenario]\nname = "which"\nkind = "detection"\n\n'
        '[source]\npreset = "phm09-30"\nteeth = [1, 2]\nfaults = { chip = [20] }\nhealthy = 4\n\n'
        '[target]\nvibration = "acc"\ntacho = "tacho"\npulses_per_rev = 1\npositive = "fault"\nfiles = [\n'
        + "\n".join(entries)
        + '\n]\n\n[classical]\nindicators = ["fm4"]\nmesh_orders = [32, 16]\n\n[detection]\nblocks = [10]\n\n'
        f'[network]\nname = "fast"\n\n[[methods]]\nadapter = "matched_filter"\n\n[protocol]\n{schedule(2)}\n'
        f"{EXECUTION}"
    )
    code, out, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 0, err
    run = Path(out.strip().splitlines()[-1].split(": ", 1)[1])
    loc = json.loads((run / "localisation.json").read_text())
    assert loc["watched"] == ["input pinion 32T (stage 1)"]
    calls = {Path(p).stem: r["call"] for p, r in loc["records"].items()}
    assert calls["wheel"] == "other damage: output gear 80T (stage 2)", loc["records"]
    assert calls["pinion"] == "watched-gear fault: input pinion 32T (stage 1)"
    summary = json.loads((run / "summary.json").read_text())
    for c in summary["which_gear"]["calls"]:  # every method: no output-gear unit is a pinion fault
        assert c["watched"]["output gear"] == 0.0, c
    fm4 = next(c for c in summary["which_gear"]["calls"] if c["method"] == "fm4")
    assert fm4["other"]["output gear"] > 0.0  # FM4 flags the cracked output tooth: other damage
    for page in ("table.md", "report.html"):
        text = (run / page).read_text()
        assert "Which gear (each test record against its condition" in text
        assert "other damage: output gear 80T (stage 2)" in text
    # gearlab score: the new record's gear from the run's stored history, records unread
    code, out, err = cli("score", run, data / "wheel.npz", data / "ok.npz", "--json")
    assert code == 0, err
    scored = {(Path(r["file"]).stem, r["method"], r["unit"]): r for r in json.loads(out)}
    assert {r["localised"] for k, r in scored.items() if k[0] == "wheel"} == {"output gear 80T (stage 2)"}
    assert {r["call"] for k, r in scored.items() if k[0] == "wheel"} == {"other damage: output gear 80T (stage 2)"}
    ok = [r for k, r in scored.items() if k[0] == "ok"]  # a take no method calls: its call says so, no flag's name
    assert {r["decision"] for r in ok} == {"healthy"} and {r["call"] for r in ok} == {D.NOT_CALLED}, ok


def test_a_flag_on_a_take_too_short_for_the_check_is_a_fault_of_no_gear(target):
    # DP: a 2 s take with damage on another gear than the watched one, too short for the which-gear check, was flagged
    # and counted a fault of the watched gear ('watched-gear fault (not localised)'); its gear cannot be read: said so,
    # and neither the watched gear's nor other damage
    source, conditions, labels = target
    cond = dict(conditions["40 Hz"])
    revs, first = cond["raw"]["wheel"]
    cond["raw"] = {**cond["raw"], "wheel": (revs[:20], first)}  # 20 input turns: 4 of the output shaft, 6 needed
    loc = D.localise_target(source, {"40 Hz": cond})
    assert loc["records"]["wheel"]["call"] == "fault, gear not determined: 4 turns of the output shaft, 6 needed"
    assert loc["records"]["pinion"]["call"] == "watched-gear fault: input pinion 32T (stage 1)"
    (called,) = D.calls_by_label(loc, [flags_everything(("wheel", "pinion", "ok"))], labels)
    assert called["watched"]["broken output tooth"] == 0.0 and called["other"]["broken output tooth"] == 0.0
    assert called["undetermined"] == {"broken output tooth": 100.0, "fault": 0.0, "healthy": 0.0}
    assert "| 40 Hz | flags everything | 0 / 0 / 100 | 100 / 0 / 0 | 100 / 0 / 0 |" in D.calls_md([called])
    assert D.decision_of(True, loc["records"]["wheel"]["call"]) == loc["records"]["wheel"]["call"]
    assert D.decision_of(False, loc["records"]["wheel"]["call"]) == "healthy"


def test_the_localisation_thresholds_come_from_the_history_records_alone(target):
    """A condition's per-shaft and non-synchronous thresholds are fixed on its history records: the
    test takes replaced by other recordings (each the output-gear crack's) move none of them."""
    source, conditions, _ = target
    ((name, cond),) = conditions.items()
    tests = [f.path for f, _ in cond["test"]]
    others = {**cond, "raw": {**cond["raw"], **{p: cond["raw"]["wheel"] for p in tests}}}
    plain, other = (D.localise_target(source, {name: c})["conditions"][name] for c in (cond, others))
    assert plain["thresholds"] == other["thresholds"]
    assert plain["nonsync_threshold"] == other["nonsync_threshold"]
