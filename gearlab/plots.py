"""Figures (matplotlib, no display needed): the drawing the kinds and front-ends share (save, the
TVMS and signal plots of `gearlab stiffness`/`simulate`, a gearlab.charts.Chart as a PNG). A kind's
own figures live with the kind (gearlab.kinds.<kind>_figures) and are written through save.

A figure is drawn in memory and written whole (save): inside a run directory through
gearlab.confined (no link followed, a fresh temporary name), elsewhere (a file named on the
command line) by atomic rename.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import matplotlib

from .confined import Confined, write_file
from .events import figure_written
from .gearbox.simulation import label as preset_label
from .signals import spectrum

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

Target = Path | Confined  # where a figure goes: a run directory's file, or one the user named


def target(path) -> Target:
    """*path* as a Target: a run directory's file as it is, anything else as a Path."""
    return path if isinstance(path, Confined) else Path(path)


def save(fig, path: Target, dpi: int = 120, **options) -> Target:
    """Write *fig* as a PNG at *path* (rendered in memory, then written whole) and close it."""
    path = target(path)
    buf = io.BytesIO()
    try:
        options = {"bbox_inches": "tight", **options}
        fig.savefig(buf, format=(path.suffix or ".png")[1:], dpi=dpi, **options)
    finally:
        plt.close(fig)
    write_file(path, buf.getvalue())
    figure_written(path.name)  # the run in progress counts it (its 'report' stage)
    return path


def tvms_figure(
    curves: Sequence[tuple[str, np.ndarray, np.ndarray]],
    title: str,
    path: Path,
    window_deg: tuple[float, float] | None = None,
) -> Path:
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


def signal_and_spectrum(sim, path: Path, mesh_hz: float, start: int = 0, harmonics: int = 6) -> Path:
    """Steady acceleration signals and their spectra with mesh harmonics marked (Figures 2.34-2.39)."""
    names = list(sim.channels)
    fig, axes = plt.subplots(len(names), 2, figsize=(12, 2.6 * len(names)), squeeze=False, layout="constrained")
    t = sim.t[start:]
    show = t < t[0] + 3.0 / sim.speed_hz  # three input-shaft revolutions
    for row, name in zip(axes, names):
        x = sim.channels[name][start:]
        row[0].plot((t[show] - t[0]) * 1e3, x[show], lw=0.6)
        row[0].set_ylabel(f"{name} (m/s²)")
        row[0].set_xlabel("time in steady state (ms)")
        f, amp = spectrum(x, sim.fs)
        keep = f <= (harmonics + 0.5) * mesh_hz
        row[1].plot(f[keep], amp[keep], lw=0.6)
        for h in range(1, harmonics + 1):
            row[1].axvline(h * mesh_hz, color="tab:red", lw=0.6, ls="--", alpha=0.6)
        row[1].set_xlabel(f"frequency (Hz); dashed: mesh harmonics n × {mesh_hz:g} Hz")
        row[1].set_ylabel("amplitude (m/s²)")
        for ax in row:
            ax.grid(alpha=0.3)
    labels = ", ".join(f.label for f in sim.faults) or "healthy"
    fig.suptitle(f"{sim.model} ({preset_label(sim.preset)}), {labels}, {sim.speed_hz:g} Hz, {sim.load_nm:g} N·m")
    return save(fig, path)


def chart_figure(chart, path: Path) -> Path:
    """A gearlab.charts.Chart as a PNG (the comparison page draws the TUI's charts so):
    lines with ± bands, or horizontal bars for named categories."""
    curves = [c for c in chart.curves if len(c.y)]
    if chart.categories is not None:
        names = list(chart.categories)
        fig, ax = plt.subplots(figsize=(8, 0.45 * len(names) * max(len(curves), 1) + 1.5), layout="constrained")
        height = 0.8 / max(len(curves), 1)
        y = np.arange(len(names))
        for i, curve in enumerate(curves):
            ax.barh(
                y + i * height,
                [float(v) for v in curve.y],
                height,
                label=curve.label,
                xerr=None if curve.err is None else [float(v) for v in curve.err],
            )
        ax.set_yticks(y + height * (len(curves) - 1) / 2, names)
        ax.invert_yaxis()
        ax.set_xlabel(chart.ylabel)
        ax.grid(alpha=0.3, axis="x")
    else:
        fig, ax = plt.subplots(figsize=(9, 4.2), layout="constrained")
        # overlaid runs ('A: mmd', 'B: mmd'): one colour per series, one line style per run
        names = list(dict.fromkeys(c.label.split(": ", 1)[-1] for c in curves))
        runs = list(dict.fromkeys(c.label.split(": ", 1)[0] for c in curves if ": " in c.label))
        colours = plt.get_cmap("tab10").colors
        for curve in curves:
            x, yv = np.asarray(curve.x, dtype=float), np.asarray(curve.y, dtype=float)
            run, _, name = curve.label.rpartition(": ")
            style = ("-", "--", ":", "-.")[runs.index(run) % 4] if run in runs else "-"
            (line,) = ax.plot(
                x, yv, style, marker="o", ms=3, label=curve.label, color=colours[names.index(name) % len(colours)]
            )
            if curve.err is not None:
                err = np.asarray(curve.err, dtype=float)
                ax.fill_between(x, yv - err, yv + err, color=line.get_color(), alpha=0.15)
        if chart.xticks is not None:
            ax.set_xticks(list(chart.xticks))
        ax.set_xlabel(chart.xlabel)
        ax.set_ylabel(chart.ylabel)
        ax.grid(alpha=0.3)
    ax.set_title(chart.title, fontsize=9)
    ax.legend(fontsize=7)
    return save(fig, path)
