"""Which gear of a shaft's two gears where the own-mesh phases barely lead (signals.which_template.REFERENCE_MARGIN;
WEAK_LEAD past FAR_DB): both gears stay named, so a scenario watching either calls the flag its fault (but where the
phases lean: EVEN_LEAD, tests/test_which_order.py), and every call says why. A three-stage box (13/43 + 31/67 +
41/97) from a generator written outside gearlab: damage on the intermediate shaft's 31T pinion was named its 43T
wheel at phase matches such as 0.14 / 0.08 (17.9 dB off the simulated), and detection and score called it other
damage. The records' spectra are the hand-written ones of
tests/test_which_gear_reference.py (another structure than the simulator's); the phase match is set, as such a
record reads it."""

import pytest
from test_which_gear_reference import PINION, SIMULATED, WHEEL, decide

from gearlab.inspect_history import call_of as inspect_call
from gearlab.kinds.detection_which_gear import call_of, decision_of, is_other
from gearlab.signals import localise as L
from gearlab.signals import which_template as T


def _found(by, ev) -> dict:
    """The localisation (Localisation.describe()) of a record whose intermediate shaft is flagged, its gear *by*."""
    gear = L.shaft_label("intermediate", [WHEEL, PINION]) if by is None else by.name
    which = None if by is None else by.name
    shaft = {"shaft": "intermediate", "gears": [WHEEL.name, PINION.name], "which": which, "gear": gear}
    shaft |= {"flagged": True, "z": 177.0, "threshold": 2.81, "tooth": {}, "stage_evidence": ev}
    return {"named": gear, "named_shaft": "intermediate", "shafts": [shaft]}


def _read(monkeypatch, wheel: float, pinion: float):
    """which_by_template on a pinion fault through another structure, the phases matching as given."""
    monkeypatch.setattr(T, "reference_phase_match", lambda *args: {WHEEL.name: wheel, PINION.name: pinion})
    return decide(PINION, 11, -1.0, SIMULATED[::-1])


@pytest.mark.parametrize("wheel, pinion", [(0.14, 0.08), (0.07, -0.05), (0.40, 0.27), (0.12, 0.08)])
def test_a_weak_phase_lead_names_both_gears_and_the_watched_one_calls_it_its_fault(monkeypatch, wheel, pinion):
    # red before: the 63T wheel named at a lead of 0.05 or more, 'other damage' to a scenario watching the pinion.
    # The favoured gear (here the wheel, first as described) is listed first; over EVEN_LEAD only the wheel's scenario
    # calls it its fault (tests/test_which_order.py), at or under it either gear's
    by, ev = _read(monkeypatch, wheel, pinion)
    assert ev["structure gap dB"] > T.SHAPE_DB and ev["rule"] == T.RULE_REFERENCE
    assert by is None, ev
    lead = T.lead_words(wheel - pinion)
    assert ev["undecided"].endswith(f"own mesh lead by {lead}, not over 0.15"), ev
    found = _found(by, ev)
    both = "intermediate shaft: 63T gear (stage 1) or 24T pinion (stage 2)"
    leans = wheel - pinion > T.EVEN_LEAD
    bound = "0.15" if leans else "0.05: either as likely"
    said = f"{both} (undecided by the mesh phases: the first leads by {lead}, not over {bound})"
    for watched in (PINION.name, WHEEL.name):  # either gear's scenario: its fault (detection's table, score)
        call = call_of(found, [watched])
        if leans and watched == PINION.name:
            assert call == f"other damage: {said}" and decision_of(True, call) == call, call
            continue
        assert call == f"watched-gear fault: {said}", call
        assert decision_of(True, call) == "fault"
    other = call_of(found, ["input pinion 21T (stage 1)"])
    assert other == f"other damage: {said}" and is_other(other)
    assert inspect_call(found, {}) == f"localised change: {said}"  # inspect --history
    width = {"event width": "pitches of the 63T wheel", "expected": {WHEEL.name: 0.82, PINION.name: 1.47}}
    words = L.which_line(width | ev, None)  # the evidence as localise merges the width's and the phases'
    assert "; which of the two: undecided by the mesh phases of the simulated events (" in words, words
    assert words.endswith(f"own mesh lead by {lead}, not over 0.15)"), words


def test_a_lead_over_the_margin_still_names_the_gear_said_weak_under_weak_lead(monkeypatch):
    by, ev = _read(monkeypatch, 0.10, 0.27)
    assert by == PINION and not ev.get("undecided")
    found = _found(by, ev)
    call = call_of(found, [WHEEL.name])
    assert call == f"other damage: {PINION.name}, weakly over {WHEEL.name} (phase lead 0.17)", call
    assert call_of(found, [PINION.name]).startswith(f"watched-gear fault: {PINION.name}, weakly over")
    by, ev = _read(monkeypatch, 0.05, 0.45)
    assert by == PINION and call_of(_found(by, ev), [WHEEL.name]) == f"other damage: {PINION.name}"


def test_a_lead_under_weak_lead_names_both_gears_where_the_structures_differ_beyond_far_db(monkeypatch):
    # that box's 31T pinion faults: 43T 0.27 / 31T 0.01 by the phases, its mesh lines 17.9 dB off the simulated
    monkeypatch.setattr(T, "structure_gap", lambda *args: 17.9)
    by, ev = _read(monkeypatch, 0.27, 0.01)
    assert by is None, ev
    assert ev["undecided"].endswith("own mesh lead by 0.26, under 0.3 at a structure gap over 12 dB"), ev
    call = call_of(_found(by, ev), [PINION.name])
    assert call.startswith("watched-gear fault: intermediate shaft: 63T gear (stage 1) or 24T pinion (stage 2)"), call
    assert call.endswith(" (undecided by the mesh phases: lead 0.26, under 0.3 at a structure gap over 12 dB)"), call
    by, ev = _read(monkeypatch, 0.45, 0.01)  # a lead of WEAK_LEAD or more: named
    assert by == WHEEL and call_of(_found(by, ev), [PINION.name]) == f"other damage: {WHEEL.name}"
    monkeypatch.setattr(T, "structure_gap", lambda *args: 9.0)  # within the simulated structures' gaps: named, weakly
    by, ev = _read(monkeypatch, 0.27, 0.01)
    assert by == WHEEL and call_of(_found(by, ev), [PINION.name]).startswith(f"other damage: {WHEEL.name}, weakly")
