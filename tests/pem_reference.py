"""An independent, deliberately plain implementation of the healthy-tooth PEM equations.

It integrates thesis eq. 2.21, 2.23, 2.25 (case 1) and 2.34, 2.36, 2.38 (case 2) in the
angle alpha with scipy.integrate.quad, one contact angle at a time, as published PEM
code does. The tests compare the engine against it; benchmarks/stiffness.py times it.
Only the geometry helpers of GearPair are shared.
"""

from __future__ import annotations

import math

from scipy.integrate import quad

SAINSOT = [
    (-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045),
    (60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086),
    (-50.952e-5, 185.50e-3, 0.0538e-4, 53.3000e-4, 0.2895, 0.9236),
    (-6.204e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904),
]


def tooth_compliance(g, a1: float, E: float, nu: float, L: float, fillet: bool = True) -> float:
    """1/k_a + 1/k_b + 1/k_s (+ 1/k_f) of one healthy tooth at force angle a1."""
    Rb, Rr, a2 = g.R_b, g.R_r, g.alpha_2

    def hx(a):
        return Rb * ((a2 - a) * math.cos(a) + math.sin(a))

    def w(a):
        return (a2 - a) * math.cos(a)

    upper = a2 if g.root_below_base else g.alpha_5
    ka = Rb * math.sin(a1) ** 2 / E * quad(lambda a: w(a) / (2 * hx(a) * L), -a1, upper, limit=200)[0]
    kb = (
        Rb**3
        / E
        * quad(
            lambda a: (1 + math.cos(a1) * ((a2 - a) * math.sin(a) - math.cos(a))) ** 2
            * w(a)
            / (2 / 3 * hx(a) ** 3 * L),
            -a1,
            upper,
            limit=200,
        )[0]
    )
    ks = 2.4 * (1 + nu) * Rb * math.cos(a1) ** 2 / E * quad(lambda a: w(a) / (2 * hx(a) * L), -a1, upper, limit=200)[0]
    if g.root_below_base:  # the straight root region d_1, eq. 2.21, 2.23, 2.25
        a3 = math.asin(Rb * math.sin(a2) / Rr)
        d1 = Rb * math.cos(a2) - Rr * math.cos(a3)
        h1 = Rb * math.sin(a2)
        ka += d1 * math.sin(a1) ** 2 / (2 * E * L * h1)
        kb += (
            Rb**3
            * ((1 - Rr / Rb * math.cos(a1) * math.cos(a3)) ** 3 - (1 - math.cos(a1) * math.cos(a2)) ** 3)
            / (2 * E * L * math.cos(a1) * h1**3)
        )
        ks += 1.2 * (1 + nu) * d1 * math.cos(a1) ** 2 / (E * L * h1)
        x0 = Rr * math.cos(a3)
    else:
        x0 = math.sqrt(Rr**2 - hx(g.alpha_5) ** 2)
    total = ka + kb + ks
    if fillet:
        a0, ha, rc = g.pressure_angle, g.addendum, g.tool_tip_radius
        theta_f = (math.pi / 2 + 2 * math.tan(a0) * (ha - rc) + 2 * rc / math.cos(a0)) / g.Z
        hi = Rr / g.hub_radius
        Ls, Ms, Ps, Qs = (
            A / theta_f**2 + B * hi**2 + C * hi / theta_f + D / theta_f + Ee * hi + F for A, B, C, D, Ee, F in SAINSOT
        )
        d = Rb * ((a1 + a2) * math.sin(a1) + math.cos(a1)) - x0
        h = Rb * ((a1 + a2) * math.cos(a1) - math.sin(a1))
        u = (d - h * math.tan(a1)) / (2 * Rr * theta_f)
        total += math.cos(a1) ** 2 / (E * L) * (Ls * u**2 + Ms * u + Ps * (1 + Qs * math.tan(a1) ** 2))
    return total


def tooth_pair_stiffness(pair, phi: float, fillet: bool = True) -> float:
    """k_t of eq. 2.47 for one healthy tooth pair at pinion angle phi after contact start."""
    a1p = phi - pair.pinion.alpha_2 + pair.roll_start_pinion  # eq. 2.7
    a1g = pair.roll_tip_gear - pair.gear.alpha_2 - pair.Z1 / pair.Z2 * phi  # eq. 2.8
    E, nu, L = pair.E, pair.nu, pair.face_width
    hertz = 4 * (1 - nu**2) / (math.pi * E * L)  # eq. 2.40
    return 1.0 / (
        hertz
        + tooth_compliance(pair.pinion, a1p, E, nu, L, fillet)
        + tooth_compliance(pair.gear, a1g, E, nu, L, fillet)
    )
