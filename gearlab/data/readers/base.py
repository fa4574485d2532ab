"""What every reader of a measured file shares: the record size limit, the found-contents record
and the small helpers that turn a file's values into arrays and its keys into channels."""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import GearlabInputError

# rate and interval fields by name, their unit in the name or not ('fs', 'fs_kHz', 'dt_us'): rates.named
from .rates import named, own_field, rate_field

# A time channel by any of its common names, with its unit if the name says one: t, time, time_s,
# "Time [s]", "t (ms)", "t/s", "Time, s", timestamp, Zeit, "Relative Time (s)", "rel. Zeit [ms]",
# LabVIEW's X_Value, ... (seconds unless the name says ms or us; not "Absolute Time": a clock's text)
_TIME_NAME = re.compile(
    r"^(?:(?:relative|rel\.?|elapsed|measurement|meas\.?|recording|acquisition|acq\.?)[\s_\-.]*)?"
    r"(?:t|time|times|timestamp|time[\s_\-]stamp|zeit|zeitstempel|temps|tiempo|tempo|elapsed|x_value)"
    r"(?:\s*(?:[_\-.,/]|in\b)?\s*[\[(]?\s*(s|sec|secs|second|seconds|ms|msec|msecs|milliseconds?|us|usec|µs|μs"
    r"|microseconds?)\s*[\])]?)?$"
)
_TIME_UNITS = {"ms": 1e-3, "msec": 1e-3, "msecs": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3}
_TIME_UNITS |= {"us": 1e-6, "usec": 1e-6, "µs": 1e-6, "μs": 1e-6, "microsecond": 1e-6, "microseconds": 1e-6}


def time_scale(name: str) -> float | None:
    """Seconds per value of a channel named as a time vector (see _TIME_NAME), or None."""
    match = _TIME_NAME.match(" ".join(str(name).split()).lower())
    if match is None:
        return None
    return _TIME_UNITS.get(match.group(1) or "s", 1.0)


def is_rate_or_time(name: str) -> bool:
    """Whether a channel name is a sampling-rate field or a time vector (no signal channel), in a group too: an HDF5
    group's or a MATLAB v7.3 struct's 'take/fs' was listed as a channel, and inspect of a file whose group held one
    signal asked 'which channel is the vibration? the file has take/acc, take/fs'."""
    leaf = str(name).rsplit("/", 1)[-1]
    return named(leaf) is not None or time_scale(leaf) is not None


_MATRIX_COLUMN = re.compile(r"^(.+)\[(\d+)\]$")


def matrix_column(name) -> tuple[str, int] | None:
    """(array, index) of a channel named as one column of a matrix of channels ('data[1]': a logger's N x k
    'data'), or None."""
    match = _MATRIX_COLUMN.match(str(name))
    return (match.group(1), int(match.group(2))) if match else None


def column_of(matrix: np.ndarray, index: int, name: str, path) -> np.ndarray:
    """Channel *index* of a 2-D *matrix* of channels (along its shorter axis: N x k or k x N); one line where there
    is no such channel."""
    arr = np.asarray(matrix)
    if arr.ndim != 2 or index >= min(arr.shape):
        held = f"shape {arr.shape}" if arr.ndim != 2 else f"{min(arr.shape)} channels (0 … {min(arr.shape) - 1})"
        raise GearlabInputError(f"{path}: no channel {name!r}: its array holds {held}; expected a column of a matrix")
    return arr[:, index] if arr.shape[0] >= arr.shape[1] else arr[index, :]


def not_time(names, columns, path, where: str) -> None:
    """One line when a channel asked for (*names*: names or 0-based column indices, None skipped) is the
    file's time or rate column (a header CSV's column '0' is its time column: K's 'Relative Time (s)'
    was read as the vibration, and its acceleration, column '1', as a tacho of 65 Hz)."""
    columns = [str(c) for c in columns]
    for name in (str(n) for n in names if n is not None):
        indexed = name not in columns and name.strip().isdigit() and int(name) < len(columns)
        column = columns[int(name)] if indexed else name
        if is_rate_or_time(column):
            signals = ", ".join(repr(c) for c in columns if not is_rate_or_time(c))
            raise GearlabInputError(
                f"{where}: {name!r} is {Path(str(path)).name}'s time or rate column {column!r}"
                f"{f' (column {name} counts it)' if indexed else ''}; expected a signal channel: {signals}"
            )


# Most megabytes a measured file, and each channel as stored (decoded), may hold; the import
# takes several times that in memory. GEARLAB_MAX_RECORD_MB overrides it (docs/scenarios.md).
MAX_RECORD_MB = 1024


def max_record_bytes() -> int:
    text = os.environ.get("GEARLAB_MAX_RECORD_MB", "")
    try:
        mb = float(text) if text else MAX_RECORD_MB
    except ValueError:
        raise GearlabInputError(f"GEARLAB_MAX_RECORD_MB: expected a number of megabytes, got {text[:40]!r}") from None
    if not mb > 0 or not math.isfinite(mb):
        raise GearlabInputError(f"GEARLAB_MAX_RECORD_MB: expected a positive number of megabytes, got {text[:40]!r}")
    return int(mb * 2**20)


def check_size(path, what: str, nbytes: int) -> None:
    """Refuse *what* of *path* when it would take more than the record size limit."""
    limit = max_record_bytes()
    if nbytes > limit:
        raise GearlabInputError(
            f"{path}: {what} would take {nbytes / 2**20:,.0f} MB, more than the limit of "
            f"{limit / 2**20:,.0f} MB for a measured record (set GEARLAB_MAX_RECORD_MB to allow more)"
        )


@dataclass
class Contents:
    """What a reader found: the asked-for channels, every channel's name, the rate fields.

    rates: (where, value) of every sampling-rate field that applies (Hz, one number);
    times: (where, value) of every time vector that applies (s, one per sample).
    """

    found: dict[str, np.ndarray]
    available: list[str]
    rates: list[tuple[str, object]] = field(default_factory=list)
    times: list[tuple[str, object]] = field(default_factory=list)
    # the value step of channels a reader has already turned from integers to floats (WAV PCM)
    steps: dict[str, float] = field(default_factory=dict)
    # the unit a file states for a channel beside its name (an HDF5 'units' attribute: "m/s^2", "V")
    units: dict[str, str] = field(default_factory=dict)
    # what the reader left out of the file, said once (a logger's footer under the rows: csv.footer_note)
    warnings: list[str] = field(default_factory=list)
    # the names asked of arrays that are no channel of their own, read for their named columns (hdf5.named_matrices)
    matrices: set[str] = field(default_factory=set)


# The unit a file states as text beside its channels, as users save one: an NPZ's `unit="g"` or `vib_unit="m/s^2"`, a
# MATLAB struct's 'units' field (v5 or v7.3), a text table's '# units: g' line. One reading for every reader: a
# file's 'g' was read as m/s² (9.8 times too small) by whichever reader did not know that file's way of saying it.
UNIT_KEYS, UNIT_SUFFIXES = ("unit", "units"), ("_unit", "_units")


def is_unit_entry(name: str) -> bool:
    """An entry (path 'a/b/c') that states a unit: 'unit(s)' or '<channel>_unit(s)', any case."""
    leaf = name.rsplit("/", 1)[-1].lower()
    return leaf in UNIT_KEYS or leaf.endswith(UNIT_SUFFIXES)


def stated_units(texts: dict[str, str], channels: Sequence[str]) -> dict[str, str]:
    """{channel: unit} the text entries *texts* ({path: text}) state for *channels* (paths): a 'unit(s)' entry every
    channel of its group, struct or file (the same parent path), a '<channel>_unit(s)' entry that channel's, which
    stands over the former; an empty text states nothing."""
    out: dict[str, str] = {}
    said = {n: t.strip() for n, t in texts.items() if is_unit_entry(n) and isinstance(t, str)}
    for name, unit in sorted(said.items(), key=lambda item: item[0].rsplit("/", 1)[-1].lower() in UNIT_KEYS):
        parent, _, leaf = name.rpartition("/")
        if leaf.lower() in UNIT_KEYS:  # after the '<channel>_unit' ones: theirs stand
            out.update({c: unit for c in channels if c.rpartition("/")[0] == parent and c not in out})
        elif (base := name[: name.rindex("_")]) in channels:
            out[base] = unit
    return {c: u for c, u in out.items() if u}


# NI's TDMS names a channel's unit "unit_string" (its HDF5 copies too): a channel in g was taken as m/s²
UNIT_ATTRIBUTES = ("units", "unit", "Units", "Unit", "unit_string")


def stated_unit(attrs) -> str | None:
    """The unit an HDF5 object's attributes state ('units' or 'unit', as text or bytes), or None (a list of units is
    its columns', hdf5.named_columns)."""
    for key in UNIT_ATTRIBUTES:
        value = attrs.get(key)
        if np.size(value) > 1:
            return None
        if np.ndim(value) > 0:
            value = np.asarray(value).ravel()[0]
        if value is not None:
            value = value.decode(errors="replace") if isinstance(value, bytes) else str(value)
            return value.strip() or None
    return None


def _text_array(values: np.ndarray) -> np.ndarray:
    """Text of any storage (bytes, object arrays of str, padded MATLAB char rows) as stripped str."""
    flat = [v.decode("utf-8", "replace") if isinstance(v, bytes) else v for v in values.ravel().tolist()]
    return np.char.strip(np.asarray(flat, dtype=str)).reshape(values.shape)


def _normalise(value) -> np.ndarray:
    """A reader's raw value as an array: text unified to str; numbers and anything else as is."""
    if hasattr(value, "toarray"):  # a MATLAB sparse matrix (scipy.sparse): its numbers, dense
        value = value.toarray()
    arr = np.asarray(value)
    if arr.dtype.kind in "SU":
        return _text_array(arr)
    if arr.dtype.kind == "O" and arr.size and all(isinstance(v, str | bytes) for v in arr.ravel().tolist()):
        return _text_array(arr)  # a MATLAB cell array of text, an HDF5 variable-length string
    return arr


def _keyed(available: Iterable[str], get, names: Sequence[str], listed: Iterable[str] | None = None) -> Contents:
    """Contents of a format whose channels are looked up by name (CSV, NPZ, MATLAB v5).

    The sampling rate fields are the entries named fs (any case) and the time vectors the
    entries named as a time vector (time_scale), wherever the format keeps its names.
    """
    available = list(available)
    present = set(available)
    shown = available if listed is None else list(listed)  # what the file names (not index aliases)
    contents = Contents({n: _normalise(get(n)) for n in dict.fromkeys(names) if n in present}, shown)
    for n in shown:
        if named(n) is not None:  # in Hz, a unit in its name read (rates.rate_field)
            contents.rates.append(rate_field(f"'{n}'", n, _normalise(get(n))))
        elif time_scale(n) is not None:
            contents.times.append(_time_field(f"time '{n}'", _normalise(get(n)), time_scale(n)))
    own: dict[str, tuple] = {}  # a channel's own rate field ('ACC_fs'), its time vector ('Data1_time_ACC')
    for name in contents.found:
        for n in available:
            kind = own_field(n, name)
            if kind == "rate":
                own[name] = rate_field(f"'{n}'", n[len(name) + 1 :], _normalise(get(n)))
                contents.rates.append(own[name])
            elif kind == "time":
                contents.times.append((f"time '{n}'", _normalise(get(n))))
            if kind is not None and n in contents.available:  # no channel, as 'fs' is none
                contents.available.remove(n)
    held_to_vibration(contents, list(names), own)
    return contents


def held_to_vibration(contents: Contents, names: list[str], own: dict[str, tuple]) -> None:
    """A channel logged at a lower rate than the vibration (*names*' first), each at a rate of its own (*own*: name ->
    (where, rate field)) over the same time, held sample by sample onto the vibration's (a DAQ's tacho counter at 10
    kHz beside its 20 kHz accelerometer was refused: 'the sampling rates in the file disagree ... expected one
    rate'); its rate field is then no rate of the record. Any other disagreement is left for the rate check."""

    def hz(field) -> float | None:
        value = np.asarray(field[1])
        return float(value.item()) if value.size == 1 and value.dtype.kind in "iuf" and value.item() > 0 else None

    if not names or names[0] not in own or hz(own[names[0]]) is None:
        return
    fv, nv = hz(own[names[0]]), np.asarray(contents.found[names[0]]).shape[0]
    for name in names[1:]:
        values = np.asarray(contents.found.get(name, ()))
        f = hz(own[name]) if name in own and own[name][0] != own[names[0]][0] else None
        if f is None or f >= fv or values.ndim != 1 or values.dtype.kind not in "iuf":
            continue
        if abs(values.size / f - nv / fv) > 2 / f:  # not the same stretch of time
            continue
        contents.found[name] = values[np.minimum((np.arange(nv) * f / fv).astype(np.int64), values.size - 1)]
        held = f"; '{name}' held from {f:g} Hz"  # said where the rate's source is (inspect's first line)
        mine = own[names[0]][0]
        contents.rates[:] = [(w + held if w == mine else w, v) for w, v in contents.rates if w != own[name][0]]
        own[names[0]] = (own[names[0]][0] + held, own[names[0]][1])


def _time_field(where: str, value: np.ndarray, scale: float) -> tuple[str, np.ndarray]:
    """(where, times in seconds) of a time vector written in *scale* seconds per value."""
    if scale == 1.0 or value.dtype.kind not in "biuf":
        return where, value  # text is refused where the rate is computed, naming the field
    return f"{where} (x {scale:g} s)", value * scale


def _scalar(text: str):
    """A comment's value: a number when it reads as one, else the text."""
    try:
        return float(text)
    except ValueError:
        return text


def _column(values: list[str]) -> np.ndarray:
    """A CSV column as float64 when every field is a number, else as text (checked later)."""
    try:
        return np.asarray(values, dtype=np.float64)
    except ValueError:
        return np.asarray(values, dtype=str)


def _one_line(exc: BaseException) -> str:
    """A library exception as one short line (its text, or its type when it has none)."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "..."


def _one_line_repr(value) -> str:
    """repr() of a value found in a file, on one short line whatever the object is."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 80 else text[:77] + "..."


def _listing(names: Iterable[str], limit: int = 12) -> str:
    names = [" ".join(str(n).split()) for n in names]  # names from a file: kept to one line
    if not names:
        return "none"
    shown = ", ".join(names[:limit])
    return shown if len(names) <= limit else f"{shown}, … ({len(names)} in all)"


def channel_listing(names: Iterable[str]) -> str:
    """A file's channels on one line, for messages, its sampling-rate and time fields said apart: they are no
    channels (validate listed an npz's 'Dev1_ai0, Dev1_ai1, Time, fs' and a CSV's 'time_s, acc_V, tacho_V')."""
    names = list(names)
    fields = [n for n in names if is_rate_or_time(str(n))]
    said = _listing([n for n in names if n not in fields])
    kind = {n: "sampling rate" if named(str(n).rsplit("/", 1)[-1]) else "time" for n in fields}
    what = [f"the {kind[n]} '{' '.join(str(n).split())}'" for n in fields]
    return said + (f" (and {', '.join(what)})" if what else "")
