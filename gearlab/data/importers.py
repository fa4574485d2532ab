"""Measured vibration as a gearlab Dataset, through the same pipeline as simulated data (SPEC 5).

A real user's target domain is measured: a vibration channel recorded together with a
tacho channel, or at a known nominal speed, in whatever file the acquisition system
writes. :func:`import_measured` reads such a record and sends it through the functions
of :mod:`gearlab.signals` that also turn simulated records into samples:

    file ─► named channels + sampling rate          read_channels (one small reader per format)
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

import csv
import hashlib
import json
import math
import os
import re
import struct
import warnings
import zipfile
import zlib
from collections.abc import Iterable, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
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

_RATE_NAMES = ("fs",)  # compared lower-case: fs, Fs, FS
_TIME_NAMES = ("t", "time")
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
        raise GearlabInputError(f"{path}: {what} would take {nbytes / 2**20:,.0f} MB, more than the limit of "
                                f"{limit / 2**20:,.0f} MB for a measured record (set GEARLAB_MAX_RECORD_MB to allow more)")


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
            {"file": digest.hexdigest(), "format": path.suffix.lower(), "options": self.canonical(),
             "importer": IMPORTER_VERSION, "physics": PHYSICS_VERSION},
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
        if (isinstance(names, str) or not isinstance(names, Sequence) or not names
                or not all(isinstance(c, str) and c for c in names) or len(set(names)) != len(names)):
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


def _check_exists(path: Path) -> None:
    try:
        exists, is_file = path.exists(), path.is_file()
    except (OSError, ValueError) as exc:  # a name too long, a NUL character in it, ...
        raise GearlabInputError(f"{_one_line_repr(str(path))}: cannot be a measured record: "
                                f"{getattr(exc, 'strerror', None) or exc}") from None
    if not exists:
        raise GearlabInputError(f"{path}: no such file; expected a measured record ({_supported()})")
    if not is_file:
        raise GearlabInputError(f"{path}: is not a file; expected a measured record ({_supported()})")


def _supported() -> str:
    return ", ".join(FORMATS)


# --- readers -----------------------------------------------------------------------------


@dataclass
class _Contents:
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


def _keyed(available: Iterable[str], get, names: Sequence[str]) -> _Contents:
    """Contents of a format whose channels are looked up by name (CSV, NPZ, MATLAB v5).

    The sampling rate fields are the entries named fs (any case) and the time vectors the
    entries named t or time, wherever the format keeps its names.
    """
    available = list(available)
    present = set(available)
    contents = _Contents({n: _normalise(get(n)) for n in dict.fromkeys(names) if n in present}, available)
    for n in available:
        if n.lower() in _RATE_NAMES:
            contents.rates.append((f"'{n}'", _normalise(get(n))))
        elif n.lower() in _TIME_NAMES:
            contents.times.append((f"time '{n}'", _normalise(get(n))))
    return contents


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


_COMMENT_FIELD = re.compile(r"^#\s*([A-Za-z_][\w.-]*)\s*[=:]\s*(.*?)\s*$")


def _read_csv(path: Path, names: Sequence[str]) -> _Contents:
    """Header row of names, numeric columns, '#' comments ('# fs = 51200' gives a field 'fs')."""
    text = path.read_text(encoding="utf-8-sig")  # a BOM from spreadsheet exports is dropped
    fields: dict[str, object] = {}
    lines: list[tuple[int, str]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            match = _COMMENT_FIELD.match(stripped)
            if match:
                fields[match.group(1)] = _scalar(match.group(2))
            continue
        lines.append((number, line))
    if not lines:
        raise GearlabInputError(f"{path}: no header row; expected a first line of column names, then numbers")
    header_line = lines[0][1]
    delimiter = next((d for d in (",", ";", "\t") if d in header_line), ",")
    rows = list(csv.reader((line for _, line in lines), delimiter=delimiter))
    header = [h.strip() for h in rows[0]]
    if len(set(header)) != len(header):
        twice = next(h for h in header if header.count(h) > 1)
        raise GearlabInputError(f"{path}: column '{twice}' appears twice in the header; expected distinct names")
    for (number, _), row in zip(lines[1:], rows[1:]):
        if len(row) != len(header):
            raise GearlabInputError(
                f"{path}: line {number} has {len(row)} fields but the header has {len(header)}; "
                "expected one value per column (a truncated or ragged file?)"
            )
    if len(rows) < 2:
        raise GearlabInputError(f"{path}: has a header but no data rows; expected one row per sample")
    if not any(_column([row[j].strip() for row in rows[1:2]]).dtype.kind == "f" for j in range(len(header))):
        # not a measured record (a system file reached through a link?): nothing of it is quoted
        raise GearlabInputError(f"{path}: its first data row (line {lines[1][0]}) holds no number; expected a header "
                                "row of column names, then rows of numbers")
    index = {h: j for j, h in enumerate(header)}

    def get(name: str):
        if name in index:
            j = index[name]
            return _column([row[j].strip() for row in rows[1:]])
        return fields[name]

    return _keyed([*header, *fields], get, names)


def _read_npz(path: Path, names: Sequence[str]) -> _Contents:
    """Arrays by name; never unpickles (allow_pickle=False refuses object arrays)."""
    # np.load guesses from the first bytes (.npy, zip, else pickle); say what the file is instead.
    with path.open("rb") as f:
        magic = f.read(6)
    if magic == b"\x93NUMPY":
        raise ValueError("it holds a single array (.npy), not an archive of named arrays")
    if not zipfile.is_zipfile(path):
        raise ValueError("not a zip archive (an .npz file is a zip of named .npy arrays)")
    with np.load(path, allow_pickle=False) as data:  # read inside: members load lazily
        def get(name: str):
            check_size(path, f"array '{name}'", _npz_member_bytes(data.zip, f"{name}.npy"))
            return data[name]

        return _keyed(data.files, get, names)


def _npz_member_bytes(archive: zipfile.ZipFile, member: str) -> int:
    """What an NPZ member takes once read: its .npy header's shape times its item size (what
    numpy allocates), or its declared inflated size if that is larger."""
    info = archive.getinfo(member)
    with archive.open(member) as f:
        version = np.lib.format.read_magic(f)
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, _, dtype = read_header(f, max_header_size=10_000)
    return max(math.prod(shape) * dtype.itemsize, info.file_size)


def _h5py():
    try:
        import h5py
    except ImportError:  # pragma: no cover - h5py is a dependency
        raise GearlabInputError("reading HDF5 and MATLAB v7.3 files needs h5py: pip install h5py") from None
    return h5py


def _read_hdf5(path: Path, names: Sequence[str], matlab: bool = False) -> _Contents:
    """Datasets by path ("group/acc").

    Rate fields are scoped like variables: for each channel, the nearest level that has
    any wins — an 'fs' attribute on the channel itself, else an 'fs' attribute or an
    'fs'/'t' dataset in its group, else in the group above, up to the file's root. So a
    file-wide rate can be overridden per group, and groups recorded at different rates
    can share one file. The fields found for the different channels must agree.

    matlab: the file is a MATLAB v7.3 MAT-file, whose variables are HDF5 datasets stored
    transposed, with text as uint16 character codes and internals under '#refs#'.
    """
    h5py = _h5py()

    def read(ds):
        # declared, not stored: a dataset never written takes no room in the file
        check_size(path, f"dataset '{ds.name}'", (ds.size or 0) * max(ds.dtype.itemsize, 8))
        if h5py.check_string_dtype(ds.dtype) is not None:
            return _normalise(ds.asstr()[()])
        value = np.asarray(ds[()])
        if matlab:
            cls = ds.attrs.get("MATLAB_class", b"")
            cls = cls.decode() if isinstance(cls, bytes) else str(cls)
            value = value.T  # back to MATLAB's (rows, columns)
            if cls == "char" and value.dtype.kind in "iu":
                rows = np.atleast_2d(value)
                return _normalise(["".join(map(chr, row)) for row in rows.tolist()])
            value = np.squeeze(value)  # as loadmat(squeeze_me=True) gives v5 variables
        return _normalise(value)

    def level_fields(node, is_group: bool) -> tuple[list, list]:
        """(rates, times) defined at one node: its 'fs' attributes, and for a group its
        'fs' and 't'/'time' datasets."""
        rates = [(f"attribute '{key}' of '{node.name}'", _normalise(value))
                 for key, value in node.attrs.items() if key.lower() in _RATE_NAMES]
        times = []
        if is_group:
            for key in node:
                child = node.get(key)
                if isinstance(child, h5py.Dataset) and key.lower() in _RATE_NAMES:
                    rates.append((f"dataset '{child.name}'", read(child)))
                elif isinstance(child, h5py.Dataset) and key.lower() in _TIME_NAMES:
                    times.append((f"time dataset '{child.name}'", read(child)))
        return rates, times

    with h5py.File(path, "r") as f:
        contents = _Contents({}, _hdf5_datasets(h5py, f))
        seen: set[str] = set()
        for name in dict.fromkeys(names):
            try:
                obj = f[name.strip("/")]
            except (KeyError, ValueError, TypeError):
                continue  # not there: reported with the list of datasets
            if not isinstance(obj, h5py.Dataset):
                continue  # a group is not a channel
            contents.found[name] = read(obj)
            node, is_group = obj, False
            while True:  # from the channel up to the root; the nearest definition wins
                rates, times = level_fields(node, is_group)
                if rates or times or node.name == "/":
                    break
                node, is_group = node.parent, True
            for kind, fields in ((contents.rates, rates), (contents.times, times)):
                for where, value in fields:
                    if where not in seen:  # channels of one group share its fields
                        seen.add(where)
                        kind.append((where, value))
        return contents


_HDF5_MAX_OBJECTS = 100_000


def _hdf5_datasets(h5py, f) -> list[str]:
    """Paths of the datasets in the file, depth first in name order (MATLAB's '#refs#' and
    the like left out). Each object is visited once, through hard links only: h5py's
    visititems loops forever in some damaged files, and an external link would open
    another file."""
    found: list[str] = []
    seen = {f.id}
    stack = [("", f)]
    while stack:
        prefix, group = stack.pop()
        children = []
        for key in group:
            if not isinstance(group.get(key, getlink=True), h5py.HardLink):
                continue
            obj = group[key]
            if obj.id in seen:
                continue
            seen.add(obj.id)
            if len(seen) > _HDF5_MAX_OBJECTS:
                raise ValueError(f"more than {_HDF5_MAX_OBJECTS} objects (a damaged file?)")
            name = f"{prefix}{key}"
            if isinstance(obj, h5py.Group):
                children.append((f"{name}/", obj))
            elif isinstance(obj, h5py.Dataset) and not name.startswith("#"):
                found.append(name)
        stack.extend(reversed(children))
    return found


def _read_wav(path: Path, names: Sequence[str]) -> _Contents:
    """Channels "0", "1", … of a WAV file; integer PCM scaled to [-1, 1), float kept as is."""
    from scipy.io import wavfile

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            rate, data = wavfile.read(path)
        except ZeroDivisionError:  # scipy divides by the header's bytes per frame
            raise ValueError("its header declares 0 channels or 0 bytes per sample; expected at least one "
                             "channel of samples") from None
    for w in caught:
        # scipy reads what is there of a truncated file and only warns: refuse, never half a record.
        if "EOF" in str(w.message):
            raise ValueError(str(w.message))
    data = np.asarray(data)
    if data.ndim == 1:
        data = data[:, None]
    step = 0.0
    if data.dtype.kind == "u":  # 8-bit PCM is unsigned around 128
        half = 2.0 ** (8 * data.dtype.itemsize - 1)
        data, step = (data.astype(np.float64) - half) / half, 1.0 / half
    elif data.dtype.kind == "i":  # 24-bit PCM arrives left-justified in int32
        step = 1.0 / 2.0 ** (8 * data.dtype.itemsize - 1)
        data = data.astype(np.float64) * step
    if data.ndim != 2 or data.shape[1] == 0:
        raise ValueError("it holds no channel; expected at least one")
    channels = [str(i) for i in range(data.shape[1])]
    found = {n: data[:, int(n)] for n in dict.fromkeys(names) if n in channels}
    steps = {n: step for n in found} if step else {}
    return _Contents(found, channels, rates=[("the WAV header", np.asarray(rate))], steps=steps)


def _is_mat73(path: Path) -> bool:
    """MATLAB v7.3 files carry version 0x0200 in their 128-byte header (and are HDF5)."""
    with path.open("rb") as f:
        header = f.read(128)
    return len(header) == 128 and header[124:126] in (b"\x00\x02", b"\x02\x00")


def _read_mat(path: Path, names: Sequence[str]) -> _Contents:
    """MATLAB variables by name: v4/v5 through scipy, v7.3 (HDF5) through h5py.

    A v5 file's layout is checked first (_mat5_variables), and scipy reads only the
    variables asked for and the rate fields, never the others (objects, function handles).
    """
    if _is_mat73(path):
        return _read_hdf5(path, names, matlab=True)
    from scipy.io import loadmat

    with path.open("rb") as f:
        v4 = 0 in f.read(4)  # how scipy tells v4 files from v5 ones
    if v4:  # scipy's v4 reader is plain Python over numpy: nothing to check first
        variables = loadmat(path, squeeze_me=True, chars_as_strings=True)
        available = [k for k in variables if not k.startswith("__")]  # __header__, __version__, …
    else:
        def wanted(name: str) -> bool:  # the channels asked for and the rate fields (see _keyed)
            return name in names or name.lower() in _RATE_NAMES + _TIME_NAMES

        every = _mat5_variables(path.read_bytes(), wanted)
        available = list(dict.fromkeys(n for n in every if n and not n.startswith("__")))
        # squeeze_me: a 1×N row or N×1 column becomes a vector, a 1×1 a scalar.
        variables = loadmat(path, squeeze_me=True, chars_as_strings=True,
                            variable_names=[n for n in available if wanted(n)])
    return _keyed(available, lambda n: variables[n], names)


# --- MATLAB v5 layout ----------------------------------------------------------------------
# scipy's v5 reader trusts the element types it finds, and scipy documents it as not
# hardened for untrusted files: a data element of a type it has no dtype for makes it index
# past its table of dtypes and crash the process (one flipped bit in a variable's array flags
# does it). So the elements are walked here first, as the reader will take them; a file that
# does not follow the layout is refused before scipy sees it.

_MI_INT8, _MI_INT32, _MI_UINT32, _MI_MATRIX, _MI_COMPRESSED, _MI_UTF8 = 1, 5, 6, 14, 15, 16
_MI_DATA = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 16, 17, 18})  # the types scipy has a dtype for
_MI_TEXT = frozenset({_MI_INT8, _MI_UTF8})  # names, class names, field names
_MX_CELL, _MX_STRUCT, _MX_OBJECT, _MX_CHAR, _MX_SPARSE, _MX_OPAQUE = 1, 2, 3, 4, 5, 17
_MX_NUMERIC = range(6, 16)  # double, single, int8 … uint64
_MAT_MAX_DEPTH = 32  # cells in cells, structs in structs


class _Mat5Layout:
    """Walks MATLAB v5 elements: tag (type, size) then data padded to 8 bytes, or a small data
    element (size and type in one word, up to 4 bytes of data in the next)."""

    def __init__(self, order: str):
        self.order = order

    def element(self, buf: memoryview, pos: int, end: int) -> tuple[int, memoryview, int]:
        """(type, data, position after it) of the element at *pos*; it must end by *end*."""
        if pos + 8 > end:
            raise ValueError(f"an element at byte {pos} runs past the end of the variable")
        first, size = struct.unpack_from(self.order + "II", buf, pos)
        if first >> 16:
            if first >> 16 > 4:
                raise ValueError(f"a small data element of {first >> 16} bytes at byte {pos}")
            return first & 0xFFFF, buf[pos + 4:pos + 4 + (first >> 16)], pos + 8
        start = pos + 8
        if start + size > end:
            raise ValueError(f"an element of {size} bytes at byte {pos} runs past the end of the variable")
        return first, buf[start:start + size], min(end, start + (size + 7) // 8 * 8)

    def data(self, buf: memoryview, pos: int, end: int, types: frozenset = _MI_DATA) -> int:
        kind, _, pos = self.element(buf, pos, end)
        if kind not in types:
            raise ValueError(f"a data element of type {kind}, which MATLAB does not use there")
        return pos

    def matrix(self, buf: memoryview, pos: int, end: int, depth: int) -> int:
        """A matrix element inside a cell or struct; the position after it."""
        kind, body, after = self.element(buf, pos, end)
        if kind != _MI_MATRIX:
            raise ValueError(f"a cell or field of element type {kind}, expected a matrix")
        if body:  # an empty matrix has no body at all
            self.body(body, depth, lambda name: True)
        return after

    def body(self, body: memoryview, depth: int, read) -> str:
        """Check a matrix: array flags, dimensions, name and, when read(name), its contents.
        Returns the name."""
        if depth > _MAT_MAX_DEPTH:
            raise ValueError(f"cells or structs nested more than {_MAT_MAX_DEPTH} deep")
        end = len(body)
        kind, flags, pos = self.element(body, 0, end)
        if kind != _MI_UINT32 or len(flags) != 8:
            raise ValueError("a matrix without its array flags")
        word = struct.unpack_from(self.order + "I", flags)[0]
        mclass, is_complex = word & 0xFF, bool(word >> 11 & 1)
        count = 0
        if mclass != _MX_OPAQUE:  # objects of classdef classes carry no dimensions
            kind, dims, pos = self.element(body, pos, end)
            if kind not in (_MI_INT32, _MI_UINT32) or len(dims) % 4 or not 2 <= len(dims) // 4 <= 32:
                raise ValueError("a matrix without valid dimensions")
            sizes = struct.unpack(self.order + f"{len(dims) // 4}i", dims)
            if min(sizes) < 0:
                raise ValueError(f"a matrix of negative size {sizes}")
            count = math.prod(sizes)
        kind, raw, pos = self.element(body, pos, end)
        if kind not in _MI_TEXT:
            raise ValueError("a matrix without a valid name")
        name = bytes(raw).decode("latin1")
        if not read(name):
            return name  # scipy reads no more of a variable it is not asked for
        if mclass in _MX_NUMERIC:
            for _ in range(2 if is_complex else 1):  # real part, imaginary part
                pos = self.data(body, pos, end)
        elif mclass == _MX_CHAR:
            pos = self.data(body, pos, end)
        elif mclass == _MX_SPARSE:
            for _ in range(4 if is_complex else 3):  # row indices, column starts, values (real, imaginary)
                pos = self.data(body, pos, end)
        elif mclass == _MX_CELL:
            for _ in range(count):  # each cell takes 8 bytes at least: the walk ends with the data
                pos = self.matrix(body, pos, end, depth + 1)
        elif mclass in (_MX_STRUCT, _MX_OBJECT):
            if mclass == _MX_OBJECT:
                pos = self.data(body, pos, end, _MI_TEXT)  # the class name
            kind, length, pos = self.element(body, pos, end)
            if kind not in (_MI_INT32, _MI_UINT32) or len(length) != 4:
                raise ValueError("a struct without the length of its field names")
            length = struct.unpack(self.order + "i", length)[0]
            kind, fields, pos = self.element(body, pos, end)
            if kind not in _MI_TEXT or length <= 0:
                raise ValueError("a struct without valid field names")
            for _ in range(count * (len(fields) // length)):
                pos = self.matrix(body, pos, end, depth + 1)
        else:  # function handles, classdef objects, Java objects: no measured data
            raise ValueError(f"variable '{name}' is a MATLAB {('function handle' if mclass == 16 else 'object')}, "
                             "not numbers or text")
        return name


def _inflate(data, at: int) -> bytes:
    """A compressed MATLAB variable, refused once it inflates beyond the record size limit."""
    limit = max_record_bytes()
    inflater = zlib.decompressobj()
    out = inflater.decompress(data, limit + 1)
    if len(out) > limit:
        raise ValueError(f"the compressed variable at byte {at} inflates to more than the limit of "
                         f"{limit / 2**20:,.0f} MB for a measured record (set GEARLAB_MAX_RECORD_MB to allow more)")
    return out


def _mat5_variables(data: bytes, read) -> list[str]:
    """Names of the variables of a MATLAB v5 file, after checking their layout: every
    variable's header, and in full those for which read(name) is true."""
    if len(data) < 128 or data[126:128] not in (b"IM", b"MI"):
        raise ValueError("no MATLAB 5 header (128 bytes ending in 'IM' or 'MI')")
    layout = _Mat5Layout("<" if data[126:128] == b"IM" else ">")
    data = memoryview(data)  # slices without copies of the arrays
    names = []
    pos = 128
    while pos < len(data):
        if pos + 8 > len(data):
            raise ValueError(f"{len(data) - pos} stray bytes at the end")
        kind, size = struct.unpack_from(layout.order + "II", data, pos)
        start, pos = pos + 8, pos + 8 + size  # variables follow each other unpadded
        if size == 0 or pos > len(data):
            raise ValueError(f"a variable of {size} bytes at byte {start - 8} of {len(data)}")
        if kind == _MI_COMPRESSED:
            inner = memoryview(_inflate(data[start:pos], start - 8))
            kind, body, _ = layout.element(inner, 0, len(inner))
        else:
            body = data[start:pos]
        if kind != _MI_MATRIX:
            raise ValueError(f"a variable of element type {kind}, expected a matrix")
        names.append(layout.body(body, 0, read))
    return names


_READERS = {"CSV": _read_csv, "NPZ": _read_npz, "HDF5": _read_hdf5, "WAV": _read_wav, "MATLAB": _read_mat}


def _read(path, names: Sequence[str], roles: dict[str, str] | None = None) -> tuple[_Contents, str]:
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
        contents = _READERS[fmt](path, names)
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
        raise GearlabInputError(
            f"{path}: sampling rate field {where} must be one number in Hz, got {shown}"
        )
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


def _file_rate(contents: _Contents, n: int | None, path: str) -> tuple[float, float, str] | None:
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


def _sampling_rate(contents: _Contents, given: float | None, n: int, path: str) -> tuple[float, str]:
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
        raise GearlabInputError(
            f"{path}: {what} is not numeric (stored as {arr.dtype}); expected an array of numbers"
        )
    if arr.dtype.kind == "b" and role == "vibration":  # a tacho's pulses may be true/false; a vibration not
        raise GearlabInputError(f"{path}: {what} holds true/false values; expected a vibration signal of numbers")
    if arr.ndim > 1 and sum(s > 1 for s in arr.shape) <= 1:
        arr = arr.reshape(-1)  # a 1×N or N×1 matrix is one channel
    if arr.ndim == 0:
        raise GearlabInputError(f"{path}: {what} holds a single value; expected a time series, one value per sample")
    if arr.ndim > 1:
        raise GearlabInputError(
            f"{path}: {what} has shape {arr.shape}; expected one channel over time (a 1-D array)"
        )
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
    """"angle" or "pulses" for a tacho channel (tacho_kind = "auto").

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


def _shaft_angle(spec: MeasuredSpec, tacho: np.ndarray | None, fs: float, n: int, path: str
                 ) -> tuple[dict, np.ndarray, str]:
    """(cut_revolutions' angle argument, the continuous angle it computes from it, a description).

    The angle is computed here with the very functions cut_revolutions applies to the
    same argument, so revolution boundaries found here (for labels) are exactly those of
    the revolutions it cuts.
    """
    if tacho is None:
        return ({"speed_hz": float(spec.speed_hz)}, angle_from_speed(n, fs, spec.speed_hz),
                f"nominal speed {fmt_hz(spec.speed_hz)}")
    kind = _tacho_kind(tacho) if spec.tacho_kind == "auto" else spec.tacho_kind
    detected = ", detected" if spec.tacho_kind == "auto" else ""
    if kind == "angle":
        with _prefixed(f"{path}: tacho '{spec.tacho}' (read as the shaft angle in rad{detected})"):
            wrapped = _angle_tacho(tacho)
            return {"tacho": wrapped}, unwrap_tacho(wrapped), f"tacho '{spec.tacho}' (shaft angle{detected})"
    # angle_from_pulses fails only for want of edges: a tacho that never completes a revolution.
    with _prefixed(f"{path}: tacho '{spec.tacho}' never completes a revolution "
                   f"(read as a once-per-revolution pulse train{detected})"):
        return ({"pulses": tacho}, angle_from_pulses(tacho, fs),
                f"tacho '{spec.tacho}' (once-per-revolution pulses{detected})")


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
                why = (f"by {source}, the shaft turns {turns:.3g} revolutions at {fmt_hz(speed)}; one revolution "
                       f"needs {per_rev:.0f} samples at {fmt_hz(fs)}: the record is too short or the tacho "
                       "never completes a revolution")
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
                    f"{path}: {what} holds the unknown class {_one_line_repr(v)}{did_you_mean(v, names)} at sample {i}; "
                    f"{known}"
                )
        return np.asarray([lookup[v] for v in values.tolist()], dtype=np.int64)[inverse.reshape(-1)]
    if arr.dtype.kind not in "biuf":
        raise GearlabInputError(
            f"{path}: {what} is stored as {arr.dtype}; expected class names or class indices"
        )
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
        return (f"m/s² = value x gain {1.0 if spec.gain is None else spec.gain:g} V / sensitivity "
                f"{1.0 if spec.sensitivity is None else spec.sensitivity:g} V/(m/s²)")
    what = ("integer counts (full-scale fractions for WAV)" if integer else "numbers")
    return (f"unknown: the {fmt} record holds {what} with no sensitivity or gain given; its values are taken "
            "as m/s² (set sensitivity = '10 mV/g' and, for integer data, gain = volts per count)")


def import_measured(spec: MeasuredSpec) -> Dataset:
    """A measured record as a Dataset (see _import_measured); running out of memory on the
    way (a record just under the size limit on a small machine) is one clear line."""
    try:
        return _import_measured(spec)
    except MemoryError:
        raise GearlabInputError(f"{spec.path}: not enough memory to import this record; a shorter record, or a "
                                "machine with more memory") from None


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
