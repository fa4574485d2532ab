"""Which of a shaft's two gears without simulated events: the event's mesh phase (signals.which_template.
mesh_phases). A tooth that meshes softer deepens its own mesh's cycle while in mesh, so the event's content
about that gear's mesh line stands in phase with the line; the other gear's line at any angle. It names
the gear where the tooth counts are too close for the width (109T and 85T: 1.28). Hand-written trains
(tests/gearboxes.mesh_train: a damaged tooth lifting its own mesh), not gearlab's simulator."""

from __future__ import annotations

from test_localise_noise_units import localised

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


def test_the_mesh_phase_is_said_only_where_it_is_read(tmp_path):
    """29/71 + 22/57: the intermediate shaft's 71T and 22T are 3.2 apart, so the event's width decides (here:
    undecided, a low mode rings) and the mesh phase is not read: the summary and the evidence leave it out
    (before: "undecided by the event's width (..., mesh phase cos 71T -0.25 / 22T 1.00, ...; 81% of the excess
    below order 35.5: a low mode rings)")."""
    found = localised(tmp_path, ((29, 71), (22, 57)), (1, "pinion", 12), fs=12_000.0, speed=20.0, seconds=6.0, bump=0.3)
    for seed in (5, 6, 7):
        ev = next(e for e in found[seed]["shafts"] if e["shaft"] == "intermediate")
        assert ev["stage_evidence"], found[seed]["summary"]  # the width's evidence: two gears, flagged
        assert "mesh phase" not in ev["stage_evidence"] and "mesh phase" not in found[seed]["summary"], found[seed]
        assert ev["stage_evidence"].get("rule", "by the event's width") == "by the event's width"


def test_the_mesh_phase_is_not_said_where_the_simulated_events_decided():
    from gearlab.signals import which_template as T

    ev = {"mesh phase": {"a (stage 1)": 0.9, "b (stage 2)": -0.2}, "simulated fit": {"a (stage 1)": 0.8}}
    assert T.phase_words({**ev, "rule": T.RULE_PHASE}) == "mesh phase cos a 0.90 / b -0.20, "
    assert T.phase_words({**ev, "rule": T.RULE_SIMULATED}) == ""
