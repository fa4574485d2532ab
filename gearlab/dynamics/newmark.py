"""Newmark time integration of a lumped gearbox with a rank-one mesh update (numba).

The equations of motion M u'' + C(t) u' + K(t) u = F (eq. 2.95) have
K(t) = Kc + k(t) P^T P and C(t) = Cc + mu k(t) P^T P (eq. 2.105-2.109). With Newmark's
constants a0..a5 the effective stiffness of every step is

    K_hat(t) = (Kc + a0 M + a1 Cc) + k(t) (1 + a1 mu) P^T P = K_hat_c + s(t) P^T P,

a constant matrix plus a rank-one term. K_hat_c is inverted once, before the loop; every
step then solves exactly by the Sherman-Morrison formula with two small matrix-vector
products: no factorisation or inverse inside the time loop.

Parameters follow the GN22 form of Zienkiewicz (2013) that the thesis names: beta1 = 0.5,
beta2 = 2.25, i.e. Newmark's gamma = beta1 and beta = beta2 / 2 (docs/physics.md).
"""

from __future__ import annotations

import contextvars
import math
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import numba
import numpy as np

from ..errors import GearlabInputError
from ..gearbox.description import gear_name
from ..gearbox.simulation import shaft_names
from ..physics import stiffness
from ..physics.stiffness import BOTH, MeshStiffnessModel, PlacedFault, table_gear, table_slots
from .excitation import Excitation
from .model import CHANNEL_DOFS, MESH_DAMPING_MODELS, DynamicModel, mesh_damping_ratio

BETA1, BETA2 = 0.5, 2.25
DEFAULT_FS = 200e3
TVMS_POINTS = 8192
_CHECK_EVERY = 2048
CHUNK = 512 * _CHECK_EVERY  # steps Simulator.tail integrates at once (~8 MB a series); whole checks' spans
_LIMIT = 1e3  # m or rad: no gearbox DOF gets anywhere near this
# Series that depend only on (fs, steps, speed) or (steps, table period), read-only: a gap search makes
# a simulator per parameter set it tries and runs hundreds at one speed. At most _MEMO_BYTES, least
# recently used out first.
_MEMO: dict = {}
_MEMO_BYTES = 1 << 27
# Set while Simulator.tail makes a long run's series after its first chunk: made, not kept (a 143T wheel's
# 1144 turns are 9 chunks of ~40 MB of series that no run reads again before the memo drops them).
_UNKEPT = contextvars.ContextVar("unkept", default=False)
_STIFFNESS: dict = {}  # MeshStiffnessModel per gear pair (its healthy sections: 4 ms a simulator)


def _stiffness_model(pair) -> MeshStiffnessModel:
    """The TVMS builder of *pair*, made once per process (it keeps no state a run changes)."""
    if pair not in _STIFFNESS:
        if len(_STIFFNESS) >= 64:
            _STIFFNESS.pop(next(iter(_STIFFNESS)))
        _STIFFNESS[pair] = MeshStiffnessModel(pair)
    return _STIFFNESS[pair]


class SimulationError(GearlabInputError):
    """The integration diverged (NaN or overflow): the parameters or the step are wrong."""


@numba.njit(cache=True, fastmath={"reassoc", "contract", "arcp", "nsz"})  # NaN checks stay valid
def _advance(u, v, a, u_new, c, dt, gamma, out, out_idx, step):
    """The Newmark update to the solved displacement *u_new* (GN22, beta1 = gamma), the step's
    output row, and every 2048 steps the divergence check: True when the response diverged."""
    n = u.shape[0]
    for i in range(n):
        a_new = c[0] * (u_new[i] - u[i]) - c[2] * v[i] - c[3] * a[i]
        v[i] += dt * ((1.0 - gamma) * a[i] + gamma * a_new)
        u[i] = u_new[i]
        a[i] = a_new
    for j in range(out_idx.shape[0]):
        out[step + 1, j] = a[out_idx[j]]
    if step % 2048 == 0:
        for i in range(n):
            if not (abs(u[i]) < 1e3):  # also catches NaN
                return True
    return False


@numba.njit(cache=True, fastmath={"reassoc", "contract", "arcp", "nsz"})  # NaN checks stay valid
def _integrate(GMC, gF, GB, g, w, p, pw, k, mu, c, dt, gamma, u, v, a, out_idx, out):
    """Advance len(k) steps from (u, v, a); out[0] is the start, out[i] the state after step i.

    GMC = [G M | G Cc] with G = K_hat_c^-1; c = (a0, a1, a2, a3, a4, a5) Newmark constants; the load
    F(t) = F0 + B g(t) with gF = G F0, GB = G B (n, m), g (steps, m): m = 0 (GB (n, 0), g (steps, 0))
    without the time-varying part, the empty loop over it adding nothing (the same floats).
    Returns the step where the response diverged, or -1.
    """
    n = u.shape[0]
    m = GB.shape[1]
    mz = np.empty(2 * n)  # [M-part | C-part] of the effective load
    y = np.empty(n)
    for j in range(out_idx.shape[0]):
        out[0, j] = a[out_idx[j]]
    for step in range(k.shape[0]):
        kk = k[step]
        pz = 0.0
        for i in range(n):
            mz[i] = c[0] * u[i] + c[2] * v[i] + c[3] * a[i]
            mz[n + i] = c[1] * u[i] + c[4] * v[i] + c[5] * a[i]
            pz += p[i] * mz[n + i]
        damping = mu * kk * pz
        py = 0.0
        for i in range(n):
            acc = gF[i] + damping * w[i]
            for j in range(m):
                acc += GB[i, j] * g[step, j]
            for j in range(2 * n):
                acc += GMC[i, j] * mz[j]
            y[i] = acc
            py += p[i] * acc
        s = kk * (1.0 + c[1] * mu)
        corr = s * py / (1.0 + s * pw)
        for i in range(n):
            y[i] -= corr * w[i]  # u at the new step
        if _advance(u, v, a, y, c, dt, gamma, out, out_idx, step):
            return step
    return -1


@numba.njit(cache=True, fastmath={"reassoc", "contract", "arcp", "nsz"})
def _integrate_meshes(GMC, gF, GB, g, W, Pm, PW, k, mu, c, dt, gamma, u, v, a, out_idx, out):
    """:func:`_integrate` for m meshes (a multi-stage gearbox): K_hat(t) = K_hat_c + sum_i s_i(t) P_i^T P_i,
    a rank-m update solved each step by the Woodbury identity with an m x m system,

        u = y - W z,   (I + S PW) z = S (Pm y),   S = diag(k_i (1 + a1 mu_i)),

    W = G Pm^T (n, m), PW = Pm G Pm^T (m, m). With m = 1 this is the Sherman-Morrison step of
    :func:`_integrate` exactly. k: (steps, m) mesh stiffnesses; mu: (m,) proportional damping ratios.
    """
    n = u.shape[0]
    m = Pm.shape[0]
    f = GB.shape[1]
    mz = np.empty(2 * n)
    y = np.empty(n)
    d = np.empty(m)
    A = np.empty((m, m))
    z = np.empty(m)
    for j in range(out_idx.shape[0]):
        out[0, j] = a[out_idx[j]]
    for step in range(k.shape[0]):
        for i in range(n):
            mz[i] = c[0] * u[i] + c[2] * v[i] + c[3] * a[i]
            mz[n + i] = c[1] * u[i] + c[4] * v[i] + c[5] * a[i]
        for q in range(m):  # mesh damping mu_i k_i(t) P_i^T P_i acting on the Newmark velocity terms
            pz = 0.0
            for i in range(n):
                pz += Pm[q, i] * mz[n + i]
            d[q] = mu[q] * k[step, q] * pz
        for i in range(n):
            acc = gF[i]
            for q in range(m):
                acc += d[q] * W[i, q]
            for j in range(f):
                acc += GB[i, j] * g[step, j]
            for j in range(2 * n):
                acc += GMC[i, j] * mz[j]
            y[i] = acc
        for q in range(m):  # the m x m system (I + S PW) z = S Pm y
            sq = k[step, q] * (1.0 + c[1] * mu[q])
            py = 0.0
            for i in range(n):
                py += Pm[q, i] * y[i]
            z[q] = sq * py
            for r in range(m):
                A[q, r] = sq * PW[q, r] + (1.0 if q == r else 0.0)
        for col in range(m):  # Gaussian elimination; I + S PW is well conditioned (S >= 0, PW SPD)
            for row in range(col + 1, m):
                factor = A[row, col] / A[col, col]
                for r in range(col, m):
                    A[row, r] -= factor * A[col, r]
                z[row] -= factor * z[col]
        for q in range(m - 1, -1, -1):
            acc = z[q]
            for r in range(q + 1, m):
                acc -= A[q, r] * z[r]
            z[q] = acc / A[q, q]
        for i in range(n):
            for q in range(m):
                y[i] -= W[i, q] * z[q]  # u at the new step
        if _advance(u, v, a, y, c, dt, gamma, out, out_idx, step):
            return step
    return -1


@dataclass
class Simulation:
    model: str
    preset: str
    speed_hz: float
    load_nm: float
    fs: float
    t: np.ndarray
    tacho: np.ndarray  # input-shaft angle, wrapped into [-pi, pi)
    tvms: np.ndarray  # mesh stiffness seen at each step, N/m
    channels: dict[str, np.ndarray]  # accelerations, m/s^2
    wall_s: float
    faults: tuple[PlacedFault, ...] = ()
    state: tuple = field(default=(), repr=False)  # final (u, v, a) for continuation
    angle: np.ndarray | None = field(default=None, repr=False)  # continuous input-shaft angle when effects moved it


@dataclass
class Tail:
    """The last samples of one channel of a run (Simulator.tail) and where the run ended."""

    x: np.ndarray  # the channel at steps steps + 1 - len(x) .. steps (Simulator.tail's since on)
    steps: int  # steps integrated from the run's start
    state: tuple  # (u, v, a) after the last step, to continue from
    call: tuple  # (faults, speed, load, channel, start): what a continuation repeats


class Simulator:
    """One model on one preset at one sampling rate: everything that does not depend on the
    faults or the operating point is prepared once (sections, healthy TVMS, K_hat_c^-1)."""

    def __init__(
        self,
        model: DynamicModel,
        preset: str,
        fs: float = DEFAULT_FS,
        overrides: Mapping | None = None,
        beta1: float = BETA1,
        beta2: float = BETA2,
        mesh_damping: str = "proportional",
        warn_step: bool = True,
    ):
        """*warn_step*: warn when *fs* gives fewer than 10 steps per period of the highest natural
        frequency (fs_floor); a caller that picks its own rate from fs_floor passes False."""
        where = f"model '{model.name}', preset '{preset}'"
        if not (math.isfinite(fs) and fs > 0):
            raise GearlabInputError(f"{where}: sampling rate fs must be a positive number of Hz, got {fs!r}")
        if not (beta2 >= beta1 >= 0.5):
            raise GearlabInputError(f"{where}: Newmark needs beta2 >= beta1 >= 0.5 for stability, got {beta1}, {beta2}")
        if mesh_damping not in MESH_DAMPING_MODELS:
            raise GearlabInputError(
                f"{where}: mesh damping model must be one of {', '.join(MESH_DAMPING_MODELS)}, got {mesh_damping!r}"
            )
        self.model, self.preset, self.fs = model, preset, float(fs)
        self.pair, self.values = model.resolve(preset, overrides, where)
        self.stiffness = _stiffness_model(self.pair)
        self.k_mean = self.stiffness.mesh_stiffness(points=TVMS_POINTS).mean
        self.mu = mesh_damping_ratio(self.values, self.k_mean)
        asm = model.assemble(self.pair, self.values)
        free = [i for i, d in enumerate(asm.dofs) if d != asm.input_dof]
        self.dofs = tuple(asm.dofs[i] for i in free)
        sub = np.ix_(free, free)
        self.M, self.Kc, self.Cc, self.P = asm.M[sub], asm.Kc[sub], asm.Cc[sub], asm.P[free]
        self.load_index = self.dofs.index(asm.load_dof)
        self.load_dof = asm.load_dof
        self.rigid = asm.rigid
        # Further meshes of a multi-stage model (Assembly.meshes): each its own TVMS, mean and damping ratio.
        self.meshes = tuple(asm.meshes)
        self.mesh_models = tuple(_stiffness_model(m.pair) for m in self.meshes)
        self.mesh_means = tuple(sm.mesh_stiffness(points=TVMS_POINTS).mean for sm in self.mesh_models)
        self.mesh_mu = [mesh_damping_ratio(self.values, km, m.masses) for km, m in zip(self.mesh_means, self.meshes)]
        self.mesh_P = tuple(m.P[free] for m in self.meshes)
        # Mesh damping c(t) = c0 + mu k(t). The thesis (eq. 2.108, Tian 2004): c0 = 0, mu = c_m / k_m.
        # The constant model most authors use (thesis 2.3): c = c_m (eq. 2.107), a constant rank-one
        # term that joins Cc, so the time loop is the same.
        self.mesh_damping, self.c0 = mesh_damping, 0.0
        if mesh_damping == "constant":
            self.c0, self.mu = self.mu * self.k_mean, 0.0
            self.Cc = self.Cc + self.c0 * np.outer(self.P, self.P)
            for i, (P, km) in enumerate(zip(self.mesh_P, self.mesh_means)):
                self.Cc = self.Cc + self.mesh_mu[i] * km * np.outer(P, P)
                self.mesh_mu[i] = 0.0
        self.gamma, self.beta = beta1, beta2 / 2
        dt = 1.0 / self.fs
        b, g = self.beta, self.gamma
        self.c = np.array(
            [1 / (b * dt * dt), g / (b * dt), 1 / (b * dt), 1 / (2 * b) - 1, g / b - 1, dt / 2 * (g / b - 2)]
        )
        G = np.linalg.inv(self.Kc + self.c[0] * self.M + self.c[1] * self.Cc)  # once, outside the loop
        self.G, self.GMC = G, np.ascontiguousarray(np.hstack([G @ self.M, G @ self.Cc]))
        self.w = G @ self.P
        self.pw = float(self.P @ self.w)
        if self.meshes:  # the rank-m update of _integrate_meshes: all meshes, the first pair's first
            self.Pm = np.ascontiguousarray(np.vstack([self.P, *self.mesh_P]))
            self.Wm = np.ascontiguousarray(G @ self.Pm.T)
            self.PW = np.ascontiguousarray(self.Pm @ self.Wm)
        self._check_step(where, warn_step)
        self._warm_up()

    def _warm_up(self) -> None:
        """Load the compiled integrator now (one step), so run() times only the simulation: the one this model's
        runs use (_newmark), not both (a fresh install compiles each: 1.79 -> 1.35 s of CPU for a multi-stage box)."""
        n = len(self.dofs)

        def tail():  # constants, step, a fresh zero state, one output channel
            zeros = np.zeros(n)
            return (
                self.c,
                1.0 / self.fs,
                self.gamma,
                zeros,
                zeros.copy(),
                zeros.copy(),
                np.zeros(1, dtype=np.int64),
                np.empty((2, 1)),
            )

        unloaded = (self.GMC, np.zeros(n), np.zeros((n, 0)), np.zeros((1, 0)))  # no load, no forces
        if self.meshes:
            m = len(self.Pm)
            _integrate_meshes(*unloaded, self.Wm, self.Pm, self.PW, np.ones((1, m)), np.zeros(m), *tail())
        else:
            _integrate(*unloaded, self.w, self.P, self.pw, np.ones(1), self.mu, *tail())

    def natural_frequencies(self, k: float | None = None, fixed_input: bool = True) -> np.ndarray:
        """Undamped natural frequencies (Hz) at mesh stiffness k (default: the mean)."""
        k = self.k_mean if k is None else k
        if fixed_input:
            M, K = self.M, self.Kc + k * np.outer(self.P, self.P)
            K = K + sum((km * np.outer(P, P) for km, P in zip(self.mesh_means, self.mesh_P)), np.zeros_like(K))
        else:
            asm = self.model.assemble(self.pair, self.values)
            M, K = asm.M, asm.Kc + k * np.outer(asm.P, asm.P)
            K = K + sum((km * np.outer(m.P, m.P) for km, m in zip(self.mesh_means, asm.meshes)), np.zeros_like(K))
        from scipy.linalg import eigh

        lam = eigh(K, M, eigvals_only=True)
        return np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi)

    def _check_step(self, where: str, warn: bool) -> None:
        top = float(self.natural_frequencies(k=self.stiffness.mesh_stiffness(points=TVMS_POINTS).k.max()).max())
        self.fs_floor = 10 * top  # the lowest rate with 10 steps per period of the stiffest mode
        if warn and self.fs < self.fs_floor:
            warnings.warn(
                f"{where}: fs = {self.fs:g} Hz gives fewer than 10 steps per period of the highest natural "
                f"frequency ({top:.0f} Hz); results will be inaccurate; expected fs >= {math.ceil(self.fs_floor)} Hz "
                # the model's name and preset hash alone leave a user of a scenario with no key to change
                f'(a scenario\'s [source] fs = "{math.ceil(self.fs_floor / 1e3)} kHz"; simulate: --fs)',
                stacklevel=3,
            )

    def run(
        self,
        faults: Sequence[PlacedFault] = (),
        speed_hz: float | None = None,
        load_nm: float | None = None,
        duration: float = 0.4,
        channels: Sequence[str] | None = None,
        effects: Sequence = (),
        after: Simulation | None = None,
        start: int = 0,
    ) -> Simulation:
        """Integrate from the static equilibrium for *duration* seconds.

        *effects*: excitation-level effects as (Effect, resolved params) pairs (gearlab.effects.EffectChain.at),
        applied in order to the nominal excitation (fixed speed, constant load) before the loop.
        *after*: a shorter run of this very call (the same faults, operating point and channels): its
        steps are kept and the loop continues from its final state, the same floats as a run from
        the start (every series is a function of the step alone). Only without effects on one
        mesh; else, or when *after* does not fit, the whole run is integrated.
        *start*: the step the run begins at (from the static equilibrium there), t = start / fs: every
        series (mesh stiffnesses, tacho, effects) is read at its own absolute step, so once its start-up
        transient has died away such a run is the steady response of a run from t = 0 at those steps.

        The stages: check the operating point, the mesh stiffness k(t) along the nominal shaft
        angle, the excitation effects, the static equilibrium, the Newmark loop, the result.
        """
        where = f"model '{self.model.name}', preset '{self.preset}'"
        speed, load, channels = self._operating_point(speed_hz, load_nm, duration, channels, where)
        staged = self.faults_by_stage(faults, where)
        self.check_hunting(staged, where)
        began = time.perf_counter()
        steps = int(round(duration * self.fs))
        t, shaft, phase, tacho = self._time_base(steps, speed, start)
        per_rev = self.fs / speed
        tvms, index, k = self._nominal_stiffness(staged[0], phase, per_rev, steps, speed, start)
        k_mean = tvms.mean
        forces, angle = [], None
        if effects:
            k, k_mean, forces, angle = self._excite(effects, tvms, index, t, speed, load)
            if angle is not None:
                phase = np.mod(angle, 2 * np.pi)  # the tacho follows the moved shaft
                tacho = np.where(phase >= np.pi, phase - 2 * np.pi, phase)
        F, (u, v, a) = self._static_start(staged, load, k_mean)
        out_idx = np.array([self.dofs.index(CHANNEL_DOFS[ch]) for ch in channels], dtype=np.int64)
        out = np.empty((steps + 1, len(out_idx)))
        done = 0 if start else self._continued(after, faults, speed, load, channels, steps, effects)
        if done:
            out[: done + 1] = np.column_stack([after.channels[ch] for ch in channels])
            u, v, a = (x.copy() for x in after.state)
        failed = self._newmark(
            k[done:], forces, angle, t[done:], speed, per_rev, F, (u, v, a), out_idx, out[done:], staged[1:], start
        )
        if failed >= 0:
            raise self._diverged(where, faults, speed, load, failed + done + start)
        wall = time.perf_counter() - began
        return Simulation(
            model=self.model.name,
            preset=self.preset,
            speed_hz=speed,
            load_nm=load,
            fs=self.fs,
            t=t.copy(),
            tacho=np.array(tacho),  # the memo's are read-only
            tvms=k,
            channels={ch: out[:, j] for j, ch in enumerate(channels)},
            wall_s=wall,
            faults=tuple(faults),
            state=(u, v, a),
            angle=angle,
        )

    def tail(
        self,
        faults,
        speed_hz: float,
        load_nm: float,
        channel: str,
        duration: float,
        since: int,
        after: Tail | None = None,
        start: int = 0,
    ) -> Tail:
        """The samples of *channel* from step *since* on of ``run(faults, speed_hz, load_nm, duration,
        [channel], start=start)`` without effects (steps counted from *start*), float for float, integrated
        CHUNK steps at a time: no series of the whole run (time base, stiffness, response: ~73 bytes a
        step, 0.64 GB for 1144 turns of a 143T wheel's cycle) is held, only the samples kept. *after*: a
        shorter tail of this very call, continued from its state (every series is a function of the step
        alone: the same floats as a run from the start, on several meshes too)."""
        where = f"model '{self.model.name}', preset '{self.preset}'"
        speed, load, _ = self._operating_point(speed_hz, load_nm, duration, [channel], where)
        staged = self.faults_by_stage(faults, where)
        self.check_hunting(staged, where)
        steps, per_rev = int(round(duration * self.fs)), self.fs / speed
        call = (tuple(faults), speed, load, channel, start)
        out_idx = np.array([self.dofs.index(CHANNEL_DOFS[channel])], dtype=np.int64)
        lo = min(max(since, 0), steps)  # the step of kept[0]
        kept = np.empty(steps + 1 - lo)
        state = None
        have = 0 if after is None else after.steps + 1 - lo  # samples of the window *after* holds
        if after is not None and after.call == call and after.steps < steps and have <= len(after.x):
            state = tuple(x.copy() for x in after.state)
            kept[: max(have, 0)] = after.x[len(after.x) - max(have, 0) :]
        first, F = after.steps if state is not None else 0, None
        while F is None or first < steps:  # (a run of no step: its start)
            n, later = min(CHUNK, steps - first), _UNKEPT.set(F is not None)
            try:
                t, _, phase, _ = self._time_base(n, speed, start + first)
                tvms, _, k = self._nominal_stiffness(staged[0], phase, per_rev, n, speed, start + first)
                if F is None:
                    F, static = self._static_start(staged, load, tvms.mean)
                    state = static if state is None else state
                out = np.empty((n + 1, 1))
                at = start + first
                failed = self._newmark(k, [], None, t, speed, per_rev, F, state, out_idx, out, staged[1:], at)
            finally:
                _UNKEPT.reset(later)
            if failed >= 0:
                raise self._diverged(where, faults, speed, load, failed + start + first)
            if first + n >= lo:  # out[i] is step first + i
                i = max(lo - first, 0)
                kept[first + i - lo : first + n + 1 - lo] = out[i:, 0]
            first += n
        return Tail(kept, steps, state, call)

    def _diverged(self, where: str, faults, speed: float, load: float, step: int) -> SimulationError:
        labels = ", ".join(f.label for f in faults) or "healthy"
        return SimulationError(
            f"{where} ({labels}, {speed:g} Hz, {load:g} N*m, fs {self.fs:g} Hz): the response diverged "
            f"(NaN or overflow) near t = {step / self.fs:.4g} s; check the model parameters and the time step"
        )

    @staticmethod
    def _memoised(key: tuple, make, length: int | None = None):
        """make() (a tuple of arrays, made read-only), kept in _MEMO: the time base and table indices
        of a diagnosis' hundreds of runs at one speed are made once. With *length*, *key* names series
        that are elementwise functions of the step, make(length) their first *length* entries: the
        longest made is kept and a shorter one is its first entries (views: the same floats). A steady
        simulation's runs of 8, 32, 128 and 512 revolutions (builder.steady_response) keep one series,
        not four that together overflow _MEMO_BYTES and are made again at every simulator's run. Under
        _UNKEPT (a long tail's later chunks) made and not kept."""
        if _UNKEPT.get():
            made = make() if length is None else make(length)
            for x in made:
                x.setflags(write=False)
            return made
        entry = _MEMO.pop(key, None)
        if entry is None or (length is not None and len(entry[0][0]) < length):
            made = make() if length is None else make(length)
            for x in made:
                x.setflags(write=False)
            entry = (made, {})  # the arrays; their prefixes by length, each made once
        _MEMO[key] = entry  # the most recently used last
        while sum(x.nbytes for kept, _ in _MEMO.values() for x in kept) > _MEMO_BYTES:
            _MEMO.pop(next(iter(_MEMO)))
        if length is None:
            return entry[0]
        views = entry[1]
        if length not in views:
            views[length] = tuple(x[:length] for x in entry[0])
        return views[length]

    def _time_base(self, steps: int, speed: float, start: int = 0) -> tuple[np.ndarray, ...]:
        """t, the nominal input-shaft angle (fixed speed, unwrapped), its phase in [0, 2 pi) and the
        tacho (the phase in [-pi, pi)) of *steps* steps at *speed* from step *start*: read-only, memoised
        (the same floats as the steps of a run from 0: the integer step over fs)."""
        (t,) = self._memoised(("t", self.fs, start), lambda n: ((np.arange(n) + start) / self.fs,), steps + 1)

        def make(n):  # n == len(t)
            shaft = 2 * np.pi * speed * t
            phase = np.mod(shaft, 2 * np.pi)
            return shaft, phase, np.where(phase >= np.pi, phase - 2 * np.pi, phase)

        return (t, *self._memoised(("angle", self.fs, speed, start), make, steps + 1))

    def _index(self, n: int, period: int, start: int = 0) -> np.ndarray:
        """The table index of *n* steps from step *start* on a table of *period* entries, one entry a
        step: read-only, memoised."""
        first = start % period
        return self._memoised(("index", period, first), lambda size: ((np.arange(size) + first) % period,), n)[0]

    @staticmethod
    def _repeat(k: np.ndarray, index: np.ndarray, period: int) -> np.ndarray:
        """k[index] for index = _index(n, period, start): the same floats, the table repeated (no gather)."""
        if len(k) != period:
            return k[index]
        return np.resize(k, len(index)) if index[0] == 0 else np.resize(np.roll(k, -int(index[0])), len(index))

    def _continued(self, after, faults, speed: float, load: float, channels, steps: int, effects) -> int:
        """The steps of *after* that a run of *steps* keeps (:meth:`run`): 0 unless it is a shorter run
        of the same call on a one-mesh model without effects."""
        if after is None or effects or self.meshes or after.angle is not None:
            return 0
        same = (after.speed_hz, after.load_nm, after.fs, tuple(after.faults)) == (speed, load, self.fs, tuple(faults))
        done = len(after.t) - 1
        if not same or list(after.channels) != list(channels) or not 0 < done < steps or len(after.state) != 3:
            return 0
        return done

    def _operating_point(
        self, speed_hz: float | None, load_nm: float | None, duration: float, channels: Sequence[str] | None, where: str
    ) -> tuple[float, float, list[str]]:
        """Speed and load (the preset's unless given) and the channels, checked: one line each."""
        preset = self.model.preset(self.preset)
        speed = float(preset["speed_hz"] if speed_hz is None else speed_hz)
        load = float(preset["load_nm"] if load_nm is None else load_nm)
        if not (math.isfinite(speed) and speed > 0):
            raise GearlabInputError(f"{where}: speed must be a positive number of Hz, got {speed!r}")
        if not (math.isfinite(load) and load >= 0):
            raise GearlabInputError(f"{where}: load must be a torque >= 0 N*m, got {load!r}")
        mesh_hz = speed * self.pair.Z1
        if self.fs < 10 * mesh_hz:
            raise GearlabInputError(
                f"{where}: fs = {self.fs:g} Hz is too low for the mesh harmonics at {mesh_hz:g} Hz; "
                f"expected at least {10 * mesh_hz:g} Hz (5 mesh harmonics below Nyquist)"
            )
        if not (math.isfinite(duration) and duration > 0):
            raise GearlabInputError(f"{where}: duration must be a positive number of seconds, got {duration!r}")
        channels = list(channels) if channels is not None else list(self.model.channels)
        for ch in channels:
            if ch not in self.model.channels:
                raise GearlabInputError(
                    f"{where}: model has no channel '{ch}'; its channels: {', '.join(self.model.channels)}"
                )
        return speed, load, channels

    @property
    def stages(self) -> int:
        """Gear meshes of the model: 1, or 1 + its further meshes (a multi-stage train)."""
        return 1 + len(self.meshes)

    def faults_by_stage(self, faults: Sequence[PlacedFault], where: str = "") -> tuple[tuple[PlacedFault, ...], ...]:
        """*faults* split by the stage they sit on (stage 1 first); a stage the model lacks is an input error."""
        out: list[list[PlacedFault]] = [[] for _ in range(self.stages)]
        for f in faults:
            if isinstance(f.stage, bool) or not isinstance(f.stage, int) or not 1 <= f.stage <= self.stages:
                raise GearlabInputError(
                    f"{where or self.model.name}: fault {f.label} sits on stage {f.stage!r}; "
                    f"the model has stage(s) 1..{self.stages}"
                )
            out[f.stage - 1].append(f)
        return tuple(tuple(on) for on in out)

    def gear_turns(self, stage: int, gear: str) -> float:
        """Revolutions of a gear per input-shaft revolution: stage 1's pinion 1, its wheel Z1/Z2,
        a further stage's pinion its mesh's ratio (its shaft's) and its wheel that times Z1/Z2 of its pair."""
        pair, turns = (self.pair, 1.0) if stage == 1 else (self.meshes[stage - 2].pair, self.meshes[stage - 2].ratio)
        return turns if gear == "pinion" else turns * pair.Z1 / pair.Z2

    def table_turns(self, stage: int, faults: Sequence[PlacedFault]) -> float:
        """Revolutions per input revolution of the TVMS table of *stage* with *faults*: its faulted
        gear's (gear_turns), or with faults on both its gears the hunting-tooth period's (its pinion's
        times Z1/lcm(Z1, Z2))."""
        gear = table_gear(faults)
        if gear != BOTH:
            return self.gear_turns(stage, gear)
        pair = self.pair if stage == 1 else self.meshes[stage - 2].pair
        return self.gear_turns(stage, "pinion") * pair.Z1 / table_slots(pair, gear)

    def check_hunting(self, staged: Sequence[Sequence[PlacedFault]], where: str) -> None:
        """Refuse faults on both gears of a stage whose TVMS table (the hunting-tooth period, read at
        its own angle: table_turns) spans more than MAX_HUNTING_TURNS turns of that stage's pinion
        (one line: the faults, on the gears as the description names them, the stage, the period).
        The train's own period does not matter."""
        for stage, on in enumerate(staged, start=1):
            pair = self.pair if stage == 1 else self.meshes[stage - 2].pair
            if table_gear(on) == BOTH and (turns := table_slots(pair, BOTH) // pair.Z1) > stiffness.MAX_HUNTING_TURNS:
                shafts = shaft_names(self.preset, self.stages)
                named = (f"'{f.fault.name}@{gear_name(stage, f.gear, shafts)}' (tooth {f.tooth})" for f in on)
                faults = " and ".join(named)
                pinion = gear_name(stage, "pinion", shafts)
                its = "input revolutions" if stage == 1 else f"turns of the stage {stage} pinion, the {pinion}"
                raise GearlabInputError(
                    f"{where}: faults {faults} on both gears of stage {stage} repeat only "
                    f"after {turns} {its} (the hunting-tooth period); at most "
                    f"{stiffness.MAX_HUNTING_TURNS}: put the damage on one gear"
                )

    def period(self, faults: Sequence[PlacedFault] = ()) -> int:
        """Input revolutions after which the steady response repeats: 1 healthy or with pinion faults on
        stage 1 (every further mesh repeats within one input turn in the built-in models), else the
        least number of input turns that turns every faulted gear a whole number of times."""
        turns = [Fraction(self.gear_turns(f.stage, f.gear)).limit_denominator(10_000) for f in faults]
        return math.lcm(1, *(q.denominator for q in turns))

    @staticmethod
    def _grid(pair, faults: Sequence[PlacedFault]) -> int:
        """Points of a TVMS table over one revolution of the faulted gear on a pitch-aligned grid of
        TVMS_POINTS per pinion revolution's worth of mesh periods (the same points per mesh period)."""
        return table_slots(pair, table_gear(faults)) * math.ceil(TVMS_POINTS / pair.Z1)

    def mesh_table(self, i: int, faults: Sequence[PlacedFault], points: int):
        """The TVMS of further mesh *i* (faults included) over one revolution of its faulted gear."""
        return self.mesh_models[i].mesh_stiffness(faults, points=points)

    def _nominal_stiffness(
        self,
        faults: Sequence[PlacedFault],
        phase: np.ndarray,
        per_rev: float,
        steps: int,
        speed: float = 0.0,
        start: int = 0,
    ):
        """The TVMS over one revolution of the faulted gear (the pinion when none is) and k(t) at the
        nominal angle, whose input-shaft phase is *phase*, from step *start*: (table, table index per
        step or None, k(t))."""
        if table_gear(faults) != "pinion":
            turns = self.table_turns(1, faults)
            shaft = self._time_base(steps, speed, start)[1]  # the nominal input angle, unwrapped
            return self._table_series(self.stiffness, faults, turns, shaft, per_rev, start)
        if abs(per_rev - round(per_rev)) < 1e-9 * per_rev:
            # A whole number of steps per revolution: the TVMS on exactly those angles, no
            # interpolation, so a fault on tooth n sees exactly the shifted TVMS of tooth 1.
            tvms = self.stiffness.mesh_stiffness(faults, points=round(per_rev))
            index = self._index(steps + 1, round(per_rev), start)
            return tvms, index, self._repeat(tvms.k, index, round(per_rev))
        points = self.pair.Z1 * math.ceil(TVMS_POINTS / self.pair.Z1)  # pitch-aligned grid
        tvms = self.stiffness.mesh_stiffness(faults, points=points)
        return tvms, None, np.interp(phase, np.append(tvms.theta, 2 * np.pi), np.append(tvms.k, tvms.k[0]))

    def _table_series(self, model, faults, turns: float, shaft: np.ndarray, per_rev: float | None, start: int = 0):
        """A mesh's TVMS over one revolution of its table's gear, which turns *turns* times per input
        turn, and k(t) at input angle *shaft* (its first step *start*): exact table entries when that
        gear's revolution is a whole number of steps (nominal speed), else interpolated. (table, index
        or None, k(t))."""
        if per_rev is not None:
            steps_per_turn = per_rev / turns
            if abs(steps_per_turn - round(steps_per_turn)) < 1e-9 * steps_per_turn:
                table = model.mesh_stiffness(faults, points=round(steps_per_turn))
                index = self._index(len(shaft), round(steps_per_turn), start)
                return table, index, self._repeat(table.k, index, round(steps_per_turn))
        table = model.mesh_stiffness(faults, points=self._grid(model.pair, faults))
        k = np.interp(
            np.mod(turns * shaft, 2 * np.pi), np.append(table.theta, 2 * np.pi), np.append(table.k, table.k[0])
        )
        return table, None, k

    def _static_start(self, staged, load: float, k_mean: float) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """_equilibrium of a run with faults *staged* (faults_by_stage): a faulted further mesh at its own
        mean stiffness, as stage 1's at *k_mean* (the healthy ones at theirs)."""
        means = tuple(
            self.mesh_table(i, on, self._grid(self.mesh_models[i].pair, on)).mean if on else km
            for i, (on, km) in enumerate(zip(staged[1:], self.mesh_means))
        )
        return self._equilibrium(load, k_mean, means)

    def _equilibrium(
        self, load: float, k_mean: float, mesh_means: Sequence[float] | None = None
    ) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """The load vector F and the start (u, v, a): the static equilibrium at the mean stiffness, at rest."""
        F = np.zeros(len(self.dofs))
        F[self.load_index] = -load  # T_l opposes the driven gear's rotation (eq. 2.111)
        K_mean = self.Kc + k_mean * np.outer(self.P, self.P)
        for km, P in zip(self.mesh_means if mesh_means is None else mesh_means, self.mesh_P):
            K_mean = K_mean + km * np.outer(P, P)
        u = np.linalg.solve(K_mean, F)
        return F, (u, np.zeros_like(u), np.zeros_like(u))

    def _newmark(
        self,
        k: np.ndarray,
        forces: list,
        angle: np.ndarray | None,
        t: np.ndarray,
        speed: float,
        per_rev: float,
        F: np.ndarray,
        start: tuple,
        out_idx: np.ndarray,
        out: np.ndarray,
        mesh_faults: Sequence[Sequence[PlacedFault]] = (),
        first: int = 0,
    ) -> int:
        """The time loop (one of two compiled integrators: one mesh, several meshes; either with extra
        forces); fills *out* and updates *start* (u, v, a) in place. The step it diverged at, or -1.
        *mesh_faults*: the faults on each further mesh (stage 2 first); *first*: the step of t[0]."""
        steps = len(t) - 1
        G_F = self.G @ F
        # the arguments every integrator ends with: Newmark constants, step, state (updated in place), output
        tail = (self.c, 1.0 / self.fs, self.gamma, *start, out_idx, out)
        n = len(self.dofs)
        GB, g = self._forcing(forces) if forces else (np.zeros((n, 0)), np.zeros((steps, 0)))
        if self.meshes:
            # further meshes: k_i at their pinions' angles, ratio_i x the input angle
            if angle is not None:
                shaft = angle
            else:  # the run's own time base (from its start) is memoised
                own = round(t[0] * self.fs) == first
                shaft = self._time_base(steps, speed, first)[1] if own else 2 * np.pi * speed * t
            on = list(mesh_faults) + [()] * (len(self.meshes) - len(mesh_faults))
            k_all = np.column_stack(
                [k]
                + [
                    self._mesh_series(
                        i, shaft, per_rev if angle is None else None, *([on[i]] if on[i] else []), start=first
                    )
                    for i in range(len(self.meshes))
                ]
            )
            mu = np.array([self.mu, *self.mesh_mu])
            k_meshes = np.ascontiguousarray(k_all[1:])
            return _integrate_meshes(self.GMC, G_F, GB, g, self.Wm, self.Pm, self.PW, k_meshes, mu, *tail)
        return _integrate(self.GMC, G_F, GB, g, self.w, self.P, self.pw, k[1:], self.mu, *tail)

    def _forcing(self, forces: list) -> tuple[np.ndarray, np.ndarray]:
        """G B (the force vectors through K_hat_c^-1) and the force series g from the second step on."""
        B = np.stack([vector for vector, _ in forces], axis=1)
        g = np.ascontiguousarray(np.stack([series for _, series in forces], axis=1)[1:])
        return np.ascontiguousarray(self.G @ B), g

    def _mesh_series(self, i: int, shaft: np.ndarray, per_rev: float | None, faults=(), start: int = 0) -> np.ndarray:
        """k(t) of further mesh *i* with the input shaft at angle *shaft*: its pinion turns at ratio x the
        input; with *faults* its table spans a revolution of the faulted gear (both: the hunting period), read at
        that gear's angle. Exact table entries when that revolution is a whole number of steps (nominal
        speed), else interpolated on a pitch-aligned grid."""
        mesh, model = self.meshes[i], self.mesh_models[i]
        turns = self.table_turns(i + 2, faults) if faults else mesh.ratio
        return self._table_series(model, faults, turns, shaft, per_rev, start)[2]

    def _excite(self, effects, tvms, index, t, speed, load):
        """Apply excitation-level effects to the nominal excitation: (k(t), mean k, forces, moved angle or None)."""
        nominal = 2 * np.pi * speed * t
        exc = Excitation(
            fs=self.fs,
            speed_hz=speed,
            load_nm=load,
            t=t,
            angle=nominal,
            tvms=tvms,
            load=np.full(t.shape, load),
            dofs=self.dofs,
            M=self.M,
            P=self.P,
            mu=self.mu,
            c0=self.c0,
            load_dof=self.load_dof,
            stiffness=self.stiffness,
            index=index,
            rigid=self.rigid,
        )
        for effect, params in effects:
            exc = effect.apply_excitation(exc, params)
        return exc.stiffness_series(), exc.tvms.mean, exc.force_terms(), (None if exc.angle is nominal else exc.angle)
