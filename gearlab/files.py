"""Writing files safely: whole files by atomic rename, names kept inside a folder, one-line
messages for a file system that refuses a write; the files a scenario's glob pattern names.

The bottom of gearlab's run infrastructure (see docs/architecture.md): imported by the data
cache, the gap diagnosis, the learners and the run directory alike, so it imports nothing of
gearlab but the errors.
"""

from __future__ import annotations

import errno
import glob
import os
import re
import tempfile
import tomllib
from collections.abc import Callable
from pathlib import Path

from .errors import GearlabInputError, clipped, shown


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
_WRITE_PROBLEMS = {
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "read-only file system",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.EFBIG: "file too large",
}


def write_problem(exc: OSError) -> str | None:
    """What keeps a file from being written (a full disk, a read-only place), or None when
    *exc* is not such a problem of the user's file system."""
    return _WRITE_PROBLEMS.get(exc.errno)


def cannot_write(exc: OSError, where: Path | str = "") -> GearlabInputError:
    """One line naming the path and the problem, for an OSError of writing (under *where*)."""
    problem = write_problem(exc) or exc.strerror or type(exc).__name__
    path = exc.filename or where
    return GearlabInputError(f"{path}: cannot write: {problem}" if path else f"cannot write: {problem}")


def toml_tables(path: Path, read: Callable[[], bytes], missing: str, directory: str) -> dict:
    """The tables of a TOML file a user names (a scenario, a gearbox description), *read* giving
    its bytes; one line for each way it cannot be read: "<path>: <missing>" when it is not there,
    "<path>: <directory>" when it is a folder."""
    try:
        text = read().decode("utf-8")
    except FileNotFoundError:
        raise GearlabInputError(f"{path}: {missing}") from None
    except IsADirectoryError:
        raise GearlabInputError(f"{path}: {directory}") from None
    except UnicodeDecodeError as exc:
        raise GearlabInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise GearlabInputError(f"{path}: cannot read ({exc.strerror})") from None
    try:
        return tomllib.loads(text)
    except ValueError as exc:  # TOMLDecodeError, or an integer of more digits than Python converts
        raise GearlabInputError(f"{path}: invalid TOML: {clipped(str(exc))}") from None
    except RecursionError:  # arrays or inline tables nested hundreds deep
        raise GearlabInputError(
            f"{path}: invalid TOML: nested too deeply (arrays or tables inside one another hundreds of levels deep)"
        ) from None
    except MemoryError:
        raise GearlabInputError(f"{path}: invalid TOML: too large to read into memory") from None


# A take of a logger's file of several (data.takes), "log.csv[segment=3]": a file, then its take column and the
# take's mark in brackets at the end of the name
_TAKE = re.compile(r"^(?P<file>.+?)\[(?P<column>[^\[\]=]+)=(?P<mark>[^\[\]]*)\]$", re.S)


def split_take(path) -> tuple[str, str, str] | None:
    """(file, column, mark) of a take's name "file.csv[segment=3]"; None for a file's own name."""
    found = _TAKE.match(str(path))
    return None if found is None else (found["file"], found["column"], found["mark"])


def take_file(path) -> Path:
    """The file a record's name reads: a take's file, else *path* itself."""
    take = split_take(path)
    return Path(path) if take is None else Path(take[0])


def take_name(path, column: str, mark: str) -> str:
    """The name of one of *path*'s takes: "file.csv[segment=3]" (the file as the scenario writes it)."""
    return f"{path}[{column}={mark}]"


def matched(name: str, base: Path, where: str) -> list[str]:
    """The files a scenario's measured-file *name* stands for: itself, or, where it holds a glob
    pattern (*, ?, [...]; ** across folders) and is no file's own name, each file it matches, sorted
    by name and written as the pattern is (relative to *base*, the scenario's folder, unless
    absolute). A pattern matching no file: one line naming *where* and the pattern. A Windows user's
    backslashes ('..\\daten\\take.csv') separate folders here too, where no file is named so; a drive's
    path ('C:\\data\\take.csv') is refused in one line (it is no path on this machine)."""
    if "\\" in name and os.sep != "\\" and not (base / name).exists():
        if re.match(r"[A-Za-z]:[\\/]", name):
            raise GearlabInputError(
                f"{where}: {name!r} is a path on a Windows drive; expected the file's path on this machine, "
                f"absolute or relative to {base}"
            )
        name = name.replace("\\", "/")
    if not set(name) & set("*?[") or (base / name).exists() or (base / take_file(name)).is_file():  # a take's name
        return [name]
    found = sorted(m for m in glob.glob(name, root_dir=base, recursive=True) if (base / m).is_file())
    if not found:
        raise GearlabInputError(f"{where}: {name!r} matches no file")
    return found


def one_file(name: str, base: Path, where: str) -> str:
    """The file a key that reads one record names (a dataset entry's, a gap's or a transfer's 'file'):
    *name* as matched() reads it, a glob pattern only where it matches a single file. One line naming
    *where* and the files otherwise (none: matched's)."""
    names = matched(name, base, where)
    if len(names) > 1:
        listed = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
        raise GearlabInputError(
            f"{where}: {name!r} matches {len(names)} files ({listed}); this key reads one record: expected "
            "a name or a pattern matching one file (several records: a gap or detection [target]'s 'files')"
        )
    return names[0]
