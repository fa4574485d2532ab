"""Parameter schemas for plugins: name, SI unit, bounds, default and a line of doc, on the Setting
record a scenario key is declared with too (gearlab.settings)."""

from __future__ import annotations

import difflib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from .errors import GearlabInputError
from .units import display, to_si


@dataclass(frozen=True)
class Setting:
    """What a setting declares besides its name and default: a scenario key's (gearlab.settings.setting)
    or a plugin parameter's (Param, which adds the unit shown to people)."""

    types: type | tuple[type, ...]
    low: float | None = None
    high: float | None = None
    unit: str = ""
    doc: str = ""
    choices: tuple[str, ...] = ()
    quick: Any = None  # --quick: the value is at most this
    check: Callable[[Any, str], Any] | None = None  # a check of its own: returns the value or raises
    display_unit: str = ""  # the unit shown to people where it is not the SI *unit*


@dataclass(frozen=True, init=False)
class Param(Setting):
    """One plugin parameter: a Setting with a name and a default. Values are stored in SI (*unit*);
    *display_unit* is for people. Written Param(name, unit, default, low, high, doc[, display_unit,
    integer])."""

    name: str = ""
    default: float = 0.0

    def __init__(
        self,
        name: str,
        unit: str,
        default: float,
        low: float,
        high: float,
        doc: str,
        display_unit: str = "",
        integer: bool = False,
    ):
        super().__init__(int if integer else float, low, high, unit, doc, display_unit=display_unit)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "default", default)

    @property
    def integer(self) -> bool:
        return self.types is int

    def describe(self) -> dict:
        return {
            "name": self.name,
            "unit": self.unit,
            "display_unit": self.display_unit or self.unit,
            "default": self.default,
            "low": self.low,
            "high": self.high,
            "integer": self.integer,
            "doc": self.doc,
        }

    def show(self, value: float) -> str:
        return display(value, self.unit, self.display_unit)


def did_you_mean(name: str, known: list[str] | tuple[str, ...]) -> str:
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.5)  # 0.5: 'q1' still finds 'q0'
    return f" (did you mean '{close[0]}'?)" if close else ""


def refuse_unknown(given, known: list[str] | tuple[str, ...], where: str) -> None:
    """A one-line error for the first parameter of *given* that is not *known*: the closest known one and the list."""
    for key in given:
        if key not in known:
            raise GearlabInputError(
                f"{where}: unknown parameter '{key}'{did_you_mean(key, known)}; known: {', '.join(known) or 'none'}"
            )


def plugin_description(plugin, **more) -> dict:
    """What every plugin's describe() holds (its doc, its parameters), and *more* of its kind's."""
    return {"doc": plugin.doc, "params": [p.describe() for p in plugin.params], **more}


def resolve_params(schema: tuple[Param, ...], given: Mapping[str, object], where: str) -> dict[str, float]:
    """Fill defaults, parse units, check names, types and the schema's static bounds."""
    by_name = {p.name: p for p in schema}
    if not isinstance(given, Mapping):
        raise GearlabInputError(f"{where}: expected a table of parameters {{name = value, ...}}, got {given!r}")
    refuse_unknown(given, list(by_name), where)
    values: dict[str, float] = {}
    for p in schema:
        here = f"{where}, parameter '{p.name}'"
        value = to_si(given[p.name], p.unit, here) if p.name in given else p.default
        if p.integer:
            if value != int(value):
                raise GearlabInputError(f"{here}: expected a whole number, got {value:g}")
            value = int(value)
        if not (p.low <= value <= p.high):
            raise GearlabInputError(f"{here}: {p.show(value)} is outside [{p.show(p.low)}, {p.show(p.high)}]")
        values[p.name] = value
    return values
