"""The gap_benchmark kind's figure (gearlab.kinds.gap_benchmark; report.html): how often each
hidden effect is named, and every trial's gap before and after. Imported when the report is
drawn, not at start-up (matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import plots
from ..plots import plt

# the colour of each trial kind's points
COLOURS = {"single": "C0", "pair": "C1", "null": "C2", "withheld": "C3", "suborder": "C4"}


def draw(figures, summary: Mapping, records: list[dict]) -> None:
    """Per-effect identification and the gap before/after of every trial (PNG in the folder *figures*)."""
    figures = plots.target(figures)
    names = list(summary["per_effect"])
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    x = np.arange(len(names))
    for offset, key, label in ((-0.2, "top1", "top-1"), (0.2, "top3", "top-3")):
        axes[0].bar(x + offset, [100 * (summary["per_effect"][n][key] or 0) for n in names], 0.4, label=label)
    axes[0].set_xticks(x, names, rotation=60, ha="right", fontsize=8)
    axes[0].set_ylabel("identified (%)")
    axes[0].set_title("identification per hidden effect")
    axes[0].legend()
    for kind, colour in COLOURS.items():
        mine = [r for r in records if r["kind"] == kind and r["gap_before"] > 0 and r["gap_after"] == r["gap_after"]]
        axes[1].scatter(
            [r["gap_before"] for r in mine], [max(r["gap_after"], 1e-3) for r in mine], c=colour, label=kind, s=18
        )
    axes[1].set_xscale("log")
    axes[1].set_yscale("log")
    lims = axes[1].get_xlim()
    axes[1].plot(lims, lims, "k:", lw=0.8)
    axes[1].set_xlabel("gap before")
    axes[1].set_ylabel("gap after (corrected source)")
    axes[1].set_title("gap before / after, per trial")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    plots.save(fig, figures / "gap_benchmark.png", dpi=90, bbox_inches=None)
