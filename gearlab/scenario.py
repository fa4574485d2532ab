"""Scenario TOML files: schema, validation before any work, resolution of plugins by name.

A scenario has a ``[scenario]`` table (name, description, kind) and the tables its kind
declares. Each kind module (gearlab.kinds.*) gives a schema of tables whose keys are the
fields of settings dataclasses (gearlab.settings.setting, turned into keys by keys_of); every
key is checked for type and range here, unknown keys get a "did you mean", and every
error names the file, the table and the key. ``gearlab validate`` prints the same errors.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .confined import Confined
from .errors import GearlabInputError, did_you_mean, shown
from .files import toml_tables
from .settings import declared, in_bounds, setting

_REQUIRED = object()


@dataclass(frozen=True)
class Key:
    """One key of a scenario table: its type(s), default and an optional converter/check. Made by
    keys_of from a settings dataclass (gearlab.settings), the one place a setting is declared."""

    types: type | tuple[type, ...]
    default: Any = _REQUIRED
    check: Callable[[Any, str], Any] | None = None  # returns the converted value or raises
    doc: str = ""
    unit: str = ""  # the SI unit a plain number is read in (docs/settings.md)

    @property
    def required(self) -> bool:
        return self.default is _REQUIRED


@dataclass(frozen=True)
class Table:
    keys: Mapping[str, Key]
    array: bool = False  # [[table]]: an array of tables
    required: bool = False
    doc: str = ""
    moved: Mapping[str, str] | None = None  # a key this table had: where its setting is now (one line)


def keys_of(cls, names: tuple[str, ...] | None = None, **defaults) -> dict[str, Key]:
    """The scenario keys of the settings dataclass *cls* (gearlab.settings): each field's type,
    default, bounds, choices and doc; *names* picks and orders them, *defaults* replace the
    declared defaults (a kind with other defaults for the same table)."""
    fields = declared(cls)
    out = {}
    for name in names or tuple(fields):
        meta, default = fields[name]
        default = defaults.get(name, default)
        check = None
        if meta.low is not None or meta.high is not None or meta.choices or meta.check:

            def check(value, where, meta=meta):
                return in_bounds(meta, value, where)

            check.choices = meta.choices  # what a front-end may offer (the TUI's run form)
            check.setting = meta  # its bounds and --quick limit, for docs/settings.md
        default = _REQUIRED if default is dataclasses.MISSING else default
        out[name] = Key(meta.types, default, check, meta.doc, meta.unit)
    return out


def one_of(*choices: str) -> Callable[[Any, str], Any]:
    def check(value, where):
        if value not in choices:
            raise GearlabInputError(
                f"{where}: {shown(value)} is not one of {', '.join(choices)}"
                f"{did_you_mean(value, choices) if len(value) <= 100 else ''}"
            )
        return value

    check.choices = choices  # what a front-end may offer (the TUI's run form)
    return check


# The characters of a name that becomes part of a file or folder name (a scenario's, a
# dataset's, a stiffness case's): letters and digits of any script, spaces and these marks.
# No separator can occur, and a name may not start with '.', so it is never '..' nor hidden.
NAME_MARKS = " _-.+(),@="
NAME_MAX = 100


def plain_name(value: str, where: str) -> str:
    """A name that may become one component of a path in a run directory (see NAME_MARKS)."""
    if not (
        value
        and len(value) <= NAME_MAX
        and value[0] not in " ."
        and value[-1] != " "
        and all(c.isalnum() or c in NAME_MARKS for c in value)
    ):
        raise GearlabInputError(
            f"{where}: expected a plain name usable as a file name (letters, digits, spaces and "
            f"'{NAME_MARKS.strip()}', not starting with '.' or a space, at most {NAME_MAX} "
            f"characters), got {shown(value)}"
        )
    return value


@dataclass(frozen=True, kw_only=True)
class ScenarioHead:
    """[scenario]"""

    name: str = setting(str, check=plain_name, doc="run name, used for runs/<name>/")
    description: str = setting(str, "")
    kind: str = setting(
        str, doc="the scenario kind: a name of gearlab.kinds.SCENARIO_KINDS (gearlab validate lists them)"
    )


def folder(value: str, where: str) -> str:
    """A folder name the file system can take (Python refuses a NUL character in a path)."""
    if not value or "\0" in value:
        raise GearlabInputError(
            f"{where}: expected a folder, got {shown(value)}" + (" (a NUL character)" if value else "")
        )
    return value


@dataclass(frozen=True, kw_only=True)
class Output:
    """[output]"""

    dir: str = setting(str, "runs", check=folder, doc="base directory of run directories")


@dataclass(frozen=True, kw_only=True)
class Execution:
    """[execution]"""

    executor: str = setting(str, "local", choices=("local", "ray"), doc="local process pool or a Ray cluster")
    workers: int = setting(int, 0, low=0, doc="processes for the local executor (CPUs of a local Ray); 0 = all cores")
    address: str = setting(str, "", doc="Ray cluster address, below --ray-address and RAY_ADDRESS; '' = a local Ray")
    device: str = setting(str, "auto", choices=("auto", "cpu", "cuda"), doc="where networks train")


SCENARIO_TABLE = Table(keys_of(ScenarioHead), required=True)
OUTPUT_TABLE = Table(keys_of(Output))
EXECUTION_TABLE = Table(keys_of(Execution))


@dataclass
class Scenario:
    path: Path
    name: str
    kind: str
    description: str
    tables: dict[str, Any]  # validated tables with defaults filled in
    spec: Any = None  # the kind's parsed specification (gear pair, placed faults, ...)
    raw: dict = field(default_factory=dict)
    # the folder relative file paths resolve against: the scenario file's, also when a run
    # directory's copy of it is loaded (RunDir.scenario, --resume)
    base: Path | None = None
    # what its kind's units load first (ScenarioKind.unit_modules, set with the spec): its run's workers load it
    # before their first unit (gearlab.kinds.common.executor_for)
    unit_modules: tuple[str, ...] = ()

    def where(self, table: str, key: str | None = None, index: int | None = None) -> str:
        return location(self.path, table, key, index)

    def runs_folder(self, out: str | Path | None = None) -> Path:
        """The folder that holds this scenario's runs (<folder>/<name>/<timestamp>/): *out* (--out),
        else its [output] dir; a relative one is taken from the current folder. The TUI looks up
        past runs with this, so it finds them where `gearlab run` puts them."""
        return Path(out) if out is not None else Path(self.tables["output"]["dir"])


def location(path: Path | str, table: str, key: str | None = None, index: int | None = None) -> str:
    t = f"[[{table}]] #{index + 1}" if index is not None else f"[{table}]"
    return f"{path}: {t}" + (f" key '{key}'" if key else "")


def _type_name(types) -> str:
    types = types if isinstance(types, tuple) else (types,)
    names = {str: "a string", int: "an integer", float: "a number", bool: "true/false", list: "a list", dict: "a table"}
    return " or ".join(names.get(t, t.__name__) for t in types)


def check_type(value, types, where):
    types = types if isinstance(types, tuple) else (types,)
    ok = isinstance(value, types) and not (isinstance(value, bool) and bool not in types)
    if float in types and isinstance(value, int) and not isinstance(value, bool):
        ok = True
    if not ok:
        raise GearlabInputError(f"{where}: expected {_type_name(types)}, got {type(value).__name__} {shown(value)}")


def validate_table(path, name: str, table: Table, data: Mapping, index: int | None = None) -> dict:
    """Check one table's keys against its schema; return the values with defaults filled."""
    if not isinstance(data, Mapping):
        raise GearlabInputError(f"{location(path, name, index=index)}: expected a table, got {type(data).__name__}")
    for key in data:
        if key in (table.moved or {}):  # an older file: one line that names the key to use
            raise GearlabInputError(f"{location(path, name, key, index)}: {table.moved[key]}")
        if key not in table.keys:
            raise GearlabInputError(
                f"{location(path, name, key, index)}: unknown key{did_you_mean(key, list(table.keys))}; "
                f"known keys: {', '.join(table.keys)}"
            )
    out = {}
    for key, spec in table.keys.items():
        where = location(path, name, key, index)
        if key not in data:
            if spec.required:
                raise GearlabInputError(f"{where}: missing; expected {_type_name(spec.types)}. {spec.doc}".rstrip(". "))
            out[key] = spec.default
            continue
        value = data[key]
        check_type(value, spec.types, where)
        out[key] = spec.check(value, where) if spec.check else value
    return out


def validate_tables(path, schema: Mapping[str, Table], data: Mapping) -> dict:
    for name in data:
        if name not in schema:
            raise GearlabInputError(
                f"{path}: unknown table [{name}]{did_you_mean(name, list(schema))}; known tables: {', '.join(schema)}"
            )
    tables = {}
    for name, table in schema.items():
        if name not in data:
            if table.required:
                raise GearlabInputError(
                    f"{path}: missing table [{'[' if table.array else ''}{name}{']' if table.array else ''}]"
                )
            tables[name] = [] if table.array else validate_table(path, name, table, {})
            continue
        value = data[name]
        if table.array:
            if not isinstance(value, list):
                raise GearlabInputError(f"{path}: '{name}' must be an array of tables [[{name}]]")
            tables[name] = [validate_table(path, name, table, item, i) for i, item in enumerate(value)]
        else:
            if isinstance(value, list):
                raise GearlabInputError(f"{path}: '{name}' must be a single table [{name}], not an array")
            tables[name] = validate_table(path, name, table, value)
    return tables


def _nearby(path: Path) -> str:
    """' (did you mean 'scenarios/quick.toml'?)' for a mistyped file name: the scenario file
    of the folder it names whose name is closest (compared without the .toml)."""
    import difflib

    try:
        files = {p.stem: p for p in path.parent.glob("*.toml")} if path.parent.is_dir() else {}
    except OSError:
        return ""
    stem = path.stem if path.suffix == ".toml" else path.name
    close = difflib.get_close_matches(stem, list(files), n=1, cutoff=0.5) or [
        s for s in files if s.lower() == stem.lower()
    ]
    return f" (did you mean '{files[close[0]]}'?)" if close else ""


def read_toml(source: Path | Confined) -> dict:
    """The tables of a scenario file: one the user names, or a run directory's copy (a
    Confined, read without following a link)."""
    path = source.path if isinstance(source, Confined) else source
    return toml_tables(
        path,
        source.read_bytes if isinstance(source, Confined) else path.read_bytes,
        f"no such scenario file{_nearby(path)}",
        "is a directory, expected a scenario .toml file",
    )
