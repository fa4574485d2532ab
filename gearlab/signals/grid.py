"""signals.shaft.on_grid's loop, compiled (numba): one pass over the positions, where numpy's form made
ten (floor, clip, the cast, two gathers, the products, the two ends' masks) over arrays of a record's
4 x denser reading: 7.5 ms a call of ~500,000 positions, a quarter of the localisation's own CPU after
the FFTs. The same operations in the same order, each rounded alone (no fastmath: no fused
multiply-add, no reordering), so every value is numpy's and np.interp's to the bit
(tests/test_localise_noise_units). Loaded by on_grid's first call, not by importing gearlab.signals."""

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
