"""A sensor's isolated spikes in a record's revolutions: samples the accelerometer or its ADC saturated
on, bridged before a record is cut into units (the detection kind and `gearlab score`), so that a few
of them do not set a history's thresholds; a change that comes back at one angle of a shaft is the
gearbox's and stays."""

from __future__ import annotations

import math

import numpy as np

from ..errors import GearlabInputError

# A sensor's spike (a sample the accelerometer or ADC saturated on): a point this many robust standard
# deviations (1.4826 MAD) from the record's median, in a record where such points come back fewer
# times than once every SPIKE_TURNS turns of the units' shaft (without_spikes).
SPIKE_Z = 12.0
# ... one sample alone: the samples beside it within this many deviations.
SPIKE_BESIDE = 3.0
SPIKE_TURNS = 4
# ... or a run of at most this many samples flat at one value (a few at the ADC's range: clipped), beside it within.
SPIKE_RUN = 4
# ... and no three of them within the angle this many samples span of the input's or the units'
# shaft's turn (a tooth's, however rare; two by chance: S's history takes 1 and 3, 0.6 and 1.7 samples)
SPIKE_SAME = 1.5


def without_spikes(revs: np.ndarray, fs: float, speed_hz: float, turns_per_input: float = 1.0) -> np.ndarray:
    """A record's consecutive input revolutions *revs* (sampled at *fs* at *speed_hz*) with its
    isolated spikes bridged: each run of points over SPIKE_Z robust deviations from the record's
    median whose samples beside stay within SPIKE_BESIDE (one sample alone), widened by the points
    one sample spans (the cut interpolates a sample over them), is replaced by the record's median
    input turn at those angles (the mesh goes on), offset along the straight line that meets the
    record at the run's ends -- when such runs number fewer than one every SPIKE_TURNS turns of the
    units' shaft (*turns_per_input* turns an input turn) and no three lie within SPIKE_SAME
    samples' angle of one shaft's turn; a change that comes back at one angle of a shaft (a
    tooth's) is left whole. A development box of 105/143 teeth recorded at 16 kHz holds 4 saturated
    samples a take at 25-28 deviations (the rest within 1.6; beside them 0-1.4): in the history they set the
    thresholds (fm4 record30 582 for the chipped take's 104-159; matched_filter 0.318 for
    0.19-0.23), so record30 found 0-33 % of the chip's units at AUC 1.0."""
    x = np.asarray(revs, dtype=np.float64).ravel()
    centre = np.median(x)
    scale = 1.4826 * np.median(np.abs(x - centre))
    if not scale > 0:
        return revs
    over = np.abs(x - centre) > SPIKE_Z * scale
    if not over.any():
        return revs
    edges = np.flatnonzero(np.diff(np.concatenate([[0], over.astype(np.int8), [0]])))
    starts, ends = edges[::2], edges[1::2]  # runs [start, end)
    # a lone sample: the samples either side of its peak stay near the record's level (a mechanical
    # event rings through the sensor's mounting: PHM 2009's idler at 7-14 deviations beside 12-18)
    side = int(math.ceil(revs.shape[-1] * speed_hz / fs + 0.5))
    peaks = np.array([a + np.argmax(np.abs(x[a:b] - centre)) for a, b in zip(starts, ends)])

    def near(at: np.ndarray) -> np.ndarray:
        beside = np.abs(x[np.clip(at, 0, x.size - 1)] - centre)
        return (beside.reshape(2, -1) < SPIKE_BESIDE * scale).all(axis=0)

    # ... or a few samples flat at the ADC's range (clipped: points equal to the peak), beside the run's ends: an
    # int24 WAV's 4 samples at full scale (a knock over its 5 V) were left whole, their peak's neighbour inside the
    # run, and set a 25/52 + 16/81 box's fm4 record10 threshold at 40.4 (3.77 without), a 16T chip's 10.4 uncalled
    flat = np.array([np.count_nonzero(x[a:b] == x[p]) > 1 for a, b, p in zip(starts, ends, peaks)])
    short = (ends - starts) <= (SPIKE_RUN + 1) * side  # k samples and the ramps to them, in points
    lone = near(np.concatenate([peaks - side, peaks + side]))
    lone |= flat & short & near(np.concatenate([starts - side, ends - 1 + side]))
    starts, ends = starts[lone], ends[lone]
    if not len(starts):
        return revs
    if len(starts) * SPIKE_TURNS >= len(revs) * turns_per_input:
        return revs  # it comes back every few turns: the gearbox's, not the sensor's
    span = int(math.ceil(revs.shape[-1] * speed_hz / fs)) + 1  # points one sample spans, and one
    points = revs.shape[-1]
    turns = (starts + ends) / 2 / points  # input turns
    for ratio in {1.0, turns_per_input}:  # three at one angle of the input or the units' shaft: a tooth's
        at = np.sort((turns * ratio) % 1.0)
        ring = np.concatenate([at, at[:2] + 1.0])
        if len(at) > 2 and (ring[2:] - ring[:-2]).min() < SPIKE_SAME * ratio * speed_hz / fs:
            return revs
    typical = np.median(np.asarray(revs, dtype=np.float64), axis=0)  # the input's turn: the mesh goes on
    y = x.copy()
    for a, b in zip(starts, ends):
        a, b = max(a - span, 0), min(b + span, x.size - 1)
        at = np.arange(a, b + 1)
        ends_off = x[[a, b]] - typical[[a % points, b % points]]
        y[at] = typical[at % points] + np.linspace(ends_off[0], ends_off[1], len(at))
    return y.reshape(revs.shape).astype(revs.dtype)


# A channel clipped at its logger's or sensor's range: samples flat at its largest (or smallest) value, at least
# CLIP_SAMPLES of them, some side by side, that value CLIP_Z robust deviations (1.4826 MAD) off the median (a
# quantised sine's peak repeats too, at ~1 deviation; a Gaussian record's largest sample is unique)
CLIP_SAMPLES = 3
CLIP_Z = 3.0
# ... or, nearer the median (a steady mesh tone clipped over 5 % of the take: 1.1 deviations), this many times the
# samples at the next value inward: what lay beyond the range piled at its edge (a quantised tone's peak level holds
# about 2.4 times the next one's, a noisy record's extreme is unique)
CLIP_PILE = 10.0


def clipped(x: np.ndarray) -> list[tuple[int, float]]:
    """[(samples, value)] of each side of *x* flat at its extreme (CLIP_SAMPLES, side by side, CLIP_Z off the
    median); [] for none. An outside lab's int24 WAV with a knock over its 5 V full scale (4 samples) was read
    by inspect without a word (detection bridges such spikes: without_spikes)."""
    x = np.asarray(x, dtype=np.float64)
    centre = float(np.median(x))
    scale = 1.4826 * float(np.median(np.abs(x - centre)))
    out = []
    for value, inward in ((float(x.max()), np.max), (float(x.min()), np.min)):
        at = x == value
        if at.sum() < CLIP_SAMPLES or not np.any(at[1:] & at[:-1]) or at.all():
            continue
        piled = at.sum() >= CLIP_PILE * np.sum(x == inward(x[~at]))
        if abs(value - centre) > CLIP_Z * scale or piled:
            out.append((int(at.sum()), value))
    return out


# A dropout: a run of equal samples (a logger's lost packet or a loose cable, written as zeros or the last value held)
# this long at least (DROPOUT_SAMPLES and DROPOUT_S), not at the channel's extreme (that is clipped): a vibration,
# noisy and quantised finely, repeats a value a few samples at most
DROPOUT_SAMPLES = 32
DROPOUT_S = 0.002
# A baseline off zero (a DC-coupled input: an ICP sensor's bias logged; the matched filter and the likelihood ratio
# called a healthy take at 2.1 V over 5 mV/(m/s²) a fault) or drifting (the sensor settling, a DC-coupled input warming
# up): a polynomial of this degree over the take whose offset or swing exceeds this share of the vibration's RMS about
# it. A gearbox's lines, turns of each shaft within the take, barely project on it (a 2 s take of shafts at 2.9 Hz and
# up: a swing of 0.04 RMS); a decay over 0.8 s of a 2 s take is left at 0.3 % (a cubic: 2.6 %)
BASELINE_DEGREE = 5
BASELINE_SHARE = 0.25
BASELINE_BLOCKS = 4096
# A slow shaft's run-out of a few turns over the take is a line, no baseline: it projected on the polynomial alone (a
# 92T output gear at 2 Hz, 6 turns of a 3 s take at 0.4 m/s²: 'drifts by 0.94 m/s²', taken out with the shaft's own
# line). The strongest line of BASELINE_TURNS turns over the take is fitted beside the polynomial; fewer turns than
# the least are a drift's (the which-gear check needs 8 turns of a shaft: signals.nonsync.TURNS).
BASELINE_TURNS = (2.0, 16.0)


# A channel of which over PULSE_LEVELS of the samples lie within PULSE_BAND of its range from its lowest or its highest
# value, each level PULSE_LEVEL_SHARE of them at least, holds a pulse train (a tacho's: all of them), not a vibration
# (a gearbox's, of one mesh tone or many: 0.1-0.25; clipped: its few samples at the rails)
PULSE_LEVELS = 0.8
PULSE_BAND = 0.1
PULSE_LEVEL_SHARE = 0.01


def not_pulses(x: np.ndarray) -> None:
    """Refuses a vibration *x* that holds a pulse train (PULSE_LEVELS). A 33/74 drive's take whose tacho and vibration
    columns were named the other way round read its mesh's cycles as a tacho's pulses (726 Hz: '+3200 %'), the pulses
    as '2136 samples flat at 49.03 m/s² (clipped ...)'; a gap run of such a take ended 'unexplained'."""
    lo, hi = float(np.min(x)), float(np.max(x))
    band = PULSE_BAND * (hi - lo)
    low, high = float(np.mean(x <= lo + band)), float(np.mean(x >= hi - band))
    if low + high > PULSE_LEVELS and min(low, high) >= PULSE_LEVEL_SHARE:
        raise GearlabInputError(
            f"holds a pulse train: {low + high:.0%} of its samples lie at its two levels ({lo:.4g} and {hi:.4g}), "
            "not a vibration; a tacho? (vibration and tacho swapped?)"
        )


def _baseline(x: np.ndarray, line: bool) -> tuple[np.ndarray, float, float, float]:
    """The baseline of *x* at every sample, its offset, its swing and the RMS of *x* about it: a polynomial of
    BASELINE_DEGREE fitted to the means of BASELINE_BLOCKS blocks (a 10-minute take's design matrix: 0.5 GB); with
    *line*, beside the strongest line of BASELINE_TURNS turns over the take the polynomial leaves (the line kept)."""
    cuts = np.linspace(0, x.size, min(x.size, BASELINE_BLOCKS) + 1).astype(int)
    means, middles = np.add.reduceat(x, cuts[:-1]) / np.diff(cuts), (cuts[:-1] + cuts[1:] - 1) / 2 / (x.size - 1)
    u = 2.0 * middles - 1.0
    V = np.polynomial.legendre.legvander(u, BASELINE_DEGREE)
    coef = np.linalg.lstsq(V, means, rcond=None)[0]
    if line and means.size >= 8 * BASELINE_TURNS[1]:  # enough blocks to tell a line
        turns = np.arange(BASELINE_TURNS[0], BASELINE_TURNS[1], 0.05)  # u spans 2: a turn over the take is pi in u
        power = np.abs(np.exp(-1j * np.pi * np.outer(turns, u)) @ (means - V @ coef))
        phase = np.pi * turns[int(np.argmax(power))] * u
        coef = np.linalg.lstsq(np.column_stack([V, np.cos(phase), np.sin(phase)]), means, rcond=None)[0][: len(coef)]
    fit = np.polynomial.legendre.legval(np.linspace(-1.0, 1.0, x.size), coef)
    return fit, float(np.mean(fit)), float(np.ptp(fit)), float(np.std(x - fit))


def acquisition(x: np.ndarray, fs: float) -> tuple[np.ndarray, tuple[str, ...]]:
    """*x* (m/s², sampled at *fs*) with a baseline off zero or drifting taken out, and what its acquisition did to it:
    each side clipped, each dropout, the baseline; a pulse train refused (not_pulses). A healthy take whose ICP sensor
    was still settling (a 2 s take at 0.4 V decaying over 0.8 s, 5 mV/(m/s²)) was scored a fault by every method, its
    level said 6.5 x its history's ('another load or gain?'); a take with 0.3 s of zeros was said to be of another
    gearbox and scored healthy."""
    x = np.asarray(x, dtype=np.float64)
    not_pulses(x)
    notes = [f"{n} samples flat at {v:.4g} m/s² (clipped at the logger's or sensor's range?)" for n, v in clipped(x)]
    same = np.concatenate([[0], (x[1:] == x[:-1]).astype(np.int8), [0]])  # runs of repeats: sample a + 1 .. b - 1
    edges = np.flatnonzero(np.diff(same))
    starts, ends = edges[::2], edges[1::2] + 1
    long = (ends - starts) >= max(DROPOUT_SAMPLES, DROPOUT_S * fs)
    for a, b in zip(starts[long], ends[long]):
        if x[a] not in (x.max(), x.min()):
            notes.append(
                f"a dropout: {b - a} samples ({(b - a) / fs:.3g} s) flat at {x[a]:.4g} m/s² from {a / fs:.4g} s"
            )
    if x.size > 2 * BASELINE_DEGREE:
        # a drift the polynomial alone finds, and finds again beside a slow shaft's line (BASELINE_TURNS)
        for line in (False, True):
            fit, offset, swing, rest = _baseline(x, line)
            if max(abs(offset), swing) <= BASELINE_SHARE * rest:
                break
        else:
            notes.append(
                f"the baseline sits at {offset:.4g} m/s² and drifts by {swing:.4g} m/s² over the take (the vibration's "
                f"RMS {rest:.4g}: a DC-coupled input, a sensor settling?): taken out"
            )
            x = x - fit
    return x, tuple(notes)
