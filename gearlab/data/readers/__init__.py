"""One small reader per measured-file format (gearlab.data.importers uses them): each takes a path
and the asked-for channel names and returns a :class:`~gearlab.data.readers.base.Contents`.

parsed() is the one way a file is read: the last few files parsed are kept in the process, so a logger's
file of several takes (data.takes), read once per take, and a record read again by inspect, score and the
run are parsed once."""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from .base import Contents, check_size, max_record_bytes
from .csv import _read_csv
from .hdf5 import _read_hdf5
from .matlab import _read_mat
from .npz import _read_npz
from .text import _read_text, asked_only
from .wav import _read_wav

READERS = {
    "CSV": _read_csv,
    "text": _read_text,
    "zipped text": _read_text,
    "NPZ": _read_npz,
    "HDF5": _read_hdf5,
    "WAV": _read_wav,
    "MATLAB": _read_mat,
}

# Files kept parsed: a logger's file of takes and the record an inspect, a score and a run read again; a few, as
# each may hold a record of up to GEARLAB_MAX_RECORD_MB
KEPT_FILES = 4
# A file changed within this long of its last change may change again with the same time stamp and size (a file
# system stamps in ticks of a few ms): kept only once older, as git treats a "racily clean" file
SAME_STAMP_S = 0.1
_kept: OrderedDict[tuple, Contents] = OrderedDict()


def parsed(fmt: str, path: Path, names: Sequence[str]) -> Contents:
    """READERS[fmt](path, names), parsed once while the file is unchanged (the same file, size and time stamps):
    a copy of the contents each call, its arrays read-only (shared by every caller)."""
    stat = path.stat()
    key = (fmt, str(path.resolve()), stat.st_dev, stat.st_ino, stat.st_size, stat.st_mtime_ns, stat.st_ctime_ns)
    key += (*names, asked_only())  # contents read with only the asked-for numbers parsed are kept apart
    contents = _kept.get(key)
    if contents is None:
        contents = READERS[fmt](path, names)
        _freeze(contents)
        if time.time_ns() - stat.st_mtime_ns > SAME_STAMP_S * 1e9:
            _kept[key] = contents
            while len(_kept) > KEPT_FILES:
                _kept.popitem(last=False)
    else:
        _kept.move_to_end(key)
    return replace(
        contents,
        found=dict(contents.found),
        available=list(contents.available),
        rates=list(contents.rates),
        times=list(contents.times),
        steps=dict(contents.steps),
        units=dict(contents.units),
        warnings=list(contents.warnings),
    )


def _freeze(contents: Contents) -> None:
    for value in [*contents.found.values(), *(v for _, v in contents.rates), *(v for _, v in contents.times)]:
        if isinstance(value, np.ndarray):
            value.flags.writeable = False


__all__ = ["READERS", "Contents", "check_size", "max_record_bytes", "parsed"]
