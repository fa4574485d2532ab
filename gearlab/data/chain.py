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

import math
from dataclasses import dataclass, field

import numpy as np

from ..signals import resample_revolutions

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
    """

    fs: float
    speed: float
    fractions: tuple[float, ...] = ()
    step: float = 0.0
    offset: float | None = None
    reference: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def samples_per_rev(self) -> float:
        return self.fs / self.speed

    @property
    def nyquist_order(self) -> float:
        return 0.5 * self.samples_per_rev


def chain_of(meta: dict) -> Chain:
    """A measured file's chain from the importer's meta (gearlab.data.importers): its rate, tacho
    speed, the kept revolutions' start fractions and its quantisation step."""
    return Chain(
        fs=float(meta["fs_hz"]),
        speed=float(meta["speed_hz"]),
        fractions=tuple(float(f) for f in meta.get("start_fractions", ())),
        step=float(meta.get("quantum", 0.0)),
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


def read_at(row: np.ndarray, max_order: int, u0: float, step: float, count: int) -> np.ndarray:
    """The periodic revolution *row* without orders above *max_order*, read at the *count* angles
    u0 + k step (revolutions): its Fourier series evaluated exactly there, by a chirp z-transform
    (the record's samples are uniform in angle but not a whole number per revolution; an
    interpolation would dull the mesh harmonics by parts per thousand, which 80 quiet revolutions
    resolve)."""
    from scipy.signal import czt

    F = np.fft.rfft(row)[: max_order + 1] / row.size
    F[1:] *= 2.0
    return np.real(czt(F, m=count, w=np.exp(2j * np.pi * step), a=np.exp(-2j * np.pi * u0)))


def measure(deterministic: np.ndarray, chain: Chain, noise, offset: float = 0.0, first: int = 0) -> np.ndarray:
    """Rows *deterministic* (n, P) -- angle-domain revolutions in the simulation's frame -- as the
    target's acquisition and importer would deliver them (module docstring). *noise(i, x)* adds
    row i's noise to its time-domain samples x (1, L) at the record's rate (None: no noise).
    *offset*: the record's tacho zero in the simulation's frame (rad). *first*: the index of the
    first row among the target's start fractions."""
    X = np.asarray(deterministic, dtype=np.float64)
    n, P = X.shape
    per_rev = chain.samples_per_rev
    # Strictly below the record's Nyquist order: what an anti-alias filter lets through.
    max_order = max(1, min(P // 2, int(math.ceil(chain.nyquist_order)) - 1))
    length = int(math.ceil(per_rev)) + 3
    out = np.empty((n, P))
    psi = offset / TWO_PI
    for i in range(n):
        fractions = chain.fractions
        frac = fractions[(first + i) % len(fractions)] if fractions else (0.5 + 0.618034 * (first + i)) % 1.0
        # Sample k lies at revolution (k - 1 - frac) / per_rev: the revolution starts between samples 1 and 2.
        u = (np.arange(length, dtype=np.float64) - 1.0 - frac) / per_rev
        x = read_at(X[i], max_order, u[0] + psi, 1.0 / per_rev, length)[None, :]
        if noise is not None:
            x = noise(i, x)
        if chain.step > 0:
            x = np.round(x / chain.step) * chain.step
        out[i] = resample_revolutions(x[0], TWO_PI * u, points=P)[0]
    return out
