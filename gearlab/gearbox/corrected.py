"""A gearbox description with [dynamics] values set, as TOML text: what a gap diagnosis writes as
gearbox_corrected.toml (gearlab.gap.corrected; docs/your_gearbox.md step 4).

The user's file stays line for line: a set key's line in [dynamics] (or [operation]: load_level) is replaced by
``key = "VALUE UNIT"  # COMMENT (was OLD; the user's comment)``, a key not written yet is added after
the table's last key (a [dynamics] table is added at the end when there is none), and *head* and
*tail* comment lines go before and after it. A value is written in the unit the user wrote that key
in, else in the key's SI unit (DYNAMICS), to 6 significant digits: read back, it is the value to 5e-7.
"""

from __future__ import annotations

import re
import tomllib

from ..errors import GearlabInputError
from ..units import to_si
from .description import DYNAMICS

_UNITS = {name: p.unit for name, (p, _) in DYNAMICS.items()}
_HEADER = re.compile(r"^\s*\[\[?\s*([^\]]*?)\s*\]\]?\s*(#.*)?$")  # a [table] or [[array]] line
_KEY = re.compile(r"^\s*([A-Za-z0-9_-]+)\s*=")
_WRITTEN = re.compile(r"^\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*(.*?)\s*$")  # "200 kN/m" -> "kN/m"


def number(value: float) -> str:
    """*value* to 6 significant digits, exponents short: 4.1e7, 0.0043, 1e-5."""
    text = f"{value:.6g}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}e{int(exponent)}"
    return text


def quantity(key: str, value: float, written: object = None) -> str:
    """The TOML value of [dynamics] *key* at *value* (SI): in the unit of *written* (the user's value
    of the key, when it has one), else in the key's SI unit; a bare number for a ratio."""
    unit = _UNITS[key]
    if not unit:
        return number(value)
    if isinstance(written, str):
        found = _WRITTEN.match(written)
        if found and found.group(1):
            try:
                factor = to_si(f"1 {found.group(1)}", unit, key)
            except GearlabInputError:
                factor = None
            if factor:
                return f'"{number(value / factor)} {found.group(1)}"'
    return f'"{number(value)} {unit}"'


def with_dynamics(text: str, values: dict[str, str], comments: dict[str, str], head=(), tail=()) -> str:
    """*text* (a description) with each [dynamics] key of *values* (TOML value text) set, the line
    ending in '# ' and its comment; *head* and *tail* lines (comments) before and after."""
    return "\n".join([*head, *with_table(text, "dynamics", values, comments).splitlines(), *tail]) + "\n"


def with_table(text: str, table: str, values: dict[str, str], comments: dict[str, str]) -> str:
    """*text* with each key of *values* set in [*table*] as with_dynamics sets [dynamics]'s."""
    if not values:
        return text
    lines = text.splitlines()
    start = next((i for i, line in enumerate(lines) if _table(line) == table), None)
    if start is None:
        if table in tomllib.loads(text):
            raise GearlabInputError(f"[{table}] is not written as a [{table}] table (dotted or inline keys)")
        lines += ["", f"[{table}]"]
        start = len(lines) - 1
    end = next((i for i in range(start + 1, len(lines)) if _table(lines[i]) is not None), len(lines))
    last, left = start, dict(values)
    for i in range(start + 1, end):
        key = _KEY.match(lines[i])
        if key:
            last = i
            if key.group(1) in left:
                value, _, note = lines[i].split("=", 1)[1].partition("#")  # the user's value and comment, kept
                was = f" (was {value.strip()}{f'; {note.strip()}' if note.strip() else ''})"
                lines[i] = f"{key.group(1)} = {left.pop(key.group(1))}  # {comments[key.group(1)]}{was}"
    added = [f"{key} = {value}  # {comments[key]}" for key, value in left.items()]
    lines[last + 1 : last + 1] = added
    return "\n".join(lines) + "\n"


def _table(line: str) -> str | None:
    """The name of the table a header *line* opens ([a] or [[a]]), None for any other line."""
    if _KEY.match(line):
        return None
    found = _HEADER.match(line)
    return found.group(1).strip().strip('"') if found else None
