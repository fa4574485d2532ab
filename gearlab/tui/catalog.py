"""What the TUI browses: scenario files with their validation status, and their past runs.

Nothing here draws; the app turns these entries into tree nodes and views.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import GearlabInputError
from ..notebook import load_scenario
from ..runs import RunDir
from ..scenario import Scenario


@dataclass
class ScenarioEntry:
    path: Path
    scenario: Scenario | None = None
    error: str = ""  # the validation error, file/table/key included
    runs: list[RunEntry] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.scenario is not None


@dataclass
class RunEntry:
    path: Path
    units: int  # finished units in results.jsonl
    finished: bool  # the run ended and wrote its summary (else cancelled, killed or running)


def scan(directory: Path, cwd: Path) -> list[ScenarioEntry]:
    """Every *.toml under *directory*, validated, with the runs found under its output dir
    (a relative one taken from *cwd*, the folder the TUI starts its runs in)."""
    entries = []
    for path in sorted(Path(directory).rglob("*.toml")):
        entry = ScenarioEntry(path)
        try:
            entry.scenario = load_scenario(path)
        except GearlabInputError as exc:
            entry.error = str(exc)
        except Exception as exc:  # noqa: BLE001 - a browser must list every file, whatever is wrong with it
            entry.error = f"{path}: cannot be read: {type(exc).__name__}: {exc}"
        if entry.scenario is not None:
            entry.runs = runs_of(entry.scenario, cwd)
        entries.append(entry)
    return entries


def runs_base(scenario: Scenario, cwd: Path) -> Path:
    """The absolute folder `gearlab run` started in *cwd* puts *scenario*'s runs in (the
    TUI passes it as --out, so that its runs land exactly where it looks for them)."""
    return Path(cwd) / scenario.runs_folder()


def runs_of(scenario: Scenario, cwd: Path) -> list[RunEntry]:
    """Run directories of *scenario* (<output dir>/<name>/<timestamp>/), newest first."""
    base = runs_base(scenario, cwd) / scenario.name
    if not base.is_dir():
        return []
    out = []
    for path in sorted(base.iterdir(), reverse=True):
        if (path / "scenario.toml").is_file():
            out.append(run_entry(path))
    return out


def run_entry(path: Path) -> RunEntry:
    try:
        records = len(RunDir(path).records())
    except (GearlabInputError, OSError):  # a link planted at results.jsonl: listed, refused when opened
        records = 0
    return RunEntry(path, records, (path / "summary.json").is_file())


_WHERE = re.compile(r"\[\[?(?P<table>[\w.]+)\]?\](?: #(?P<index>\d+))?(?: key '(?P<key>[^']+)')?")


def error_line(toml_text: str, error: str) -> int | None:
    """The 1-based line of *toml_text* that an error message points at ("[table] key 'k'",
    "[[table]] #2 key 'k'"): the key's line inside that table, else the table's header."""
    match = _WHERE.search(error)
    if not match:
        return None
    table, key = match["table"], match["key"]
    index = int(match["index"] or 1)
    lines = toml_text.splitlines()
    header = re.compile(rf"^\s*\[\[?\s*{re.escape(table)}\s*\]?\]\s*(#.*)?$")
    seen, start = 0, None
    for i, line in enumerate(lines):
        if header.match(line):
            seen += 1
            if seen == index:
                start = i
                break
    if start is None:
        return None
    if key:
        for i in range(start + 1, len(lines)):
            if lines[i].lstrip().startswith("["):
                break
            if re.match(rf"^\s*{re.escape(key)}\s*=", lines[i]):
                return i + 1
    return start + 1
