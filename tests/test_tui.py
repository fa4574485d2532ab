"""The Textual TUI, driven with keys through Textual's pilot, and snapshots of its main screens.

Runs started from the TUI are real `gearlab run --events` child processes on tiny scenarios.
"""

from __future__ import annotations

import asyncio
import json
import shutil
import time
from pathlib import Path

import pytest
from textual.widgets import DataTable, Static, TabbedContent, Tree
from tiny import transfer

from gearlab.registry import load_registry
from gearlab.runs import RunDir
from gearlab.tui import GearlabApp
from gearlab.tui.catalog import error_line

REPO = Path(__file__).resolve().parents[1]

STIFFNESS = """\
[scenario]
name = "stiff"
kind = "stiffness"
description = "crack ladder"

[stiffness]
pair = "luo2019"
points = 256

[sweep]
faults = ["crack", "chip"]
steps = [1, 20]

[output]
dir = "{runs}"
"""

BAD = """\
[scenario]
name = "bad"
kind = "stiffness"

[stiffness]
pair = "luo2019"
pionts = 512
"""

TRANSFER = transfer("""\
[[methods]]
adapter = "source_only"

[[methods]]
adapter = "mmd"
""", repetitions=3, max_epochs=40) + '[output]\ndir = "{runs}"\n'


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A scenarios folder with a valid stiffness scenario, an invalid one and a subfolder."""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    sc = tmp_path / "scenarios"
    (sc / "more").mkdir(parents=True)
    (sc / "stiff.toml").write_text(STIFFNESS.replace("{runs}", str(tmp_path / "runs")))
    (sc / "bad.toml").write_text(BAD)
    (sc / "more" / "binary.toml").write_bytes(b"\xff\xfe\x00 not toml")
    return sc


def drive(app: GearlabApp, script, size=(100, 30)):
    """Run *script(pilot)* against *app* in a test harness."""

    async def main():
        async with app.run_test(size=size) as pilot:
            await pilot.pause()
            await script(pilot)

    asyncio.run(main())


async def until(pilot, condition, limit: float = 120.0) -> None:
    start = time.monotonic()
    while not condition():
        assert time.monotonic() - start < limit, "the TUI did not get there in time"
        await pilot.pause(0.1)


def labels(tree: Tree) -> list[str]:
    return [str(node.label) for node in tree.root.children]


def text_of(app, selector: str) -> str:
    return str(app.query_one(selector, Static).render())


def rows(table: DataTable) -> list[list[str]]:
    return [[str(c) for c in table.get_row_at(i)] for i in range(table.row_count)]


async def select(pilot, name: str) -> None:
    """Move the tree cursor to the scenario file *name* and open it (enter)."""
    tree = pilot.app.query_one("#browser", Tree)
    node = next(n for n in tree.root.children if str(n.label).endswith(name))
    tree.move_cursor(node)
    await pilot.press("enter")
    await pilot.pause()


# ----------------------------------------------------------------------------- browsing


def test_browser_lists_every_scenario_file_with_its_validation_status(folder):
    def script(pilot):
        async def go():
            assert labels(pilot.app.query_one("#browser", Tree)) == ["✗ bad.toml", "✗ more/binary.toml", "✓ stiff.toml"]

        return go()

    drive(GearlabApp(folder), script)


def test_invalid_scenario_shows_its_error_with_file_table_and_key(folder):
    async def script(pilot):
        await select(pilot, "bad.toml")
        status = text_of(pilot.app, "#scenario-status")
        assert "invalid" in status and "[stiffness] key 'pionts'" in status and "did you mean 'points'" in status
        assert pilot.app.query_one("#views", TabbedContent).active == "scenario"
        await pilot.press("r")  # refused: nothing starts
        await pilot.pause()
        assert pilot.app.process is None and not (folder.parent / "runs").exists()
        await select(pilot, "binary.toml")
        assert "binary.toml" in text_of(pilot.app, "#scenario-status")

    drive(GearlabApp(folder), script)


def test_error_line_points_at_the_key_inside_its_table():
    text = "[scenario]\nname = 'x'\n\n[[methods]]\nadapter = 'a'\n\n[[methods]]\nadapter = 'b'\nsupervised = 1\n"
    assert error_line(text, "s.toml: [[methods]] #2 key 'supervised': expected true/false") == 9
    assert error_line(text, "s.toml: [[methods]] #1 key 'adapter': unknown") == 5
    assert error_line(text, "s.toml: [scenario]: missing") == 1
    assert error_line(text, "s.toml: cannot be parsed") is None


def test_valid_scenario_shows_its_summary(folder):
    async def script(pilot):
        await select(pilot, "stiff.toml")
        status = text_of(pilot.app, "#scenario-status")
        assert "valid" in status and "stiff (stiffness)" in status and "41 TVMS cases" in status

    drive(GearlabApp(folder), script)


def test_missing_directory_is_shown_not_fatal(tmp_path):
    async def script(pilot):
        assert "no such directory" in labels(pilot.app.query_one("#browser", Tree))[0]

    drive(GearlabApp(tmp_path / "nowhere"), script)


def test_cli_refuses_a_missing_directory(cli, tmp_path):
    code, _, err = cli("tui", tmp_path / "nowhere")
    assert code == 2 and "no such directory" in err


# ----------------------------------------------------------------------------- runs


def test_run_fills_the_table_then_opens_the_results(folder):
    async def script(pilot):
        app = pilot.app
        await select(pilot, "stiff.toml")
        await pilot.press("r")
        assert app.query_one("#views", TabbedContent).active == "run"
        await until(pilot, lambda: app.process is not None)
        await until(pilot, lambda: app.process is None)
        assert "finished: 41 unit(s)" in text_of(app, "#run-status")
        live = rows(app.query_one("#live", DataTable))
        assert len(live) == 20 and live[0][0] == "1" and live[-1][0] == "20"
        assert app.query_one("#views", TabbedContent).active == "results"
        assert "finished" in text_of(app, "#results-status")
        assert rows(app.query_one("#results-table", DataTable)) == live
        assert [c.title for c in app.charts] == ["TVMS of luo2019", "relative fault area of each ladder (eq. 2.113)"]
        assert {c.label for c in app.charts[0].curves} == {"healthy", "crack_step20", "chip_step20"}
        await pilot.press("n")
        assert app.chart_index == 1
        # the run is now in the tree, under its scenario
        node = next(n for n in app.query_one("#browser", Tree).root.children if "stiff" in str(n.label))
        assert len(node.children) == 1 and str(node.children[0].label).startswith("● ")

    drive(GearlabApp(folder), script)


def test_quick_run_key_runs_the_shrunk_scenario(folder):
    async def script(pilot):
        app = pilot.app
        await select(pilot, "stiff.toml")
        await pilot.press("k")
        await until(pilot, lambda: app.process is not None)
        await until(pilot, lambda: app.process is None)
        # --quick keeps steps 1, 10 and 20 of each ladder: 3 crack + 3 chip cases and the healthy one
        assert "finished: 7 unit(s)" in text_of(app, "#run-status")
        assert [r[0] for r in rows(app.query_one("#live", DataTable))] == ["1", "10", "20"]

    drive(GearlabApp(folder), script)


@pytest.fixture
def transfer_folder(folder, tmp_path):
    (folder / "tiny.toml").write_text(TRANSFER.replace("{runs}", str(tmp_path / "runs")))
    return folder


def test_cancel_keeps_finished_units_and_resume_completes_the_run(transfer_folder, tmp_path):
    total = 3 * 2 * 2

    async def script(pilot):
        app = pilot.app
        await select(pilot, "tiny.toml")
        await pilot.press("r")
        await until(pilot, lambda: len(app.records) >= 2)
        live = rows(app.query_one("#live", DataTable))
        assert live and live[0][0] == "0"  # the Table 5.4 layout gains rows as units finish
        await pilot.press("c")
        await until(pilot, lambda: app.process is None, 30)
        assert "cancelled" in text_of(app, "#run-status")
        (run,) = (tmp_path / "runs" / "tiny").iterdir()
        kept = RunDir(run).records()
        assert 2 <= len(kept) < total and not (run / "summary.json").exists()
        # the cancelled run opens in the results view, then resumes
        tree = app.query_one("#browser", Tree)
        node = next(n for n in tree.root.children if "tiny" in str(n.label))
        node.expand()
        await pilot.pause()
        tree.move_cursor(node.children[0])
        await pilot.press("enter")
        await pilot.pause()
        assert "not finished" in text_of(app, "#results-status")
        await pilot.press("u")
        await until(pilot, lambda: app.process is not None, 10)
        await until(pilot, lambda: app.process is None)
        assert "finished" in text_of(app, "#run-status")
        units = [r["unit"] for r in RunDir(run).records()]
        assert len(units) == len(set(units)) == total
        assert (run / "summary.json").exists()
        table = rows(app.query_one("#results-table", DataTable))
        assert [r[0] for r in table] == ["0", "2"]

    drive(GearlabApp(transfer_folder), script)


def test_a_damaged_or_cancelled_run_directory_opens_without_a_crash(folder, tmp_path):
    runs = tmp_path / "runs" / "stiff"
    cut = runs / "20260101-000000-000000"
    cut.mkdir(parents=True)
    shutil.copy(folder / "stiff.toml", cut / "scenario.toml")
    (cut / "results.jsonl").write_text(json.dumps({"unit": "healthy", "fault": None, "step": 0, "faults": [],
                                                   "rfa": 0.0, "mean_N_per_m": 1.9e8, "min_N_per_m": 1.2e8,
                                                   "max_N_per_m": 2.3e8}) + '\n{"unit": "crack_st')
    broken = runs / "20260101-000000-000001"
    broken.mkdir()
    (broken / "scenario.toml").write_text("not = [valid")

    async def script(pilot):
        app = pilot.app
        tree = app.query_one("#browser", Tree)
        node = next(n for n in tree.root.children if "stiff" in str(n.label))
        node.expand()
        await pilot.pause()
        for child in node.children:
            tree.move_cursor(child)
            await pilot.press("enter")
            await pilot.pause()
            status = text_of(app, "#results-status")
            assert "not finished (1 units kept" in status or "cannot show this run" in status

    drive(GearlabApp(folder), script)


# ----------------------------------------------------------------------------- plugins


def test_plugins_view_lists_plugins_and_reports_broken_ones(folder, monkeypatch):
    class Broken:
        name, value, group = "oops", "no_such_module_xyz", "gearlab"
        dist = None

        def load(self):
            raise ImportError("No module named 'no_such_module_xyz'")

    import importlib.metadata

    import gearlab.registry as registry

    eps = list(importlib.metadata.entry_points(group="gearlab")) + [Broken()]
    monkeypatch.setattr(registry, "get_registry", lambda: load_registry(eps))

    async def script(pilot):
        await pilot.press("p")
        await pilot.pause()
        assert pilot.app.query_one("#views", TabbedContent).active == "plugins"
        table = rows(pilot.app.query_one("#plugin-table", DataTable))
        names = {(r[0], r[1]) for r in table}
        assert {("fault", "crack"), ("model", "ten_dof"), ("adapter", "mmd")} <= names
        crack = next(r for r in table if r[1] == "crack")
        assert crack[2] == "gearlab" and "q0 [mm] = 0  (0 .. 50)" in crack[3]
        problems = text_of(pilot.app, "#problems")
        assert "package 'no_such_module_xyz', plugin 'oops'" in problems and "ImportError" in problems

    drive(GearlabApp(folder), script)


# ----------------------------------------------------------------------------- snapshots


@pytest.fixture
def repo_scenarios(tmp_path, monkeypatch):
    """The repository's scenarios, in a folder named 'scenarios' with no past runs beside it."""
    shutil.copytree(REPO / "scenarios", tmp_path / "scenarios")
    monkeypatch.chdir(tmp_path)
    return Path("scenarios")


@pytest.mark.parametrize("size", [(80, 24), (100, 30)])
def test_snapshot_scenario_view(snap_compare, repo_scenarios, size):
    async def before(pilot):
        await select(pilot, "quick.toml")

    assert snap_compare(GearlabApp(repo_scenarios), run_before=before, terminal_size=size)


def test_snapshot_invalid_scenario(snap_compare, folder):
    async def before(pilot):
        await select(pilot, "bad.toml")

    assert snap_compare(GearlabApp(Path("scenarios")), run_before=before)


def test_snapshot_plugins_view(snap_compare, repo_scenarios):
    assert snap_compare(GearlabApp(repo_scenarios), press=["p"])


def test_several_markdown_tables_are_read_apart():
    from gearlab.tui.widgets import markdown_tables

    text = "| a | b |\n|---|---|\n| 1 | 2 |\n\n| effect | share | params |\n|---|---|---|\n| x | 10 % | p = 1 |\n"
    assert markdown_tables(text) == [[["a", "b"], ["1", "2"]], [["effect", "share", "params"], ["x", "10 %", "p = 1"]]]
    assert markdown_tables("") == []
