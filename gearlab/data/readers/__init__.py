"""One small reader per measured-file format (gearlab.data.importers uses them): each takes a path
and the asked-for channel names and returns a :class:`~gearlab.data.readers.base.Contents`."""

import copy
import functools
import hashlib
import zipfile
from pathlib import Path

from .base import Contents, check_size, max_record_bytes
from .csv import _read_csv
from .hdf5 import _read_hdf5
from .matlab import _read_mat
from .npz import _read_npz
from .text import _read_text
from .wav import _read_wav

# A text's parse is kept by (reader, path, the file's digest, names): a command reads a record's file more than once
# (its channels listed, then read; a history's takes by the detection and again by the which-gear check: 211 of
# 505 reads in the 20 slowest test files were of a file read before, 1.5 s of 5.1 s). Keyed on the bytes, so a file
# written again is read again; each caller gets its own copy (read_contents adds a matrix's columns to it). Kept
# for a text of at most KEEP_BYTES (a zip's as its member declares it): its columns at most 4 x that (a value of
# one digit and a separator as a float64), 4 kept.
KEEP_BYTES = 8 << 20


@functools.lru_cache(maxsize=4)
def _parsed(read, path: str, digest: bytes, names: tuple) -> Contents:
    return read(Path(path), list(names))


def _text_size(path: Path) -> int:
    """The bytes of the text of *path*: a .zip's members as it declares them; over KEEP_BYTES where it cannot be
    read (not kept: the reader says what is wrong, in its words)."""
    try:
        if path.suffix.lower() != ".zip":
            return path.stat().st_size
        with zipfile.ZipFile(path) as z:
            return sum(i.file_size for i in z.infolist())
    except (OSError, zipfile.BadZipFile):
        return KEEP_BYTES + 1


def _kept(read):
    """*read* with its parse kept (KEEP_BYTES)."""

    def reader(path, names) -> Contents:
        path = Path(path)
        if path.suffix.lower() == ".gz" or _text_size(path) > KEEP_BYTES:
            return read(path, names)
        try:  # in blocks: a streamed text's reading holds no copy of the file
            with path.open("rb") as f:
                digest = hashlib.file_digest(f, lambda: hashlib.blake2b(digest_size=16)).digest()
        except OSError:
            return read(path, names)
        return copy.deepcopy(_parsed(read, str(path), digest, tuple(names)))

    return reader


READERS = {
    "CSV": _kept(_read_csv),
    "text": _kept(_read_text),
    "zipped text": _kept(_read_text),
    "NPZ": _read_npz,
    "HDF5": _read_hdf5,
    "WAV": _read_wav,
    "MATLAB": _read_mat,
}

__all__ = ["READERS", "Contents", "check_size", "max_record_bytes"]
