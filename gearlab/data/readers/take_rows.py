"""The rows of one take of a logger's file of several takes one after another (data.takes: "log.csv[segment=3]"),
kept of what a reader found: every channel and time vector cut to the samples its take column marks."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...errors import GearlabInputError, which_meant
from .base import Contents, _listing


def marks_of(values: np.ndarray) -> np.ndarray:
    """A take column's marks as text: whole numbers as integers (3.0 -> '3'), others as written."""
    arr = np.asarray(values)
    if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
        return arr.astype(np.int64).astype(str)
    return arr.astype(str)


def no_take_column(path, column: str, available, where: str) -> GearlabInputError:
    """The one line for a 'takes' column *path* does not have (*where*: the key that names it)."""
    return GearlabInputError(
        f"{where}: {path} has no column {column!r}{which_meant(column, [str(c) for c in available])}; expected "
        f"the column marking each sample's take; the file has: {_listing(available)}"
    )


def take_rows(contents: Contents, path, column: str, mark: str) -> Contents:
    """*contents* of a file kept to the rows of take *mark* under *column* (*path*: the take's name, for messages).
    The column marks takes, it is none of the take's channels: not offered as its vibration (a log of time_s, acc_V,
    segment asked 'which channel is the vibration? the file has acc_V, segment')."""
    marks = marks_of(np.ravel(contents.found[column]))
    keep = marks == mark
    if not keep.any():
        known = list(dict.fromkeys(marks.tolist()))
        raise GearlabInputError(f"{path}: column {column!r} has no take {mark!r}; expected one of {_listing(known)}")
    n = marks.size

    def rows(v):
        arr = np.asarray(v)
        return arr[keep] if arr.ndim >= 1 and arr.shape[0] == n else v

    found = {k: rows(v) for k, v in contents.found.items()}
    available = [c for c in contents.available if c != column]
    return replace(contents, found=found, available=available, times=[(w, rows(v)) for w, v in contents.times])
