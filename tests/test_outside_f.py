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
    monkeypatch.setattr(detection_scoring.scoring, "read_skipped", lambda run: [])  # no take refused
    (chart,) = detection_scoring.score_trends(None)
    assert 0.0 in chart.hlines
    drawn, limits = [], []
    monkeypatch.setattr(plotext, "hline", lambda y, *a, **k: drawn.append(y))
    real_ylim = plotext.ylim
    monkeypatch.setattr(plotext, "ylim", lambda lo=None, hi=None, **k: limits.append((lo, hi)) or real_ylim(lo, hi))
    ChartView()._draw(chart, [c for c in chart.curves if len(c.y)], chart.title, 100)
    assert drawn == [0.0]
    assert limits and limits[-1][0] < 0 < limits[-1][1]


def test_gap_note_and_verdict_agree_on_a_speed_read_off_the_mesh_lines(cli, tmp_path, monkeypatch, no_figures):
    # box Q's history at 41 Hz under a 28 Hz description, no tacho and no [target] speed: the note said 'the source
    # simulates that speed' (41 Hz), the verdict 'speed 41 Hz ... or a 40-tooth pinion at 27.67 Hz: check the tooth
    # count'. Both now say it is ambiguous and to declare the records' speed
    from test_outside_e import BOX_Q, _box_q_take

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "boxQ.toml").write_text(BOX_Q.replace('speed = "28 Hz"', 'speed = "28 Hz"\nload = "15 N*m"'))
    for seed in (1, 2):
        _box_q_take(tmp_path / f"q{seed}.npz", seed, speed=41.0, seconds=6.0)
    (tmp_path / "gap.toml").write_text(
        '[scenario]\nname = "q41"\nkind = "gap"\n[source]\ngearbox = "boxQ.toml"\n[target]\nvibration = "acc"\n'
        'files = [\n  { file = "q1.npz", role = "history", label = "healthy" },\n'
        '  { file = "q2.npz", role = "history", label = "healthy" },\n]\n'
        '[diagnosis]\ncandidates = ["sensor_noise"]\n[accuracy]\nenabled = false\n'
    )
    code, stdout, err = cli("run", tmp_path / "gap.toml", "--out", tmp_path / "runs")
    assert code == 0, err
    said = stdout + err
    assert "structure differs" in said and "ambiguous" in said, said[-2000:]
    assert "the source simulates that speed, right if the pinion has the described 27 teeth" in said, said[-2000:]
    assert said.count("declare the records' speed ([target] speed)") >= 2
    # a speed a motor's slip off the described one is no other tooth count: the note stays plain
    from gearlab.gap.structure import speed_line
    from gearlab.kinds.gap_inputs import mesh_speed_note

    assert mesh_speed_note(28.3, 28.0, 27) == "the source simulates that speed"
    assert "check the tooth count" not in speed_line(40.998, 28.0, 27)
