"""Settings declared once: a dataclass field carries its type, unit, bounds, default, --quick
limit and doc, and everything else is derived from it — the scenario keys and their checks
(gearlab.scenario.keys_of), the --quick shrinking (:func:`shrunk`), the checks of an inline
table such as a dataset's noise ``{kind = "laplace", snr_db = 0, seed = 1}`` (:func:`from_inline`) and the
reference tables of docs/settings.md (gearlab.settings_doc, through the scenario keys). A
plugin's parameters are such a dataclass too (its ``params``, written in its class with
:func:`parameters`; read by :func:`resolve_params`, :func:`describe_params`), numbers in SI with
the unit shown to people:

    params = parameters(q0=setting(float, 0.0, low=0.0, high=0.05, unit="m", display_unit="mm", doc="crack depth"))

    @dataclass(frozen=True)
    class NoiseSpec:
        kind: str = setting(str, choices=NOISE_KINDS, doc="noise distribution")
        snr_db: float = setting(float, unit="dB", doc="signal-to-noise ratio")

A field without a default (``setting(types, ...)`` alone) is required. Every scenario table is
declared so (``kw_only=True`` where a required key follows one with a default): a kind's
``Table(keys_of(cls))`` and, in build(), ``typed(cls, table)``. Base layer: imports nothing of
gearlab but the errors and the units.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from .errors import GearlabInputError, did_you_mean, refuse_unknown, shown
from .units import display, to_si

# Most epochs any training key may ask for (the thesis trains for at most 800): beyond it a
# value is a mistake that would hold a run for years.
MAX_EPOCHS = 100_000
# torch takes seeds below 2**64 (1000 * seed + repetition); a seed is a 32-bit word
MAX_SEED = 2**32 - 1
# beyond this the list of units of a protocol would not fit in memory
MAX_REPETITIONS = 1000


@dataclasses.dataclass(frozen=True)
class Setting:
    """What a setting declares besides its name and default (:func:`setting`). Values are stored
    in SI (*unit*); *display_unit* is for people."""

    types: type | tuple[type, ...]
    low: float | None = None
    high: float | None = None
    unit: str = ""
    doc: str = ""
    choices: tuple[str, ...] = ()
    quick: Any = None  # --quick: the value is at most this
    check: Callable[[Any, str], Any] | None = None  # a check of its own: returns the value or raises
    display_unit: str = ""  # the unit shown to people where it is not the SI *unit*

    @property
    def integer(self) -> bool:
        return self.types is int

    def show(self, value: float) -> str:
        return display(value, self.unit, self.display_unit)


# A setting's SI unit and the unit people read, where they differ: setting(..., **MM, ...) is
# unit="m", display_unit="mm".
MM = {"unit": "m", "display_unit": "mm"}
UM = {"unit": "m", "display_unit": "um"}
DEG = {"unit": "rad", "display_unit": "deg"}
KHZ = {"unit": "Hz", "display_unit": "kHz"}


def setting(
    types: type | tuple[type, ...],
    default: Any = dataclasses.MISSING,
    *,
    low: float | None = None,
    high: float | None = None,
    unit: str = "",
    doc: str = "",
    choices: Iterable[str] = (),
    quick: Any = None,
    check: Callable[[Any, str], Any] | None = None,
    display_unit: str = "",
) -> Any:
    """A dataclass field declared with everything the scenario, --quick and the docs need. A list
    or table default is copied for each instance (a dataclass refuses a shared mutable default).
    *unit* is the SI unit values are stored in, *display_unit* the one shown to people."""
    meta = Setting(types, low, high, unit, doc, tuple(choices), quick, check, display_unit)
    if isinstance(default, (list, dict)):
        return dataclasses.field(default_factory=lambda: copy.deepcopy(default), metadata={"setting": meta})
    return dataclasses.field(default=default, metadata={"setting": meta})


def _default(f: dataclasses.Field):
    return f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default


def declared(cls) -> dict[str, tuple[Setting, Any]]:
    """{field: (its Setting, its default or MISSING)} of the fields of *cls* declared with setting()."""
    return {f.name: (f.metadata["setting"], _default(f)) for f in dataclasses.fields(cls) if "setting" in f.metadata}


def setting_of(cls, name: str) -> Setting:
    """The Setting of field *name* of *cls* (a plugin's bounds where its code needs them)."""
    return declared(cls)[name][0]


def parameters(*bases, **fields):
    """A plugin's parameters written in its class: the frozen settings dataclass of *fields*
    (name=setting(float or int, ...)) after the fields of *bases* (settings dataclasses)."""
    return dataclasses.make_dataclass(
        "Params", [(name, f.metadata["setting"].types, f) for name, f in fields.items()], bases=bases, frozen=True
    )


@functools.cache
def subset(cls, names: tuple[str, ...]):
    """A settings dataclass of the fields *names* of *cls*, in that order (a plugin that takes
    some of a shared list, such as a lumped model's parameters)."""
    fields = {f.name: f for f in dataclasses.fields(cls)}
    return parameters(**{n: dataclasses.field(default=fields[n].default, metadata=fields[n].metadata) for n in names})


@dataclasses.dataclass(frozen=True)
class NoParams:
    """The parameters of a plugin that takes none."""


def params_problem(cls) -> str:
    """What is wrong with a plugin's ``params`` ('' when nothing): a dataclass whose every field
    is a number declared with setting(), its default within its bounds."""
    if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
        return "params must be a dataclass of fields declared with gearlab.api.setting"
    for f in dataclasses.fields(cls):
        meta, default = f.metadata.get("setting"), _default(f)
        if meta is None or not _number(meta.types) or meta.low is None or meta.high is None:
            return f"parameter '{f.name}' must be declared with setting(float or int, default, low=, high=, ...)"
        if not (meta.low <= default <= meta.high):
            return f"parameter '{f.name}' default {default!r} lies outside its bounds [{meta.low}, {meta.high}]"
    return ""


def describe_params(cls) -> list[dict]:
    """Each parameter of *cls* as a plain table (the registry's describe, the TUI, `gearlab plugins`)."""
    return [
        {
            "name": name,
            "unit": meta.unit,
            "display_unit": meta.display_unit or meta.unit,
            "default": default,
            "low": meta.low,
            "high": meta.high,
            "integer": meta.integer,
            "doc": meta.doc,
        }
        for name, (meta, default) in declared(cls).items()
    ]


def shown_values(cls, values: Mapping) -> list[str]:
    """Each of *values* (SI, by the fields of *cls*) as people read it: in its display unit, a bare
    number where the setting has no unit."""
    return [meta.show(values[name]) if meta.unit else f"{values[name]}" for name, (meta, _) in declared(cls).items()]


def plugin_description(plugin, **more) -> dict:
    """What every plugin's describe() holds (its doc, its parameters), and *more* of its kind's."""
    return {"doc": plugin.doc, "params": describe_params(plugin.params), **more}


def resolve_params(cls, given: Mapping[str, object], where: str) -> dict[str, float]:
    """The parameters of the settings dataclass *cls* from *given* (a scenario's table): defaults
    filled, units parsed to SI, names, whole numbers and bounds checked. {name: SI value}."""
    schema = declared(cls)
    if not isinstance(given, Mapping):
        raise GearlabInputError(f"{where}: expected a table of parameters {{name = value, ...}}, got {given!r}")
    refuse_unknown(given, list(schema), where)
    values: dict[str, float] = {}
    for name, (meta, default) in schema.items():
        here = f"{where}, parameter '{name}'"
        value = to_si(given[name], meta.unit, here) if name in given else default
        if meta.integer:
            if value != int(value):
                raise GearlabInputError(f"{here}: expected a whole number, got {value:g}")
            value = int(value)
        if not (meta.low <= value <= meta.high):
            raise GearlabInputError(
                f"{here}: {meta.show(value)} is outside [{meta.show(meta.low)}, {meta.show(meta.high)}]"
            )
        values[name] = value
    return values


def typed(cls, values: Mapping):
    """A validated scenario table (gearlab.scenario.validate_table's dict) as an instance of its
    settings dataclass *cls*: the keys *cls* declares, the others (a table sharing keys with
    another declaration) left out."""
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{k: v for k, v in values.items() if k in names})


def in_bounds(meta: Setting, value, where: str):
    """*value* checked against the bounds and choices of *meta* (the scenario's messages)."""
    if meta.choices and value not in meta.choices:
        raise GearlabInputError(
            f"{where}: {shown(value)} is not one of {', '.join(meta.choices)}"
            f"{did_you_mean(str(value), meta.choices) if len(str(value)) <= 100 else ''}"
        )
    if meta.low is not None or meta.high is not None:
        low, high = meta.low, meta.high
        # written as "not inside" so that NaN, which compares false with everything, is outside
        if not ((low is None or value >= low) and (high is None or value <= high)) or (
            isinstance(value, float) and not math.isfinite(value)
        ):
            span = f"[{low if low is not None else '-inf'}, {high if high is not None else 'inf'}]"
            raise GearlabInputError(f"{where}: {shown(value)} is outside {span}")
    return meta.check(value, where) if meta.check else value


def quick_limits(cls) -> dict[str, Any]:
    """{field: its --quick limit} of *cls*."""
    return {name: meta.quick for name, (meta, _) in declared(cls).items() if meta.quick is not None}


def shrunk(settings, **limits):
    """A copy of the dataclass *settings* for a smoke run (--quick): each field with a --quick
    limit (declared, or given here, which wins) at most that limit."""
    limits = {**quick_limits(type(settings)), **limits}
    return dataclasses.replace(
        settings, **{name: min(getattr(settings, name), limit) for name, limit in limits.items()}
    )


def _number(types) -> bool:
    types = types if isinstance(types, tuple) else (types,)
    return float in types or int in types


def from_inline(cls, table: Mapping, where: str, defaults: Mapping | None = None):
    """An inline TOML table (``{kind = "laplace", snr_db = 0}``) as an instance of *cls*: unknown
    keys, missing required keys, types and bounds refused in one line naming *where*.
    *defaults* replace the declared defaults (a preset's values)."""
    fields = declared(cls)
    unknown = set(table) - set(fields)
    if unknown:
        raise GearlabInputError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}; expected {', '.join(fields)}")
    defaults = dict(defaults or {})
    missing = [n for n, (_, d) in fields.items() if n not in table and n not in defaults and d is dataclasses.MISSING]
    if missing:
        shape = ", ".join(
            f"{n} = "
            + (
                "|".join(f"'{c}'" for c in meta.choices)
                if meta.choices
                else "number"
                if _number(meta.types)
                else meta.types.__name__
            )
            for n, (meta, d) in fields.items()
            if d is dataclasses.MISSING
        )
        raise GearlabInputError(f"{where}: expected {{{shape}}}")
    values = {}
    for name, (meta, _) in fields.items():
        if name not in table:
            if name in defaults:
                values[name] = defaults[name]
            continue
        value = table[name]
        if meta.types is int or meta.types == (int,):
            if (
                isinstance(value, bool)
                or not isinstance(value, int)
                or not ((meta.low is None or meta.low <= value) and (meta.high is None or value <= meta.high))
            ):
                raise GearlabInputError(
                    f"{where}: {name} must be a whole number in [{meta.low}, {meta.high}], got {shown(value)}"
                )
        elif _number(meta.types):
            # abs() < 1e300 also refuses nan, inf and integers too large for a float
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not abs(value) < 1e300:
                raise GearlabInputError(
                    f"{where}: {name} must be a finite number of {meta.unit or 'units'}, got {str(value)[:40]}"
                )
            value = float(value)
            if not meta.check:  # its bounds (with a check, the line below checks both)
                value = in_bounds(meta, value, f"{where}: {name}")
        else:
            value = str(value)
        values[name] = in_bounds(meta, value, f"{where}: {name}") if meta.check else value
    return cls(**values)
