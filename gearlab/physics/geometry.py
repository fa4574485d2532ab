"""Spur gear pair geometry for the potential-energy method (thesis 2.1.1, 2.1.2).

Symbols follow the thesis: Z teeth, m module, alpha_0 pressure angle, R_b base radius,
R_r root radius, alpha_2 half tooth angle on the base circle, alpha_3 / alpha_4, alpha_5 the
angles where the tooth meets the root circle, d_1 the straight root region, theta_d and
theta_s the double- and single-contact durations in pinion angle. SI units throughout.

Profile shift (ISO 21771): gear i is cut with the rack x_i m further out, so

    R_a = R_p + (h_a* + x) m,   R_r = R_p - (h_a* + c* - x) m,
    alpha_2 = pi/(2Z) + 2 x tan(alpha_0)/Z + inv(alpha_0)      (eq. 2.9; s = m (pi/2 + 2 x tan alpha_0)),

and the pair meshes at the working pressure angle and centre distance

    inv(alpha_w) = inv(alpha_0) + 2 (x1 + x2) tan(alpha_0)/(Z1 + Z2),   a_w = a cos(alpha_0)/cos(alpha_w),

which replace alpha_0 and a in the contact start of eq. 2.7 / 2.49. With x1 = x2 = 0 every
expression is the thesis's, float for float. Each gear carries its own material (E, nu).

Per gear (ISO 21771), a tip diameter d_a (a shortened or lengthened tip: R_a = d_a / 2) and a
dedendum coefficient h_f* (R_r = R_p - (h_f* - x) m; the generating rack's h_a of eq. 2.45 is
then h_f* - c); absent, the pair's addendum and clearance give both, float for float as before.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

from ..errors import GearlabInputError


def involute(angle: float) -> float:
    return math.tan(angle) - angle


def inverse_involute(value: float) -> float:
    """alpha with inv(alpha) = value (Newton from a cube-root start; a few steps below 60 deg)."""
    if value <= 0:
        return 0.0
    a = (3.0 * value) ** (1.0 / 3.0)
    for _ in range(50):
        step = (involute(a) - value) / math.tan(a) ** 2  # d inv(alpha) / d alpha = tan^2(alpha)
        a -= step
        if abs(step) < 1e-15:
            break
    return a


@dataclass(frozen=True)
class Gear:
    """Derived geometry of one gear of the pair (i = 1 pinion, i = 2 driven gear): profile shift
    coefficient x (ISO 21771) and the gear's own material E (Pa), nu (None: geometry only)."""

    Z: int
    module: float
    pressure_angle: float
    addendum: float  # h_a
    clearance: float  # c
    hub_radius: float  # R_h
    tool_tip_radius: float  # r_c, dimensionless (Sainsot et al. 2004)
    x: float = 0.0  # profile shift coefficient
    E: float | None = None
    nu: float | None = None
    tip_diameter: float | None = None  # d_a (m); None: d + 2 (h_a + x) m
    dedendum: float | None = None  # h_f*; None: h_a + c

    @property
    def R_p(self) -> float:
        return 0.5 * self.module * self.Z

    @property
    def R_b(self) -> float:  # eq. 2.10
        return self.R_p * math.cos(self.pressure_angle)

    @property
    def R_r(self) -> float:  # eq. 2.11 with the shift: R_p - (h_f* - x) m
        if self.dedendum is not None:
            return self.R_p - (self.dedendum - self.x) * self.module
        return self.R_p - (self.addendum + self.clearance - self.x) * self.module

    @property
    def R_a(self) -> float:  # R_p + (h_a* + x) m, or d_a / 2 where the tip diameter is given
        if self.tip_diameter is not None:
            return 0.5 * self.tip_diameter
        return self.R_p + (self.addendum + self.x) * self.module

    @property
    def alpha_2(self) -> float:  # eq. 2.9 with the shift's 2 x tan(alpha_0)/Z
        return (
            math.pi / (2 * self.Z) + 2 * self.x * math.tan(self.pressure_angle) / self.Z + involute(self.pressure_angle)
        )

    @property
    def root_below_base(self) -> bool:
        """Case 1 of the thesis (Z <= 41 for standard 20 deg gears): R_r <= R_b.

        Decided on the radii themselves, so other pressure angles and tooling
        coefficients fall into the right case.
        """
        return self.R_r <= self.R_b

    @property
    def alpha_3(self) -> float:  # eq. 2.12, case 1 only
        return math.asin(self.R_b * math.sin(self.alpha_2) / self.R_r)

    @property
    def alpha_5(self) -> float:
        """Involute parameter alpha where the profile meets the root circle (case 2).

        Eq. 2.26 carries a sign error (it should read ... cos a5 + sin a5, as eq. 2.32 does);
        with it corrected, eq. 2.28 reduces to R_b^2 (1 + (alpha_2 - alpha_5)^2) = R_r^2: the
        radius of an involute point with roll angle alpha_2 - alpha. Its root below alpha_2
        is the closed form below; no Newton iteration is needed (docs/physics.md).
        """
        return self.alpha_2 - math.sqrt((self.R_r / self.R_b) ** 2 - 1.0)

    @property
    def alpha_4(self) -> float:  # eq. 2.29 with the corrected sign
        return math.asin(self.half_thickness(self.alpha_5) / self.R_r)

    @property
    def x_root(self) -> float:
        """Radial position of the tooth root (x = 0) along the centreline: R_r cos alpha_3|4."""
        return self.R_r * math.cos(self.alpha_3 if self.root_below_base else self.alpha_4)

    @property
    def d_1(self) -> float:  # eq. 2.15; no straight root region in case 2
        return self.R_b * math.cos(self.alpha_2) - self.x_root if self.root_below_base else 0.0

    @property
    def alpha_root(self) -> float:
        """Involute parameter at the lower end of the involute: alpha_2 (case 1) or alpha_5 (case 2)."""
        return self.alpha_2 if self.root_below_base else self.alpha_5

    @property
    def alpha_tip(self) -> float:
        """Involute parameter alpha at the tip circle (the most negative alpha on the tooth)."""
        return self.alpha_2 - math.sqrt((self.R_a / self.R_b) ** 2 - 1.0)

    def half_thickness(self, alpha):
        """h_x on the involute, eq. 2.17 / 2.32 (works on floats and numpy arrays)."""
        import numpy as np

        return self.R_b * ((self.alpha_2 - alpha) * np.cos(alpha) + np.sin(alpha))

    def x_of(self, alpha):
        """Distance from the tooth root along the centreline, eq. 2.16 / 2.31."""
        import numpy as np

        return self.R_b * ((alpha - self.alpha_2) * np.sin(alpha) + np.cos(alpha)) - self.x_root

    @property
    def tooth_height(self) -> float:
        """d_h of eq. 2.70: distance from the root to the tip along the centreline."""
        return float(self.x_of(self.alpha_tip))

    @property
    def theta_f(self) -> float:
        """Eq. 2.45, the same for any x: the shifted rack's half space on the rolling line is
        x m tan(alpha_0) wider and its tip line (h - x) m deeper, so the half width at the root
        circle, R_p theta_f, is pi m/4 + h m tan(alpha_0) (+ the tool-tip terms) whatever x is.
        h is the generating rack's: h_a, or h_f* - c where the gear's dedendum is given (the tip
        diameter does not enter: a turned tip leaves the cut root as it is)."""
        ha = self.addendum if self.dedendum is None else self.dedendum - self.clearance
        a0, rc = self.pressure_angle, self.tool_tip_radius
        return (math.pi / 2 + 2 * math.tan(a0) * (ha - rc) + 2 * rc / math.cos(a0)) / self.Z

    @property
    def S_f(self) -> float:  # eq. 2.44
        return 2 * self.R_r * self.theta_f


@dataclass(frozen=True)
class GearPair:
    """A spur gear pair: pinion (1) drives gear (2). Values in SI units (m, rad, Pa)."""

    Z1: int
    Z2: int
    module: float
    face_width: float
    pressure_angle: float
    E: float
    nu: float
    hub_radius: float
    addendum: float = 1.0
    clearance: float = 0.25
    tool_tip_radius: float = 0.2
    name: str = ""
    x1: float = 0.0  # profile shift coefficients (ISO 21771) of the pinion and the gear
    x2: float = 0.0
    E2: float | None = None  # the gear's material; None: the pinion's (E, nu)
    nu2: float | None = None
    d_a1: float | None = None  # tip diameters (m) of the pinion and the gear; None: d + 2 (h_a + x) m
    d_a2: float | None = None
    h_f1: float | None = None  # dedendum coefficients h_f* of the pinion and the gear; None: h_a + c
    h_f2: float | None = None
    pinion: Gear = field(init=False, repr=False, compare=False)
    gear: Gear = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        self._check()
        # one rack (module, pressure angle, addendum, clearance, tool tip) and one hub for both gears
        shared = ("module", "pressure_angle", "addendum", "clearance", "hub_radius", "tool_tip_radius")
        common = {name: getattr(self, name) for name in shared}
        E2 = self.E if self.E2 is None else self.E2
        nu2 = self.nu if self.nu2 is None else self.nu2
        one = dict(x=self.x1, E=self.E, nu=self.nu, tip_diameter=self.d_a1, dedendum=self.h_f1)
        two = dict(x=self.x2, E=E2, nu=nu2, tip_diameter=self.d_a2, dedendum=self.h_f2)
        object.__setattr__(self, "pinion", Gear(Z=self.Z1, **one, **common))
        object.__setattr__(self, "gear", Gear(Z=self.Z2, **two, **common))
        self._check_mesh()

    def _check(self) -> None:
        where = f"gear pair {self.name!r}" if self.name else "gear pair"
        for label, z in (("Z1", self.Z1), ("Z2", self.Z2)):
            if isinstance(z, bool) or not isinstance(z, int) and not (isinstance(z, float) and z.is_integer()):
                raise GearlabInputError(f"{where}: {label} must be a whole number of teeth, got {z!r}")
            if int(z) < 8:
                raise GearlabInputError(f"{where}: {label} = {int(z)} teeth is too few; expected at least 8")
        object.__setattr__(self, "Z1", int(self.Z1))
        object.__setattr__(self, "Z2", int(self.Z2))
        positive = {
            "module": self.module,
            "face_width": self.face_width,
            "E": self.E,
            "hub_radius": self.hub_radius,
            "addendum": self.addendum,
        }
        for label, value in positive.items():
            if not (value > 0 and math.isfinite(value)):
                raise GearlabInputError(f"{where}: {label} must be a positive number, got {value!r}")
        if not (0 < self.pressure_angle < math.radians(45)):
            raise GearlabInputError(
                f"{where}: pressure_angle must lie between 0 and 45 deg, got {math.degrees(self.pressure_angle):g} deg"
            )
        for label, nu in (("nu", self.nu), ("nu2", self.nu2)):
            if nu is not None and not (0 <= nu < 0.5):
                raise GearlabInputError(f"{where}: Poisson's ratio {label} must lie in [0, 0.5), got {nu!r}")
        if self.E2 is not None and not (self.E2 > 0 and math.isfinite(self.E2)):
            raise GearlabInputError(f"{where}: E2 must be a positive number, got {self.E2!r}")
        for label, x in (("x1", self.x1), ("x2", self.x2)):
            if not (isinstance(x, (int, float)) and -1.0 <= x <= 2.0):
                raise GearlabInputError(f"{where}: profile shift {label} must lie in [-1, 2], got {x!r}")
        for label, value in (("d_a1", self.d_a1), ("d_a2", self.d_a2), ("h_f1", self.h_f1), ("h_f2", self.h_f2)):
            if value is not None and not (isinstance(value, (int, float)) and value > 0 and math.isfinite(value)):
                raise GearlabInputError(f"{where}: {label} must be a positive number, got {value!r}")
        if not (0 <= self.clearance < 1 and 0 <= self.tool_tip_radius < self.addendum):
            raise GearlabInputError(f"{where}: clearance must lie in [0, 1) and tool_tip_radius in [0, addendum)")

    def _check_mesh(self) -> None:
        where = f"gear pair {self.name!r}" if self.name else "gear pair"
        for label, g in (("pinion", self.pinion), ("gear", self.gear)):
            if not (0 < self.hub_radius < g.R_r):
                raise GearlabInputError(
                    f"{where}: hub_radius {self.hub_radius * 1e3:g} mm must be smaller than the {label} root radius "
                    f"{g.R_r * 1e3:.4g} mm"
                )
        for (label, g), other in zip((("pinion", self.pinion), ("gear", self.gear)), (self.gear, self.pinion)):
            if g.R_a <= max(g.R_b, g.R_r):
                raise GearlabInputError(
                    f"{where}: the {label} tip circle ({g.R_a * 2e3:.4g} mm) lies inside its base or root circle"
                )
            if g.half_thickness(g.alpha_tip) <= 0:
                raise GearlabInputError(
                    f"{where}: the {label} teeth are pointed at x = {g.x:g} (no thickness left at the tip circle "
                    f"{g.R_a * 1e3:.4g} mm); use a smaller profile shift or addendum"
                )
            clearance = self.centre_distance - other.R_a - g.R_r
            if clearance < -1e-12 * self.centre_distance:
                raise GearlabInputError(
                    f"{where}: the mating tip reaches the {label} root circle (tip clearance {clearance * 1e3:.3g} mm "
                    f"at a_w = {self.centre_distance * 1e3:.5g} mm); shorten the mating tip (d_a) or the profile shifts"
                )
        if self.roll_start_pinion <= 0 or self.roll_end_gear <= 0:
            raise GearlabInputError(
                f"{where}: the teeth interfere (contact below the base circle); "
                "use more teeth, a larger pressure angle or a positive profile shift"
            )
        if not (1.0 <= self.contact_ratio < 2.0):
            raise GearlabInputError(
                f"{where}: contact ratio {self.contact_ratio:.3f} is outside [1, 2), which the mesh model assumes"
            )

    # --- meshing (eq. 2.7, 2.8, 2.49-2.51) ----------------------------------------------

    @property
    def working_pressure_angle(self) -> float:
        """alpha_w: inv(alpha_w) = inv(alpha_0) + 2 (x1 + x2) tan(alpha_0)/(Z1 + Z2) (ISO 21771);
        alpha_0 itself when x1 + x2 = 0."""
        x_sum = self.x1 + self.x2
        if x_sum == 0:
            return self.pressure_angle
        a0 = self.pressure_angle
        return inverse_involute(involute(a0) + 2 * x_sum * math.tan(a0) / (self.Z1 + self.Z2))

    @property
    def centre_distance(self) -> float:
        """a_w = a cos(alpha_0)/cos(alpha_w), a = R_p1 + R_p2 the reference centre distance."""
        a = self.pinion.R_p + self.gear.R_p
        if self.x1 + self.x2 == 0:
            return a
        return a * math.cos(self.pressure_angle) / math.cos(self.working_pressure_angle)

    @property
    def line_of_action(self) -> float:
        """T1 T2 = a_w sin(alpha_w): the line of action between the base-circle tangent points."""
        return self.centre_distance * math.sin(self.working_pressure_angle)

    @property
    def roll_start_pinion(self) -> float:
        """tan of the pinion's pressure angle where contact starts (gear tip on the line of action):
        the triangle O1 O2 A, with the angle alpha_a2 - alpha_w at O2 and a_w between the centres;
        -1 when A lies at or beyond T1 (interference)."""
        g, a = self.gear, self.centre_distance
        if self.line_of_action - math.sqrt(g.R_a**2 - g.R_b**2) <= 0:
            return -1.0
        alpha_a2 = math.acos(g.R_b / g.R_a)
        r_start = math.sqrt(g.R_a**2 + a**2 - 2 * g.R_a * a * math.cos(alpha_a2 - self.working_pressure_angle))
        if r_start <= self.pinion.R_b:
            return -1.0
        return math.sqrt((r_start / self.pinion.R_b) ** 2 - 1.0)

    @property
    def roll_tip_pinion(self) -> float:
        return math.sqrt((self.pinion.R_a / self.pinion.R_b) ** 2 - 1.0)

    @property
    def roll_tip_gear(self) -> float:
        return math.sqrt((self.gear.R_a / self.gear.R_b) ** 2 - 1.0)

    @property
    def roll_end_gear(self) -> float:
        """tan of the gear's pressure angle where contact ends; must stay on its involute."""
        lowest = 0.0 if self.gear.root_below_base else math.sqrt((self.gear.R_r / self.gear.R_b) ** 2 - 1)
        return self.roll_tip_gear - self.Z1 / self.Z2 * self.theta_t - lowest

    @property
    def theta_t(self) -> float:
        """Pinion rotation during one tooth pair's contact: theta_tot = 2 theta_d + theta_s (eq. 2.71)."""
        return self.roll_tip_pinion - self.roll_start_pinion

    @property
    def theta_d(self) -> float:  # eq. 2.49, written with the corrected cos(alpha_0) inside
        return self.theta_t - 2 * math.pi / self.Z1

    @property
    def theta_s(self) -> float:  # eq. 2.50
        return 2 * math.pi / self.Z1 - self.theta_d

    @property
    def contact_ratio(self) -> float:
        return self.theta_t / (2 * math.pi / self.Z1)

    def alpha1_pinion(self, theta):
        """Eq. 2.7: force angle on the pinion tooth at pinion angle theta after its contact starts."""
        return theta - self.pinion.alpha_2 + self.roll_start_pinion

    def alpha1_gear(self, theta):
        """Eq. 2.8: force angle on the driven gear tooth, as a function of the pinion angle."""
        return self.roll_tip_gear - self.gear.alpha_2 - self.Z1 / self.Z2 * theta

    def seen_from(self, gear: str) -> GearPair:
        """The pair with *gear* ("pinion" or "wheel") as gear 1: the pair itself, or the same mesh
        with the roles of the two gears exchanged (Z1 <-> Z2, each gear keeping its own hub, profile
        shift and material).

        A fault plugin works on gear 1 of the pair it is given (its section, its geometry checks,
        its ladder); on the wheel it is given this view. The mesh is the same, so its path of
        contact, contact ratio and contact duration in wheel angle, theta_t Z1/Z2, follow from
        eq. 2.7, 2.8, 2.49-2.51 with the indices exchanged; no check needs to run again.
        """
        if gear == "pinion":
            return self
        if gear != "wheel":
            raise GearlabInputError(f"gear must be 'pinion' or 'wheel', got {gear!r}")
        view = copy.copy(self)
        for name, value in (
            ("Z1", self.Z2),
            ("Z2", self.Z1),
            ("hub_radius", self.gear.hub_radius),
            ("pinion", self.gear),
            ("gear", self.pinion),
            ("x1", self.x2),
            ("x2", self.x1),
            ("d_a1", self.d_a2),
            ("d_a2", self.d_a1),
            ("h_f1", self.h_f2),
            ("h_f2", self.h_f1),
        ):
            object.__setattr__(view, name, value)
        if self.E2 is not None or self.nu2 is not None:  # two materials: each gear keeps its own
            for name, value in (("E", self.gear.E), ("nu", self.gear.nu), ("E2", self.E), ("nu2", self.nu)):
                object.__setattr__(view, name, value)
        if hasattr(view, "wheel_hub_radius"):  # a pair whose gears sit on different bores
            object.__setattr__(view, "wheel_hub_radius", self.pinion.hub_radius)
        return view

    def describe(self) -> dict:
        p, g = self.pinion, self.gear
        return {
            "name": self.name,
            "Z1": self.Z1,
            "Z2": self.Z2,
            "module_m": self.module,
            "face_width_m": self.face_width,
            "pressure_angle_rad": self.pressure_angle,
            "R_b1_m": p.R_b,
            "R_r1_m": p.R_r,
            "R_b2_m": g.R_b,
            "R_r2_m": g.R_r,
            "x1": self.x1,
            "x2": self.x2,
            "E1_Pa": p.E,
            "E2_Pa": g.E,
            "working_pressure_angle_rad": self.working_pressure_angle,
            "centre_distance_m": self.centre_distance,
            "theta_d_rad": self.theta_d,
            "theta_s_rad": self.theta_s,
            "contact_ratio": self.contact_ratio,
        }
