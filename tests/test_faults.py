"""Fault plugins against the claims of thesis 2.2.1-2.2.6 and Figures 2.32 / 2.33."""

import math

import numpy as np
import pytest

from gearlab.errors import GearlabInputError
from gearlab.physics.stiffness import contact_geometry, tooth_pair_compliances
from gearlab_plugins.faults.pit import draw_pits

PRESETS = ["luo2019", "meng2020"]
KINDS = ["crack", "chip", "broken_tip", "spall", "pit"]


def tvms(registry, pair, model, specs, points=4096):
    """specs: (kind, tooth, step) triples, all in one call."""
    placed = []
    for kind, tooth, step in specs:
        fault = registry.get("fault", kind)
        placed.append(fault.place(tooth, fault.at_step(pair, step), pair))
    return model.mesh_stiffness(placed, points=points)


def local_angle(pair, theta, tooth):
    return np.mod(theta - (tooth - 1) * 2 * math.pi / pair.Z1, 2 * math.pi)


def pinion_contact_x(pair, phi):
    """Contact position d (from the pinion tooth root) at tooth-local pinion angle phi."""
    d, _ = contact_geometry(pair.pinion, pair.alpha1_pinion(np.asarray(phi, dtype=float)))
    return d


# --- broken tooth and crack ------------------------------------------------------------------


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("tooth", [1, 5, 16])
def test_broken_tooth_has_zero_stiffness_in_its_single_contact_zone(registry, pairs, models, preset, tooth):
    pair, model = pairs[preset], models[preset]
    healthy = model.mesh_stiffness(points=4096)
    broken = tvms(registry, pair, model, [("crack", tooth, 20)])
    phi = local_angle(pair, broken.theta, tooth)
    single = (phi > pair.theta_d) & (phi < pair.theta_d + pair.theta_s)
    assert single.sum() > 20
    assert np.all(broken.k[single] < 1e-6 * healthy.mean)
    # Elsewhere the neighbouring teeth carry the load: stiffness stays positive, and
    # outside the broken tooth's meshing arc it is the healthy TVMS.
    assert np.all(broken.k[~single] > 0.2 * healthy.mean)
    out = phi >= pair.theta_t
    np.testing.assert_array_equal(broken.k[out], healthy.k[out])
    # In double contact only the neighbour is left: below healthy.
    double = (phi < pair.theta_t) & ~single
    assert np.all(broken.k[double] < healthy.k[double])


@pytest.mark.parametrize("preset", PRESETS)
def test_crack_stiffness_loss_grows_with_the_ladder(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    runs = [tvms(registry, pair, model, [("crack", 5, step)]) for step in range(1, 21)]
    means = np.array([r.mean for r in runs])
    mins = np.array([r.k.min() for r in runs])
    healthy = model.mesh_stiffness(points=4096)
    assert means[0] == pytest.approx(healthy.mean, rel=1e-5)  # step 1 is healthy (exactness: see below)
    assert np.all(np.diff(means) < 0), means
    assert np.all(np.diff(mins) <= 0), mins
    assert mins[-1] == 0.0  # broken tooth


@pytest.mark.parametrize("preset", PRESETS)
def test_crack_loss_grows_with_depth_per_explicit_parameters(registry, pairs, models, preset):
    """Beyond the ladder: a deeper crack (explicit q0 = q2 with units) always lowers every sample."""
    pair, model = pairs[preset], models[preset]
    crack = registry.get("fault", "crack")
    previous = model.mesh_stiffness(points=4096).k
    for depth_mm in (0.5, 1.0, 2.0, 3.0):
        params = crack.resolve({"q0": f"{depth_mm} mm", "q2": f"{depth_mm} mm"}, pair)
        assert params["q0"] == pytest.approx(depth_mm * 1e-3)
        k = model.mesh_stiffness([crack.place(5, params, pair)], points=4096).k
        assert np.all(k <= previous) and np.any(k < previous)
        previous = k


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("preset", PRESETS)
def test_step_1_is_exactly_healthy(registry, pairs, models, preset, kind):
    pair, model = pairs[preset], models[preset]
    fault = registry.get("fault", kind)
    section = fault.apply(model.pinion_section, fault.at_step(pair, 1), pair)
    for name in ("h", "A", "I", "L"):
        np.testing.assert_array_equal(getattr(section, name), getattr(model.pinion_section, name))
    np.testing.assert_array_equal(tvms(registry, pair, model, [(kind, 5, 1)]).k, model.mesh_stiffness(points=4096).k)


@pytest.mark.parametrize("preset", PRESETS)
def test_zero_depth_crack_leaves_the_tooth_healthy(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    crack = registry.get("fault", "crack")
    section = crack.apply(model.pinion_section, crack.resolve({"q0": 0.0, "q2": 0.0}, pair), pair)
    np.testing.assert_array_equal(section.h, model.pinion_section.h)


def _worst_on_pinion(registry, pair, model, kind: str):
    """The parameters of *kind*'s worst ladder step (20) and the pinion section it leaves."""
    fault = registry.get("fault", kind)
    params = fault.at_step(pair, 20)
    return params, fault.apply(model.pinion_section, params, pair)


# --- chip: only the Hertz term ----------------------------------------------------------------


@pytest.mark.parametrize("preset", PRESETS)
def test_chip_changes_only_the_hertz_term(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    healthy_section = model.pinion_section
    params, chipped = _worst_on_pinion(registry, pair, model, "chip")
    # The section arrays other than L are untouched
    for name in ("x", "h", "A", "I"):
        np.testing.assert_array_equal(getattr(chipped, name), getattr(healthy_section, name))
    assert np.any(chipped.L < healthy_section.L)

    phi = np.linspace(0.0, pair.theta_t, 801)
    before = tooth_pair_compliances(pair, phi, healthy_section, model.gear_section)
    after = tooth_pair_compliances(pair, phi, chipped, model.gear_section)
    assert set(before) == set(after) and "hertz" in before and "total" in before
    assert {"axial1", "bending1", "shear1", "fillet1", "axial2", "bending2", "shear2", "fillet2"} <= set(before)
    for key in before:
        if key not in ("hertz", "total"):
            assert np.array_equal(before[key], after[key]), key

    x = pinion_contact_x(pair, phi)
    on_chip = x > healthy_section.tooth_height - params["b"]
    below = x < healthy_section.tooth_height - params["b"] - 2 * np.diff(healthy_section.x).max()
    assert on_chip.sum() > 10 and below.sum() > 10
    assert np.all(after["hertz"][on_chip] > before["hertz"][on_chip])
    np.testing.assert_array_equal(after["hertz"][below], before["hertz"][below])
    # the tip is where the chip takes the most width
    assert after["hertz"][-1] / before["hertz"][-1] == np.max(after["hertz"] / before["hertz"])


# --- broken tip: the chip with a sharp fracture edge ---------------------------------------------


@pytest.mark.parametrize("preset", PRESETS)
def test_broken_tip_loses_contact_above_its_fracture_line_where_the_chip_tapers(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    broken, chip = registry.get("fault", "broken_tip"), registry.get("fault", "chip")
    params = broken.at_step(pair, 20)
    assert params == chip.at_step(pair, 20)  # the same ladder: depth b, the whole face width at step 20
    phi = np.linspace(0.0, pair.theta_t, 1601)
    x = pinion_contact_x(pair, phi)
    dx = np.diff(model.pinion_section.x).max()
    line = model.pinion_section.tooth_height - params["b"]
    above, below = x > line + dx, x < line - dx
    assert above.sum() > 50 and below.sum() > 50
    healthy = model.tooth_pair_stiffness(phi)
    k_broken = model.tooth_pair_stiffness(phi, [broken.place(1, params, pair)])
    k_chip = model.tooth_pair_stiffness(phi, [chip.place(1, params, pair)])
    # Above the line the whole width is gone: no contact, where the tapered chip still carries load
    # until the very tip (it has lost nothing just above its line and everything at the tip).
    assert np.all(k_broken[above] == 0.0)
    assert k_chip[above][0] > 0.99 * healthy[above][0] and np.all(k_chip[above][:-1] > 0.0)
    # Below the line the tooth is the healthy one: every compliance term the same.
    np.testing.assert_array_equal(k_broken[below], healthy[below])


@pytest.mark.parametrize("preset", PRESETS)
def test_broken_tip_keeps_the_width_left_above_its_line(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    broken = registry.get("fault", "broken_tip")
    params = broken.at_step(pair, 11)  # about half the face width
    healthy_section = model.pinion_section
    section = broken.apply(healthy_section, params, pair)
    above = healthy_section.x > healthy_section.tooth_height - params["b"]
    share = (pair.face_width - params["c"]) / pair.face_width
    for name in ("L", "A", "I"):  # Table 2.2's section: A_x and I_x in proportion to the width
        np.testing.assert_allclose(getattr(section, name)[above], share * getattr(healthy_section, name)[above])
        np.testing.assert_array_equal(getattr(section, name)[~above], getattr(healthy_section, name)[~above])
    np.testing.assert_array_equal(section.h, healthy_section.h)
    phi = np.linspace(0.0, pair.theta_t, 1601)
    x = pinion_contact_x(pair, phi)
    on = x > healthy_section.tooth_height - params["b"] + np.diff(healthy_section.x).max()
    before = tooth_pair_compliances(pair, phi, healthy_section, model.gear_section)
    after = tooth_pair_compliances(pair, phi, section, model.gear_section)
    np.testing.assert_allclose(after["hertz"][on], before["hertz"][on] / share)  # eq. 2.94 with L - c
    assert np.all(after["bending1"][on] > before["bending1"][on])
    # The TVMS loses more the wider the break.
    means = [tvms(registry, pair, model, [("broken_tip", 3, step)]).mean for step in range(1, 21)]
    assert np.all(np.diff(means) < 0)


def test_broken_tip_refuses_a_break_past_the_root_or_the_face(registry, pairs):
    pair = pairs["meng2020"]
    broken, where = registry.get("fault", "broken_tip"), "fault broken_tip@3"
    with pytest.raises(GearlabInputError, match=rf"^{where}: chip depth b = 5 mm reaches past the tooth root"):
        broken.resolve({"b": "5 mm", "c": "10 mm"}, pair, where)
    with pytest.raises(GearlabInputError, match=rf"^{where}: chip width c = 25 mm exceeds the face width 20 mm"):
        broken.resolve({"b": "1 mm", "c": "25 mm"}, pair, where)


# --- spall: depth lowers beam stiffness after the spall (Fig. 2.13 discussion) -----------------


@pytest.mark.parametrize("preset", PRESETS)
def test_spall_lowers_beam_stiffness_past_the_spall_but_not_hertz(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    healthy_section = model.pinion_section
    params, spalled = _worst_on_pinion(registry, pair, model, "spall")

    phi = np.linspace(0.0, pair.theta_t, 1601)
    before = tooth_pair_compliances(pair, phi, healthy_section, model.gear_section)
    after = tooth_pair_compliances(pair, phi, spalled, model.gear_section)
    x = pinion_contact_x(pair, phi)
    dx = np.diff(healthy_section.x).max()
    start, end = params["x_1"], params["x_1"] + params["l_s"]
    past = x > end + 2 * dx
    inside = (x > start + 2 * dx) & (x < end - 2 * dx)
    before_spall = x < start - 2 * dx
    assert past.sum() > 20 and inside.sum() > 20 and before_spall.sum() > 20

    for key in ("bending1", "axial1", "shear1"):
        assert np.all(after[key][past] > before[key][past]), key
        np.testing.assert_array_equal(after[key][before_spall], before[key][before_spall])
    np.testing.assert_array_equal(after["hertz"][past], before["hertz"][past])
    np.testing.assert_array_equal(after["hertz"][before_spall], before["hertz"][before_spall])
    assert np.all(after["hertz"][inside] > before["hertz"][inside])
    # Fillet and the gear's terms are untouched.
    for key in ("fillet1", "axial2", "bending2", "shear2", "fillet2"):
        np.testing.assert_array_equal(after[key], before[key])

    # In the TVMS: past the spall the stiffness stays below healthy (not just inside it).
    healthy = model.mesh_stiffness(points=4096)
    faulted = tvms(registry, pair, model, [("spall", 5, 20)])
    phi_t = local_angle(pair, faulted.theta, 5)
    in_arc = phi_t < pair.theta_t
    x_t = np.where(in_arc, pinion_contact_x(pair, np.minimum(phi_t, pair.theta_t)), -1.0)
    after_spall = in_arc & (x_t > end + 2 * dx)
    assert after_spall.sum() > 5
    assert np.all(faulted.k[after_spall] < healthy.k[after_spall])


# --- pits ------------------------------------------------------------------------------------


def irregularity(diff: np.ndarray) -> int:
    """Number of sign changes of the slope of *diff* over its affected zone.

    Slopes smaller than 1e-3 of the largest are ignored so that rounding noise and flat
    stretches do not count; a smooth dip (spall, crack, chip) changes slope sign once or twice.
    """
    zone = np.flatnonzero(np.abs(diff) > 1e-9 * np.abs(diff).max())
    segment = diff[zone.min() : zone.max() + 1]
    slope = np.diff(segment)
    slope = slope[np.abs(slope) > 1e-3 * np.abs(slope).max()]
    return int(np.count_nonzero(np.sign(slope[1:]) != np.sign(slope[:-1])))


@pytest.mark.parametrize("preset", PRESETS)
def test_pit_stiffness_decreases_with_pit_count(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    pit = registry.get("fault", "pit")
    ladder = pit.ladder(pair)
    counts = [p["count"] for p in ladder]
    assert counts[0] == 0 and counts[-1] == 2000 and counts == sorted(counts)
    means = np.array([tvms(registry, pair, model, [("pit", 5, step)]).mean for step in range(1, 21)])
    assert means[0] == model.mesh_stiffness(points=4096).mean
    assert np.all(np.diff(means) <= 0), means
    assert means[-1] < means[0] * (1 - 5e-4)


@pytest.mark.parametrize("preset", PRESETS)
def test_pit_tvms_is_irregular_unlike_the_spall(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    points = pair.Z1 * 1024
    healthy = model.mesh_stiffness(points=points).k
    stats = {}
    for kind in ("pit", "spall", "crack", "chip"):
        k = tvms(registry, pair, model, [(kind, 5, 20 if kind != "crack" else 12)], points=points).k
        stats[kind] = irregularity(k - healthy)
    assert stats["pit"] > 10, stats
    for smooth in ("spall", "crack", "chip"):
        assert stats[smooth] <= 3, stats
        assert stats["pit"] > 5 * max(stats[smooth], 1), stats


def test_pit_draws_are_seeded_and_nested(registry, pairs):
    pit = registry.get("fault", "pit")
    pair = pairs["luo2019"]
    base = pit.resolve({"count": 1500}, pair)
    few = pit.resolve({"count": 500}, pair)
    again = draw_pits(base)
    first = draw_pits(base)
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a, b)
    small = draw_pits(few)
    assert [len(a) for a in first] == [1500] * 3 and [len(a) for a in small] == [500] * 3
    for a, b in zip(small, first):
        np.testing.assert_array_equal(a, b[:500])
    # another seed is another draw
    other = draw_pits({**base, "seed": 1})
    assert not np.array_equal(other[0], first[0])
    # centres follow the pitting line: mean u, spread sigma_u
    assert np.mean(first[0]) == pytest.approx(base["u"], abs=4 * base["sigma_u"] / math.sqrt(1500))
    assert np.std(first[0]) == pytest.approx(base["sigma_u"], rel=0.1)


def test_pit_sections_are_nested(registry, pairs, models):
    """More pits never give back material: L, A, I are non-increasing in the count."""
    pit = registry.get("fault", "pit")
    pair, model = pairs["luo2019"], models["luo2019"]
    previous = model.pinion_section
    for count in (100, 500, 1500):
        section = pit.apply(model.pinion_section, pit.resolve({"count": count}, pair), pair)
        for name in ("L", "A", "I"):
            assert np.all(getattr(section, name) <= getattr(previous, name)), (count, name)
        previous = section


# --- RFA (Figure 2.32) -----------------------------------------------------------------------


@pytest.mark.parametrize("preset", PRESETS)
def test_rfa_per_figure_2_32(registry, pairs, preset):
    pair = pairs[preset]
    rfa = {
        kind: [registry.get("fault", kind).rfa(p, pair) for p in registry.get("fault", kind).ladder(pair)]
        for kind in KINDS
    }
    for kind in KINDS:
        assert rfa[kind][0] == 0.0, kind
        assert np.all(np.diff(rfa[kind]) >= 0), kind
    assert rfa["crack"][-1] == pytest.approx(1.0, abs=1e-12)
    assert np.all(np.diff(rfa["crack"]) > 0)
    for kind in ("chip", "spall", "pit"):
        assert 0.0 < rfa[kind][-1] <= 0.2, (kind, rfa[kind][-1])


def test_rfa_documented_values_luo2019(registry, pairs):
    pair = pairs["luo2019"]
    documented = {"crack": 1.000, "spall": 0.129, "pit": 0.086, "chip": 0.072}
    for kind, value in documented.items():
        fault = registry.get("fault", kind)
        assert fault.rfa(fault.at_step(pair, 20), pair) == pytest.approx(value, abs=5e-4), kind


# --- several faults on several teeth ------------------------------------------------------------


@pytest.mark.parametrize("preset", PRESETS)
def test_several_faults_on_several_teeth(registry, pairs, models, preset):
    pair, model = pairs[preset], models[preset]
    healthy = model.mesh_stiffness(points=4096)
    specs = [("crack", 2, 12), ("spall", 9, 20), ("pit", 9, 20)]
    both = tvms(registry, pair, model, specs)
    arc2 = local_angle(pair, both.theta, 2) < pair.theta_t
    arc9 = local_angle(pair, both.theta, 9) < pair.theta_t
    assert not np.any(arc2 & arc9)
    outside = ~(arc2 | arc9)
    assert outside.sum() > 1000
    np.testing.assert_array_equal(both.k[outside], healthy.k[outside])
    diff = np.abs(both.k - healthy.k)
    assert diff[arc2].max() > 1e-3 * healthy.mean
    assert diff[arc9].max() > 1e-3 * healthy.mean

    # Each tooth's part is what that tooth's faults give on their own ...
    crack_only = tvms(registry, pair, model, specs[:1])
    np.testing.assert_allclose(both.k[arc2], crack_only.k[arc2], rtol=1e-12)
    tooth9 = tvms(registry, pair, model, specs[1:])
    np.testing.assert_allclose(both.k[arc9], tooth9.k[arc9], rtol=1e-12)
    # ... and the spall and the pits on tooth 9 both count.
    spall_only = tvms(registry, pair, model, specs[1:2])
    pit_only = tvms(registry, pair, model, specs[2:])
    assert np.all(tooth9.k[arc9] <= spall_only.k[arc9] + 1e-9 * healthy.mean)
    assert np.all(tooth9.k[arc9] <= pit_only.k[arc9] + 1e-9 * healthy.mean)
    assert tooth9.k[arc9].sum() < min(spall_only.k[arc9].sum(), pit_only.k[arc9].sum())


# --- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kind, given, message",
    [
        ("crack", {"q0": "6 mm"}, r"parameter 'q0' = 6 mm makes the crack deeper than the tooth is thick \(5\.398 mm"),
        ("crack", {"q0": "6 mm", "q2": "6 mm"}, r"deeper than the tooth is thick"),
        ("spall", {"x_1": "7 mm", "l_s": "1 mm"}, r"spall ends 8 mm from the root, past the tooth tip at 7\.294 mm"),
        ("chip", {"c": "-1 mm"}, r"parameter 'c'.*-1 mm is outside \[0 mm, 1000 mm\]"),
        ("crack", {"q1": "1 mm"}, r"unknown parameter 'q1' \(did you mean 'q(0|2)'\?\)"),
        ("crack", {"q1": "1 mm"}, r"unknown parameter 'q1'.*; known: q0, q2, L_c, nu"),
        ("crack", {"L_C": "1 mm"}, r"unknown parameter 'L_C' \(did you mean 'L_c'\?\)"),
        ("pit", {"sigma_uu": "1 um"}, r"unknown parameter 'sigma_uu' \(did you mean 'sigma_u'\?\)"),
        ("spall", {"ls": "1 mm"}, r"unknown parameter 'ls' \(did you mean 'l_s'\?\)"),
        ("spall", {"l_s": "3 s"}, r"parameter 'l_s'.*'3 s' has the wrong dimension; expected a quantity in m"),
        ("pit", {"count": 2.5}, r"parameter 'count'.*expected a whole number"),
        ("pit", {"count": 2001}, r"count = 2001 pits exceeds the draw size"),
    ],
)
def test_bad_fault_parameters(registry, pairs, kind, given, message):
    fault = registry.get("fault", kind)
    with pytest.raises(GearlabInputError, match=message):
        fault.resolve(given, pairs["luo2019"])


def test_good_explicit_parameters_with_units(registry, pairs):
    pair = pairs["luo2019"]
    params = registry.get("fault", "crack").resolve({"q0": "2 mm", "q2": "2000 um", "nu": "45 deg"}, pair)
    assert params == pytest.approx({"q0": 2e-3, "q2": 2e-3, "L_c": 1.0, "nu": math.pi / 4})
    # a just-through crack is allowed (the ladder's top), a bit deeper is not
    crack = registry.get("fault", "crack")
    top = crack.at_step(pair, 20)
    crack.resolve(top, pair)
    with pytest.raises(GearlabInputError, match="deeper than the tooth"):
        crack.resolve({**top, "q0": top["q0"] * 1.001}, pair)


@pytest.mark.parametrize("step", [0, 21])
def test_bad_ladder_step(registry, pairs, step):
    for kind in KINDS:
        with pytest.raises(GearlabInputError, match=rf"intensity step must lie in 1\.\.20, got {step}"):
            registry.get("fault", kind).at_step(pairs["luo2019"], step)


@pytest.mark.parametrize("tooth", [0, 17])
def test_bad_tooth(registry, pairs, tooth):
    pair = pairs["luo2019"]
    crack = registry.get("fault", "crack")
    with pytest.raises(GearlabInputError, match=rf"tooth must be a pinion tooth number in 1\.\.16, got {tooth}"):
        crack.place(tooth, crack.at_step(pair, 5), pair)


def test_tooth_17_is_fine_on_meng2020(registry, pairs):
    pair = pairs["meng2020"]
    crack = registry.get("fault", "crack")
    assert crack.place(25, crack.at_step(pair, 5), pair).tooth == 25
    with pytest.raises(GearlabInputError, match=r"1\.\.25, got 26"):
        crack.place(26, crack.at_step(pair, 5), pair)
