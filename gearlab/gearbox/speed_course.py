"""The speed's course through a record without a tacho, from the record's own spectra over time (a speed change
is a shift on a log-frequency axis): speed_course (a smooth course about the mean, for a steady record's swing or
a ramp) and speed_shift (the ratio between a record's ends: a run-up or coast-down). Used by gearbox.speed's
follow_speed and by `gearlab inspect`."""

from __future__ import annotations

import math

import numpy as np

from ..memo import ArraysOf

FLOOR_BINS = 201  # width of the running median (bins)


COURSE_PARTS = 8  # the record's spectra over time: half-overlapping windows, an eighth of it each
# a step's course is read over windows of a 128th of the record (62 ms of 8 s: a turn at 17.5 Hz), 512 samples at
# least: beside a 6 % step of 0.2 s the course lay 0.2-0.3 % off at most (a 64th: 0.6-0.8 %, an eighth: 3.2 %, and
# the mesh band, ±0.43 orders, lost the line there); a ramp keeps the eighths, whose lines stand over its smear
STEP_PARTS = 128
STEP_WINDOW = 512
CROSS_ROWS = 4  # window_ratios correlates this many windows at a time (its memory, not its result)
COURSE_SPAN = 0.04  # the speed's course is looked for within ±4 % of its mean, or as far as speed_shift reads
COURSE_STEP = 1e-4  # the log-frequency axis's step: 0.01 % of speed
COURSE_MIN = 2e-3  # a course that moves less than 0.2 % is no course (a steady record's windows scatter)
# a course whose windows lie further than this share of its span off the quadratic is a step, not a ramp (windows off
# by 0.39-0.47 of a 1-6 % step's span; by 0.02-0.03 of a 30 % linear run-up's or coast-down's, whose lines smear)
STEP_MISFIT = 0.1


def lifted_rows(signal: np.ndarray, fs: float, starts, size: int, step: float, wide: float):
    """(log-frequency axis, rows): each window of *size* samples from *starts*, its spectrum's lines over the
    running median (log, clipped at 0) on a log-frequency axis of *step* (where a speed change is a shift),
    less its mean; None where the band read (20 bins up to 0.45 fs) spans under *wide* x."""
    from scipy import ndimage

    nfft = 1 << int(math.ceil(math.log2(2 * size)))
    freq = np.fft.rfftfreq(nfft, 1 / fs)
    low, high = max(20 * fs / size, 1.0), 0.45 * fs
    if high <= low * wide:
        return None
    axis = np.exp(np.arange(math.log(low), math.log(high), step))
    window = np.hanning(size)
    # np.interp(axis, freq, lifted) of every window on one search: each axis point's bin j (freq[j] <= x < freq[j + 1],
    # x inside the band) and x - freq[j], then np.interp's own slope (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]) times
    # it plus fp[j], each rounded alone: the same floats for finite rows (a step's 255 windows: its searches were a
    # quarter of lifted_rows' CPU, and the rows' list copied once more)
    j = np.searchsorted(freq, axis, side="right") - 1
    into, pitch = axis - freq[j], np.diff(freq)
    amps = np.abs(np.fft.rfft(signal[np.add.outer(np.asarray(starts), np.arange(size))] * window, nfft))
    rows = np.empty((len(amps), axis.size))
    for amp, row in zip(amps, rows):
        floor = ndimage.median_filter(amp, size=min(FLOOR_BINS, amp.size | 1), mode="nearest")
        lifted = np.clip(np.log(np.maximum(amp, 1e-300) / np.maximum(floor, 1e-300)), 0.0, None)
        np.multiply((np.diff(lifted) / pitch)[j], into, out=row)
        row += lifted[j]
    rows -= rows.mean(axis=1, keepdims=True)
    return axis, rows


def speed_course(signal: np.ndarray, fs: float) -> np.ndarray | None:
    """The speed per sample over its mean (a smooth course, mean 1) of a record without a tacho, from its own
    spectra: each window's spectrum (lines over the running median, on a log-frequency axis, where a speed
    change is a shift) correlated with the middle window's, every line of every stage at once, up to the shift
    the record's ends show (speed_shift; COURSE_SPAN at least); a quadratic through the windows' ratios; None
    where it moves less than COURSE_MIN. A 2 % ramp read as 0.44 % where
    the mesh harmonic's band was narrower than its sweep. Read once per record and rate (COURSES), shared
    read-only."""

    def made() -> tuple:
        course = _speed_course(signal, fs)
        return () if course is None else (course,)

    hit = COURSES.of(signal, float(fs), made)
    return hit[0] if hit else None


# The speed courses last read, by record (its digest, shape and type) and rate: follow_speed reads one to
# look at the record and again where the description's speed was no prior, inspect along it and for its
# count check, on the same record (inspect's and the joint-mesh tests: 59 reads of 23 records, 4.6 of
# their 31 s of CPU); a read is 17 windows' spectra, running medians and correlations.
COURSES = ArraysOf(16)


def _speed_course(signal: np.ndarray, fs: float) -> np.ndarray | None:
    """speed_course of *signal*, read afresh."""
    from scipy import ndimage

    n = signal.size
    # the course is looked for as far as the record's ends show its speed move (speed_shift), the whole shift each
    # way from the middle window (twice what a steady ramp needs): a ±4 % reach read a 14 -> 19 Hz run-up as
    # 0.94 .. 1.07 of its mean (0.85 .. 1.15 true), its mesh lines stayed smeared and the 1x shaft line was read as
    # the mesh (0.506 Hz); a steady record's ends show no shift, its reach stays COURSE_SPAN
    moved = speed_shift(signal, fs)
    reach = max(math.log(1 + COURSE_SPAN), abs(math.log(moved or 1.0)))
    if (read := window_ratios(signal, fs, COURSE_PARTS, reach)) is None:
        return None
    centre, ratio = read
    t = np.arange(n) / fs
    course = np.polyval(np.polyfit(centre, ratio, 2), t)
    if np.max(np.abs(np.interp(centre, t, course) - ratio)) > max(COURSE_MIN, STEP_MISFIT * float(np.ptp(ratio))):
        # not a quadratic: a step between two plateaus (a 6 % step, 98/113 + 112/135: its mesh band, half-way to
        # the next mesh's 0.87 orders away, held neither plateau about the quadratic, the mean read 2.2 % low);
        # read again over STEP_PARTS windows (those of an eighth, joined, put the plateaus' ends up to 3.5 % off
        # over a second beside a 6 % step), one window's outlier taken out (a running median of 3 keeps a step's
        # edge); the windows' ratios joined, each end segment's slope carried on to the record's end (a run-up's
        # ramp goes on there, a step's plateau stays flat)
        # reaching the coarse course's whole span further: the middle short window may lie on either plateau (a -5 %
        # step read from its start was clipped at the ±4 % reach, its far plateau garbage)
        wider = reach + math.log(float(np.max(ratio) / np.min(ratio)))
        if (fine := window_ratios(signal, fs, min(STEP_PARTS, n // STEP_WINDOW), wider)) is not None:
            sharp = ndimage.median_filter(fine[1], size=3, mode="nearest")
            at = np.interp(centre, fine[0], sharp)
            # the short windows sharpen the course, never leave it by more than its span: on a slow take they hold
            # a few mesh periods (8 -> 16 Hz, 32 teeth: 25 ms, 6 periods at the start) and read a wrapped lag there,
            # 50-100 % off; beside a 6 % step they differ from the eighths by 3.5 % at most
            if np.max(np.abs(at / at.mean() - ratio / ratio.mean())) <= np.ptp(ratio) / ratio.mean():
                centre, ratio = fine[0], sharp
        slope = np.diff(ratio)[[0, -1]] / np.diff(centre)[[0, -1]]
        ends = np.where(
            t < centre[0], slope[0] * (t - centre[0]), np.where(t > centre[-1], slope[1] * (t - centre[-1]), 0)
        )
        course = np.interp(t, centre, ratio) + ends
    course /= course.mean()
    return course if float(np.ptp(course)) >= COURSE_MIN else None


def window_ratios(signal: np.ndarray, fs: float, parts: int, reach: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(window centres in s, speed over the middle window's) of 2 *parts* - 1 half-overlapping windows, a *parts*-th
    of the record each: each window's lifted spectrum (lifted_rows) correlated with the middle one's, every line of
    every stage at once, up to a ratio of exp(±*reach*); None where the windows are too short to read."""
    n = signal.size
    size = n // parts
    if size < 256:
        return None
    windows = 2 * parts - 1
    starts = np.linspace(0, n - size, windows).astype(int)
    if (lifted := lifted_rows(signal, fs, starts, size, COURSE_STEP, 1.5)) is None:
        return None
    axis, rows = lifted
    lag_reach = int(reach / COURSE_STEP)
    # zero-padded to N + reach, not 2 N: a lag up to the reach wraps onto the padding alone (half the transforms of
    # a step's 255 short windows); to the next fast length there (factors 2, 3, 5), not the next power of 2, which
    # was up to twice as long: a step's 35,836 points and reach 1,330: 37,500, not 65,536, 0.20 -> 0.12 s of FFTs
    from scipy.fft import next_fast_len

    m = next_fast_len(axis.size + lag_reach + 1, real=True)
    middle = np.conj(np.fft.rfft(rows[windows // 2], m))
    lags = np.empty((windows, 2 * lag_reach + 1))  # lag -reach .. reach
    # CROSS_ROWS windows at a time: all 255 of a step's at once make three temporaries of 77-134 MB, each page-faulted
    # afresh (sys time); each row's transforms are its own, so the lags are the same to the bit
    for a in range(0, windows, CROSS_ROWS):
        spec = np.fft.rfft(rows[a : a + CROSS_ROWS], m)
        spec *= middle
        cross = np.fft.irfft(spec, m)
        lags[a : a + CROSS_ROWS, :lag_reach] = cross[:, -lag_reach:]
        lags[a : a + CROSS_ROWS, lag_reach:] = cross[:, : lag_reach + 1]
    k = np.clip(np.argmax(lags, axis=1), 1, 2 * lag_reach - 1)
    l, c, r = (lags[np.arange(k.size), k + d] for d in (-1, 0, 1))
    denom = l - 2 * c + r
    shift = k - lag_reach + np.where(denom < 0, 0.5 * (l - r) / np.where(denom < 0, denom, -1), 0.0)
    return (starts + size / 2) / fs, np.exp(shift * COURSE_STEP)


SHIFT_SPAN = 1.0  # speed_shift looks for a ratio of speeds up to 2 (a run-up from 20 to 35 Hz: 1.62 between its ends)
SHIFT_STEP = 1e-3  # its log-frequency axis's step: 0.1 % of speed
SHIFT_MIN = 0.05  # a shift under 5 % is a steady record's (a motor's slip, a drive's swing: speed_course reads those)
# the windows compared, a sixteenth of the record each: over an eighth a 20 -> 35 Hz ramp smears a 73-tooth mesh's
# lines over 137 Hz, under the running median (a mesh and its 2nd harmonic alone read 0.95; over a sixteenth 1.69)
SHIFT_PARTS = 16


def speed_shift(signal: np.ndarray, fs: float) -> float | None:
    """The speed at the record's last sixteenth over its first's (a run-up: > 1, a coast-down: < 1), from the two
    windows' spectra (lines over the running median on a log-frequency axis, where a speed change is a shift,
    every line of every stage at once, as speed_course reads a smaller one); None within SHIFT_MIN of 1. An
    outside lab's 31/73 run-up from 20 to 35 Hz without its tacho: 'no line within ±1 % of a mesh frequency
    (the lines fit 0.3794 Hz (27.39 Hz as 1×M1))', nothing said of its speed's course; read 1.687 (1.687 true)."""
    size = signal.size // SHIFT_PARTS
    if size < 256 or (lifted := lifted_rows(signal, fs, [0, signal.size - size], size, SHIFT_STEP, 4.0)) is None:
        return None
    axis, rows = lifted
    reach = int(math.log(1 + SHIFT_SPAN) / SHIFT_STEP)
    m = 1 << int(math.ceil(math.log2(2 * axis.size)))
    cross = np.fft.irfft(np.fft.rfft(rows[1], m) * np.conj(np.fft.rfft(rows[0], m)), m)
    lags = np.concatenate([cross[-reach:], cross[: reach + 1]])  # lag -reach .. reach
    ratio = math.exp((int(np.argmax(lags)) - reach) * SHIFT_STEP)
    return ratio if abs(ratio - 1) > SHIFT_MIN else None
