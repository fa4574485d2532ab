"""Issue 41, a transfer report's training curves (thesis Figure 5.7): the legend stays clear of the
curves and of both axes' labels. Beside each plot at 1.08 of its width, it lay over the right
axis's label 'discrepancy, λ (1)' and its tick labels (quick.toml's report, Chromium screenshot)."""

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

from gearlab import plots
from gearlab.kinds import dataset_figures, transfer_figures


def test_the_training_curves_legend_covers_no_axis_label_or_curve(tmp_path, monkeypatch):
    kept = {}
    monkeypatch.setattr(plots, "save", lambda fig, path, **o: kept.setdefault(path.name, fig))
    history = {
        "val_acc": list(np.linspace(0.8, 0.9, 30)),
        "discrepancy": [0.2] * 30,
        "lam": list(np.linspace(0, 1, 30)),
    }
    records = [
        {
            "rep": 0,
            "k": 4,
            "method": m,
            "accuracy": 88.3,
            "confusion": [[5, 1], [2, 4]],
            "history": {**history, "best_epoch": 20},
        }
        for m in ("mmd (unsupervised)", "dann (unsupervised)")
    ]
    table = {m: {"4": {"mean": 88.3, "std": 0.0}} for m in ("mmd (unsupervised)", "dann (unsupervised)")}
    transfer_figures.draw(tmp_path, records, table, [4])
    fig = kept["training_curves.png"]
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    legends = [*fig.legends, *(a.get_legend() for a in fig.axes if a.get_legend() is not None)]
    assert legends
    boxes = [legend.get_window_extent(renderer) for legend in legends]
    for ax in fig.axes:
        texts = [ax.yaxis.label, ax.xaxis.label, *ax.get_yticklabels(), *ax.get_xticklabels()]
        for text in (t for t in texts if t.get_visible() and t.get_text()):
            assert not any(box.overlaps(text.get_window_extent(renderer)) for box in boxes), text.get_text()
        assert not any(box.overlaps(ax.get_window_extent(renderer)) for box in boxes)  # nor the curves
    for box in boxes:  # on the canvas
        assert box.x0 >= 0 and box.y0 >= 0 and box.x1 <= fig.bbox.x1 and box.y1 <= fig.bbox.y1


def test_the_dataset_figures_legends_and_labels_cover_no_curve_title_or_label(monkeypatch):
    """A dataset run's figure (thesis Figures 2.34-2.39) put each panel's legend over its curves (the
    spectrum's over the top of the order-175 line) and the spectrum's 'amplitude (standardised, 1)'
    ran into the figure's title (tests/tui_scenarios/tdata.toml's report)."""
    from test_noise_study import small_spec, synthetic

    kept = []
    monkeypatch.setattr(plots, "save", lambda fig, path, **o: kept.append(fig))
    dataset_figures.dataset_signals(synthetic(small_spec(teeth=(5,))), Path("signals.png"))
    (fig,) = kept
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    title = fig._suptitle.get_window_extent(renderer)
    boxes = [a.get_legend().get_window_extent(renderer) for a in fig.axes if a.get_legend() is not None]
    assert boxes
    for ax in fig.axes:
        assert not any(box.overlaps(ax.get_window_extent(renderer)) for box in boxes), ax.get_ylabel()
        for text in (ax.yaxis.label, ax.xaxis.label, *ax.get_yticklabels(), *ax.get_xticklabels()):
            if text.get_visible() and text.get_text():
                extent = text.get_window_extent(renderer)
                assert not any(box.overlaps(extent) for box in boxes), text.get_text()
                assert not title.overlaps(extent.expanded(1, 1).padded(-1)), text.get_text()  # 1 pixel: a touch
