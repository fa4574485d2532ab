"""Run directories: the folder a run writes, its lock, its results store.

A run writes ``runs/<name>/<timestamp>/``: the resolved scenario, ``results.jsonl`` (one
record per finished unit, appended, flushed and fsynced as the unit finishes),
``summary.json``, tables, ``figures/`` and ``report.html``. Whole files are written to a
temporary name and renamed, so a killed run never leaves a half-written file; the
results store is append-only, so ``--resume`` redoes nothing that finished. One process at
a time works in a run directory: it holds an flock on ``.lock`` for the whole run.

The scenario kinds write into a RunDir; the engine that creates, resumes and reports a run
(gearlab.engine) sits above the kinds.
"""

from __future__ import annotations

import datetime as _dt
import fcntl
import hashlib
import json
import os
import shutil
import tomllib
from dataclasses import dataclass
from pathlib import Path

import tomli_w

from .errors import GearlabInputError
from .files import atomic_write, inside, write_problem
from .scenario import Scenario

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
            run.write_json(
                RUN_FILE,
                {
                    "quick": quick,
                    "base": str(scenario.base.resolve()) if scenario.base else None,
                    "inputs": input_digests(scenario),
                },
            )
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
            raise GearlabInputError(
                f"cannot write the run directory under '{base}': {problem}"
                + (f" ({exc.filename})" if exc.filename else "")
            ) from None
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
            raise GearlabInputError(
                f"{self.path}: another gearlab process{who} is running in this run directory; "
                "wait for it to end (or stop it), then resume"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        return RunLock(fd)

    def scenario_path(self) -> Path:
        """The scenario file to resume from: the original text, else the resolved one."""
        original = self.path / "scenario.original.toml"
        return original if original.is_file() else self.path / "scenario.toml"

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
    for here in (folder, *folder.parents):
        if not here.is_relative_to(created):
            break
        try:
            here.rmdir()
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
            raise GearlabInputError(
                f"{path}: {change} since the run in {run.path} started (sha256 "
                f"{(digest or '?')[:12]}...); its finished units were computed from the file "
                "as it was: restore it, or start a new run"
            )


def _tomlable(value):
    if isinstance(value, dict):
        return {k: _tomlable(v) for k, v in value.items() if v is not None}
    if isinstance(value, (list, tuple)):
        return [_tomlable(v) for v in value]
    return value
