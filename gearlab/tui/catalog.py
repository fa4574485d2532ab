"""What the TUI browses: scenario files with their validation status, and their past runs.

Nothing here draws; the app turns these entries into tree nodes and views.
"""

from __future__ import annotations

import re
import threading
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import GearlabInputError
from ..files import matched
from ..notebook import load_scenario
from ..runs import RunDir
from ..scenario import Scenario


@dataclass
class ScenarioEntry:
    path: Path
    scenario: Scenario | None = None
    error: str = ""  # the validation error, file/table/key included
    runs: list[RunEntry] = field(default_factory=list)
    # a gearbox description ([gearbox] or [[stages]], no [scenario]): validate's OK line, or "" with its error
    gearbox: str | None = None
    checked: bool = False  # validated (check): until then it is listed by name alone, its mark pending

    @property
    def ok(self) -> bool:
        return self.scenario is not None


@dataclass
class RunEntry:
    path: Path
    units: int  # finished units in results.jsonl
    finished: bool  # the run ended and wrote its summary (else cancelled, killed or running)


def _stamp(path: Path) -> tuple | None:
    """A file's state as validation reads it: (modification time, size), None when it is missing."""
    try:
        found = path.stat()
    except OSError:
        return None
    return (found.st_mtime_ns, found.st_size)


def _named_files(path: Path, base: Path) -> list[Path]:
    """The files a scenario's strings name (a gearbox description, a measured record), absolute or
    from *base*: an edit of one changes the scenario's validation as much as an edit of the file."""
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return []
    found, todo = [], [data]
    while todo:
        item = todo.pop()
        if isinstance(item, dict):
            todo.extend(item.values())
        elif isinstance(item, list):
            todo.extend(item)
        elif isinstance(item, str) and 0 < len(item) < 4096 and "\n" not in item:
            try:  # a glob pattern's files: a take added to its folder changes the scenario too
                names = matched(item.split("#", 1)[0], base, "")
            except (GearlabInputError, OSError, ValueError):
                names = []
            found.extend(base / n for n in names if (base / n).is_file())
    return found


class Unsettled(Exception):
    """Validated was asked for a result it keeps, and keeps none for the files' present state."""


class Validated:
    """Scenario files validated once per state of the files they are read from (their own and the
    files their strings name: path, modification time, size): a stiffness scenario's validation
    builds its fault ladders (0.07 s each), and the tree asked for it again on every rescan and every
    highlight of one of its runs, so moving through the tree waited for it. An edited file is
    validated again; `Validate` in the command palette always reads the file afresh (forget).

    The tree's marks are validated in a thread (checking.py) while the app's thread may ask for one
    at once (a scenario selected before its mark came): one validation at a time, so that a file is
    never validated twice at once and two threads never import a kind's modules into each other."""

    def __init__(self):
        self._seen: dict[tuple, tuple[tuple, Scenario | None, Exception | None]] = {}
        self._loading = threading.Lock()

    def _load(self, key: tuple, files, load, wait: bool = True) -> Scenario:
        """load()'s result (or its exception, raised again) for the present state of files(); with
        wait=False, Unsettled where it would have to be read (no file is read for a key never seen)."""
        if not wait and key not in self._seen:
            raise Unsettled(key)
        state = tuple(_stamp(f) for f in files())
        seen = self._seen.get(key)
        if seen is None or seen[0] != state:
            if not wait:
                raise Unsettled(key)
            with self._loading:
                seen = self._seen.get(key)  # the other thread may have read it meanwhile
                if seen is None or seen[0] != state:
                    try:
                        seen = (state, load(), None)
                    except Exception as exc:  # noqa: BLE001 - kept to raise again for the same files
                        seen = (state, None, exc)
                    self._seen[key] = seen
        if seen[2] is not None:
            raise seen[2]
        return seen[1]

    def scenario(self, path: Path, wait: bool = True) -> Scenario:
        """load_scenario(path), read again only when a file it reads changed."""
        path = Path(path)
        return self._load(
            ("file", path), lambda: [path, *_named_files(path, path.parent)], lambda: load_scenario(path), wait
        )

    def of_run(self, run: RunDir) -> Scenario:
        """The scenario *run* ran (load_scenario(run=...)), read again only when its files changed."""

        def files() -> list[Path]:
            names = [run.path / name for name in ("scenario.toml", "scenario.original.toml", "run.json")]
            return names + _named_files(run.scenario_path(), run.base() or run.path)

        return self._load(("run", run.path), files, lambda: load_scenario(run=run))

    def description(self, path: Path, wait: bool = True) -> str | None:
        """validated_description(path): a gearbox description's OK line (its mistake raised), None for a
        scenario; read again only when a file it reads changed."""

        def load() -> str | None:
            from ..gearbox import validated_description

            return validated_description(path)

        path = Path(path)
        return self._load(("gearbox", path), lambda: [path, *_named_files(path, path.parent)], load, wait)

    def forget(self, path: Path) -> None:
        self._seen.pop(("file", Path(path)), None)
        self._seen.pop(("gearbox", Path(path)), None)


def scan(directory: Path, cwd: Path, validated: Validated | None = None) -> list[ScenarioEntry]:
    """Every *.toml under *directory* but a run's copies (in_run), validated (by *validated*, once per
    state of its files), with the runs found under its output dir (a relative one taken from *cwd*, the
    folder the TUI starts its runs in)."""
    validated = validated or Validated()
    entries = listing(directory)
    for entry in entries:
        check(entry, validated, cwd)
    return entries


def listing(directory: Path) -> list[ScenarioEntry]:
    """Every *.toml under *directory* but a run's copies (in_run), by name alone: nothing read yet."""
    found = sorted(Path(directory).rglob("*.toml"))
    return [ScenarioEntry(path) for path in found if not in_run(path, Path(directory))]


def check(entry: ScenarioEntry, validated: Validated, cwd: Path, wait: bool = True) -> bool:
    """Validate *entry*'s file (by *validated*, once per state of its files) and find its runs under its
    output dir (a relative one taken from *cwd*, the folder the TUI starts its runs in). With wait=False
    only a kept result is used: False, the entry left unchecked, where the file must be read."""
    path = entry.path
    # the gearbox description a user writes beside the scenarios that name it (docs/your_gearbox.md) is
    # one, checked as `gearlab validate` checks it: it was listed as an invalid scenario, 'missing table
    # [scenario]', in red beside the valid ones
    try:
        entry.gearbox = validated.description(path, wait)
    except Unsettled:
        return False
    except GearlabInputError as exc:
        entry.gearbox, entry.error = "", str(exc)
    except Exception:  # noqa: BLE001 - read as a scenario below, which says what is wrong
        entry.gearbox = None
    if entry.gearbox is None:
        try:
            entry.scenario = validated.scenario(path, wait)
        except Unsettled:
            return False
        except GearlabInputError as exc:
            entry.error = str(exc)
        except Exception as exc:  # noqa: BLE001 - a browser must list every file, whatever is wrong with it
            entry.error = f"{path}: cannot be read: {type(exc).__name__}: {exc}"
        if entry.scenario is not None:
            entry.runs = runs_of(entry.scenario, cwd)
    entry.checked = True
    return True


def in_run(path: Path, directory: Path) -> bool:
    """Whether *path* lies in a run directory (one holding run.json) below *directory*: a run's
    scenario.toml and scenario.original.toml are that run, listed under its scenario (runs_of), not
    scenarios of their own (`gearlab tui .` in a project listed two per run under runs/). The TUI
    opened on a run directory itself still lists them."""
    for folder in path.parents:
        if folder == directory or directory not in folder.parents:
            return False
        if (folder / "run.json").is_file():
            return True
    return False


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
