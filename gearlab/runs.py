"""Run directories: the folder a run writes, its lock, its results store.

A run writes ``runs/<name>/<timestamp>/``: the resolved scenario, ``results.jsonl`` (one
record per finished unit, appended, flushed and fsynced as the unit finishes),
``summary.json``, tables, ``figures/`` and ``report.html``. Whole files are written to a
temporary name and renamed, so a killed run never leaves a half-written file; the
results store is append-only, so ``--resume`` redoes nothing that finished. One process at
a time works in a run directory: it holds an flock on ``.lock`` for the whole run.

Every file of a run is reached through :class:`gearlab.confined.Confined` (``RunDir.file``):
no symbolic link is followed, and a run directory opened again (``--resume``, ``report``,
``compare``) is refused when it holds a link, a device or another account's entry.

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
import stat
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import tomli_w

from .confined import Confined, is_temporary, refuse_unsafe
from .errors import GearlabInputError
from .files import inside, matched, write_problem
from .scenario import Scenario

RUN_FILE = "run.json"  # how the run was started (--quick), for --resume
LOCK_FILE = ".lock"  # flocked by the process running in the directory; holds its pid
RESULTS_FILE = "results.jsonl"  # one finished unit a line


class RunLock:
    """The run directory held by this process (see RunDir.lock); released on close or exit,
    its lock file removed then (no stale .lock is left behind a run that ended)."""

    def __init__(self, fd: int, file: Confined | None = None):
        self.fd: int | None = fd
        self.file = file

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            # Removed while still held, and only when the name still is the file held: a process
            # that opened it meanwhile finds, once it holds it, that the name is gone (or another
            # file) and locks the name afresh (RunDir.lock), so two never hold the directory.
            if self.file is not None and _same_file(self.file.stat(), os.fstat(self.fd)):
                self.file.unlink()
        except (OSError, GearlabInputError):
            pass  # a lock file left behind is harmless: the next lock takes it over
        finally:
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
        """Where the results store lies (for messages; it is read and written through file())."""
        return self.path / RESULTS_FILE

    @property
    def figures(self) -> Confined:
        return self.file("figures")

    def file(self, *parts: str) -> Confined:
        """A file (or folder) of this run, reached without following a link; a name that
        leads out of the run directory is refused."""
        return Confined(self.path, parts)

    @classmethod
    def create(
        cls, base: Path, scenario: Scenario, quick: bool = False, overrides: Mapping[str, Mapping] | None = None
    ) -> RunDir:
        """A new run directory <base>/<name>/<timestamp>[-N]; on failure (a full disk, a
        read-only place) nothing of it is left and one line says why. *overrides*: the keys the
        command line set over the scenario file (`--seed`), kept so that a resume reads them again."""
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
                    # [execution] says where units run, which a resume may change
                    "overrides": {t: dict(v) for t, v in (overrides or {}).items() if t != "execution"},
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

    def meta(self) -> dict:
        """run.json: how the run was started ({} when it has none)."""
        meta = self.file(RUN_FILE)
        if not meta.is_file():
            return {}
        try:
            found = json.loads(meta.read_bytes(limit=1 << 24))
        except ValueError:
            raise GearlabInputError(f"{meta}: damaged (not JSON); expected what 'gearlab run' wrote") from None
        if not isinstance(found, dict):
            raise GearlabInputError(f"{meta}: damaged (not a JSON object); expected what 'gearlab run' wrote")
        return found

    @property
    def quick(self) -> bool:
        """Whether the run was started with --quick (a resume must shrink it alike)."""
        return bool(self.meta().get("quick"))

    def base(self) -> Path | None:
        """The folder of the scenario file the run was started from (relative paths in it)."""
        base = self.meta().get("base")
        return Path(base) if isinstance(base, str) and base else None

    @classmethod
    def open(cls, path: Path) -> RunDir:
        """An existing run directory, for --resume, report or compare: refused when it holds a
        symbolic link, a device or another account's entry (nothing in it is then touched)."""
        path = Path(path)
        if not path.is_dir():
            raise GearlabInputError(f"{path}: not a gearlab run directory (no such folder)")
        marker = Confined(path, ("scenario.toml",)).stat()
        if marker is None:
            raise GearlabInputError(f"{path}: not a gearlab run directory (no scenario.toml)")
        if not stat.S_ISREG(marker.st_mode):  # a link there is refused by name below
            refuse_unsafe(path)
            raise GearlabInputError(f"{path}: not a gearlab run directory (scenario.toml is not a file)")
        refuse_unsafe(path)
        return cls(path)

    def lock(self) -> RunLock:
        """Hold the run directory for this process, or refuse when another process holds it.

        An flock, not a marker file: the kernel drops it when the holder dies, however it
        dies (SIGKILL included), so a killed run never blocks its --resume. The holder removes
        the lock file as it ends (RunLock.release); a file locked here that is no longer the
        one of that name (removed meanwhile by the holder ending) is let go and the name
        locked again, so two processes never hold two different files.
        """
        lock_file = self.file(LOCK_FILE)
        for _ in range(100):
            try:
                # never through a link, never a file with another name elsewhere: it is truncated below
                fd = lock_file.open_own(os.O_RDWR | os.O_CREAT)
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
            if _same_file(lock_file.stat(), os.fstat(fd)):
                break
            os.close(fd)  # the previous holder removed it as it ended: lock the name afresh
        else:
            raise GearlabInputError(f"{self.path}: cannot lock the run directory (its lock file keeps changing)")
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        return RunLock(fd, lock_file)

    def scenario_file(self) -> Confined:
        """The scenario file to resume from: the original text, else the resolved one."""
        original = self.file("scenario.original.toml")
        return original if original.exists() else self.file("scenario.toml")

    def scenario_path(self) -> Path:
        return self.scenario_file().path

    def started_with(self, scenario: Scenario, stored_forms=lambda tables: tables) -> bool:
        """Whether *scenario* resolves to the tables this run was started with (a resume with
        another would mix its units with those finished); *stored_forms*: the stored tables read
        as the keys are now (kinds.common.stored_forms)."""
        # [execution] says where units run, not what they compute: a run may resume elsewhere
        stored = stored_forms(tomllib.loads(self.file("scenario.toml").read_text()))
        stored.pop("execution", None)
        given = {table: values for table, values in scenario.tables.items() if table != "execution"}
        return stored == tomllib.loads(tomli_w.dumps(_tomlable(given)))

    def records(self) -> list[dict]:
        """Finished units. A line cut short by a kill (no newline yet) is ignored, and so is a
        damaged line, without hiding the records appended after it."""
        store = self.file(RESULTS_FILE)
        if not store.exists():
            return []
        out = []
        for line in store.read_bytes().decode(errors="replace").splitlines(keepends=True):
            if not line.endswith("\n"):
                continue
            try:
                out.append(json.loads(line))
            except json.JSONDecodeError:
                continue
        return out

    def append(self, record: dict) -> None:
        # a full disk: a partial line is dropped on --resume (truncate_partial)
        self.file(RESULTS_FILE).append(json.dumps(record, sort_keys=True) + "\n")

    def write_json(self, name: str, obj) -> None:
        self.file(name).write(json.dumps(obj, indent=2, sort_keys=True) + "\n")

    def write_text(self, name: str, text: str | bytes) -> None:
        self.file(name).write(text)

    def read_json(self, name: str, default=None):
        """A JSON file of this run (summary.json, bound.json), read without following a link;
        *default* when there is none."""
        found = self.file(name)
        if not found.exists():
            return default
        try:
            return json.loads(found.read_bytes())
        except ValueError:
            raise GearlabInputError(f"{found}: damaged (not JSON); expected what 'gearlab run' wrote") from None

    def summary(self) -> dict:
        """summary.json ({} before the run is summarised)."""
        found = self.read_json("summary.json", {})
        return found if isinstance(found, dict) else {}

    def remove_temporaries(self) -> None:
        """Remove the temporary files of atomic writes cut short by a kill. Only with the run
        directory locked: then no writer of this run is alive."""
        for entry, st in list(self.file().walk()):
            if is_temporary(entry.name) and not stat.S_ISDIR(st.st_mode):
                entry.unlink()

    def truncate_partial(self) -> None:
        """Drop a trailing partial line left by a killed run, so appends stay line-aligned."""
        store = self.file(RESULTS_FILE)
        if not store.exists():
            return
        data = store.read_bytes()
        cut = data.rfind(b"\n") + 1
        if cut != len(data):
            store.write(data[:cut])


def _same_file(a: os.stat_result | None, b: os.stat_result) -> bool:
    return a is not None and (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


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
    (a name, or a table with its 'path'; a glob pattern: each file it matches), resolved against
    the scenario's folder; and each 'gearbox' description that is a file (not a built-in name): it
    decides the speed of a record without a tacho and what a described source simulates."""
    base = Path(scenario.base or scenario.path.parent)
    found: list[Path] = []

    def walk(node) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                names = [value] if key == "file" else value if key == "files" and isinstance(value, list) else []
                names = [n.get("path") if isinstance(n, dict) else n for n in names]
                for name in (n for n in names if isinstance(n, str) and n):
                    try:
                        found.extend((base / m).resolve() for m in matched(name, base, key))
                    except GearlabInputError:  # the kind's own check says so; its digest is none
                        found.append((base / name).resolve())
                if key == "gearbox" and isinstance(value, str) and value and (base / value).is_file():
                    found.append((base / value).resolve())
                walk(value)
        elif isinstance(node, list):
            for item in node:
                walk(item)

    walk(scenario.tables)
    return list(dict.fromkeys(found))


def input_digest(path: Path) -> str | None:
    """The sha256 of a measured file's content, read in blocks (a take's: of its file and its name's mark, one take
    of a file another take than the next); None where it cannot be read."""
    from .files import split_take, take_file

    try:
        with open(take_file(path), "rb") as f:
            digest = hashlib.file_digest(f, "sha256")
        if (take := split_take(path)) is not None:
            digest.update(f"[{take[1]}={take[2]}]".encode())
        return digest.hexdigest()
    except OSError:
        return None


def input_digests(scenario: Scenario) -> dict[str, str | None]:
    """{absolute path: sha256 of its content} of the measured files a run reads, stored in
    run.json so that a resume against a changed file is refused (its finished units were
    computed from the old content)."""
    return {str(path): input_digest(path) for path in input_paths(scenario)}


def check_inputs(run: RunDir, scenario: Scenario) -> None:
    """Refuse to resume *run* when a measured file it read has changed or gone since it started, or
    when *scenario*'s glob pattern matches a file it did not read."""
    stored = run.meta().get("inputs")
    for path in input_paths(scenario) if isinstance(stored, dict) else ():
        if str(path) not in stored:
            raise GearlabInputError(
                f"{path}: a file the scenario names (a pattern's match) that the run in {run.path} did not "
                "read; its finished units were computed without it: move it away, or start a new run"
            )
    for path, digest in (stored if isinstance(stored, dict) else {}).items():
        now = input_digest(Path(path))
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
