"""Lumped-parameter gearbox models (thesis 2.3, 2.4.1, 2.4.2) and their plugin contract.

The full model is the 10-DOF model of Luo et al. (2019b) in the DOF order of eq. 2.96:

    x1, y1, theta11 (motor), theta12 (pinion), x2, y2, theta21 (gear), theta22 (load), xf, yf (casing).

Smaller models drop DOFs (thesis 2.4.2): without the casing the bearings are grounded;
without motor and load the couplings go and the torques act on the gears. The mesh is an
inclined spring along the line of action: K = Kc + k(t) P^T P, C = Cc + mu k(t) P^T P with P
of eq. 2.104 and mu from zeta (eq. 2.105-2.109).

The input-shaft DOF (the motor, or the pinion when there is no motor) runs at a fixed
speed (thesis 2.3: "the shaft speed and motor torque are fixed"); all rotations are
measured relative to the nominal rigid-body rotation, so the fixed DOF is removed from the
unknowns and the load torque is balanced through the mesh.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..errors import GearlabInputError, did_you_mean
from ..gearbox.simulation import is_reference, preset_of_reference
from ..physics.geometry import GearPair
from ..physics.presets import gear_pair
from ..settings import plugin_description, resolve_params, setting, subset

DOF_ORDER = ("x1", "y1", "theta11", "theta12", "x2", "y2", "theta21", "theta22", "xf", "yf")
CHANNEL_DOFS = {
    "pinion_x": "x1",
    "pinion_y": "y1",
    "gear_x": "x2",
    "gear_y": "y2",
    "casing_x": "xf",
    "casing_y": "yf",
    "output_x": "x3",
    "output_y": "y3",  # the output block of a two- or three-stage model (plugins/models/two_stage.py)
    "shaft3_x": "x4",
    "shaft3_y": "y4",  # a three-stage model's block on shaft 3, its second intermediate shaft
}


def drive_dofs(dofs) -> tuple[str, str]:
    """(input_dof, load_dof) of a one-stage lumped model with *dofs*: the motor's and the load's
    rotations where it has them (theta11, theta22), else the pinion's and the gear's (theta12,
    theta21; the speed then is the pinion's and the load torque acts on the gear, thesis 2.4.2)."""
    return ("theta11" if "theta11" in dofs else "theta12"), ("theta22" if "theta22" in dofs else "theta21")


@dataclass(frozen=True)
class LumpedParams:
    """Every parameter a lumped gearbox model can take; a model declares the ones it uses."""

    m1: float = setting(
        float, 1.0, low=1e-6, high=1e4, unit="kg", doc="mass of the pinion block (gear, shaft, bearings)"
    )
    m2: float = setting(float, 1.0, low=1e-6, high=1e4, unit="kg", doc="mass of the gear block")
    mf: float = setting(float, 10.0, low=1e-6, high=1e5, unit="kg", doc="mass of the gearbox casing")
    I11: float = setting(float, 1e-2, low=1e-9, high=1e3, unit="kg*m^2", doc="mass moment of inertia of the motor")
    I12: float = setting(
        float, 1e-4, low=1e-9, high=1e3, unit="kg*m^2", doc="mass moment of inertia of the pinion block"
    )
    I21: float = setting(float, 1e-3, low=1e-9, high=1e3, unit="kg*m^2", doc="mass moment of inertia of the gear block")
    I22: float = setting(float, 1e-2, low=1e-9, high=1e3, unit="kg*m^2", doc="mass moment of inertia of the load")
    m3: float = setting(
        float, 1.0, low=1e-6, high=1e4, unit="kg", doc="mass of the output block of a two- or three-stage model"
    )
    I31: float = setting(
        float, 1e-3, low=1e-9, high=1e3, unit="kg*m^2", doc="mass moment of inertia of the output gear block"
    )
    m4: float = setting(
        float, 1.0, low=1e-6, high=1e4, unit="kg", doc="mass of the second intermediate block of a three-stage model"
    )
    I41: float = setting(
        float, 1e-3, low=1e-9, high=1e3, unit="kg*m^2", doc="mass moment of inertia of the second intermediate block"
    )
    k_b: float = setting(float, 1e8, low=1e3, high=1e12, unit="N/m", doc="bearing stiffness, x and y of both shafts")
    c_b: float = setting(float, 1e3, low=0.0, high=1e8, unit="N*s/m", doc="bearing damping, x and y of both shafts")
    k_c: float = setting(
        float, 1e3, low=0.0, high=1e9, unit="N*m/rad", doc="coupling stiffness motor-pinion and gear-load"
    )
    c_c: float = setting(float, 10.0, low=0.0, high=1e6, unit="N*m*s/rad", doc="coupling damping")
    k_xf: float = setting(float, 2e8, low=1e3, high=1e12, unit="N/m", doc="casing mounting stiffness, x")
    k_yf: float = setting(float, 2e8, low=1e3, high=1e12, unit="N/m", doc="casing mounting stiffness, y")
    c_xf: float = setting(float, 2e3, low=0.0, high=1e8, unit="N*s/m", doc="casing mounting damping, x")
    c_yf: float = setting(float, 2e3, low=0.0, high=1e8, unit="N*s/m", doc="casing mounting damping, y")
    zeta: float = setting(float, 0.07, low=0.0, high=1.0, doc="mesh damping ratio (eq. 2.107)")


@dataclass(frozen=True)
class Mesh:
    """A further gear mesh of a multi-stage model, beside the first pair's (Assembly.P).

    Its stiffness k(t) comes from the same potential-energy engine on its own gear pair; its
    pinion turns at *ratio* times the input-shaft speed; its damping follows eq. 2.107 with
    the masses of the two blocks it joins (*masses*: their parameter names)."""

    pair: GearPair
    P: np.ndarray  # projection on its line of action over the assembly's DOFs
    ratio: float
    masses: tuple[str, str]


@dataclass(frozen=True)
class Assembly:
    """Constant parts of the equations of motion of one model on one gear pair."""

    dofs: tuple[str, ...]
    M: np.ndarray
    Kc: np.ndarray
    Cc: np.ndarray
    P: np.ndarray  # projection on the line of action, eq. 2.104
    input_dof: str  # the fixed-speed, tacho DOF
    load_dof: str  # where the load torque acts
    meshes: tuple[Mesh, ...] = ()  # further meshes (multi-stage models); () for the thesis's models
    # rotation of each DOF per radian of the input shaft in the rigid-body mode; None: the one-pair rule
    rigid: Mapping[str, float] | None = None

    def index(self, dof: str) -> int:
        return self.dofs.index(dof)


class DynamicModel:
    """A lumped gearbox model plugin: which DOFs, which parameters, which presets."""

    name: ClassVar[str]
    doc: ClassVar[str] = ""
    dofs: ClassVar[tuple[str, ...]]
    input_dof: ClassVar[str]
    load_dof: ClassVar[str]
    # preset name -> {"pair": gear-pair preset or GearPair, "params": {...}, "speeds_hz": (...), "loads_nm": (...)};
    # a preset "gearbox:..." is a gearbox description's (gearlab.gearbox.simulation), of *stages* stages
    presets: ClassVar[Mapping[str, Mapping]]
    stages: ClassVar[int] = 1

    @property
    def params(self) -> type:
        """The settings dataclass of the parameters it uses (param_names)."""
        return subset(LumpedParams, tuple(self.param_names()))

    def param_names(self) -> tuple[str, ...]:
        names = ["m1", "m2", "I12", "I21", "k_b", "c_b", "zeta"]
        if "theta11" in self.dofs:
            names += ["I11", "I22", "k_c", "c_c"]
        if "xf" in self.dofs:
            names += ["mf", "k_xf", "k_yf", "c_xf", "c_yf"]
        return tuple(names)

    @property
    def channels(self) -> tuple[str, ...]:
        return tuple(c for c, dof in CHANNEL_DOFS.items() if dof in self.dofs)

    def preset(self, name: str, where: str = "") -> Mapping:
        """The preset *name*; an unknown one is an input error naming *where* it was asked for."""
        if is_reference(name):
            return preset_of_reference(name, tuple(self.param_names()), self.stages, self.name)
        try:
            return self.presets[name]
        except KeyError:
            context = f"model '{self.name}'"
            if where and context not in where:
                context = f"{where}: {context}"
            raise GearlabInputError(
                f"{context}: unknown preset '{name}'{did_you_mean(name, list(self.presets))}; "
                f"known: {', '.join(self.presets)}"
            ) from None

    def resolve(self, preset: str, overrides: Mapping | None = None, where: str = "") -> tuple[GearPair, dict]:
        """The gear pair and the full parameter set of a preset, with optional overrides (units allowed)."""
        p = self.preset(preset, where)
        values = resolve_params(self.params, {**p["params"], **(overrides or {})}, where or f"model '{self.name}'")
        return (p["pair"] if isinstance(p["pair"], GearPair) else gear_pair(p["pair"])), values

    def assemble(self, pair: GearPair, values: Mapping[str, float]) -> Assembly:
        return lumped_assembly(self.dofs, pair, values, self.input_dof, self.load_dof)

    def describe(self) -> dict:
        return plugin_description(
            self,
            dofs=list(self.dofs),
            channels=list(self.channels),
            presets={
                k: {
                    "pair": str(getattr(v["pair"], "name", v["pair"])),
                    "speeds_hz": list(v["speeds_hz"]),
                    "loads_nm": list(v["loads_nm"]),
                }
                for k, v in self.presets.items()
            },
        )


def add_spring(K: np.ndarray, C: np.ndarray, i: int, j: int | None, k: float, c: float) -> None:
    """A spring k and damper c between DOFs i and j (eq. 2.100, 2.101), or from i to ground (j None)."""
    K[i, i] += k
    C[i, i] += c
    if j is not None:
        K[j, j] += k
        C[j, j] += c
        K[i, j] -= k
        K[j, i] -= k
        C[i, j] -= c
        C[j, i] -= c


def lumped_assembly(dofs, pair: GearPair, v: Mapping[str, float], input_dof: str, load_dof: str) -> Assembly:
    """M, Kc, Cc (eq. 2.97, 2.100, 2.101) and P (eq. 2.104) of the 10-DOF model restricted to *dofs*.

    A DOF left out is held at zero: springs to it become springs to ground, so leaving out
    the casing grounds the bearings. Leaving out motor and load also needs k_c = 0, which
    the model's parameter list ensures (no coupling parameters without motor and load).
    """
    n = len(DOF_ORDER)
    idx = {d: i for i, d in enumerate(DOF_ORDER)}
    M = np.diag(
        [
            v.get("m1", 0),
            v.get("m1", 0),
            v.get("I11", 0),
            v.get("I12", 0),
            v.get("m2", 0),
            v.get("m2", 0),
            v.get("I21", 0),
            v.get("I22", 0),
            v.get("mf", 0),
            v.get("mf", 0),
        ]
    )
    K = np.zeros((n, n))
    C = np.zeros((n, n))

    def spring(a: str, b: str | None, k: float, c: float) -> None:
        add_spring(K, C, idx[a], None if b is None else idx[b], k, c)

    for a, casing in (("x1", "xf"), ("y1", "yf"), ("x2", "xf"), ("y2", "yf")):
        spring(a, casing, v["k_b"], v["c_b"])
    spring("xf", None, v.get("k_xf", 0.0), v.get("c_xf", 0.0))
    spring("yf", None, v.get("k_yf", 0.0), v.get("c_yf", 0.0))
    spring("theta11", "theta12", v.get("k_c", 0.0), v.get("c_c", 0.0))
    spring("theta21", "theta22", v.get("k_c", 0.0), v.get("c_c", 0.0))
    a0 = pair.working_pressure_angle  # the line of action: alpha_0, or alpha_w for shifted gears
    P = np.array(
        [math.sin(a0), math.cos(a0), 0.0, pair.pinion.R_b, -math.sin(a0), -math.cos(a0), -pair.gear.R_b, 0.0, 0.0, 0.0]
    )  # eq. 2.104
    keep = [idx[d] for d in dofs]
    sub = np.ix_(keep, keep)
    return Assembly(tuple(dofs), M[sub], K[sub], C[sub], P[keep], input_dof, load_dof)


# How the mesh damping c(t) follows the mesh stiffness: proportional, c(t) = mu k(t) (eq. 2.108, Tian 2004,
# the thesis's choice), or constant, c = c_m (eq. 2.107; what most authors stop at, thesis 2.3).
MESH_DAMPING_MODELS = ("proportional", "constant")


def mesh_damping_ratio(values: Mapping[str, float], k_mean: float, masses: tuple[str, str] = ("m1", "m2")) -> float:
    """mu = c_m / k_m with c_m = 2 zeta sqrt(k_m m1 m2 / (m1 + m2)) (eq. 2.107, 2.109); *masses*
    names the two blocks the mesh joins (a second stage joins m2 and m3)."""
    m1, m2 = values[masses[0]], values[masses[1]]
    c_m = 2 * values["zeta"] * math.sqrt(k_mean * m1 * m2 / (m1 + m2))
    return c_m / k_mean
