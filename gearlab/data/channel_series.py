"""A channel read from a measured file as a time series: a 1-D finite float64 array (signals.check_signal), or one
line saying what the file holds instead (text, a MATLAB struct, true/false values, a matrix of channels), and two
channels of one record checked to be of one length. gearlab.data.recordings' read_recording and `gearlab inspect`
read every channel through it."""

from __future__ import annotations

import numpy as np

from ..errors import GearlabInputError, prefixed
from ..signals import check_signal


def _first_text(arr: np.ndarray) -> tuple[int, str]:
    """Position and value of the first entry of a text array that is not a number."""
    for i, v in enumerate(arr.ravel().tolist()):
        try:
            float(v)
        except (TypeError, ValueError):
            return i, v
    return 0, arr.ravel()[0] if arr.size else ""


def _struct_series(value, at: str, depth: int = 0) -> list[str]:
    """The dotted names of a MATLAB struct's (scipy's mat_struct) fields that hold series of numbers, nested too."""
    if depth > 3 or not hasattr(value, "_fieldnames"):
        return []
    found = []
    for key in value._fieldnames:
        inner, name = getattr(value, key), f"{at}.{key}"
        arr = np.asarray(inner)
        if arr.dtype.kind in "iuf" and arr.size > 1:
            found.append(name)
        elif arr.dtype.kind == "O" and arr.size == 1:
            found += _struct_series(arr.item(), name, depth + 1)
    return found


def series(raw, name: str, role: str, path: str) -> np.ndarray:
    """A channel as a 1-D finite float64 time series (check_signal), or one clear line."""
    what = f"{role} channel '{name}'"
    arr = np.asarray(raw)
    if arr.dtype.kind in "US":
        i, v = _first_text(arr)
        shown = "an empty field" if v == "" else repr(v)
        raise GearlabInputError(f"{path}: {what} is not numeric: {shown} at sample {i}; expected numbers")
    if arr.dtype.kind == "O" and arr.size == 1 and (fields := _struct_series(arr.item(), name)):
        # a MATLAB struct named for its channel (Simcenter Testlab's Signal_1, its numbers in y_values.values)
        raise GearlabInputError(
            f"{path}: {what} is not numeric: a struct; expected the field that holds its numbers: "
            + ", ".join(fields[:4])
        )
    if arr.dtype.kind not in "biuf":
        raise GearlabInputError(f"{path}: {what} is not numeric (stored as {arr.dtype}); expected an array of numbers")
    if arr.dtype.kind == "b" and role == "vibration":  # a tacho's pulses may be true/false; a vibration not
        raise GearlabInputError(f"{path}: {what} holds true/false values; expected a vibration signal of numbers")
    if arr.ndim > 1 and sum(s > 1 for s in arr.shape) <= 1:
        arr = arr.reshape(-1)  # a 1×N or N×1 matrix is one channel
    if arr.ndim == 0:
        raise GearlabInputError(f"{path}: {what} holds a single value; expected a time series, one value per sample")
    if arr.ndim > 1:
        raise GearlabInputError(
            f"{path}: {what} has shape {arr.shape}; expected one channel over time (a 1-D array)"
            + (f", e.g. one of its columns: '{name}[0]' … '{name}[{min(arr.shape) - 1}]'" if arr.ndim == 2 else "")
        )
    with prefixed(path):
        return check_signal(arr, what)


def same_length(x: np.ndarray, name: str, role: str, n: int, vibration: str, path: str) -> None:
    if x.size != n:
        raise GearlabInputError(
            f"{path}: {role} channel '{name}' has {x.size} samples but vibration channel '{vibration}' has {n}; "
            "expected channels of equal length (one value per sample)"
        )
