"""`gearlab score RUN a.zip far.zip` (issue 39, docs/your_gearbox.md step 7): a folder of takes, one of them at
another speed than the run's history (over 5 % off every condition's). The whole batch was refused (exit 2, nothing
scored) for that one take; now the takes that can be scored are, the one that cannot is named with why, the exit
code (2) says not every take was, and the scoring history and its trend hold the scored takes only, saying which
were not. One take alone is refused as before, in one line."""

from __future__ import annotations

import json

import pytest
from detection_scenario import scenario, shared_run
from textrecords import signals, text, write_zip

from gearlab.kinds import detection_scoring
from gearlab.parts import scoring
from gearlab.runs import RunDir

FAR = "its speed read as 17.60 Hz is more than 5% from every condition's"  # and its lines not the run's gearbox's


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    """The tiny detection run (16 Hz history) and new takes: two at its speed, two 10 % faster."""
    folder = tmp_path_factory.mktemp("batch")
    out = shared_run(scenario(folder, methods=("matched_filter",)), folder / "runs")
    takes = {}
    for name, seed, speed in (("near", 11, 16.0), ("near2", 12, 16.0), ("far", 13, 17.6), ("far2", 14, 17.6)):
        vib, tacho = signals(revolutions=40, seed=seed, phase=0.3, speed=speed)
        takes[name] = str(write_zip(folder / f"{name}.zip", text(vib, tacho)))
    return out, takes


def _refused(cli, out, take: str) -> str:
    """The one line `gearlab score` refuses *take* alone with (exit 2), without its 'error: FILE: '."""
    code, _, err = cli("score", out, take)
    assert code == 2 and err.startswith(f"error: {take}: ") and err.count("\n") == 1, err
    assert FAR in err, err
    return err.strip()[len(f"error: {take}: ") :]


def _history(out) -> tuple[list, list]:
    run = RunDir.open(out)
    return scoring.read_history(run), scoring.read_skipped(run)


def test_a_batch_scores_the_takes_it_can_and_names_the_one_it_cannot(cli, made, quiet):
    out, takes = made
    before, _ = _history(out)
    why = _refused(cli, out, takes["far"])
    code, stdout, err = cli("score", out, takes["near"], takes["far"])
    assert code == 2, err  # not every take was scored
    assert f"{takes['far']}: not scored: {why}" in stdout, stdout  # as it is refused alone
    assert f"{takes['near']}: 16.0" in stdout and "matched_filter" in stdout, stdout  # the near take's table
    assert err.strip() == f"error: 1 of 2 takes not scored (each said above): {takes['far']}", err
    history, skipped = _history(out)
    assert {r["file"] for r in history[len(before) :]} == {takes["near"]}  # the scored take only
    assert [(r["file"], r["decision"]) for r in skipped] == [(takes["far"], "not scored")], skipped
    (chart,) = detection_scoring.score_trends(RunDir.open(out))
    assert f"\nnot scored: far.zip: {why.split('; ')[0]}" in chart.title, chart.title
    assert "far.zip" not in chart.title.split("records: ")[1].split("\n")[0]  # no point of the trend


def test_the_json_rows_name_the_take_not_scored_with_why(cli, made, quiet):
    out, takes = made
    code, stdout, err = cli("score", out, takes["far2"], takes["near2"], "--json")
    assert code == 2, err
    rows = json.loads(stdout)
    assert rows[0]["file"] == takes["far2"] and rows[0]["decision"] == "not scored", rows[0]  # in the order given
    assert rows[0]["skipped"] == _refused(cli, out, takes["far2"]), rows[0]
    assert {r["file"] for r in rows[1:]} == {takes["near2"]} and all(r["method"] for r in rows[1:])


def test_one_take_far_off_or_every_take_far_off_is_refused_in_one_line_nothing_written(cli, made, quiet):
    out, takes = made
    before = _history(out)
    why = [_refused(cli, out, takes[k]) for k in ("far", "far2")]  # one line each (_refused)
    code, stdout, err = cli("score", out, takes["far"], takes["far2"])
    names = f"{takes['far']}, {takes['far2']}"
    assert code == 2 and err.startswith(f"error: none of the 2 takes scored ({names}); {takes['far']}: "), err
    assert err.count("\n") == 1 and why[0][:200] in err, err  # the first one's why (a line is 600 characters at most)
    assert _history(out) == before  # nothing scored, nothing written


def test_the_tui_shows_a_partly_scored_batch_as_scored_in_part_with_its_trend(made, monkeypatch, tmp_path):
    # s in the TUI read exit 2 as "failed" and kept the old chart, though the takes it could score were scored.
    # `gearlab score` as the TUI starts it runs in this process (test_tui.in_process; test_outside_j's s starts the
    # real child): the child imported torch and scipy again, 4.8 s of CPU
    import asyncio

    from test_outside_j import scored_in_tui
    from test_tui import in_process

    from gearlab.tui import GearlabApp

    out, takes = made
    folder = out.parents[2]  # the scenario's runs are <cwd>/runs, as its [output] says nothing
    monkeypatch.chdir(folder)
    started = in_process(monkeypatch, tmp_path)

    async def main():
        async with GearlabApp(folder / "scenarios").run_test(size=(160, 45)) as pilot:
            app = pilot.app
            status = await scored_in_tui(pilot, out, f"{takes['near']} {takes['far']}")
            assert started == [["score", str(out), takes["near"], takes["far"]]]
            assert status.startswith("scored in part: error: 1 of 2 takes not scored"), status
            title = str(app.charts[app.chart_index].title)
            assert "near.zip" in title and "not scored: far.zip" in title, title

    asyncio.run(main())
