"""From a record to steady input-shaft revolutions in the angle domain (thesis 2.4.3, 3.2).

The thesis' steps (section 3.2, steps 2–4; Figure 2.25):

1. identify and crop the steady-state part of the simulated signal s_i;
2. window it into single input-shaft rotations, cut where the shaft angle passes 0;
3. resample every window s_{i,j} to 4096 points, since windows differ in length when the
   speed varies slightly.

Here the order of 1 and 2/3 is swapped so that steadiness can be judged revolution by
revolution (on equal-length, angle-aligned vectors) instead of by eye: all complete
revolutions are cut and resampled, the transient is detected on them
(:func:`steady_start`, :func:`steady_start_stats`) and the revolutions before it dropped.

Cutting and resampling are one operation, angular resampling (computed order tracking):
revolution r is the signal evaluated at the P equally spaced angles

    θ_{r,p} = offset + 2π (k0 + r + p/P),   p = 0 … P−1,

by linear interpolation of the samples (θ[n], s[n]) on the continuous shaft angle. At
constant speed this is the thesis' "cut at zero crossings and resample to 4096 points";
at varying speed it still maps each shaft order onto a fixed bin. The *offset* moves
the cut: the steady response to a fault on pinion tooth n equals the tooth-1 response
cut at offset −(n−1)·2π/Z1 (tooth-shift symmetry), a shift that is generally not a whole
number of samples and is therefore taken through the same interpolation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import GearlabInputError
from .angle import TWO_PI, angle_from_pulses, angle_from_speed, unwrap_tacho
from .checks import check_array, check_int, check_positive, check_real, check_signal, fmt_hz

POINTS = 4096  # samples per revolution in the angle domain (thesis 2.4.3)
TRANSIENT_METHODS = ("periodic", "stats", "none")


# --- the continuous angle ---------------------------------------------------------------


def _check_angle(angle, name: str = "angle") -> np.ndarray:
    """A continuous, strictly increasing shaft angle (np.interp needs increasing abscissae)."""
    a = check_signal(angle, name)
    if a.size < 2:
        raise GearlabInputError(f"{name} has {a.size} sample; at least 2 are needed to follow the shaft")
    stalled = np.flatnonzero(np.diff(a) <= 0)
    if stalled.size:
        i = int(stalled[0])
        raise GearlabInputError(
            f"{name} does not increase between samples {i} and {i + 1} ({a[i]:.6g} -> {a[i + 1]:.6g} rad): "
            "expected the continuous angle of a shaft turning forwards (unwrap a wrapped tacho with "
            "unwrap_tacho; negate the angle of a shaft turning backwards)"
        )
    return a


def _turns(a: np.ndarray) -> float:
    return float(a[-1] - a[0]) / TWO_PI


def _samples_per_rev(a: np.ndarray) -> float:
    """Mean number of samples per revolution over the record."""
    return (a.size - 1) / _turns(a)


def revolution_starts(angle: np.ndarray, offset: float = 0.0) -> np.ndarray:
    """Fractional sample positions where the continuous angle θ crosses offset + 2πk, k integer.

    With offset = 0 these are the input-shaft zero crossings at which the thesis cuts
    revolutions (2.4.3). Between samples θ is taken as linear in time, so a crossing at
    level L between samples n and n+1 lies at n + (L − θ[n]) / (θ[n+1] − θ[n]).
    Raises when θ never crosses such a level.
    """
    a = _check_angle(angle)
    offset = check_real(offset, "offset")
    k_first = math.ceil((a[0] - offset) / TWO_PI)
    k_last = math.floor((a[-1] - offset) / TWO_PI)
    if k_last < k_first:
        raise GearlabInputError(
            f"tacho never crosses {offset:.4g} rad (mod 2π): the shaft angle runs from {a[0]:.4g} to "
            f"{a[-1]:.4g} rad ({_turns(a):.3g} revolutions); expected at least one revolution start"
        )
    levels = offset + TWO_PI * np.arange(k_first, k_last + 1, dtype=np.float64)
    # Inverse of the piecewise-linear θ(n): interpolate sample index against angle.
    return np.interp(levels, a, np.arange(a.size, dtype=np.float64))


def first_complete(angle: np.ndarray, offset: float = 0.0) -> int:
    """The first complete revolution's k of a continuous *angle* (rad): revolution k spans [offset + 2πk,
    offset + 2π(k+1)), counted from the angle's zero (a record's revolutions' numbers: localisation)."""
    return math.ceil((float(angle[0]) - offset) / TWO_PI)


def _complete_revolutions(a: np.ndarray, offset: float) -> tuple[int, int]:
    """(k0, R): the first complete revolution's k and the number of complete revolutions.

    Revolution k spans [offset + 2πk, offset + 2π(k+1)); it is complete when both its
    start and its end crossing lie inside the record.
    """
    k0 = first_complete(a, offset)
    k_end = math.floor((a[-1] - offset) / TWO_PI)
    count = k_end - k0
    if count < 1:
        raise GearlabInputError(
            f"signal has {a.size} samples covering {_turns(a):.3g} revolutions (about "
            f"{_samples_per_rev(a):.0f} samples per revolution) but not one complete revolution "
            f"between two crossings of {offset:.4g} rad + 2πk; expected a longer record"
        )
    return k0, count


def resample_revolutions(
    signal: np.ndarray,
    angle: np.ndarray,
    points: int = POINTS,
    offset: float = 0.0,
    first: int | None = None,
    count: int | None = None,
) -> np.ndarray:
    """Complete revolutions of *signal*, resampled to *points* equally spaced angles: shape (R, points).

    Revolution r (r = 0 … R−1 among the complete revolutions in the record) holds

        s_r[p] = s(θ = offset + 2π (k0 + r + p/P)),   p = 0 … P−1  (endpoint excluded),

    where k0 is the first k whose revolution [offset + 2πk, offset + 2π(k+1)) lies wholly
    in the record and s(θ) is the linear interpolation of the samples against the
    continuous angle (np.interp). This is the thesis' cutting at zero crossings plus
    resampling to 4096 points (2.4.3) done in one step, exact for any speed profile up to
    the interpolation error, and for any *offset* (tooth shift −(n−1)·2π/Z1).

    *first*/*count* select revolutions first … first+count−1 of the complete ones
    (default: all), so long records can be processed in blocks.
    """
    x = check_signal(signal, "signal")
    a = _check_angle(angle)
    if x.size != a.size:
        raise GearlabInputError(
            f"signal has {x.size} samples but the angle has {a.size}; expected one angle per sample"
        )
    points = check_int(points, "points per revolution", minimum=2)
    offset = check_real(offset, "offset")
    k0, total = _complete_revolutions(a, offset)

    first = 0 if first is None else check_int(first, "first revolution", minimum=0)
    if first >= total:
        raise GearlabInputError(
            f"first revolution {first} asked for, but the record holds {total} complete revolutions (0 … {total - 1})"
        )
    count = total - first if count is None else check_int(count, "revolution count", minimum=1)
    if first + count > total:
        raise GearlabInputError(
            f"revolutions {first} … {first + count - 1} asked for, but the record holds {total} complete "
            f"revolutions (0 … {total - 1})"
        )

    k = np.arange(k0 + first, k0 + first + count, dtype=np.float64)
    theta = offset + TWO_PI * (k[:, None] + np.arange(points, dtype=np.float64) / points)
    return np.interp(theta, a, x)


UPSAMPLE = 8  # a record's rate is raised this much before it is read at uniform angle (Upsampled)
MAX_UPSAMPLED = 1 << 24  # samples: a longer record is raised less


@dataclass(frozen=True)
class Upsampled:
    """A record band-limited interpolated *up* times (:func:`upsampled`): *signal* holds (n - 1) up + 1
    samples, sample i at the record's sample position i / up."""

    signal: np.ndarray
    up: int

    def at(self, values: np.ndarray) -> np.ndarray:
        """*values* given per sample of the record (its angle), linearly interpolated at the upsampled samples."""
        values = np.asarray(values)
        if self.up == 1:
            return values
        x = np.arange(self.signal.size) / self.up
        if values.dtype.kind in "fiu" and values.ndim == 1 and values.size:
            from .grid import read_grid  # np.interp on its own grid to the bit, in half the CPU

            out = np.empty(x.size)
            read_grid(x, np.ascontiguousarray(values, dtype=np.float64), out)
            return out
        return np.interp(x, np.arange(values.size), values)


def upsampled(signal: np.ndarray) -> Upsampled:
    """*signal* band-limited interpolated UPSAMPLE times (fewer where that passes MAX_UPSAMPLED samples), for
    the linear interpolation of a reading at uniform angle: on the record's own samples it leaves an image of a
    line at ν cycles per sample at 1 - ν, about (ν / (1 - ν))² below it (the B-6-ch5 source at 500 samples per
    revolution: order 175 imaged at 187, 10 dB down, listed as a line the description does not explain); at 8
    times the rate the images fall under inspect's line threshold. Used by `gearlab inspect` and by the speed
    of a record without a tacho (gearlab.gearbox.speed.follow_speed)."""
    from scipy.signal import resample_poly

    n = signal.size
    up = int(max(1, min(UPSAMPLE, MAX_UPSAMPLED // max(n, 1))))
    if up == 1:
        return Upsampled(signal, 1)
    return Upsampled(resample_poly(signal, up, 1)[: (n - 1) * up + 1], up)  # none past the last sample


# --- transient detection ----------------------------------------------------------------


def _check_revolutions(revolutions, name: str = "revolutions") -> np.ndarray:
    r = check_array(revolutions, name, min_ndim=2)
    if r.ndim != 2:
        raise GearlabInputError(f"{name} must have shape (R, points), got {r.shape}")
    if r.shape[0] < 2:
        raise GearlabInputError(
            f"{name} holds {r.shape[0]} revolution; at least 2 are needed to judge when the signal is steady"
        )
    return r


def _first_of_last_run(ok: np.ndarray) -> int:
    """Index from which on *ok* is True to the end (len(ok) if its last entry is False)."""
    bad = np.flatnonzero(~ok)
    return int(bad[-1]) + 1 if bad.size else 0


def steady_start(revolutions: np.ndarray, rtol: float = 1e-3) -> int:
    """Index of the first steady revolution of a simulated (periodic) response.

    The simulation starts from zero initial conditions and settles into a response that
    repeats every input-shaft revolution (thesis 2.4.3: "the system takes a few iterations
    to reach steady-state"). Taking the last revolution as the best estimate of that
    steady response, revolution i deviates from it by the relative RMS difference

        d_i = ‖r_i − r_last‖ / ‖r_last‖,

    and the steady part starts at the first i with d_j ≤ rtol for j = i and all later j.
    This replaces the thesis' visual cropping. It needs a noise-free periodic signal; for
    measured or noisy data use :func:`steady_start_stats`.

    Raises ("never settles") when even the second-to-last revolution differs from the
    last by more than rtol: then there is nothing to call steady (a growing or
    drifting response, or a record too short for the transient to die out).
    """
    r = _check_revolutions(revolutions)
    rtol = check_positive(rtol, "rtol")
    last = r[-1]
    # Compare squared norms to avoid a division (and a 0/0 for an all-zero revolution).
    dev = np.sum((r - last) ** 2, axis=1)
    ok = dev <= rtol**2 * np.sum(last**2)
    start = _first_of_last_run(ok)
    if start >= r.shape[0] - 1:
        d = math.sqrt(dev[-2] / np.sum(last**2)) if np.any(last) else math.inf
        raise GearlabInputError(
            f"signal never settles: revolution {r.shape[0] - 2} still differs from the last by {d:.3g} "
            f"(relative RMS), more than rtol = {rtol:g}; expected a periodic steady state "
            "(simulate longer, or use steady_start_stats for noisy data)"
        )
    return start


def steady_start_stats(revolutions: np.ndarray, rtol: float = 0.05, window: int = 1) -> int:
    """Index of the first steady revolution of noisy or measured data, from per-revolution RMS.

    Noise makes no two revolutions alike, so instead of comparing waveforms the level is
    compared: with RMS_j = sqrt(mean(r_j²)) and the steady level taken as the median of
    RMS_j over the second half of the record (robust to a few impulsive revolutions), the
    steady part starts at the first revolution i with |RMS_j − median| ≤ rtol·median for
    j = i and all later j.

    Raises ("never settles") when that start lies in the second half of the record: the
    second half is the steady reference, and a level still leaving the band there means
    the record is not steady (or rtol is too tight for the noise).

    With *window* > 1, RMS_j is taken over revolutions j .. j + window - 1: a slower shaft's turn
    modulates the mesh, so a steady reducer's level swings from one input turn to the next (±10 %
    on a 39/109 box) and holds only over that shaft's turn (at most a quarter of the record).
    """
    r = _check_revolutions(revolutions)
    rtol = check_positive(rtol, "rtol")
    rms = np.sqrt(np.mean(r**2, axis=1))
    window = max(1, min(int(window), r.shape[0] // 4))
    if window > 1:
        rms = np.sqrt(np.convolve(rms**2, np.ones(window) / window, mode="valid"))
    over = f" over {window} revolutions (the slowest shaft's turn)" if window > 1 else ""
    half = rms.size // 2
    level = float(np.median(rms[half:]))
    if level == 0.0:
        raise GearlabInputError("signal is zero throughout the second half of the record; nothing to judge")
    start = _first_of_last_run(np.abs(rms - level) <= rtol * level)
    if start > half:
        j = start - 1
        raise GearlabInputError(
            f"signal never settles: revolution {j} of {r.shape[0]} has RMS {rms[j]:.4g}{over}, outside "
            f"{level:.4g} ± {100 * rtol:g} % (median RMS of the second half); expected a steady second half "
            "(record longer, or raise rtol for impulsive noise)"
        )
    return start


# --- the whole cut ----------------------------------------------------------------------


@dataclass(frozen=True)
class CutRevolutions:
    """Steady revolutions of one record.

    revolutions: (R, points) float64, the steady complete revolutions in the angle domain;
    first_steady: index of revolutions[0] among all complete revolutions of the record;
    complete: number of complete revolutions in the record (transient included);
    speed_hz: mean input-shaft speed over the record.
    """

    revolutions: np.ndarray
    first_steady: int
    complete: int
    speed_hz: float


def cut_revolutions(
    signal: np.ndarray,
    fs: float,
    *,
    tacho: np.ndarray | None = None,
    pulses: np.ndarray | None = None,
    speed_hz: float | None = None,
    phase: float = 0.0,
    points: int = POINTS,
    offset: float = 0.0,
    transient: str = "periodic",
    rtol: float | None = None,
) -> CutRevolutions:
    """Thesis steps 2–4 (section 3.2) for one record: angle, revolutions, transient dropped.

    The shaft angle comes from exactly one of *tacho* (wrapped angle, rad; the simulator),
    *pulses* (once-per-revolution pulse train; measured) or *speed_hz* (nominal constant
    speed, with the angle *phase* at the first sample). All complete revolutions are
    resampled (:func:`resample_revolutions`), then the start-up transient is detected with
    *transient* = "periodic" (:func:`steady_start`, rtol default 1e-3, simulations),
    "stats" (:func:`steady_start_stats`, rtol default 0.05, measured data) or "none".
    """
    x = check_signal(signal, "signal")
    fs = check_positive(fs, "sampling rate fs", "Hz")
    given = [name for name, v in (("tacho", tacho), ("pulses", pulses), ("speed_hz", speed_hz)) if v is not None]
    if len(given) != 1:
        raise GearlabInputError(
            f"give exactly one of tacho, pulses or speed_hz to know the shaft angle, got {', '.join(given) or 'none'}"
        )
    if transient not in TRANSIENT_METHODS:
        raise GearlabInputError(f"unknown transient detection '{transient}'; known: {', '.join(TRANSIENT_METHODS)}")
    if speed_hz is not None:
        angle = angle_from_speed(x.size, fs, speed_hz, phase)
    else:
        source = check_signal(tacho if tacho is not None else pulses, given[0])
        if source.size != x.size:
            raise GearlabInputError(
                f"signal has {x.size} samples but {given[0]} has {source.size}; expected one per sample"
            )
        angle = unwrap_tacho(source) if tacho is not None else angle_from_pulses(source, fs)
    a = _check_angle(angle)
    mean_speed = _turns(a) * fs / (a.size - 1)
    per_rev = fs / mean_speed
    if x.size < per_rev:
        raise GearlabInputError(
            f"signal has {x.size} samples, fewer than one revolution ({per_rev:.0f} at "
            f"{fmt_hz(mean_speed)} and {fmt_hz(fs)})"
        )

    revs = resample_revolutions(x, a, points=points, offset=offset)
    if transient == "periodic":
        start = steady_start(revs, 1e-3 if rtol is None else rtol)
    elif transient == "stats":
        start = steady_start_stats(revs, 0.05 if rtol is None else rtol)
    else:
        start = 0
    return CutRevolutions(revs[start:], start, revs.shape[0], mean_speed)
