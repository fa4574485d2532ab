"""A detection run's verdict says where a threshold rests on the history's records differing (issue 39: on the
PHM 2009 rig the two history builds put the classical thresholds above the chips, and the run said only 'AUC 1.00,
0 / 0 %')."""

from html import escape

import pytest
from detection_scenario import FILES, run, scenario
from textrecords import record


def _history(tmp_path, noise: float):
    """The tiny scenario (detection_scenario) with its two history takes from one generator, at one start angle, the
    second at *noise* (the first at textrecords' 0.3)."""
    (tmp_path / "data").mkdir()
    record(tmp_path / "data" / "h1.zip", revolutions=40, seed=10, phase=0.0)
    record(tmp_path / "data" / "h2.zip", revolutions=40, seed=11, phase=0.0, noise=noise)
    assert [f[:2] for f in FILES[:2]] == [("h1", "history"), ("h2", "history")]
    return scenario(tmp_path, methods=("matched_filter",))


@pytest.mark.parametrize("noise, said", [(0.3, False), (0.6, True)])
def test_a_threshold_resting_on_two_takes_apart_is_said_with_its_numbers(cli, tmp_path, no_figures, noise, said):
    from gearlab.report import build_report
    from gearlab.verdict import verdict_lines

    out = run(cli, _history(tmp_path, noise), tmp_path / "runs")
    lines = verdict_lines(out)
    spread = [line for line in lines if "history records differ" in line]
    table, html = (out / "table.md").read_text(), build_report(out)
    if not said:  # two takes alike but for their noise: every threshold rests on the units' scatter
        assert spread == [], lines
        assert "history records differ" not in table + html
        return
    (line,) = spread
    # the noisier take's NA4 (a fourth moment over the other take's variance) lies far from the first's
    assert line.startswith("16 Hz: the 2 history records differ (record spread over the within-record spread: "), line
    ratio = float(line.split("within-record spread: ")[1].split("x na4")[0].split(", ")[-1])
    assert ratio > 3.0, line
    assert "add healthy takes of this condition (role history): 2 records measure it on 1 degree of freedom." in line
    assert f"- {line}\n" in table and escape(line) in html
    # beside its condition's line, after the methods' introduction (the per-take lines open the verdict)
    intro = next(i for i, x in enumerate(lines) if x.startswith("At record"))
    assert lines.index(line) == intro + 2
    # the model behind the line is the run's: its summary's row for NA4 at the verdict's unit
    import json

    from gearlab.kinds.detection_verdict import RECORD_SHARE, record_share

    summary = json.loads((out / "summary.json").read_text())
    (na4,) = [r for r in summary["rows"] if r["method"] == "na4" and r["unit"] == "record10"]
    model = na4["history_model"]
    assert record_share(model) > RECORD_SHARE and model["records"] == 2
    assert f"{model['record_sd'] / model['unit_sd']:.1f}x na4" in line
