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
import errno
import fcntl
import hashlib
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

from .errors import GearlabInputError, shown
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


def current_umask() -> int:
    """The process's umask, read without changing it where Linux tells it (/proc)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)  # elsewhere: set and restore at once
    os.umask(mask)
    return mask


def atomic_write(path: Path, data: bytes | str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, 0o666 & ~current_umask())  # mkstemp makes 0600; a report is for others to read too
        with os.fdopen(fd, "wb") as f:
            f.write(data.encode() if isinstance(data, str) else data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.filename is None:  # a full disk: name the file in the message
            exc.filename = str(path)
        raise


def inside(root: Path, *parts: str) -> Path:
    """*root*/*parts*, when that is provably inside *root*: refused when a part is absolute,
    climbs out with '..', holds a NUL, or leads out through a symbolic link. Every file a
    run writes is named through this (RunDir.file), so no name taken from a scenario or a
    measured file can place one elsewhere."""
    path = Path(root).joinpath(*parts)
    try:
        real_root, real = Path(root).resolve(), path.resolve()
        ok = real != real_root and real.is_relative_to(real_root)
    except (OSError, ValueError):  # a NUL character, a loop of links
        ok = False
    if not ok:
        raise GearlabInputError(f"{shown(str(path), 200)}: refused: not a file inside {root}")
    return path


# errno -> what the user is told (and can fix) when a file cannot be written
_WRITE_PROBLEMS = {errno.ENOSPC: "no space left on the device", errno.EDQUOT: "disk quota exceeded",
                   errno.EROFS: "read-only file system", errno.EACCES: "permission denied",
                   errno.EPERM: "operation not permitted", errno.EFBIG: "file too large"}


def write_problem(exc: OSError) -> str | None:
    """What keeps a file from being written (a full disk, a read-only place), or None when
    *exc* is not such a problem of the user's file system."""
    return _WRITE_PROBLEMS.get(exc.errno)


def cannot_write(exc: OSError, where: Path | str = "") -> GearlabInputError:
    """One line naming the path and the problem, for an OSError of writing (under *where*)."""
    problem = write_problem(exc) or exc.strerror or type(exc).__name__
    path = exc.filename or where
    return GearlabInputError(f"{path}: cannot write: {problem}" if path else f"cannot write: {problem}")


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

    def file(self, *parts: str) -> Path:
        """The path of a file of this run, refused unless it lies inside the run directory."""
        return inside(self.path, *parts)

    @classmethod
    def create(cls, base: Path, scenario: Scenario, quick: bool = False) -> RunDir:
        """A new run directory <base>/<name>/<timestamp>[-N]; on failure (a full disk, a
        read-only place) nothing of it is left and one line says why."""
        stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
        parent = inside(base, scenario.name)
        try:
            created = next((p for p in reversed([parent, *parent.parents]) if not p.exists()), None)
        except OSError as exc:  # e.g. a name too long: nothing made yet
            raise GearlabInputError(f"cannot write the run directory under '{base}': {exc.strerror or exc}") from None
        run = None
        try:
            parent.mkdir(parents=True, exist_ok=True)
            run = cls(_fresh_folder(parent, stamp), created=created)
            # scenario.toml last: it marks a run directory (open() looks for it), so a run killed
            # while this runs is never resumed without its --quick setting or original scenario.
            run.write_json(RUN_FILE, {"quick": quick, "base": str(scenario.base.resolve()) if scenario.base else None,
                                      "inputs": input_digests(scenario)})
            try:
                original = scenario.path.read_bytes()
            except OSError:  # gone meanwhile: the resolved scenario.toml suffices
                original = None
            if original is not None:
                run.write_text("scenario.original.toml", original)
            run.write_text("scenario.toml", tomli_w.dumps(_tomlable(scenario.tables)))
        except OSError as exc:
            if run is not None:
                run.discard()
            elif created is not None:
                _remove_empty(parent, created)
            problem = write_problem(exc) or exc.strerror or type(exc).__name__
            raise GearlabInputError(f"cannot write the run directory under '{base}': {problem}"
                                    + (f" ({exc.filename})" if exc.filename else "")) from None
        return run

    def discard(self) -> None:
        """Remove a run directory this process created, and the folders made for it if empty."""
        shutil.rmtree(self.path, ignore_errors=True)
        if self.created is not None:
            _remove_empty(self.path.parent, self.created)

    @property
    def quick(self) -> bool:
        """Whether the run was started with --quick (a resume must shrink it alike)."""
        meta = self.path / RUN_FILE
        return bool(json.loads(meta.read_text()).get("quick")) if meta.is_file() else False

    def base(self) -> Path | None:
        """The folder of the scenario file the run was started from (relative paths in it)."""
        meta = self.path / RUN_FILE
        base = json.loads(meta.read_text()).get("base") if meta.is_file() else None
        return Path(base) if base else None

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

        scenario = load_scenario(self.scenario_path(), base=self.base())
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
        try:
            with open(self.results_path, "a") as f:
                f.write(line)
                f.flush()
                os.fsync(f.fileno())
        except OSError as exc:  # a full disk: a partial line is dropped on --resume (truncate_partial)
            exc.filename = exc.filename or str(self.results_path)
            raise

    def write_json(self, name: str, obj) -> None:
        atomic_write(self.file(name), json.dumps(obj, indent=2, sort_keys=True) + "\n")

    def write_text(self, name: str, text: str | bytes) -> None:
        atomic_write(self.file(name), text)

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


def _fresh_folder(parent: Path, stamp: str) -> Path:
    """A folder made now under *parent*: <stamp>, or <stamp>-2, -3, ... when another run (of
    another process started in the same microsecond) holds the name; never one that exists."""
    for n in range(1, 1000):
        path = parent / (stamp if n == 1 else f"{stamp}-{n}")
        try:
            path.mkdir()
            return path
        except FileExistsError:
            continue
    raise GearlabInputError(f"{parent}: cannot find a free name for a run directory ({stamp}-999 taken)")


def _remove_empty(folder: Path, created: Path) -> None:
    """Remove *folder* and its parents up to *created* (the outermost folder this process
    made) while they are empty; a folder holding anything (another run) stays."""
    for folder in (folder, *folder.parents):
        if not folder.is_relative_to(created):
            break
        try:
            folder.rmdir()
        except OSError:  # not empty: another run lives there
            break


def input_paths(scenario: Scenario) -> list[Path]:
    """The measured files a scenario reads: every 'file' of its tables and each of 'files'
    (a name, or a table with its 'path'), resolved against the scenario's folder."""
    base = Path(scenario.base or scenario.path.parent)
    found: list[Path] = []

    def walk(node) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                names = [value] if key == "file" else value if key == "files" and isinstance(value, list) else []
                names = [n.get("path") if isinstance(n, dict) else n for n in names]
                found.extend((base / name).resolve() for name in names if isinstance(name, str) and name)
                walk(value)
        elif isinstance(node, list):
            for item in node:
                walk(item)

    walk(scenario.tables)
    return list(dict.fromkeys(found))


def _digest(path: Path) -> str | None:
    try:
        with open(path, "rb") as f:
            return hashlib.file_digest(f, "sha256").hexdigest()
    except OSError:
        return None


def input_digests(scenario: Scenario) -> dict[str, str | None]:
    """{absolute path: sha256 of its content} of the measured files a run reads, stored in
    run.json so that a resume against a changed file is refused (its finished units were
    computed from the old content)."""
    return {str(path): _digest(path) for path in input_paths(scenario)}


def check_inputs(run: RunDir) -> None:
    """Refuse to resume *run* when a measured file it read has changed or gone since it started."""
    meta = run.path / RUN_FILE
    stored = json.loads(meta.read_text()).get("inputs") if meta.is_file() else None
    for path, digest in (stored or {}).items():
        now = _digest(Path(path))
        if now != digest:
            change = "is gone" if now is None else "has changed"
            raise GearlabInputError(f"{path}: {change} since the run in {run.path} started (sha256 "
                                    f"{(digest or '?')[:12]}...); its finished units were computed from the file "
                                    "as it was: restore it, or start a new run")


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
        self.path = inside(run_path, PROGRESS, unit.replace("/", "__") + ".txt")
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
        run = RunDir.create(output_base(scenario, out), scenario, quick)
    try:
        lock = run.lock()
    except GearlabInputError:
        if resume is None:  # a new run that cannot even be locked (a full disk): leave none
            run.discard()
        raise
    with lock:  # held until the run ends: a second process in this directory is refused
        if resume is not None:
            scenario = _resumed_scenario(run, scenario_path, quick, overrides)
        on_event(Event("run", message=str(run.path)))
        on_event(Event("log", message=f"scenario {scenario.name} ({scenario.kind}) -> {run.path}"))
        watcher = ProgressWatcher(run, on_event)
        watcher.start()
        try:
            KINDS[scenario.kind].run(scenario, run, on_event)
            write_report(run)
        except GearlabInputError:
            # Refused before any unit finished (e.g. by a check on the built datasets): leave no run behind.
            if resume is None and not run.records():
                run.discard()
            raise
        except OSError as exc:
            if write_problem(exc) is None:
                raise
            # A full disk, a read-only place: finished units are stored line by line, so a run
            # that has any is kept for --resume; one that has none is removed.
            kept = resume is not None or bool(run.records())
            if not kept:
                run.discard()
            then = (f"; the run is kept: once fixed, resume with: gearlab run --resume {run.path}" if kept
                    else "; no run directory is left")
            raise GearlabInputError(f"{cannot_write(exc, run.path)}{then}") from None
        finally:
            watcher.stop()
    return run


def output_base(scenario: Scenario, out: str | Path | None = None) -> Path:
    """The folder that holds a scenario's runs (<base>/<name>/<timestamp>/): --out, else its
    [output] dir; a relative one is taken from the current folder. The TUI looks up past runs
    with this, so it finds them where `gearlab run` puts them."""
    return Path(out) if out is not None else Path(scenario.tables["output"]["dir"])


def _resumed_scenario(run: RunDir, scenario_path: str | Path | None, quick: bool,
                      overrides: Mapping[str, Mapping] | None = None) -> Scenario:
    """The scenario a run was started with, shrunk alike if it was started with --quick;
    the results store made ready for appends. Called with the run directory locked."""
    from .kinds import KINDS

    if quick and not run.quick:
        raise GearlabInputError(f"--quick: the run in {run.path} was started without --quick; resume it without")
    scenario = load_scenario(scenario_path or run.scenario_path(), overrides,
                             base=None if scenario_path else run.base())
    if not run.started_with(scenario):
        raise GearlabInputError(f"{scenario.path}: differs from the scenario the run in {run.path} was started "
                                "with; resume without SCENARIO (the run keeps a copy) or start a new run")
    check_inputs(run)
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
