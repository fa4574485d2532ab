"""Effects in a dataset: their canonical form, their scenario tables, the chain that applies
them, and the registered model a configuration names.

An effect in a dataset is a canonical pair ``(name, ((param, value), ...))`` with every
parameter resolved to SI and sorted by name (:func:`effect_spec`), so it is part of the
canonical JSON and of the cache key. :class:`EffectChain` loads such a tuple, orders it by
level (model, excitation, signal; the given order within a level) and applies it. The
contract one effect fulfils is gearlab.effect_contract; this module sits above the plugin
registry, which it looks effects and models up in.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .dynamics.config import DerivedModel, ModelConfig, sorted_values
from .dynamics.model import DynamicModel
from .effect_contract import LEVELS, Effect, EffectSpec, SignalContext
from .errors import GearlabInputError
from .gearbox.simulation import is_reference
from .registry import get_registry


def default_candidates(registry) -> list[str]:
    """The effects a diagnosis tries when none are named: every registered one but the opt-in ones and
    those a diagnosis cannot see (mean_only)."""
    return [
        name
        for name in registry.names("effect")
        if not any(getattr(registry.get("effect", name), flag, False) for flag in ("opt_in", "mean_only"))
    ]


def check_candidate(registry, name: str, where: str) -> None:
    """*name* is an effect a gap diagnosis can fit: registered (else "did you mean", the known list), and
    not one that adds only a constant, which the diagnosis's mean-removed records cannot show (mean_only)."""
    if getattr(registry.get("effect", name, where), "mean_only", False):
        raise GearlabInputError(
            f"{where}: '{name}' adds only a constant to the record, and the diagnosis compares each record "
            f"without its mean, so it would change nothing; expected an effect that changes the vibration "
            f"('{name}' is for simulated datasets)"
        )


def config_of(model: str, preset: str, channel: str, where: str = "", registry=None) -> ModelConfig:
    """The configuration of a registered model on one of its presets."""
    plugin = (registry or get_registry()).get("model", model, where)
    _, values = plugin.resolve(preset, where=where)
    return ModelConfig(
        model, preset, tuple(plugin.dofs), plugin.input_dof, plugin.load_dof, channel, sorted_values(values)
    )


def model_of(config: ModelConfig) -> DynamicModel:
    """The registered model with exactly the DOFs (and the preset) of *config*, or one derived from its base."""
    return _model_for(config.base, config.preset, config.dofs, config.input_dof, config.load_dof)


@functools.cache
def _model_for(base: str, preset: str, dofs: tuple[str, ...], input_dof: str, load_dof: str) -> DynamicModel:
    registry = get_registry()
    base_model = registry.get("model", base)
    for name in [base] + registry.names("model"):
        m = registry.get("model", name)
        takes = preset in m.presets or is_reference(preset) and m.stages == base_model.stages  # a description
        if tuple(m.dofs) == dofs and (m.input_dof, m.load_dof) == (input_dof, load_dof) and takes:
            return m
    added = [d for d in dofs if d not in base_model.dofs]
    return DerivedModel(
        f"{base}+{'+'.join(added)}",
        dofs,
        input_dof,
        load_dof,
        base_model.presets,
        f"{base} with {', '.join(added)} added by a model-level effect",
    )


def effect_spec(name: str, where: str = "", registry=None, **given) -> EffectSpec:
    """The canonical form of effect *name* with *given* parameters (units allowed), e.g.
    ``effect_spec("sensor_noise", kind="laplace", snr_db=0)``."""
    effect = (registry or get_registry()).get("effect", name, where)
    return effect.spec(given, where or f"effect '{name}'")


def effects_from_tables(entries, where: str, registry=None) -> tuple[EffectSpec, ...]:
    """Scenario form -> canonical: a list of tables ``{name = "...", <param> = <value>, ...}``."""
    registry = registry or get_registry()
    if not isinstance(entries, list):
        raise GearlabInputError(f'{where}: expected a list of tables, e.g. [{{name = "sensor_noise", snr_db = 10}}]')
    out = []
    for i, entry in enumerate(entries, start=1):
        here = f"{where} #{i}"
        if pair_form(entry):  # a gap run's summary.json corrected_effects, copied as docs/your_gearbox.md step 4 says
            entry = {"name": entry[0]} | {k: v for k, v in entry[1]}
        if not isinstance(entry, Mapping):
            raise GearlabInputError(
                f'{here}: expected a table {{name = "...", ...}}, got {type(entry).__name__} {entry!r}'
            )
        name = entry.get("name")
        if not isinstance(name, str) or not name:
            raise GearlabInputError(
                f"{here}: missing 'name' (the effect's registered name; known: {', '.join(registry.names('effect'))})"
            )
        effect = registry.get("effect", name, here)
        given = {k: v for k, v in entry.items() if k != "name"}
        out.append((LEVELS.index(effect.level), effect.spec(given, f"{here} ({name})")))
    # In order of level, the given order within a level: the order they act in, so that two
    # lists that act alike have one cache key (within a level the order matters: noise, then a filter).
    return tuple(spec for _, spec in sorted(out, key=lambda item: item[0]))


def pair_form(entry) -> bool:
    """Whether *entry* is an effect as summary.json keeps it: ``["name", [["param", value], ...]]``."""
    return (
        isinstance(entry, list)
        and len(entry) == 2
        and isinstance(entry[0], str)
        and isinstance(entry[1], list)
        and all(isinstance(p, list) and len(p) == 2 and isinstance(p[0], str) for p in entry[1])
    )


def check_effect_specs(effects, where: str) -> None:
    """The structure of a canonical effects tuple (no registry needed)."""
    if not isinstance(effects, tuple):
        raise GearlabInputError(f"{where}: effects must be a tuple of (name, ((param, value), ...)), got {effects!r}")
    for item in effects:
        ok = (
            isinstance(item, tuple)
            and len(item) == 2
            and isinstance(item[0], str)
            and isinstance(item[1], tuple)
            and all(isinstance(p, tuple) and len(p) == 2 and isinstance(p[0], str) for p in item[1])
        )
        if not ok:
            raise GearlabInputError(f"{where}: effect {item!r} is not (name, ((param, value), ...)); use effect_spec()")


# A gap search realises every candidate's rows with the rows' own seeds, the same at every evaluation: a record's
# start is kept by its seed, not drawn again by a fresh generator (14 us of the 69 us a row took through sensor_noise).
@functools.lru_cache(maxsize=4096)
def record_start(seed: tuple) -> float:
    """The time in the hour of recording a record seeded *seed* starts at (SignalContext.t0), in s."""
    return float(np.random.default_rng([*seed, 0]).uniform(0.0, 3600.0))


@dataclass(frozen=True)
class EffectChain:
    """Loaded effects with resolved parameters, ordered model -> excitation -> signal."""

    items: tuple[tuple[Effect, dict], ...] = ()

    @classmethod
    def load(cls, effects: Sequence[EffectSpec], where: str = "", registry=None) -> EffectChain:
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
                f"{where or 'effects'}: the configuration after the model-level effects ({model_of(config).name}) "
                "has no "
                f"channel '{config.channel}'; its channels: {', '.join(config.channels)}"
            )
        return config

    def apply_signal(
        self, record: np.ndarray, fs: float, speed_hz: float, reference_rms: float, seed: Sequence[int]
    ) -> np.ndarray:
        """Every signal-level effect on *record* (J, P), each with its own random stream from *seed*."""
        x = np.array(record, dtype=float)
        t0 = record_start(tuple(seed))
        for i, (effect, params) in enumerate(self.at("signal"), start=1):
            ctx = SignalContext(
                fs=fs, speed_hz=speed_hz, t0=t0, rng=np.random.default_rng([*seed, i]), reference_rms=reference_rms
            )
            x = np.asarray(effect.apply_signal(x, params, ctx), dtype=float)
        return x

    def specs(self) -> tuple[EffectSpec, ...]:
        return tuple((effect.name, tuple(sorted(params.items()))) for effect, params in self.items)
