"""The continuous input-shaft angle θ(t), from whatever the record offers (thesis 2.4.3).

The thesis cuts revolutions "by observing when the rotational value of the input shaft
passes 0" (p. 2.4.3, Figure 2.25). Everything downstream therefore needs one thing: the
continuous (unwrapped) input-shaft angle θ at every sample, in radians. It can come from

* the simulator's tacho, the wrapped angle in [-π, π)           -> :func:`unwrap_tacho`;
* a measured once-per-revolution pulse (key-phasor) voltage     -> :func:`angle_from_pulses`;
* only a nominal constant speed                                 -> :func:`angle_from_speed`.
"""

from __future__ import annotations

import numpy as np

from ..errors import GearlabInputError
from .checks import check_int, check_positive, check_real, check_signal, fmt_hz

TWO_PI = 2.0 * np.pi

# A first pulse interval under this share of the next ones' median is no turn (angle_from_pulses): a shaft's
# speed moves a few percent over a record, not 10 % in one turn (a record starting inside a pulse, its channel
# rising from 0 V: a first "turn" anywhere from 0 to 1 of the next ones; dropped, a real edge loses one turn)
FIRST_PULSE = 0.9
# A channel of more samples than NO_PULSES in the middle half of its range (a cosine tacho's 1/3, a noisy or ramped
# pulse train's a few %, a vibration's 0.5-0.97) of whose turns, edge to edge, over IRREGULAR_SHARE differ from the one
# before by more than IRREGULAR (a tacho's a few % even in a run-up; a missed pulse two turns) holds no pulses: a
# vibration channel read as the tacho. A share, not the median: a two-stage box's vibration read through the Schmitt
# trigger gave edges at its mesh's cycles, skipping 47-66 % of them, the median change 1 % or 27-62 % as it fell
IRREGULAR = 0.2
IRREGULAR_SHARE = 0.1
NO_PULSES = 0.4


def _pulses_or_not(v: np.ndarray, low: float, high: float, edges: np.ndarray) -> None:
    """Refuses a 'pulse train' *v* (levels *low*, *high*; rising *edges*) that is a vibration (NO_PULSES): read
    through its noise, a 19/62 + 23/87 box's vibration given as its tacho made 66-206 Hz of a 30 Hz shaft, said as
    'a run-up or coast-down?' (its channels swapped)."""
    middle = float(np.mean((v > low) & (v < high)))
    if edges.size < 8 or middle <= NO_PULSES:
        return
    turns = np.diff(edges)
    jumps = float(np.mean(np.abs(np.diff(turns)) > IRREGULAR * np.median(turns)))
    if jumps > IRREGULAR_SHARE:
        raise GearlabInputError(
            f"pulse train: {middle:.0%} of its samples lie between its low and high levels and {jumps:.0%} of its "
            f"turns, edge to edge, differ from the one before by over {IRREGULAR:.0%}: no pulses of a shaft's turn; "
            "a vibration channel? (vibration and tacho swapped?)"
        )


# A pulse train the sampling cannot resolve: its pulses come every FAST samples or fewer with a level a sample long
# (at or over half the rate a train folds down, aliased: a 120-mark wheel at 25 Hz, 3 kHz, sampled at 5 kHz read as
# 2 kHz, 16.7 Hz, unsaid), or they last a sample or less and over UNSEEN of them fall between samples (0.04 ms pulses
# at 5 kHz: four in five unseen, read as 'a 29-1 wheel'). A once-a-turn pulse one sample wide, every one seen, passes.
FAST = 4.0
UNSEEN = 0.25
MARKS_APART = range(1, 9)  # the most pulses one interval of those seen may span, unseen between them


def _unresolved(state: np.ndarray, edges: np.ndarray, fs: float) -> None:
    """Refuses the pulses of a Schmitt-triggered *state* (rising *edges*, samples) that come faster than a sample
    interval resolves (FAST, UNSEEN), in words that say so."""
    bounds = np.flatnonzero(state[1:] != state[:-1]) + 1
    runs, high = np.diff(bounds), state[bounds[:-1]]  # each whole level between two switches, and whether high
    if edges.size < 8 or runs.size < 4 or not high.any() or high.all():
        return
    shortest, d = min(np.median(runs[high]), np.median(runs[~high])), np.diff(edges)
    if np.median(d) <= FAST and shortest <= 1:
        raise GearlabInputError(
            f"pulse train: its pulses come every {np.median(d):.3g} samples ({fmt_hz(fs / np.median(d))}) with a "
            f"level one sample long: pulses at or over half the sampling rate, {fmt_hz(fs / 2)}, read folded down "
            f"(aliased), not as they come; expected over {FAST:g} samples a pulse (fewer marks a turn, a higher rate)"
        )
    # the pulses' own period: the shortest interval's largest whole share that every interval is a whole multiple of
    # (those seen fall every 4 or 5 pulses where the period is 205.76 samples: no interval is one period)
    period = next((d.min() / k for k in MARKS_APART if np.all(np.abs(d * k / d.min() % 1 - 0.5) >= 0.35)), None)
    unseen = 0.0 if period is None else float(np.sum(np.rint(d / period) - 1))
    if np.median(runs[high]) <= 1 and unseen > UNSEEN * (unseen + d.size):
        raise GearlabInputError(
            f"pulse train: its pulses last a sample or less and {unseen / (unseen + d.size):.0%} of them fall "
            f"between samples, unseen: pulses narrower than a sample interval ({1e3 / fs:.3g} ms at {fmt_hz(fs)}); "
            "expected pulses several samples wide (a wider mark, or a higher rate)"
        )


# A sampled square pulse's edge lies anywhere between its last low and its first high sample, and the crossing
# interpolated between those two is mid-way whatever the true time: an error uniform on ±0.5 sample, variance 1/12
# sample² (angle_from_pulses smooths such edge times to it)
QUANTISED_VARIANCE = 1.0 / 12.0
# the most marks a turn, not equally spaced, whose quantised edges are smoothed each mark apart (angle_from_pulses;
# equally spaced ones: as one sequence, of any count). Read raw, 1-10 marks a turn at 25.6-66.7 kHz were 0.5-3.4 mrad
# rms off, smoothed 0.04-0.37; at 3, 4, 6, 8 marks inspect took the mesh's sidebands for a shaft's ('wheel shows 144.4
# teeth, 116 described'). The PHM rig's 10 keep their raw edges: smoothed (each mark apart, 1.0 mrad rms off the raw
# angle), its eccentric-idler take at 40 Hz low outscored the chips (angle_from_pulses)
SMOOTHED_MARKS = 9
# how far (samples) a square edge may lie from equally spaced marks' course (_evenly) and still be read as one of them
# (angle_from_pulses): the quantisation's 0.5 and the fit's slack. Square 10-mark tachos at 15.8-17 Hz (8192 Hz) and
# 60-2 encoders at 33-36 Hz (25.6 kHz) lie 0.44-0.62 off it; the PHM rig's 10 marks 1.2-2.8 (and 4 marks 2-4 % off
# equal spacing 7-10): these keep their marks' own spacing
EVEN_SLACK = 0.75
# Marks a tacho did not give: an interval between edges within MISSED_SLACK of a whole k >= 2 times the median of the
# MISSED_WINDOW intervals about it, and the intervals either side within MISSED_SLACK of theirs, holds k - 1 left-out
# marks, where no other such interval lies within the window
# (a pair of marks spaced 1/3 and 2/3 of a turn alternates, every interval "twice" or "half" the median). A 60-2
# encoder (the gap of 2 left-out marks its turn's reference) read with its 58 marks spaced alike put every order
# 60/58 low: a 37/89 box's mesh read at 36 ('a 36-tooth pinion?'), at 60 marks the gap's turn 3.4 % slow ('slip
# under load'); a once-per-turn tacho that missed one pulse read '16.5 .. 33 Hz, a run-up or coast-down'.
MISSED_SLACK = 0.2
MISSED_WINDOW = 9


def _glitches(edges: np.ndarray, quantised: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """*edges* (and their *quantised* flags) less the pulses a glitch added: an edge whose two intervals are each
    under 1 - MISSED_SLACK of the median of the MISSED_WINDOW intervals about them and together within MISSED_SLACK
    of it, no other such edge within the window. A once-per-turn tacho with a glitch 2 rad into a turn read '32.93 ..
    103.57 Hz (variation 212 %)', 'the mean of a run-up or coast-down', +0.76 % off its speed."""
    from scipy.ndimage import median_filter

    d = np.diff(edges)
    if d.size < MISSED_WINDOW:
        return edges, quantised
    ref = median_filter(d, size=MISSED_WINDOW, mode="nearest")
    short = (d[:-1] < (1 - MISSED_SLACK) * ref[:-1]) & (d[1:] < (1 - MISSED_SLACK) * ref[1:])
    extra = np.flatnonzero(short & (np.abs((d[:-1] + d[1:]) / ref[:-1] - 1) <= MISSED_SLACK)) + 1
    if extra.size == 0 or (extra.size > 1 and np.diff(extra).min() < MISSED_WINDOW):
        return edges, quantised
    return np.delete(edges, extra), np.delete(quantised, extra)


class MarksMiscounted(GearlabInputError):
    """A missing-mark wheel given another count of marks than its own (_missed_marks): the tacho turns, its count
    is wrong."""


def _missed_marks(edges: np.ndarray, quantised: np.ndarray, marks: int) -> tuple[np.ndarray, np.ndarray, int | None]:
    """*edges* (times, samples) with the marks the tacho left out put back, evenly within their interval; their
    *quantised* flags (False: put back, not read); and the shift of the edges' count that starts turns at the
    gap's end where the gaps recur every *marks* edges (a missing-mark wheel's reference), else None. Gaps recurring
    every P != *marks* edges are a P-mark wheel given the wrong count: refused, naming P."""
    from scipy.ndimage import median_filter

    d = np.diff(edges)
    if d.size < MISSED_WINDOW:
        return edges, quantised, None
    # mirrored at the ends: a take starting with the gap held its 3 pitches as the first values' median, the gap kept
    ratio = d / median_filter(d, size=MISSED_WINDOW, mode="mirror")
    k = np.rint(ratio)
    # ... between marks of the steady speed about it: the intervals either side of a stop are its coast-down's and
    # run-up's (a 1.0 s standstill at 24 Hz read as 33 marks left out: 18 turns the shaft never made)
    steady = np.abs(np.concatenate([[1.0], ratio[:-1]]) - 1) <= MISSED_SLACK
    steady &= np.abs(np.concatenate([ratio[1:], [1.0]]) - 1) <= MISSED_SLACK
    gaps = np.flatnonzero((k >= 2) & (np.abs(ratio - k) <= MISSED_SLACK) & steady)
    if gaps.size == 0 or (gaps.size > 1 and np.diff(gaps).min() < MISSED_WINDOW):
        return edges, quantised, None
    put = np.concatenate([edges[g] + d[g] * np.arange(1, k[g]) / k[g] for g in gaps])
    at = np.concatenate([np.full(int(k[g]) - 1, g + 1) for g in gaps])
    filled = np.insert(edges, at, put)
    ends = gaps + 1 + np.cumsum(k[gaps] - 1).astype(int)  # the first edge read after each gap, in *filled*
    if gaps.size < 2 or np.ptp(np.diff(ends)) != 0:
        return filled, np.insert(quantised, at, False), None
    every, left = int(ends[1] - ends[0]), int(k[gaps[0]] - 1)
    if every != marks:
        raise MarksMiscounted(
            f"{left} mark(s) left out every {every - left} (a {every}-{left} wheel, its gap the turn's reference?): "
            f"expected pulses_per_rev = {every}, its marks with the left-out ones ({marks} given)"
        )
    return filled, np.insert(quantised, at, False), int((-ends[0]) % marks)


# Slack for a wrapped tacho that touches both ends of its interval ([-π, π] after rounding).
_WRAP_SLACK = 1e-6


def unwrap_tacho(tacho: np.ndarray) -> np.ndarray:
    """Wrapped shaft angle (rad, in [-π, π)) -> continuous angle θ (rad), np.unwrap semantics.

    Any interval one turn wide is accepted ([-π, π) from the simulator, [0, 2π) from some
    encoders): jumps larger than π between samples are taken as wraps and undone by adding
    multiples of 2π, so θ[0] equals tacho[0] and the zero crossings of the tacho are
    exactly the crossings of θ through 2πk. A tacho spanning more than one turn is not a
    wrapped angle (degrees, or already continuous) and is refused rather than guessed at.
    """
    tacho = check_signal(tacho, "tacho")
    span = float(tacho.max() - tacho.min())
    if span > TWO_PI + _WRAP_SLACK:
        raise GearlabInputError(
            f"tacho spans {span:.4g} (from {tacho.min():.4g} to {tacho.max():.4g}), more than one turn "
            "(2π rad): expected the wrapped shaft angle in radians, e.g. in [-π, π) "
            "(degrees? multiply by π/180; already continuous? use it as the angle directly)"
        )
    return _unwrapped(tacho)


def _unwrapped(p: np.ndarray) -> np.ndarray:
    """np.unwrap(p) (period 2π, discont π), bit for bit on its values, its corrections summed only where they are
    not zero: a wrap every turn of 100-1000 samples, np.unwrap's mod, masks and cumsum over every sample were most
    of a take's tacho screen (validate)."""
    dd = np.diff(p)
    at = np.flatnonzero(np.abs(dd) >= np.pi)  # np.unwrap zeroes the correction where |dd| < discont
    if at.size == 0:
        return p.copy()
    jump = dd[at]
    mod = np.mod(jump + np.pi, TWO_PI) - np.pi  # np.unwrap's own arithmetic on these elements
    np.copyto(mod, np.pi, where=(mod == -np.pi) & (jump > 0))
    steps = np.concatenate([[0.0], np.cumsum(mod - jump)])  # sequential sums, as np.unwrap's cumsum over zeros
    counts = np.diff(np.concatenate([[0], at, [dd.size]]))
    up = p.copy()
    up[1:] = p[1:] + np.repeat(steps, counts)
    return up


def angle_from_speed(n: int, fs: float, speed_hz: float, phase: float = 0.0) -> np.ndarray:
    """Constant-speed angle θ[i] = phase + 2π·f·i/fs for i = 0 … n−1 (rad).

    For measured data with only a nominal speed *speed_hz* (Hz, revolutions per second)
    known; the zero of the angle (where revolutions start) is then arbitrary and set by
    *phase* (rad at the first sample).
    """
    n = check_int(n, "number of samples n", minimum=1)
    fs = check_positive(fs, "sampling rate fs", "Hz")
    speed_hz = check_positive(speed_hz, "shaft speed", "Hz")
    phase = check_real(phase, "phase")
    return phase + TWO_PI * speed_hz * (np.arange(n, dtype=np.float64) / fs)


def _rising_edges(pulses: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pulse train *pulses* as floats, its rising edges (samples, between them; angle_from_pulses) and their
    quantised flags: as read, before a missed pulse is put back or a glitch's left out."""
    v = check_signal(pulses, "pulse train")
    fs = check_positive(fs, "sampling rate fs", "Hz")
    lo, hi = float(v.min()), float(v.max())
    if hi == lo:
        raise GearlabInputError(
            f"pulse train is constant ({lo:g}) and has 0 rising edges; "
            "at least 2 once-per-revolution pulses are needed to measure the speed"
        )
    mid = 0.5 * (lo + hi)
    low_thr, high_thr = lo + 0.25 * (hi - lo), lo + 0.75 * (hi - lo)

    # Schmitt trigger without a loop: known states where the level is unambiguous, carried
    # forward through the hysteresis band (index of the last decided sample).
    decided = (v > high_thr) | (v < low_thr)
    last = np.maximum.accumulate(np.where(decided, np.arange(v.size), -1))
    first_decided = int(np.argmax(decided))  # exists: min < low_thr < high_thr < max
    state = v[np.where(last >= 0, last, first_decided)] > high_thr
    switches = np.flatnonzero(~state[:-1] & state[1:]) + 1  # first "high" sample of each pulse

    # Mid-level upward crossings between samples i and i+1, and the last one before each switch.
    crossings = np.flatnonzero((v[:-1] < mid) & (v[1:] >= mid))
    i = crossings[np.searchsorted(crossings, switches, side="right") - 1]
    edges = i + (mid - v[i]) / (v[i + 1] - v[i])
    quantised = (v[i] < low_thr) & (v[i + 1] > high_thr)  # no sample of the edge in the middle half

    # a first "pulse" much shorter than the next ones is the record's start, not a turn: a pulse already
    # rising (or a channel settling) at sample 0 made an edge there, a 27 % short first revolution
    if edges.size >= 3 and edges[1] - edges[0] < FIRST_PULSE * np.median(np.diff(edges[1:10])):
        edges, quantised = edges[1:], quantised[1:]
    if edges.size < 2:
        raise GearlabInputError(
            f"pulse train has {edges.size} rising edge(s) in {v.size} samples "
            f"({v.size / fs:.4g} s at {fmt_hz(fs)}); at least 2 once-per-revolution pulses are needed "
            "to measure the speed"
        )

    _pulses_or_not(v, low_thr, high_thr, edges)
    _unresolved(state, edges, fs)
    return v, edges, quantised


def angle_from_pulses(pulses: np.ndarray, fs: float, smooth: bool = False, marks: int = 1) -> np.ndarray:
    """Once-per-revolution pulse train (any voltage) -> continuous shaft angle θ per sample (rad).

    Edge detection. The pulse train is thresholded at the mid-level
    v_mid = (min + max)/2. A revolution starts at each rising edge; its sub-sample time is
    where the straight line between the two samples that bracket v_mid reaches it,

        t_j = i + (v_mid − v[i]) / (v[i+1] − v[i])      (in samples).

    Noise on a slow edge can cross v_mid several times; to count each pulse once the
    train is first debounced with a Schmitt trigger (state "high" above 75 % of the range,
    "low" below 25 %, unchanged in between), and each low-to-high switch takes the last
    mid-level crossing before it.

    Angle. The j-th edge (j = 0, 1, …) is at θ = 2πj: the shaft is at angle zero at
    the first pulse (a missing-mark wheel's: at its gap's end; marks left out are put back: _missed_marks),
    and between edges the angle is linear in time (constant speed within one revolution). Samples before the
    first and after the last edge are extrapolated
    with the speed of the neighbouring revolution.

    *smooth*: between edges a cubic spline through them, not a line: for a tacho on a slower shaft than
    the one read (an output shaft's mark once per 14.5 input turns), whose speed swings within a turn
    of its own; a line there put sidebands 27 dB under a three-stage box's first mesh line (0.4 % swing).

    Quantised edges. Where most edges jump from below 25 % to above 75 % of the range in one sample (a square
    TTL tacho sampled at the vibration's rate), the crossing interpolated between those two samples is mid-way
    whatever the true time: each edge time is off by an error uniform on ±0.5 sample (variance 1/12), in a
    pattern that repeats with the fraction of samples per turn. Read through such edges, every line of order k
    is phase-modulated by k times that error, and its sidebands, spaced by the pattern (0.2856 order at 28 Hz and
    25.6 kHz), were read as a shaft's order ("the wheel shows 80.5 teeth, 59 described"). The edge times are
    then a smoothing spline of edge time against edge index whose residual sum of squares is the quantisation's
    own, n/12 (UnivariateSpline, s = n σ²; n step²/12 for a tacho held from 1/step of the rate, _held_step): a
    steady speed or a run-up, smooth over the edges, keep their course and lose the pattern (the angle's error
    1.3-2.6 -> 0.06-0.9 mrad rms, 26-43 Hz at 25.6 kHz, the edges off
    the sample grid); a swing within a few turns (2 % at 0.3 order), which one mark a turn cannot follow between
    edges anyway (14.2 mrad with exact edges), reads within 5 % of the raw edges. Edges with a sample in the
    middle half of the range (a filtered, slow or cosine tacho, the simulator's ramped pulses) keep their
    interpolated times, bit for bit. *marks*: the tacho's marks a turn (pulses_per_rev). Square edges of marks
    equally spaced (each within EVEN_SLACK of _evenly's course, a knot a turn) are smoothed as one sequence, of any
    count: each mark's offset is then known, not read from edges at one fraction of a sample every turn (3, 6 or 9
    marks at a whole 512 or 1024 samples a turn: each mark apart 1.2-3.2 mrad rms, as one sequence 0.001-0.04; at
    507.9, 0.24-0.40 and 0.02-0.32). Else the edges of up to SMOOTHED_MARKS marks a turn are smoothed each mark's own
    sequence apart: marks a few % off equal spacing, as on a real wheel, keep their spacing (4 marks up to 4 % off,
    51.2 kHz: 1.54 mrad raw, 0.07 each mark apart, 1.85 all marks as one sequence). The PHM rig's 10 marks (1.2-2.8
    samples off an even course) keep their interpolated times: smoothed, its eccentric-idler take spur3_40hz_Low_2
    scored tooth_energy 23-27 (raw 11.6-12.6) and tooth_sync 47-58 (raw 13-21) at TSA30, above the chipped takes'
    18-23 and 30-45: their AUC at 40 Hz low load fell 1.00 -> 0.50 (the other takes' scores moved by up to 12 %; why
    that take, not found).
    Smoothed, the synthetic rig records' thresholds let 0-1.7 % through (raw 0-1.6 %), so the limit is the real
    records', not the threshold's.

    *fs* (Hz) is not needed for the angle itself (it is per sample); it is checked and used
    to state speeds in messages.
    """
    v, edges, quantised = _rising_edges(pulses, fs)
    edges, quantised, shift = _missed_marks(*_glitches(edges, quantised), marks)
    # most, not all: a square tacho's edge with a noisy sample mid-way now and then is still a square tacho's. A
    # missing-mark wheel's too (shift found), of any count: a 60-2 encoder's raw edges at 25.6 kHz left the angle
    # 2.2 mrad rms off (0.7 smoothed), and a healthy take read by a once-per-turn tacho (0.6) against its history
    # read by the encoder was 'localised on the input pinion 37T, z = 5.0 (threshold 2.58)'
    smoothed_marks = marks <= SMOOTHED_MARKS or shift is not None
    square = edges.size >= 4 * marks and np.count_nonzero(quantised) > edges.size / 2
    if square and marks > 1 and np.all(np.abs(edges - _evenly(edges, marks))[quantised] <= EVEN_SLACK):
        # every square edge within its quantisation of equally spaced marks: smoothed as one sequence. Each mark's
        # own offset is unknown below a sample where the samples a turn are near whole (512 at 16 Hz, 8192 Hz):
        # its edges fall at the same fraction every turn, an error that repeats with the shaft (2.8 mrad at orders
        # 2, 4, 6 of a 10-mark wheel), which the TSA keeps and a take at 16.1 Hz lacks (0.4 mrad): its input
        # pinion was 'localised' (z 4.3-6.6 against 2.6). (Of 3 marks on test_outside_z's output shaft, a healthy take
        # read z 4.70 over its 3-take history's 4.37 here, 3.23 each mark apart: exact edges read 4.78 over 4.32, its
        # own z. At exact edges 1 of 75 healthy take/history pairs of that box pass, as here; each mark apart, 0.)
        edges = _dequantised(edges, _held_step(v, edges[::marks]))
    elif smoothed_marks and square:
        # each mark's edges apart: marks need not lie equally spaced, their offsets are kept
        smoothed, step = edges.copy(), _held_step(v, edges[::marks])
        for m in range(marks):
            smoothed[m::marks] = _dequantised(edges[m::marks], step)
        edges = smoothed if np.all(np.diff(smoothed) > 0) else edges

    t = np.arange(v.size, dtype=np.float64)
    theta_edges = TWO_PI * (np.arange(edges.size, dtype=np.float64) + (shift or 0))
    theta = np.interp(t, edges, theta_edges)  # linear in time between edges
    if smooth and edges.size >= 4:  # (np.interp's line where fewer edges leave no curve to fit)
        from scipy.interpolate import CubicSpline

        inside = (t >= edges[0]) & (t <= edges[-1])
        theta[inside] = CubicSpline(edges, theta_edges)(t[inside])
    # np.interp holds the end values; extrapolate with the neighbouring revolution's speed.
    before, after = t < edges[0], t > edges[-1]
    theta[before] = theta_edges[0] + TWO_PI * (t[before] - edges[0]) / (edges[1] - edges[0])
    theta[after] = theta_edges[-1] + TWO_PI * (t[after] - edges[-1]) / (edges[-1] - edges[-2])
    return theta


def _held_step(v: np.ndarray, edges: np.ndarray) -> float:
    """The tacho's own sample interval in the vibration's samples (*edges*: one mark's): a whole *step* > 1 where it was
    logged at 1/step of the vibration's rate and held onto it (readers.base.held_to_vibration: every level change
    on a grid of *step* samples) and its edges scatter about their course as that grid's quantisation does; else 1.
    A once-per-turn tacho at 6.4 kHz held onto 25.6 kHz has edges off by up to ±2 samples, not ±0.5: smoothed to
    one sample's quantisation they kept most of it, and inspect read a 2 s take's 113T wheel as '123.9 ± 8.0
    teeth' (at 12.8 kHz, or 4 s, it matched)."""
    changes = np.flatnonzero(v[1:] != v[:-1])
    step = int(np.gcd.reduce(np.diff(changes))) if changes.size >= 4 else 1
    # the grid alone is no proof: whole samples a turn at an exact speed put every edge on one; the second
    # differences of edges each off by a uniform error of variance step²/12 have variance 6 step²/12
    seen = edges.size >= 4 and np.mean(np.diff(edges, 2) ** 2) / 6 >= 0.5 * step**2 * QUANTISED_VARIANCE
    return float(step) if step > 1 and seen else 1.0


def _dequantised(edges: np.ndarray, step: float) -> np.ndarray:
    """Edge times (samples) each off by a uniform ±0.5 *step* (the tacho's own sample interval, _held_step) -> a
    smoothing spline of them against the edge index, residual sum of squares n step²/12 (angle_from_pulses,
    "Quantised edges"). Fitted about the line through the first and last edge, so the spline holds only the
    speed's course (samples), not 10⁵ samples of ramp."""
    from scipy.interpolate import UnivariateSpline

    j = np.arange(edges.size, dtype=np.float64)
    line = edges[0] + (edges[-1] - edges[0]) * j / j[-1]
    course = UnivariateSpline(j, edges - line, k=3, s=edges.size * step**2 * QUANTISED_VARIANCE)
    smoothed = line + course(j)
    return smoothed if np.all(np.diff(smoothed) > 0) else edges  # (np.interp needs them rising)


def _evenly(edges: np.ndarray, marks: int) -> np.ndarray:
    """Edge times (samples) of equally spaced marks: a least-squares cubic spline of edge time against the edge
    index with a knot every turn (every *marks* edges, 4 at the least), about the line through the first and last
    edge. It follows the speed's course from turn to turn but not a pattern within a turn: marks off equal spacing
    stay off it by their offset (angle_from_pulses, EVEN_SLACK)."""
    from scipy.interpolate import LSQUnivariateSpline

    j = np.arange(edges.size, dtype=np.float64)
    line = edges[0] + (edges[-1] - edges[0]) * j / j[-1]
    step = max(marks, 4)
    knots = j[step : edges.size - step : step]
    course = LSQUnivariateSpline(j, edges - line, knots, k=3)
    return line + course(j)


def continued(revs: np.ndarray, shift: float) -> np.ndarray:
    """*revs*, one record's consecutive revolutions, advanced by *shift* samples as one signal,
    x(θ) -> x(θ + 2π shift / points), its last revolution given up. aligned turns each row on itself,
    which is the same for what repeats every input turn but cuts, at every row's turn, what does not:
    a later stage's mesh (a 19/58 + 25/67 fan's M2 = 8.19 read lines at 8.19 + k for every k) and a
    slower shaft's sidebands (its wheel read 50.1 teeth, 58 expected: 'structure differs'). *shift*
    in [0, points). Used by the gap's history and by detection's and score's alignment."""
    if not shift:
        return revs
    n, points = revs.shape
    whole = int(np.floor(shift))
    flat = revs.reshape(-1)
    if shift - whole > 1e-9:  # a fraction of a sample, in the frequency domain (the wrap is in the row given up)
        k = np.fft.rfftfreq(flat.size)
        flat = np.fft.irfft(np.fft.rfft(flat) * np.exp(2j * np.pi * k * (shift - whole)), n=flat.size)
    return flat[whole : whole + (n - 1) * points].reshape(n - 1, points).astype(revs.dtype, copy=False)
