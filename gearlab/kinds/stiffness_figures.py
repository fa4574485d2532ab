"""The stiffness kind's figures (gearlab.kinds.stiffness; report.html): thesis Figure 2.33 (every
ladder step's TVMS, one panel per fault type) and Figure 2.32 (relative fault area per step).
Imported when the report is drawn, not at start-up (matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .. import plots
from ..plots import plt


def ladder_grid(
    panels: Mapping[str, Sequence[tuple[int, np.ndarray, np.ndarray]]],
    path: Path,
    window_deg: tuple[float, float] | None = None,
    title: str = "",
) -> Path:
    """Figure 2.33: one panel per fault type, every ladder step as a line coloured by intensity."""
    names = list(panels)
    cols = 2 if len(names) > 1 else 1
    rows = (len(names) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(6.5 * cols, 3.4 * rows), squeeze=False, layout="constrained")
    for ax, name in zip(axes.flat, names):
        steps = panels[name]
        top = max(s for s, _, _ in steps)
        for step, theta, k in steps:
            ax.plot(np.degrees(theta), k / 1e8, lw=0.9, color=plt.cm.viridis((step - 1) / max(top - 1, 1)))
        ax.set_title(name)
        ax.set_xlabel("pinion angle (deg)")
        ax.set_ylabel("TVMS (1e8 N/m)")
        if window_deg:
            ax.set_xlim(*window_deg)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(names) :]:
        ax.axis("off")
    sm = plt.cm.ScalarMappable(cmap="viridis", norm=plt.Normalize(1, 20))
    fig.colorbar(sm, ax=axes, label="intensity step", shrink=0.8)
    if title:
        fig.suptitle(title)
    return plots.save(fig, path)


def rfa_curves(curves: Mapping[str, tuple[Sequence[int], Sequence[float]]], path: Path) -> Path:
    """Figure 2.32: relative fault area against intensity step per fault type."""
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for name, (steps, rfa) in curves.items():
        ax.plot(steps, rfa, marker="o", ms=3, label=name)
    ax.set_xlabel("intensity step (1 = healthy)")
    ax.set_ylabel("relative fault area (fraction of the tooth)")
    ax.set_ylim(-0.02, 1.05)
    ax.grid(alpha=0.3)
    ax.legend()
    return plots.save(fig, path)
