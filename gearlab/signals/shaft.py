"""Revolutions of a slower shaft from consecutive input-shaft revolutions (computed order tracking
on the shaft's own angle).

A once-per-turn event on a gear of a shaft turning r times per input turn (r = 26/73 for a
26/73 reducer's intermediate shaft) lands at another input angle every input revolution when 1/r
is no whole number, so an input-shaft TSA averages it away. Cut on that shaft's angle
θ_s = 2π (phase + r u), u the input turns, it comes back to one angle every revolution of the
shaft, where the shaft's TSA keeps it. The input revolutions given are one record's, in order and
contiguous in angle (as cut_revolutions and the dataset builder make them), so their samples are
the record on an even grid of input angle; the shaft's revolutions are that grid read at
*points* even angles of each of its complete turns. Orders of the shaft above points / 2 are
removed first (the grid holds 1/r times more of them), so that they do not alias, and the record is
read UPSAMPLE times denser or a little more (band-limited) before a cubic interpolation: linear on the grid
itself (the shaft's top orders at 2/r samples a cycle, 3.6 at r = 17/31), the interpolation's error, which
depends on where the shaft's turn falls between samples, moved a 17/31 + 17/29 box's healthy
intermediate-shaft rows 0.03 rms (peaks 0.28, a 17T pinion chip's signature 0.11) from one start
to another; cubic 2 x denser: 0.009 between rows (peak), the chip unchanged. Against the wave's own sum of
cosines it errs 3e-6 of the rms for lines below 0.05 cycles a sample, 4e-3 below 0.3 (linear 4 x denser: 2e-4,
9e-3; tests/test_shaft_reading.py), in about half the time (records of 20, 58, 99 revolutions: 16, 58,
200 ms against 30, 118, 339). And each shaft's own TSA of a record, its orders' mean and noise, for
gearlab.signals.localise (its "Fallback")."""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..errors import GearlabInputError
from .fft import rfft
from .pipeline import POINTS

UPSAMPLE = 2  # a record read 2 x denser before the cubic interpolation (module doc)


def shaft_revolutions(
    revs: np.ndarray, ratio: float, phase: float = 0.0, points: int = POINTS, max_order: float | None = None
) -> np.ndarray:
    """The complete revolutions (K, *points*) of a shaft turning *ratio* times per input turn, from
    consecutive input revolutions *revs* (R, P); *phase*: the shaft's angle in turns at revs[0, 0];
    *max_order*: the highest input order the record holds (its anti-alias band: above it, what
    cutting its samples into revolutions interpolated), none kept above it. Revolution k spans the
    shaft's turns [ceil(phase) + k, ceil(phase) + k + 1)."""
    revs = np.atleast_2d(np.asarray(revs, dtype=np.float64))
    if not ratio > 0:
        raise GearlabInputError(f"shaft revolutions: expected a shaft turning forwards (ratio > 0), got {ratio}")
    R, P = revs.shape
    x = revs.reshape(-1)
    n = x.size
    top = ratio * points / 2  # the shaft's highest order, in input orders
    if max_order:
        top = min(top, float(max_order) + 0.5)
    spectrum = rfft(x)  # a prime R: the four-step (signals.fft), not pocketfft's O(n R) pass
    spectrum[int(math.ceil(min(top, P / 2) * R)) :] = 0.0  # bin k: input order k / R
    first = math.ceil(phase - 1e-12)
    count = math.floor(phase + ratio * (n - 1) / P + 1e-12) - first
    if count < 1:
        return np.empty((0, points))
    turns = first + np.arange(count)[:, None] + np.arange(points)[None, :] / points
    return read_at(spectrum, n, (turns - phase) / ratio * P)


def read_at(
    spectrum: np.ndarray, n: int, at: np.ndarray, up: int = UPSAMPLE, dense: np.ndarray | None = None
) -> np.ndarray:
    """The n samples whose rfft is *spectrum* read at fractional sample positions *at* (position n is sample 0
    again, as the inverse FFT's wave is periodic in n): a 4-point Lagrange (cubic) interpolation between the
    samples of their band-limited interpolation at least *up* times denser (module doc). *dense*: an array of
    dense_length(n up) points the interpolation is made in (its values are overwritten), so that readings of one
    record reuse one (shaft_averages: a fresh array of a long record's reading is a tenth of its time in page
    faults)."""
    return read_dense(denser(spectrum, n, up, dense), n, at)


def denser(spectrum: np.ndarray, n: int, up: int = UPSAMPLE, dense: np.ndarray | None = None) -> np.ndarray:
    """read_at's band-limited interpolation of the n samples whose rfft is *spectrum*, at least *up* times denser
    (in *dense* where given)."""
    fine = dense_length(n * up)
    wave = np.fft.irfft(spectrum, n=fine, out=dense)
    wave *= fine / n  # in place: no second dense array
    return wave


def read_dense(wave: np.ndarray, n: int, at: np.ndarray) -> np.ndarray:
    """read_at's cubic reading at sample positions *at* of *wave*, denser's interpolation of n samples."""
    from .grid import read_cubic

    flat = np.ascontiguousarray(at, dtype=np.float64).reshape(-1)
    out = np.empty(flat.size)
    read_cubic(flat, wave.size / n, wave, out)
    return out.reshape(np.shape(at))


def dense_length(size: int) -> int:
    """The fewest points at or above *size* whose real inverse FFT has only factors 2, 3 and 5: a record of
    4096 points a revolution and R revolutions read 2 x denser has R's factors in its length, and a large one
    made the reading dear (pocketfft's Bluestein path: R = 199, 160 ms against 72 ms on the 0.5 % longer fast
    length; R = 58, 22 ms against 16 ms): the readings took a third of the localisation tests' CPU."""
    from scipy.fft import next_fast_len

    return int(next_fast_len(int(size), real=True))


def without_input_orders(revs: np.ndarray, p: int) -> np.ndarray:
    """Consecutive input revolutions *revs* less what their mean holds at the input orders that are no
    multiple of *p* (no whole order of a shaft turning p/q per input turn, p and q coprime): the input
    shaft's own content, which lands at another angle of that shaft from each start. A record's units
    lose it so (kinds.detection_records.without_input_shaft), and so do the dataset builder's rows of a
    whole cycle (data.builder.shaft_row): left in, a 17/31 + 17/29 box's healthy intermediate-shaft
    rows cut from two starts of its cycle were 0.18 apart (rms 1.25)."""
    F = np.fft.rfft(np.asarray(revs, dtype=np.float64).mean(axis=0))
    F[np.arange(len(F)) % p == 0] = 0.0
    return revs - np.fft.irfft(F, n=revs.shape[-1])


def on_turns(y: np.ndarray, at: np.ndarray, dense: np.ndarray | None = None, wave=None) -> np.ndarray:
    """Consecutive input revolutions *y* (flat) read at a shaft's grid *at* (sample positions): the samples
    themselves where the grid falls on them (the input shaft), else read_at's band-limited reading. Linear
    interpolation between y's own samples left images (size o - P) + k input orders away from a line at k
    (a shaft of o input turns cut into `size` points a turn), which every turn repeats where o = 1/q: the
    PHM 2009 rig's idler (o = 1/3) read its 3rd mesh harmonic's image 43 dB below it, a 1/7 shaft's lands
    at 585 + k; read_at's: below -130 dB (tests/test_shaft_reading.py). *dense*: read_at's. The spectrum is
    gearlab.signals.fft's: R revolutions' R x 4096 samples, R prime (a 60 s take's 2399: 0.26 s an rfft, 93 a take).
    *wave*: a function giving y's denser reading, where several shafts read the same y (made once)."""
    head = at.reshape(-1)[:64]  # a slower shaft's grid leaves the samples within a few points: no whole pass
    if np.array_equal(head, np.round(head)) and np.array_equal(at, whole := np.round(at)):
        return y[whole.astype(np.int64)]
    return read_dense(denser(rfft(y), y.size, dense=dense) if wave is None else wave(), y.size, at)


def uniform_filter1d(x: np.ndarray, size: int, mode: str) -> np.ndarray:
    """scipy's moving mean, imported on first use (0.4 s `gearlab validate` and `--help` need not pay)."""
    from scipy.ndimage import uniform_filter1d as moving_mean

    return moving_mean(x, size=size, mode=mode)


def averaged(segments: np.ndarray, top: int, smooth: int) -> tuple[np.ndarray, np.ndarray]:
    """(mean amplitude spectrum, noise power of the mean) of equal segments, bins 0 … top."""
    n, length = segments.shape
    Y = np.fft.rfft(segments, axis=1)[:, : top + 1] * (2.0 / length)
    mean = Y.mean(axis=0)
    scatter = np.sum(np.abs(Y - mean) ** 2, axis=0) / max(n - 1, 1)
    # one bin's scatter from a few segments is rough: the noise varies slowly across orders
    noise = uniform_filter1d(scatter, size=max(1, smooth), mode="nearest") / n
    return mean, noise


# Each shaft's cut of a record is kept for the next record of its layout and length: a localisation cuts such
# records again and again (tests/test_box_b_takes.py: 49 calls, 2 distinct cuts), and making them was 42 ms of a
# 340 ms call. A 99-revolution record of three shafts: 24 MB a cut, so few are kept: 4 (96 MB at most), as a
# history's takes and the record read against them alternate among 3 or 4 (2 kept: 265 of 424 calls missed over
# 20 localising test files, 4 kept: 69).
@lru_cache(maxsize=4)
def _cuts(pts: int, shafts: tuple, first: int, R: int, length: int) -> tuple[dict, int]:
    """({shaft: (its turns' grid in record samples, the record's samples in its turn's points)}, the
    fewest complete turns) of R input revolutions from *first* (*length* samples); *shafts*: (index, order,
    name) of each. Read-only arrays: the cut is shared by the calls that hit the cache."""
    cut, periods = {}, None
    for s, o, name in shafts:
        size = int(2 ** math.ceil(math.log2(pts / float(o))))  # at least the input samples of a turn
        j0 = math.ceil(first * o)
        n = math.floor((first + R) * o + 1e-9) - j0
        if n < 2:
            raise GearlabInputError(
                f"{R} input revolutions hold {max(n, 0)} complete turns of the {name} shaft; expected at least 2"
            )
        # ((j0 + turn + point / size) / o - first) x pts, clipped, and ((first + sample / pts) o mod 1) x size,
        # each step in place (the same floats, no temporaries); x - floor(x) is x % 1 to the bit (both the exact
        # fraction, rounded once where x < 0) in a seventh of np.remainder's time, which was half the cut's
        at = np.add((j0 + np.arange(n))[:, None], np.arange(size)[None, :] / size)
        at /= float(o)
        at -= first
        at *= pts
        np.clip(at, 0, length - 1, out=at)
        phase = np.arange(length) / pts
        phase += first
        phase *= float(o)
        phase -= np.floor(phase)
        phase *= size
        cut[s] = (at, phase)  # samples, phase
        for a in cut[s]:
            a.flags.writeable = False
        periods = n if periods is None else min(periods, n)
    return cut, periods


def shaft_averages(y: np.ndarray, lay, first: int, R: int, sweeps: int) -> tuple[np.ndarray, np.ndarray, int]:
    """(mean, noise, fewest turns) of each shaft's own TSA at the orders read from it (*lay*: a
    gearlab.signals.localise.Layout in per-shaft mode; *y*: R consecutive input revolutions, flat), of the
    record less the other shafts' averages (a slower one's less the orders read from this), fastest first,
    *sweeps* times over (0: each shaft's TSA of the record itself).

    The noise of a mean (sweeps > 0): the turn-to-turn scatter of the record less every other shaft's
    average, plus the power of what those averages leave in the mean (|mean - that record's mean|²).
    Another shaft's lines, at no whole order of this one, scatter its turns far more than they stay in
    its mean: read as scatter, a 38/87 + 49/93 + 69/91 box's later meshes hid an input-pinion chip
    (z 1.7 against a threshold of 2.8); left out of the noise, a slower gear's crack flagged the input
    (tests/test_localise_blocks.py)."""
    mean, noise = np.zeros(lay.orders.size, complex), np.zeros(lay.orders.size)
    shafts = sorted((s for s in range(len(lay.shafts)) if (lay.source == s).any()), key=lambda s: -lay.shaft_orders[s])
    cut, periods = _cuts(lay.points, tuple((s, lay.shaft_orders[s], lay.shafts[s]) for s in shafts), first, R, y.size)
    waves, read = {}, {}
    dense = np.empty(dense_length(y.size * UPSAMPLE))  # every reading of the record's turns is made in it

    def at_samples(r: int, s: int) -> np.ndarray:
        """Shaft r's average so far at the record's samples, as shaft s subtracts it: read once per
        average and mask, since every other shaft of a sweep (and the noise's pass) subtracts the same."""
        slower = lay.shaft_orders[r] < lay.shaft_orders[s]  # a slower r: less its orders read from s
        key = (r, (lay.shaft_orders[r] / lay.shaft_orders[s]).denominator if slower else 0)
        if key not in read:
            spec = np.fft.rfft(waves[r])
            if key[1]:
                spec[:: key[1]] = 0.0
            # a turn's average read at every sample of the record: cubic 4 x denser errs below linear 8 x, for less
            read[key] = read_at(spec, waves[r].size, cut[r][1], 4)
        return read[key]

    def less_others(s: int) -> np.ndarray:
        """Shaft s's turns of the record less the other shafts' averages so far."""
        left = y
        for r in waves:
            if r != s:  # the first difference a new array, the next ones into it (the same values)
                left = left - at_samples(r, s) if left is y else np.subtract(left, at_samples(r, s), out=left)
        return on_turns(left, cut[s][0], dense)

    # sweeps 0: every slower shaft reads the record itself, so its spectrum and denser reading are made once (a
    # template's 260-revolution record: 3 transforms and readings of 2 M points to 1)
    record = lru_cache(maxsize=1)(lambda: denser(rfft(y), y.size, dense=dense))
    for sweep in range(max(sweeps, 1)):
        for s in shafts:
            segments = less_others(s) if sweeps else on_turns(y, cut[s][0], dense, record)
            waves[s] = segments.mean(axis=0)
            for key in [k for k in read if k[0] == s]:  # s's readings were of its previous average
                del read[key]
            if sweep == max(sweeps, 1) - 1:
                sel = lay.source == s
                m, v = averaged(segments, int(lay.index[sel].max()), 3)
                mean[sel], noise[sel] = m[lay.index[sel]], v[lay.index[sel]]
    # each mean's noise (the docstring); the last shaft's turns of the last sweep were already the record
    # less every other shaft's final average, so its mean is their mean and its noise their scatter
    for s in shafts[:-1] if sweeps else ():
        sel = lay.source == s
        m, v = averaged(less_others(s), int(lay.index[sel].max()), 3)
        noise[sel] = v[lay.index[sel]] + np.abs(mean[sel] - m[lay.index[sel]]) ** 2
    return mean, noise, int(periods)
