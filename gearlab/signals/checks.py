"""Input checks shared by the signal pipeline: one clear line for every bad input.

Every function of :mod:`gearlab.signals` validates what it is given before it computes,
so that a NaN from an unstable simulation or a wrong column in an imported file is named
where it enters (which array, which sample) rather than surfacing later as a strange
accuracy figure.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import GearlabInputError


def as_real_array(x, name: str) -> np.ndarray:
    """*x* as a float64 array; booleans and integers are accepted (digital tacho channels)."""
    arr = np.asarray(x)
    if arr.dtype.kind not in "biuf":
        raise GearlabInputError(f"{name} must hold real numbers, got an array of dtype {arr.dtype}")
    return arr.astype(np.float64, copy=False)


def check_finite(arr: np.ndarray, name: str) -> None:
    """Raise naming the first NaN or inf of *arr* (position as sample, or row and sample)."""
    finite = np.isfinite(arr)
    if finite.all():
        return
    flat = np.flatnonzero(~finite.ravel())
    first = int(flat[0])
    value = arr.ravel()[first]
    what = "NaN" if np.isnan(value) else ("inf" if value > 0 else "-inf")
    if arr.ndim <= 1:
        where = f"sample {first}"
    else:
        *lead, sample = np.unravel_index(first, arr.shape)
        where = f"row {', '.join(str(int(i)) for i in lead)}, sample {int(sample)}"
    more = f" ({flat.size} non-finite values in all)" if flat.size > 1 else ""
    raise GearlabInputError(f"{name} contains {what} at {where}{more}; expected finite numbers")


def check_signal(x, name: str = "signal") -> np.ndarray:
    """A 1-D, non-empty, finite real array as float64 — or GearlabInputError saying what is wrong.

    Used for every time series that enters the pipeline: the vibration signal, the tacho,
    a pulse train, a continuous angle.
    """
    arr = as_real_array(x, name)
    if arr.ndim != 1:
        raise GearlabInputError(f"{name} must be 1-D (one channel over time), got an array of shape {arr.shape}")
    if arr.size == 0:
        raise GearlabInputError(f"{name} is empty; expected at least one sample")
    check_finite(arr, name)
    return arr


def check_array(x, name: str, min_ndim: int = 1, finite: bool = True) -> np.ndarray:
    """A finite real float64 array of at least *min_ndim* dimensions and no empty axis. *finite*=False
    leaves the values unread: for a caller that learns they are finite from a sum it computes anyway
    (a non-finite sum: check_finite names the value)."""
    arr = as_real_array(x, name)
    if arr.ndim < min_ndim:
        raise GearlabInputError(f"{name} must have at least {min_ndim} dimension(s), got an array of shape {arr.shape}")
    if arr.size == 0:
        raise GearlabInputError(f"{name} is empty (shape {arr.shape}); expected at least one value")
    if finite:
        check_finite(arr, name)
    return arr


def check_positive(value, name: str, unit: str = "") -> float:
    """A finite real number > 0 as float."""
    v = check_real(value, name)
    if v <= 0:
        raise GearlabInputError(f"{name} must be positive, got {v:g}{(' ' + unit) if unit else ''}")
    return v


def check_real(value, name: str) -> float:
    """A finite real number (Python or numpy scalar, not bool) as float."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise GearlabInputError(f"{name} must be a real number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise GearlabInputError(f"{name} must be finite, got {v}")
    return v


def check_int(value, name: str, minimum: int) -> int:
    """An integer (Python or numpy, not bool) >= *minimum*."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise GearlabInputError(f"{name} must be an integer, got {value!r}")
    v = int(value)
    if v < minimum:
        raise GearlabInputError(f"{name} must be at least {minimum}, got {v}")
    return v


def fmt_hz(f: float) -> str:
    """A frequency for people: '25.2 Hz', '200 kHz'."""
    return f"{f / 1e3:.4g} kHz" if abs(f) >= 1e3 else f"{f:.4g} Hz"


# A record whose speed spans more than this share of its mean (its revolutions' speeds, each over a few turns) is no
# steady record: a run-up or a coast-down, which gearlab order-tracks but groups and scores at its mean speed alone
SPEED_VARIES = 0.05
VARIES_WORDS = "over the take:"  # before speed_shape's words: what marks a take whose speed varies
# after them, what a run once did with such a take (varies_span leaves it out)
_MEAN_WORDS = ": its mean speed is its condition (steady records compare)"

# A speed track whose net change (between the means of its first and last of SHAPE_STRETCHES stretches) is at least
# MONOTONE of the way it travels (the stretches' changes summed) is a run-up or coast-down; one that wanders and
# returns, a drift (a motor's slow ±3 % was said 'a run-up or coast-down?'). A linear ramp reads ~1, a take that
# runs up first and then holds ~1, a drift of 1.5 slow cycles 0.0-0.4 (0.33 where it starts at a peak).
SHAPE_STRETCHES = 12
MONOTONE = 2 / 3


def speed_shape(speeds, stops: bool = False) -> str:
    """What a take's *speeds* (Hz, each revolution's or each few's, in turn order) whose span is no steady take's
    do: 'a run-up', 'a coast-down' (a monotone change of speed over the take), or 'a drift of ±3.0 %' (half their
    span over their mean: the speed wanders and returns); where the shaft *stops* a while (stopped), that wander is
    'a stop and a restart'."""
    s = np.asarray(speeds, dtype=float)
    means = np.array([part.mean() for part in np.array_split(s, max(2, min(SHAPE_STRETCHES, s.size // 5)))])
    net, way = float(means[-1] - means[0]), float(np.sum(np.abs(np.diff(means))))
    if way > 0 and abs(net) >= MONOTONE * way:
        return "a run-up" if net > 0 else "a coast-down"
    return "a stop and a restart" if stops else f"a drift of ±{50 * (s.max() - s.min()) / s.mean():.1f} %"


def varies_span(how: str) -> str:
    """A varying take's speeds and shape in words from its speed source *how* ('20.16 Hz .. 34.94 Hz over the take:
    a run-up'), without what a run once did with it (its mean speed its condition)."""
    return how.split("; ")[-1].split(_MEAN_WORDS)[0]


# said of a record without a tacho whose spectra show its speed vary, its angle not (gearbox.speed.varies_words)
UNSEEN_WORDS = "read whole at one speed: no tacho shows its speed revolution by revolution"


def turn_times(angle: np.ndarray, fs: float) -> np.ndarray:
    """The time (s) the shaft *angle* (radians, one a sample at *fs*) passes each whole turn 2πk within it, from the
    first complete revolution's start (signals.first_complete): revolution r of a cut record lasts at[r + 1] - at[r]."""
    turns = np.arange(math.ceil(angle[0] / (2 * math.pi)), math.floor(angle[-1] / (2 * math.pi)) + 1)
    return np.interp(2 * math.pi * turns, angle, np.arange(angle.size) / fs)


def revolution_speeds(angle: np.ndarray, fs: float) -> np.ndarray:
    """Each complete revolution's mean speed (Hz) of the shaft *angle*, in the order cut_revolutions cuts them."""
    return 1.0 / np.diff(turn_times(angle, fs))


def settled(angle: np.ndarray, fs: float, ends: float, need: int = 0) -> slice:
    """The complete revolutions of *angle* (as turn_times counts them) lying *ends* seconds or more from either end of
    the record (an angle followed without a tacho has not settled there: gearbox.speed.settling); all of them where
    that would leave fewer than half, or fewer than *need* (the which-gear check's least: a take long enough for it
    whole is read whole, its ends in, rather than refused as too short once they are out)."""
    at = turn_times(angle, fs)
    keep = np.flatnonzero((at[:-1] >= ends) & (at[1:] <= (angle.size - 1) / fs - ends))
    cut = 2 * keep.size >= at.size - 1 > 0 and keep.size >= need
    return slice(int(keep[0]), int(keep[-1]) + 1) if cut else slice(0, max(at.size - 1, 0))


def speed_varies(angle: np.ndarray, fs: float, smooth: int = 5) -> str:
    """ "; 20.08 Hz .. 34.93 Hz over the take: a run-up: ..." where the shaft *angle* (radians, one a sample at
    *fs*) turns at speeds, each the mean over *smooth* turns, spanning more than SPEED_VARIES of their mean (their
    shape: speed_shape); else "". An outside lab's run-up from 20 to 35 Hz was said only '27.499 Hz, from tacho
    ...', then 'condition 27.5 Hz has no history'."""
    at = turn_times(angle, fs)
    if at.size < 2 * smooth + 1:
        return ""
    speeds = smooth / (at[smooth:] - at[:-smooth])
    low, high = float(speeds.min()), float(speeds.max())
    if high - low <= SPEED_VARIES * float(np.mean(speeds)):
        return ""
    stop = stopped(np.diff(at), at[0])
    shape = speed_shape(speeds, bool(stop))
    stop = f" ({stop})" if stop else ""
    return f"; {fmt_hz(low)} .. {fmt_hz(high)}{stop} {VARIES_WORDS} {shape}{_MEAN_WORDS}"


# A turn lasting STOPPED times the take's median turn or more: the shaft stood still in it (a tacho's marks cannot
# tell a standstill from a slow turn; a 1.0 s stop of a 24 Hz box read '3.04 .. 24 Hz: a run-up or coast-down?')
STOPPED = 10.0


def stopped(turns: np.ndarray, start: float = 0.0) -> str:
    """'a turn of 1.27 s from 1.95 s: stopped?' for the longest of the *turns* (s each, the first from *start*)
    where it lasts STOPPED times their median or more; else ""."""
    turns = np.asarray(turns, dtype=float)
    if turns.size < 3:
        return ""
    longest = int(np.argmax(turns))
    if turns[longest] < STOPPED * float(np.median(turns)):
        return ""
    return f"a turn of {turns[longest]:.3g} s from {start + float(np.sum(turns[:longest])):.3g} s: stopped?"


# A take whose synchronous average correlates below -POLARITY with its history's is that average reversed: a sensor
# wired or mounted the other way round. Its mesh lines are the history's, so FM4 and NA4 see no change, while the
# matched filter and the likelihood ratio, which read the sign, called 1 of 3 record30 units of a user's healthy 41/109
# take with its leads swapped, with nothing said. Aligned by a tacho's marks the correlation is read at the marks';
# without a tacho, aligned by correlation (parts.measured.aligned: its largest, which a reversed take's mesh lines
# reach half a pitch off), at the turn of the largest |correlation|: a reversed take's stands there, negative.
POLARITY = 0.5


def polarity_line(revs: np.ndarray, reference: np.ndarray, any_turn: bool = False) -> str:
    """In words, a take's revolutions *revs* (R, points) whose mean is the history's *reference* revolution
    reversed (correlation under -POLARITY); "" otherwise. *any_turn*: no tacho fixes the turn: the correlation is
    the largest in size over every turn of the mean, with its sign."""
    mean = np.asarray(revs).mean(axis=0)
    if any_turn:
        a, b = mean - mean.mean(), reference - reference.mean()
        norm = float(np.linalg.norm(a) * np.linalg.norm(b))
        corr = np.fft.irfft(np.conj(np.fft.rfft(b)) * np.fft.rfft(a), n=a.size) / norm if norm > 0 else np.zeros(1)
        r = float(corr[np.argmax(np.abs(corr))])
    else:
        r = float(np.corrcoef(mean, reference)[0, 1])
    if not r < -POLARITY:
        return ""
    how = "" if not any_turn else ", at the turn they correlate most in size (no tacho)"
    return (
        f"polarity reversed against its history's (their synchronous averages correlate {r:.2f}{how}): a sensor wired "
        "or mounted the other way round? the matched filter and the likelihood ratio read the reversal as a change"
    )


# A take aligned by its tacho's marks whose synchronous average correlates with its history's OFF_MARK more at another
# turn than at the marks' (and POLARITY there at least) is read off its marks: a box running the other way, its tacho
# triggering on each mark's other edge (a 16/37 + 28/71 box's healthy take in reverse: 0.71 at the mark, 1.00 at
# 0.244 turn), or a mark moved. Read there, the matched filter (+0.28 over its threshold) and the likelihood
# ratio (+116) called the healthy take a fault, no gear localised, with nothing said; a forward take, chipped or not,
# stands within 0.003 of its best turn at the mark
OFF_MARK = 0.1


def off_mark_line(revs: np.ndarray, reference: np.ndarray) -> str:
    """In words, a take's revolutions *revs* (R, points; turned to the history's at its tacho's marks) whose mean
    matches the history's *reference* revolution far better at another turn (OFF_MARK); "" otherwise."""
    a, b = (v - v.mean() for v in (np.asarray(revs).mean(axis=0), np.asarray(reference)))
    norm = float(np.linalg.norm(a) * np.linalg.norm(b))
    if not norm > 0:
        return ""
    corr = np.fft.irfft(np.conj(np.fft.rfft(b)) * np.fft.rfft(a), n=a.size) / norm
    best = int(np.argmax(corr))
    if corr[best] < POLARITY or corr[best] - corr[0] <= OFF_MARK:
        return ""
    turn = (best / a.size + 0.5) % 1.0 - 0.5  # of a turn, either way
    return (
        f"its synchronous average matches its history's {turn:+.3f} turn ({360 * turn:+.0f} deg) off its tacho's mark "
        f"(correlation {corr[best]:.2f} there, {corr[0]:.2f} at the mark): the box running the other way (its tacho "
        "triggering on each mark's other edge), or a mark moved? the matched filter and the likelihood ratio read the "
        "turn as a change; a history of the box running so compares like with like"
    )


def turned_line(revs: np.ndarray, reference: np.ndarray, any_turn: bool = False) -> str:
    """What a take's revolutions *revs* say against its history's *reference* revolution: polarity_line's words, else
    (aligned by its tacho's marks: not *any_turn*) off_mark_line's; "" for neither."""
    return polarity_line(revs, reference, any_turn) or ("" if any_turn else off_mark_line(revs, reference))


def read_off_mark(revs: np.ndarray, reference: np.ndarray, any_turn: bool = False) -> bool:
    """Whether turned_line's words for a take are off_mark_line's (read off its tacho's marks, not reversed: the box
    running the other way?): its tooth is counted as its history counts it, mirrored (detection_which_gear's
    turned_tooth), in a detection run's which-gear table as in `gearlab score`."""
    return not any_turn and bool(off_mark_line(revs, reference)) and not polarity_line(revs, reference)


# A take whose shaft reverses: a pulse tacho counts turns either way, and read so the revolutions after the reversal
# are those before run backwards, off the mark by the pulse's width (the other edge triggers). Found where the
# revolutions after a take's slowest turn (through which it stops and turns back) match those before better, by
# OFF_MARK, at another turn or mirrored than at the mark (and POLARITY there at least): a 16/37 + 28/71 box 1.5 s
# forward, stopped, 2 s backward reads 0.77 at the mark and 1.00 mirrored; the same stop forward 0.995 at the mark.
# Each side needs REVERSAL_TURNS turns. A mark's edges close together (a narrow pulse) tell a symmetric mesh's
# reversal less.
REVERSAL_TURNS = 5


def reversal(revs: np.ndarray, at: np.ndarray) -> tuple[int, float, float] | None:
    """(k, t0, t1) of a take whose shaft reverses: *revs* (R, points), its consecutive revolutions cut at its tacho's
    marks, *at* their R + 1 turn times (s, turn_times); revolution k - 1, from t0 to t1 s, holds the reversal,
    revolutions k on turn the other way. None where the take shows none."""
    at = np.asarray(at, dtype=float)
    if len(revs) < 2 * REVERSAL_TURNS + 1 or at.size != len(revs) + 1:
        return None
    slow = int(np.argmax(np.diff(at)))
    if min(slow, len(revs) - slow - 1) < REVERSAL_TURNS:
        return None
    b, a = (v - v.mean() for v in (np.asarray(revs[:slow]).mean(axis=0), np.asarray(revs[slow + 1 :]).mean(axis=0)))
    norm = float(np.linalg.norm(a) * np.linalg.norm(b))
    if not norm > 0:
        return None
    ref = np.conj(np.fft.rfft(b))
    shifted, mirrored = (np.fft.irfft(ref * np.fft.rfft(x), n=a.size) / norm for x in (a, a[::-1].copy()))
    best = max(float(shifted.max()), float(mirrored.max()))
    if best < POLARITY or best - float(shifted[0]) <= OFF_MARK:
        return None
    return slow + 1, float(at[slow]), float(at[slow + 1])


def reversal_words(found: tuple[int, float, float]) -> str:
    """reversal's *found* in words: 'the shaft reverses in its turn of 1.96 .. 3.2 s'."""
    return f"the shaft reverses in its turn of {found[1]:.3g} .. {found[2]:.3g} s"
