"""A change no shaft's synchronous average carries (gearlab.signals.nonsync) and what a flag on it is
(gearlab.kinds.detection_which_gear): on simulated PHM 2009 rig records at 40 Hz, a record with
bearing-like strikes (a decaying 9 kHz ring at 3.57 strikes per input turn, each interval slipping
1.5 %) is other damage at its strike order, not a fault of the watched 32T input pinion; a cracked
tooth on either gear leaves the residual as the history's, and a record with neither change is the
watched gear's, said as not localised."""

import dataclasses

import numpy as np
import pytest
from which_gear_takes import HISTORY, RIG_TESTS, cut, flags_everything, rig_condition

from gearlab.data.simulated import simulated_record
from gearlab.data.spec import dataset_preset
from gearlab.gearbox import order_table
from gearlab.kinds import detection_which_gear as D

SPEED, REVOLUTIONS = 40.0, 80
STRIKES = 3.57  # strikes per input turn: an outer race's ball pass, no shaft's order (1, 1/3, 1/5)
NON_SYNC = "other damage: non-synchronous (bearing-like), at order"


def strikes(rec, order: float, slip: float, level: float, seed: int, ring_hz: float = 9000.0):
    """*rec* with a ring of *ring_hz* (5 % damping, peak *level* times the record's RMS) struck *order*
    times a turn, each interval off by a Gaussian *slip* of it (a rolling element's random slip)."""
    rng = np.random.default_rng(seed)
    x = rec.vibration.copy()
    t = np.arange(int(0.004 * rec.fs)) / rec.fs
    ring = np.exp(-0.05 * 2 * np.pi * ring_hz * t) * np.sin(2 * np.pi * ring_hz * t) * level * x.std()
    period = 1.0 / (order * rec.speed_hz)
    at = rng.uniform(0, period)
    while at < x.size / rec.fs - t[-1]:
        i = int(at * rec.fs)
        x[i : i + t.size] += ring
        at += period * (1 + slip * rng.standard_normal())
    return dataclasses.replace(rec, vibration=x)


@pytest.fixture(scope="module")
def target():
    files = {**HISTORY, **RIG_TESTS}
    cond, labels = rig_condition(files, SPEED, REVOLUTIONS)
    rec = simulated_record([], speed_hz=SPEED, revolutions=REVOLUTIONS, snr_db=30.0, seed=6)
    cond["raw"]["bearing"] = (cut(strikes(rec, STRIKES, 0.015, 0.3, seed=7)), 0)
    cond["test"].append(
        (dataclasses.replace(cond["test"][0][0], path="bearing", resolved="bearing", label="outer race"), None)
    )
    labels["bearing"] = "outer race"
    return dataset_preset("phm09-30"), {"40 Hz": cond}, labels


def test_the_residual_carries_the_strikes_and_not_a_cracked_tooth(target):
    from gearlab.signals import nonsync as NS

    _, conditions, _ = target
    cond = conditions["40 Hz"]
    table = order_table(D.gearbox_of(dataset_preset("phm09-30")))
    hist = NS.history([cond["raw"][p][0] for p in ("h1", "h2")], table)
    found = {p: NS.nonsync(cond["raw"][p][0], hist, table) for p in cond["raw"]}
    assert found["bearing"].changed and found["bearing"].z > 3 * hist.threshold, found["bearing"]
    assert abs(found["bearing"].order - STRIKES) < 0.02, found["bearing"]
    for p in ("wheel", "pinion", "ok"):  # synchronous (the TSAs carry it) or nothing: the residual as before
        assert not found[p].changed, (p, found[p])


def test_strikes_at_no_shaft_order_are_other_damage_not_the_watched_gear(target):
    source, conditions, labels = target
    loc = D.localise_target(source, conditions)
    calls = {p: r["call"] for p, r in loc["records"].items()}
    assert calls["bearing"].startswith(NON_SYNC), loc["records"]["bearing"]["summary"]
    assert abs(float(calls["bearing"].removeprefix(NON_SYNC)) - STRIKES) < 0.02
    assert calls["pinion"] == "watched-gear fault: input pinion 32T (stage 1)"
    assert calls["wheel"] == "other damage: output gear 80T (stage 2)"
    assert calls["ok"] == "watched-gear fault (not localised)"  # no evidence of where: said so
    assert D.decision_of(True, calls["bearing"]) == calls["bearing"]
    assert D.decision_of(True, calls["ok"]) == "fault"
    # a method that flags every unit: the strikes' flags are counted as other damage
    (called,) = D.calls_by_label(loc, [flags_everything(list(calls))], labels)
    assert called["watched"]["outer race"] == 0.0 and called["other"]["outer race"] == 100.0
    text = D.records_md(loc, labels, set(calls))  # every take flagged: its call shown
    ns = loc["records"]["bearing"]["nonsync"]
    assert f"| {ns['z']:.1f}/{ns['threshold']:.1f} ({ns['order']:.2f}) | {calls['bearing']} |" in text
    assert "non-synchronous z" in D.evidence(loc["records"]["bearing"], ns)


def test_score_reads_the_residual_against_the_runs_stored_history(target, tmp_path):
    """`gearlab score` (localise_scored) reads a new record's residual against the history the detection
    run stored with its localisation, and calls it as the run called the same record."""
    from which_gear_takes import RIG_FS

    from gearlab.data.which_gear import Take
    from gearlab.runs import RunDir

    source, conditions, _ = target
    run = RunDir(tmp_path)
    D.store_localisation(run, source, conditions)
    stored = run.read_json("localisation.json")["records"]
    raw = conditions["40 Hz"]["raw"]
    news = [(p, Take(raw[p][0], raw[p][1], SPEED, RIG_FS)) for p in ("bearing", "ok")]
    scored = D.localise_scored(run, {"40 Hz": news})
    for p in ("bearing", "ok"):
        assert scored[p]["nonsync"] == pytest.approx(stored[p]["nonsync"]), p
        assert scored[p]["call"] == stored[p]["call"], p
    assert scored["bearing"]["call"].startswith(NON_SYNC)
    ns = scored["bearing"]["nonsync"]
    assert scored["bearing"]["evidence"].endswith(
        f"non-synchronous z {ns['z']:.1f}/{ns['threshold']:.1f} (a healthy take passes it at false alarm 0.01) at "
        f"order {ns['order']:.2f}"
    )
