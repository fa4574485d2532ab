"""The dataset kind's figures (gearlab.kinds.dataset; report.html): a labelled dataset's revolutions
and order spectra per class (thesis Figures 2.34-2.39), an unlabelled recording's views. Imported
when the report is drawn, not at start-up (matplotlib)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import plots
from ..charts import dataset_examples
from ..gearbox.simulation import label as preset_label
from ..plots import plt
from ..signals import order_spectrum


def dataset_signals(dataset, path: Path, tooth: int = 5) -> Path:
    """Per class: revolutions at low, middle and top intensity, and their order spectra (an
    unlabelled recording has no class: recording_signals)."""
    names = dataset.spec.class_names
    fig, axes = plt.subplots(len(names), 2, figsize=(12, 2.3 * len(names)), squeeze=False, layout="constrained")
    angle = np.arange(dataset.X.shape[1]) * 360.0 / dataset.X.shape[1]
    examples = dataset_examples(dataset, tooth)
    for c, label, i in examples:
        row = axes[c]
        row[0].plot(angle, dataset.X[i], lw=0.5, label=label)
        orders, amp = order_spectrum(dataset.X[i])
        keep = orders <= 200
        row[1].plot(orders[keep], amp[keep], lw=0.6, label=label)
    for c, (name, row) in enumerate(zip(names, axes)):
        row[0].set_ylabel(f"{name}\n(standardised, 1)")
        row[0].set_xlabel("input-shaft angle (deg)")
        row[1].set_xlabel("shaft order (per revolution)")
        row[1].set_ylabel("amplitude\n(standardised, 1)")  # on one line it ran into the title
        for ax in row:
            ax.grid(alpha=0.3)
        if any(e[0] == c for e in examples):  # one legend a row, beside it: inside, it lay over the curves
            row[1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    spec = dataset.spec
    origin = (
        f"{spec.model} ({preset_label(spec.preset)}), {spec.channel}"
        if hasattr(spec, "model")
        else f"measured: {Path(spec.path).name}, {spec.vibration}"
    )
    fig.suptitle(f"dataset {spec.name}: {origin}")
    return plots.save(fig, path)


def recording_signals(charts, title: str, path: Path) -> Path:
    """An unlabelled recording's views (dataset.recording_views): its revolutions,
    their synchronous average with the revolutions' spread, and order spectra, one panel each."""
    fig, axes = plt.subplots(3, 1, figsize=(12, 8), layout="constrained")
    for ax, chart in zip(axes, charts):
        for curve in chart.curves:
            ax.plot(curve.x, curve.y, lw=0.6, label=curve.label)
            if curve.err is not None:
                y, e = np.asarray(curve.y), np.asarray(curve.err)
                ax.fill_between(curve.x, y - e, y + e, alpha=0.2, lw=0)
        ax.set_title(chart.title, fontsize=9)
        ax.set_xlabel(chart.xlabel)
        ax.set_ylabel(chart.ylabel)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_yscale("log")
    fig.suptitle(title)
    return plots.save(fig, path)
