"""What drives one simulation: the excitation (shaft angle, TVMS, load torque, extra forces)
that excitation-level effects change before the Newmark integration (gearlab.dynamics.newmark)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from ..physics.geometry import GearPair
from ..physics.stiffness import MeshStiffness, MeshStiffnessModel, table_slots

# An extra generalised force, evaluated once every excitation effect has acted:
# f(exc) -> (vector over exc.dofs, series over exc.t), or a list of such pairs.
Force = Callable[["Excitation"], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Excitation:
    """What drives one simulation, sampled on the integration steps t_i = i / fs.

    The equations of motion (eq. 2.95) with the input DOF at its prescribed angle read

        M u'' + (Cc + c(t) P^T P) u' + (Kc + k(t) P^T P) u = F0 T_l(t)/T_l + sum_j b_j g_j(t),

    with k(t) = k(θ(t)) read from the TVMS over one revolution (with the faults) at the
    input-shaft angle θ(t) (over one wheel revolution, at the wheel's angle (Z1/Z2) θ(t), when a
    fault sits on the wheel), c(t) = c0 + mu k(t) (eq. 2.107-2.109), the load torque series
    T_l(t) and extra forces (vector b_j over the free DOFs, series g_j). An excitation effect
    returns a changed copy: a new angle (``with_angle``), a new TVMS table (``with_tvms``),
    a new load series, or one more force (``add_force``). Forces are evaluated last, on the
    final excitation, so their order relative to other effects does not matter.
    """

    fs: float
    speed_hz: float  # mean input-shaft speed
    load_nm: float  # mean load torque T_l
    t: np.ndarray  # s
    angle: np.ndarray  # continuous input-shaft (= pinion) angle θ(t), rad
    tvms: MeshStiffness  # k over one revolution of its gear (pinion, or a faulted wheel), faults included
    load: np.ndarray  # load torque T_l(t), N*m
    dofs: tuple[str, ...]  # free DOFs (the input DOF is prescribed)
    M: np.ndarray  # mass matrix of the free DOFs
    P: np.ndarray  # projection on the line of action of the free DOFs (eq. 2.104)
    mu: float  # stiffness-proportional mesh damping, c = c0 + mu k (eq. 2.108)
    c0: float  # constant mesh damping, N*s/m
    load_dof: str  # where the load torque acts (the load inertia, or the gear without one)
    stiffness: MeshStiffnessModel = field(repr=False)  # per-tooth-pair stiffness, for effects that need it
    forces: tuple[Force, ...] = ()
    index: np.ndarray | None = field(default=None, repr=False)  # table index per step while θ is nominal
    rigid: Mapping[str, float] | None = None  # rigid-body rotation per input radian of a multi-stage model

    @property
    def pair(self) -> GearPair:
        return self.tvms.pair

    @property
    def faults(self):
        return self.tvms.faults

    # --- changes (each returns a new excitation) ---
    def with_angle(self, angle: np.ndarray) -> Excitation:
        return dataclasses.replace(self, angle=np.asarray(angle, dtype=float), index=None)

    def with_tvms(self, k: np.ndarray) -> Excitation:
        table = MeshStiffness(
            theta=self.tvms.theta,
            k=np.asarray(k, dtype=float),
            pair=self.tvms.pair,
            faults=self.tvms.faults,
            gear=self.tvms.gear,
        )
        return dataclasses.replace(self, tvms=table)

    def with_load(self, load: np.ndarray) -> Excitation:
        return dataclasses.replace(self, load=np.asarray(load, dtype=float))

    def add_force(self, force: Force) -> Excitation:
        return dataclasses.replace(self, forces=self.forces + (force,))

    # --- what effects read ---
    def stiffness_series(self) -> np.ndarray:
        """k(t) = k(θ(t)): exact table entries while θ is nominal on the table's grid, else interpolated."""
        return self.at_angle(self.tvms.k)

    def damping_series(self, k: np.ndarray | None = None) -> np.ndarray:
        """Mesh damping c(t) = c0 + mu k(t) (eq. 2.107-2.109), N*s/m."""
        return self.c0 + self.mu * (self.stiffness_series() if k is None else k)

    def speed_series(self) -> np.ndarray:
        """Input-shaft angular speed dθ/dt, rad/s."""
        return np.gradient(self.angle, 1.0 / self.fs)

    def vector(self, entries: Mapping[str, float]) -> np.ndarray:
        """A generalised-force vector over the free DOFs; entries on absent or prescribed DOFs are dropped
        (a torque on the fixed-speed input shaft is taken up by the drive)."""
        v = np.zeros(len(self.dofs))
        for dof, value in entries.items():
            if dof in self.dofs:
                v[self.dofs.index(dof)] += value
        return v

    def rigid_rotation(self) -> np.ndarray:
        """Rotation of each free DOF per radian of the input shaft in the rigid-body mode: 1 on the input
        side, R_b1/R_b2 = Z1/Z2 on the output side (so P r = 0, eq. 2.104)."""
        if self.rigid is not None:
            return self.vector(self.rigid)
        ratio = self.pair.pinion.R_b / self.pair.gear.R_b
        return self.vector({"theta11": 1.0, "theta12": 1.0, "theta21": ratio, "theta22": ratio})

    def tooth_pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per tooth n = 1..Z of the table's gear (the pinion, Z = Z1, or a faulted wheel, Z = Z2; with
        faults on both gears per mesh n of the hunting period, Z = lcm(Z1, Z2)) on the TVMS grid: its
        pair's local mesh angle phi (pinion rad since its contact began), whether it is in mesh, and its
        pair stiffness k_n (faults included), each (Z, points).

        Pinion tooth n meshes for (n-1) 2 pi/Z1 <= theta < (n-1) 2 pi/Z1 + theta_t (eq. 2.51-2.54), wheel
        tooth n for (n-1) 2 pi/Z2 <= theta_2 < (n-1) 2 pi/Z2 + theta_t Z1/Z2; the local angle is formed in
        integer arithmetic so every tooth sees the same angles at corresponding grid points and the
        per-tooth picture shifts exactly with the tooth.
        """
        pair, points = self.pair, len(self.tvms.theta)
        Z1 = pair.Z1
        Z = table_slots(pair, self.tvms.gear)
        j = np.arange(points, dtype=np.int64)[None, :]
        n = np.arange(Z, dtype=np.int64)[:, None]
        phi = 2 * np.pi * np.mod(j * Z - n * points, points * Z) / (points * Z1)
        in_mesh = phi < pair.theta_t
        k = np.zeros(phi.shape)
        k[in_mesh] = self.stiffness.tooth_pair_stiffness(phi[in_mesh])  # all teeth healthy, one pass
        faulted = sorted({slot for f in self.faults for slot in range(f.tooth, Z + 1, _teeth(pair, f.gear))})
        for slot in faulted:  # a table's row: a tooth of its gear, or a mesh of the hunting period (BOTH)
            on = [f for f in self.faults if (slot - f.tooth) % _teeth(pair, f.gear) == 0]
            row = in_mesh[slot - 1]
            k[slot - 1, row] = self.stiffness.tooth_pair_stiffness(phi[slot - 1, row], on)
        return phi, in_mesh, k

    def at_angle(self, table: np.ndarray) -> np.ndarray:
        """Read a per-revolution table on the TVMS grid at θ(t): by index while θ is the nominal angle on
        a grid of whole steps per revolution (exact, so tooth shifts stay exact), else interpolated. The
        table spans a revolution of the TVMS's gear, which turns tvms.turns times per input turn."""
        if self.index is not None:
            return table[self.index]
        theta = np.append(self.tvms.theta, 2 * np.pi)
        return np.interp(np.mod(self.tvms.turns * self.angle, 2 * np.pi), theta, np.append(table, table[0]))

    def force_terms(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(vector, series) of every extra force, the load-torque variation included."""
        terms = []
        deviation = self.load - self.load_nm
        if np.any(deviation != 0.0):
            terms.append((self.vector({self.load_dof: -1.0}), deviation))  # T_l opposes rotation (eq. 2.111)
        for force in self.forces:
            out = force(self)
            for vector, series in out if isinstance(out, list) else [out]:
                terms.append((np.asarray(vector, dtype=float), np.asarray(series, dtype=float)))
        return terms


def _teeth(pair, gear: str) -> int:
    return pair.Z1 if gear == "pinion" else pair.Z2
