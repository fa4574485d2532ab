"""docs/settings.md, generated from the declarations: every table of every scenario kind, one row per
key (type, default, unit, bounds, --quick limit, meaning), read off the kinds' TABLES (each key a
`gearlab.settings.setting` field of a settings dataclass, made a scenario key with its bounds and
--quick limit by `gearlab.scenario.keys_of`). A table that repeats one printed before (the dataset
keys of every [source], a [network]) is written as that table and what differs. Then every key of a
gearbox description file, read off its tables' declarations (gearlab.gearbox.description.DOC_TABLES).

    python -m gearlab.settings_doc            # rewrite docs/settings.md
    python -m gearlab.settings_doc --check    # exit 1 when docs/settings.md is out of date

Plugin parameters (`params` of [[methods]], an effect's or a fault's) belong to the installed
plugins, not to the scenario schema: `gearlab plugins` lists them.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from pathlib import Path

from .files import atomic_write
from .gearbox.description import DOC_TABLES
from .kinds import SCENARIO_KINDS
from .scenario import EXECUTION_TABLE, OUTPUT_TABLE, SCENARIO_TABLE, Key, Table

DOC = Path(__file__).resolve().parent.parent / "docs" / "settings.md"

HEADER = """# Settings reference

Every key of every scenario table and of a gearbox description file, generated from the declarations by `python -m
gearlab.settings_doc` (`tests/test_settings.py` fails when this page is out of date). *unit*: what a plain number is
read in (`'25 Hz'` is converted); *quick*: `--quick` takes at most this; an empty default: not set (the preset's or the
kind's own value). Plugin parameters: `gearlab plugins`.
"""

_TYPES = {str: "str", int: "int", float: "float", bool: "bool", list: "list", tuple: "list", dict: "table"}
# the least shared rows for a table to be written as an earlier one and its differences
_SHARED = 3


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _type(types) -> str:
    types = types if isinstance(types, tuple) else (types,)
    if int in types and float in types:
        types = ("number", *(t for t in types if t not in (int, float)))
    return " or ".join(dict.fromkeys(t if isinstance(t, str) else _TYPES.get(t, t.__name__) for t in types))


def _toml(value) -> str:
    """A default as a scenario file writes it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + "}"
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    return "" if value is None else repr(value)


def _num(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _span(low, high) -> str:
    if low is not None and high is not None:
        return f"[{_num(low)}, {_num(high)}]"
    return f"≥ {_num(low)}" if low is not None else f"≤ {_num(high)}" if high is not None else ""


def row(name: str, key: Key) -> str:
    """One key's row: key, type, default, unit, bounds, --quick, meaning."""
    meta = getattr(key.check, "setting", None)  # keys_of's check carries its field's declaration
    bounds = "" if meta is None else " \\| ".join(meta.choices) if meta.choices else _span(meta.low, meta.high)
    quick = "" if meta is None or meta.quick is None else f"≤ {_num(meta.quick)}"
    default = "required" if key.required else _cell(_toml(key.default))
    return f"| `{name}` | {_type(key.types)} | {default} | {key.unit} | {bounds} | {quick} | {_cell(key.doc)} |"


_HEAD = "| key | type | default | unit | bounds | quick | meaning |\n|---|---|---|---|---|---|---|"


def _title(name: str, table: Table) -> str:
    shown = f"[[{name}]]" if table.array else f"[{name}]"
    return f"### `{shown}`" + (" (required)" if table.required else "")


def tables() -> list[tuple[str, list[tuple[str, Table]]]]:
    """(section, [(table name, Table)]) in the page's order: the tables every kind has, then each
    kind's own."""
    common = [("scenario", SCENARIO_TABLE), ("output", OUTPUT_TABLE), ("execution", EXECUTION_TABLE)]
    return [
        ("Every kind", common),
        *((f'kind = "{kind}"', list(module.TABLES.items())) for kind, module in SCENARIO_KINDS.items()),
    ]


def reference() -> str:
    """The text of docs/settings.md."""
    out = [HEADER]
    written: list[tuple[str, dict[str, str]]] = []  # (how a later table names it, its rows)
    for section, entries in tables():
        out.append(f"## {section}\n")
        kind = section.split('"')[1] if section.startswith("kind") else ""
        for name, table in entries:
            rows = {key: row(key, spec) for key, spec in table.keys.items()}
            title = _title(name, table)
            base, shared = None, 0
            for label, earlier in written:
                same = sum(1 for k, r in rows.items() if earlier.get(k) == r)
                if same > shared:
                    base, shared = (label, earlier), same
            if base is not None and shared >= min(_SHARED, len(rows)):
                label, earlier = base
                left = [k for k in earlier if k not in rows]
                new = [r for k, r in rows.items() if earlier.get(k) != r]
                said = f"The keys of {label}" + (f" without {', '.join(f'`{k}`' for k in left)}" if left else "")
                tail = ", and these (other or new):\n\n" + _HEAD + "\n" + "\n".join(new) + "\n" if new else ".\n"
                out.append(f"{title}\n{said}{tail}")
            else:  # a heading may run straight into its table
                out.append(f"{title}\n" + _HEAD + "\n" + "\n".join(rows.values()) + "\n")
            shown = f"[[{name}]]" if table.array else f"[{name}]"
            written.append((f"`{shown}` ({kind})" if kind else f"`{shown}`", rows))
    out.append(gearbox_reference())
    return "\n".join(out)


GEARBOX_HEAD = """## A gearbox description file

docs/gearbox.md. Write a quantity with its unit (`"2 mm"`, `"20 deg"`): a bare number is read in the SI *unit*.

| table | key | type | default | unit | bounds | meaning |
|---|---|---|---|---|---|---|"""


def gearbox_row(table: str, name: str, meta, default, fitted: dict[str, str]) -> str:
    """One key of a gearbox description's *table*: default and bounds in the unit people read where it is
    not the SI one ('20 deg')."""

    def shown(value) -> str:
        if value is dataclasses.MISSING:
            return "required"
        if value is None or value == "" or (isinstance(value, float) and math.isnan(value)):
            return ""
        if isinstance(value, str):
            return _cell(_toml(value))
        return meta.show(value) if meta.display_unit not in ("", meta.unit) else _num(value)

    low, high = (None if v is None else shown(v) for v in (meta.low, meta.high))
    bounds = " \\| ".join(meta.choices) if meta.choices else f"[{low}, {high}]" if low and high else ""
    bounds = bounds or (f"≥ {low}" if low else f"≤ {high}" if high else "")
    doc = meta.doc + (f"; a gap run fits it: `{fitted[name]}`" if name in fitted else "")
    return f"| {table} | `{name}` | {_type(meta.types)} | {shown(default)} | {meta.unit} | {bounds} | {_cell(doc)} |"


def gearbox_reference() -> str:
    """The section of the gearbox description's keys (DOC_TABLES), a table's name on its first row."""
    rows = [
        gearbox_row(f"`{table}`" if i == 0 else "", name, meta, default, fitted)
        for table, keys, fitted in DOC_TABLES
        for i, (name, (meta, default)) in enumerate(keys.items())
    ]
    return GEARBOX_HEAD + "\n" + "\n".join(rows) + "\n"


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    check = "--check" in args
    paths = [a for a in args if a != "--check"]
    path = Path(paths[0]) if paths else DOC
    text = reference()
    if check:
        if not path.exists() or path.read_text() != text:
            print(f"{path} is out of date: run python -m gearlab.settings_doc", file=sys.stderr)
            return 1
        return 0
    atomic_write(path, text)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
