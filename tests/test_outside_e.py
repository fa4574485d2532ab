"""An outside user's later steps, second look (issue 39, "How it will be checked"; helper D's box Q, a 27/61 + 18/49
reducer without a tacho, and box P's next weeks scored by `gearlab score`): what D left. The recordings are made
here, small, not D's."""

from __future__ import annotations

import json

from detection_scenario import run, scenario
from textrecords import record


def test_score_prints_the_files_in_the_order_given_not_grouped_by_condition(cli, tmp_path, monkeypatch, no_figures):
    # box P's weeks, given as week1 (28 Hz), week2 (41 Hz), week3 (28 Hz): printed week1, week3, week2
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "data").mkdir()
    files = []
    for i, (speed, role, label, chip) in enumerate(
        [(16.0, "history", "healthy", 0), (16.0, "history", "healthy", 0), (16.0, "test", "fault", 4.0)]
        + [(20.0, "history", "healthy", 0), (20.0, "history", "healthy", 0), (20.0, "test", "fault", 4.0)]
    ):
        name = f"r{i}"
        record(tmp_path / "data" / f"{name}.zip", revolutions=40, chip=chip, seed=i, phase=0.7 * i, speed=speed)
        files.append((name, role, label, chip))
    out = run(cli, scenario(tmp_path, files=files, methods=("source_only",)), tmp_path / "runs")
    weeks = []
    for week, speed in ((1, 16.0), (2, 20.0), (3, 16.0), (4, 20.0)):
        weeks.append(record(tmp_path / f"week{week}.zip", revolutions=40, seed=20 + week, speed=speed))
    code, stdout, err = cli("score", out, *weeks, "--json")
    assert code == 0, err
    order = list(dict.fromkeys(r["file"].rsplit("/", 1)[-1] for r in json.loads(stdout)))
    assert order == ["week1.zip", "week2.zip", "week3.zip", "week4.zip"], order
    code, stdout, err = cli("score", out, *weeks)
    assert code == 0, err
    said = [stdout.index(f"week{w}.zip: ") for w in (1, 2, 3, 4)]
    assert said == sorted(said), said


def test_the_report_s_score_trend_has_whole_number_ticks(tmp_path, monkeypatch):
    # box P's two weeks at 28 Hz: the report's PNG ticked its x axis at 1.0, 1.2, ... 2.0 (the TUI's: 1, 2);
    # a history more than 20 records long has no ticks given: whole numbers still
    from gearlab import plots
    from gearlab.charts import Chart, Curve
    from gearlab.kinds.detection_figures import score_trend

    drawn = []
    monkeypatch.setattr(plots, "save", lambda fig, path, **kw: drawn.append(fig) or path)
    two = Chart("28 Hz", "record", "score less threshold", (Curve("fm4", [1, 2], [-0.5, 0.4]),), xticks=[1, 2])
    long = Chart("41 Hz", "record", "score less threshold", (Curve("fm4", [1, 2.0, 3], [0.1, -0.2, 0.3]),))
    score_trend([two, long], tmp_path / "trend.png")
    (fig,) = drawn
    for ax in fig.axes:
        ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
        assert ticks and all(float(t).is_integer() for t in ticks), ticks
        assert any(list(line.get_ydata()) == [0.0, 0.0] for line in ax.get_lines())  # the zero line: called above
