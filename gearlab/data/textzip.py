"""Measured records in whitespace-separated text, plain or zipped (the PHM 2009 gearbox format).

A data-acquisition system often writes one text file per record: one row per sample,
columns separated by blanks, no sampling rate in the file, voltages as measured. Such a
record reaches gearlab through three steps:

    file (.zip of one text file, or the text itself)
       ─► the asked-for columns, as float64                  read_columns (streamed, chunked)
       ─► vibration in m/s² = volts / sensitivity            parse_sensitivity (pint, "10 mV/g")
       ─► continuous input-shaft angle from a tacho with N pulses per revolution
       ─► complete revolutions at 4096 angles                signals.cut_revolutions

The text is read from the archive in blocks of ``CHUNK_BYTES`` and only the asked-for
columns are kept, so a 13 MB text needs about the size of those columns (plus one block),
never the whole text and its parsed table at once. The one memory limit of every measured
file (``GEARLAB_MAX_RECORD_MB``, gearlab.data.readers.base) holds here too: a text (or a
zip member) declaring more is refused before a byte is inflated, and the text read and the
columns kept are counted while streaming, so an archive that lies about its size is
stopped at the limit too.

Columns are chosen by 0-based index (an int, or a text of digits) or by name when the
first row is a header of names. A tacho with ``pulses_per_rev`` = N equally spaced marks
gives a pulse every 1/N revolution: the j-th rising edge is at θ = 2πj/N
(:func:`gearlab.signals.angle_from_pulses` divided by N). The revolutions start at the first
mark seen in the record, which is any one of the N marks: two records of the same shaft may
start 2πm/N apart (the chip kind aligns them, :func:`align_to`).

Every bad file raises :class:`GearlabInputError` naming the file, the line or column and
what was expected.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..errors import GearlabInputError, shown
from ..signals import POINTS, angle_from_pulses, cut_revolutions, steady_start_stats
from ..signals.checks import fmt_hz
from ..units import to_si
from .readers.text import read_columns

__all__ = ["TextRecord", "align_to", "parse_sensitivity", "read_columns", "read_record"]

STANDARD_GRAVITY = 9.80665  # m/s², the "g" of accelerometer sensitivities (ISO 80000-3)
TWO_PI = 2.0 * np.pi


# --- sensor sensitivity ------------------------------------------------------------------

# "g" in a sensitivity is standard gravity, never the gram: pint's name for it is g_n.
_GRAVITY = re.compile(r"(?<![\w.])g(?![\w])")


def parse_sensitivity(value, where: str) -> float:
    """An accelerometer sensitivity ("10 mV/g", "1.02 mV/(m/s^2)", or a number in V/(m/s²))
    as volts per m/s²."""
    if isinstance(value, str):
        value = _GRAVITY.sub("g_n", value)
    try:
        s = to_si(value, "V*s^2/m", where)
    except GearlabInputError as exc:
        raise GearlabInputError(f"{exc} (volts per acceleration, e.g. '10 mV/g'; g is standard gravity)") from None
    if not s > 0:
        raise GearlabInputError(f"{where}: expected a positive sensitivity such as '10 mV/g', got {shown(value)}")
    return s


# --- a record ----------------------------------------------------------------------------


@dataclass(frozen=True)
class TextRecord:
    """One measured record cut into revolutions: *revolutions* (n, points) in m/s², not
    standardised, in record order, starting at the first tacho mark."""

    path: str
    revolutions: np.ndarray
    speed_hz: float
    fs: float
    samples: int
    transient_revolutions: int


def read_record(
    path,
    *,
    vibration,
    tacho,
    pulses_per_rev: int,
    sensitivity: float,
    fs: float,
    points: int = POINTS,
    transient: str = "none",
) -> TextRecord:
    """Read a record (``read_columns``), convert the vibration to m/s², find the shaft angle
    from the tacho's N = *pulses_per_rev* marks per revolution and cut the complete
    revolutions (*transient* "stats" drops a start-up transient, "none" keeps all)."""
    found, _, _ = read_columns(path, [vibration, tacho])
    raw = found[vibration]
    if raw.size and raw.min() == raw.max():  # refused as every other reader's import refuses it
        raise GearlabInputError(
            f"{path}: vibration column {shown(vibration)}: all {raw.size} values equal {raw[0]:g}; expected "
            "a measured vibration (a constant column: a wrong column, or a sensor not connected)"
        )
    vib = raw / sensitivity
    where = f"{path}: tacho column {shown(tacho)}"
    try:
        angle = angle_from_pulses(found[tacho], fs) / pulses_per_rev
    except GearlabInputError as exc:
        raise GearlabInputError(f"{where}: {exc}") from None
    turns = (angle[-1] - angle[0]) / TWO_PI
    if turns < 2:
        raise GearlabInputError(
            f"{where}: the {pulses_per_rev}-pulses-per-revolution tacho shows {turns:.3g} "
            f"revolutions in {vib.size} samples at {fmt_hz(fs)}; expected at least 2 (is "
            "pulses_per_rev right?)"
        )
    # the wrapped angle in [-π, π): cut_revolutions unwraps it and starts revolutions at its 2πk crossings
    wrapped = (angle + np.pi) % TWO_PI - np.pi
    try:
        cut = cut_revolutions(vib, fs, tacho=wrapped, points=points, transient="none")
        start = steady_start_stats(cut.revolutions) if transient == "stats" else 0
    except GearlabInputError as exc:
        raise GearlabInputError(f"{path}: vibration column {shown(vibration)}: {exc}") from None
    return TextRecord(str(path), cut.revolutions[start:], float(cut.speed_hz), float(fs), int(vib.size), int(start))


def align_to(reference: np.ndarray, signal: np.ndarray, marks: int) -> tuple[int, np.ndarray]:
    """(m, *signal* advanced by m/*marks* of a turn), m = 0 … marks-1 the advance whose mean
    revolution correlates best with *reference* (rows of *signal*: revolutions).

    Two records of one shaft may start at different tacho marks, i.e. 2πm/N apart; the shift
    is done in the order domain (exact for a periodic, band-limited revolution)."""
    n = reference.shape[-1]
    R = np.fft.rfft(reference)
    S = np.fft.rfft(np.mean(np.atleast_2d(signal), axis=0))
    orders = np.arange(R.size)
    best, best_corr = 0, -np.inf
    for m in range(marks):
        phase = np.exp(2j * np.pi * orders * m / marks)  # x(θ) -> x(θ + 2πm/marks)
        corr = float(np.real(np.sum(np.conj(R) * S * phase)))
        if corr > best_corr:
            best, best_corr = m, corr
    phase = np.exp(2j * np.pi * orders * best / marks)
    shifted = np.fft.irfft(np.fft.rfft(signal, axis=-1) * phase, n=n, axis=-1)
    return best, shifted.astype(signal.dtype, copy=False)
