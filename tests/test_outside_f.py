"""An outside user's leftovers, third look (issue 39, "How it will be checked"; what helpers D and E found in
D's project folder and box Q): the TUI's tree, the TUI's score trend, the gap's speed note. Small data made here."""

from __future__ import annotations

from pathlib import Path


def test_tui_lists_a_run_s_scenario_copies_as_that_run_not_as_scenarios(tmp_path):
    # `gearlab tui .` in D's project: runs/<name>/<stamp>/scenario.toml and scenario.original.toml were two
    # more scenarios per run in the tree, beside the scenario whose run they are
    from gearlab.tui.catalog import scan

    (tmp_path / "mine.toml").write_text('[scenario]\nname = "mine"\nkind = "dataset"\n')
    run = tmp_path / "runs" / "mine" / "20261204-205137-096097"
    run.mkdir(parents=True)
    for name in ("scenario.toml", "scenario.original.toml"):
        (run / name).write_text('[scenario]\nname = "mine"\nkind = "dataset"\n')
    (run / "run.json").write_text("{}")
    listed = [e.path.relative_to(tmp_path) for e in scan(tmp_path, tmp_path)]
    assert listed == [Path("mine.toml")], listed
    # the TUI opened on the run directory itself still shows what is there
    assert [e.path.name for e in scan(run, tmp_path)] == ["scenario.original.toml", "scenario.toml"]


def test_tui_score_trend_draws_its_zero_line_in_view(monkeypatch):
    # the report's PNG draws the threshold's zero line; the TUI's trend drew none, and a trend all above
    # 0 (every record called) was scaled off it
    import plotext

    from gearlab.kinds import detection_scoring
    from gearlab.tui.widgets import ChartView

    rows = [
        {"condition": "28 Hz", "unit": "revolution", "method": "fm4", "median_score": s, "threshold": 1.0}
        | {"file": f"week{i}.npz", "decision": "fault"}
        for i, s in enumerate((1.3, 1.6, 2.0), 1)
    ]
    monkeypatch.setattr(detection_scoring.scoring, "read_history", lambda run: rows)
    (chart,) = detection_scoring.score_trends(None)
    assert 0.0 in chart.hlines
    drawn, limits = [], []
    monkeypatch.setattr(plotext, "hline", lambda y, *a, **k: drawn.append(y))
    real_ylim = plotext.ylim
    monkeypatch.setattr(plotext, "ylim", lambda lo=None, hi=None, **k: limits.append((lo, hi)) or real_ylim(lo, hi))
    ChartView()._draw(chart, [c for c in chart.curves if len(c.y)], chart.title, 100)
    assert drawn == [0.0]
    assert limits and limits[-1][0] < 0 < limits[-1][1]
