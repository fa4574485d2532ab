"""The effect contract: an unmodelled effect for the sim-to-real gap diagnosis (docs/gap.md).

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
  differ from the tooth-1 response shifted by (n-1)/Z1 of a revolution
  (docs/physics.md, the builder's tooth-shift rule):
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

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .dynamics.config import ModelConfig
from .dynamics.excitation import Excitation
from .errors import GearlabInputError, did_you_mean, refuse_unknown
from .settings import NoParams, declared, plugin_description, resolve_params

LEVELS = ("model", "excitation", "signal")
HOOKS = {"model": "apply_model", "excitation": "apply_excitation", "signal": "apply_signal"}

EffectSpec = tuple[str, tuple[tuple[str, object], ...]]  # (name, ((param, value), ...)) sorted, SI


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


class Effect:
    """An unmodelled effect: override the hook of its level (``HOOKS[level]``) and nothing else; the
    hook it overrides is its ``level`` (a class may name it too, and then must override that one).

    Parameters: ``params`` is a settings dataclass of bounded numbers with SI units (gearlab.settings.setting) — what a
    diagnosis fits by bounded search; ``log_scale`` names those best searched on a log
    scale; ``options`` are categorical parameters, name -> choices (the first is the
    default), which a search enumerates.
    """

    name: ClassVar[str]
    doc: ClassVar[str] = ""
    breaks_symmetry: ClassVar[bool] = False
    # True for a zero-mean random addition (measurement noise): it leaves the simulation's
    # expected response as it is, so the fault shapes a detector matches are taken without it
    noise: ClassVar[bool] = False
    # True for an effect a diagnosis fits only when a scenario names it: a model-updating parameter
    # (a quantity of the real machine that is simply not published, such as its load torque) or an
    # artefact of one acquisition (a DC offset). "Every registered effect" (default_candidates)
    # leaves these out, so the library a diagnosis tries by default stays the mechanisms.
    opt_in: ClassVar[bool] = False
    # True for an effect that adds only a constant to the record (a DC offset): the gap diagnosis compares
    # each record without its mean (gearlab.gap.views.offset_removed), where it changes nothing, so no
    # diagnosis takes it as a candidate; a simulated dataset may still carry it.
    mean_only: ClassVar[bool] = False
    params: ClassVar[type] = NoParams
    options: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    log_scale: ClassVar[frozenset[str]] = frozenset()

    @property
    def level(self) -> str | None:
        """The level whose hook the class overrides; None where it overrides none or several."""
        own = [level for level, hook in HOOKS.items() if getattr(type(self), hook) is not getattr(Effect, hook)]
        return own[0] if len(own) == 1 else None

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
        refuse_unknown(given, [*declared(self.params), *self.options], where)
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
        out = [
            {
                "name": name,
                "unit": p.unit,
                "low": p.low,
                "high": p.high,
                "default": default,
                "integer": p.integer,
                "log": name in self.log_scale,
            }
            for name, (p, default) in declared(self.params).items()
        ]
        out += [{"name": k, "choices": list(v), "default": v[0]} for k, v in self.options.items()]
        return out

    def describe(self) -> dict:
        return plugin_description(
            self,
            level=self.level,
            breaks_symmetry=bool(self.breaks_symmetry),
            options={k: list(v) for k, v in self.options.items()},
        )


def hook_problem(obj) -> str:
    """What is wrong with an effect plugin's level, symmetry flag or hook ('' when nothing)."""
    level = getattr(obj, "level", None)
    if level is None and isinstance(obj, Effect):
        return f"effect '{obj.name}': override exactly one of {', '.join(HOOKS.values())} (its level's hook)"
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
