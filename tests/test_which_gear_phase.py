"""Which of a shaft's two gears without simulated events: the event's mesh phase (signals.which_template.
mesh_phases). A tooth that meshes softer deepens its own mesh's cycle while in mesh, so the event's content
about that gear's mesh line stands in phase with the line; the other gear's line at any angle. It names
the gear where the tooth counts are too close for the width (109T and 85T: 1.28), and of counts further
apart where the width leaves it undecided, by its 1st and 2nd harmonic alike (in phase or against).
Hand-written trains (tests/gearboxes.mesh_train: a damaged tooth lifting or lowering its own mesh), not
gearlab's simulator."""

from __future__ import annotations

from test_localise_noise_units import localised, z_of

CLOSE = ((31, 109), (85, 127))  # the intermediate shaft's 109T wheel and 85T pinion
OPTIONS = {"fs": 16_000.0, "speed": 20.0, "seconds": 6.0, "bump": 0.3}


def _calls(found: dict) -> list[str | None]:
    """What each fault take names on the intermediate shaft: its gear, or None (both)."""
    out = []
    for seed in (5, 6, 7):
        ev = next(e for e in found[seed]["shafts"] if e["shaft"] == "intermediate")
        assert found[seed]["named_shaft"] == "intermediate", found[seed]["summary"]
        out.append(ev["which"])
    return out


def test_close_tooth_counts_are_told_apart_by_the_mesh_phase(tmp_path):
    """109T vs 85T: before, 'tooth counts 109 and 85 too alike' on every take. Now the 109T's tooth 7 is
    named on every take (cos 1.00 against the 85T's -0.17). Never the wrong gear: where the other line
    stands in anti-phase (109T teeth 40 and 90: -0.96, -0.94; 85T tooth 70: -1.00) or within PHASE_MARGIN
    (85T teeth 12 and 33: 0.26, 0.05 apart), both are named."""
    wheel = localised(tmp_path, CLOSE, (0, "wheel", 7), **OPTIONS)
    pinion = localised(tmp_path, CLOSE, (1, "pinion", 12), **OPTIONS)
    assert wheel[None]["named"] is None and pinion[None]["named"] is None
    assert _calls(wheel) == ["intermediate gear 109T (stage 1)"] * 3, [wheel[s]["summary"] for s in (5, 6, 7)]
    assert set(_calls(pinion)) <= {"intermediate pinion 85T (stage 2)", None}, _calls(pinion)
    assert "by the event's mesh phase" in wheel[5]["summary"] and "mesh phase cos" in wheel[5]["summary"]


FAR = ((29, 71), (22, 57))  # the intermediate shaft's 71T wheel and 22T pinion, 3.2 apart
FAR_OPTIONS = {"fs": 12_000.0, "speed": 20.0, "seconds": 6.0}


def test_a_stage_2_pinion_fault_is_localised_on_its_shaft(tmp_path):
    """29/71 + 22/57: a 22T pinion's damage lifts its mesh (9 input orders); before, the intermediate
    shaft's z was 1.1-1.8 and nothing was localised (against 2.71)."""
    found = localised(tmp_path, FAR, (1, "pinion", 12), bump=0.3, **FAR_OPTIONS)  # read once with the test below
    for seed in (5, 6, 7):
        f = found[seed]
        assert f["named_shaft"] == "intermediate", f["summary"]
        assert z_of(f, "intermediate") > 5 * max(z_of(f, s) for s in ("input", "output")), f["summary"]
    assert found[None]["named"] is None, found[None]["summary"]


def test_far_apart_counts_the_width_leaves_undecided_are_named_by_two_mesh_harmonics(tmp_path):
    """71T and 22T: a 22T tooth lifting its mesh was 'undecided by the event's width (...; 81% of the excess
    below order 35.5: a low mode rings)' on every take, as outside round 14's intermediate-shaft faults
    (22/69 + 25/74, 14/53 + 18/59 + 23/67) were. The event stands at its own mesh's phase at the 1st and
    2nd harmonic alike (22T 1.00, 1.00; 71T -0.25, 0.12): the 22T is named; on one take the 71T's lines
    stand alike by chance too (-0.40, -0.71): both stay named, never the wrong gear. A 71T tooth lowering its
    mesh (a stiffness lost) is named by the width on one take; on two the width reads it between the gears,
    where the phase does not decide (test below): both, never the 22T."""
    pinion = localised(tmp_path, FAR, (1, "pinion", 12), bump=0.3, **FAR_OPTIONS)
    wheel = localised(tmp_path, FAR, (0, "wheel", 30), bump=-0.3, **FAR_OPTIONS)
    assert pinion[None]["named"] is None and wheel[None]["named"] is None
    pinion_22 = "intermediate pinion 22T (stage 2)"
    assert _calls(pinion) == [pinion_22, pinion_22, None], [pinion[s]["summary"] for s in (5, 6, 7)]
    assert _calls(wheel) == ["intermediate gear 71T (stage 1)", None, None], [wheel[s]["summary"] for s in (5, 6, 7)]
    for seed in (5, 6):
        said = pinion[seed]["summary"]
        assert "by the event's mesh phase" in said and "mesh phase cos at 1st, 2nd harmonic" in said, said
    assert "71T -0.40, -0.71 / intermediate pinion 22T 1.00, 1.00: not one alike" in pinion[7]["summary"]


def test_the_mesh_phase_is_not_said_where_the_simulated_events_decided():
    from gearlab.signals import which_template as T

    ev = {"mesh phase": {"a (stage 1)": 0.9, "b (stage 2)": -0.2}, "simulated fit": {"a (stage 1)": 0.8}}
    assert T.phase_words({**ev, "rule": T.RULE_PHASE}) == "mesh phase cos a 0.90 / b -0.20, "
    assert T.phase_words({**ev, "rule": T.RULE_SIMULATED}) == ""


def test_an_event_the_width_reads_between_the_gears_is_not_named_by_the_phase(monkeypatch):
    """The simulated 24/79 + 27/72 reducer's 27T pinion fault (tests/test_localise_blocks, z 13,419): the width
    read 'between the two gears', the 79T's lines stood alike (0.98, 0.99; the 27T's 0.11, 0.39) and the
    phase named the 79T wheel: a wrong gear. The phase decides only where the width abstained (a low mode
    rings, or z under WIDTH_Z); between, both stay named."""
    from gearlab.signals import localise as L
    from gearlab.signals import which_template as T

    wheel, pinion = L.Gear("intermediate", 1, "wheel", 79), L.Gear("intermediate", 2, "pinion", 27)
    both = {wheel.name: [0.98, 0.99], pinion.name: [0.11, 0.39]}
    between = {"undecided": "width between the two gears' (0 < u <= 0.1)", "u": 0.05, "low-order share": 0.1}
    monkeypatch.setattr(T, "_width", lambda *a: (None, dict(between)))
    assert T.which_by_width(None, None, None, [wheel, pinion], 13419.0, {}, both)[0] is None
    rings = {**between, "low-order share": 0.6}  # the width abstained: the phase names the 79T
    monkeypatch.setattr(T, "_width", lambda *a: (None, dict(rings)))
    assert T.which_by_width(None, None, None, [wheel, pinion], 13419.0, {}, both)[0] == wheel
