"""The effect contract: unmodelled effects for the sim-to-real gap (SPEC sections 2 and 9).

The thesis shows that a classifier trained on one simulated domain fails on another — a
sensor on the casing instead of the pinion (Experiment A), motor and load inertias the
source model lacks (Experiment B) — and names further mismatches it leaves out: vibration
from nearby machines, motor dynamics, dynamic loads and measurement noise (chapter 4
introduction), friction (2.4.1, 2.4.2), the mesh damping model (6.2, physics item 1) and
the fillet-foundation overestimate in double contact (6.2, physics item 5). An *effect* is
one such mismatch as a plugin with bounded, unit-carrying parameters that can be added to
any source simulator configuration. It acts at exactly one of three levels, through one
hook per level:

    level        hook                                      what it may change
    -----------  ----------------------------------------  -------------------------------------------
    model        apply_model(config, params) -> config     ModelConfig: DOFs, parameter values, the
                                                           sensor channel, the mesh damping model
    excitation   apply_excitation(exc, params) -> exc      Excitation: shaft angle θ(t), TVMS k(θ),
                                                           load torque T_l(t), extra forces F(t)
    signal       apply_signal(x, params, ctx) -> x         the measured record x (J, P): J consecutive
                                                           revolutions of P samples (SignalContext)

Rules that keep the dataset builder simple and exact:

* model effects are pure functions of the configuration; they may add DOFs (from the 10-DOF
  set of eq. 2.96), change parameter values and move the sensor, never change the gear pair;
* excitation effects keep the excitation periodic in one input-shaft revolution (their
  time-varying parts are synchronous, whole orders), because the builder simulates one
  steady revolution per case; non-synchronous disturbances belong to the signal level;
* signal effects draw every random number from ``ctx.rng`` and every non-synchronous
  phase from ``ctx.t0``, so records are reproducible and differ from sample to sample;
* ``breaks_symmetry`` is True when the effect makes the steady response to a fault on tooth n
  differ from the tooth-1 response shifted by (n-1)/Z1 of a revolution (SPEC section 4):
  anything locked to the shaft angle but not periodic in the tooth pitch. The builder then
  simulates every tooth instead of rolling one revolution.

An effect in a dataset is a canonical pair ``(name, ((param, value), ...))`` with every
parameter resolved to SI and sorted by name (:func:`effect_spec`), so it is part of the
canonical JSON and of the cache key. :class:`EffectChain` loads such a tuple, orders it by
level (model, excitation, signal; the given order within a level) and applies it. This is
all a diagnosis needs: add any effect with parameters to a source configuration, search its
bounded parameters (``Effect.space()``), and run the simulations in parallel (a dataset spec
with effects is a plain, picklable value whose simulation units go through the executor).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .dynamics.model import CHANNEL_DOFS, DOF_ORDER, MESH_DAMPING_MODELS, DynamicModel
from .errors import GearlabInputError
from .params import Param, did_you_mean, resolve_params
from .physics.geometry import GearPair
from .physics.stiffness import MeshStiffness, MeshStiffnessModel

LEVELS = ("model", "excitation", "signal")
HOOKS = {"model": "apply_model", "excitation": "apply_excitation", "signal": "apply_signal"}

EffectSpec = tuple[str, tuple[tuple[str, object], ...]]  # (name, ((param, value), ...)) sorted, SI


# --- model level -------------------------------------------------------------------------


@dataclass(frozen=True)
class ModelConfig:
    """A simulator configuration: which DOFs, which parameter values, where the sensor sits.

    *base* is the registered model whose presets give the gear pair and the operating point;
    the DOFs may be more than the base model's (a model-level effect added some). *values*
    holds every lumped parameter of the configuration in SI, sorted by name, so the
    configuration is hashable and two equal configurations simulate identically.
    """

    base: str
    preset: str
    dofs: tuple[str, ...]
    input_dof: str  # the fixed-speed (tacho) DOF
    load_dof: str  # where the load torque acts
    channel: str  # the measured channel, e.g. pinion_x, casing_x
    values: tuple[tuple[str, float], ...]
    mesh_damping: str = "proportional"  # one of MESH_DAMPING_MODELS: c(t) = mu k(t) (eq. 2.108) or c_m (eq. 2.107)

    def __post_init__(self):
        if self.mesh_damping not in MESH_DAMPING_MODELS:
            raise GearlabInputError(f"mesh damping model must be one of {', '.join(MESH_DAMPING_MODELS)}, "
                                    f"got {self.mesh_damping!r}")

    @classmethod
    def of(cls, model: str, preset: str, channel: str, where: str = "") -> ModelConfig:
        """The configuration of a registered model on one of its presets."""
        from .registry import get_registry

        plugin = get_registry().get("model", model, where)
        _, values = plugin.resolve(preset, where=where)
        return cls(model, preset, tuple(plugin.dofs), plugin.input_dof, plugin.load_dof, channel, _sorted(values))

    @property
    def params(self) -> dict[str, float]:
        return dict(self.values)

    @property
    def channels(self) -> tuple[str, ...]:
        return tuple(c for c, dof in CHANNEL_DOFS.items() if dof in self.dofs)

    def has(self, *dofs: str) -> bool:
        return all(d in self.dofs for d in dofs)

    def with_values(self, **values: float) -> ModelConfig:
        return dataclasses.replace(self, values=_sorted({**self.params, **values}))

    def with_dofs(self, *added: str, input_dof: str | None = None, load_dof: str | None = None) -> ModelConfig:
        """More DOFs (kept in the order of eq. 2.96); optionally a new input or load DOF."""
        unknown = [d for d in added if d not in DOF_ORDER]
        if unknown:
            raise ValueError(f"unknown DOF(s) {unknown}; the DOFs are {DOF_ORDER}")
        dofs = tuple(d for d in DOF_ORDER if d in self.dofs or d in added)
        return dataclasses.replace(self, dofs=dofs, input_dof=input_dof or self.input_dof,
                                   load_dof=load_dof or self.load_dof)

    def replace(self, **changes) -> ModelConfig:
        return dataclasses.replace(self, **changes)

    def model(self) -> DynamicModel:
        """The registered model with exactly these DOFs (and the preset), or one derived from the base."""
        return _model_for(self.base, self.preset, self.dofs, self.input_dof, self.load_dof)

    @property
    def name(self) -> str:
        return self.model().name

    def overrides(self) -> dict[str, float]:
        """The values as overrides for Simulator/DynamicModel.resolve (only the model's own parameters)."""
        names = set(self.model().param_names())
        return {k: v for k, v in self.values if k in names}


def _sorted(values: Mapping[str, float]) -> tuple[tuple[str, float], ...]:
    return tuple(sorted((k, float(v)) for k, v in values.items()))


class DerivedModel(DynamicModel):
    """A lumped model with the DOFs a model-level effect asked for, on its base model's presets.

    The assembly is the same restriction of the 10-DOF model (eq. 2.97-2.104) that every
    registered model uses (dynamics.model.lumped_assembly); nothing is assembled twice.
    """

    def __init__(self, name: str, dofs: tuple[str, ...], input_dof: str, load_dof: str, presets: Mapping, doc: str):
        self.name, self.dofs, self.input_dof, self.load_dof, self.doc = name, dofs, input_dof, load_dof, doc
        self.presets = presets


@functools.lru_cache(maxsize=None)
def _model_for(base: str, preset: str, dofs: tuple[str, ...], input_dof: str, load_dof: str) -> DynamicModel:
    from .registry import get_registry

    registry = get_registry()
    base_model = registry.get("model", base)
    for name in [base] + registry.names("model"):
        m = registry.get("model", name)
        if tuple(m.dofs) == dofs and (m.input_dof, m.load_dof) == (input_dof, load_dof) and preset in m.presets:
            return m
    added = [d for d in dofs if d not in base_model.dofs]
    return DerivedModel(f"{base}+{'+'.join(added)}", dofs, input_dof, load_dof, base_model.presets,
                        f"{base} with {', '.join(added)} added by a model-level effect")


# --- excitation level --------------------------------------------------------------------

# An extra generalised force, evaluated once every excitation effect has acted:
# f(exc) -> (vector over exc.dofs, series over exc.t), or a list of such pairs.
Force = Callable[["Excitation"], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Excitation:
    """What drives one simulation, sampled on the integration steps t_i = i / fs.

    The equations of motion (eq. 2.95) with the input DOF at its prescribed angle read

        M u'' + (Cc + c(t) P^T P) u' + (Kc + k(t) P^T P) u = F0 T_l(t)/T_l + sum_j b_j g_j(t),

    with k(t) = k(θ(t)) read from the TVMS over one revolution (with the faults) at the
    input-shaft angle θ(t), c(t) = c0 + mu k(t) (eq. 2.107-2.109), the load torque series
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
    tvms: MeshStiffness  # k(θ) over one revolution, faults included
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
        table = MeshStiffness(theta=self.tvms.theta, k=np.asarray(k, dtype=float), pair=self.tvms.pair,
                              faults=self.tvms.faults)
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
        """Per pinion tooth n = 1..Z1 on the TVMS grid: its local mesh angle phi (rad since its contact
        began), whether it is in mesh, and its pair stiffness k_n (faults included), each (Z1, points).

        Tooth n meshes for (n-1) 2 pi/Z1 <= theta < (n-1) 2 pi/Z1 + theta_t (eq. 2.51-2.54); the
        local angle is formed in integer arithmetic so every tooth sees the same angles at
        corresponding grid points and the per-tooth picture shifts exactly with the tooth.
        """
        pair, points = self.pair, len(self.tvms.theta)
        Z1 = pair.Z1
        j = np.arange(points, dtype=np.int64)[None, :]
        n = np.arange(Z1, dtype=np.int64)[:, None]
        phi = 2 * np.pi * np.mod(j * Z1 - n * points, points * Z1) / (points * Z1)
        in_mesh = phi < pair.theta_t
        k = np.zeros(phi.shape)
        k[in_mesh] = self.stiffness.tooth_pair_stiffness(phi[in_mesh])  # all teeth healthy, one pass
        for tooth in sorted({f.tooth for f in self.faults}):
            on = [f for f in self.faults if f.tooth == tooth]
            row = in_mesh[tooth - 1]
            k[tooth - 1, row] = self.stiffness.tooth_pair_stiffness(phi[tooth - 1, row], on)
        return phi, in_mesh, k

    def at_angle(self, table: np.ndarray) -> np.ndarray:
        """Read a per-revolution table on the TVMS grid at θ(t): by index while θ is the nominal angle on
        a grid of whole steps per revolution (exact, so tooth shifts stay exact), else interpolated."""
        if self.index is not None:
            return table[self.index]
        theta = np.append(self.tvms.theta, 2 * np.pi)
        return np.interp(np.mod(self.angle, 2 * np.pi), theta, np.append(table, table[0]))

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


# --- signal level ------------------------------------------------------------------------


@dataclass(frozen=True)
class SignalContext:
    """What a signal-level effect knows about the record it changes.

    A record is J consecutive input-shaft revolutions of P samples each, equally spaced in
    the shaft angle; at the (constant) mean speed they are equally spaced in time too, at
    fs = P x speed. The record starts at time t0, drawn at random for each record, so a
    non-synchronous component has a different phase in every sample.
    """

    fs: float  # samples per second along the record
    speed_hz: float
    t0: float  # s, time of the record's first sample
    rng: np.random.Generator
    reference_rms: float  # RMS of the domain's clean healthy signal, the scale of relative levels

    def time(self, n: int) -> np.ndarray:
        return self.t0 + np.arange(n) / self.fs


# --- the plugin contract -----------------------------------------------------------------


class Effect:
    """An unmodelled effect: override the hook of its level (``HOOKS[level]``) and nothing else.

    Parameters: ``params`` are bounded numbers with SI units (gearlab.params.Param) — what a
    diagnosis fits by bounded search; ``log_scale`` names those best searched on a log
    scale; ``options`` are categorical parameters, name -> choices (the first is the
    default), which a search enumerates.
    """

    name: ClassVar[str]
    doc: ClassVar[str] = ""
    level: ClassVar[str]
    breaks_symmetry: ClassVar[bool] = False
    # True for a zero-mean random addition (measurement noise): it leaves the simulation's
    # expected response as it is, so the fault shapes a detector matches are taken without it
    noise: ClassVar[bool] = False
    # True for an effect a diagnosis fits only when a scenario names it: a model-updating parameter
    # (a quantity of the real machine that is simply not published, such as its load torque) or an
    # artefact of one acquisition (a DC offset). "Every registered effect" (default_candidates)
    # leaves these out, so the library a diagnosis tries by default stays the mechanisms.
    opt_in: ClassVar[bool] = False
    params: ClassVar[tuple[Param, ...]] = ()
    options: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    log_scale: ClassVar[frozenset[str]] = frozenset()

    # --- the hook of the effect's level (one of three) ---
    def apply_model(self, config: ModelConfig, params: Mapping) -> ModelConfig:
        raise NotImplementedError

    def apply_excitation(self, exc: Excitation, params: Mapping) -> Excitation:
        raise NotImplementedError

    def apply_signal(self, x: np.ndarray, params: Mapping, ctx: SignalContext) -> np.ndarray:
        raise NotImplementedError

    # --- optional checks ---
    def check(self, params: Mapping, where: str) -> None:
        """Raise GearlabInputError for impossible parameter combinations (default: none)."""

    def check_config(self, params: Mapping, config: ModelConfig, where: str) -> None:
        """Raise GearlabInputError when the effect cannot act on *config* (default: it always can)."""

    # --- optional: where a diagnosis should look ---
    def guesses(self, target_X: np.ndarray, speed_hz: float) -> list[dict]:
        """Parameter values read off a target's healthy revolutions (physical units, (n, 4096),
        fs = 4096 x speed_hz), which a diagnosis tries right after the defaults; parameters a
        guess leaves out keep their defaults (default: no guesses). For needle-like parameters
        that a budgeted search over the bounds would miss, such as a tone's frequency."""
        return []

    # --- provided ---
    def resolve(self, given: Mapping[str, object], where: str = "") -> dict:
        """Defaults filled, units parsed, bounds and choices checked: {param: SI value or choice}."""
        where = where or f"effect '{self.name}'"
        known = [p.name for p in self.params] + list(self.options)
        for key in given:
            if key not in known:
                raise GearlabInputError(
                    f"{where}: unknown parameter '{key}'{did_you_mean(key, known)}; known: {', '.join(known) or 'none'}"
                )
        values: dict = resolve_params(self.params, {k: v for k, v in given.items() if k not in self.options}, where)
        for key, choices in self.options.items():
            value = given.get(key, choices[0])
            if value not in choices:
                shown = value if isinstance(value, str) else repr(value)
                raise GearlabInputError(
                    f"{where}, parameter '{key}': '{shown}' is not one of {', '.join(choices)}"
                    f"{did_you_mean(str(value), choices)}"
                )
            values[key] = value
        self.check(values, where)
        return values

    def spec(self, given: Mapping[str, object] | None = None, where: str = "") -> EffectSpec:
        """The canonical (name, sorted SI params) of this effect with *given* parameters."""
        return (self.name, tuple(sorted(self.resolve(given or {}, where).items())))

    def space(self) -> list[dict]:
        """The search space: one entry per parameter (bounds, scale) and per option (choices)."""
        out = [{"name": p.name, "unit": p.unit, "low": p.low, "high": p.high, "default": p.default,
                "integer": p.integer, "log": p.name in self.log_scale} for p in self.params]
        out += [{"name": k, "choices": list(v), "default": v[0]} for k, v in self.options.items()]
        return out

    def describe(self) -> dict:
        return {"doc": self.doc, "params": [p.describe() for p in self.params], "level": self.level,
                "breaks_symmetry": bool(self.breaks_symmetry), "options": {k: list(v) for k, v in self.options.items()}}


def default_candidates(registry) -> list[str]:
    """The effects a diagnosis tries when none are named: every registered one but the opt-in ones."""
    return [name for name in registry.names("effect") if not getattr(registry.get("effect", name), "opt_in", False)]


def hook_problem(obj) -> str:
    """What is wrong with an effect plugin's level, symmetry flag or hook ('' when nothing)."""
    level = getattr(obj, "level", None)
    if level not in LEVELS:
        return f"effect '{obj.name}': level must be one of {', '.join(LEVELS)}, got {level!r}"
    if not isinstance(getattr(obj, "breaks_symmetry", None), bool):
        return f"effect '{obj.name}': breaks_symmetry must be True or False"
    hook = HOOKS[level]
    inherited = isinstance(obj, Effect) and getattr(type(obj), hook) is getattr(Effect, hook)  # not overridden
    if not callable(getattr(obj, hook, None)) or inherited:
        return f"effect '{obj.name}' of level '{level}' lacks {hook}"
    options = getattr(obj, "options", {})
    if not isinstance(options, Mapping) or not all(
        isinstance(v, tuple) and v and all(isinstance(c, str) for c in v) for v in options.values()
    ):
        return f"effect '{obj.name}': options must map names to non-empty tuples of strings"
    return ""


# --- effects in a dataset: canonical form, loading, applying ---------------------------------


def effect_spec(name: str, where: str = "", registry=None, **given) -> EffectSpec:
    """The canonical form of effect *name* with *given* parameters (units allowed), e.g.
    ``effect_spec("sensor_noise", kind="laplace", snr_db=0)``."""
    from .registry import get_registry

    effect = (registry or get_registry()).get("effect", name, where)
    return effect.spec(given, where or f"effect '{name}'")


def effects_from_tables(entries, where: str, registry=None) -> tuple[EffectSpec, ...]:
    """Scenario form -> canonical: a list of tables ``{name = "...", <param> = <value>, ...}``."""
    from .registry import get_registry

    registry = registry or get_registry()
    if not isinstance(entries, list):
        raise GearlabInputError(f"{where}: expected a list of tables, e.g. [{{name = \"sensor_noise\", snr_db = 10}}]")
    out = []
    for i, entry in enumerate(entries, start=1):
        here = f"{where} #{i}"
        if not isinstance(entry, Mapping):
            raise GearlabInputError(
                f"{here}: expected a table {{name = \"...\", ...}}, got {type(entry).__name__} {entry!r}"
            )
        name = entry.get("name")
        if not isinstance(name, str) or not name:
            raise GearlabInputError(f"{here}: missing 'name' (the effect's registered name; known: "
                                    f"{', '.join(registry.names('effect'))})")
        effect = registry.get("effect", name, here)
        given = {k: v for k, v in entry.items() if k != "name"}
        out.append((LEVELS.index(effect.level), effect.spec(given, f"{here} ({name})")))
    # In order of level, the given order within a level: the order they act in, so that two
    # lists that act alike have one cache key (within a level the order matters: noise, then a filter).
    return tuple(spec for _, spec in sorted(out, key=lambda item: item[0]))


def check_effect_specs(effects, where: str) -> None:
    """The structure of a canonical effects tuple (no registry needed)."""
    if not isinstance(effects, tuple):
        raise GearlabInputError(f"{where}: effects must be a tuple of (name, ((param, value), ...)), got {effects!r}")
    for item in effects:
        ok = (isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str) and isinstance(item[1], tuple)
              and all(isinstance(p, tuple) and len(p) == 2 and isinstance(p[0], str) for p in item[1]))
        if not ok:
            raise GearlabInputError(f"{where}: effect {item!r} is not (name, ((param, value), ...)); use effect_spec()")


@dataclass(frozen=True)
class EffectChain:
    """Loaded effects with resolved parameters, ordered model -> excitation -> signal."""

    items: tuple[tuple[Effect, dict], ...] = ()

    @classmethod
    def load(cls, effects: Sequence[EffectSpec], where: str = "", registry=None) -> EffectChain:
        from .registry import get_registry

        registry = registry or get_registry()
        where = where or "effects"
        check_effect_specs(tuple(effects), where)
        items = []
        for i, (name, params) in enumerate(effects, start=1):
            here = f"{where} #{i}"
            effect = registry.get("effect", name, here)
            items.append((effect, effect.resolve(dict(params), f"{here} ({name})")))
        items.sort(key=lambda item: LEVELS.index(item[0].level))  # stable: the given order within a level
        return cls(tuple(items))

    def __bool__(self) -> bool:
        return bool(self.items)

    def at(self, level: str) -> tuple[tuple[Effect, dict], ...]:
        return tuple(item for item in self.items if item[0].level == level)

    @property
    def breaks_symmetry(self) -> bool:
        return any(effect.breaks_symmetry for effect, _ in self.items)

    def model_config(self, source: ModelConfig, where: str = "") -> ModelConfig:
        """*source* with every model-level effect applied in order."""
        config = source
        for effect, params in self.at("model"):
            here = f"{where}: effect '{effect.name}'" if where else f"effect '{effect.name}'"
            effect.check_config(params, config, here)
            config = effect.apply_model(config, params)
        if config.channel not in config.channels:
            raise GearlabInputError(
                f"{where or 'effects'}: the configuration after the model-level effects ({config.name}) has no "
                f"channel '{config.channel}'; its channels: {', '.join(config.channels)}"
            )
        return config

    def apply_signal(self, record: np.ndarray, fs: float, speed_hz: float, reference_rms: float,
                     seed: Sequence[int]) -> np.ndarray:
        """Every signal-level effect on *record* (J, P), each with its own random stream from *seed*."""
        x = np.array(record, dtype=float)
        t0 = float(np.random.default_rng([*seed, 0]).uniform(0.0, 3600.0))  # a time in the hour of recording
        for i, (effect, params) in enumerate(self.at("signal"), start=1):
            ctx = SignalContext(fs=fs, speed_hz=speed_hz, t0=t0, rng=np.random.default_rng([*seed, i]),
                                reference_rms=reference_rms)
            x = np.asarray(effect.apply_signal(x, params, ctx), dtype=float)
        return x

    def specs(self) -> tuple[EffectSpec, ...]:
        return tuple((effect.name, tuple(sorted(params.items()))) for effect, params in self.items)
