"""The transfer_benchmark kind's figure (gearlab.kinds.transfer_benchmark; report.html): each
method's accuracy per random target beside the trial's Bayes bound, and its distance to the bound.
Imported when the report is drawn, not at start-up (matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import plots
from ..events import figures_ahead
from ..parts.bound import BOUND
from ..plots import plt


def draw(figures, summary: Mapping, close: float) -> None:
    """Accuracy per trial (methods and bound) and each method's distance to the bound, with a
    dotted line at *close* points (PNG in the folder *figures*)."""
    figures = plots.target(figures)
    figures_ahead(1)  # the run's 'report' stage counts i of n
    names = list(summary["trials"])
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2))
    x = np.arange(len(names))
    plain = [label for label in summary["methods"] if "corrected source" not in label]
    for label in summary["methods"]:
        # a method on the corrected source: its plain row's colour, an open square
        corrected = label not in plain
        i = plain.index(label.replace(", corrected source", "")) if corrected else plain.index(label)
        style = {"marker": "s", "mfc": "none"} if corrected else {"marker": "o"}
        y = [summary["trials"][n]["accuracy"].get(label, np.nan) for n in names]
        axes[0].plot(x, y, ls="none", ms=4, color=f"C{i}", label=label, **style)
    bound = [summary["trials"][n]["bound"] for n in names]
    axes[0].plot(x, [np.nan if b is None else b for b in bound], "k_", ms=12, label=BOUND)
    axes[0].set_xticks(x, [n.removeprefix("trial") for n in names], fontsize=7)
    axes[0].set_xlabel("trial")
    axes[0].set_ylabel("target test accuracy (%)")
    axes[0].set_title("accuracy per random target")
    gaps = [
        [
            t["bound"] - t["accuracy"][label]
            for t in summary["trials"].values()
            if t["bound"] is not None and label in t["accuracy"]
        ]
        for label in summary["methods"]
    ]
    ticks = [label.split(" ")[0] + (" corr." if "corrected source" in label else "") for label in summary["methods"]]
    axes[1].boxplot([g or [np.nan] for g in gaps], tick_labels=ticks)
    axes[1].tick_params(axis="x", labelrotation=45, labelsize=7)
    axes[1].axhline(close, color="k", ls=":", lw=0.8)
    axes[1].set_ylabel("points below the Bayes bound")
    axes[1].set_title("distance to the bound, trials with a bound")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, 0.17, 1, 1))
    plots.save(fig, figures / "transfer_benchmark.png", dpi=90, bbox_inches=None)
