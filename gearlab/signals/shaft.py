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
removed first (the grid holds 1/r times more of them), so that they do not alias."""

from __future__ import annotations

import math

import numpy as np

from ..errors import GearlabInputError
from .pipeline import POINTS


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
    if top < P / 2:
        spectrum = np.fft.rfft(x)
        spectrum[int(math.ceil(top * R)) :] = 0.0  # bin k: input order k / R
        x = np.fft.irfft(spectrum, n=n)
    first = math.ceil(phase - 1e-12)
    count = math.floor(phase + ratio * (n - 1) / P + 1e-12) - first
    if count < 1:
        return np.empty((0, points))
    turns = first + np.arange(count)[:, None] + np.arange(points)[None, :] / points
    return np.interp((turns - phase) / ratio * P, np.arange(n, dtype=np.float64), x)
