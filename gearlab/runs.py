"""Run directories and the run engine shared by the CLI and the TUI.

A run writes ``runs/<name>/<timestamp>/``: the resolved scenario, ``results.jsonl`` (one
record per finished unit, appended, flushed and fsynced as the unit finishes),
``summary.json``, tables, ``figures/`` and ``report.html``. Whole files are written to a
temporary name and renamed, so a killed run never leaves a half-written file; the
results store is append-only, so ``--resume`` redoes nothing that finished.

Progress goes out as :class:`Event` objects to one callback: the CLI draws rich
progress bars from them, the TUI its widgets.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import shutil
import tempfile
import tomllib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import tomli_w

from .errors import GearlabInputError
from .scenario import Scenario, load_scenario


@dataclass(frozen=True)
class Event:
    """A progress event. kind: 'stage' (a stage starts), 'advance' (units done within the
    stage), 'record' (a unit finished; `record` holds it), 'log' (a line for people)."""

    kind: str
    stage: str = ""
    done: int = 0
    total: int = 0
    message: str = ""
    record: dict | None = None


EventSink = Callable[[Event], None]


def _ignore(_: Event) -> None:
    pass


def atomic_write(path: Path, data: bytes | str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data.encode() if isinstance(data, str) else data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


RUN_FILE = "run.json"  # how the run was started (--quick), for --resume


@dataclass
class RunDir:
    path: Path
    created: Path | None = None  # the outermost folder create() made, for discard()

    @property
    def results_path(self) -> Path:
        return self.path / "results.jsonl"

    @property
    def figures(self) -> Path:
        return self.path / "figures"

    @classmethod
    def create(cls, base: Path, scenario: Scenario, quick: bool = False) -> RunDir:
        stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
        path = Path(base) / scenario.name / stamp
        created = next((p for p in reversed([path, *path.parents]) if not p.exists()), path)
        try:
            path.mkdir(parents=True, exist_ok=False)
            probe = path / ".write-test"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            cls(path, created=created).discard()
            raise GearlabInputError(f"cannot write the run directory under '{base}': {exc.strerror or exc}") from None
        run = cls(path, created=created)
        atomic_write(path / "scenario.toml", tomli_w.dumps(_tomlable(scenario.tables)))
        run.write_json(RUN_FILE, {"quick": quick})
        try:
            shutil.copyfile(scenario.path, path / "scenario.original.toml")
        except OSError:
            pass
        return run

    def discard(self) -> None:
        """Remove a run directory this process created, and the folders made for it if empty."""
        shutil.rmtree(self.path, ignore_errors=True)
        if self.created is None:
            return
        for folder in self.path.parents:
            if not folder.is_relative_to(self.created):
                break
            try:
                folder.rmdir()
            except OSError:  # not empty: another run lives there
                break

    @property
    def quick(self) -> bool:
        """Whether the run was started with --quick (a resume must shrink it alike)."""
        meta = self.path / RUN_FILE
        return bool(json.loads(meta.read_text()).get("quick")) if meta.is_file() else False

    @classmethod
    def open(cls, path: Path) -> RunDir:
        path = Path(path)
        if not (path / "scenario.toml").is_file():
            raise GearlabInputError(f"{path}: not a gearlab run directory (no scenario.toml)")
        return cls(path)

    def scenario_path(self) -> Path:
        """The scenario file to resume from: the original text, else the resolved one."""
        original = self.path / "scenario.original.toml"
        return original if original.is_file() else self.path / "scenario.toml"

    def started_with(self, scenario: Scenario) -> bool:
        """Whether *scenario* resolves to the tables this run was started with (a resume with
        another would mix its units with those finished)."""
        stored = tomllib.loads((self.path / "scenario.toml").read_text())
        return stored == tomllib.loads(tomli_w.dumps(_tomlable(scenario.tables)))

    def records(self) -> list[dict]:
        """Finished units. A line cut short by a kill (no newline yet) is ignored, and so is a
        damaged line, without hiding the records appended after it."""
        if not self.results_path.exists():
            return []
        out = []
        for line in self.results_path.read_text().splitlines(keepends=True):
            if not line.endswith("\n"):
                continue
            try:
                out.append(json.loads(line))
            except json.JSONDecodeError:
                continue
        return out

    def append(self, record: dict) -> None:
        line = json.dumps(record, sort_keys=True) + "\n"
        with open(self.results_path, "a") as f:
            f.write(line)
            f.flush()
            os.fsync(f.fileno())

    def write_json(self, name: str, obj) -> None:
        atomic_write(self.path / name, json.dumps(obj, indent=2, sort_keys=True) + "\n")

    def write_text(self, name: str, text: str) -> None:
        atomic_write(self.path / name, text)

    def truncate_partial(self) -> None:
        """Drop a trailing partial line left by a killed run, so appends stay line-aligned."""
        if not self.results_path.exists():
            return
        data = self.results_path.read_bytes()
        cut = data.rfind(b"\n") + 1
        if cut != len(data):
            atomic_write(self.results_path, data[:cut])


def _tomlable(value):
    if isinstance(value, dict):
        return {k: _tomlable(v) for k, v in value.items() if v is not None}
    if isinstance(value, (list, tuple)):
        return [_tomlable(v) for v in value]
    return value


def run_scenario(
    scenario_path: str | Path | None = None,
    *,
    out: str | Path | None = None,
    resume: str | Path | None = None,
    quick: bool = False,
    on_event: EventSink = _ignore,
) -> RunDir:
    """Validate, then run a scenario into a new (or resumed) run directory."""
    from .kinds import KINDS

    if resume is not None:
        run = RunDir.open(Path(resume))
        if quick and not run.quick:
            raise GearlabInputError(f"--quick: the run in {run.path} was started without --quick; resume it without")
        quick = run.quick
        scenario = load_scenario(scenario_path or run.scenario_path())
        if not run.started_with(scenario):
            raise GearlabInputError(f"{scenario.path}: differs from the scenario the run in {run.path} was started "
                                    "with; resume without SCENARIO (the run keeps a copy) or start a new run")
        run.truncate_partial()
    else:
        if scenario_path is None:
            raise GearlabInputError("no scenario given")
        scenario = load_scenario(scenario_path)
        base = Path(out) if out is not None else Path(scenario.tables["output"]["dir"])
        run = RunDir.create(base, scenario, quick)
    module = KINDS[scenario.kind]
    if quick:
        module.quick(scenario)
    on_event(Event("log", message=f"scenario {scenario.name} ({scenario.kind}) -> {run.path}"))
    try:
        module.run(scenario, run, on_event)
    except GearlabInputError:
        # Refused before any unit finished (e.g. by a check on the built datasets): leave no run behind.
        if resume is None and not run.records():
            run.discard()
        raise
    write_report(run)
    return run


def write_report(run: RunDir) -> Path:
    from .report import build_report

    html = build_report(run.path)
    run.write_text("report.html", html)
    return run.path / "report.html"


def finished_keys(records: Iterable[dict]) -> set[str]:
    return {r["unit"] for r in records if "unit" in r}
