"""Measured vibration as a gearlab Dataset, through the same pipeline as simulated data (docs/real_data.md).

A real user's target domain is measured: a vibration channel recorded together with a
tacho channel, or at a known nominal speed, in whatever file the acquisition system
writes. :func:`import_measured` reads such a record and sends it through the functions
of :mod:`gearlab.signals` that also turn simulated records into samples:

    file ─► named channels + sampling rate          read_channels (one small reader per format:
                                                    gearlab.data.readers)
         ─► numeric, finite, equal lengths          check_signal
         ─► continuous input-shaft angle            unwrap_tacho | angle_from_pulses | angle_from_speed
         ─► complete revolutions at 4096 angles     cut_revolutions
         ─► start-up transient dropped              steady_start_stats (the method for measured data)
         ─► standardised against healthy data       Standardiser (eq. 2.112/4.6)

Formats (by extension) and where the sampling rate comes from:

    .csv          header row of column names, numeric columns, '#' comment lines;
                  rate from a 't'/'time' column (seconds, uniform) or a comment '# fs = 51200'
    .npz          arrays by name, loaded without pickle; rate from a scalar 'fs' or a 't' array
    .h5 / .hdf5   datasets by path ("group/acc"); rate from an attribute 'fs' on the channel,
                  else from an 'fs' attribute or 'fs'/'t' dataset in its group, or the
                  nearest group above that has one (up to the file's root)
    .wav          channels by index ("0", "1", …); rate from the header; integer PCM scaled to ±1
    .mat          MATLAB v5 variables (scipy), or v7.3 (an HDF5 file, read with h5py); rate
                  from a variable 'fs' or 'Fs'

Zipped whitespace-separated text with a multi-pulse tacho and a sensor sensitivity (the PHM 2009
gearbox records) is read by :mod:`gearlab.data.textzip`, for the measured [target] of the
detection kind (docs/real_data.md).

Names 'fs' (any case) and 't'/'time' are looked up the same way in every keyed format; when
the file carries a rate and one is given too (MeasuredSpec.fs) they must agree.

Every bad file raises :class:`GearlabInputError` with one line that names the file, the
channel and what was expected; nothing is returned half-built.

Sizes are checked before anything is read: the file, and every channel as its file declares
it (an HDF5 dataset never written, an NPZ member that inflates), may hold at most
GEARLAB_MAX_RECORD_MB megabytes (default MAX_RECORD_MB), so that a file claiming more than
memory holds is refused in one line instead of exhausting it.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .. import PHYSICS_VERSION
from ..errors import GearlabInputError
from ..params import did_you_mean
from ..signals import (
    POINTS,
    Standardiser,
    angle_from_pulses,
    angle_from_speed,
    check_signal,
    cut_revolutions,
    revolution_starts,
    steady_start_stats,
    unwrap_tacho,
)
from ..signals.checks import check_int, check_positive, fmt_hz
from .chain import FRACTIONS_KEPT
from .readers import READERS, Contents, check_size
from .readers.base import _listing, _one_line, _one_line_repr
from .spec import Dataset

__all__ = ["FORMATS", "MeasuredSpec", "import_measured", "read_channels"]

TWO_PI = 2.0 * np.pi

# Extension -> format name used in messages.
FORMATS = {".csv": "CSV", ".npz": "NPZ", ".h5": "HDF5", ".hdf5": "HDF5", ".wav": "WAV", ".mat": "MATLAB"}
TACHO_KINDS = ("auto", "angle", "pulses")
# "periodic" (steady_start) compares waveforms and needs a noise-free simulation: not offered.
IMPORT_TRANSIENTS = ("stats", "none")
# Bumped whenever the importer's output for the same file and options changes (cache keys).
IMPORTER_VERSION = "1"

# A time column is uniform when every step, and every sample's distance from the straight
# line through its ends, stays within this fraction of a sampling period: rounding of written
# times (to the microsecond at 50 kHz: 5 %) stays below it, a dropped sample does not.
_TIME_JITTER = 0.25
# Relative agreement asked of two sampling rates (the file's and the one given).
_RATE_RTOL = 1e-6
# A wrapped angle spans one turn; measured ones may fall a little short or overshoot.
_TURN_SLACK = 0.01
# Share of rising steps that marks a channel as a shaft angle rather than a pulse train
# (a pulse train is flat most of the time, an angle rises at every sample).
_RISING_SHARE = 0.9
# Fewest samples a revolution may span (a wrapped angle advancing by π or more per sample
# cannot even be unwrapped).
_MIN_SAMPLES_PER_REV = 2


# --- what the importer is asked -------------------------------------------------------


@dataclass(frozen=True)
class MeasuredSpec:
    """A measured record to import; plays the role of DatasetSpec for measured data.

    name:        the dataset's (and its one domain's) name
    path:        the file; its format follows from the extension (FORMATS)
    vibration:   channel/column/variable/dataset name of the vibration (WAV: channel index "0")
    tacho:       a tacho channel: the shaft angle in rad (wrapped, e.g. [-π, π) or [0, 2π), or
                 continuous) or a once-per-revolution pulse train; None with speed_hz
    tacho_kind:  "auto" (detected, see _tacho_kind), "angle" or "pulses"
    speed_hz:    nominal constant input-shaft speed when there is no tacho (revolutions/s)
    fs:          sampling rate (Hz) when the file does not carry one; checked when it does
    labels:      optional channel with the class (name or index into class_names) of the whole
                 record (one value) or of every sample (constant within each revolution)
    class_names: class 0 is the healthy reference used for standardisation
    points:      samples per revolution in the angle domain
    transient:   "stats" drops a start-up transient (steady_start_stats), "none" keeps all
    rtol:        tolerance of the transient detection (default that of steady_start_stats)
    sensitivity: the sensor's output per m/s² in the record's (volt) units, SI: V/(m/s²) ("10 mV/g"
                 in a scenario); None: not given
    gain:        volts per file unit: per count for integer arrays, at full scale for integer WAV
                 (read as ±1); None: not given (1). The vibration in m/s² is file value × gain /
                 sensitivity; with neither given the record's units are unknown and its values are
                 taken as m/s² (meta "units" says so, and the gap kind warns)
    """

    name: str
    path: str
    vibration: str
    tacho: str | None = None
    tacho_kind: str = "auto"
    speed_hz: float | None = None
    fs: float | None = None
    labels: str | None = None
    class_names: tuple[str, ...] = ("healthy", "fault")
    points: int = POINTS
    transient: str = "stats"
    rtol: float | None = None
    sensitivity: float | None = None
    gain: float | None = None

    def canonical(self) -> dict:
        """The options that shape the data: not the name (a label) nor where the file lies (nor the
        units when not given: records imported before they existed keep their cache keys)."""
        d = asdict(self)
        d.pop("name")
        d.pop("path")
        for key in ("sensitivity", "gain"):
            if d[key] is None:
                d.pop(key)
        return d

    @property
    def scale(self) -> float:
        """m/s² per file unit: gain / sensitivity (1 for what is not given)."""
        return (1.0 if self.gain is None else self.gain) / (1.0 if self.sensitivity is None else self.sensitivity)

    @property
    def units_known(self) -> bool:
        return self.sensitivity is not None or self.gain is not None

    def key(self) -> str:
        """Cache key: sha256 over the file's bytes, its format and the options (24 hex chars)."""
        path = Path(self.path)
        _check_exists(path)
        digest = hashlib.sha256()
        try:
            with path.open("rb") as f:
                for block in iter(lambda: f.read(1 << 20), b""):
                    digest.update(block)
        except OSError as exc:
            raise GearlabInputError(f"{path}: cannot read ({exc.strerror or exc})") from None
        text = json.dumps(
            {
                "file": digest.hexdigest(),
                "format": path.suffix.lower(),
                "options": self.canonical(),
                "importer": IMPORTER_VERSION,
                "physics": PHYSICS_VERSION,
            },
            sort_keys=True,
        )
        return hashlib.sha256(text.encode()).hexdigest()[:24]

    def check(self, where: str = "") -> None:
        """Raise on options that cannot work, before the file is read."""
        where = where or f"measured dataset '{self.name}' ({self.path})"
        for label in ("name", "path", "vibration"):
            value = getattr(self, label)
            if not isinstance(value, str) or not value:
                raise GearlabInputError(f"{where}: '{label}' must be a non-empty text, got {value!r}")
        if "\0" in self.path:
            raise GearlabInputError(f"{where}: 'path' contains a NUL character")
        if (self.tacho is None) == (self.speed_hz is None):
            got = "both" if self.tacho is not None else "neither"
            raise GearlabInputError(
                f"{where}: give either a tacho channel (tacho = ...) or a nominal shaft speed "
                f"(speed_hz = ...) to know the shaft angle, got {got}"
            )
        if self.tacho_kind not in TACHO_KINDS:
            raise GearlabInputError(
                f"{where}: unknown tacho_kind '{self.tacho_kind}'{did_you_mean(str(self.tacho_kind), TACHO_KINDS)}; "
                f"known: {', '.join(TACHO_KINDS)}"
            )
        with _prefixed(where):
            if self.speed_hz is not None:
                check_positive(self.speed_hz, "speed_hz (nominal shaft speed)", "Hz")
            if self.fs is not None:
                check_positive(self.fs, "sampling rate fs", "Hz")
            if self.rtol is not None:
                check_positive(self.rtol, "rtol (transient detection)")
            if self.sensitivity is not None:
                check_positive(self.sensitivity, "sensitivity (V per m/s²)", "V/(m/s²)")
            if self.gain is not None:
                check_positive(self.gain, "gain (V per file unit)", "V")
            check_int(self.points, "points per revolution", minimum=2)
        names = self.class_names
        if (
            isinstance(names, str)
            or not isinstance(names, Sequence)
            or not names
            or not all(isinstance(c, str) and c for c in names)
            or len(set(names)) != len(names)
        ):
            raise GearlabInputError(
                f"{where}: class_names must be distinct non-empty names, healthy first, got {names!r}"
            )
        if len(names) > 127:  # labels are stored as int8, as for simulated datasets
            raise GearlabInputError(f"{where}: at most 127 class names, got {len(names)}")
        if self.transient not in IMPORT_TRANSIENTS:
            raise GearlabInputError(
                f"{where}: unknown transient detection '{self.transient}' for measured data; "
                f"known: {', '.join(IMPORT_TRANSIENTS)}"
            )


# --- errors ------------------------------------------------------------------------------


@contextmanager
def _prefixed(prefix: str):
    """Re-raise GearlabInputError from the shared pipeline with the file (and channel) in front."""
    try:
        yield
    except GearlabInputError as exc:
        raise GearlabInputError(f"{prefix}: {exc}") from None


def file_problem(path: Path) -> str | None:
    """Why *path* cannot be read as a measured file ('no such file', 'is not a file', a name
    too long, a NUL in it), or None when it is a file. Every kind checks its measured files
    so when a scenario is loaded: `gearlab validate` finds them all."""
    try:
        exists, is_file = path.exists(), path.is_file()
    except (OSError, ValueError) as exc:  # a name too long, a NUL character in it, ...
        return f"cannot be a measured record: {getattr(exc, 'strerror', None) or exc}"
    if not exists:
        return "no such file"
    return None if is_file else "is not a file"


def check_measured_file(path: Path, where: str = "", expected: str = "") -> None:
    """Refuse *path* in one line (prefixed with *where*) unless it is a readable file."""
    problem = file_problem(Path(path))
    if problem is not None:
        head = f"{where}: " if where else ""
        shown_path = _one_line_repr(str(path)) if problem.startswith("cannot") else str(path)
        raise GearlabInputError(
            f"{head}{shown_path}: {problem}; expected {expected or f'a measured record ({_supported()})'}"
        )


_check_exists = check_measured_file


def _supported() -> str:
    return ", ".join(FORMATS)


# --- reading a file (the readers themselves: gearlab.data.readers) ---------------------------


def _read(path, names: Sequence[str], roles: dict[str, str] | None = None) -> tuple[Contents, str]:
    """Read *names* from *path*: (contents, format name). Every failure is one clear line."""
    path = Path(path)
    _check_exists(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise GearlabInputError(
            f"{path}: unknown file type '{path.suffix or '(no extension)'}'; supported: {_supported()}"
        )
    check_size(path, "the file", path.stat().st_size)
    try:
        contents = READERS[fmt](path, names)
    except GearlabInputError:
        raise
    except MemoryError:
        raise GearlabInputError(f"cannot read {path} as {fmt}: not enough memory for what it declares") from None
    except Exception as exc:  # noqa: BLE001 - each library fails its own way on a corrupt file
        raise GearlabInputError(f"cannot read {path} as {fmt}: {_one_line(exc)}") from None
    for name in names:
        if name not in contents.found:
            role = f"{roles[name]} " if roles and name in roles else ""
            raise GearlabInputError(
                f"{path}: no {role}channel '{name}'{did_you_mean(name, contents.available)}; "
                f"the file has: {_listing(contents.available)}"
            )
    return contents, fmt


def read_channels(path, names: Sequence[str]) -> tuple[dict[str, np.ndarray], float | None]:
    """The named channels of a measured-data file and its sampling rate (None if it has none).

    Arrays come back as stored (numbers, or text for label channels; WAV PCM scaled to
    ±1). The rate is the file's 'fs' field or follows from its time vector; raises on a
    missing file or channel, an unreadable file, or a bad or inconsistent rate field.
    """
    names = list(names)
    contents, _ = _read(path, names)
    rate = _file_rate(contents, None, str(path))
    return contents.found, (None if rate is None else rate[0])


# --- sampling rate -----------------------------------------------------------------------


def _rate_value(value, where: str, path: str) -> float:
    arr = np.asarray(value)
    shown = _one_line_repr(arr.item()) if arr.size == 1 else f"{arr.size} values"
    if arr.dtype.kind not in "biuf" or arr.size != 1:
        raise GearlabInputError(f"{path}: sampling rate field {where} must be one number in Hz, got {shown}")
    fs = float(arr.item())
    if not math.isfinite(fs) or fs <= 0:
        raise GearlabInputError(f"{path}: sampling rate {where} must be positive, got {fs:g} Hz")
    return fs


def _rate_from_time(value, where: str, path: str, n: int | None) -> tuple[float, float]:
    """(fs, relative uncertainty) from a time vector in seconds, checked to be uniform.

    fs = (N − 1) / (t_last − t_first); the times must lie within _TIME_JITTER of a sampling
    period of that uniform grid. The rate is known only as well as the times were written
    (rounded to a few digits in a CSV file), so its uncertainty, 2·max deviation / span,
    widens the agreement asked of a given fs.
    """
    arr = np.asarray(value)
    if arr.dtype.kind not in "biuf":
        raise GearlabInputError(f"{path}: {where} must hold numbers (seconds), got dtype {arr.dtype}")
    with _prefixed(path):
        t = check_signal(np.squeeze(arr) if arr.ndim > 1 else arr, where)
    if n is not None and t.size != n:
        raise GearlabInputError(
            f"{path}: {where} has {t.size} samples but the vibration has {n}; expected one time per sample"
        )
    if t.size < 2:
        raise GearlabInputError(f"{path}: {where} has {t.size} sample; at least 2 are needed for a sampling rate")
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.flatnonzero(steps <= 0)[0])
        raise GearlabInputError(
            f"{path}: {where} does not increase between samples {i} and {i + 1} "
            f"({t[i]:.9g} -> {t[i + 1]:.9g} s); expected increasing times in seconds"
        )
    span = float(t[-1] - t[0])
    dt = span / (t.size - 1)
    uneven = np.flatnonzero(np.abs(steps - dt) > _TIME_JITTER * dt)
    if uneven.size:  # a gap, a repeated block, a clock jump: name the first
        i = int(uneven[0])
        raise GearlabInputError(
            f"{path}: {where} is not uniformly sampled: the step between samples {i} and {i + 1} is "
            f"{steps[i]:.6g} s, {steps[i] / dt:.3g} times the mean step {dt:.6g} s; expected uniform sampling"
        )
    deviation = np.abs(t - (t[0] + dt * np.arange(t.size)))
    worst = int(np.argmax(deviation))
    if deviation[worst] > _TIME_JITTER * dt:  # steps each fine but drifting
        raise GearlabInputError(
            f"{path}: {where} is not uniformly sampled: sample {worst} is {deviation[worst] / dt:.3g} sampling "
            f"periods off the uniform grid of {fmt_hz(1 / dt)} (a gap or jitter); expected uniform sampling"
        )
    return (t.size - 1) / span, 2.0 * float(deviation[worst]) / span


def _file_rate(contents: Contents, n: int | None, path: str) -> tuple[float, float, str] | None:
    """(fs, relative tolerance, where) from the file's rate fields, or None when it has none.

    An explicit 'fs' field comes first; all fields the file has must agree with each other.
    """
    found = [(_rate_value(v, where, path), _RATE_RTOL, where) for where, v in contents.rates]
    for where, v in contents.times:
        fs, uncertainty = _rate_from_time(v, where, path, n)
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


def _sampling_rate(contents: Contents, given: float | None, n: int, path: str) -> tuple[float, str]:
    """The rate to use and where it came from: the file's, checked against a given one."""
    from_file = _file_rate(contents, n, path)
    if from_file is None:
        if given is None:
            raise GearlabInputError(
                f"{path}: no sampling rate: the file has no 'fs'/time and none was given (--fs / fs = ...)"
            )
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


# --- channels ----------------------------------------------------------------------------


def _first_text(arr: np.ndarray) -> tuple[int, str]:
    """Position and value of the first entry of a text array that is not a number."""
    for i, v in enumerate(arr.ravel().tolist()):
        try:
            float(v)
        except (TypeError, ValueError):
            return i, v
    return 0, arr.ravel()[0] if arr.size else ""


def _series(raw, name: str, role: str, path: str) -> np.ndarray:
    """A channel as a 1-D finite float64 time series (check_signal), or one clear line."""
    what = f"{role} channel '{name}'"
    arr = np.asarray(raw)
    if arr.dtype.kind in "US":
        i, v = _first_text(arr)
        shown = "an empty field" if v == "" else repr(v)
        raise GearlabInputError(f"{path}: {what} is not numeric: {shown} at sample {i}; expected numbers")
    if arr.dtype.kind not in "biuf":
        raise GearlabInputError(f"{path}: {what} is not numeric (stored as {arr.dtype}); expected an array of numbers")
    if arr.dtype.kind == "b" and role == "vibration":  # a tacho's pulses may be true/false; a vibration not
        raise GearlabInputError(f"{path}: {what} holds true/false values; expected a vibration signal of numbers")
    if arr.ndim > 1 and sum(s > 1 for s in arr.shape) <= 1:
        arr = arr.reshape(-1)  # a 1×N or N×1 matrix is one channel
    if arr.ndim == 0:
        raise GearlabInputError(f"{path}: {what} holds a single value; expected a time series, one value per sample")
    if arr.ndim > 1:
        raise GearlabInputError(f"{path}: {what} has shape {arr.shape}; expected one channel over time (a 1-D array)")
    with _prefixed(path):
        return check_signal(arr, what)


def _same_length(x: np.ndarray, name: str, role: str, n: int, vibration: str, path: str) -> None:
    if x.size != n:
        raise GearlabInputError(
            f"{path}: {role} channel '{name}' has {x.size} samples but vibration channel '{vibration}' has {n}; "
            "expected channels of equal length (one value per sample)"
        )


# --- shaft angle -------------------------------------------------------------------------


def _wrap(x: np.ndarray) -> np.ndarray:
    """Angle into [-π, π): keeps every angle modulo 2π, so where revolutions start."""
    return (x + np.pi) % TWO_PI - np.pi


def _tacho_kind(tacho: np.ndarray) -> str:
    """ "angle" or "pulses" for a tacho channel (tacho_kind = "auto").

    A shaft angle rises at (nearly) every sample: steadily (continuous angle), or with
    wraps of about −2π between steady rises when it is wrapped, in which case it spans one
    turn (2π ± 1 %). A once-per-revolution pulse train is flat between edges that jump
    both ways. Anything that is not an angle is read as pulses.
    """
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


def _angle_tacho(tacho: np.ndarray) -> np.ndarray:
    """A tacho read as an angle -> the wrapped tacho that cut_revolutions unwraps.

    Wrapped angles of any one-turn interval ([-π, π), [0, 2π), a slight overshoot) and
    continuous angles all become the same [-π, π) tacho; an angle spanning more than a
    turn with wraps in it (degrees?) is refused.
    """
    span = float(tacho.max() - tacho.min())
    continuous = not np.any(np.abs(np.diff(tacho)) > np.pi)
    if span <= (1 + _TURN_SLACK) * TWO_PI or continuous:
        return _wrap(tacho)
    raise GearlabInputError(
        f"spans {span:.4g} (from {tacho.min():.4g} to {tacho.max():.4g}), more than one turn (2π), and jumps "
        "back: expected the shaft angle in radians, wrapped into one turn or continuous (degrees? multiply by π/180)"
    )


def _shaft_angle(
    spec: MeasuredSpec, tacho: np.ndarray | None, fs: float, n: int, path: str
) -> tuple[dict, np.ndarray, str]:
    """(cut_revolutions' angle argument, the continuous angle it computes from it, a description).

    The angle is computed here with the very functions cut_revolutions applies to the
    same argument, so revolution boundaries found here (for labels) are exactly those of
    the revolutions it cuts.
    """
    if tacho is None:
        return (
            {"speed_hz": float(spec.speed_hz)},
            angle_from_speed(n, fs, spec.speed_hz),
            f"nominal speed {fmt_hz(spec.speed_hz)}",
        )
    kind = _tacho_kind(tacho) if spec.tacho_kind == "auto" else spec.tacho_kind
    detected = ", detected" if spec.tacho_kind == "auto" else ""
    if kind == "angle":
        with _prefixed(f"{path}: tacho '{spec.tacho}' (read as the shaft angle in rad{detected})"):
            wrapped = _angle_tacho(tacho)
            return {"tacho": wrapped}, unwrap_tacho(wrapped), f"tacho '{spec.tacho}' (shaft angle{detected})"
    # angle_from_pulses fails only for want of edges: a tacho that never completes a revolution.
    with _prefixed(
        f"{path}: tacho '{spec.tacho}' never completes a revolution "
        f"(read as a once-per-revolution pulse train{detected})"
    ):
        return (
            {"pulses": tacho},
            angle_from_pulses(tacho, fs),
            f"tacho '{spec.tacho}' (once-per-revolution pulses{detected})",
        )


def _revolution_bounds(angle: np.ndarray, fs: float, source: str, path: str) -> np.ndarray:
    """Fractional sample positions where the complete revolutions start (and the last ends).

    Raises when the record is shorter than one revolution, or holds no complete one
    (a revolution runs between two crossings of the angle through 2πk).
    """
    n = angle.size
    turns = float(angle[-1] - angle[0]) / TWO_PI if n > 1 else 0.0
    if turns > 0:
        speed = turns * fs / (n - 1)
        per_rev = fs / speed
        if n < per_rev:
            if source.startswith("nominal"):
                why = f"one revolution at the {source} needs {per_rev:.0f} samples at {fmt_hz(fs)}"
            else:
                why = (
                    f"by {source}, the shaft turns {turns:.3g} revolutions at {fmt_hz(speed)}; one revolution "
                    f"needs {per_rev:.0f} samples at {fmt_hz(fs)}: the record is too short or the tacho "
                    "never completes a revolution"
                )
            raise GearlabInputError(f"{path}: too short for one revolution: {n} samples; {why}")
        # Fewer samples than that cannot show a revolution, and a rate or speed off by orders
        # of magnitude would ask revolution_starts for billions of revolution starts.
        if per_rev < _MIN_SAMPLES_PER_REV:
            raise GearlabInputError(
                f"{path}: by {source}, one revolution spans {per_rev:.3g} samples at {fmt_hz(fs)} "
                f"({turns:.3g} revolutions in {n} samples); expected at least {_MIN_SAMPLES_PER_REV} samples per "
                "revolution: is the sampling rate or the speed right?"
            )
    with _prefixed(f"{path}: {source}"):
        starts = revolution_starts(angle)  # also checks the angle increases (shaft turning forwards)
    if starts.size < 2:
        raise GearlabInputError(
            f"{path}: no complete revolution: by {source}, the {n} samples cover {turns:.3g} revolutions but "
            f"cross the revolution start (angle 2πk) only once; expected a longer record (up to "
            f"{2 * n / turns:.0f} samples to hold one complete revolution)"
        )
    return starts


# --- labels ------------------------------------------------------------------------------


def _class_indices(raw, spec: MeasuredSpec, n: int, path: str) -> np.ndarray:
    """Class index per sample (length n) or of the whole record (length 1)."""
    name, names = spec.labels, tuple(spec.class_names)
    what = f"labels channel '{name}'"
    arr = np.asarray(raw)
    if arr.ndim > 1 and sum(s > 1 for s in arr.shape) <= 1:
        arr = arr.reshape(-1)
    arr = arr.reshape(1) if arr.size == 1 else arr
    if arr.ndim != 1 or arr.size == 0:
        raise GearlabInputError(
            f"{path}: {what} has shape {arr.shape}; expected one label for the record or one per sample"
        )
    if arr.size != 1 and arr.size != n:
        raise GearlabInputError(
            f"{path}: {what} has {arr.size} samples but vibration channel '{spec.vibration}' has {n}; "
            "expected one label per sample or one for the whole record"
        )
    known = f"known classes (class_names): {', '.join(names)}"
    if arr.dtype.kind in "US":
        values, inverse = np.unique(arr, return_inverse=True)
        lookup = {c: i for i, c in enumerate(names)}
        for v in values.tolist():
            if v not in lookup:
                i = int(np.flatnonzero(arr == v)[0])
                raise GearlabInputError(
                    f"{path}: {what} holds the unknown class {_one_line_repr(v)}{did_you_mean(v, names)} "
                    f"at sample {i}; "
                    f"{known}"
                )
        return np.asarray([lookup[v] for v in values.tolist()], dtype=np.int64)[inverse.reshape(-1)]
    if arr.dtype.kind not in "biuf":
        raise GearlabInputError(f"{path}: {what} is stored as {arr.dtype}; expected class names or class indices")
    with _prefixed(path):
        values = check_signal(arr, what)
    bad = np.flatnonzero((values != np.round(values)) | (values < 0) | (values >= len(names)))
    if bad.size:
        i = int(bad[0])
        raise GearlabInputError(
            f"{path}: {what} holds {values[i]:g} at sample {i}, not a class index 0 … {len(names) - 1}; {known}"
        )
    return values.astype(np.int64)


def _revolution_labels(per_sample: np.ndarray, starts: np.ndarray, spec: MeasuredSpec, path: str) -> np.ndarray:
    """Label of every complete revolution: that of its first sample, the same for all its samples."""
    count = starts.size - 1
    if per_sample.size == 1:
        return np.full(count, per_sample[0], dtype=np.int64)
    first = np.ceil(starts).astype(np.int64)  # first sample of revolution r is first[r]; first[-1] ends the last
    changes = np.flatnonzero(np.diff(per_sample)) + 1  # sample indices where the label changes
    inside = changes[(changes > first[0]) & (changes < first[-1])]
    stray = inside[~np.isin(inside, first)]
    if stray.size:
        c = int(stray[0])
        r = int(np.searchsorted(first, c, side="right")) - 1
        names = spec.class_names
        raise GearlabInputError(
            f"{path}: labels channel '{spec.labels}' changes within revolution {r} (samples {first[r]} … "
            f"{first[r + 1] - 1}): '{names[per_sample[c - 1]]}' until sample {c - 1}, then '{names[per_sample[c]]}'; "
            "expected one label per revolution (change labels where a revolution starts, or cut the record there)"
        )
    return per_sample[first[:-1]]


# --- the import --------------------------------------------------------------------------


def _steady_start(revs: np.ndarray, labels: np.ndarray | None, spec: MeasuredSpec, path: str) -> tuple[int, str]:
    """Index of the first steady revolution and how it was found.

    A start-up transient lies at the start of the record. It is judged
    (steady_start_stats, as cut_revolutions(transient="stats") does) on the leading
    revolutions that share the first label: a later change of condition in a labelled
    record changes the vibration level too, and must not be taken for a transient.
    """
    if spec.transient == "none":
        return 0, "not detected (transient = 'none')"
    run = revs.shape[0] if labels is None else int(np.argmax(np.append(labels != labels[0], True)))
    if run < 2:
        return 0, "not judged (fewer than 2 revolutions to compare)"
    with _prefixed(f"{path}: vibration channel '{spec.vibration}'"):
        try:
            start = steady_start_stats(revs[:run], *(() if spec.rtol is None else (spec.rtol,)))
        except GearlabInputError as exc:
            raise GearlabInputError(
                f"{exc}; in the import: rtol = ..., or transient = 'none' if the record is steady from its start"
            ) from None
    return start, "stats"


def units_note(spec: MeasuredSpec, fmt: str, integer: bool) -> str:
    """What the record's values were taken as: m/s² through the sensitivity and gain, or -- neither
    given -- "unknown" (one line; the gap kind warns with it)."""
    if spec.units_known:
        return (
            f"m/s² = value x gain {1.0 if spec.gain is None else spec.gain:g} V / sensitivity "
            f"{1.0 if spec.sensitivity is None else spec.sensitivity:g} V/(m/s²)"
        )
    what = "integer counts (full-scale fractions for WAV)" if integer else "numbers"
    return (
        f"unknown: the {fmt} record holds {what} with no sensitivity or gain given; its values are taken "
        "as m/s² (set sensitivity = '10 mV/g' and, for integer data, gain = volts per count)"
    )


def import_measured(spec: MeasuredSpec) -> Dataset:
    """A measured record as a Dataset (see _import_measured); running out of memory on the
    way (a record just under the size limit on a small machine) is one clear line."""
    try:
        return _import_measured(spec)
    except MemoryError:
        raise GearlabInputError(
            f"{spec.path}: not enough memory to import this record; a shorter record, or a machine with more memory"
        ) from None


def _import_measured(spec: MeasuredSpec) -> Dataset:
    """A measured record as a Dataset of standardised revolutions (float32, (n, spec.points)).

    Rows are the steady complete revolutions in record order. label/fault are the class
    index and fault flag of each revolution, −1 when the record is unlabelled;
    intensity = tooth = 0, rfa = NaN (unknown for measured data), revolution = index of the
    revolution among the record's complete revolutions, domain = 0 with domains =
    (spec.name,). Standardisation (eq. 2.112) is against the revolutions labelled healthy
    (class 0), or all revolutions of an unlabelled record, as meta["reference"] says.
    """
    spec.check()
    path = str(spec.path)
    roles = {spec.vibration: "vibration"}
    for role, name in (("tacho", spec.tacho), ("labels", spec.labels)):
        if name is not None:
            roles.setdefault(name, role)
    contents, fmt = _read(path, list(roles), roles)

    raw = np.asarray(contents.found[spec.vibration])
    # An integer record is quantised: one count (a WAV's 1/2^(bits-1) of full scale) is its step.
    step = contents.steps.get(spec.vibration, 1.0 if raw.dtype.kind in "iu" else 0.0)
    vib = _series(raw, spec.vibration, "vibration", path) * spec.scale
    n = vib.size
    fs, fs_source = _sampling_rate(contents, spec.fs, n, path)
    tacho = None
    if spec.tacho is not None:
        tacho = _series(contents.found[spec.tacho], spec.tacho, "tacho", path)
        _same_length(tacho, spec.tacho, "tacho", n, spec.vibration, path)
    per_sample = None
    if spec.labels is not None:
        per_sample = _class_indices(contents.found[spec.labels], spec, n, path)

    source, angle, how = _shaft_angle(spec, tacho, fs, n, path)
    starts = _revolution_bounds(angle, fs, how, path)
    labels = None if per_sample is None else _revolution_labels(per_sample, starts, spec, path)

    # The shared pipeline: the same call as for simulated records. The transient is judged
    # below on the leading single-label run rather than inside (see _steady_start).
    with _prefixed(f"{path}: vibration channel '{spec.vibration}'"):
        cut = cut_revolutions(vib, fs, **source, points=spec.points, transient="none")
    revs = cut.revolutions
    if revs.shape[0] != starts.size - 1:  # pragma: no cover - both follow from the same angle
        raise RuntimeError(f"importer bug: {revs.shape[0]} revolutions cut, {starts.size - 1} bounded")
    start, transient = _steady_start(revs, labels, spec, path)
    revs = revs[start:]
    fractions = starts[start:-1][:FRACTIONS_KEPT] % 1.0  # where the kept revolutions start between samples
    count = revs.shape[0]

    if labels is None:
        healthy = np.ones(count, dtype=bool)
        reference = "all revolutions (unlabelled)"
    else:
        labels = labels[start:]
        healthy = labels == 0
        reference = "labelled healthy"
        if not healthy.any():
            dropped = f", after {start} transient revolution(s) were dropped" if start else ""
            raise GearlabInputError(
                f"{path}: labels channel '{spec.labels}' marks none of the {count} revolutions "
                f"'{spec.class_names[0]}' (class 0){dropped}: the record has no healthy data to standardise "
                "against (eq. 2.112); expected some revolutions labelled healthy"
            )
    with _prefixed(f"{path}: healthy reference of vibration channel '{spec.vibration}'"):
        standardiser = Standardiser.fit(revs[healthy])
    X = standardiser.apply(revs)

    if labels is None:
        label = np.full(count, -1, dtype=np.int8)
        fault = np.full(count, -1, dtype=np.int8)
    else:
        label = labels.astype(np.int8)
        fault = (labels > 0).astype(np.int8)
    return Dataset(
        spec=spec,
        X=X,
        label=label,
        fault=fault,
        intensity=np.zeros(count, dtype=np.int8),
        tooth=np.zeros(count, dtype=np.int8),
        rfa=np.full(count, np.nan, dtype=np.float32),
        revolution=np.arange(start, start + count, dtype=np.int32),  # long records exceed int16
        domain=np.zeros(count, dtype=np.int8),
        domains=(spec.name,),
        reference=(standardiser.mean, standardiser.std),
        meta={
            "source": "measured",
            "file": path,
            "format": fmt,
            "fs_hz": float(fs),
            "fs_source": fs_source,
            "speed_hz": float(cut.speed_hz),
            "angle_source": how,
            "samples": int(n),
            "complete_revolutions": int(cut.complete),
            "transient_revolutions": int(start),
            "transient": transient,
            "reference": reference,
            "healthy_revolutions": int(healthy.sum()),
            # the measurement chain (gearlab.data.chain): what a simulation goes through to compare
            "start_fractions": [round(float(f), 4) for f in fractions],
            "quantum": float(step * spec.scale),
            "units": units_note(spec, fmt, step > 0),
        },
    )
