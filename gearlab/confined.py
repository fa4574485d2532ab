"""The files of a run directory, reached so that the directory cannot be turned against its user.

A run directory may come from elsewhere (an archive, a shared disk) and be resumed or
reported by someone who did not make it. Whoever prepared it may have planted a symbolic
link where a run writes (``.lock``, ``results.jsonl``, ``figures/``, a temporary name), a
device, or entries owned by another account. So every file a run reads or writes goes
through :class:`Confined`:

* the run directory is opened once per access and every name below it is opened relative
  to that descriptor (``dir_fd``) with ``O_NOFOLLOW``: a symbolic link, at the file or at
  any folder on the way, is refused in one line and never followed;
* whole files are written to a fresh temporary name (``O_CREAT | O_EXCL``: never an
  existing entry) in the same folder, synced, and renamed over the name: a link planted at
  the name is replaced, not written through;
* files changed in place (the results store, the lock) must be regular files of this
  account with no other hard link;
* :func:`refuse_unsafe` walks a directory before a resume or a report and refuses any
  symbolic link, device, pipe, socket or entry owned by another account.

The folder itself (the run directory's own path) is the user's choice and is taken as
given; only what lies inside it is distrusted. Writes the user asks for outside any run
directory (``--out``, ``--csv``, the dataset cache) use :func:`gearlab.files.atomic_write`.
"""

from __future__ import annotations

import errno
import fnmatch
import os
import secrets
import shutil
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from .errors import GearlabInputError, shown
from .files import atomic_write

NAME_MAX = 255  # bytes of one name on Linux, macOS and Windows file systems
_DIR_FLAGS = os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC
# O_NONBLOCK: opening a planted pipe would otherwise wait forever for a writer
_FILE_FLAGS = os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK


def _owner() -> int:
    """The account whose run directories these are (a function, so a test can pose as another)."""
    return os.geteuid()


def _kind(mode: int) -> str:
    if stat.S_ISLNK(mode):
        return "a symbolic link"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "a folder" if stat.S_ISDIR(mode) else "a file"


def _names(parts: tuple[str, ...], root: Path) -> tuple[str, ...]:
    """*parts* split at '/' into single names, each checked: no absolute path, no '..', no
    NUL, none longer than a file system takes (refused here in one line, not by the OS)."""
    out: list[str] = []
    for part in parts:
        if not isinstance(part, str) or part.startswith("/") or "\0" in part:
            raise GearlabInputError(f"{shown(str(part), 200)}: refused: not a file inside {root}")
        for name in part.split("/"):
            if name in ("", "."):
                continue
            if name == "..":
                raise GearlabInputError(f"{shown(part, 200)}: refused: not a file inside {root}")
            if len(os.fsencode(name)) > NAME_MAX:
                raise GearlabInputError(
                    f"{shown(name, 80)}: refused: a name of {len(os.fsencode(name))} bytes; "
                    f"a file name holds at most {NAME_MAX} (in {root})"
                )
            out.append(name)
    return tuple(out)


@dataclass(frozen=True)
class Confined:
    """A file or folder *parts* below the folder *root*, reached only through *root*'s
    descriptor without following a link. Picklable (a unit in a worker process gets one).

    It has no ``__fspath__`` on purpose: it cannot be handed to ``open()`` or ``savefig``
    by mistake; its ``path`` is for messages."""

    root: Path
    parts: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "root", Path(self.root))
        object.__setattr__(self, "parts", _names(tuple(self.parts), self.root))

    # --- names -------------------------------------------------------------------------

    def __truediv__(self, name: str) -> Confined:
        return Confined(self.root, (*self.parts, name))

    def joinpath(self, *names: str) -> Confined:
        return Confined(self.root, (*self.parts, *names))

    @property
    def path(self) -> Path:
        return self.root.joinpath(*self.parts)

    def __str__(self) -> str:
        return str(self.path)

    @property
    def name(self) -> str:
        return self.parts[-1] if self.parts else self.root.name

    @property
    def stem(self) -> str:
        return Path(self.name).stem

    @property
    def suffix(self) -> str:
        return Path(self.name).suffix

    @property
    def parent(self) -> Confined:
        return Confined(self.root, self.parts[:-1])

    # --- reaching the folder that holds it ---------------------------------------------

    def _refused(self, depth: int, what: str) -> GearlabInputError:
        where = self.root.joinpath(*self.parts[:depth])
        return GearlabInputError(
            f"{where}: refused: {what} inside the folder {self.root}; a run directory holds "
            "only its own files and folders (no links, devices or others' files)"
        )

    @contextmanager
    def _folder(self, parts: tuple[str, ...], create: bool) -> Iterator[int]:
        """A descriptor of the folder *parts* below the root, each step opened with
        O_NOFOLLOW; made on the way when *create*."""
        fd = os.open(self.root, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        try:
            for depth, name in enumerate(parts, start=1):
                if create:
                    try:
                        os.mkdir(name, 0o777, dir_fd=fd)
                    except FileExistsError:
                        pass
                try:
                    inner = os.open(name, _DIR_FLAGS, dir_fd=fd)
                except OSError as exc:
                    if exc.errno in (errno.ELOOP, errno.ENOTDIR):
                        mode = os.stat(name, dir_fd=fd, follow_symlinks=False).st_mode
                        raise self._refused(depth, f"{_kind(mode)} where a folder was expected") from None
                    raise
                os.close(fd)
                fd = inner
            yield fd
        finally:
            os.close(fd)

    def _open(self, flags: int, mode: int = 0o666) -> int:
        """The file opened with *flags* (never through a link): a descriptor the caller closes."""
        if not self.parts:
            raise GearlabInputError(f"{self.root}: refused: a folder, not a file")
        with self._folder(self.parts[:-1], create=bool(flags & os.O_CREAT)) as d:
            try:
                fd = os.open(self.parts[-1], flags | _FILE_FLAGS, mode, dir_fd=d)
            except OSError as exc:
                if exc.errno == errno.ELOOP:
                    raise self._refused(len(self.parts), "a symbolic link") from None
                if exc.filename is None:
                    exc.filename = str(self.path)
                raise
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                raise self._refused(len(self.parts), f"{_kind(st.st_mode)} where a file was expected")
        except BaseException:
            os.close(fd)
            raise
        return fd

    def open_own(self, flags: int) -> int:
        """For a file changed in place (the lock, the results store): a regular file of this
        account with no other hard link (a write to it reaches nothing else). The caller
        closes the descriptor."""
        fd = self._open(flags)
        st = os.fstat(fd)
        problem = (
            f"a file owned by uid {st.st_uid}"
            if st.st_uid != _owner()
            else f"a file with {st.st_nlink - 1} other hard link(s)"
            if st.st_nlink != 1
            else None
        )
        if problem:
            os.close(fd)
            raise self._refused(len(self.parts), problem)
        return fd

    # --- reading -----------------------------------------------------------------------

    def stat(self) -> os.stat_result | None:
        """The entry's own status (a link is not followed), or None when there is none."""
        if not self.parts:
            return os.stat(self.root)
        try:
            with self._folder(self.parts[:-1], create=False) as d:
                return os.stat(self.parts[-1], dir_fd=d, follow_symlinks=False)
        except FileNotFoundError:
            return None

    def exists(self) -> bool:
        return self.stat() is not None

    def is_file(self) -> bool:
        st = self.stat()
        return st is not None and stat.S_ISREG(st.st_mode)

    def is_dir(self) -> bool:
        st = self.stat()
        return st is not None and stat.S_ISDIR(st.st_mode)

    def read_bytes(self, limit: int | None = None) -> bytes:
        """The file's bytes; refused in one line when it holds more than *limit* bytes."""
        fd = self._open(os.O_RDONLY)
        try:
            size = os.fstat(fd).st_size
            if limit is not None and size > limit:
                raise GearlabInputError(f"{self.path}: holds {size} bytes; expected at most {limit}")
            chunks, total = [], 0
            while chunk := os.read(fd, 1 << 20):
                chunks.append(chunk)
                total += len(chunk)
                if limit is not None and total > limit:  # it grew while read
                    raise GearlabInputError(f"{self.path}: holds more than {limit} bytes")
            return b"".join(chunks)
        finally:
            os.close(fd)

    def read_text(self) -> str:
        return self.read_bytes().decode("utf-8")

    def iterdir(self) -> list[Confined]:
        """The entries of this folder, by name ([] when it does not exist)."""
        try:
            with self._folder(self.parts, create=False) as d:
                names = sorted(os.listdir(d))
        except FileNotFoundError:
            return []
        return [self / n for n in names]

    def files(self, pattern: str = "*") -> list[Confined]:
        """The regular files of this folder whose names match *pattern*, by name."""
        return [f for f in self.iterdir() if fnmatch.fnmatchcase(f.name, pattern) and f.is_file()]

    def walk(self) -> Iterator[tuple[Confined, os.stat_result]]:
        """Every entry below this folder with its own status, depth first; links are listed,
        never followed."""
        with self._folder(self.parts, create=False) as d:
            yield from self._walk(d, self.parts)

    def _walk(self, fd: int, parts: tuple[str, ...]) -> Iterator[tuple[Confined, os.stat_result]]:
        with os.scandir(fd) as listing:
            entries = sorted(listing, key=lambda e: e.name)
        for entry in entries:
            st = entry.stat(follow_symlinks=False)
            here = Confined(self.root, (*parts, entry.name))
            yield here, st
            if stat.S_ISDIR(st.st_mode):
                inner = os.open(entry.name, _DIR_FLAGS, dir_fd=fd)
                try:
                    yield from self._walk(inner, (*parts, entry.name))
                finally:
                    os.close(inner)

    # --- writing -----------------------------------------------------------------------

    def mkdir(self) -> None:
        """Make this folder and those above it (within the root) that are missing."""
        with self._folder(self.parts, create=True):
            pass

    def write(self, data: bytes | str, durable: bool = True) -> None:
        """Write the whole file atomically: a fresh temporary name in its folder (never an
        existing entry), synced, renamed over the name (a link there is replaced, not followed).
        durable=False: not synced (a unit's progress line, gone when it ends: the sync held its
        training 1-1.7 % of its time)."""
        if not self.parts:
            raise GearlabInputError(f"{self.root}: refused: a folder, not a file")
        payload = data.encode() if isinstance(data, str) else bytes(data)
        name = self.parts[-1]
        try:
            with self._folder(self.parts[:-1], create=True) as d:
                fd, tmp = _fresh(d, name)
                try:
                    with os.fdopen(fd, "wb") as f:
                        f.write(payload)
                        f.flush()
                        if durable:
                            os.fsync(f.fileno())
                    os.replace(tmp, name, src_dir_fd=d, dst_dir_fd=d)
                except BaseException:
                    try:
                        os.unlink(tmp, dir_fd=d)
                    except OSError:
                        pass
                    raise
        except OSError as exc:
            if exc.filename is None:  # a full disk: the message names the file
                exc.filename = str(self.path)
            raise

    def append(self, data: bytes | str) -> None:
        """Append to the file (made if missing), flushed to disk: the results store."""
        payload = data.encode() if isinstance(data, str) else data
        fd = self.open_own(os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        try:
            view = memoryview(payload)
            while view:
                view = view[os.write(fd, view) :]
            os.fsync(fd)
        except OSError as exc:
            exc.filename = exc.filename or str(self.path)
            raise
        finally:
            os.close(fd)

    def unlink(self, missing_ok: bool = True) -> None:
        try:
            with self._folder(self.parts[:-1], create=False) as d:
                os.unlink(self.parts[-1], dir_fd=d)
        except FileNotFoundError:
            if not missing_ok:
                raise

    def remove_tree(self) -> None:
        """Remove this folder and all it holds (links removed, never followed); nothing when absent."""
        st = self.stat()
        if st is None:
            return
        if not stat.S_ISDIR(st.st_mode):
            self.unlink()
            return
        with self._folder(self.parts[:-1], create=False) as d:
            shutil.rmtree(self.parts[-1], dir_fd=d)


def _fresh(folder_fd: int, name: str) -> tuple[int, str]:
    """(descriptor, name) of a new file '.<name>.<random>.tmp' in the folder: made with
    O_EXCL, so never a name that exists (a planted link included). The name is cut to fit."""
    stem = os.fsencode(name)[: NAME_MAX - 20].decode(errors="ignore")
    for _ in range(100):
        tmp = f".{stem}.{secrets.token_hex(6)}.tmp"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _FILE_FLAGS, 0o666, dir_fd=folder_fd)
        except FileExistsError:
            continue
        return fd, tmp
    raise FileExistsError(errno.EEXIST, "no free temporary name", name)  # pragma: no cover


def is_temporary(name: str) -> bool:
    """Whether *name* is a temporary file of an interrupted write (this module's, or the
    '.<stem>.tmp.<ext>' of earlier versions)."""
    return name.startswith(".") and (name.endswith(".tmp") or ".tmp." in name)


def refuse_unsafe(root: Path, what: str = "run directory") -> None:
    """Refuse *root* in one line when it, or anything in it, is not this account's own plain
    file or folder: a symbolic link, a device, a pipe, a socket, another account's entry, a
    file with a second name elsewhere (a hard link)."""
    root = Path(root)
    folder = Confined(root)
    st = folder.stat()
    if not stat.S_ISDIR(st.st_mode):
        raise GearlabInputError(f"{root}: not a {what} (not a folder)")
    if st.st_uid != _owner():
        raise GearlabInputError(f"{root}: refused: the {what} is owned by uid {st.st_uid}, not by you")
    for entry, st in folder.walk():
        if not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
            raise GearlabInputError(
                f"{entry.path}: refused: {_kind(st.st_mode)} in the {what} {root}; a {what} "
                "holds only its own files and folders"
            )
        if st.st_uid != _owner():
            raise GearlabInputError(
                f"{entry.path}: refused: owned by uid {st.st_uid}, not by you, in the {what} {root}"
            )
        if stat.S_ISREG(st.st_mode) and st.st_nlink != 1:  # a run writes each file once, by rename
            raise GearlabInputError(
                f"{entry.path}: refused: a file with {st.st_nlink - 1} other hard link(s) in the {what} "
                f"{root}; a {what} holds only its own files"
            )


def write_file(target: Path | Confined, data: bytes | str) -> None:
    """Write a whole file: inside a run directory through Confined, elsewhere (a file the
    user named, the cache) by atomic rename."""
    if isinstance(target, Confined):
        target.write(data)
    else:
        atomic_write(Path(target), data)


def read_file(source: Path | Confined) -> bytes:
    """Read a whole file: inside a run directory through Confined, elsewhere as it is."""
    if isinstance(source, Confined):
        return source.read_bytes()
    with open(source, "rb") as f:  # a file the user named, or one this process just wrote
        return f.read()
