"""The measurement chain of a record, which a simulation must go through to be compared with it.

A measured record is not the angle-domain revolution a simulator makes: the acquisition
samples the vibration at its own rate fs (anti-alias filtered below fs/2), adds the sensor
and amplifier noise *in time*, rounds to the converter's step when it stores integers, and
gearlab's importer then order-tracks it (linear interpolation against the tacho angle,
gearlab.signals.resample_revolutions) to 4096 points per revolution. Revolutions start
between samples (any real record), so every revolution is interpolated at its own
fractional offset; the interpolation low-passes what the record holds, noise included
(0.6-2.5 dB at high orders). A simulated source whose noise is added after the
resampling can never match that, and the gap diagnosis then reports a gap no effect can
close. :func:`measure` sends simulated revolutions through the same chain:

    deterministic revolution (angle domain, every non-noise effect applied)
      ─► band-limited below the record's Nyquist order, read at the record's sample times
         (the revolution's start fraction taken from the target, the tacho's angle offset)
      ─► noise effects in time, at the record's rate (the sensor's noise is white in time)
      ─► rounded to the record's step (integer formats)
      ─► order-tracked by resample_revolutions, the importer's own function

:class:`Chain` describes one target's chain; :func:`chain_of` reads it off the importer's meta
(which records where the kept revolutions start between samples).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ..signals import resample_revolutions
from .spec import POINTS

TWO_PI = 2.0 * np.pi
# Start fractions a record keeps (meta): enough for every row a diagnosis simulates.
FRACTIONS_KEPT = 512
# A record holds shaft orders up to its Nyquist order fs / (2 speed); its anti-alias filter passes
# this share of that band (the usual 80-90 %): a comparison is limited to it (the gap's max_order).
PASSBAND = 0.9


@dataclass(frozen=True)
class Chain:
    """How a target was acquired, as far as the comparison needs it.

    fs:        the record's sampling rate (Hz)
    speed:     its shaft speed (Hz; the tacho's mean)
    fractions: where each of its revolutions starts between two samples (0 <= f < 1), in record
               order; the simulated rows take them in turn. () = uniform draws
    step:      the record's quantisation step in physical units (integer formats), 0 = none
    offset:    the angle (rad) of the record's tacho zero in the simulation's frame; None = fitted
               for every simulated set against *reference* (the target's synchronous average)
    speed_from_mesh: no tacho: the speed was found from a gearbox description's mesh lines, so only
               speed x pinion teeth is measured
    described_speed: the description's speed (Hz) where the source was set to the speed of
               measured records (found from the mesh lines: a wrong tooth count moves the speed
               found, not the mesh order; a tacho's: read on another shaft, the speed is a ratio off)
    tacho_shaft: the shaft a measured target's tacho was read as (None: no tacho)
    pulses_per_rev: the marks a turn its tacho was read with, one count for every record (None: no tacho, or
               records of other counts): the structure check names a misread count as a count, not a share
    takes:     the revolutions of each record laid end to end, in order (() = one take): a slower
               shaft's phase jumps where two records meet, so its sidebands are read within one
    """

    fs: float
    speed: float
    fractions: tuple[float, ...] = ()
    step: float = 0.0
    offset: float | None = None
    reference: np.ndarray | None = field(default=None, compare=False, repr=False)
    speed_from_mesh: bool = False
    described_speed: float | None = None
    tacho_shaft: str | None = None
    pulses_per_rev: int | None = None
    takes: tuple[int, ...] = field(default=(), compare=False, repr=False)

    @property
    def samples_per_rev(self) -> float:
        return self.fs / self.speed

    @property
    def nyquist_order(self) -> float:
        return 0.5 * self.samples_per_rev

    @property
    def max_order(self) -> int:
        """The highest shaft order the record holds: PASSBAND of its Nyquist order."""
        return int(PASSBAND * self.nyquist_order)


def chain_of(meta: dict) -> Chain:
    """A measured file's chain from the importer's meta (gearlab.data.importers): its rate, tacho
    speed, the kept revolutions' start fractions and its quantisation step."""
    return Chain(
        fs=float(meta["fs_hz"]),
        speed=float(meta["speed_hz"]),
        fractions=tuple(float(f) for f in meta.get("start_fractions", ())),
        step=float(meta.get("quantum", 0.0)),
        speed_from_mesh=bool(meta.get("speed_from_mesh", False)),
    )


def fit_offset(deterministic: np.ndarray, reference: np.ndarray, teeth: int = 1) -> float:
    """The angle ψ (rad, in [0, 2π)) by which the simulation's revolution must turn to match the
    target's synchronous average *reference*: the maximum of their circular cross-correlation. A
    free rotation of the revolution: the record's tacho zero is wherever its mark sits on the shaft.

    The correlation of a gear's vibration is dominated by the mesh orders, which repeat every tooth
    pitch: its peaks one pitch apart are nearly equal, and the grid picks among them by rounding.
    So the peak is found on the 4096-point grid, refined between grid points on the exact sum,
    and then the *teeth* pitch aliases (where only the orders that are not mesh harmonics differ)
    are compared exactly."""
    from scipy.optimize import minimize_scalar

    P = deterministic.shape[-1]
    cross = np.conj(np.fft.rfft(reference - reference.mean())) * np.fft.rfft(deterministic - deterministic.mean())
    weight = np.full(cross.size, 2.0)
    weight[0] = weight[-1] = 1.0
    cross = cross * weight
    m = np.arange(cross.size)

    def corr(s: float) -> float:  # s in revolutions
        return float(np.real(np.sum(cross * np.exp(2j * np.pi * m * s))))

    k = int(np.argmax(np.fft.irfft(cross / weight, n=P)))
    res = minimize_scalar(
        lambda s: -corr(s), bounds=((k - 1) / P, (k + 1) / P), method="bounded", options={"xatol": 1e-7}
    )
    s0 = float(res.x)
    best = max((s0 + j / teeth for j in range(max(1, teeth))), key=corr)
    return float((TWO_PI * best) % TWO_PI)


@functools.lru_cache(maxsize=16)
def _chirp(terms: int, count: int, step: float):
    """The chirp z-transform plan that evaluates a Fourier series of *terms* orders at *count*
    angles *step* revolutions apart (from angle 0). Building a plan costs several FFTs; a search
    reads thousands of revolutions at the same record's step, each from its own start, which is a
    phase ramp on the coefficients, not another plan."""
    from scipy.signal import CZT

    return CZT(terms, m=count, w=np.exp(2j * np.pi * step), a=1.0)


def _coefficients(rows: np.ndarray, max_order: int) -> np.ndarray:
    """The one-sided Fourier series coefficients of periodic *rows* (n, P), orders 0..max_order."""
    F = np.fft.rfft(rows, axis=-1)[..., : max_order + 1] / rows.shape[-1]
    F[..., 1:] *= 2.0
    return F


def sampled(
    deterministic: np.ndarray, chain: Chain, offset: float = 0.0, first: int = 0, record: bool = False
) -> tuple:
    """Rows *deterministic* (n, P) -- angle-domain revolutions in the simulation's frame -- read at
    the record's sample times: (x, u), x (n, L) the samples of each row's stretch of record and u
    (n, L) their angles in revolutions from the row's tacho mark (sample 1 and 2 straddle u = 0).
    Each row's Fourier series below the record's Nyquist order is evaluated exactly there, by a
    chirp z-transform (the record's samples are uniform in angle but not a whole number per
    revolution; an interpolation would dull the mesh harmonics by parts per thousand, which 80
    quiet revolutions resolve).
    *offset*: the record's tacho zero in the simulation's frame (rad). The rows take the target's
    start fractions at evenly spaced quantiles of their distribution, turned by *first* places
    (none kept: a uniform spread).
    *record*: the rows are consecutive revolutions of one record (a tone that runs on from one into
    the next). Each is then read through the Fourier series of itself and its two neighbours
    (three revolutions, row i in the middle), as the record holds it, not as its own row repeated:
    one row's series wraps its end onto its start, and a line that is not a whole order then jumps
    there, which rings in every row with the tone's phase (images at k +- the tone's order, 11 dB
    under a 1.25-order tone). The first and last rows serve as neighbours only: n - 2 come back."""
    X = np.asarray(deterministic, dtype=np.float64)
    if record:
        X = np.concatenate([X[:-2], X[1:-1], X[2:]], axis=1)  # (n - 2, 3P): row i+1 in the middle
    span = 3 if record else 1  # revolutions per series
    n, P = X.shape
    P //= span
    per_rev = chain.samples_per_rev
    # Strictly below the record's Nyquist order: what an anti-alias filter lets through.
    max_order = max(1, min(P // 2, int(math.ceil(chain.nyquist_order)) - 1))
    length = int(math.ceil(per_rev)) + 3
    fractions = chain.fractions
    if fractions:
        # The target's distribution of fractions, at evenly spaced quantiles: the importer's
        # interpolation loss depends on the fraction, and the source's TSA residual must spread as
        # the target's does. Near a whole number of samples per revolution the fractions drift
        # slowly (0.0125 per revolution at 2698.9875): the first 40 of 79 covered half the range
        # (+0.5 dB in every residual sector, a null target "significant" at p = 0.002 on every
        # seed); at 1614.25 they take 4 values in turn, of which every other row saw only 2.
        ranked = np.sort(np.asarray(fractions, dtype=np.float64))
        frac = ranked[(first + ((np.arange(n) + 0.5) * len(ranked) / n).astype(int)) % len(ranked)]
    else:
        frac = (0.5 + 0.618034 * (first + np.arange(n))) % 1.0
    # Sample k lies at revolution (k - 1 - frac) / per_rev: the revolution starts between samples 1 and 2.
    u = (np.arange(length, dtype=np.float64)[None, :] - 1.0 - frac[:, None]) / per_rev
    F = _coefficients(X, span * max_order)  # line m is order m / span
    middle = span // 2  # the row's own revolution within its series
    F = F * np.exp(2j * np.pi * np.arange(F.shape[1])[None, :] * (middle + u[:, :1] + offset / TWO_PI) / span)
    return np.real(_chirp(F.shape[1], length, 1.0 / (span * per_rev))(F, axis=-1)), u


def tracked(x: np.ndarray, u: np.ndarray, chain: Chain, noise, points: int = POINTS) -> np.ndarray:
    """Sampled rows (x, u) of :func:`sampled` as the importer delivers them: *noise(i, x)* adds row
    i's noise to its samples x (1, L) at the record's rate (None: no noise), the record's step
    rounds them, and resample_revolutions order-tracks them to *points* per revolution."""
    n = x.shape[0]
    out = np.empty((n, points))
    for i in range(n):
        xi = x[i : i + 1]
        if noise is not None:
            xi = noise(i, xi)
        if chain.step > 0:
            xi = np.round(xi / chain.step) * chain.step
        out[i] = resample_revolutions(xi[0], TWO_PI * u[i], points=points)[0]
    return out


def measure(deterministic: np.ndarray, chain: Chain, noise, offset: float = 0.0, first: int = 0) -> np.ndarray:
    """Rows *deterministic* (n, P) -- angle-domain revolutions in the simulation's frame -- as the
    target's acquisition and importer would deliver them (module docstring): :func:`sampled`, then
    :func:`tracked`. *noise(i, x)* adds row i's noise to its time-domain samples x (1, L) at the
    record's rate (None: no noise). *offset*: the record's tacho zero in the simulation's frame
    (rad). *first*: the index of the first row among the target's start fractions."""
    X = np.asarray(deterministic, dtype=np.float64)
    x, u = sampled(X, chain, offset, first)
    return tracked(x, u, chain, noise, X.shape[1])
