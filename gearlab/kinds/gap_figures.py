"""The gap kind's figures (gearlab.kinds.gap; report.html): where the gap lies, which effect
closes it, how far the accuracy moves. Imported when the report is drawn, not at start-up
(matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .. import plots
from ..events import figures_ahead
from ..plots import plt


def draw(figures: Path, summary: Mapping) -> None:
    """The gap diagnosis's figures: per-view gap before/after with bootstrap intervals, the
    effect ranking (share of the gap each candidate removes alone), accuracy before/after."""
    figures = plots.target(figures)
    views = summary["views"]
    figures_ahead(bool(views) + bool(summary.get("ranking")) + bool(summary.get("accuracy")))
    if views:  # none: a structure difference, no gap measured
        _per_view(figures, summary, views)

    ranking = summary.get("ranking") or []
    if ranking:
        accepted = {e["name"] for e in summary.get("effects", [])}
        fig, ax = plt.subplots(figsize=(7, 0.35 * len(ranking) + 1.2), layout="constrained")
        labels = [r["name"] for r in ranking][::-1]
        shares = [100 * r["share_removed"] for r in ranking][::-1]
        ax.barh(labels, shares, color=["tab:blue" if n in accepted else "tab:gray" for n in labels])
        ax.axvline(0, color="k", lw=0.6)
        ax.set_xlabel("share of the gap removed when added alone (%)")
        verdict = "unexplained" if summary.get("unexplained") else "accepted in blue"
        ax.set_title(f"which effect: ranking of the candidates ({verdict})", fontsize=9)
        ax.grid(alpha=0.3, axis="x")
        plots.save(fig, figures / "gap_effect_ranking.png")

    acc = summary.get("accuracy")
    if acc:
        labels = list(acc)
        fig, ax = plt.subplots(figsize=(1.6 * len(labels) + 2, 3.6), layout="constrained")
        colours = ["tab:red" if "uncorrected" in n else "tab:green" if "corrected" in n else "tab:gray" for n in labels]
        ax.bar(
            range(len(labels)),
            [acc[n]["mean"] for n in labels],
            yerr=[acc[n]["std"] for n in labels],
            capsize=3,
            color=colours,
        )
        ax.set_xticks(range(len(labels)), labels, rotation=15, fontsize=8)
        ax.set_ylabel("target test accuracy (%)")
        ax.set_ylim(0, 102)
        ax.set_title("how far: target fault detection (k = 0) before and after correcting the simulator", fontsize=9)
        ax.grid(alpha=0.3, axis="y")
        plots.save(fig, figures / "gap_accuracy.png")


def _per_view(figures: Path, summary: Mapping, views: Mapping) -> None:
    """Where the gap lies: per-view gap before/after, with the bootstrap intervals where the report has them."""
    names = list(views)
    x = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(9, 3.8), layout="constrained")
    for offset, when, colour in ((-0.2, "before", "tab:red"), (0.2, "after", "tab:green")):
        gaps = np.array([views[n][f"gap_{when}"] or 0.0 for n in names], dtype=float)
        # asymmetric error bars from the percentile intervals, where the report has them
        err = np.zeros((2, len(names)))
        for i, n in enumerate(names):
            iv = views[n].get(f"gap_{when}_interval")
            if iv:
                err[:, i] = max(gaps[i] - iv[0], 0.0), max(iv[1] - gaps[i], 0.0)
        ax.bar(
            x + offset,
            gaps,
            0.4,
            yerr=err,
            capsize=2,
            color=colour,
            alpha=0.8,
            label=f"{when} (total {summary[f'gap_{when}']:.3g})",
        )
    ax.set_xticks(x, names, rotation=20)
    ax.set_ylabel("gap (sum of squared effect sizes, 1)")
    # the gap of a broad change (noise) can be orders of magnitude above the others
    if any((views[n]["gap_before"] or 0) > 0 for n in names):
        ax.set_yscale("symlog", linthresh=1.0)
    ax.set_title("where the gap lies: per-view gap of the healthy revolutions, before and after correction")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    plots.save(fig, figures / "gap_per_view.png")
