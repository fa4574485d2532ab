"""Figures (matplotlib, no display needed)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def save(fig, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=120, bbox_inches="tight")
    plt.close(fig)
    tmp.replace(path)
    return path


def tvms_figure(curves: Sequence[tuple[str, np.ndarray, np.ndarray]], title: str, path: Path,
                window_deg: tuple[float, float] | None = None) -> Path:
    """TVMS against pinion angle, one line per (label, theta_rad, k) curve (Figure 2.33 style)."""
    fig, ax = plt.subplots(figsize=(9, 3.8))
    for label, theta, k in curves:
        ax.plot(np.degrees(theta), k / 1e8, lw=1.0, label=label)
    ax.set_xlabel("pinion angle (deg)")
    ax.set_ylabel("mesh stiffness (1e8 N/m)")
    ax.set_title(title)
    if window_deg:
        ax.set_xlim(*window_deg)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return save(fig, path)


def ladder_grid(panels: Mapping[str, Sequence[tuple[int, np.ndarray, np.ndarray]]], path: Path,
                window_deg: tuple[float, float] | None = None, title: str = "") -> Path:
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
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    sm = plt.cm.ScalarMappable(cmap="viridis", norm=plt.Normalize(1, 20))
    fig.colorbar(sm, ax=axes, label="intensity step", shrink=0.8)
    if title:
        fig.suptitle(title)
    return save(fig, path)


def rfa_curves(curves: Mapping[str, tuple[Sequence[int], Sequence[float]]], path: Path) -> Path:
    """Figure 2.32: relative fault area against intensity step per fault type."""
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for name, (steps, rfa) in curves.items():
        ax.plot(steps, rfa, marker="o", ms=3, label=name)
    ax.set_xlabel("intensity step")
    ax.set_ylabel("relative fault area")
    ax.set_ylim(-0.02, 1.05)
    ax.grid(alpha=0.3)
    ax.legend()
    return save(fig, path)
