"""The transfer kind's figures (gearlab.kinds.transfer; report.html): Figures 5.5/5.6 (accuracy
against k), 5.7 (training curves), 5.8 (confusion matrices) and 5.9 (latent maps), drawn from the
finished run's records, table and latent features. Imported when the report is drawn, not at start-up
(matplotlib)."""

from __future__ import annotations

import io

import numpy as np

from .. import plots
from ..confined import Confined, read_file
from ..events import figures_ahead
from ..plots import Target, plt


def draw(run_path: Target, records: list[dict], table: dict, ks) -> None:
    """Figures 5.5/5.6 (accuracy vs k), 5.7 (training curves), 5.8 (confusion), 5.9 (latent maps)."""
    run_path = plots.target(run_path)
    figures = run_path / "figures"
    curved = [r for r in records if r.get("history") and r["rep"] == 0 and r["history"].get("discrepancy")]
    latent_files = _files(run_path / "latent", "*.npz")
    figures_ahead(2 + bool(curved) + bool(latent_files))  # the run's 'report' stage counts i of n
    # accuracy against k with one-standard-deviation bands
    fig, ax = plt.subplots(figsize=(10, 4.5), layout="constrained")
    colours = plt.get_cmap("tab20").colors  # one colour per method, for up to 20 methods
    for i, (label, per_k) in enumerate(table.items()):
        xs = [k for k in ks if str(k) in per_k]
        mean = np.array([per_k[str(k)]["mean"] for k in xs])
        std = np.array([per_k[str(k)]["std"] for k in xs])
        style = "-" if "(supervised" in label else "--"  # as Figures 5.5/5.6
        (line,) = ax.plot(xs, mean, style, marker="o", ms=3, label=label, color=colours[i % len(colours)])
        ax.fill_between(xs, mean - std, mean + std, color=line.get_color(), alpha=0.15)
    ax.set_xticks(list(ks))
    ax.set_xlabel("fault samples in the target training set (k)")
    ax.set_ylabel("target test accuracy (%)")
    ax.set_ylim(0, 102)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    plots.save(fig, figures / "accuracy_vs_k.png")

    # training curves of the first repetition at the middle k (Figure 5.7)
    if curved:
        k_show = sorted({r["k"] for r in curved})[len({r["k"] for r in curved}) // 2]
        shown = [r for r in curved if r["k"] == k_show]
        fig, axes = plt.subplots(len(shown), 1, figsize=(8, 2.4 * len(shown)), squeeze=False, layout="constrained")
        for ax, r in zip(axes[:, 0], shown):
            h = r["history"]
            epochs = np.arange(len(h["val_acc"]))
            ax.plot(epochs, 100 * np.asarray(h["val_acc"]), label="source validation accuracy (%)")
            ax2 = ax.twinx()
            ax2.plot(epochs, h["discrepancy"], color="tab:red", lw=0.8, label="domain discrepancy")
            ax2.plot(epochs, h["lam"], color="tab:gray", lw=0.8, ls=":", label="lambda")
            if h["best_epoch"] >= 0:
                ax.axvline(h["best_epoch"], color="k", ls="--", lw=0.7)
            ax.set_title(f"{r['method']}, k = {k_show}: test accuracy {r['accuracy']:.1f} %", fontsize=9)
            ax.set_xlabel("epoch")
            ax.set_ylabel("accuracy (%)")
            ax2.set_ylabel("discrepancy, λ (1)")
        # one legend for every plot and both axes, under them: inside a plot it hid the curves, beside
        # one (at 1.08 of its width) it lay over the right axis's label and tick labels
        (h1, l1), (h2, l2) = ax.get_legend_handles_labels(), ax2.get_legend_handles_labels()
        fig.legend(h1 + h2, l1 + l2, loc="outside lower center", ncols=3, fontsize=8)
        plots.save(fig, figures / "training_curves.png")

    # confusion matrices at the smallest k, summed over repetitions (Figure 5.8)
    k0 = min(ks)
    methods = [m for m in table if any(r["method"] == m for r in records)]  # not a reference column (the bound)
    fig, axes = plt.subplots(1, len(methods), figsize=(2.6 * len(methods), 2.8), squeeze=False, layout="constrained")
    for ax, label in zip(axes[0], methods):
        cm = np.zeros((2, 2), dtype=int)
        for r in records:
            if r["method"] == label and r["k"] == k0:
                cm += np.asarray(r["confusion"])
        ax.imshow(cm, cmap="Blues", vmin=0)  # from 0: the text colour below follows the cell's shade
        for (a, b), v in np.ndenumerate(cm):
            dark = v > cm.max() / 2  # white on the dark cells, readable at the report's width
            ax.text(b, a, str(v), ha="center", va="center", fontsize=12, color="white" if dark else "black")
        ax.set_xticks([0, 1], ["healthy", "fault"])
        ax.set_yticks([0, 1], ["healthy", "fault"])
        ax.set_xlabel("predicted (count)")
        ax.set_title(label, fontsize=7)
    axes[0][0].set_ylabel("true")
    fig.suptitle(f"k = {k0}: counts summed over the repetitions", fontsize=9)
    plots.save(fig, figures / "confusion_k0.png")

    # latent feature maps after adaptation (Figure 5.9): a PCA of source and target training features
    if latent_files:
        fig, axes = plt.subplots(
            1, len(latent_files), figsize=(3.2 * len(latent_files), 3.2), squeeze=False, layout="constrained"
        )
        for ax, f in zip(axes[0], latent_files):
            with _npz(f) as d:
                zs, zt = d["source"], d["target"]
            z = np.concatenate([zs, zt])
            if not np.all(np.isfinite(z)):  # a diverged unit: say so rather than fail the whole report
                ax.set_title(f"{f.stem.replace('_', ' ')}\n(non-finite features: training diverged)", fontsize=7)
                continue
            p, collapsed = latent_projection(z)
            if p is None:
                ax.set_title(f"{f.stem.replace('_', ' ')}\n(features collapse to {collapsed}: no map)", fontsize=7)
                ax.set_axis_off()
                continue
            # colour: domain; marker: class, where the unit stored the labels (healthy o, fault x)
            labels = _latent_labels(f)
            for (lo, hi), domain, colour in (
                ((0, len(zs)), "source", "tab:blue"),
                ((len(zs), len(z)), "target", "tab:orange"),
            ):
                cls = labels[0 if domain == "source" else 1]
                if cls is None:
                    ax.scatter(p[lo:hi, 0], p[lo:hi, 1], s=4, alpha=0.6, color=colour, label=domain)
                    continue
                for c, marker, name in ((0, "o", "healthy"), (1, "x", "fault")):
                    keep = np.flatnonzero(np.asarray(cls) == c) + lo
                    ax.scatter(
                        p[keep, 0], p[keep, 1], s=6, alpha=0.6, color=colour, marker=marker, label=f"{domain} {name}"
                    )
            ax.set_title(f.stem.replace("_", " "), fontsize=7)
            ax.set_xlabel("PC 1 (1)", fontsize=7)
            ax.set_ylabel("PC 2 (1)", fontsize=7)
            ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(0.0, -0.18), ncol=2)
        plots.save(fig, figures / "latent_maps.png")


def latent_projection(z: np.ndarray) -> tuple[np.ndarray | None, str]:
    """The first two principal components of features *z* (rows), or (None, "a point"/"a line")
    when they collapse: a PCA of features on a point or a line (a detector's one score, a
    saturated layer) is rounding noise drawn at axes of 1e-15, so no map is drawn of it."""
    from threadpoolctl import threadpool_limits

    z = z - z.mean(0)
    # one BLAS thread: a 240 x 256 SVD took 0.04 s on one, 0.3-3 s with its threads contending on a busy
    # two-core machine (a quick run's four latent maps were 11 s of its report stage)
    with threadpool_limits(1, user_api="blas"):
        sv, vt = np.linalg.svd(z, full_matrices=False)[1:]
    scale = 1e-9 * max(1.0, float(np.abs(z).max(initial=0.0)))
    if sv.size == 0 or sv[0] <= scale:
        return None, "a point"
    if sv.size < 2 or sv[1] <= 1e-6 * sv[0]:
        return None, "a line"
    return z @ vt[:2].T, ""


def _files(folder: Target, pattern: str) -> list:
    if isinstance(folder, Confined):
        return folder.files(pattern)
    return sorted(folder.glob(pattern)) if folder.is_dir() else []


def _npz(path: Target):
    """An .npz opened without pickle, its bytes read through the run directory."""
    return np.load(io.BytesIO(read_file(path)), allow_pickle=False)


def _latent_labels(path: Target) -> list:
    """The class labels (0 healthy, 1 fault) stored beside a latent map, or None per domain."""
    with _npz(path) as d:
        return [d["source_label"] if "source_label" in d else None, d["target_label"] if "target_label" in d else None]
