"""Measured vibration as a gearlab Dataset, through the same pipeline as simulated data (docs/real_data.md).

A real user's target domain is measured: a vibration channel recorded together with a
tacho channel, or at a known nominal speed, in whatever file the acquisition system
writes. :func:`import_measured` reads such a record and sends it through the functions
of :mod:`gearlab.signals` that also turn simulated records into samples:

    file ─► channels, rate, vibration in m/s²       gearlab.data.recordings (the one import path of a
                                                    measured file, every format and kind)
         ─► continuous input-shaft angle            unwrap_tacho | angle_from_pulses | angle_from_speed
                                                    (no tacho: a declared speed, or the speed found
                                                    from a gearbox description's mesh lines)
         ─► complete revolutions at 4096 angles     cut_revolutions
         ─► start-up transient dropped              steady_start_stats (the method for measured data;
                                                    a level that never settles is kept whole, with
                                                    a warning in meta["warnings"])
         ─► standardised against healthy data       Standardiser (eq. 2.112/4.6)
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .. import PHYSICS_VERSION
from ..errors import GearlabInputError, did_you_mean
from ..files import split_take, take_file
from ..signals import (
    POINTS,
    Standardiser,
    check_signal,
    cut_revolutions,
    revolution_starts,
)
from ..signals.checks import check_int, check_positive, fmt_hz
from .chain import FRACTIONS_KEPT
from .channel_units import declared_unit
from .readers.base import _one_line_repr
from .recordings import (
    FORMATS,
    TACHO_KINDS,
    check_measured_file,
    prefixed,
    read_channels,
    read_recording,
    shaft_angle,
    steady_start,
)
from .spec import Dataset

__all__ = ["FORMATS", "MeasuredSpec", "import_measured", "read_channels"]

TWO_PI = 2.0 * np.pi

# "periodic" (steady_start) compares waveforms and needs a noise-free simulation: not offered.
IMPORT_TRANSIENTS = ("stats", "none")
# Bumped whenever the importer's output for the same file and options changes (cache keys).
# 2: units from channel names, the steady-start warning; 3: no-tacho speed not followed on noise; 4: a no-tacho
# record's speed read near the description's [operation] speed first, as inspect reads it
IMPORTER_VERSION = "4"
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
    tacho_kind:  "auto" (detected, see tacho_kind), "angle" or "pulses"
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
                 taken as m/s² (meta "units" says so, and the gap kind warns); a channel whose name
                 says its unit (acc_V, "acc [m/s^2]", acc_g) is taken so (recordings.channel_scale)
    unit:        the vibration channel's unit where neither its name nor the file says it (recordings.UNITS:
                 "m/s^2", "g", "V" or "mV"); None: not given
    pulses_per_rev: marks per revolution of a pulse tacho
    gearbox:     a gearbox description (file or built-in name): without a tacho, the speed is found
                 from its mesh lines (to ±1 % of speed_hz when that is given too); with one, the
                 shaft the tacho reads ([sensor] tacho) turns the tacho's angle into the input's
    tacho_shaft: the shaft the tacho reads, one of the description's (default: its [sensor] tacho)
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
    pulses_per_rev: int = 1
    gearbox: str | None = None
    unit: str | None = None
    tacho_shaft: str | None = None

    def canonical(self) -> dict:
        """The options that shape the data: not the name (a label) nor where the file lies (nor the
        units when not given: records imported before they existed keep their cache keys)."""
        d = asdict(self)
        d.pop("name")
        d.pop("path")
        for key, default in (
            ("sensitivity", None),
            ("gain", None),
            ("pulses_per_rev", 1),
            ("gearbox", None),
            ("unit", None),
            ("tacho_shaft", None),
        ):
            if d[key] == default:
                d.pop(key)
        return d

    @property
    def scale(self) -> float:
        """m/s² per file unit: gain / sensitivity (1 for what is not given)."""
        return (1.0 if self.gain is None else self.gain) / (1.0 if self.sensitivity is None else self.sensitivity)

    @property
    def units_known(self) -> bool:
        return self.sensitivity is not None or self.gain is not None or self.unit is not None

    def key(self) -> str:
        """Cache key: sha256 over the file's bytes, its format and the options (24 hex chars); a
        gearbox description by its content, not its name or place (the speed found without a
        tacho follows its tooth counts: an edited description must not reuse the old import)."""
        path = Path(self.path)
        check_measured_file(path)
        digest = hashlib.sha256()
        try:
            with take_file(path).open("rb") as f:  # a take's: its file's, and which take (below)
                for block in iter(lambda: f.read(1 << 20), b""):
                    digest.update(block)
            if (take := split_take(path)) is not None:
                digest.update(repr(take).encode())
        except OSError as exc:
            raise GearlabInputError(f"{path}: cannot read ({exc.strerror or exc})") from None
        options = self.canonical()
        if self.gearbox is not None:
            from ..gearbox.simulation import reference

            try:
                options["gearbox"] = reference(self.gearbox).rpartition("#")[2]
            except OSError as exc:
                raise GearlabInputError(f"{self.gearbox}: cannot read ({exc.strerror or exc})") from None
        text = json.dumps(
            {
                "file": digest.hexdigest(),
                "format": take_file(path).suffix.lower(),
                "options": options,
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
        if self.tacho is not None and self.speed_hz is not None:
            raise GearlabInputError(
                f"{where}: give either a tacho channel (tacho = ...) or a nominal shaft speed (speed = ...) or a "
                "gearbox description to find it from (gearbox = ...) to know the shaft angle, got both"
            )
        if self.tacho_shaft is not None and (
            self.tacho is None or self.gearbox is None and self.tacho_shaft != "input"
        ):
            raise GearlabInputError(
                f"{where}: tacho_shaft {self.tacho_shaft!r}: expected a tacho channel (tacho = ...) and a gearbox "
                "description (gearbox = ...) whose shafts it names"
            )
        if self.tacho is None and self.speed_hz is None and self.gearbox is None:
            raise GearlabInputError(
                f"{where}: give either a tacho channel (tacho = ...) or a nominal shaft speed (speed = ...) or a "
                "gearbox description to find it from (gearbox = ...) to know the shaft angle, got neither"
            )
        declared_unit(self.unit, f"{where}: unit")
        if self.tacho_kind not in TACHO_KINDS:
            raise GearlabInputError(
                f"{where}: unknown tacho_kind '{self.tacho_kind}'{did_you_mean(str(self.tacho_kind), TACHO_KINDS)}; "
                f"known: {', '.join(TACHO_KINDS)}"
            )
        with prefixed(where):
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
            check_int(self.pulses_per_rev, "pulses_per_rev (tacho pulses per revolution)", minimum=1)
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
    with prefixed(f"{path}: {source}"):
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
    with prefixed(path):
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


def _steady_start(
    revs: np.ndarray, labels: np.ndarray | None, spec: MeasuredSpec, path: str
) -> tuple[int, str, str | None]:
    """Index of the first steady revolution, how it was found, and a warning (a level that never
    settles: every revolution kept, recordings.steady_start).

    A start-up transient lies at the start of the record. It is judged on the leading revolutions
    that share the first label: a later change of condition in a labelled record changes the
    vibration level too, and must not be taken for a transient.
    """
    if spec.transient == "none":
        return 0, "not detected (transient = 'none')", None
    run = revs.shape[0] if labels is None else int(np.argmax(np.append(labels != labels[0], True)))
    return steady_start(revs[:run], f"{path}: vibration channel '{spec.vibration}'", spec.rtol)


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
    rec = read_recording(
        path,
        spec.vibration,
        spec.tacho,
        fs=spec.fs,
        sensitivity=spec.sensitivity,
        gain=spec.gain,
        unit=spec.unit,
        extra=() if spec.labels is None else ((spec.labels, "labels"),),
    )
    vib, fs, n = rec.signal, rec.fs, rec.signal.size
    per_sample = None
    if spec.labels is not None:
        per_sample = _class_indices(rec.extra[spec.labels], spec, n, path)

    box = None
    if spec.gearbox is not None:
        from ..gearbox import resolve_gearbox

        box = resolve_gearbox(spec.gearbox)
    shaft = None  # with a description: its [sensor] tacho, unless the spec names the shaft
    if spec.tacho_shaft is not None and box is not None:
        from ..gearbox.orders import TachoShaft

        shaft = TachoShaft.of(box, spec.tacho_shaft, f"{path}: tacho_shaft")
    source, angle, how = shaft_angle(
        rec,
        kind=spec.tacho_kind,
        pulses_per_rev=spec.pulses_per_rev,
        speed_hz=spec.speed_hz,
        gearbox=box,
        tacho_shaft=shaft,
    )
    source.pop("ends", None)  # every revolution: a followed angle's unsettled ends are left out by localisation alone
    starts = _revolution_bounds(angle, fs, how, path)
    labels = None if per_sample is None else _revolution_labels(per_sample, starts, spec, path)

    # The shared pipeline: the same call as for simulated records. The transient is judged
    # below on the leading single-label run rather than inside (see _steady_start).
    with prefixed(f"{path}: vibration channel '{spec.vibration}'"):
        cut = cut_revolutions(vib, fs, **source, points=spec.points, transient="none")
    revs = cut.revolutions
    if revs.shape[0] != starts.size - 1:  # pragma: no cover - both follow from the same angle
        raise RuntimeError(f"importer bug: {revs.shape[0]} revolutions cut, {starts.size - 1} bounded")
    start, transient, warning = _steady_start(revs, labels, spec, path)
    warns = [f"{path}: {w}" for w in rec.warnings] + ([warning] if warning else [])  # a footer left out, a drift
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
    with prefixed(f"{path}: healthy reference of vibration channel '{spec.vibration}'"):
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
            "format": rec.format,
            "fs_hz": float(fs),
            "fs_source": rec.fs_source,
            "speed_hz": float(cut.speed_hz),
            "angle_source": how,
            # no tacho, no declared speed: found from the description's mesh lines, where a speed and a
            # pinion's tooth count trade off (the gap's structure line names both)
            "speed_from_mesh": rec.tacho is None and box is not None and spec.speed_hz is None,
            "samples": int(n),
            "complete_revolutions": int(cut.complete),
            "transient_revolutions": int(start),
            "transient": transient,
            "reference": reference,
            "healthy_revolutions": int(healthy.sum()),
            # the measurement chain (gearlab.data.chain): what a simulation goes through to compare
            "start_fractions": [round(float(f), 4) for f in fractions],
            "quantum": rec.step,
            "units": rec.units,
            **({"warnings": warns} if warns else {}),
        },
    )
