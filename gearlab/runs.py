"""Run directories and the run engine shared by the CLI and the TUI.

A run writes ``runs/<name>/<timestamp>/``: the resolved scenario, ``results.jsonl`` (one
record per finished unit, appended, flushed and fsynced as the unit finishes),
``summary.json``, tables, ``figures/`` and ``report.html``. Whole files are written to a
temporary name and renamed, so a killed run never leaves a half-written file; the
results store is append-only, so ``--resume`` redoes nothing that finished. One process at
a time works in a run directory: it holds an flock on ``.lock`` for the whole run.

Progress goes out as :class:`Event` objects to one callback: the CLI draws rich
progress bars from them, the TUI its widgets.
"""

from __future__ import annotations

import datetime as _dt
import fcntl
import json
import os
import shutil
import tempfile
import threading
import time
import tomllib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

import tomli_w

from .errors import GearlabInputError
from .scenario import Scenario, load_scenario


@dataclass(frozen=True)
class Event:
    """A progress event. kind: 'run' (the run directory is ready; `message` is its path),
    'stage' (a stage starts), 'advance' (units done within the stage), 'record' (a unit
    finished; `record` holds it), 'unit' (a unit in progress says how far it is in `message`,
    `stage` names it; an empty message: it ended), 'log' (a line for people).

    `gearlab run --events` writes them as JSON lines: that is how the TUI follows a run."""

    kind: str
    stage: str = ""
    done: int = 0
    total: int = 0
    message: str = ""
    record: dict | None = None

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, line: str) -> Event:
        data = json.loads(line)
        return cls(**{k: data[k] for k in ("kind", "stage", "done", "total", "message", "record") if k in data})


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
LOCK_FILE = ".lock"  # flocked by the process running in the directory; holds its pid


class RunLock:
    """The run directory held by this process (see RunDir.lock); released on close or exit."""

    def __init__(self, fd: int):
        self.fd: int | None = fd

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)  # closing the only descriptor drops the flock
            self.fd = None

    def __enter__(self) -> RunLock:
        return self

    def __exit__(self, *exc) -> None:
        self.release()


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
        try:
            created = next((p for p in reversed([path, *path.parents]) if not p.exists()), path)
        except OSError as exc:  # e.g. a name too long: nothing made yet
            raise GearlabInputError(f"cannot write the run directory under '{base}': {exc.strerror or exc}") from None
        try:
            path.mkdir(parents=True, exist_ok=False)
            probe = path / ".write-test"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            cls(path, created=created).discard()
            raise GearlabInputError(f"cannot write the run directory under '{base}': {exc.strerror or exc}") from None
        run = cls(path, created=created)
        # scenario.toml last: it marks a run directory (open() looks for it), so a run killed
        # while this runs is never resumed without its --quick setting or original scenario.
        run.write_json(RUN_FILE, {"quick": quick})
        try:
            shutil.copyfile(scenario.path, path / "scenario.original.toml")
        except OSError:
            pass
        atomic_write(path / "scenario.toml", tomli_w.dumps(_tomlable(scenario.tables)))
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

    def lock(self) -> RunLock:
        """Hold the run directory for this process, or refuse when another process holds it.

        An flock, not a marker file: the kernel drops it when the holder dies, however it
        dies (SIGKILL included), so a killed run never blocks its --resume. The lock file
        is left in place: removing it would let two processes lock two different files.
        """
        path = self.path / LOCK_FILE
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        except OSError as exc:
            raise GearlabInputError(f"{self.path}: cannot lock the run directory ({exc.strerror or exc})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip()
            os.close(fd)
            who = f" (pid {holder})" if holder.isdigit() else ""
            raise GearlabInputError(f"{self.path}: another gearlab process{who} is running in this run directory; "
                                    "wait for it to end (or stop it), then resume") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        return RunLock(fd)

    def scenario_path(self) -> Path:
        """The scenario file to resume from: the original text, else the resolved one."""
        original = self.path / "scenario.original.toml"
        return original if original.is_file() else self.path / "scenario.toml"

    def scenario(self) -> Scenario:
        """The scenario as this run ran it (shrunk alike when started with --quick)."""
        from .kinds import KINDS

        scenario = load_scenario(self.scenario_path())
        if self.quick:
            KINDS[scenario.kind].quick(scenario)
        return scenario

    def started_with(self, scenario: Scenario) -> bool:
        """Whether *scenario* resolves to the tables this run was started with (a resume with
        another would mix its units with those finished)."""
        # [execution] says where units run, not what they compute: a run may resume elsewhere
        stored = tomllib.loads((self.path / "scenario.toml").read_text())
        stored.pop("execution", None)
        given = {table: values for table, values in scenario.tables.items() if table != "execution"}
        return stored == tomllib.loads(tomli_w.dumps(_tomlable(given)))

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

    def remove_temporaries(self) -> None:
        """Remove the temporary files of atomic writes cut short by a kill. Only with the run
        directory locked: then no writer of this run is alive."""
        for tmp in self.path.rglob(".*.tmp"):
            tmp.unlink(missing_ok=True)

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


PROGRESS = "progress"  # the run directory's folder of units in progress


class UnitProgress:
    """What a unit in progress reports ('epoch 120, validation accuracy 88 %'), written to a
    small file in the run directory's progress/ folder, from whichever process or cluster node
    runs the unit; the engine watches the folder (ProgressWatcher) and sends 'unit' events.
    Use as a context manager: the file goes when the unit ends."""

    def __init__(self, run_path: Path, unit: str, every: float = 0.5):
        self.path = Path(run_path) / PROGRESS / (unit.replace("/", "__") + ".txt")
        self.every, self.last = every, -every

    def __call__(self, text: str) -> None:
        if time.monotonic() - self.last >= self.every:  # a few writes a second at most
            atomic_write(self.path, text)
            self.last = time.monotonic()

    def __enter__(self) -> UnitProgress:
        return self

    def __exit__(self, *exc) -> None:
        self.path.unlink(missing_ok=True)


class ProgressWatcher(threading.Thread):
    """Turns the progress/ folder into events: Event('unit', stage=unit, message=text) when a
    unit reports, and with an empty message when its file goes (the unit ended)."""

    def __init__(self, run: RunDir, on_event: EventSink, every: float = 0.5):
        super().__init__(daemon=True)
        self.folder, self.on_event, self.every = run.path / PROGRESS, on_event, every
        self.stopped = threading.Event()
        shutil.rmtree(self.folder, ignore_errors=True)  # left by a killed run

    def run(self) -> None:
        shown: dict[str, str] = {}
        while not self.stopped.wait(self.every):
            now = {}
            for path in self.folder.glob("*.txt") if self.folder.is_dir() else ():
                try:
                    now[path.stem.replace("__", "/")] = path.read_text()
                except OSError:  # it went between the listing and the read
                    continue
            for unit, text in now.items():
                if shown.get(unit) != text:
                    self.on_event(Event("unit", stage=unit, message=text))
            for unit in shown.keys() - now.keys():
                self.on_event(Event("unit", stage=unit))
            shown = now

    def stop(self) -> None:
        self.stopped.set()
        self.join()


def _serialised(on_event: EventSink) -> EventSink:
    """The sink, safe to call from the engine and the progress watcher alike."""
    lock = threading.Lock()

    def sink(event: Event) -> None:
        with lock:
            on_event(event)

    return sink


def run_scenario(
    scenario_path: str | Path | None = None,
    *,
    out: str | Path | None = None,
    resume: str | Path | None = None,
    quick: bool = False,
    overrides: Mapping[str, Mapping] | None = None,
    on_event: EventSink = _ignore,
) -> RunDir:
    """Validate, then run a scenario into a new (or resumed) run directory. *overrides*
    ({table: {key: value}}) replace keys of the scenario file (see load_scenario); a resumed
    run may change only [execution] (where it runs, not what it computes)."""
    from .kinds import KINDS

    on_event = _serialised(on_event)
    if resume is not None:
        run = RunDir.open(Path(resume))
    else:
        if scenario_path is None:
            raise GearlabInputError("no scenario given")
        scenario = load_scenario(scenario_path, overrides)
        if quick:  # the shrunk scenario is checked again: refused before any folder is made
            KINDS[scenario.kind].quick(scenario)
        base = Path(out) if out is not None else Path(scenario.tables["output"]["dir"])
        run = RunDir.create(base, scenario, quick)
    with run.lock():  # held until the run ends: a second process in this directory is refused
        if resume is not None:
            scenario = _resumed_scenario(run, scenario_path, quick, overrides)
        on_event(Event("run", message=str(run.path)))
        on_event(Event("log", message=f"scenario {scenario.name} ({scenario.kind}) -> {run.path}"))
        watcher = ProgressWatcher(run, on_event)
        watcher.start()
        try:
            KINDS[scenario.kind].run(scenario, run, on_event)
        except GearlabInputError:
            # Refused before any unit finished (e.g. by a check on the built datasets): leave no run behind.
            if resume is None and not run.records():
                run.discard()
            raise
        finally:
            watcher.stop()
        write_report(run)
    return run


def _resumed_scenario(run: RunDir, scenario_path: str | Path | None, quick: bool,
                      overrides: Mapping[str, Mapping] | None = None) -> Scenario:
    """The scenario a run was started with, shrunk alike if it was started with --quick;
    the results store made ready for appends. Called with the run directory locked."""
    from .kinds import KINDS

    if quick and not run.quick:
        raise GearlabInputError(f"--quick: the run in {run.path} was started without --quick; resume it without")
    scenario = load_scenario(scenario_path or run.scenario_path(), overrides)
    if not run.started_with(scenario):
        raise GearlabInputError(f"{scenario.path}: differs from the scenario the run in {run.path} was started "
                                "with; resume without SCENARIO (the run keeps a copy) or start a new run")
    if run.quick:
        KINDS[scenario.kind].quick(scenario)
    run.truncate_partial()
    run.remove_temporaries()
    return scenario


def write_report(run: RunDir) -> Path:
    from .report import build_report

    html = build_report(run.path)
    run.write_text("report.html", html)
    return run.path / "report.html"


def finished_keys(records: Iterable[dict]) -> set[str]:
    return {r["unit"] for r in records if "unit" in r}
