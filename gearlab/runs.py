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
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
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


@dataclass
class RunDir:
    path: Path
    _records: list[dict] = field(default_factory=list)

    @property
    def results_path(self) -> Path:
        return self.path / "results.jsonl"

    @property
    def figures(self) -> Path:
        return self.path / "figures"

    @classmethod
    def create(cls, base: Path, scenario: Scenario) -> RunDir:
        stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
        path = Path(base) / scenario.name / stamp
        try:
            path.mkdir(parents=True, exist_ok=False)
            probe = path / ".write-test"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            raise GearlabInputError(f"cannot write the run directory under '{base}': {exc.strerror or exc}") from None
        run = cls(path)
        atomic_write(path / "scenario.toml", tomli_w.dumps(_tomlable(scenario.tables)))
        try:
            shutil.copyfile(scenario.path, path / "scenario.original.toml")
        except OSError:
            pass
        return run

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

    def records(self) -> list[dict]:
        """Finished units. A line cut short by a kill (no newline yet) is ignored."""
        if not self.results_path.exists():
            return []
        out = []
        for line in self.results_path.read_text().splitlines(keepends=True):
            if not line.endswith("\n"):
                break
            try:
                out.append(json.loads(line))
            except json.JSONDecodeError:
                break
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
        scenario = load_scenario(scenario_path or run.scenario_path())
        run.truncate_partial()
    else:
        if scenario_path is None:
            raise GearlabInputError("no scenario given")
        scenario = load_scenario(scenario_path)
        base = Path(out) if out is not None else Path(scenario.tables["output"]["dir"])
        run = RunDir.create(base, scenario)
    module = KINDS[scenario.kind]
    if quick:
        module.quick(scenario)
    on_event(Event("log", message=f"scenario {scenario.name} ({scenario.kind}) -> {run.path}"))
    module.run(scenario, run, on_event)
    write_report(run)
    return run


def write_report(run: RunDir) -> Path:
    from .report import build_report

    html = build_report(run.path)
    run.write_text("report.html", html)
    return run.path / "report.html"


def finished_keys(records: Iterable[dict]) -> set[str]:
    return {r["unit"] for r in records if "unit" in r}
