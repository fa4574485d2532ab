"""The noise study's figures (gearlab.kinds.noise_study; report.html): thesis Figures 4.4-4.6, one
row per noise type and one column per variant (noisy, TSA). Imported when the report is drawn, not
at start-up (matplotlib)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .. import plots
from ..events import figures_ahead
from ..plots import plt

# Figure 4.4's colours: crack red, chip blue, spall yellow, pit purple; all faults black, as-healthy green.
FAULT_COLOURS = {"crack": "tab:red", "chip": "tab:blue", "spall": "goldenrod", "pit": "tab:purple"}
VARIANT_TITLES = {"noisy": "noisy", "tsa": "TSA"}


def _band(ax, x, mean, std, **style):
    mean = np.array(mean, dtype=float)
    std = np.nan_to_num(np.array(std, dtype=float))
    (line,) = ax.plot(x, mean, marker="o", ms=2.5, lw=1.1, **style)
    ax.fill_between(x, mean - std, mean + std, color=line.get_color(), alpha=0.15, lw=0)


def _study_grid(results: Mapping[str, Mapping[str, dict]], width: float = 5.2, height: float = 3.4):
    """One row per noise type, one column per variant (noisy left, TSA right, as in Figures 4.4-4.6)."""
    variants = [v for v in VARIANT_TITLES if any(v in r for r in results.values())]
    fig, axes = plt.subplots(
        len(results),
        len(variants),
        figsize=(width * len(variants), height * len(results)),
        squeeze=False,
        layout="constrained",
    )
    panels = [
        (ax, noise, v, results[noise].get(v)) for row, noise in zip(axes, results) for ax, v in zip(row, variants)
    ]
    return fig, panels


def _study_title(noise: str, variant: str, stats: dict) -> str:
    acc = stats["accuracy"]
    runs = f"{stats['runs']} run{'s' if stats['runs'] != 1 else ''}"
    return f"{noise}, {VARIANT_TITLES[variant]}: {acc['mean']:.1f} ± {acc['std']:.1f} % ({runs})"


def draw(figures: Path, results: Mapping[str, Mapping[str, dict]]) -> None:
    """Figures 4.4 (accuracy per fault type against intensity step, with the fault-as-healthy
    share), 4.5 (against relative fault area, up to 50 %) and 4.6 (confusion matrices compiled
    over runs). *results*: {noise: {variant: learn.noise_study.aggregate(...)}}."""
    figures = plots.target(figures)
    results = {n: r for n, r in results.items() if any(v in r for v in VARIANT_TITLES)}
    if not results:
        return
    figures_ahead(3)

    fig, panels = _study_grid(results)
    for ax, noise, variant, stats in panels:
        if stats is None:
            ax.axis("off")
            continue
        for name in stats["classes"][1:]:  # the dataset's order (summary.json sorts its keys)
            c = stats["curves"][name]
            _band(ax, c["steps"], c["accuracy_mean"], c["accuracy_std"], color=FAULT_COLOURS.get(name), label=name)
        c = stats["curves"]["all"]
        _band(ax, c["steps"], c["accuracy_mean"], c["accuracy_std"], color="black", label="all faults")
        _band(
            ax,
            c["steps"],
            c["as_healthy_mean"],
            c["as_healthy_std"],
            color="tab:green",
            ls="--",
            label="faults predicted healthy",
        )
        ax.set_title(_study_title(noise, variant, stats), fontsize=9)
        ax.set_xlabel("fault intensity step (1 = no fault)")
        ax.set_ylabel("test samples (%)")
        ax.set_xticks([1, 5, 10, 15, 20])
        ax.set_xlim(0.5, 20.5)
        ax.set_ylim(-2, 102)
        ax.grid(alpha=0.3)
    fig.legend(*panels[0][0].get_legend_handles_labels(), loc="outside lower center", ncols=6, fontsize=8)
    plots.save(fig, figures / "accuracy_vs_intensity.png")

    fig, panels = _study_grid(results)
    for ax, noise, variant, stats in panels:
        if stats is None:
            ax.axis("off")
            continue
        for name in stats["classes"][1:]:
            c = stats["curves"][name]
            rfa = 100.0 * np.asarray(c["rfa"], dtype=float)
            keep = rfa <= 50.0  # as Figure 4.5: the broken-tooth end of the crack ladder is left out
            _band(
                ax,
                rfa[keep],
                np.asarray(c["accuracy_mean"], dtype=float)[keep],
                np.asarray(c["accuracy_std"], dtype=float)[keep],
                color=FAULT_COLOURS.get(name),
                label=name,
            )
        ax.set_title(_study_title(noise, variant, stats), fontsize=9)
        ax.set_xlabel("relative fault area (%)")
        ax.set_ylabel("test accuracy (%)")
        ax.set_xlim(-1, 51)
        ax.set_ylim(-2, 102)
        ax.grid(alpha=0.3)
    fig.legend(*panels[0][0].get_legend_handles_labels(), loc="outside lower center", ncols=4, fontsize=8)
    plots.save(fig, figures / "accuracy_vs_rfa.png")

    fig, panels = _study_grid(results, width=3.6, height=3.4)
    for ax, noise, variant, stats in panels:
        if stats is None:
            ax.axis("off")
            continue
        cm = np.asarray(stats["confusion"])
        share = cm / np.maximum(cm.sum(axis=1, keepdims=True), 1)
        ax.imshow(share, cmap="Blues", vmin=0, vmax=1)
        for (a, b), v in np.ndenumerate(cm):
            ax.text(b, a, str(v), ha="center", va="center", fontsize=7, color="white" if share[a, b] > 0.6 else "black")
        ticks = range(len(stats["classes"]))
        ax.set_xticks(ticks, stats["classes"], fontsize=7, rotation=45)
        ax.set_yticks(ticks, stats["classes"], fontsize=7)
        ax.set_xlabel("predicted")
        ax.set_ylabel("true")
        ax.set_title(_study_title(noise, variant, stats), fontsize=8)
    plots.save(fig, figures / "confusion.png")
