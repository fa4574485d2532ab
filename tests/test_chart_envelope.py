"""A terminal chart of many points is drawn from their envelope (gearlab.charts.envelope): each of a few hundred
spans of x keeps its first, lowest, highest and last point. `gearlab inspect`'s order spectrum gave plotext every
n-th of its points (up to 8,000: 80-90 ms a chart), and a line one bin wide between them was not drawn."""

from __future__ import annotations

import numpy as np
from textrecords import FS, signals

from gearlab.charts import envelope


def test_each_span_keeps_its_ends_its_lowest_and_its_highest_point():
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.uniform(0.5, 1.5, 20_000))
    y = rng.standard_normal(x.size)
    ex, ey = envelope(x, y, 100)
    assert 300 < ex.size <= 400 and np.all(np.diff(ex) > 0)
    assert (ex[0], ex[-1]) == (x[0], x[-1])
    edges = np.linspace(x[0], x[-1], 101)
    spans = np.searchsorted(edges[1:-1], x, side="right")  # each point's span
    kept = set(ex.tolist())
    for k in range(100):
        inside = np.flatnonzero(spans == k)
        assert {x[inside[0]], x[inside[-1]], x[inside[np.argmin(y[inside])]], x[inside[np.argmax(y[inside])]]} <= kept
    assert set(zip(ex.tolist(), ey.tolist())) <= set(zip(x.tolist(), y.tolist()))  # points of the line, not made up
    few = envelope(x[:400], y[:400], 100)  # no more than the chart can tell apart: all of them
    assert few[0].size == 400


def test_inspect_draws_a_line_one_bin_wide_among_thousands(tmp_path, monkeypatch):
    import io

    import plotext
    from rich.console import Console

    from gearlab.inspect import render
    from gearlab.notebook import inspect_recording

    vib, tacho = signals(revolutions=40)
    path = tmp_path / "take.csv"
    t = np.arange(vib.size) / FS
    path.write_text("time_s,acc,tacho\n" + "".join(f"{a:.6f},{b:.6e},{c:.2f}\n" for a, b, c in zip(t, vib, tacho)))
    report = inspect_recording(path, vibration="acc", tacho="tacho")
    orders = np.linspace(0.0, report["max_order"], 20_001)[1:]  # 20,000 bins: the chart's every 5th before
    amp = np.full(orders.size, 1e-3)
    amp[12_347] = 1.0  # 0 dB, one bin wide
    report = report | {"spectrum": (orders, amp)}
    drawn = []
    monkeypatch.setattr(plotext, "plot", lambda x, y, **kw: drawn.append((x, y)))
    render(report, Console(file=io.StringIO(), width=100))
    ((x, y),) = drawn
    assert len(x) <= 800 and max(y) == 0.0 and x[int(np.argmax(y))] == orders[12_347]
