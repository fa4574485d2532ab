"""What a run directory says about its run: the metadata in run.json (who ran what, where,
when, for how long, with which gearlab), the list of past runs (`gearlab runs`) and the
differences between the scenarios of runs (`gearlab compare`).

run.json holds, beside what a resume needs (quick, base, inputs):

* ``gearlab_version``, ``command`` (the command line), ``host``, ``user``, ``python``,
  ``platform``, ``git`` (the revision of gearlab's source tree and whether it had
  uncommitted changes; absent for an installed gearlab);
* ``execution`` (executor and device asked) and ``device`` (where the networks trained, when
  the run says);
* ``started``, ``ended`` (ISO 8601 with the UTC offset), ``duration_s`` (working time, the
  sessions summed), ``status`` (running, finished, failed, cancelled);
* ``sessions``: one entry per start or resume, each with its command, times and status.

A run killed outright (SIGKILL, a power cut) keeps ``status = "running"``; ``gearlab runs``
tells it apart from a live one by its lock (the pid in ``.lock``, on the same host).
"""

from __future__ import annotations

import datetime as _dt
import functools
import os
import platform
import shlex
import socket
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .errors import GearlabInputError

STATUSES = ("running", "finished", "failed", "cancelled")
SESSION_KEYS = ("command", "host", "user", "gearlab_version", "git", "started", "status")


def now_iso() -> str:
    return _dt.datetime.now(_dt.UTC).astimezone().isoformat(timespec="seconds")


def gearlab_version() -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("gearlab")
    except PackageNotFoundError:
        return None


@functools.cache
def git_revision(root: Path | None = None) -> dict | None:
    """{'revision': sha, 'dirty': bool} of gearlab's source tree; None outside a git checkout
    (an installed gearlab) or without git. Reads only: no index lock is taken."""
    root = root or Path(__file__).resolve().parents[1]
    if not (root / ".git").exists():
        return None
    env = {**os.environ, "GIT_OPTIONAL_LOCKS": "0", "LC_ALL": "C"}

    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(
                ["git", "--no-optional-locks", "-C", str(root), *args],
                capture_output=True,
                text=True,
                timeout=5,
                env=env,
                check=False,
            )
        except (OSError, subprocess.SubprocessError):
            return None
        return done.stdout.strip() if done.returncode == 0 else None

    revision = git("rev-parse", "HEAD")
    if not revision:
        return None
    changes = git("status", "--porcelain", "--untracked-files=no")
    return {"revision": revision, "dirty": None if changes is None else bool(changes)}


def command_line(argv: list[str] | None = None) -> str:
    """The command as typed: `gearlab run ...` (the program's path shortened to its name)."""
    argv = list(sys.argv if argv is None else argv)
    if argv:
        name = Path(argv[0]).name
        argv[0] = "gearlab" if name in ("__main__.py", "gearlab", "-m", "-c") else name
    return shlex.join(argv)


def session_start(execution: dict | None = None) -> dict:
    """The metadata of a run (or resume) starting now, in this process."""
    found = {
        "gearlab_version": gearlab_version(),
        "command": command_line(),
        "host": socket.gethostname(),
        "user": _user(),
        "pid": os.getpid(),
        "python": platform.python_version(),
        "platform": platform.platform(terse=True),
        "git": git_revision(),
        "started": now_iso(),
        "status": "running",
    }
    if execution:
        found["execution"] = {k: execution[k] for k in ("executor", "device") if k in execution}
    return found


def _user() -> str | None:
    try:
        import pwd

        return pwd.getpwuid(os.getuid()).pw_name
    except (ImportError, KeyError):
        return os.environ.get("USER")


class Session:
    """The metadata of one session (a start or a resume) kept in a run's run.json: begun on
    construction, ended by end(status). Metadata is best effort: a write that fails (a full
    disk) never fails the run."""

    def __init__(self, run, execution: dict | None = None):
        self.run, self.clock = run, time.monotonic()
        self.info = session_start(execution)
        meta = _meta(run)
        sessions = [s for s in meta.get("sessions", []) if isinstance(s, dict)]
        first = sessions[0] if sessions else self.info
        sessions.append({k: v for k, v in self.info.items() if k in SESSION_KEYS})
        meta.update({k: v for k, v in self.info.items() if k not in ("started", "pid")})
        meta.update(
            {"started": first.get("started", self.info["started"]), "sessions": sessions, "pid": self.info["pid"]}
        )
        meta.pop("ended", None)
        self.meta = meta
        _write(run, meta)

    def end(self, status: str, device: str | None = None) -> None:
        took = round(time.monotonic() - self.clock, 3)
        ended = now_iso()
        meta = _meta(self.run) or self.meta
        sessions = [s for s in meta.get("sessions", []) if isinstance(s, dict)]
        if sessions:
            sessions[-1].update({"ended": ended, "duration_s": took, "status": status})
        total = sum(s.get("duration_s", 0) for s in sessions if isinstance(s.get("duration_s"), int | float))
        meta.update({"ended": ended, "status": status, "duration_s": round(total, 3), "sessions": sessions})
        meta.pop("pid", None)
        if device:
            meta["device"] = device
        _write(self.run, meta)


def _meta(run) -> dict:
    try:
        return run.meta()
    except (OSError, GearlabInputError):
        return {}


def _write(run, meta: dict) -> None:
    from .runs import RUN_FILE

    try:
        run.write_json(RUN_FILE, meta)
    except (OSError, GearlabInputError):
        pass


# --------------------------------------------------------------------------- gearlab runs


@dataclass
class RunInfo:
    path: Path
    name: str
    kind: str
    started: str | None
    duration_s: float | None
    status: str
    headline: str
    problem: str | None = None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another account's process
        return True
    except OSError:
        return False
    return True


def run_status(run, meta: dict) -> str:
    """finished / failed / cancelled / running / stopped (killed or crashed: resumable) /
    unfinished (a run of an older gearlab without a status)."""
    from .runs import LOCK_FILE

    status = meta.get("status")
    if status == "running":
        pid = meta.get("pid")
        live = (
            isinstance(pid, int)
            and meta.get("host") == socket.gethostname()
            and run.file(LOCK_FILE).exists()
            and _alive(pid)
        )
        return "running" if live else "stopped"
    if status in STATUSES:
        return status
    return "finished" if run.file("summary.json").exists() else "unfinished"


def headline(run, kind: str) -> str:
    """The run's headline figure: what its kind says (an optional `headline(run)` of the
    kind contract), else the first sentence of its verdict that is not an introduction (ending in
    ':'), else the first summary line."""
    from .kinds import SCENARIO_KINDS

    module = SCENARIO_KINDS.get(kind)
    lines: list[str] = []
    try:
        if module is not None and hasattr(module, "headline"):
            lines = [module.headline(run)]
        if not any(lines):
            from .verdict import verdict_lines

            lines = verdict_lines(run)
        if not any(lines) and module is not None and run.file("summary.json").exists():
            lines = [line for line in module.summary_lines(run) if not line.lstrip().startswith("|")]
    except Exception:  # noqa: BLE001 - a damaged or older summary: the listing goes on
        lines = []
    # an introduction to the lines that follow (a detection verdict's 'At record10 (...):') is no finding
    text = next((line for line in lines if line and not line.rstrip().endswith(":")), "")
    text = " ".join((text or next((line for line in lines if line), "")).split())
    return text if len(text) <= 90 else text[:89] + "…"


def describe_run(path: Path) -> RunInfo:
    """One run directory as `gearlab runs` lists it; a damaged one says why."""
    from .runs import RunDir

    try:
        run = RunDir.open(path)
        meta = run.meta()
        head = tomllib.loads(run.file("scenario.toml").read_text()).get("scenario", {})
    except (OSError, ValueError, GearlabInputError) as exc:
        return RunInfo(path, path.parent.name, "?", None, None, "damaged", "", problem=str(exc))
    name, kind = str(head.get("name", path.parent.name)), str(head.get("kind", "?"))
    started = meta.get("started") if isinstance(meta.get("started"), str) else None
    if started is None:  # an older run: its folder name is its start time
        try:
            started = _dt.datetime.strptime(path.name[:22], "%Y%m%d-%H%M%S-%f").isoformat(timespec="seconds")
        except ValueError:
            started = None
    duration = meta.get("duration_s") if isinstance(meta.get("duration_s"), int | float) else None
    status = run_status(run, meta)
    return RunInfo(path, name, kind, started, duration, status, headline(run, kind) if status != "running" else "")


def find_runs(folder: Path, depth: int = 4) -> list[Path]:
    """The run directories (folders holding scenario.toml) at or below *folder*, newest
    first by their start time; links are not followed."""
    found: list[Path] = []

    def walk(here: Path, left: int) -> None:
        try:
            entries = sorted(os.scandir(here), key=lambda e: e.name)
        except OSError:
            return
        if any(e.name == "scenario.toml" and e.is_file(follow_symlinks=False) for e in entries):
            found.append(here)
            return
        if left:
            for e in entries:
                if e.is_dir(follow_symlinks=False) and not e.name.startswith("."):
                    walk(Path(e.path), left - 1)

    walk(Path(folder), depth)
    return found


def list_runs(folder: Path) -> list[RunInfo]:
    if not Path(folder).is_dir():
        raise GearlabInputError(f"{folder}: no such folder of runs")
    runs = [describe_run(p) for p in find_runs(folder)]
    return sorted(runs, key=lambda r: (r.started or "", str(r.path)), reverse=True)


def duration_text(seconds: float | None) -> str:
    if seconds is None:
        return "-"
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    minutes, s = divmod(seconds, 60)
    if minutes < 60:
        return f"{minutes} min {s:02d} s"
    hours, m = divmod(minutes, 60)
    return f"{hours} h {m:02d} min"


def date_text(iso: str | None) -> str:
    if not iso:
        return "-"
    try:
        return _dt.datetime.fromisoformat(iso).strftime("%Y-%m-%d %H:%M")
    except ValueError:
        return iso


# --------------------------------------------------------------------------- gearlab compare


def _flat(node, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    if isinstance(node, dict):
        for key, value in node.items():
            out.update(_flat(value, f"{prefix}.{key}" if prefix else str(key)))
    elif isinstance(node, list) and any(isinstance(v, dict) for v in node):
        for i, value in enumerate(node):
            out.update(_flat(value, f"{prefix}[{i}]"))
    else:
        out[prefix] = node
    return out


def scenario_differences(run_paths: list[Path]) -> list[tuple[str, list[str]]]:
    """The scenario keys whose values differ between runs ('table.key', one shown value per
    run, '-' where a run lacks the key), [execution] included, the scenario's name left out."""
    from .runs import RunDir

    flats = []
    for path in run_paths:
        tables = tomllib.loads(RunDir(Path(path)).file("scenario.toml").read_text())
        flats.append(_flat(tables))
    keys = sorted(set().union(*flats)) if flats else []
    rows = []
    for key in keys:
        if key in ("scenario.name", "scenario.description"):
            continue
        values = [f.get(key, None) for f in flats]
        if any(v != values[0] for v in values[1:]):
            rows.append((key, ["-" if v is None else _shown(v) for v in values]))
    return rows


def _shown(value) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)
