"""An outside user's fifth look (issue 39, "How it will be checked"; helper J): the TUI in the user's own project
folder (`gearlab tui .` beside the gearbox description, the scenarios and their runs), the learned rows of a
detection scenario and `gearlab score` as the TUI and the report show it. The recordings are made here, small."""

from __future__ import annotations

import asyncio
from contextlib import asynccontextmanager

import pytest
from conftest import unrendered
from rich.console import Console
from test_outside_h import BOX_B as BOX_B_H
from test_tui import checked
from textual.widgets import Static

from gearlab.tui import GearlabApp

# test_outside_h's 25/52 + 16/81 box (a 4-mark tacho on its intermediate shaft), with a load to simulate
BOX_B = BOX_B_H.replace('speed = "25 Hz"', 'speed = "25 Hz"\nload = "40 N*m"')


def shown(app, selector: str, width: int = 200) -> str:
    """What a Static shows, as plain text at *width* columns (a str, a Text or a Group of tables)."""
    widget = app.query_one(selector, Static)
    console = Console(width=width, record=True, file=open("/dev/null", "w"))  # noqa: SIM115 - record only
    console.print(widget.content)
    return console.export_text()


@asynccontextmanager
async def results_shown(detection_run, size: tuple[int, int] = (160, 45)):
    """The TUI in the run's folder at *size*, the Results tab of the run as the tree lists it: its pilot."""
    folder, run = detection_run
    async with GearlabApp(folder).run_test(size=size) as pilot:
        await checked(pilot)
        (entry,) = [r for e in pilot.app.entries for r in e.runs if r.path == run]
        pilot.app.show_results(entry)
        await pilot.pause()
        yield pilot


async def settled(pilot, view, turns: int = 20) -> None:
    """Pauses until *view* is drawn at its width, at most *turns*: its Resize comes a refresh or more after the
    layout (a scrollbar, the sidebar folded), later on a busy machine."""
    for _ in range(turns):
        await pilot.pause()
        if view.drawn_at == view.content_size.width:
            return


def test_a_gearbox_description_beside_the_scenarios_is_listed_as_one(tmp_path, monkeypatch):
    # `gearlab tui .` in a project folder holding boxB.toml (the guide's step 1) beside its scenarios listed the
    # description in red as an invalid scenario, 'missing table [scenario] (with name, kind and description)'; a
    # description with a mistake said the same, not its mistake
    monkeypatch.chdir(tmp_path)
    (tmp_path / "boxB.toml").write_text(BOX_B)
    (tmp_path / "bad_box.toml").write_text(BOX_B.replace("pulses_per_rev = 4", "pulses_per_rev = 0"))

    async def main():
        async with GearlabApp(tmp_path).run_test(size=(160, 45)) as pilot:
            await checked(pilot)
            app = pilot.app
            good, bad = (next(e for e in app.entries if e.path.name == n) for n in ("boxB.toml", "bad_box.toml"))
            assert good.gearbox and "gearbox description 'boxB', stages 25/52, 16/81" in good.gearbox, good
            assert "pulses_per_rev" in bad.error and "missing table" not in bad.error, bad.error
            labels = [str(n.label) for n in app.tree.root.children]
            assert "✓ boxB.toml gearbox" in labels and "✗ bad_box.toml gearbox" in labels, labels
            app._move_to(good.path)
            await pilot.pause()
            said = shown(app, "#scenario-status")
            assert "✓ valid" in said and "stages 25/52, 16/81" in said and "missing table" not in said, said
            await pilot.press("r")  # nothing to run: said so, not 'highlight a valid scenario'
            await pilot.pause()
            assert app.process is None
            assert "gearbox description runs in a scenario" in list(app._notifications)[-1].message

    asyncio.run(main())


@pytest.fixture(scope="module")
def detection_run(tmp_path_factory):
    """A finished run of the tiny detection scenario (tests/detection_scenario.py), the matched filter beside FM4
    and NA4, from its records' folder; its figures not drawn. Its healthy test take is read at 10/6 x its level
    (a sensitivity of 6 mV/g where the others have 10: as a take at another load)."""
    from detection_scenario import run_in_module, scenario

    folder = tmp_path_factory.mktemp("tui_detection")
    path = scenario(folder, methods=("matched_filter",))
    text = path.read_text().replace("[scenario]", f'[output]\ndir = "{folder / "runs"}"\n\n[scenario]', 1)
    text = text.replace(
        'h3.zip", role = "test", label = "healthy" }',
        'h3.zip", role = "test", label = "healthy", sensitivity = "6 mV/g" }',
    )
    path.write_text(text)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("gearlab.plots.save", unrendered)
        mp.setenv("GEARLAB_CACHE", str(folder / "cache"))
        run = run_in_module(path, folder / "runs", cwd=folder / "data", figures=False, events=folder / "det.events")
    return path.parent, run


def test_a_detection_run_s_results_show_its_tables_in_the_tui(detection_run):
    # the Results tab of a finished detection run showed a table 'unit | method' (a row per condition and method,
    # no number) and the headings of the run's tables without them: the AUC / detected / false-alarm table, the
    # units called per label, which gear each test record's change lies on, what the learned rows learned; the
    # terminal and report.html print them

    async def main():
        async with results_shown(detection_run) as pilot:
            app = pilot.app
            lines = shown(app, "#results-lines")
            assert "det %" in lines and "FA %" in lines, lines[:2000]  # the AUC table, under its caption
            row = next(line for line in lines.splitlines() if "matched_filter" in line and "│" in line)
            assert any(c.isdigit() for c in row), row
            assert "called % 'fault'" in lines, lines[:3000]
            assert not app.query_one("#results-table").display  # no 'unit | method' table in their stead

    asyncio.run(main())


def test_a_take_off_its_history_s_level_is_said_in_the_report_and_the_tui(detection_run):
    # the 31/73 and 25/52 + 16/81 boxes' takes at 1.5-1.6 x their history's load: 'warning: ...: level 1.6 x its
    # history's (another load or gain?): NA4, a size, reads it as a change; ...' was printed while the run read its
    # records (4f0e99c, dd7e2e9), and nowhere else: not in table.md, report.html, summary.json, nor the TUI's view of
    # the run (whose NA4 row called the healthy takes); the guide's step 5 says 'a take off its history's level is
    # said so'
    import json

    _, run = detection_run
    said = json.loads((run / "summary.json").read_text())["warnings"]
    assert any("h3.zip: level 1.7 x its history's" in line for line in said), said
    assert "h3.zip: level 1.7 x its history's" in (run / "table.md").read_text()
    assert "h3.zip: level 1.7 x its history&#x27;s" in (run / "report.html").read_text()

    async def main():
        async with results_shown(detection_run) as pilot:
            lines = shown(pilot.app, "#results-lines")
            assert "h3.zip: level 1.7 x its history's (another load or gain?)" in " ".join(lines.split()), lines[-3000:]

    asyncio.run(main())


def test_a_detection_run_from_the_tui_counts_its_finished_units(detection_run, monkeypatch, tmp_path):
    # box B's learned scenario (source_only, dann beside FM4 and NA4) run from the TUI with k: four units finished
    # in its run directory, the TUI said 'finished: 0 unit(s)', its live table stayed empty and a cancel would have
    # said '0 finished unit(s) kept': a detection run sent no record event. The TUI's child replays the event lines
    # the engine wrote for the module's run of this scenario (detection_run, `--events` as the TUI starts it) and
    # that run's directory (test_tui.REPLAY): the engine's events and the TUI's count of them, without a second run
    # of the scenario in a child process (its imports, training and figures: 7 s of CPU)
    from test_tui import REPLAY

    folder, run = detection_run
    monkeypatch.chdir(folder.parent / "data")  # where the module's run was started: its records' folder
    monkeypatch.setenv("GEARLAB_CACHE", str(folder.parent / "cache"))
    started, real, go = [], asyncio.create_subprocess_exec, tmp_path / "go"

    async def replayed(program, *args, **kwargs):
        started.append(list(args[2:]))
        into = str(tmp_path / "runs" / run.parent.name / run.name)
        lines = str(folder.parent / "det.events")
        return await real(program, "-c", REPLAY, str(run), str(run), lines, into, str(go), **kwargs)

    monkeypatch.setattr(asyncio, "create_subprocess_exec", replayed)

    async def main():
        async with GearlabApp(folder).run_test(size=(160, 45)) as pilot:
            app = pilot.app
            await checked(pilot)
            app._move_to(folder / "det.toml")
            await pilot.pause()
            go.touch()  # the replay starts at once
            await pilot.press("r")
            for _ in range(600):
                await pilot.pause(0.5)
                if app.process is None and not shown(app, "#run-status").startswith("running"):
                    break
            status = shown(app, "#run-status")
            assert status.startswith("finished"), status
            units = len((app.run_path / "results.jsonl").read_text().splitlines())
            assert units > 0 and f"finished: {units} unit(s)" in status, (units, status)
            assert {r["method"] for r in app.records} >= {"matched_filter", "fm4", "na4"}, app.records
            assert started == [["run", str(folder / "det.toml"), "--out", str(run.parent.parent), "--events"]], started

    asyncio.run(main())


def test_a_run_up_without_a_history_is_said_a_run_up_in_the_error(cli, tmp_path, monkeypatch):
    # the 31/73 box's run-up (20 -> 35 Hz, tacho) beside steady 20 Hz takes: the run ended 'condition '27.5 Hz'
    # (rec/A_runup.csv) has no history record', the one line the TUI shows of a failed run (its status); the
    # run-up words (ef681d8) were in the log lines above it only
    _run_up_scenario(tmp_path, monkeypatch, "")
    code, _, err = cli("run", tmp_path / "det.toml", "--quick", "--out", tmp_path / "runs")
    last = err.strip().splitlines()[-1]
    assert code == 2 and "has no history record" in last, err[-2000:]
    assert "up.csv (20" in last and "over the take: a run-up)" in last, last


def test_at_80_columns_a_wide_table_of_the_results_is_a_block_per_row(detection_run):
    # at 80 x 24 the which-gear table (nine columns) was folded into five-cell columns: '../da|ta/f1|.zip', every
    # word cut; now fitted as the terminal fits it (turned: a column a record), else a block per record, each column a
    # 'name: value' line (box B's twelve takes, at 80 and at 160 columns)

    async def main():
        async with results_shown(detection_run, (80, 24)) as pilot:
            width = pilot.app.query_one("#results-lines").size.width
            assert 60 < width <= 80, width
            lines = shown(pilot.app, "#results-lines", width).splitlines()
            # turned (a column a record) where that keeps the words whole, as the terminal does; else a block a record
            assert any("../data/f1.zip" in line for line in lines), "\n".join(lines)
            assert any("localised on" in line and "input pinion" in line for line in lines), "\n".join(lines)

    asyncio.run(main())


async def scored_in_tui(pilot, run, typed: str) -> str:
    """s on *run* in the TUI, *typed* as the recordings and options, enter: the status line once score ended."""
    app = pilot.app
    await checked(pilot)
    app._move_to(run)
    await pilot.pause()
    await pilot.press("s")
    await pilot.pause()
    for ch in typed:
        await pilot.press(ch)
    await pilot.press("enter")
    for _ in range(600):
        await pilot.pause(0.5)
        if app.process is None and shown(app, "#run-status").startswith(("scored", "failed")):
            break
    return shown(app, "#run-status")


def test_s_scores_new_recordings_with_the_run_and_shows_the_trend(detection_run, monkeypatch):
    # the guide's step 7 reads the scoring trend in `gearlab tui .`, but the scoring itself was the shell's only: no
    # key of the TUI ran `gearlab score`. Now s on a finished detection run asks for the recordings and options (as
    # typed after RUN_DIR), runs it with its output in the Progress tab, then shows the trend chart
    folder, run = detection_run
    monkeypatch.chdir(folder.parent / "data")
    monkeypatch.setenv("GEARLAB_CACHE", str(folder.parent / "cache"))

    async def main():
        async with GearlabApp(folder).run_test(size=(160, 45)) as pilot:
            app = pilot.app
            status = await scored_in_tui(pilot, run, "f2.zip")
            assert status.startswith("scored: f2.zip"), status
            assert "scored with" in " ".join(str(line.text) for line in app.query_one("#log").lines)
            title = str(app.charts[app.chart_index].title)
            assert "scored records" in title and "f2.zip" in title, title

    asyncio.run(main())


def _run_up_scenario(tmp_path, monkeypatch, condition: str):
    """det.toml: the 31/73 box (73T driving, tacho), two steady 20 Hz history takes and a test take running up
    20 -> 35 Hz, given *condition* (a TOML inline key, or "")."""
    from test_outside_h import BOX_A, _run_up_csv

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "boxA.toml").write_text(BOX_A.replace('speed = "20 Hz"', 'speed = "20 Hz"\nload = "30 N*m"'))
    takes = [_run_up_csv(tmp_path / f"h{i}.csv", 20.0, 20.0) for i in (1, 2)] + [
        _run_up_csv(tmp_path / "up.csv", 20, 35)
    ]
    files = ", ".join(
        f'{{ file = "{p.name}", role = "{r}", label = "healthy"{condition if r == "test" else ""} }}'
        for p, r in zip(takes, ("history", "history", "test"))
    )
    (tmp_path / "det.toml").write_text(
        '[scenario]\nname = "runup"\nkind = "detection"\n\n[source]\ngearbox = "boxA.toml"\n'
        'faults = { "chip@output gear" = [20] }\nhealthy = 48\n\n'
        f'[target]\nvibration = "Beschl. 1 [g]"\ntacho = "Tacho [V]"\nfiles = [{files}]\n\n'
        '[[methods]]\nadapter = "matched_filter"\n'
    )
    return tmp_path / "det.toml"


def test_a_run_up_grouped_by_hand_is_cut_to_its_condition_s_speed_or_refused_in_one_line(tmp_path, monkeypatch):
    # the same run-up given condition = "20 Hz" (the guide: groups by hand) ran on, scored whole; now cut to its
    # revolutions at the 20 Hz history's speed as gearlab score cuts one (tests/test_outside_ab), here too few: one line
    import pytest

    from gearlab.errors import GearlabInputError
    from gearlab.kinds.detection_records import read_target, unit_shaft
    from gearlab.notebook import load_scenario

    spec = load_scenario(_run_up_scenario(tmp_path, monkeypatch, ', condition = "20 Hz"')).spec
    with pytest.raises(GearlabInputError) as got:
        read_target(spec.target, spec.detection.blocks, lambda e: None, shaft=unit_shaft(spec.source))
    said = str(got.value)
    assert " Hz .. 34.7" in said and "over the take: a run-up" in said and "('20 Hz')" in said, said
    assert len(said.splitlines()) == 1 and "h1.csv" not in said and "h2.csv" not in said, said


def test_the_results_tables_are_fitted_again_when_the_sidebar_folds(detection_run):
    # the tables were fitted once, to an estimate of the view's width made before the Results tab was shown; b (the
    # sidebar folded or shown) left them at that width

    async def main():
        async with results_shown(detection_run, (120, 40)) as pilot:
            app = pilot.app
            view = app.query_one("#results-lines")
            await settled(pilot, view)
            before = view.content_size.width
            assert view.drawn_at == before, (view.drawn_at, before)
            await pilot.press("b")
            await settled(pilot, view)
            assert view.content_size.width != before and view.drawn_at == view.content_size.width

    asyncio.run(main())


def test_a_learned_row_that_learned_the_simulator_but_not_the_test_is_said_so():
    # box B's learned rows (--quick): source_only learned the simulated chip (source AUC 1.00) and ranked the test's
    # takes below chance (record30 AUC 0.44, revolution 0.23); the verdict named dann the best learned row and said
    # nothing of source_only, whose 'source AUC 1.00' in the learned table reads as a success
    from gearlab.kinds.detection_verdict import detection_lines

    def row(method, auc, det, fa):
        return {"condition": "25 Hz", "unit": "record30", "method": method, "auc": auc, "detection": det}

    rows = [
        row("source_only", 0.438, 0.0, 0.0) | {"false_alarm": 0.0},
        row("dann", 0.725, 100.0, 50.0) | {"false_alarm": 50.0},
        row("fm4", 0.5, 100.0, 56.0) | {"false_alarm": 56.0},
    ]
    rows = [r | {"n_positive": 16, "n_negative": 32} for r in rows]
    learned = [
        {"condition": "25 Hz", "method": m, "source_auc": 1.0, "source_units": [96, 96]}
        for m in ("source_only", "dann")
    ]
    (_, line) = detection_lines({"rows": rows, "learned": learned}, "record30")
    assert "no better than chance" in line and "source_only (source AUC 1.00, test AUC 0.44)" in line, line
    assert "dann (source" not in line, line  # 0.72 is over chance at 16 / 32 units (0.65)
