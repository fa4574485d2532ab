"""A sampling rate or sample interval field by its name, its unit in the name or beside it: the one rule by which
a CSV preamble's 'Sampling Rate (kHz): 25.6', an HDF5 attribute 'fs_kHz', an NPZ or MATLAB 'SampleRate_kHz' and a
dataset 'sampling_rate_hz' are read, by every reader and by the header checks of `gearlab validate`."""

from __future__ import annotations

import re
import warnings

import numpy as np

from ...errors import GearlabInputError

# compared lower-case, blanks and '-' as '_' (fs, Fs, FS, 'Sample Rate'); a DAQ's HDF5 export writes 'SamplingRate'
# or 'SamplingFrequency' (a file attribute 'SamplingRate' was 'no sampling rate: the file has no 'fs'/time')
_RATE_NAMES = ("fs", "sample_rate", "sampling_rate", "samplerate", "samplingrate", "sampling_frequency")
_RATE_NAMES += ("samplingfrequency", "sample_frequency", "samplefrequency", "abtastrate", "abtastfrequenz")  # German
# a sample interval in seconds, which a logger may store instead of the rate (MATLAB's dt): its reciprocal is one
_INTERVAL_NAMES = ("dt", "delta_t", "sample_interval", "sampling_interval", "sample_period", "sampling_period")
_INTERVAL_NAMES += ("abtastintervall",)  # a German logger's preamble ('Abtastrate: 20 kHz' above, a rate)
# NI's TDMS waveform channel keeps it as 'wf_increment' (an HDF5 copy too), Simcenter Testlab's MAT export as its
# struct's x_values.increment: both were 'no sampling rate: the file has no 'fs'/time'
_INTERVAL_NAMES += ("wf_increment", "increment")

# Hz per value of a rate in a unit, seconds per value of an interval ("": none said, Hz or s)
RATE_UNITS = {"": 1.0, "hz": 1.0, "khz": 1e3, "s/s": 1.0, "sa/s": 1.0, "samples/s": 1.0, "1/s": 1.0, "ks/s": 1e3}
INTERVAL_UNITS = {"": 1.0, "s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6}

# Excel keeps a time as serial days since 1899-12-30 (a 'Time' column exported as General: 46357.4166666667 is
# 2026-12-01 10:00); read as seconds, a 25.6 kHz take came out at 2.2 GHz and 1.6e8 rpm. A time column of days from
# 1954 to 2119 whose step, read as seconds, is finer than any vibration logger's is read as days
_SERIAL_DAYS = (20000.0, 80000.0)
_FASTEST_LOGGER_HZ = 10e6
SECONDS_PER_DAY = 86400.0

# a name that ends in its unit: 'fs_kHz', 'sampling_rate_hz', 'fs (kHz)', 'SampleRate[kHz]', 'dt-us'
_UNIT_IN_NAME = re.compile(r"^(.+?)\s*(?:[_\-\s]+|[\[(]\s*)([A-Za-zµμ/1]+)\s*[\])]?$")


def key_of(text: str) -> str:
    """A field's name as the rate names are listed: lower case, blanks and '-' as '_'."""
    return "_".join(str(text).lower().split()).replace("-", "_")


def scale_of(key: str, unit: str) -> tuple[bool, float] | None:
    """(an interval?, Hz per value of a rate or seconds per value of an interval) of a field *key* (key_of) stated
    in *unit* ('' for none; any case); None where it is neither a rate nor an interval in a unit of one."""
    unit = unit.strip().lower()
    if key in _RATE_NAMES and unit in RATE_UNITS:
        return False, RATE_UNITS[unit]
    if key in _INTERVAL_NAMES and unit in INTERVAL_UNITS:
        return True, INTERVAL_UNITS[unit]
    return None


def named(name) -> tuple[bool, float] | None:
    """scale_of a field by its name alone: 'fs', 'Fs', 'dt', or a name that ends in its unit ('fs_kHz')."""
    whole = scale_of(key_of(name), "")
    if whole is not None:
        return whole
    match = _UNIT_IN_NAME.match(str(name).strip())
    return None if match is None else scale_of(key_of(match.group(1)), match.group(2))


def interval_rate(where: str, value: np.ndarray) -> tuple[str, np.ndarray]:
    """(where, the rate in Hz) of a sample interval field (_INTERVAL_NAMES) in seconds; a value that is not one
    positive number is passed on as it is, for the rate's check to refuse naming the field."""
    arr = np.asarray(value)
    if arr.size == 1 and arr.dtype.kind in "iuf" and float(arr.item()) > 0:
        return f"{where} (1 / sample interval)", np.asarray(1.0 / float(arr.item()))
    return where, value


def rate_field(where: str, name, value) -> tuple[str, object]:
    """(where, the rate in Hz) of the field *name* (a rate or interval field: named() is not None) holding *value*;
    a value that is not numbers is passed on as it is, for the rate's check to refuse naming the field."""
    interval, factor = named(name)
    arr = np.asarray(value)
    if factor != 1.0 and arr.dtype.kind in "iuf":
        value = arr * factor
    return interval_rate(where, value) if interval else (where, value)


def own_field(field: str, channel: str) -> str | None:
    """What *field* is of *channel* alone, as a DAQ exports each channel beside its own fields: 'rate' for a rate or
    interval field written after the channel's name ('ACC_fs', 'ACC_SampleRate_kHz'), 'time' for the channel's name
    with 'time_' or '_time' in it (Dewesoft's 'Data1_time_ACC' beside 'Data1_ACC', 'ACC_time'); else None."""
    for sep in ("_", " ", "-"):
        if field.startswith(channel + sep) and named(field[len(channel) + 1 :]) is not None:
            return "rate"
    return "time" if any(field.replace(s, "", 1) == channel for s in ("time_", "_time") if s in field) else None


def stated_hz(name, value) -> float | None:
    """The rate in Hz a field *name* states with its one number *value* (a rate, or an interval's reciprocal); None
    where *name* is no rate or interval field, or *value* not one number (an interval: not a positive one)."""
    found = named(name)
    if found is None:
        return None
    try:
        number = float(np.asarray(value).item())
    except (TypeError, ValueError):
        return None
    return in_hz(found, number)


def in_hz(found: tuple[bool, float], number: float) -> float | None:
    """The rate in Hz of *number* in a field of scale_of *found*: an interval's reciprocal (None where it is not
    positive), a rate as it is (0 Hz or less too, for the rate's check to refuse)."""
    interval, factor = found
    if interval:
        return 1.0 / (number * factor) if number > 0 else None
    return number * factor


def serial_days(t: np.ndarray) -> bool:
    """Whether a rising time column *t* holds Excel serial days rather than seconds (_SERIAL_DAYS)."""
    if t.size < 2 or not _SERIAL_DAYS[0] <= t[0] <= _SERIAL_DAYS[1]:
        return False
    return 0 < (t[-1] - t[0]) / (t.size - 1) < 1 / _FASTEST_LOGGER_HZ


# ISO 8601's decimal comma in a clock time ('10:00:00,000123', as German loggers write it), read as its point
_DECIMAL_COMMA = re.compile(r"(\d\d:\d\d:\d\d),(\d)")


def clock_seconds(arr: np.ndarray) -> np.ndarray:
    """Text times that are ISO 8601 clock times ('2026-11-30T10:00:00.000039', '2026-12-01 10:00:00,000123Z', a
    logger's timestamps) as seconds from the first, to the microsecond; any other array as it is. A zone ('Z',
    '+01:00') is read as UTC, without numpy's warning ('no explicit representation of timezones', shown as a run's
    warning though it changes nothing of a take's time differences); a decimal comma was 'must hold times'."""
    if arr.dtype.kind not in "USO" or arr.size < 2:
        return arr
    texts = [str(v).strip() for v in arr.ravel()]
    if "," in texts[0]:
        texts = [_DECIMAL_COMMA.sub(r"\1.\2", t) for t in texts]
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "no explicit representation of timezones", UserWarning)
        try:
            clock = np.array(texts, dtype="datetime64[us]")
        except ValueError:
            return arr
    return (clock - clock[0]).astype(np.int64) * 1e-6


class CoarseTimes(GearlabInputError):
    """A time column stamped coarser than a sampling period (a logger's clock to 1 ms at 25.6 kHz): refused unless a
    rate is given, which its stamps are checked against (its attributes fs, tolerance (relative) and where)."""


def coarse_times(said: str, fs: float, tolerance: float, where: str) -> CoarseTimes:
    """CoarseTimes for a time column *where* whose stamps give *fs* within *tolerance*: the line *said* with the rate to
    give ('does not increase ... (0 -> 0 s)' said none, and a given fs was refused by the same line)."""
    from ...signals.checks import fmt_hz

    exc = CoarseTimes(f"{said}, written coarser than a sampling period: give the rate, about fs = '{fmt_hz(fs)}'")
    exc.fs, exc.tolerance, exc.where = fs, tolerance, f"{where} (stamped coarser than a sampling period)"
    return exc
