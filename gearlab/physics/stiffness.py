"""Potential-energy mesh stiffness engine (thesis 2.1 and the general formulation 2.88-2.94).

The beam terms are integrated along the tooth centreline x on the generalised section
(h_x, A_x, I_x, L(x)) rather than in the angle alpha: for a contact point at x = d with
force angle alpha_1 the bending moment per unit force is cos(alpha_1)(d - x) - sin(alpha_1) h
(eq. 2.3, 2.5, 2.6), so

    1/k_b = (a^2 K_0(d) - 2 a cos(alpha_1) K_1(d) + cos^2(alpha_1) K_2(d)) / E,
    a = cos(alpha_1) d - sin(alpha_1) h,   K_m(d) = int_0^d x^m / I_x dx,

and 1/k_a, 1/k_s need only int_0^d 1/A_x dx. These cumulative integrals are built once
per tooth section, so a whole meshing arc costs one pass over the section plus an
interpolation per angle. E and nu are those of the tooth's own gear (two materials: the Hertz
term combines both, hertz_compliance). In the healthy case this is exactly eq. 2.21-2.25 / 2.34-2.38
after the change of variable x(alpha); for faulted sections it is eq. 2.88-2.93.
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import GearlabInputError
from ..memo import SharedArrays
from .geometry import Gear, GearPair
from .sections import DEFAULT_NODES, ToothSection, healthy_section

# Table 2.1 (Sainsot et al. 2004): rows L*, M*, P*, Q*; columns A_i ... F_i.
FILLET_COEFFICIENTS = {
    "L": (-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045),
    "M": (60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086),
    "P": (-50.952e-5, 185.50e-3, 0.0538e-4, 53.3000e-4, 0.2895, 0.9236),
    "Q": (-6.204e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904),
}


@dataclass(frozen=True)
class StiffnessOptions:
    """Term switches of thesis 2.2.6.2, needed to compare with literature that omits them."""

    fillet: bool = True
    root_region: bool = True
    nodes: int = DEFAULT_NODES


class SectionIntegrals:
    """Cumulative integrals K_0, K_1, K_2 (of x^m / I_x) and K_A (of 1 / A_x) along a section."""

    def __init__(self, section: ToothSection, start: float = 0.0):
        x = section.x
        with np.errstate(divide="ignore"):
            inv_I = np.where(section.I > 0, 1.0 / np.maximum(section.I, 1e-300), np.inf)
            inv_A = np.where(section.A > 0, 1.0 / np.maximum(section.A, 1e-300), np.inf)
        outside = x < start - 1e-15  # the root region, when it is switched off
        inv_I[outside] = 0.0
        inv_A[outside] = 0.0
        self.x = x
        with np.errstate(invalid="ignore"):
            self.f = np.stack([inv_I, x * inv_I, x * x * inv_I, inv_A])  # integrands, (4, n)
        self.f[np.isnan(self.f)] = np.inf  # 0 * inf at x = 0 under a zero section
        with np.errstate(invalid="ignore"):
            cells = 0.5 * (self.f[:, 1:] + self.f[:, :-1]) * np.diff(x)
        cells[~np.isfinite(cells)] = np.inf  # a zero section anywhere makes the rest infinite
        self.F = np.concatenate([np.zeros((4, 1)), np.cumsum(cells, axis=1)], axis=1)

    def at(self, d: np.ndarray) -> np.ndarray:
        """Integrals from the root to each contact position d: array (4, len(d))."""
        x = self.x
        j = np.clip(np.searchsorted(x, d, side="right") - 1, 0, len(x) - 2)
        t = d - x[j]
        with np.errstate(invalid="ignore"):
            slope = (self.f[:, j + 1] - self.f[:, j]) / (x[j + 1] - x[j])
            f_d = self.f[:, j] + slope * t
            out = self.F[:, j] + 0.5 * t * (self.f[:, j] + f_d)
        out[~np.isfinite(out)] = np.inf
        return out


def contact_geometry(gear: Gear, alpha1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Contact distance d from the root (eq. 2.14 / 2.30) and contact height h (eq. 2.13)."""
    a2 = gear.alpha_2
    d = gear.R_b * ((alpha1 + a2) * np.sin(alpha1) + np.cos(alpha1)) - gear.x_root
    h = gear.R_b * ((alpha1 + a2) * np.cos(alpha1) - np.sin(alpha1))
    return d, h


def beam_compliances(
    gear: Gear, integrals: SectionIntegrals, alpha1: np.ndarray, E: float, nu: float
) -> dict[str, np.ndarray]:
    """1/k_a, 1/k_b, 1/k_s of one tooth (eq. 2.88-2.93)."""
    d, h = contact_geometry(gear, alpha1)
    K0, K1, K2, KA = integrals.at(d)
    c, s = np.cos(alpha1), np.sin(alpha1)
    a = c * d - s * h
    with np.errstate(invalid="ignore"):
        bending = (a * a * K0 - 2 * a * c * K1 + c * c * K2) / E
        axial = s * s * KA / E
        shear = 2.4 * (1 + nu) * c * c * KA / E
    broken = ~np.isfinite(K0) | ~np.isfinite(KA)
    for term in (bending, axial, shear):
        term[broken] = np.inf
    return {"axial": axial, "bending": bending, "shear": shear}


def fillet_compliance(gear: Gear, alpha1: np.ndarray, E: float, face_width: float) -> np.ndarray:
    """1/k_f of eq. 2.42-2.46; faults never change it (thesis 2.1.1.3, last paragraph)."""
    d, h = contact_geometry(gear, alpha1)
    u_over_S = (d - h * np.tan(alpha1)) / gear.S_f  # eq. 2.43, 2.44
    hi, tf = gear.R_r / gear.hub_radius, gear.theta_f
    L, M, P, Q = (
        A / tf**2 + B * hi**2 + C * hi / tf + D / tf + Ei * hi + F for A, B, C, D, Ei, F in FILLET_COEFFICIENTS.values()
    )  # eq. 2.46
    return np.cos(alpha1) ** 2 / (E * face_width) * (L * u_over_S**2 + M * u_over_S + P * (1 + Q * np.tan(alpha1) ** 2))


def hertz_compliance(
    E: float, nu: float, contact_width: np.ndarray, E2: float | None = None, nu2: float | None = None
) -> np.ndarray:
    """1/k_h of eq. 2.94 with the effective contact width L at the contact point. Two materials:
    k_h = pi L / (2 [(1 - nu1^2)/E1 + (1 - nu2^2)/E2]) (two cylinders in line contact), which is
    eq. 2.94's pi E L / (4 (1 - nu^2)) when (E2, nu2) = (E1, nu1)."""
    width = np.maximum(contact_width, 1e-300)
    with np.errstate(divide="ignore"):
        if E2 is None or (E2, nu2) == (E, nu):
            compliance = 4 * (1 - nu**2) / (np.pi * E * width)
        else:
            compliance = 2 * ((1 - nu**2) / E + (1 - nu2**2) / E2) / (np.pi * width)
        return np.where(contact_width > 0, compliance, np.inf)


def tooth_pair_compliances(
    pair: GearPair,
    phi: np.ndarray,
    pinion: ToothSection,
    gear: ToothSection,
    options: StiffnessOptions = StiffnessOptions(),
    pinion_integrals: SectionIntegrals | None = None,
    gear_integrals: SectionIntegrals | None = None,
) -> dict[str, np.ndarray]:
    """Every compliance term of one tooth pair (eq. 2.47, 2.48) at pinion angles phi in [0, theta_t].

    Keys: hertz, and axial/bending/shear/fillet with suffix 1 (pinion) or 2 (gear); 'total'.
    """
    phi = np.asarray(phi, dtype=float)
    out: dict[str, np.ndarray] = {}
    widths = []
    for suffix, g, section, integrals, alpha1 in (
        ("1", pair.pinion, pinion, pinion_integrals, pair.alpha1_pinion(phi)),
        ("2", pair.gear, gear, gear_integrals, pair.alpha1_gear(phi)),
    ):
        if integrals is None:
            integrals = SectionIntegrals(section, start=0.0 if options.root_region else section.d_1)
        for name, value in beam_compliances(g, integrals, alpha1, g.E, g.nu).items():  # each tooth its material
            out[name + suffix] = value
        out["fillet" + suffix] = (
            fillet_compliance(g, alpha1, g.E, section.face_width) if options.fillet else np.zeros_like(phi)
        )
        d, _ = contact_geometry(g, alpha1)
        widths.append(np.interp(d, section.x, section.L))
    p, g = pair.pinion, pair.gear
    out["hertz"] = hertz_compliance(p.E, p.nu, np.minimum(*widths), g.E, g.nu)
    out["total"] = sum(out.values())
    return out


GEARS = ("pinion", "wheel")  # gear 1 (the driver) and gear 2 of a pair
BOTH = "both"  # a TVMS table of a pair with faults on both gears: the hunting-tooth period
# Input revolutions a TVMS with faults on both gears of a pair may take to repeat (its table, and a
# simulation of its whole period, grow with it); the dataset builder's placement.MAX_PERIOD likewise.
MAX_HUNTING_TURNS = 1000


def table_slots(pair: GearPair, gear: str) -> int:
    """Mesh periods in a TVMS table of *gear*: Z1 (pinion), Z2 (wheel) or lcm(Z1, Z2) (BOTH, the
    hunting-tooth period: mesh n engages pinion tooth n mod Z1 and wheel tooth n mod Z2)."""
    return pair.Z1 if gear == "pinion" else pair.Z2 if gear == "wheel" else math.lcm(pair.Z1, pair.Z2)


def table_gear(faults: Sequence) -> str:
    """The gear a TVMS table with *faults* (of one pair) spans: the faulted gear, the pinion when none
    is, BOTH when both are faulted."""
    gears = {f.gear for f in faults}
    return BOTH if len(gears) > 1 else gears.pop() if gears else "pinion"


def gear_label(stage: int, gear: str) -> str:
    """Short name of a gear of a train: "pinion"/"wheel" of stage 1, "s2-pinion", ... of later stages."""
    return gear if stage == 1 else f"s{stage}-{gear}"


@dataclass(frozen=True)
class PlacedFault:
    """A fault plugin with resolved parameters (SI) on tooth *tooth* (1-based) of one gear: the
    *gear* ("pinion", gear 1, or "wheel", gear 2) of the train's *stage* (1 = the input stage)."""

    fault: object  # gearlab.physics.faults.Fault
    tooth: int
    params: dict
    gear: str = "pinion"
    stage: int = 1

    @property
    def label(self) -> str:
        if (self.stage, self.gear) == (1, "pinion"):
            return f"{self.fault.name}@{self.tooth}"
        return f"{self.fault.name}@{gear_label(self.stage, self.gear)}:{self.tooth}"


@dataclass(frozen=True)
class MeshStiffness:
    """TVMS k(theta) over one revolution of *gear* (the faulted gear; the pinion when healthy), theta =
    2 pi j / n its angle; *gear* BOTH (faults on both gears): over the hunting-tooth period, theta
    the pinion angle over lcm(Z1, Z2)/Z1 turns scaled to 2 pi."""

    theta: np.ndarray
    k: np.ndarray
    pair: GearPair
    faults: tuple[PlacedFault, ...] = ()
    gear: str = "pinion"

    @property
    def mean(self) -> float:
        return float(self.k.mean())

    @property
    def turns(self) -> float:
        """Revolutions of the table per pinion revolution: 1, Z1/Z2 for the wheel, Z1/lcm(Z1, Z2) for
        faults on both gears (the table spans the hunting-tooth period)."""
        return 1.0 if self.gear == "pinion" else self.pair.Z1 / table_slots(self.pair, self.gear)

    def csv_text(self) -> str:
        """The table as CSV, theta_rad,k_N_per_m to 10 significant digits: `gearlab stiffness
        --csv` and a stiffness run's cases/*.csv (read back by kinds.stiffness.read_csv)."""
        buf = io.StringIO()
        buf.write("theta_rad,k_N_per_m\n")
        np.savetxt(buf, np.column_stack([self.theta, self.k]), delimiter=",", fmt="%.10g")
        return buf.getvalue()


# The healthy TVMS depends on the pair, the options and the grid alone: shared by every model of
# one pair (in this process). A gap search makes a new simulator for each parameter set it tries,
# and computing its pair's healthy TVMS again was 12 ms of each (an eighth of a drive-inertias fit).
_HEALTHY = SharedArrays(64)


class MeshStiffnessModel:
    """Builds TVMS for one gear pair; the healthy sections and integrals are made once."""

    def __init__(self, pair: GearPair, options: StiffnessOptions = StiffnessOptions()):
        self.pair = pair
        self.options = options
        self.pinion_section = healthy_section(pair.pinion, pair.face_width, options.nodes)
        self.gear_section = healthy_section(pair.gear, pair.face_width, options.nodes)
        self._gear_integrals = self._integrals(self.gear_section)
        self._pinion_integrals = self._integrals(self.pinion_section)

    def _integrals(self, section: ToothSection) -> SectionIntegrals:
        return SectionIntegrals(section, start=0.0 if self.options.root_region else section.d_1)

    def faulted_section(self, faults: Sequence[PlacedFault], gear: str = "pinion") -> ToothSection:
        """The section of *gear* with *faults* applied in order (several faults on one tooth compose).

        A plugin edits gear 1 of the pair it is given, so on the wheel it gets the pair seen from
        the wheel (GearPair.seen_from): its checks, its ladder and its geometry are the wheel's.
        """
        section = self.pinion_section if gear == "pinion" else self.gear_section
        view = self.pair.seen_from(gear)
        for placed in faults:
            section = placed.fault.apply(section, placed.params, view)
        return section

    def tooth_pair_stiffness(self, phi: np.ndarray, faults: Sequence[PlacedFault] = ()) -> np.ndarray:
        """k of one tooth pair (eq. 2.47, 2.48) at pinion angles *phi* since its contact began, with
        *faults* on its pinion tooth and/or its wheel tooth (each changes its own gear's section)."""
        on_pinion = [f for f in faults if f.gear == "pinion"]
        on_wheel = [f for f in faults if f.gear != "pinion"]
        pinion, gear = self.pinion_section, self.gear_section
        pinion_integrals, gear_integrals = self._pinion_integrals, self._gear_integrals
        if on_pinion:
            pinion = self.faulted_section(on_pinion)
            pinion_integrals = self._integrals(pinion)
        if on_wheel:
            gear = self.faulted_section(on_wheel, "wheel")
            gear_integrals = self._integrals(gear)
        total = tooth_pair_compliances(self.pair, phi, pinion, gear, self.options, pinion_integrals, gear_integrals)[
            "total"
        ]
        with np.errstate(divide="ignore"):
            return np.where(np.isfinite(total), 1.0 / total, 0.0)

    def mesh_stiffness(self, faults: Sequence[PlacedFault] = (), points: int = 4096) -> MeshStiffness:
        """Superpose all tooth pairs over one revolution of the faulted gear (eq. 2.51-2.54).

        Pinion faults (and no fault): one pinion revolution, Z1 mesh periods. Pinion tooth n is in
        mesh for (n-1) 2 pi/Z1 <= theta < (n-1) 2 pi/Z1 + theta_t; taking the local angle modulo
        2 pi wraps the last tooth's second double-contact zone onto the start of the revolution
        (eq. 2.53, 2.54). Wheel faults: one wheel revolution, Z2 mesh periods; the wheel turns
        theta_2 = (Z1/Z2) theta_1 (R_b1 theta_1 = R_b2 theta_2 along the line of action), so wheel
        tooth m is in mesh for (m-1) 2 pi/Z2 <= theta_2 < (m-1) 2 pi/Z2 + (Z1/Z2) theta_t, where its
        pair's pinion angle since contact began is (Z2/Z1)(theta_2 - (m-1) 2 pi/Z2). Faults on both
        gears: the hunting-tooth period, L = lcm(Z1, Z2) mesh periods (L/Z1 pinion turns); mesh n
        (0-based) engages pinion tooth n mod Z1 + 1 and wheel tooth n mod Z2 + 1, and its pair has
        both teeth's faulted sections. The healthy TVMS is computed once per grid; a fault only
        replaces its own tooth pairs' contributions.
        """
        gear = table_gear(faults)
        for placed in faults:
            if placed.gear not in GEARS:
                raise GearlabInputError(
                    f"fault {placed.label}: gear must be one of {', '.join(GEARS)}, got {placed.gear!r}"
                )
            Z = self.pair.Z1 if placed.gear == "pinion" else self.pair.Z2
            if not 1 <= placed.tooth <= Z:
                raise GearlabInputError(f"fault {placed.label}: tooth must lie in 1..{Z}, got {placed.tooth}")
        slots = table_slots(self.pair, gear)
        if slots // self.pair.Z1 > MAX_HUNTING_TURNS:
            raise GearlabInputError(
                f"faults {', '.join(f.label for f in faults)}: on both gears of {self.pair.name} the TVMS repeats only "
                f"after {slots} meshes = {slots // self.pair.Z1} pinion turns; at most {MAX_HUNTING_TURNS}"
            )
        by_slot: dict[int, list[PlacedFault]] = {}
        for placed in faults:  # the table's mesh periods (1-based) that engage the faulted tooth
            Z = self.pair.Z1 if placed.gear == "pinion" else self.pair.Z2
            for slot in range(placed.tooth, slots + 1, Z):
                by_slot.setdefault(slot, []).append(placed)
        theta, healthy = self._healthy(points, gear)
        k = healthy.copy()
        for slot, slot_faults in by_slot.items():
            phi, in_mesh = self._arc(points, [slot], gear)
            k[in_mesh[0]] += self.tooth_pair_stiffness(phi, slot_faults) - self.tooth_pair_stiffness(phi)
        return MeshStiffness(theta=theta, k=k, pair=self.pair, faults=tuple(faults), gear=gear)

    def _arc(self, points: int, teeth: Sequence[int], gear: str = "pinion") -> tuple[np.ndarray, np.ndarray]:
        """Pinion angles of the pairs of *teeth* (of *gear*) since their contact began, where they are in
        mesh, and the (teeth, points) in-mesh mask, on a grid of *points* over one revolution of *gear*.

        The local angle of tooth n at grid point j is 2 pi ((j Z - (n-1) points) mod (points Z)) / (points Z1),
        Z the teeth of *gear* (the wheel's angle times Z2/Z1 is the pinion's): integer arithmetic, so
        every tooth sees bit-identical angles at corresponding points and a tooth's arc starts on the
        same side of a grid point for every tooth.
        """
        Z1 = self.pair.Z1
        Z = table_slots(self.pair, gear)
        j = np.arange(points, dtype=np.int64)[None, :]
        n = np.asarray(teeth, dtype=np.int64)[:, None]
        local = 2 * np.pi * np.mod(j * Z - (n - 1) * points, points * Z) / (points * Z1)
        in_mesh = local < self.pair.theta_t
        return local[in_mesh], in_mesh

    def healthy(self, points: int, gear: str = "pinion") -> np.ndarray:
        """The healthy TVMS on the grid of a *gear* table (table_slots) of *points* points."""
        return self._healthy(points, gear)[1]

    def _healthy(self, points: int, gear: str = "pinion") -> tuple[np.ndarray, np.ndarray]:
        def make() -> tuple[np.ndarray, np.ndarray]:
            theta = 2 * np.pi * np.arange(points) / points
            phi, in_mesh = self._arc(points, range(1, table_slots(self.pair, gear) + 1), gear)
            per_tooth = np.zeros(in_mesh.shape)
            per_tooth[in_mesh] = self.tooth_pair_stiffness(phi)  # all healthy teeth in one pass
            return theta, per_tooth.sum(axis=0)

        return _HEALTHY.get_or_make((self.pair, self.options, points, gear), make)


def mesh_stiffness(
    pair: GearPair,
    faults: Sequence[PlacedFault] = (),
    points: int = 4096,
    options: StiffnessOptions = StiffnessOptions(),
) -> MeshStiffness:
    return MeshStiffnessModel(pair, options).mesh_stiffness(faults, points)
