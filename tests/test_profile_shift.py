"""Profile-shifted gears and two materials in the PEM mesh stiffness (issue 39 item 1; docs/physics.md 1).

ISO 21771: a shift x moves the tip and root circles out by x m and thickens the tooth by
2 x m tan(alpha_0) at the reference circle; the pair meshes at alpha_w, inv(alpha_w) = inv(alpha_0)
+ 2 (x1 + x2) tan(alpha_0)/(z1 + z2), a_w = a cos(alpha_0)/cos(alpha_w). Two materials: each tooth's
beam and fillet energies with its own E, nu; Hertz k_h = pi L / (2 [(1-nu1^2)/E1 + (1-nu2^2)/E2]).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from gearlab.errors import GearlabInputError
from gearlab.gearbox import gear_pairs, order_table, parse_gearbox, stage_geometry
from gearlab.physics.faults import place_fault
from gearlab.physics.geometry import GearPair
from gearlab.physics.presets import gear_pair
from gearlab.physics.sections import healthy_section
from gearlab.physics.stiffness import MeshStiffnessModel, SectionIntegrals, beam_compliances, hertz_compliance

ALPHA = math.radians(20)
BASE = dict(module=2e-3, face_width=20e-3, pressure_angle=ALPHA, E=200e9, nu=0.3, hub_radius=8e-3)
CAST_IRON = dict(E2=110e9, nu2=0.28)
SHIFTS = [(16, 48, 0.3, 0.0), (16, 48, 0.5, -0.5), (16, 48, 0.5, 0.3), (25, 30, 0.2, 0.2), (14, 39, 0.3, 0.0)]


def inv(a):
    return math.tan(a) - a


def iso(z1, z2, x1, x2, m=2e-3, ha=1.0):
    """(alpha_w, a_w, eps_alpha) straight from ISO 21771 / DIN 3960, alpha_w by bracketing."""
    target = inv(ALPHA) + 2 * (x1 + x2) * math.tan(ALPHA) / (z1 + z2)
    alpha_w = brentq(lambda a: inv(a) - target, 1e-3, 1.2, xtol=1e-15)
    a_w = m * (z1 + z2) / 2 * math.cos(ALPHA) / math.cos(alpha_w)
    rolls = sum(
        math.sqrt((m * z / 2 + (ha + x) * m) ** 2 - (m * z / 2 * math.cos(ALPHA)) ** 2) for z, x in ((z1, x1), (z2, x2))
    )
    return alpha_w, a_w, (rolls - a_w * math.sin(alpha_w)) / (math.pi * m * math.cos(ALPHA))


def described(z1, z2, x1, x2, wheel_material="steel"):
    return parse_gearbox(
        {
            "materials": {"castiron": {"E": "110 GPa", "nu": 0.28, "density": "7200 kg/m^3"}},
            "stages": [
                {
                    "module": "2 mm",
                    "face_width": "20 mm",
                    "pinion": {"z": z1, "x": x1, "bore": "16 mm"},
                    "wheel": {"z": z2, "x": x2, "bore": "16 mm", "material": wheel_material},
                }
            ],
        },
        "box.toml",
    )


def double_contact_share(k: np.ndarray) -> float:
    """Share of a revolution in double contact, read off the TVMS alone: above its widest level gap."""
    s = np.sort(k)
    cut = np.argmax(np.diff(s))
    return float(np.mean(k > 0.5 * (s[cut] + s[cut + 1])))


@pytest.mark.parametrize("z1, z2, x1, x2", SHIFTS)
def test_working_pressure_angle_centre_distance_and_contact_ratio_are_isos(z1, z2, x1, x2):
    pair = GearPair(Z1=z1, Z2=z2, x1=x1, x2=x2, **BASE)
    alpha_w, a_w, eps = iso(z1, z2, x1, x2)
    assert pair.working_pressure_angle == pytest.approx(alpha_w, abs=1e-12)
    assert pair.centre_distance == pytest.approx(a_w, rel=1e-12)
    assert pair.contact_ratio == pytest.approx(eps, rel=1e-10)
    check = stage_geometry(described(z1, z2, x1, x2).stages[0])  # the description's checks agree
    assert (check.alpha_w, check.a_w, check.contact_ratio) == pytest.approx((alpha_w, a_w, eps), rel=1e-10)
    if x1 + x2 > 0:
        assert alpha_w > ALPHA and a_w > 0.5 * 2e-3 * (z1 + z2)


@pytest.mark.parametrize("z1, z2, x1, x2", [(16, 48, 0.0, 0.0), *SHIFTS])
def test_the_tvms_double_contact_share_is_eps_minus_one(z1, z2, x1, x2):
    pair = GearPair(Z1=z1, Z2=z2, x1=x1, x2=x2, **BASE, **CAST_IRON)
    k = MeshStiffnessModel(pair).mesh_stiffness(points=z1 * 512).k
    assert double_contact_share(k) == pytest.approx(iso(z1, z2, x1, x2)[2] - 1, abs=2.5e-3)


def test_a_positive_shift_thickens_a_small_pinions_root_and_stiffens_its_tooth():
    compliance, thickness = {}, {}
    for x in (0.0, 0.25, 0.5):
        g = GearPair(Z1=16, Z2=48, x1=x, **BASE).pinion
        section = healthy_section(g, BASE["face_width"])
        # the load at the tip: the same tooth height (R_a - R_r = 2.25 m) whatever x, a thicker tooth
        alpha1 = np.array([math.sqrt((g.R_a / g.R_b) ** 2 - 1) - g.alpha_2])
        terms = beam_compliances(g, SectionIntegrals(section), alpha1, g.E, g.nu)
        compliance[x], thickness[x] = float(terms["bending"][0]), 2 * float(section.h[0])
        # s = m (pi/2 + 2 x tan alpha_0) on the reference circle
        half_angle = g.alpha_2 - inv(ALPHA)
        assert g.R_p * 2 * half_angle == pytest.approx(2e-3 * (math.pi / 2 + 2 * x * math.tan(ALPHA)), rel=1e-12)
        assert g.R_a - g.R_p == pytest.approx((1 + x) * 2e-3) and g.R_p - g.R_r == pytest.approx((1.25 - x) * 2e-3)
    assert thickness[0.0] < thickness[0.25] < thickness[0.5]
    assert compliance[0.5] < compliance[0.25] < 0.85 * compliance[0.0]  # 1.47e-9, 1.17e-9, 1.04e-9 m/N


def test_no_shift_and_one_material_give_the_numbers_of_before():
    # the presets' means before shifts existed (4096 points, float repr)
    before = {"luo2019": 189114382.00822234, "meng2020": 371784556.61527777, "phm09_stage1": 161792056.254219}
    for name, mean in before.items():
        pair = gear_pair(name)
        assert (pair.x1, pair.x2, pair.working_pressure_angle) == (0.0, 0.0, pair.pressure_angle)
        # to the last bits: numpy's sin/cos differ by one ulp with the CPU's SIMD (AVX-512 or not:
        # NPY_DISABLE_CPU_FEATURES="AVX512_ICL X86_V4" gives meng2020's ...77, AVX-512 ...78); any change
        # of the maths moves the mean by far more than 4 ulp
        assert abs(MeshStiffnessModel(pair).mesh_stiffness().mean - mean) <= 4 * np.spacing(mean)
    shifted_zero = GearPair(Z1=16, Z2=48, x1=0.0, x2=0.0, E2=None, **BASE)
    assert np.array_equal(
        MeshStiffnessModel(shifted_zero).mesh_stiffness().k,
        MeshStiffnessModel(GearPair(Z1=16, Z2=48, **BASE)).mesh_stiffness().k,
    )


def test_two_materials_reduce_to_one_as_e2_tends_to_e1():
    one = MeshStiffnessModel(GearPair(Z1=16, Z2=48, **BASE)).mesh_stiffness().k
    same = MeshStiffnessModel(GearPair(Z1=16, Z2=48, E2=200e9, nu2=0.3, **BASE)).mesh_stiffness().k
    near = MeshStiffnessModel(GearPair(Z1=16, Z2=48, E2=200e9 * (1 + 1e-9), nu2=0.3, **BASE)).mesh_stiffness().k
    assert np.array_equal(same, one)
    assert np.allclose(near, one, rtol=1e-8, atol=0)
    L = np.array([0.02])
    assert hertz_compliance(200e9, 0.3, L, 200e9 * (1 + 1e-12), 0.3) == pytest.approx(
        hertz_compliance(200e9, 0.3, L), rel=1e-10
    )
    # steel on cast iron lies between all steel and all cast iron; the cast-iron wheel alone is softer
    iron = GearPair(Z1=16, Z2=48, **{**BASE, "E": 110e9, "nu": 0.28})
    mixed = MeshStiffnessModel(GearPair(Z1=16, Z2=48, **BASE, **CAST_IRON)).mesh_stiffness().mean
    assert MeshStiffnessModel(iron).mesh_stiffness().mean < mixed < one.mean()
    assert hertz_compliance(200e9, 0.3, L, 110e9, 0.28)[0] == pytest.approx(
        2 * ((1 - 0.09) / 200e9 + (1 - 0.28**2) / 110e9) / (math.pi * 0.02), rel=1e-14
    )


@pytest.mark.parametrize("z1, z2, x1, x2", [(16, 48, 0.5, 0.3), (14, 39, 0.4, 0.1), (16, 48, 0.5, -0.5)])
def test_a_shifted_two_material_tooth_pair_matches_direct_quadrature(z1, z2, x1, x2):
    from pem_reference import tooth_compliance  # thesis eq. 2.21-2.46 in alpha, one angle at a time

    pair = GearPair(Z1=z1, Z2=z2, x1=x1, x2=x2, **BASE, **CAST_IRON)
    phi = np.linspace(0.0, pair.theta_t, 13)[1:-1]
    ours = MeshStiffnessModel(pair).tooth_pair_stiffness(phi)
    p, g, L = pair.pinion, pair.gear, pair.face_width
    hertz = 2 * ((1 - p.nu**2) / p.E + (1 - g.nu**2) / g.E) / (math.pi * L)
    reference = [
        1
        / (
            hertz
            + tooth_compliance(p, pair.alpha1_pinion(f), p.E, p.nu, L)
            + tooth_compliance(g, pair.alpha1_gear(f), g.E, g.nu, L)
        )
        for f in phi
    ]
    assert np.max(np.abs(ours / np.array(reference) - 1)) < 1e-4


def test_the_wheel_view_keeps_each_gears_shift_and_material():
    pair = GearPair(Z1=16, Z2=48, x1=0.4, x2=-0.1, **BASE, **CAST_IRON)
    view = pair.seen_from("wheel")
    assert (view.Z1, view.x1, view.x2, view.E, view.E2, view.nu, view.nu2) == (48, -0.1, 0.4, 110e9, 200e9, 0.28, 0.3)
    assert view.pinion is pair.gear and view.contact_ratio == pytest.approx(pair.contact_ratio, rel=1e-12)
    assert view.working_pressure_angle == pair.working_pressure_angle


@pytest.mark.parametrize("kind", ["crack", "chip", "spall", "pit", "broken_tip"])
@pytest.mark.parametrize("gear", ["pinion", "wheel"])
def test_every_fault_plugin_works_on_a_shifted_two_material_pair(registry, kind, gear):
    pair = GearPair(Z1=14, Z2=39, x1=0.4, x2=0.1, **BASE, **CAST_IRON)
    model = MeshStiffnessModel(pair)
    healthy = model.mesh_stiffness().mean  # over a pinion turn; a wheel fault's table is over a wheel turn
    means = [model.mesh_stiffness([place_fault(registry, pair, kind, 3, step=s, gear=gear)]).mean for s in (1, 10, 20)]
    assert means[0] == pytest.approx(healthy, rel=1e-3)  # step 1 is healthy
    assert all(np.isfinite(means)) and means[2] <= means[1] < means[0]


def test_a_shifted_steel_on_cast_iron_description_simulates_at_its_mesh_order(tmp_path):
    from gearlab.notebook import simulate_signals

    path = tmp_path / "shifted.toml"
    path.write_text(
        '[gearbox]\nname = "shifted"\n[operation]\nspeed = "25 Hz"\nload = "20 N*m"\n'
        '[materials.castiron]\nE = "110 GPa"\nnu = 0.28\ndensity = "7200 kg/m^3"\n'
        '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
        'pinion = { z = 14, x = 0.4, bore = "12 mm" }\n'
        'wheel = { z = 39, x = 0.1, bore = "20 mm", material = "castiron" }\n'
    )
    sim = simulate_signals(gearbox=str(path), duration=0.44, faults=["crack@3=12"])
    assert np.all(np.isfinite(sim.tvms)) and sim.tvms.min() > 0
    x = sim.channels["casing_x"][sim.t >= 0.04]
    order = np.fft.rfftfreq(x.size, sim.t[1] - sim.t[0]) / 25.0  # 10 revolutions: bins of 0.1 order
    amp = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size)))
    strongest = order[np.argmax(np.where(order > 2, amp, 0))]
    assert strongest / 14 == pytest.approx(round(strongest / 14), abs=0.01)  # a mesh harmonic of 14 teeth
    mesh = amp[np.argmin(abs(order - 14))]
    assert mesh > 100 * np.median(amp[(order > 2) & (order < 200)])
    assert order_table(described(14, 39, 0.4, 0.1, "castiron")).stages[0].mesh == 14


def test_the_checks_refuse_what_cannot_be_cut_and_name_x_as_a_remedy():
    with pytest.raises(GearlabInputError, match=r"undercut.*profile shift 'x' ≥ 0.131") as info:
        described(12, 40, 0.0, 0.0)
    assert "inspect only" not in str(info.value)
    (pair,) = gear_pairs(described(12, 40, 0.3, 0.0))  # the remedy: a shifted 12-tooth pinion simulates
    assert pair.contact_ratio == pytest.approx(iso(12, 40, 0.3, 0.0)[2], rel=1e-10)
    with pytest.raises(GearlabInputError, match=r"pointed"):
        described(12, 40, 1.5, 0.0)
    with pytest.raises(GearlabInputError, match=r"pinion teeth are pointed"):
        GearPair(Z1=12, Z2=40, x1=1.5, **BASE)
    with pytest.raises(GearlabInputError, match=r"mating tip reaches the pinion root circle"):
        GearPair(Z1=20, Z2=40, x1=1.0, x2=1.0, **{**BASE, "clearance": 0.0})
    with pytest.raises(GearlabInputError, match=r"x1 must lie in \[-1, 2\]"):
        GearPair(Z1=20, Z2=40, x1=float("nan"), **BASE)
