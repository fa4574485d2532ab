"""Chart data that a front-end draws: the TUI in the terminal (plotext).

Each scenario kind says what to plot of a run (``charts(scenario, run)``) as plain
numbers; drawing is the front-end's business, so the kinds stay free of any UI code.
The PNG figures of the report are drawn by gearlab.plots with matplotlib.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Curve:
    label: str
    x: Sequence[float]
    y: Sequence[float]
    err: Sequence[float] | None = None  # a ± band, e.g. the std over repetitions


@dataclass(frozen=True)
class Chart:
    title: str
    xlabel: str
    ylabel: str
    curves: tuple[Curve, ...]
    xticks: Sequence[float] | None = None  # numbered axes shown tick by tick (k, intensity step)
    notes: tuple[str, ...] = field(default=())  # what could not be drawn, and why
    # Named categories (views, effects, methods): the curves' y are bars, one per category in
    # this order (their x are ignored); a front-end labels the bars with these names.
    categories: Sequence[str] | None = None
    # Horizontal reference lines drawn across the plot and kept in view (a score trend's threshold at 0:
    # above it a record is called; the report's PNG draws it, the TUI's chart drew none)
    hlines: Sequence[float] = ()


def dataset_examples(dataset, tooth: int = 5, per_class: int = 3) -> list[tuple[int, str, int]]:
    """Samples that show a dataset: per class (class index, label, row), at the lowest, middle
    and top intensity (*per_class* = 3) or the top one (1), faults on *tooth* where present."""
    teeth = sorted({int(t) for t in dataset.tooth if t > 0})
    shown_tooth = tooth if tooth in teeth else (teeth[0] if teeth else 0)
    out = []
    for c, name in enumerate(dataset.spec.class_names):
        mask = (dataset.label == c) & ((dataset.tooth == shown_tooth) | (c == 0))
        steps = sorted({int(s) for s in dataset.intensity[mask]})
        if not steps:
            continue
        chosen = sorted({steps[0], steps[len(steps) // 2], steps[-1]}) if per_class > 1 else steps[-1:]
        for step in chosen:
            row = int(np.flatnonzero(mask & (dataset.intensity == step))[0])
            label = "healthy" if c == 0 else (f"{name} step {step}" if per_class == 1 else f"step {step}")
            out.append((c, label, row))
    return out


def envelope(x: np.ndarray, y: np.ndarray, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """A line of many points (*x* increasing) cut to at most 4 a column of *columns* equal spans of x: each
    span's first, lowest, highest and last point, in order. A terminal chart of `columns` dots across draws the
    same line (every peak and dip, each span joined to the next) from a few hundred points: an order spectrum's
    4,000-8,000 took plotext 80-90 ms, and every n-th point alone left out a line one bin wide."""
    if x.size <= 4 * columns:
        return x, y
    starts = np.searchsorted(x, np.linspace(x[0], x[-1], columns + 1)[:-1])
    ends = np.r_[starts[1:], x.size]
    keep = [np.unique([a, a + np.argmin(y[a:b]), a + np.argmax(y[a:b]), b - 1]) for a, b in zip(starts, ends) if b > a]
    kept = np.concatenate(keep)
    return x[kept], y[kept]
