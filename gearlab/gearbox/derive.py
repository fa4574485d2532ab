"""What gearlab derives from a description: the gear pairs of the potential-energy model.

Each stage becomes a :class:`gearlab.physics.geometry.GearPair` (pinion = gear 1 drives the
wheel = gear 2), so the stiffness engine and every fault plugin work on it unchanged:

    Z1, Z2 = z;  module = m;  pressure_angle = α;  face_width = min(b1, b2) (the contact width)
    addendum = h_a*;  clearance = h_f* - h_a*;  tool_tip_radius = ρ_fP*;  hub_radius = d_bore / 2
    x1, x2 = each gear's profile shift x;  E, nu = the pinion's material;  E2, nu2 = the wheel's
    (given only when it differs, so a one-material stage is the same GearPair as before)
    d_a1, d_a2 = a gear's own tip (its 'tip_diameter', or d + 2 m (h_a* + x) of its own 'addendum');
    h_f1, h_f2 = a gear's own 'dedendum' (None where the gear gives none: the stage's, as before)

The stiffness model takes profile-shifted gears (tip and root circles, tooth thickness, the
working pressure angle α_w and centre distance a_w; gearlab/physics/geometry.py) and a material
per gear (each tooth's energies with its own E, ν; the Hertz term of eq. 2.94 with both). Different
bores are kept: the fillet term (eq. 2.46) of each gear uses its own hub radius.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..errors import GearlabInputError
from ..physics.geometry import GearPair
from .checks import gear_tip


@dataclass(frozen=True)
class StagePair(GearPair):
    """A GearPair whose wheel sits on its own bore: hub_radius is the pinion's, wheel_hub_radius the wheel's.
    *next_stage*: the pair its wheel's shaft drives in a two- or three-stage train (train_pair), which
    the multi-stage models mesh next (plugins/models/two_stage.py)."""

    wheel_hub_radius: float = 0.0
    next_stage: GearPair | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        wheel = dataclasses.replace(self.gear, hub_radius=self.wheel_hub_radius)
        if not 0 < self.wheel_hub_radius < wheel.R_r:
            raise GearlabInputError(
                f"gear pair {self.name!r}: wheel_hub_radius {self.wheel_hub_radius * 1e3:g} mm must be smaller "
                f"than the wheel root radius {wheel.R_r * 1e3:.4g} mm"
            )
        object.__setattr__(self, "gear", wheel)


def pair_name(box, stage) -> str:
    if stage.name:
        return stage.name
    return box.name if len(box.stages) == 1 else f"{box.name}_stage{stage.index}"


def gear_pair(box, stage) -> GearPair:
    """The GearPair of one stage of the description *box* (see the module doc)."""
    p, w = stage.pinion.material, stage.wheel.material
    two_materials = (p.E, p.nu) != (w.E, w.nu)
    values = dict(
        Z1=stage.pinion.z,
        Z2=stage.wheel.z,
        module=stage.module,
        face_width=min(stage.pinion.face_width, stage.wheel.face_width),
        pressure_angle=stage.pressure_angle,
        E=p.E,
        nu=p.nu,
        hub_radius=stage.pinion.bore / 2,
        addendum=stage.addendum,
        clearance=stage.dedendum - stage.addendum,
        tool_tip_radius=stage.tool_tip_radius,
        name=pair_name(box, stage),
        x1=stage.pinion.x,
        x2=stage.wheel.x,
        E2=w.E if two_materials else None,
        nu2=w.nu if two_materials else None,
        d_a1=own_tip(stage, stage.pinion),
        d_a2=own_tip(stage, stage.wheel),
        h_f1=stage.pinion.dedendum,
        h_f2=stage.wheel.dedendum,
    )
    try:
        if stage.wheel.bore == stage.pinion.bore:
            return GearPair(**values)
        return StagePair(**values, wheel_hub_radius=stage.wheel.bore / 2)
    except GearlabInputError as exc:
        raise GearlabInputError(f"{stage.where}: {exc}") from None


def own_tip(stage, gear) -> float | None:
    """The tip diameter a gear gives itself (its 'tip_diameter' or 'addendum'), else None."""
    return None if gear.tip_diameter is None and gear.addendum is None else gear_tip(stage, gear)


def gear_pairs(box) -> tuple[GearPair, ...]:
    """The gear pairs of every stage, input first."""
    return tuple(gear_pair(box, stage) for stage in box.stages)


def train_pair(first: GearPair, second: GearPair, *rest: GearPair) -> StagePair:
    """Stage 1's pair carrying stage 2's, which carries stage 3's when given: what a multi-stage
    model simulates (each pair the same mesh stiffness as before, each wheel on its own bore)."""
    values = {f.name: getattr(first, f.name) for f in dataclasses.fields(GearPair) if f.init}
    after = train_pair(second, *rest) if rest else second
    return StagePair(**values, wheel_hub_radius=first.gear.hub_radius, next_stage=after)


# --- the lumped model ----------------------------------------------------------------------------
#
# The existing formulations: one stage -> ten_dof (and its eight/six-DOF subsets, which pick
# their parameters from it), two stages -> two_stage (the PHM 2009 rig's model), three ->
# three_stage (two_stage with a block on shaft 3: m4, I41). Names are those of thesis Tables 2.3
# and 2.4; each shaft's block (mass m, polar inertia I) as plugins/models/two_stage.py numbers them.

DYNAMICS_NAMES = {
    "motor_inertia": "I11",
    "load_inertia": "I22",
    "coupling_stiffness": "k_c",
    "coupling_damping": "c_c",
    "bearing_stiffness": "k_b",
    "bearing_damping": "c_b",
    "casing_mass": "mf",
    "mounting_stiffness_x": "k_xf",
    "mounting_stiffness_y": "k_yf",
    "mounting_damping_x": "c_xf",
    "mounting_damping_y": "c_yf",
    "mesh_damping_ratio": "zeta",
}
_SHAFT_BLOCKS = {
    1: (("m1", "I12"), ("m2", "I21")),
    2: (("m1", "I12"), ("m2", "I21"), ("m3", "I31")),
    3: (("m1", "I12"), ("m2", "I21"), ("m4", "I41"), ("m3", "I31")),  # the output block stays m3, I31
}
MODELS = {1: "ten_dof", 2: "two_stage", 3: "three_stage"}


def disc(gear, module: float) -> tuple[float, float]:
    """(mass kg, polar inertia kg m^2) of a gear as a solid disc of its reference diameter d = m z
    with its bore: m = ρ π (d² - d_bore²) b / 4, J = m (d² + d_bore²) / 8."""
    d, bore = module * gear.z, gear.bore
    mass = gear.material.density * 3.141592653589793 * (d * d - bore * bore) * gear.face_width / 4
    return mass, mass * (d * d + bore * bore) / 8


def shaft_blocks(box) -> list[tuple[float, float]]:
    """(mass, inertia) of each shaft's block: as described, else the sum of its gears' discs."""
    gears: list[list[tuple[float, float]]] = [[] for _ in box.shafts]
    for k, stage in enumerate(box.stages):
        gears[k].append(disc(stage.pinion, stage.module))
        gears[k + 1].append(disc(stage.wheel, stage.module))
    out = []
    for i, parts in enumerate(gears):
        mass = box.shaft_mass[i] if box.shaft_mass[i] is not None else sum(m for m, _ in parts)
        inertia = box.shaft_inertia[i] if box.shaft_inertia[i] is not None else sum(j for _, j in parts)
        out.append((mass, inertia))
    return out


def lumped_params(box) -> tuple[str, dict[str, float]]:
    """(model name, its parameters) of the lumped model of *box*: ten_dof for one stage, two_stage
    for two, three_stage for three (a description has 1 to 3)."""
    stages = len(box.stages)
    params = {DYNAMICS_NAMES[k]: v for k, v in box.dynamics.items()}
    for (m_name, i_name), (mass, inertia) in zip(_SHAFT_BLOCKS[stages], shaft_blocks(box)):
        params[m_name], params[i_name] = mass, inertia
    return MODELS[stages], params
