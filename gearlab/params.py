"""The Setting record every setting is declared with (gearlab.settings.setting: a scenario key's,
a plugin parameter's, a gearbox description key's) and the did-you-mean messages of unknown names."""

from __future__ import annotations

import difflib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .errors import GearlabInputError
from .units import display


@dataclass(frozen=True)
class Setting:
    """What a setting declares besides its name and default (gearlab.settings.setting). Values are
    stored in SI (*unit*); *display_unit* is for people."""

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
