"""Gear-pair geometry (thesis 2.1.1, 2.1.2): radii, the two root cases, alpha_5, theta_d/theta_s, contact ratio."""

import math

import pytest

from gearlab.errors import GearlabInputError
from gearlab.physics.geometry import Gear, GearPair
from gearlab.physics.presets import PAIR_PRESETS, gear_pair

PRESETS = ["luo2019", "meng2020"]
# Which gear of each preset has its root circle below the base circle (thesis case 1, Z <= 41).
CASE_1 = {
    ("luo2019", "pinion"): True,
    ("luo2019", "gear"): False,
    ("meng2020", "pinion"): True,
    ("meng2020", "gear"): True,
}


@pytest.fixture(scope="module", params=PRESETS)
def pair(request):
    return gear_pair(request.param)


def _gears(pair):
    return (("pinion", pair.pinion, pair.Z1), ("gear", pair.gear, pair.Z2))


def test_preset_values_are_the_thesis_tables():
    luo, meng = gear_pair("luo2019"), gear_pair("meng2020")
    assert (luo.Z1, luo.Z2, luo.module, luo.face_width) == (16, 48, 3.175e-3, 16e-3)
    assert (meng.Z1, meng.Z2, meng.module, meng.face_width) == (25, 30, 2e-3, 20e-3)
    for p in (luo, meng):
        assert p.pressure_angle == pytest.approx(math.radians(20), abs=1e-15)
        assert (p.E, p.nu, p.hub_radius) == (200e9, 0.3, 9.76e-3)


def test_radii(pair):
    m, a0 = pair.module, pair.pressure_angle
    for _, g, Z in _gears(pair):
        assert g.Z == Z
        assert g.R_b == pytest.approx(0.5 * m * Z * math.cos(a0), rel=1e-14)  # eq. 2.10
        assert g.R_r == pytest.approx(0.5 * m * Z - 1.25 * m, rel=1e-14)  # eq. 2.11
        assert g.R_a == pytest.approx(0.5 * m * Z + m, rel=1e-14)
        assert g.alpha_2 == pytest.approx(math.pi / (2 * Z) + math.tan(a0) - a0, rel=1e-14)  # eq. 2.9


def test_root_case_of_each_gear(pair):
    for label, g, Z in _gears(pair):
        expected = CASE_1[(pair.name, label)]
        assert g.root_below_base is expected, (pair.name, label, g.R_r, g.R_b)
        assert (g.R_r <= g.R_b) is expected
        # For standard 20 deg gears the thesis's split is Z <= 41.
        assert (Z <= 41) is expected
        if expected:
            assert g.d_1 > 0
            assert g.alpha_root == g.alpha_2
            # eq. 2.12: the root circle point of the straight flank
            assert g.R_r * math.sin(g.alpha_3) == pytest.approx(g.R_b * math.sin(g.alpha_2), rel=1e-13)
        else:
            assert g.d_1 == 0.0
            assert g.alpha_root == g.alpha_5


def test_theta_d_plus_theta_s_is_one_pitch(pair):
    assert pair.theta_d + pair.theta_s == pytest.approx(2 * math.pi / pair.Z1, rel=1e-14)
    assert pair.theta_d > 0 and pair.theta_s > 0
    assert pair.theta_t == pytest.approx(2 * pair.theta_d + pair.theta_s, rel=1e-14)


def test_contact_ratio_matches_the_standard_formula(pair):
    p, g, m, a0 = pair.pinion, pair.gear, pair.module, pair.pressure_angle
    a = 0.5 * m * (pair.Z1 + pair.Z2)
    eps = (math.sqrt(p.R_a**2 - p.R_b**2) + math.sqrt(g.R_a**2 - g.R_b**2) - a * math.sin(a0)) / (
        math.pi * m * math.cos(a0)
    )
    assert 1.0 < pair.contact_ratio < 2.0
    assert pair.contact_ratio == pytest.approx(eps, abs=1e-9)


def test_theta_d_is_eq_2_49_with_cos_alpha0(pair):
    Z1, Z2, a0 = pair.Z1, pair.Z2, pair.pressure_angle
    root = math.sqrt(
        (Z2 + 2) ** 2
        + (Z1 + Z2) ** 2
        - 2 * (Z2 + 2) * (Z1 + Z2) * math.cos(math.acos(Z2 * math.cos(a0) / (Z2 + 2)) - a0)
    )
    theta_d = (
        math.tan(math.acos(Z1 * math.cos(a0) / (Z1 + 2)))
        - 2 * math.pi / Z1
        - math.tan(math.acos(Z1 * math.cos(a0) / root))
    )
    assert pair.theta_d == pytest.approx(theta_d, abs=1e-12)
    assert pair.theta_s == pytest.approx(2 * math.pi / Z1 - theta_d, abs=1e-12)  # eq. 2.50


def test_documented_theta_values():
    """The values of docs/physics.md (4 significant digits)."""
    luo, meng = gear_pair("luo2019"), gear_pair("meng2020")
    assert (round(luo.theta_d, 4), round(luo.theta_s, 4), round(luo.contact_ratio, 4)) == (0.2447, 0.1480, 1.6231)
    assert (round(meng.theta_d, 4), round(meng.theta_s, 4), round(meng.contact_ratio, 4)) == (0.1590, 0.0923, 1.6326)


def test_tooth_ends(pair):
    for _, g, _ in _gears(pair):
        # The tip lies on the addendum circle; the involute starts d_1 above the root
        # (case 1: at the base circle, after the straight root region; case 2: on the root circle).
        tip_radius = g.R_b * math.sqrt(1 + (g.alpha_2 - g.alpha_tip) ** 2)
        assert tip_radius == pytest.approx(g.R_a, rel=1e-13)
        assert float(g.x_of(g.alpha_root)) == pytest.approx(g.d_1, abs=1e-12)
        if g.root_below_base:
            # eq. 2.15: d_1 = R_b cos(alpha_2) - R_r cos(alpha_3)
            assert g.d_1 == pytest.approx(g.R_b * math.cos(g.alpha_2) - g.R_r * math.cos(g.alpha_3), rel=1e-12)
        # measured along the centreline from the root point (R_r cos alpha_3|4), so a little over R_a - R_r
        assert 2.25 * pair.module < g.tooth_height < 2.4 * pair.module


@pytest.mark.parametrize("pressure_deg", [14.5, 20.0, 25.0])
def test_alpha_5_on_the_root_circle(pressure_deg):
    a0 = math.radians(pressure_deg)
    module = 2e-3
    case_2 = 0
    for Z in range(42, 301):
        g = Gear(
            Z=Z, module=module, pressure_angle=a0, addendum=1.0, clearance=0.25, hub_radius=5e-3, tool_tip_radius=0.2
        )
        assert g.root_below_base is (g.R_r <= g.R_b)
        if g.root_below_base:
            continue
        case_2 += 1
        a5 = g.alpha_5
        assert math.isfinite(a5)
        assert a5 < g.alpha_2
        assert a5 > g.alpha_tip  # the root lies below the tip on the involute
        assert g.R_b * math.sqrt(1 + (g.alpha_2 - a5) ** 2) == pytest.approx(g.R_r, rel=1e-13, abs=0)
        assert abs(float(g.x_of(a5))) < 1e-12
        # alpha_4 (eq. 2.29): the half thickness at the root seen from the gear centre
        assert g.R_r * math.sin(g.alpha_4) == pytest.approx(float(g.half_thickness(a5)), rel=1e-12)
        assert g.tooth_height > 0
    # 20 deg: every Z >= 42 is case 2; the other angles switch where R_r passes R_b.
    first_case_2 = math.floor(1.25 / (0.5 - 0.5 * math.cos(a0))) + 1
    assert case_2 == 301 - max(42, first_case_2)
    assert case_2 > 0


def _luo(**changes):
    values = {**PAIR_PRESETS["luo2019"], **changes}
    return GearPair(**values)


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"Z1": 16.5}, r"Z1 must be a whole number of teeth, got 16\.5"),
        ({"Z1": 5}, r"Z1 = 5 teeth is too few"),
        ({"module": -3.175e-3}, r"module must be a positive number"),
        ({"hub_radius": 30e-3}, r"hub_radius 30 mm must be smaller than the pinion root radius"),
        ({"pressure_angle": 0.0}, r"pressure_angle must lie between 0 and 45 deg, got 0 deg"),
    ],
)
def test_bad_gear_pair_input(changes, message):
    with pytest.raises(GearlabInputError, match=message):
        _luo(**changes)


def test_hub_radius_equal_to_root_radius_is_rejected():
    p = gear_pair("luo2019")
    with pytest.raises(GearlabInputError, match="hub_radius .* must be smaller than the pinion root radius"):
        _luo(hub_radius=p.pinion.R_r)
    # just below the root radius is fine
    assert _luo(hub_radius=0.999 * p.pinion.R_r).hub_radius == pytest.approx(0.999 * p.pinion.R_r)


def test_unknown_preset_suggests_the_closest():
    with pytest.raises(GearlabInputError, match=r"did you mean 'luo2019'") as info:
        gear_pair("luo2018")
    assert "luo2018" in str(info.value)
    assert "meng2020" in str(info.value)  # known presets are listed
