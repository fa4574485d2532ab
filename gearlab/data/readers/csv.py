"""CSV: a header row of column names, numeric columns, '#' comment lines; the rate from a 't'/'time'
column or a comment '# fs = 51200'."""

from __future__ import annotations

import csv
import re
from collections.abc import Sequence
from pathlib import Path

from ...errors import GearlabInputError
from .base import Contents, _column, _keyed, _scalar

_COMMENT_FIELD = re.compile(r"^#\s*([A-Za-z_][\w.-]*)\s*[=:]\s*(.*?)\s*$")


def _read_csv(path: Path, names: Sequence[str]) -> Contents:
    """Header row of names, numeric columns, '#' comments ('# fs = 51200' gives a field 'fs')."""
    text = path.read_text(encoding="utf-8-sig")  # a BOM from spreadsheet exports is dropped
    fields: dict[str, object] = {}
    lines: list[tuple[int, str]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            match = _COMMENT_FIELD.match(stripped)
            if match:
                fields[match.group(1)] = _scalar(match.group(2))
            continue
        lines.append((number, line))
    if not lines:
        raise GearlabInputError(f"{path}: no header row; expected a first line of column names, then numbers")
    header_line = lines[0][1]
    delimiter = next((d for d in (",", ";", "\t") if d in header_line), ",")
    rows = list(csv.reader((line for _, line in lines), delimiter=delimiter))
    header = [h.strip() for h in rows[0]]
    if len(set(header)) != len(header):
        twice = next(h for h in header if header.count(h) > 1)
        raise GearlabInputError(f"{path}: column '{twice}' appears twice in the header; expected distinct names")
    for (number, _), row in zip(lines[1:], rows[1:]):
        if len(row) != len(header):
            raise GearlabInputError(
                f"{path}: line {number} has {len(row)} fields but the header has {len(header)}; "
                "expected one value per column (a truncated or ragged file?)"
            )
    if len(rows) < 2:
        raise GearlabInputError(f"{path}: has a header but no data rows; expected one row per sample")
    if not any(_column([row[j].strip() for row in rows[1:2]]).dtype.kind == "f" for j in range(len(header))):
        # not a measured record (a system file reached through a link?): nothing of it is quoted
        raise GearlabInputError(
            f"{path}: its first data row (line {lines[1][0]}) holds no number; expected a header "
            "row of column names, then rows of numbers"
        )
    index = {h: j for j, h in enumerate(header)}

    def get(name: str):
        if name in index:
            j = index[name]
            return _column([row[j].strip() for row in rows[1:]])
        return fields[name]

    return _keyed([*header, *fields], get, names)
