"""Readings of samples on their own grid 0 … n-1, compiled (numba): one pass over the positions, where
numpy's form made ten (floor, clip, the cast, two gathers, the products, the two ends' masks).
read_grid is np.interp's linear reading: the same operations in the same order, each rounded alone
(no fastmath: no fused multiply-add, no reordering), so every value is np.interp's to the bit
(tests/test_localise_noise_units). read_cubic is signals.shaft.read_at's. Loaded by their first call,
not by importing gearlab.signals."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def read_grid(x: np.ndarray, fp: np.ndarray, out: np.ndarray) -> None:
    """out[i] = np.interp(x[i], arange(fp.size), fp) (1-D, float64; NaN where x[i] is NaN)."""
    last = fp.size - 1
    top = max(last - 1, 0)
    for i in range(x.size):
        xi = x[i]
        if xi != xi:  # NaN: no interval (numpy's form failed on its index); never read past the grid
            out[i] = xi
        elif xi <= 0.0:
            out[i] = fp[0]
        elif xi >= last:
            out[i] = fp[last]
        else:
            j = min(max(np.floor(xi), 0.0), top)
            f = xi - j
            k = int(j)
            step = fp[min(k + 1, last)] - fp[k]
            step = step * f
            out[i] = step + fp[k]


@numba.njit(cache=True)
def read_cubic(x: np.ndarray, scale: float, fp: np.ndarray, out: np.ndarray) -> None:
    """out[i]: the 4-point Lagrange (cubic) interpolation at position x[i] * scale of the periodic samples *fp*
    (fp[k + fp.size] = fp[k]; 1-D, float64), from the samples at floor(x[i] scale) - 1 … floor(x[i] scale) + 2;
    NaN where x[i] is not finite. signals.shaft.read_at's step on its 2 x denser band-limited samples (*scale*:
    their density, applied here, not in an array of the positions as large as the reading)."""
    n = fp.size
    for i in range(x.size):
        xi = x[i] * scale
        if not np.isfinite(xi):  # no sample to read; never an index from a NaN or infinity
            out[i] = np.nan
            continue
        j = np.floor(xi)
        t = xi - j
        k = int(j)
        if k >= 1 and k + 2 < n:
            a, b, c, d = fp[k - 1], fp[k], fp[k + 1], fp[k + 2]
        else:  # past either end: the samples wrap (the band-limited reading is periodic in n)
            a, b, c, d = fp[(k - 1) % n], fp[k % n], fp[(k + 1) % n], fp[(k + 2) % n]
        u, v, w = t - 1.0, t - 2.0, t + 1.0  # the weights of the nodes -1, 0, 1, 2 at t
        out[i] = (w * t * u * d - t * u * v * a) / 6.0 + (w * u * v * b - w * t * v * c) * 0.5
