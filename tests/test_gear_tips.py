"""Per-gear addendum, dedendum and tip diameter (issue 39 item 1; ISO 21771 h_a*, h_f*, d_a).

A gear's own 'addendum' or 'tip_diameter' moves its tip circle (d_a = d + 2 m (h_a* + x), or as
given), its own 'dedendum' its root circle (d_f = d - 2 m (h_f* - x)); absent, the stage's. The
PEM stiffness (R_a, R_r per gear), the contact ratio and the checks follow; a shifted pair whose
tip reaches the mating root is refused naming the key, and derives once the tip is shortened.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from gearlab.errors import GearlabInputError
from gearlab.gearbox import gear_pairs, parse_gearbox, stage_geometry
from gearlab.physics.faults import place_fault
from gearlab.physics.geometry import GearPair
from gearlab.physics.stiffness import MeshStiffnessModel

ALPHA = math.radians(20)
M = 2e-3


def described(z1, z2, pinion=None, wheel=None, **stage):
    return parse_gearbox(
        {
            "stages": [
                {
                    "module": "2 mm",
                    "face_width": "20 mm",
                    **stage,
                    "pinion": {"z": z1, "bore": "16 mm", **(pinion or {})},
                    "wheel": {"z": z2, "bore": "16 mm", **(wheel or {})},
                }
            ]
        },
        "box.toml",
    )


def iso_contact_ratio(z1, z2, d_a1, d_a2, x1=0.0, x2=0.0):
    """ε_α of ISO 21771 from the tip diameters: (√(r_a1² - r_b1²) + √(r_a2² - r_b2²) - a_w sin α_w) / p_b."""
    inv = math.tan(ALPHA) - ALPHA + 2 * (x1 + x2) * math.tan(ALPHA) / (z1 + z2)
    lo, hi = 1e-3, 1.2  # α_w by bisection on inv α_w
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if math.tan(mid) - mid < inv else (lo, mid)
    alpha_w = 0.5 * (lo + hi)
    a_w = M * (z1 + z2) / 2 * math.cos(ALPHA) / math.cos(alpha_w)
    rolls = sum(math.sqrt((d / 2) ** 2 - (M * z / 2 * math.cos(ALPHA)) ** 2) for z, d in ((z1, d_a1), (z2, d_a2)))
    return (rolls - a_w * math.sin(alpha_w)) / (math.pi * M * math.cos(ALPHA))


def double_contact_share(k: np.ndarray) -> float:
    """Share of a revolution in double contact, read off the TVMS alone: above its widest level gap."""
    s = np.sort(k)
    cut = np.argmax(np.diff(s))
    return float(np.mean(k > 0.5 * (s[cut] + s[cut + 1])))


# (z1, z2, pinion keys, wheel keys, tip diameters d_a1, d_a2 in mm by ISO 21771)
CASES = [
    (16, 48, {"addendum": 0.8}, {}, 16 * 2 + 4 * 0.8, 48 * 2 + 4),
    (16, 48, {}, {"addendum": 0.85}, 36.0, 96 + 4 * 0.85),
    (25, 30, {"addendum": 1.1}, {"tip_diameter": "63.2 mm"}, 50 + 4 * 1.1, 63.2),
    (20, 40, {"x": 0.5, "addendum": 0.9}, {"x": 0.3, "addendum": 0.95}, 40 + 4 * 1.4, 80 + 4 * 1.25),
    (18, 54, {"dedendum": 1.3, "x": 0.2}, {"dedendum": 1.35}, 36 + 4 * 1.2, 108 + 4),
]


@pytest.mark.parametrize("z1, z2, pinion, wheel, d_a1, d_a2", CASES)
def test_contact_ratio_of_per_gear_tips_is_isos_and_the_tvms_s(z1, z2, pinion, wheel, d_a1, d_a2):
    box = described(z1, z2, pinion, wheel)
    x1, x2 = pinion.get("x", 0.0), wheel.get("x", 0.0)
    eps = iso_contact_ratio(z1, z2, d_a1 * 1e-3, d_a2 * 1e-3, x1, x2)
    assert stage_geometry(box.stages[0]).contact_ratio == pytest.approx(eps, rel=1e-9)
    (pair,) = gear_pairs(box)
    assert pair.contact_ratio == pytest.approx(eps, rel=1e-9)
    assert (2 * pair.pinion.R_a, 2 * pair.gear.R_a) == pytest.approx((d_a1 * 1e-3, d_a2 * 1e-3), rel=1e-12)
    for gear, spec in ((pair.pinion, box.stages[0].pinion), (pair.gear, box.stages[0].wheel)):
        h_f = 1.25 if spec.dedendum is None else spec.dedendum
        assert gear.R_r == pytest.approx(gear.R_p - (h_f - spec.x) * M, rel=1e-12)
    k = MeshStiffnessModel(pair).mesh_stiffness(points=z1 * 512).k
    assert double_contact_share(k) == pytest.approx(eps - 1, abs=2.5e-3)


def test_the_stages_values_given_per_gear_change_nothing_and_absent_keys_are_the_pair_of_before():
    (plain,) = gear_pairs(described(16, 48))
    assert (plain.d_a1, plain.d_a2, plain.h_f1, plain.h_f2) == (None, None, None, None)
    assert plain == GearPair(Z1=16, Z2=48, module=M, face_width=20e-3, pressure_angle=ALPHA, E=200e9, nu=0.3,
                             hub_radius=8e-3, name="box")  # fmt: skip
    (same,) = gear_pairs(described(16, 48, {"addendum": 1.0, "dedendum": 1.25}, {"tip_diameter": "100 mm"}))
    a, b = MeshStiffnessModel(plain).mesh_stiffness().k, MeshStiffnessModel(same).mesh_stiffness().k
    assert np.allclose(a, b, rtol=1e-9, atol=0)


def test_a_tip_reaching_the_mating_root_names_the_key_and_a_shortened_tip_derives():
    shifts = ({"x": 1.0}, {"x": 1.0})
    with pytest.raises(GearlabInputError) as info:
        described(20, 40, *shifts)
    text = str(info.value)
    assert text.startswith("box.toml: [[stages]] #1.wheel key 'addendum': the wheel's tip (d_a = 88 mm) reaches ")
    assert "pinion's root circle" in text and "\n" not in text
    tip, addendum = (
        float(v) for v in re.search(r"'tip_diameter' ≤ ([\d.]+) mm or 'addendum' ≤ ([\d.]+)", text).groups()
    )
    # the same with the pinion's tip: both tips are shortened, by the diameter or by the coefficient
    pinion = {"x": 1.0, "addendum": addendum}
    (pair,) = gear_pairs(described(20, 40, pinion, {"x": 1.0, "tip_diameter": f"{tip} mm"}))
    clearance = pair.centre_distance - pair.gear.R_a - pair.pinion.R_r
    assert -1e-9 < clearance < 1e-6  # the suggested tip just clears the root
    eps = iso_contact_ratio(20, 40, 2 * pair.pinion.R_a, tip * 1e-3, 1.0, 1.0)
    assert pair.contact_ratio == pytest.approx(eps, rel=1e-9)
    with pytest.raises(GearlabInputError, match=r"#1.wheel key 'tip_diameter': the wheel's tip .* reaches"):
        described(20, 40, pinion, {"x": 1.0, "tip_diameter": f"{tip + 0.01} mm"})


@pytest.mark.parametrize(
    "pinion, wheel, message",
    [
        ({"addendum": 0.9, "tip_diameter": "35 mm"}, {}, r"#1.pinion key 'tip_diameter': give the tip by 'addendum'"),
        ({}, {"addendum": 3}, r"#1.wheel key 'addendum': 3 is outside \[0.5, 1.5\]"),
        ({}, {"tip_diameter": 25}, r"#1.wheel key 'tip_diameter': 25 is outside .*a bare number is in m"),
        # a number in quotes is as bare ('module = "2.5"' read only "'2.5' is outside [0.1 mm, 100 mm]")
        (
            {},
            {"tip_diameter": "25"},
            r"key 'tip_diameter': '25' is outside .*a bare number is in m; expected e.g. '25 mm'",
        ),
        ({}, {"tip_diameter": "90 mm"}, r"#1.wheel key 'tip_diameter': 90 mm lies inside the root circle \(91 mm\)"),
        ({}, {"tip_diameter": "120 mm"}, r"#1.wheel key 'tip_diameter': the teeth are pointed"),
        ({"dedendum": 1.45}, {}, r"#1.pinion key 'z': 16 teeth .* undercut .*smaller 'dedendum' of this gear: 1.45"),
        ({"addendum": 0.5}, {"addendum": 0.5}, r"contact ratio ε_α = 0.8.. below 1 .*'addendum' or 'tip_diameter'"),
        ({"dedendum": 1.25, "unknown": 1}, {}, r"#1.pinion key 'unknown': unknown key"),
    ],
)
def test_bad_per_gear_tips_are_one_line_naming_the_key(pinion, wheel, message):
    with pytest.raises(GearlabInputError, match=message) as info:
        described(16, 48, pinion, wheel)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("kind", ["crack", "chip", "broken_tip"])
def test_the_wheel_view_keeps_each_gears_tip_and_a_fault_on_a_short_tip_works(registry, kind):
    (pair,) = gear_pairs(described(16, 48, {"addendum": 0.85, "dedendum": 1.2}, {"tip_diameter": "99 mm"}))
    view = pair.seen_from("wheel")
    assert (view.d_a1, view.d_a2, view.h_f1, view.h_f2) == (pair.d_a2, pair.d_a1, None, 1.2)
    assert view.pinion is pair.gear and view.contact_ratio == pytest.approx(pair.contact_ratio, rel=1e-12)
    model = MeshStiffnessModel(pair)
    healthy = model.mesh_stiffness().mean
    for gear in ("pinion", "wheel"):
        means = [model.mesh_stiffness([place_fault(registry, pair, kind, 3, step=s, gear=gear)]).mean for s in (1, 20)]
        assert means[0] == pytest.approx(healthy, rel=1e-3) and means[1] < means[0]
