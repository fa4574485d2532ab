"""A simulation's rows made when a sample reads them, not when the simulation ends.

A fault on a slower gear (or a later mesh of no whole input order) repeats only after a cycle of
many input turns: 143 for the 143T output gear of a 105/143 stage. Each of its teeth's rows is that
cycle turned (turned, below) and resampled to POINTS angles a turn: 143 x 4096 float64, 4.8 MB a
tooth, 0.69 GB a fault step on 143 teeth, where the cycle's time samples are 1 MB for them all.
TurnedRows keeps the cycle and each row's turn; Row names one row, and a sample's task makes it
from them (the same call on the same floats: the same row), in the worker that adds its noise.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..signals import resample_revolutions
from ..signals.angle import TWO_PI
from .spec import POINTS


def turned(periodic: np.ndarray, revolutions: int, shift: int, angle=None, first: int = 0) -> np.ndarray:
    """*revolutions* steady input revolutions (time samples from a tacho zero) turned by *shift*
    samples and started at revolution *first*, as one row of revolutions x POINTS angles (order
    tracking at the moved *angle*, when an effect moved it; then *shift* is 0)."""
    per_rev = len(periodic) // revolutions
    x = np.roll(periodic, shift - first * per_rev)
    if angle is None:
        theta = 2 * np.pi * np.arange(len(x) + 1) / per_rev
    else:  # the moved angle over the revolutions, from revolution *first* on
        moved = np.concatenate([angle[first * per_rev :], angle[: first * per_rev] + 2 * np.pi * revolutions])
        theta = np.append(moved - moved[0], 2 * np.pi * revolutions)
    theta[-1] = 2 * np.pi * revolutions  # exactly the revolutions' turns
    # ... which the cut must count as whole: 2π·15 / 2π is 14.999999999999998 (11, 15, 22, 30 ...
    # turns), and the cycle lost its last revolution (a TSA wrapping it jumped the slower shafts)
    while math.floor(theta[-1] / TWO_PI) < revolutions:
        theta[-1] = np.nextafter(theta[-1], np.inf)
    return resample_revolutions(np.append(x, x[0]), theta, POINTS).reshape(-1)


class TurnedRows:
    """The rows of one simulation on several teeth, each ``turned(periodic, revolutions, shift,
    angle, first)`` with its own (shift, first) of *turns*: len() rows of ``row_size`` points."""

    def __init__(self, periodic: np.ndarray, revolutions: int, angle, turns: list[tuple[int, int]]):
        self.periodic, self.revolutions, self.angle, self.turns = periodic, revolutions, angle, tuple(turns)

    def __len__(self) -> int:
        return len(self.turns)

    @property
    def row_size(self) -> int:
        return self.revolutions * POINTS

    @property
    def nbytes(self) -> int:
        """What it holds (a process's store of simulations counts it)."""
        return self.periodic.nbytes + (0 if self.angle is None else self.angle.nbytes)

    def setflags(self, write: bool) -> None:
        for array in (self.periodic, self.angle):
            if array is not None:
                array.setflags(write=write)

    def row(self, k: int) -> np.ndarray:
        shift, first = self.turns[k]
        return turned(self.periodic, self.revolutions, shift, self.angle, first)

    def stacked(self) -> np.ndarray:
        """Every row at once (len, row_size), as a caller of builder.simulate_unit gets them."""
        return np.stack([self.row(k) for k in range(len(self))])


class Row(NamedTuple):
    """Row *k* of *rows*, made when read (made)."""

    rows: TurnedRows
    k: int

    @property
    def size(self) -> int:
        return self.rows.row_size


def entries(rows) -> list:
    """A simulation's rows as samples take them: each a Row of TurnedRows, else a row of the array."""
    return [Row(rows, k) for k in range(len(rows))] if isinstance(rows, TurnedRows) else list(rows)


def made(row, last: dict | None = None) -> np.ndarray:
    """*row*'s values: a Row made (kept in *last*, one row, for the next sample that reads it: a chunk's
    healthy samples, a fault's duplicates), an array as itself."""
    if not isinstance(row, Row):
        return row
    if last is None:
        return row.rows.row(row.k)
    key = (id(row.rows), row.k)
    if key not in last:
        last.clear()
        last[key] = row.rows.row(row.k)
    return last[key]
