"""Revolutions on another angle grid: so many points a revolution as a saved history holds, or today's.

A detection run keeps its history revolutions, and the localisation's reference revolution, at the points a
revolution the gearlab that made it cut records to (signals.POINTS); `gearlab score` cuts a new take at today's. The
record's revolutions are laid end to end, its DFT kept at every order below half the coarser of the two grids and
nothing made above it, the inverse DFT taken at the other grid's points. Every order the run reads lies below that (a
layout reads up to 0.45 of its points, the learned input and the classical indicators within the run's band), and
there the whole record's DFT is its own to rounding (1e-12 of it): a take cut to 4096 points and put on 2048 reads as
one cut to 2048 from a recording band-limited below 1024 orders. A part of the record (a slower shaft's whole turns,
a block) sees the discarded orders' share of the record's ends, as an ideal low-pass leaves it.

Everything is numpy.
"""

from __future__ import annotations

import numpy as np


def at_points(revolutions: np.ndarray, points: int) -> np.ndarray:
    """*revolutions* (R, p) consecutive revolutions as (R, *points*) on the same angles' grid of *points* a
    revolution; themselves where p is *points*."""
    revs = np.asarray(revolutions)
    count, have = revs.shape
    if have == points:
        return revs
    keep = count * min(have, points) // 2  # orders below half the coarser grid: bins 0 .. keep - 1
    spectrum = np.fft.rfft(revs.astype(np.float64, copy=False).ravel())[:keep]
    out = np.fft.irfft(spectrum, n=count * points) * (points / have)
    return out.reshape(count, points).astype(revs.dtype if revs.dtype.kind == "f" else np.float64, copy=False)
