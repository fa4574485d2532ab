"""A time column read as a sampling rate: checked uniform within the jitter of a logger's clock and the digits its
times were written to; a gap, a restart or a drift named in one line."""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from ..errors import GearlabInputError
from ..signals import check_signal
from ..signals.checks import fmt_hz
from .readers.base import _one_line_repr
from .readers.rates import SECONDS_PER_DAY, clock_seconds, coarse_times, serial_days

# A time column is uniform when every sample's distance from the straight line fitted to it
# stays within this fraction of a sampling period: rounding of written times (to the
# microsecond at 50 kHz: 5 %) stays below it, a dropped sample does not.
_TIME_JITTER = 0.25
# A column numbering a logger's takes (or segments, runs) one after another in one file: each file is one take
_TAKE_COLUMN = re.compile(r"(take|segment|trial|run|block|burst|chunk)[\s_#.-]*(no|nr|num|number|id|index)?\.?", re.I)


# A time column written in other units than seconds, as gearlab.data.readers.base._time_field names it: its errors
# say its times in its own unit ('time_ms' going back was said as '0.10045 -> 0.1004 s ... in seconds')
_SCALED = re.compile(r"\(x ([0-9.e+-]+) s\)$")
_UNIT_OF_SCALE = {1e-3: "ms", 1e-6: "µs"}


def _written_unit(where: str) -> tuple[str, float]:
    """(unit, seconds per value) in which the time column *where* was written."""
    match = _SCALED.search(where)
    scale = float(match.group(1)) if match else 1.0
    return (_UNIT_OF_SCALE[scale], scale) if scale in _UNIT_OF_SCALE else ("s", 1.0)


def take_columns(available: Sequence) -> list[str]:
    """The columns of *available* whose name says they number takes ('take', 'Segment #', 'run_id')."""
    return [str(c) for c in available if _TAKE_COLUMN.fullmatch(str(c).strip())]


def _written_resolution(t: np.ndarray) -> np.ndarray:
    """Each time's decimal step as written (1e-5 for 7.99972, 1e-6 for 2.5e-05: six significant digits),
    0 where finer than 1e-12 s."""
    step = np.zeros(t.size)
    for digits in range(12, -1, -1):  # the coarsest step a time is a whole multiple of
        scaled = t * 10.0**digits
        step[np.abs(scaled - np.round(scaled)) <= 1e-6 * np.maximum(1.0, np.abs(scaled))] = 10.0**-digits
    return step


def _grid_shift(residual: np.ndarray, steps: np.ndarray, m: int = 16) -> np.ndarray:
    """For each step i in *steps*: the mean residual of the m samples after it less that of the m before it."""
    total = np.concatenate(([0.0], np.cumsum(residual)))
    after = steps + 1
    lo, hi = np.maximum(after - m, 0), np.minimum(after + m, residual.size)
    return (total[hi] - total[after]) / (hi - after) - (total[after] - total[lo]) / (after - lo)


def rate_from_time(value, where: str, path: str, n: int | None, takes: Sequence[str] = ()) -> tuple[float, float, str]:
    """(fs, relative uncertainty, where) from a time vector in seconds (or Excel's serial days), checked uniform.

    fs = (N − 1) / (t_last − t_first); the times must lie within _TIME_JITTER of a sampling period of a uniform grid
    of that step (fitted to them by least squares). The rate is known only as well as the times were written
    (rounded to a few digits in a CSV file), so its uncertainty, 2·max deviation / span, widens the agreement asked
    of a given fs.
    """
    arr = clock_seconds(np.asarray(value))
    if arr.dtype.kind not in "biuf":
        first = next((str(v) for v in arr.ravel()[:1]), "")
        raise GearlabInputError(
            f"{path}: {where} must hold times in seconds or ISO 8601 clock times, got {_one_line_repr(first)}"
        )
    try:
        t = check_signal(np.squeeze(arr) if arr.ndim > 1 else arr, where)
    except GearlabInputError as exc:
        raise GearlabInputError(f"{path}: {exc}") from None
    if n is not None and t.size != n:
        raise GearlabInputError(f"{path}: {where} has {t.size} samples but the vibration has {n}; one per sample")
    written_as, scale = t, (SECONDS_PER_DAY if serial_days(t) else 1.0)
    t = (t - t[0]) * scale if scale != 1.0 else t
    if t.size < 2:
        raise GearlabInputError(f"{path}: {where} has {t.size} sample; at least 2 are needed for a sampling rate")
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.flatnonzero(steps <= 0)[0])
        unit, per = _written_unit(where)
        shown = t if per == 1.0 else written_as / per
        said = f"{path}: {where} does not increase between samples {i} and {i + 1} "
        said += f"({shown[i]:.9g} -> {shown[i + 1]:.9g} {unit})"
        mean, step = (t[-1] - t[0]) / (t.size - 1), np.min(steps[steps > 0], initial=np.inf)
        # stamped to 1 ms at 25.6 kHz, or written to 0.1 ms at 12.8 kHz (1.28 periods: 0.0002, 0.0002, 0.0003)
        coarse = step > 1.5 * mean or np.median(_written_resolution(written_as)) * scale > mean
        if np.all(steps >= 0) and mean > 0 and step < np.inf and coarse:
            raise coarse_times(said, 1 / mean, 2 * step / (t[-1] - t[0]), where)
        restarts = np.flatnonzero(t[1:] - t[0] < (t[:-1] - t[0]) / 2)  # back over half the time run: a new take
        if restarts.size:
            i, marked = int(restarts[0]), f", its takes marked by column {takes[0]!r}" if takes else ""
            key = f"takes = {takes[0]!r}" if takes else "takes = '<the column marking them>'"
            raise GearlabInputError(
                f"{path}: {where}: the time restarts at sample {i + 1} ({shown[i]:.9g} -> {shown[i + 1]:.9g} {unit}; "
                f"{restarts.size + 1} runs of time in all): several takes one after another in one file{marked}? "
                f"expected one take a recording: give {key} (each take a recording of its own; one alone by its name, "
                f"'{path}[{takes[0] if takes else 'take'}=1]') or write one file per take"
            )
        raise GearlabInputError(f"{said}; expected increasing times in {'seconds' if unit == 's' else unit}")
    span = float(t[-1] - t[0])
    dt = span / (t.size - 1)
    # off the least-squares line, not the one through the ends: a jittered first or last stamp would tilt that
    k = np.arange(t.size) - (t.size - 1) / 2
    residual = t - np.mean(t) - k * (np.dot(k, t - np.mean(t)) / np.dot(k, k))
    deviation = np.abs(residual)
    # times written to fewer digits than the rate needs (7.99972 s, 10 µs: 0.4 periods at 40 kHz) stand within
    # half their written resolution of the grid, besides the jitter allowed
    written = np.zeros(t.size)
    if np.any(np.abs(steps - dt) > _TIME_JITTER * dt) or np.any(deviation > _TIME_JITTER * dt):
        written = _written_resolution(written_as) * scale
    uneven = np.flatnonzero(np.abs(steps - dt) > _TIME_JITTER * dt + (written[1:] + written[:-1]) / 2)
    # a step off by more than the jitter is a gap where the stamps after it sit on a grid shifted by half a period
    # or more from the one before; a logger stamping each sample by its own clock moves single stamps, not the grid
    uneven = uneven[np.abs(_grid_shift(residual / dt, uneven)) >= 0.5]
    if uneven.size:  # a gap, a repeated block, a clock jump: name the first
        i = int(uneven[0])
        usual = float(np.mean(np.delete(steps, uneven))) if uneven.size < steps.size else dt
        lost = round(steps[i] / usual) - 1
        missing = f" (about {lost} samples missing at {t[i + 1]:.6g} s)" if lost >= 1 else ""
        raise GearlabInputError(
            f"{path}: {where} is not uniformly sampled: the step between samples {i} and {i + 1} is "
            f"{steps[i]:.6g} s, {steps[i] / usual:.3g} times the usual step {usual:.6g} s{missing}; expected uniform "
            "sampling: split the record at the gap, each part a file of its own"
        )
    worst = int(np.argmax(deviation - written / 2))
    if deviation[worst] > _TIME_JITTER * dt + written[worst] / 2:  # steps each fine but drifting
        raise GearlabInputError(
            f"{path}: {where} is not uniformly sampled: sample {worst} is {deviation[worst] / dt:.3g} sampling "
            f"periods off the uniform grid of {fmt_hz(1 / dt)} (a gap or jitter); expected uniform sampling"
        )
    return (t.size - 1) / span, 2.0 * float(deviation.max()) / span, where + (" in Excel serial days" * (scale != 1))
