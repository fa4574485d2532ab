"""The one import path of a measured recording, for every kind: the file, its channels, their
roles and units, the sampling rate and the shaft angle (docs/real_data.md).

    file ─► named channels + rate fields          read_contents: one small reader per format (data.readers)
         ─► vibration in m/s², tacho, rate         read_recording: units from the sensitivity, the
                                                  gain and what a column's name says ('acc_V'),
                                                  else the file or the scenario's 'unit' key
         ─► complete revolutions                   cut_recording (the detection and gap [target]: what the
                                                  acquisition did said, a drifting baseline out: signals.spikes);
                                                  gearlab.data.importers.import_measured (a dataset)

    check_recording opens only a file's header (its channel names, rate fields and storage types) and checks what a
    scenario says of it: `gearlab validate` finds a wrong column, a missing rate or a unit mistake without reading it.

Formats (by extension) and where the sampling rate comes from:
    .csv / .tsv   columns separated by commas, semicolons, tabs or blanks; a header row of names,
                  or none (columns "0", "1", …); '#' comment lines; the rate from a time column
                  (time, t, time_s, 'Time [s]', 'time (ms)', …: see time_scale) or a comment
                  '# fs = 51200'
    .txt .dat .gz .zip  blank-separated text: plain, gzipped, or one file zipped (streamed); a header row or none
                  (both: a logger's preamble above the table is read, its footer under the rows left out and said)
    .npz          arrays by name, loaded without pickle; rate from a scalar 'fs' or a time array
    .h5 / .hdf5   datasets by path ("group/acc"); rate from an attribute 'fs' on the channel,
                  else from an 'fs' attribute or 'fs'/time dataset in its group, or the
                  nearest group above that has one (up to the file's root)
    .wav          channels by index ("0", "1", …); rate from the header; integer PCM scaled to ±1
    .mat          MATLAB v5 variables (scipy), or v7.3 (an HDF5 file, read with h5py); rate
                  from a variable 'fs' or 'Fs' or a time variable

A channel is named as its file names it, or by its 0-based column index in a text file (an integer in a scenario,
or its digits). Rate fields are 'fs' in any case (and sample_rate, sampling_rate; fs_kHz: readers.rates); when the file
carries a rate and one is given too they must agree.

Every bad file raises :class:`GearlabInputError` with one line that names the file, the channel and what was expected;
nothing is returned half-built. Sizes are checked before anything is read (GEARLAB_MAX_RECORD_MB, readers.base).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import GearlabInputError, prefixed, which_meant
from ..files import split_take, take_file  # a take of a logger's file of several: data.takes
from ..gearbox.orders import order_table, settle_turns
from ..gearbox.speed import varies_words  # a run-up said so, with a tacho or without
from ..signals import first_complete
from ..signals.checks import VARIES_WORDS, fmt_hz, reversal, revolution_speeds, settled, turn_times
from ..signals.nonsync import revolutions_needed
from ..signals.spikes import acquisition
from ..signals.tacho_mended import mended_words
from ..units import rate_hz
from . import raw_binary
from .channel_series import same_length, series  # every channel read as a series: one check
from .channel_units import STANDARD_GRAVITY as STANDARD_GRAVITY  # the one g of units and sensitivities
from .channel_units import UNITS as UNITS
from .channel_units import channel_scale as channel_scale
from .channel_units import level_hint as level_hint
from .channel_units import name_unit as name_unit  # what a channel's name says of its unit
from .readers import Contents, check_size, parsed
from .readers.base import _listing, _one_line, _one_line_repr, channel_listing, column_of, matrix_column, not_time
from .readers.base import is_rate_or_time as is_rate_or_time  # the one list of rate and time names
from .readers.base import time_scale as time_scale
from .readers.headers import HEADERS, Header, time_hint
from .readers.rates import CoarseTimes, own_field
from .readers.take_rows import no_take_column, take_rows
from .time_column import rate_from_time, take_columns

TWO_PI = 2.0 * np.pi

# Extension -> format name used in messages.
FORMATS = {
    ".csv": "CSV",
    ".tsv": "CSV",
    ".txt": "text",
    ".dat": "text",
    ".zip": "zipped text",
    ".gz": "zipped text",
    ".npz": "NPZ",
    ".h5": "HDF5",
    ".hdf5": "HDF5",
    ".wav": "WAV",
    ".mat": "MATLAB",
}
TACHO_KINDS = ("auto", "angle", "pulses")

# Relative agreement asked of two sampling rates (the file's and the one given).
_RATE_RTOL = 1e-6
# A wrapped angle spans one turn; measured ones may fall a little short or overshoot.
_TURN_SLACK = 0.01
# Share of rising steps that marks a channel as a shaft angle rather than a pulse train (flat most of the time)
_RISING_SHARE = 0.9


def file_problem(path: Path) -> str | None:
    """Why *path* cannot be read as a measured file ('no such file', 'is not a file', 'is empty', a name
    too long, a NUL in it), or None when it is a file (a take's, "log.csv[segment=3]": its file's). Every kind
    checks its measured files so when a scenario is loaded: `gearlab validate` finds them all."""
    path = take_file(path)
    try:
        exists, is_file = path.exists(), path.is_file()
    except (OSError, ValueError) as exc:  # a name too long, a NUL character in it, ...
        return f"cannot be a measured record: {getattr(exc, 'strerror', None) or exc}"
    if not exists:
        return "no such file"
    if not is_file:
        return "is not a file"
    try:
        empty = path.stat().st_size == 0
    except OSError as exc:
        return f"cannot be a measured record: {exc.strerror or exc}"
    return "is empty (0 bytes)" if empty else None  # a copy or export that wrote nothing: no reader's own words


def check_measured_file(path: Path, where: str = "", expected: str = "") -> None:
    """Refuse *path* in one line (prefixed with *where*) unless it is a readable file."""
    problem = file_problem(Path(path))
    if problem is not None:
        head = f"{where}: " if where else ""
        shown_path = _one_line_repr(str(path)) if problem.startswith("cannot") else str(path)
        raise GearlabInputError(
            f"{head}{shown_path}: {problem}; expected {expected or f'a measured record ({supported()})'}"
        )


def supported() -> str:
    return ", ".join(FORMATS)


# --- reading a file (the readers themselves: gearlab.data.readers) ---------------------------


def format_of(path: Path) -> str:
    """The reader's name for a measured file that may be read (check_measured_file), by its suffix;
    one line naming the supported types otherwise."""
    check_measured_file(path)
    suffix = take_file(path).suffix
    fmt = FORMATS.get(suffix.lower())
    if fmt in (None, "CSV", "text") and (raw := raw_binary.refusal(take_file(path), suffix.lower(), fmt is not None)):
        raise GearlabInputError(raw)  # a DAQ's samples: how to write them as a file read with its rate
    if fmt is None:
        raise GearlabInputError(f"{path}: unknown file type '{suffix or '(no extension)'}'; supported: {supported()}")
    return fmt


def read_contents(path, names: Sequence[str], roles: dict[str, str] | None = None) -> tuple[Contents, str]:
    """Read *names* from *path* (a take's name, "log.csv[segment=3]": that take's rows alone; takes):
    (contents, format name). Every failure is one clear line."""
    path, take = Path(path), split_take(path)
    fmt, file = format_of(path), take_file(path)
    check_size(path, "the file", file.stat().st_size)
    columns = {n: c for n in names if (c := matrix_column(n)) is not None}  # 'data[1]': a matrix's column
    read = list(dict.fromkeys(columns[n][0] if n in columns else n for n in names))
    if take is not None and take[1] not in read:
        read.append(take[1])
    try:
        contents = parsed(fmt, file, read)
    except GearlabInputError:
        raise
    except MemoryError:
        raise GearlabInputError(f"cannot read {path} as {fmt}: not enough memory for what it declares") from None
    except Exception as exc:  # noqa: BLE001 - each library fails its own way on a corrupt file
        raise GearlabInputError(f"cannot read {path} as {fmt}: {_one_line(exc)}") from None
    for name, (matrix, index) in columns.items():
        if matrix in contents.found and name not in contents.found:
            contents.found[name] = column_of(contents.found[matrix], index, name, path)
            if (unit := contents.units.get(name, contents.units.get(matrix))) is not None:
                contents.units[name] = unit  # the column's own (hdf5.named_columns), else its matrix's
    if take is not None:
        if take[1] not in contents.found:
            raise no_take_column(file, take[1], contents.available, str(path))
        contents = take_rows(contents, path, take[1], take[2])
    contents.warnings += [
        f"column {c!r} numbers takes one after another? each file is read as one take: takes = {c!r} reads each "
        "as a recording of its own, or write one file per take"
        for c in take_columns(contents.available)
        if c not in read
    ]
    for name in names:  # a matrix whose columns are named is none, as validate's header says (readers.headers)
        if name not in contents.found or name in contents.matrices:
            role = f"{roles[name]} " if roles and name in roles else ""
            free = [c for c in contents.available if c not in (roles or {})]  # not the tacho's own, given
            raise GearlabInputError(
                f"{path}: no {role}channel '{name}'{channel_meant(name, free, role.strip())}; "
                f"the file has channels: {channel_listing(contents.available)}"
            )
    return contents, fmt


def read_channels(path, names: Sequence[str]) -> tuple[dict[str, np.ndarray], float | None]:
    """The named channels of a measured-data file and its sampling rate (None if it has none).

    Arrays come back as stored (numbers, or text for label channels; WAV PCM scaled to ±1). The rate is the file's
    'fs' field or follows from its time vector; raises on a missing file or channel, an unreadable file, or a bad or
    inconsistent rate field."""
    names = list(names)
    contents, _ = read_contents(path, names)
    rate = file_rate(contents, None, str(path))
    return contents.found, (None if rate is None else rate[0])


# --- sampling rate -----------------------------------------------------------------------


def rate_value(value, where: str, path: str) -> float:
    arr = np.asarray(value)
    shown = _one_line_repr(arr.item()) if arr.size == 1 else f"{arr.size} values"
    if arr.size == 1 and arr.dtype.kind in "US":  # a DAQ's rate as text with its unit, '25.6 kHz', as a scenario's fs
        text = arr.item().decode("latin-1") if isinstance(arr.item(), bytes) else arr.item()
        try:
            fs = rate_hz(text.strip(), "")
        except GearlabInputError as e:
            raise GearlabInputError(
                f"{path}: sampling rate field {where} must be one number in Hz or text with its unit, e.g. '25.6 kHz'"
                f", got {shown} ({str(e).removeprefix(': ')})"
            ) from None
    elif arr.dtype.kind not in "biuf" or arr.size != 1:
        raise GearlabInputError(f"{path}: sampling rate field {where} must be one number in Hz, got {shown}")
    else:
        fs = float(arr.item())
    if not math.isfinite(fs) or fs <= 0:
        raise GearlabInputError(f"{path}: sampling rate {where} must be positive, got {fs:g} Hz")
    return fs


def file_rate(contents: Contents, n: int | None, path: str) -> tuple[float, float, str] | None:
    """(fs, relative tolerance, where) from the file's rate fields, or None when it has none.

    An explicit 'fs' field comes first; all fields the file has must agree with each other."""
    found = [(rate_value(v, where, path), _RATE_RTOL, where) for where, v in contents.rates]
    for where, v in contents.times:
        fs, uncertainty, where = rate_from_time(v, where, path, n, take_columns(contents.available))
        found.append((fs, max(_RATE_RTOL, uncertainty), where))
    if not found:
        return None
    fs0, tol0, where0 = found[0]
    for fs, tol, where in found[1:]:
        if abs(fs - fs0) > max(tol, tol0) * fs0:
            raise GearlabInputError(
                f"{path}: the sampling rates in the file disagree: {where0} gives {fmt_hz(fs0)}, "
                f"{where} gives {fmt_hz(fs)}; expected one rate"
            )
    return found[0]


def sampling_rate(contents: Contents, given: float | None, n: int, path: str) -> tuple[float, str]:
    """The rate to use and where it came from: the file's, checked against a given one."""
    try:
        from_file = file_rate(contents, n, path)
    except CoarseTimes as exc:  # a clock stamped coarser than a period: the rate given, checked against its stamps
        if given is None:
            raise
        from_file = (exc.fs, exc.tolerance, exc.where)
    if from_file is None:
        if given is None:
            hint = time_hint(path) or " (--fs / fs = ...)"
            raise GearlabInputError(f"{path}: no sampling rate: the file has no 'fs'/time and none was given{hint}")
        return float(given), "given"
    fs, tol, where = from_file
    if given is not None:
        if abs(given - fs) > tol * fs:
            raise GearlabInputError(
                f"{path}: the sampling rate given, fs = {given:.10g} Hz, disagrees with {where} in the file "
                f"({fs:.10g} Hz); expected them equal (relative difference <= {tol:.2g})"
            )
        # Agreeing within the tolerance; the given figure is exact where a time column is rounded.
        return float(given), f"given, agrees with {where}"
    return fs, where


# --- shaft angle -------------------------------------------------------------------------


def wrap(x: np.ndarray) -> np.ndarray:
    """Angle into [-π, π): keeps every angle modulo 2π, so where revolutions start."""
    return (x + np.pi) % TWO_PI - np.pi


def tacho_kind(tacho: np.ndarray) -> str:
    """ "angle" or "pulses" for a tacho channel (tacho_kind = "auto").

    A shaft angle rises at (nearly) every sample: steadily (continuous angle), or with wraps of about −2π between steady
    rises when it is wrapped, in which case it spans one turn (2π ± 1 %). A once-per-revolution pulse train is flat
    between edges that jump both ways. Anything that is not an angle is read as pulses."""
    steps = np.diff(tacho)
    if steps.size == 0:
        return "pulses"
    wraps = np.abs(steps) > np.pi
    rising = np.mean(steps[~wraps] > 0) if np.any(~wraps) else 0.0
    if rising < _RISING_SHARE:
        return "pulses"
    if not wraps.any():
        return "angle"  # continuous
    span = float(tacho.max() - tacho.min())
    one_turn = abs(span - TWO_PI) <= _TURN_SLACK * TWO_PI
    return "angle" if one_turn and np.all(steps[wraps] < 0) else "pulses"


def angle_tacho(tacho: np.ndarray) -> np.ndarray:
    """A tacho read as an angle -> the wrapped tacho that cut_revolutions unwraps.

    Wrapped angles of any one-turn interval ([-π, π), [0, 2π), a slight overshoot) and continuous angles all become the
    same [-π, π) tacho; an angle spanning more than a turn with wraps in it (degrees?) is refused."""
    span = float(tacho.max() - tacho.min())
    continuous = not np.any(np.abs(np.diff(tacho)) > np.pi)
    if span <= (1 + _TURN_SLACK) * TWO_PI or continuous:
        return wrap(tacho)
    raise GearlabInputError(
        f"spans {span:.4g} (from {tacho.min():.4g} to {tacho.max():.4g}), more than one turn (2π), and jumps "
        "back: expected the shaft angle in radians, wrapped into one turn or continuous (degrees? multiply by π/180)"
    )


# --- a recording ---------------------------------------------------------------------------


def channel_key(value) -> str:
    """A channel as a scenario names it (a name, or a 0-based column index) as the readers take it."""
    return str(value) if isinstance(value, int) and not isinstance(value, bool) else value


def named(name: str, columns: list[str]) -> str:
    """The header name of a column asked for by its 0-based index ("1"), else *name* (what its unit is read from)."""
    if name not in columns and str(name).strip().isdigit() and int(name) < len(columns):
        return columns[int(name)]
    return name


@dataclass
class Recording:
    """One measured file's vibration (m/s²) and tacho, its rate, and what else was asked for."""

    path: str
    format: str
    channels: list[str]  # the file's signal channels (rate and time fields left out)
    vibration: str
    signal: np.ndarray
    fs: float
    fs_source: str
    tacho_name: str | None
    tacho: np.ndarray | None
    units: str  # how the values became m/s² (channel_scale)
    step: float = 0.0  # one quantisation step in m/s² (0: floating-point data, or not read: inspect)
    extra: dict[str, np.ndarray] = field(default_factory=dict)  # other channels asked for, as stored
    warnings: tuple[str, ...] = ()  # what the reader left out of the file (a logger's footer), said once


def read_recording(
    path,
    vibration,
    tacho=None,
    *,
    fs: float | None = None,
    sensitivity: float | None = None,
    gain: float | None = None,
    unit: str | None = None,
    extra: Sequence[tuple[str, str]] = (),
    where: str = "",
) -> Recording:
    """The vibration in m/s² (channel_scale; *unit*: the scenario's 'unit' key), the tacho and the rate of one file;
    *extra*: (name, role) of other channels as stored; *where*: the scenario table of the keys (default: the file)."""
    path = str(path)
    vibration, tacho = channel_key(vibration), channel_key(tacho) if tacho is not None else None
    roles = {vibration: "vibration"}
    for name, role in ((tacho, "tacho"), *extra):
        if name is not None:
            roles.setdefault(channel_key(name), role)
    contents, fmt = read_contents(path, list(roles), roles)
    not_time((vibration, tacho), contents.available, path, where or path)
    raw = np.asarray(contents.found[vibration])
    # An integer record is quantised: one count (a WAV's 1/2^(bits-1) of full scale) is its step.
    step = contents.steps.get(vibration, 1.0 if raw.dtype.kind in "iu" else 0.0)
    name = named(vibration, contents.available)
    stated = contents.units.get(name)  # the unit the file states for it
    scale, units = channel_scale(name, sensitivity, gain, where or path, unit=stated, declared=unit, path=path)
    vib = series(raw, vibration, "vibration", path) * scale
    units += level_hint(units, vib, "unit = '{}'")
    rate, fs_source = sampling_rate(contents, fs, vib.size, path)
    tacho_values = None if tacho is None else series(contents.found[tacho], tacho, "tacho", path)
    if tacho is not None:
        same_length(tacho_values, tacho, "tacho", vib.size, vibration, path)
    channels = [c for c in contents.available if not is_rate_or_time(str(c))]
    asked = {channel_key(n): contents.found[channel_key(n)] for n, _ in extra if n is not None}
    said = tuple(contents.warnings)  # what the reader left out: a logger's footer
    step = float(step * scale)  # in m/s²
    return Recording(
        path, fmt, channels, vibration, vib, rate, fs_source, tacho, tacho_values, units, step, asked, said
    )


# --- the shaft angle and the revolutions ---------------------------------------------------


UNCONFIRMED = "which the mesh lines do not confirm"  # a declared speed that a description's mesh lines contradict


def speed_channel_note(x: np.ndarray) -> str | None:
    """Why a tacho gave no revolutions, where it holds a positive level varying less than 30 % but varying (a speed
    channel in rpm or Hz; a pulse train swings between its low and high level, a stuck one is flat), else None."""
    lo, mid, hi = np.percentile(x, [1, 50, 99])
    if not (lo > 0 and 0 < hi - lo < 0.3 * mid):
        return None
    return (
        f"it holds a steady level ({mid:.4g} ± {(hi - lo) / 2:.2g}), neither pulses nor a shaft angle: a speed "
        f"channel? expected a tacho's pulses or the shaft angle; give the speed instead (--speed / speed = "
        f"'{mid:.4g} rpm' or '{mid:.4g} Hz', as it reads) or no tacho: the mesh lines give the speed"
    )


def shaft_angle(
    rec: Recording,
    *,
    kind: str = "auto",
    pulses_per_rev: int = 1,
    speed_hz: float | None = None,
    gearbox=None,
    tacho_shaft=None,
    smooth: bool = False,
) -> tuple[dict, np.ndarray, str]:
    """(cut_revolutions' angle argument, the continuous angle it computes from it, a description).

    From the tacho: a shaft angle, or a pulse train of *pulses_per_rev* marks per revolution (the j-th rising edge at
    2πj/N); without one: the declared speed, or -- with a gearbox description and no speed, or to refine a declared one
    to ±1 % -- the speed its mesh lines show, followed through the record on a mesh harmonic's phase (follow_speed;
    constant where it follows none; refused when ambiguous). A tacho on another shaft (*tacho_shaft*, a
    gearbox.orders.TachoShaft, else the *gearbox*'s [sensor] tacho): its angle / its turns is the input's, a slower
    one's marks joined by a spline (*smooth*). The angle is computed here with the functions cut_revolutions applies
    to the same argument: revolution boundaries found here (for labels) are those of the revolutions it cuts.
    """
    from ..signals.angle import MarksMiscounted, angle_from_pulses, angle_from_speed, unwrap_tacho

    path, n, fs = rec.path, rec.signal.size, rec.fs
    if rec.tacho is None:
        how = "nominal speed"
        if gearbox is not None:
            from ..gearbox.speed import follow_speed, settling

            # a real record's speed always swings a little (0.3 %: every mesh line smeared over its sidebands, the
            # TSA's mesh harmonic lost); followed on a mesh harmonic's phase, revolutions are cut as from a tacho
            theta, speed_hz, found, note = follow_speed(
                rec.signal, fs, gearbox, speed_hz, f"{path}: vibration channel '{rec.vibration}'", file=str(path)
            )
            if theta is not None:
                found = found.removesuffix(", followed on a mesh harmonic's phase")
                angle = wrap(theta - theta[0])  # zero at the first sample, as at a constant speed
                return (
                    {"tacho": angle, "ends": settling(gearbox, speed_hz)},  # unsettled: localisation leaves out
                    unwrap_tacho(angle),
                    f"speed followed on the mesh phase ({found}; {gearbox.name}), mean {fmt_hz(speed_hz)}",
                )
            how = f"constant speed {found} ({gearbox.name})"
            if note and found == "declared":  # (a pinion's tooth count off: the gap fitted effects, no word)
                how = f"{how} {fmt_hz(speed_hz)}, {UNCONFIRMED}: {note}"
                return {"speed_hz": float(speed_hz)}, angle_from_speed(n, fs, speed_hz), how
        if speed_hz is None:
            raise GearlabInputError(
                f"{path}: no tacho and no speed: expected a tacho channel, a speed (e.g. '25 Hz'), or a gearbox "
                "description to find the speed from its mesh orders"
            )
        return {"speed_hz": float(speed_hz)}, angle_from_speed(n, fs, speed_hz), f"{how} {fmt_hz(speed_hz)}"
    name = rec.tacho_name
    if tacho_shaft is None and gearbox is not None:  # the description's [sensor] tacho
        from ..gearbox.orders import TachoShaft

        tacho_shaft = TachoShaft.of(gearbox, gearbox.sensor.tacho, f"{path}: [sensor] key 'tacho'")
    if tacho_shaft is not None and tacho_shaft.turns != 1:  # a slower or faster shaft: angle / turns is the input's
        source, angle, how = shaft_angle(rec, kind=kind, pulses_per_rev=pulses_per_rev, smooth=tacho_shaft.turns < 1)
        angle = angle / float(tacho_shaft.turns)
        cut = unwrap_tacho(wrapped := wrap(angle))  # the angle it returns keeps the tacho's zero's turns (numbers)
        return {"tacho": wrapped}, cut + (angle[0] - cut[0]), f"{how} on the {tacho_shaft.name} shaft"
    found_kind = kind if kind != "auto" else ("pulses" if pulses_per_rev > 1 else tacho_kind(rec.tacho))
    detected = ", detected" if kind == "auto" and pulses_per_rev == 1 else ""
    if found_kind == "angle":
        with prefixed(f"{path}: tacho '{name}' (read as the shaft angle in rad{detected})"):
            wrapped = angle_tacho(rec.tacho)
            return {"tacho": wrapped}, unwrap_tacho(wrapped), f"tacho '{name}' (shaft angle{detected})"
    # angle_from_pulses fails only for want of edges: a tacho that never completes a revolution.
    what = "a once-per-revolution pulse train" if pulses_per_rev == 1 else f"{pulses_per_rev} pulses per revolution"
    where = f"{path}: tacho '{name}' never completes a revolution (read as {what}{detected})"
    try:
        angle = angle_from_pulses(rec.tacho, fs, smooth=smooth, marks=pulses_per_rev)
    except MarksMiscounted as exc:  # it turns: its marks are miscounted
        raise GearlabInputError(f"{path}: tacho '{name}' (read as {what}{detected}): {exc}") from None
    except GearlabInputError as exc:
        raise GearlabInputError(f"{where}: {speed_channel_note(rec.tacho) or exc}") from None
    mended = mended_words(rec.tacho, fs, pulses_per_rev)  # a missed pulse put back, a glitch's left out: said
    if pulses_per_rev == 1:
        return {"pulses": rec.tacho}, angle, f"tacho '{name}' (once-per-revolution pulses{detected}{mended})"
    angle = angle / pulses_per_rev
    # the wrapped angle in [-π, π): cut_revolutions unwraps it and starts revolutions at its 2πk crossings
    how = f"tacho '{name}' ({pulses_per_rev} pulses per revolution{mended})"
    return {"tacho": (wrapped := wrap(angle))}, unwrap_tacho(wrapped), how  # wrapped once


def steady_start(
    revs: np.ndarray, where: str, rtol: float | None = None, window: int = 1
) -> tuple[int, str, str | None]:
    """(index of the first steady revolution, how it was found, a warning or None).

    A start-up transient is dropped (steady_start_stats). A level that never settles -- a steady record whose
    revolution-to-revolution spread exceeds the tolerance, or a slow drift -- is no failure: every revolution is kept
    and the drift is said in a warning."""
    from ..signals import steady_start_stats

    if revs.shape[0] < 2:
        return 0, "not judged (fewer than 2 revolutions to compare)", None
    try:
        return steady_start_stats(revs, *(() if rtol is None else (rtol,)), window=window), "stats", None
    except GearlabInputError as exc:
        return (
            0,
            "none found (level drifts; every revolution kept)",
            (
                f"{where}: {exc}; every revolution is kept (transient = 'none' says the record is steady, "
                "rtol = ... widens the tolerance)"
            ),
        )


@dataclass(frozen=True)
class CutRecording:
    """One measured record cut into revolutions: *revolutions* (n, points) in m/s², not
    standardised, in record order, starting at the first tacho mark."""

    path: str
    revolutions: np.ndarray
    speed_hz: float
    fs: float
    samples: int
    transient_revolutions: int
    angle_source: str = ""
    warnings: tuple[str, ...] = ()
    first_revolution: int = 0  # revolutions[0]'s number from the angle's zero (first_complete)
    units: str = ""  # how the values became m/s² (channel_scale): gearlab score shows it
    speeds: np.ndarray | None = None  # each revolution's (Hz, input shaft): gearlab score scores a run-up's in band
    read: tuple = ()  # (the Recording read, drift out; its flaws) where keep_read: gearlab score reads it once
    reverses: tuple = ()  # (k, t0, t1): its shaft reverses in revolution k - 1, t0 .. t1 s (signals.checks.reversal)
    settled: slice | None = None  # the revolutions localisation reads: a followed angle's unsettled ends out (Take.of)


def cut_recording(
    path,
    *,
    vibration,
    tacho=None,
    pulses_per_rev: int = 1,
    sensitivity: float | None = None,
    gain: float | None = None,
    unit: str | None = None,
    fs: float | None = None,
    speed_hz: float | None = None,
    gearbox=None,
    points: int | None = None,
    transient: str = "none",
    where: str = "",
    tacho_shaft=None,
    settle_window: int = 1,
    keep_read: bool = False,
    before_cut=None,
) -> CutRecording:
    """Read a record (read_recording), find the input's angle (shaft_angle; *tacho_shaft* a TachoShaft) and
    cut its complete revolutions (*transient* "stats" drops a start-up over settle_turns or *settle_window*).
    *before_cut*(fs, mean input speed in Hz): called once the angle is known, before the cut, the dear part of a
    read (a tacho's count typed 10 x short makes 10 x the revolutions: parts.measured.Target.read refuses it)."""
    from ..signals import POINTS, cut_revolutions

    rec = read_recording(path, vibration, tacho, fs=fs, sensitivity=sensitivity, gain=gain, unit=unit, where=where)
    if (raw := rec.signal).size and raw.min() == raw.max():  # a wrong column, a sensor unplugged (drift still in)
        raise GearlabInputError(
            f"{path}: vibration column {_one_line_repr(rec.vibration)}: all {raw.size} values equal {raw[0]:g}; "
            "expected a measured vibration (a constant column: a wrong column, or a sensor not connected)"
        )
    with prefixed(f"{path}: vibration {_one_line_repr(rec.vibration)}"):  # the speed from the mesh lines too, drift out
        rec.signal, flaws = acquisition(rec.signal, rec.fs)
    raw = rec.signal
    source, angle, how = shaft_angle(
        rec, pulses_per_rev=pulses_per_rev, speed_hz=speed_hz, gearbox=gearbox, tacho_shaft=tacho_shaft
    )
    ends = source.pop("ends", 0.0)  # every revolution cut: a followed angle's ends are left out by localisation alone
    turns, how = (angle[-1] - angle[0]) / TWO_PI, how + varies_words(angle, rec)  # a run-up said so, tacho or not
    if turns < 2:
        raise GearlabInputError(
            f"{path}: by {how}, the record shows {turns:.3g} revolutions in {raw.size} samples at "
            f"{fmt_hz(rec.fs)}; expected at least 2 (is pulses_per_rev right?)"
        )
    if before_cut is not None:
        before_cut(rec.fs, turns * rec.fs / max(angle.size - 1, 1))
    with prefixed(f"{path}: vibration column {_one_line_repr(rec.vibration)}"):
        cut = cut_revolutions(raw, rec.fs, **source, points=points or POINTS, transient="none")
    start, warning = 0, None
    if transient == "stats":  # the level over the slowest shaft's turn (steady_start_stats)
        window = settle_window if gearbox is None else settle_turns(gearbox)
        where_ = f"{path}: vibration column {_one_line_repr(rec.vibration)}"
        start, _, warning = steady_start(cut.revolutions, where_, window=window)
    revs, warns = cut.revolutions[start:], rec.warnings + flaws + (() if warning is None else (warning,))
    first, speeds = first_complete(angle) + int(start), revolution_speeds(angle, rec.fs)[start:]  # localisation, score
    need = revolutions_needed(order_table(gearbox)) if ends else 0  # a take the which-gear check reads whole
    kept = settled(angle, rec.fs, ends, need)  # localisation's revolutions: a followed angle's unsettled ends out
    made = (str(path), revs, float(cut.speed_hz), float(rec.fs), raw.size, int(start), how, warns, first, rec.units)
    # a shaft that stops and turns back: its speed varies, and a tacho's pulses alone do not tell it (reversal)
    turned = (
        reversal(revs, turn_times(angle, rec.fs)[start:]) if rec.tacho is not None and VARIES_WORDS in how else None
    )
    part = slice(max(kept.start - start, 0), max(kept.stop - start, 0))
    return CutRecording(*made, speeds, (rec, flaws) if keep_read else (), turned or (), part)


# --- the header alone: what `gearlab validate` checks -----------------------------------------


def read_header(path) -> Header:
    """What *path* says of itself (Header), its data unread; every failure is one line."""
    path = Path(path)
    fmt = format_of(path)
    try:
        return HEADERS[fmt](take_file(path))
    except GearlabInputError:
        raise
    except Exception as exc:  # noqa: BLE001 - each library fails its own way on a corrupt file
        raise GearlabInputError(f"cannot read {path} as {fmt}: {_one_line(exc)}") from None


# A channel name a tacho often has (tacho_V, Tach, keyphasor, once-per-rev, pulses, trigger, encoder, rpm)
_TACHO_NAME = re.compile(r"tach|key\s*pha|once|pulse|trig|encoder|rpm", re.IGNORECASE)


def channel_meant(name: str, available, role: str) -> str:
    """The hint after 'no <role> channel NAME' (which_meant); of a vibration, among the channels that look like one
    (no tacho's, time's or take column's name) first: 'acc_x' meant 'ax_g', not 'tacho_V' (the closest spelling of
    all); none spelt close, those channels named."""
    if role != "vibration":
        return which_meant(name, available)
    looks = [
        str(c) for c in available if not (_TACHO_NAME.search(str(c)) or is_rate_or_time(str(c)) or take_columns([c]))
    ]
    hint = which_meant(name, looks)
    return hint or (f" (a vibration channel: {_listing(looks)}?)" if looks else which_meant(name, available))


def pulses_without_tacho(path, at: str, tacho_is, key: str = "'tacho'") -> GearlabInputError:
    """The one-line error of a tacho's marks per turn given where no tacho is: *at* names the key; a channel of
    *path* whose name looks like a tacho's is named as *tacho_is*(name) says to give it (none is taken unasked);
    *key*: the tacho's key or option."""
    try:
        looks = [c for c in read_header(path).channels if _TACHO_NAME.search(str(c))]
    except GearlabInputError:  # the file's own error comes where it is read
        looks = []
    hint = f" ({path} has channel '{looks[0]}': {tacho_is(looks[0])}?)" if looks else ""
    return GearlabInputError(f"{at}: belongs to a tacho; no {key} is given{hint}")


def only_vibration(path, tacho, where: str) -> str:
    """The vibration channel of a file whose scenario names none: its one channel besides the
    tacho and any rate or time field (as `gearlab inspect` takes it), read from the header alone;
    a one-line error naming *where*'s 'vibration' key when there are several or none."""
    header = read_header(path)
    tacho_name = None if tacho in (None, "") else named(channel_key(tacho), header.channels)
    left = [c for c in header.channels if not is_rate_or_time(str(c)) and c != tacho_name]
    if len(left) != 1:
        raise GearlabInputError(
            f"{where} key 'vibration': missing, and {path} has {len(left)} signal channels "
            f"({_listing(left) or 'none'}); expected the vibration channel's name"
            + (" or 0-based column index" if header.indexed else "")
        )
    return left[0]


def check_recording(
    path,
    where: str,
    channels: dict[str, object],
    *,
    fs: float | None = None,
    sensitivity: float | None = None,
    gain: float | None = None,
    unit: str | None = None,
) -> Header:
    """Check what a scenario says of a measured file against its header alone (read_header): every channel in
    *channels* ({key: channel}, e.g. {"vibration": "acc_V", "tacho": 2}) is there and no time column, a rate is known
    (the file's or *fs*), the vibration's units given (channel_scale); each error one line naming *where*, key, file."""
    try:
        header = read_header(path)
    except GearlabInputError as exc:  # a file its reader refuses (a zip of two texts): named where it is listed
        raise GearlabInputError(f"{where} key 'file': {exc}") from None
    header.check_rate(fs, where, path)
    for key, value in channels.items():
        if value is None or value == "":
            continue
        name = channel_key(value)
        column = matrix_column(name)
        if column is not None and not header.find(name) and header.find(column[0]):
            raise GearlabInputError(
                f"{where} key '{key}': {path} has no channel {_one_line_repr(name)}: {header.not_a_column(name)}"
            )
        if not header.find(name) and header.channels:
            index = " (or a 0-based column index)" if header.indexed else ""
            raise GearlabInputError(
                f"{where} key '{key}': {path} has no channel {_one_line_repr(name)}"
                f"{channel_meant(str(name), header.channels, key)}; the file has channels: "
                f"{channel_listing(header.channels)}{index}"
            )
        header.check_channel(header.resolve(name), f"{where} key '{key}'", path)  # no time column, a series
    asked = [str(channel_key(v)) for v in channels.values() if v not in (None, "")]
    own = any(own_field(str(n), a) for a in asked for n in header.channels)  # 'ACC_fs', 'Data1_time_ACC'
    if not header.rate and fs is None and not own:
        raise GearlabInputError(
            f"{where} key 'fs': missing; {path} carries no sampling rate (no 'fs' field, no time column such as "
            "time, t, time_s or 'Time [s]')" + (time_hint(path) or "; expected the rate, e.g. fs = '51.2 kHz'")
        )
    vibration = channels.get("vibration")
    if vibration not in (None, ""):
        name = channel_key(vibration)
        name = named(name, header.channels) if header.indexed else header.resolve(name)
        channel_scale(name, sensitivity, gain, where, name in header.integer, header.units.get(name), unit, path=path)
    return header
