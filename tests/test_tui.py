"""The Textual TUI, driven with keys through Textual's pilot, and snapshots of its main screens.

Runs started from the TUI are real `gearlab run --events` child processes on tiny scenarios
(cancel/resume's holds its third and later units until the cancel, held_units),
except in the tests of what the TUI starts, not of the run (`stub_engine`), in the every-kind
runs, the run-end notification and the quick-run key, whose child replays a run the real engine made
once in this session (`replayed`, `quick_stream`), and in the runs of where runs go and the resume
of cancel/resume, made by the real engine in this process (`in_process`).
"""

from __future__ import annotations

import asyncio
import json
import shutil
import threading
import time
from pathlib import Path

import pytest
from conftest import unrendered
from test_detection import scenario as detection_scenario
from textual.widgets import DataTable, Static, TabbedContent, Tree
from tiny import TARGET_NOISE, transfer

from gearlab.registry import load_registry
from gearlab.runs import RunDir
from gearlab.tui import GearlabApp, catalog
from gearlab.tui.catalog import error_line, run_entry
from gearlab.tui.progress import stage_id

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

TRANSFER = (
    transfer(
        """\
[[methods]]
adapter = "source_only"

[[methods]]
adapter = "mmd"
""",
        repetitions=2,  # the every-kind run's two repetitions: finished_runs's verdict needs a method ahead
    )
    + '[output]\ndir = "{runs}"\n'
)
# cancel/resume's: 4 units (k 0 and 2, two methods), of which the cancel keeps the first two (the others held,
# held_units) and the resume makes the other two. The held units, not the training's length, decide where the
# cancel lands: TRANSFER's 8 units made the test 13.1 s of CPU, these 11.4 s (same assertions).
# Its target without the tiny scenarios' sensor noise: a noise-free target has no Bayes bound, which each of the
# two runs (the cancelled one and the resume) computed before its units, loading torch for it (about 0.6 s of a
# child's CPU each); nothing here reads the bound, and the every-kind runs keep it
CANCELLED = (
    transfer('[[methods]]\nadapter = "source_only"\n\n[[methods]]\nadapter = "mmd"\n').replace(TARGET_NOISE, "")
    + '[output]\ndir = "{runs}"\n'
)


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


# The sizes the issue tried: a test of what is drawn (layout, snapshots, charts) runs at both; a test of what a key
# or a run does, the same at both widths, at 80x24 (NARROW), where the sidebar also folds away for runs and results.
SIZES = [(160, 45), (80, 24)]
NARROW = SIZES[1]


def drive(app: GearlabApp, script, size=(100, 30)):
    """Run *script(pilot)* against *app* in a test harness, once the tree's marks are all set."""

    async def main():
        async with app.run_test(size=size) as pilot:
            await pilot.pause()
            await checked(pilot)
            await script(pilot)

    asyncio.run(main())


async def until(pilot, condition, limit: float = 120.0) -> None:
    start = time.monotonic()
    while not condition():
        assert pilot.app._exception is None, f"the TUI crashed: {pilot.app._exception!r}"
        assert time.monotonic() - start < limit, "the TUI did not get there in time"
        await pilot.pause(0.1)


async def checked(pilot) -> None:
    """Until every scenario's mark is set: the tree is listed first, its files validated after (tui.checking). Polled
    by the loop's own sleep: a pilot.pause draws the screen at each turn."""
    app = pilot.app
    for _ in range(12000):  # 2 min at most
        if all(entry.checked for entry in app.entries):
            break
        assert app._exception is None, f"the TUI crashed: {app._exception!r}"
        await asyncio.sleep(0.01)
    assert all(entry.checked for entry in app.entries), "the marks did not all come"
    await pilot.pause()


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


def test_the_tree_is_listed_at_once_and_its_marks_come_without_a_key(folder, monkeypatch):
    gate, real = threading.Event(), catalog.load_scenario

    def held(path=None, *, run=None):  # the validations wait until the first frames are read
        assert gate.wait(30)
        return real(path, run=run)

    monkeypatch.setattr(catalog, "load_scenario", held)

    async def main():
        async with GearlabApp(folder).run_test(size=(100, 30)) as pilot:
            app, tree = pilot.app, pilot.app.query_one("#browser", Tree)
            try:
                await pilot.pause()
                assert labels(tree) == ["· bad.toml", "· more/binary.toml", "· stiff.toml"]
                assert "not validated yet" in text_of(app, "#scenario-status")  # bad.toml, highlighted
            finally:
                gate.set()
            await checked(pilot)  # no key pressed
            assert labels(tree) == ["✗ bad.toml", "✗ more/binary.toml", "✓ stiff.toml"]
            status = text_of(app, "#scenario-status")  # the highlighted file's view, drawn again with its error
            assert "invalid" in status and "[stiffness] key 'pionts'" in status and "did you mean 'points'" in status

    asyncio.run(main())


def test_a_scenario_selected_or_run_before_its_mark_came_is_validated_then(folder):
    app, started = GearlabApp(folder), []
    app._check_pending = lambda: None  # no background validation: every mark stays pending until asked for
    app.follow = lambda args: started.append(args)  # the command line a run would be

    async def main():
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.pause()
            tree = app.query_one("#browser", Tree)
            await pilot.press("r")  # bad.toml, highlighted: validated, then refused
            await pilot.pause()
            assert labels(tree)[0] == "✗ bad.toml" and not started
            await select(pilot, "stiff.toml")
            assert labels(tree) == ["✗ bad.toml", "· more/binary.toml", "✓ stiff.toml"]
            assert "stiff (stiffness)" in text_of(app, "#scenario-status")
            tree.move_cursor(tree.root.children[1])
            await pilot.pause()
            await pilot.press("k")  # binary.toml: validated as it is run, refused
            assert labels(tree)[1] == "✗ more/binary.toml" and not started
            tree.move_cursor(tree.root.children[2])
            await pilot.press("r")
            assert started and started[0][:2] == ["run", str(folder / "stiff.toml")]

    asyncio.run(main())


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


def test_quick_run_key_runs_the_shrunk_scenario(folder, quick_stream, monkeypatch, tmp_path):
    """k starts `gearlab run FILE --quick` and draws the shrunk scenario's run: the engine's quick run of it,
    recorded in this process and replayed by the TUI's child (quick_stream; the real child, which imported
    gearlab again for 1.1 s of CPU, is started in test_run_fills_the_table_then_opens_the_results; with
    --quick, the tests of where runs go run the engine in this process)."""
    started = replay(monkeypatch, quick_stream, tmp_path)

    async def script(pilot):
        app = pilot.app
        await select(pilot, "stiff.toml")
        await pilot.press("k")
        await until(pilot, lambda: app.process is not None)
        (args,) = started
        assert args[:2] == ["run", str(folder / "stiff.toml")] and "--quick" in args and args[-1] == "--events"
        (tmp_path / "go").touch()
        await until(pilot, lambda: app.process is None)
        # --quick keeps steps 1, 10 and 20 of each ladder: 3 crack + 3 chip cases and the healthy one
        assert "finished: 7 unit(s)" in text_of(app, "#run-status")
        assert [r[0] for r in rows(app.query_one("#live", DataTable))] == ["1", "10", "20"]

    drive(GearlabApp(folder), script)


@pytest.fixture
def transfer_folder(folder, tmp_path, monkeypatch, kinds_cache, kind_streams):
    """CANCELLED beside the `folder` fixture's scenarios, its datasets in the module's cache of the every-kind
    runs (kind_streams): TRANSFER's run left there the source dataset CANCELLED also uses (their targets differ
    by the noise alone), which the cancelled run's child otherwise simulated again (1.8 s of its CPU)."""
    monkeypatch.setenv("GEARLAB_CACHE", str(kinds_cache))
    (folder / "tiny.toml").write_text(CANCELLED.replace("{runs}", str(tmp_path / "runs")))
    return folder


HELD = """\
import sys, time
from pathlib import Path
import gearlab.kinds.transfer as transfer
from gearlab.cli import main
gate, sys.argv = Path(sys.argv[1]), ["gearlab", *sys.argv[2:]]
train, started, deadline = transfer.train_unit, [], time.monotonic() + 60  # a hung test's bound
def held(task):
    started.append(task)
    while len(started) > 2 and not gate.exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    return train(task)
transfer.train_unit = held
main()
"""


@pytest.fixture
def held_units(monkeypatch, tmp_path):
    """The TUI's child is the real engine, whose third and later transfer units (one worker: in
    its own process) wait until the file returned exists: a cancel lands after exactly two
    finished units, however fast the machine trains the others. The resume (`--resume`) is the
    real engine in this process (in_process), its child ended once tmp_path/go exists."""
    gate, real = tmp_path / "let-go", asyncio.create_subprocess_exec
    in_process(monkeypatch, tmp_path, tmp_path / "go")
    resumed = asyncio.create_subprocess_exec

    async def stand_in(program, *args, **kwargs):
        assert args[:2] == ("-m", "gearlab"), args
        if "--resume" in args:
            return await resumed(program, *args, **kwargs)
        return await real(program, "-c", HELD, str(gate), *args[2:], **kwargs)

    monkeypatch.setattr(asyncio, "create_subprocess_exec", stand_in)
    return gate


def test_cancel_keeps_finished_units_and_resume_completes_the_run(transfer_folder, held_units, tmp_path):
    total = 2 * 2  # ks x methods of CANCELLED

    async def script(pilot):
        app = pilot.app
        await select(pilot, "tiny.toml")
        await pilot.press("r")
        await until(pilot, lambda: len(app.records) >= 2)
        live = rows(app.query_one("#live", DataTable))
        assert live and live[0][0] == "0"  # the Table 5.4 layout gains rows as units finish
        await pilot.press("c")
        await until(pilot, lambda: app.process is None, 30)
        held_units.touch()  # the cancelled run's units are let go: the resumed run trains freely
        assert "cancelled" in text_of(app, "#run-status")
        (run,) = (tmp_path / "runs" / "tiny").iterdir()
        kept = RunDir(run).records()
        assert len(kept) == 2 < total and not (run / "summary.json").exists()
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
        await until(pilot, lambda: app.process is not None, 30)
        (tmp_path / "go").touch()
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
    (cut / "results.jsonl").write_text(
        json.dumps(
            {
                "unit": "healthy",
                "fault": None,
                "step": 0,
                "faults": [],
                "rfa": 0.0,
                "mean_N_per_m": 1.9e8,
                "min_N_per_m": 1.2e8,
                "max_N_per_m": 2.3e8,
            }
        )
        + '\n{"unit": "crack_st'
    )
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


@pytest.fixture
def stable_scenarios(tmp_path, monkeypatch):
    """Two shipped scenarios that rarely change (a snapshot of the whole folder would change
    with every scenario added or edited), the longest file name among them."""
    (tmp_path / "scenarios").mkdir()
    for name in ("dataset_B.toml", "stiffness_verification.toml"):
        shutil.copy(REPO / "scenarios" / name, tmp_path / "scenarios" / name)
    monkeypatch.chdir(tmp_path)
    return Path("scenarios")


@pytest.mark.parametrize("size", SIZES)
def test_snapshot_scenario_view(snap_compare, stable_scenarios, size):
    async def before(pilot):
        await checked(pilot)
        await select(pilot, "stiffness_verification.toml")

    assert snap_compare(GearlabApp(stable_scenarios), run_before=before, terminal_size=size)


@pytest.mark.parametrize("size", SIZES)
def test_snapshot_invalid_scenario(snap_compare, folder, size):
    async def before(pilot):
        await checked(pilot)
        await select(pilot, "bad.toml")

    assert snap_compare(GearlabApp(Path("scenarios")), run_before=before, terminal_size=size)


@pytest.mark.parametrize("size", SIZES)
def test_snapshot_plugins_view(snap_compare, stable_scenarios, size):
    assert snap_compare(GearlabApp(stable_scenarios), run_before=checked, press=["p"], terminal_size=size)


@pytest.mark.parametrize("size", SIZES)
def test_snapshot_keys_panel(snap_compare, folder, size):
    assert snap_compare(GearlabApp(Path("scenarios")), run_before=checked, press=["question_mark"], terminal_size=size)


@pytest.fixture(scope="module")
def quick_stiff_run(quick_stream):
    """A quick run of stiff.toml for the two sizes' snapshots, the quick-run key's (quick_stream: the same
    scenario gives the same run), laid out as the `folder` fixture lays out a test's: (base, its run directory)."""
    made = Path(quick_stream["stiff.toml"][0])
    return made.parents[2], made


@pytest.mark.parametrize("size", SIZES)
def test_snapshot_results_of_a_stiffness_run(snap_compare, folder, tmp_path, quick_stiff_run, size):
    base, made = quick_stiff_run
    fixed = tmp_path / "runs" / "stiff" / "20260101-000000-000000"  # the timestamp is on screen: a fixed one
    shutil.copytree(made, fixed)
    for name in ("scenario.toml", "scenario.original.toml", "run.json"):  # as if run from this test's folder
        (fixed / name).write_text((fixed / name).read_text().replace(str(base), str(tmp_path)))

    async def before(pilot):
        await checked(pilot)
        node = node_named(pilot.app, "stiff.toml")
        node.expand()
        await pilot.pause()
        pilot.app.query_one("#browser", Tree).move_cursor(node.children[0])
        await pilot.press("enter")
        await pilot.pause()

    assert snap_compare(GearlabApp(Path("scenarios")), run_before=before, terminal_size=size)


def test_several_markdown_tables_are_read_apart():
    from gearlab.tui.widgets import markdown_tables

    text = "| a | b |\n|---|---|\n| 1 | 2 |\n\n| effect | share | params |\n|---|---|---|\n| x | 10 % | p = 1 |\n"
    assert markdown_tables(text) == [[["a", "b"], ["1", "2"]], [["effect", "share", "params"], ["x", "10 %", "p = 1"]]]
    assert markdown_tables("") == []


# ----------------------------------------------------------------------------- every kind, to the end

KINDS_DIR = Path(__file__).resolve().parent / "tui_scenarios"


@pytest.fixture(scope="module")
def kinds_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("kinds_cache")


@pytest.fixture
def kinds_folder(tmp_path, monkeypatch, kinds_cache):
    """Tiny scenarios of every kind shipped (stiffness, dataset, noise_study, transfer, gap,
    gap_benchmark): each runs for a few seconds with the real engine."""
    monkeypatch.setenv("GEARLAB_CACHE", str(kinds_cache))
    monkeypatch.chdir(tmp_path)
    return make_kinds_folder(tmp_path)


def make_kinds_folder(base: Path) -> Path:
    """*base*/scenarios with the tiny scenario of every kind (their runs in 'runs', relative)."""
    folder = base / "scenarios"
    shutil.copytree(KINDS_DIR, folder)
    (folder / "stiff.toml").write_text(STIFFNESS.replace("{runs}", "runs"))
    # both repetitions: the run is also finished_runs's, whose verdict needs a method ahead (one ties)
    (folder / "transfer.toml").write_text(TRANSFER.replace("{runs}", "runs"))
    detection_scenario(base, methods=("source_only", "matched_filter"))  # scenarios/det.toml, records in data/
    return folder


async def run_to_the_end(pilot, name: str, key: str = "r", then=None) -> None:
    """Run scenario *name* from the TUI and wait for its end; *then()* once it says 'running'."""
    app = pilot.app
    await select(pilot, name)
    await pilot.press(key)
    assert text_of(app, "#run-status").startswith("running")
    if then is not None:
        then()
    # the status says 'running' until the child ends (a child that fails at once ends between polls)
    await until(pilot, lambda: app.process is None and not text_of(app, "#run-status").startswith("running"), 300)
    status = text_of(app, "#run-status")
    assert status.startswith("finished"), f"{name}: {status}\n{app.query_one('#log').lines}"
    assert app.return_code is None  # the app is still up: no widget crashed on the run's events
    assert "finished" in text_of(app, "#results-status")


# Each kind once (a few seconds each), both sizes between them; the gap kind, whose stage names
# have spaces (it crashed the TUI), at both.
EVERY_KIND = [
    ("tgap.toml", SIZES[0]),
    ("tgap.toml", SIZES[1]),
    ("tbench.toml", SIZES[0]),
    ("tnoise.toml", SIZES[1]),
    ("tdata.toml", SIZES[0]),
    ("stiff.toml", SIZES[1]),
    ("transfer.toml", SIZES[0]),
    ("det.toml", SIZES[1]),
    ("ttbench.toml", SIZES[0]),
]


# The child a replayed run starts: it puts the recorded run directory where the run would have
# made it and writes the recorded event lines, that run directory's path in them made the new one.
# It starts when the test has seen the TUI say 'running' (file *go* made, a minute at most), as a
# real run takes its time.
REPLAY = """
import shutil, sys, time
from pathlib import Path

made, written, lines, into, go = sys.argv[1:]
start = time.monotonic()
while not Path(go).exists() and time.monotonic() - start < 60:
    time.sleep(0.02)
Path(into).parent.mkdir(parents=True, exist_ok=True)
shutil.copytree(made, into)
sys.stdout.write(Path(lines).read_text().replace(written, into))
"""


@pytest.fixture(scope="module")
def kind_streams(tmp_path_factory, kinds_cache):
    """{scenario file: (its run directory, that directory as the events write it, the file of the
    event lines)}: each tiny scenario of EVERY_KIND run once by the real engine, as `gearlab run
    FILE --out RUNS --events` beside the scenarios' folder, in this process (its imports already made)."""

    base = tmp_path_factory.mktemp("kind_streams")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GEARLAB_CACHE", str(kinds_cache))
        mp.setattr("gearlab.plots.save", unrendered)
        mp.chdir(base)
        make_kinds_folder(base)
        # what the TUI starts (but its --out)
        return {
            name: recorded(base, ["run", str(Path("scenarios") / name), "--out", str(base / "runs")], name)
            for name in dict(EVERY_KIND)
        }


def recorded(base: Path, args: list[str], name: str) -> tuple[str, str, Path]:
    """`gearlab ARGS --events` run by the real engine in this process, from *base* (the caller sets the
    folder, the cache and the figures): (its run directory, that directory as the events write it, the file
    of the event lines, base/NAME.events)."""
    from contextlib import redirect_stdout
    from io import StringIO

    from gearlab.cli import main

    out = StringIO()
    with pytest.MonkeyPatch.context() as mp, redirect_stdout(out):
        mp.setattr("sys.argv", ["gearlab", *args, "--events"])
        try:
            main()
        except SystemExit as exc:
            assert not exc.code, f"{name}: exit {exc.code}"
    lines = out.getvalue().splitlines()
    (made,) = [json.loads(x)["message"] for x in lines if x.startswith("{") and json.loads(x)["kind"] == "run"]
    (base / f"{name}.events").write_text("\n".join(lines) + "\n")
    return str(base / made), made, base / f"{name}.events"


@pytest.fixture(scope="module")
def quick_stream(tmp_path_factory):
    """{"stiff.toml": recorded's triple} of the `folder` fixture's stiff.toml run as the quick-run key starts
    it (`gearlab run FILE --out RUNS --quick --events`), by the real engine in this process."""
    base = tmp_path_factory.mktemp("quick_stream")
    (base / "scenarios").mkdir()
    (base / "scenarios" / "stiff.toml").write_text(STIFFNESS.replace("{runs}", str(base / "runs")))
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GEARLAB_CACHE", str(base / "cache"))
        mp.setattr("gearlab.plots.save", unrendered)
        mp.chdir(base)
        args = ["run", str(Path("scenarios") / "stiff.toml"), "--out", str(base / "runs"), "--quick"]
        return {"stiff.toml": recorded(base, args, "stiff.toml")}


@pytest.fixture
def replayed(monkeypatch, kind_streams, tmp_path):
    """The TUI's child replays the recorded run of the scenario it is asked to run (kind_streams):
    for the tests of how the TUI follows each kind's events and opens its results, not of how it
    starts a run (the runs of test_run_fills_the_table_then_opens_the_results and cancel/resume keep
    the real child, those of where runs go the real engine: in_process); the list gets each start's arguments."""
    return replay(monkeypatch, kind_streams, tmp_path)


def replay(monkeypatch, streams: dict, tmp_path: Path) -> list:
    """The TUI's child made a replay of the run of *streams* (recorded's triples by scenario file name) for
    the file it is asked to run, into tmp_path/runs, once the file tmp_path/go exists; the list returned
    gets each start's arguments."""
    started, real = [], asyncio.create_subprocess_exec

    async def stand_in(program, *args, **kwargs):
        assert args[:2] == ("-m", "gearlab"), args
        started.append(list(args[2:]))
        made, written, lines = streams[Path(args[3]).name]
        into = str(tmp_path / "runs" / Path(made).parent.name / Path(made).name)
        return await real(program, "-c", REPLAY, made, written, str(lines), into, str(tmp_path / "go"), **kwargs)

    monkeypatch.setattr(asyncio, "create_subprocess_exec", stand_in)
    return started


# The child of an in-process run (in_process): it writes what `gearlab` wrote in the test's process, its
# output then its errors, and exits with its code, once the file *go* exists ('-': at once; a minute at most).
ECHO = """
import sys, time
from pathlib import Path

out, err, code, go = sys.argv[1:]
start = time.monotonic()
while go != "-" and not Path(go).exists() and time.monotonic() - start < 60:
    time.sleep(0.02)
sys.stdout.write(Path(out).read_text())
sys.stdout.flush()
sys.stderr.write(Path(err).read_text())
sys.exit(int(code))
"""


def in_process(monkeypatch, tmp_path: Path, go: Path | None = None) -> list:
    """The TUI's child made `gearlab ARGS` run by the real engine in this process, with the arguments and in the
    folder the TUI gives its child, then a stand-in child that writes its output and exits with its code once
    *go* exists (None: at once): a real child imported gearlab, scipy and torch again for 1.5-4.5 s of CPU. For the
    tests of what the TUI starts and shows, where a real child is started elsewhere (test_run_fills_the_table_
    then_opens_the_results, the cancelled run of cancel/resume, test_outside_j's scoring); the list returned gets
    each start's arguments."""
    from contextlib import redirect_stderr, redirect_stdout
    from io import StringIO

    from gearlab.cli import main

    started, real = [], asyncio.create_subprocess_exec

    async def stand_in(program, *args, cwd=None, **kwargs):
        assert args[:2] == ("-m", "gearlab"), args
        started.append(list(args[2:]))
        out, err, code = StringIO(), StringIO(), 0
        with pytest.MonkeyPatch.context() as mp, redirect_stdout(out), redirect_stderr(err):
            mp.chdir(cwd)
            mp.setattr("sys.argv", ["gearlab", *args[2:]])
            try:
                main()
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
        said = [tmp_path / f"child{len(started)}.{name}" for name in ("out", "err")]
        for path, text in zip(said, (out, err)):
            path.write_text(text.getvalue())
        return await real(program, "-c", ECHO, *map(str, said), str(code), str(go or "-"), cwd=cwd, **kwargs)

    monkeypatch.setattr(asyncio, "create_subprocess_exec", stand_in)
    return started


@pytest.mark.parametrize("name,size", EVERY_KIND)
def test_every_scenario_kind_runs_from_the_tui_to_the_end(kinds_folder, replayed, tmp_path, name, size):
    """Each kind's events, as the real engine writes them in this session, drawn to the end and its
    run opened in the results view (the engine's run recorded once, replayed by the TUI's child)."""

    async def script(pilot):
        app = pilot.app
        await run_to_the_end(pilot, name, then=(tmp_path / "go").touch)
        assert replayed == [["run", str(Path("scenarios") / name), "--out", str(tmp_path / "runs"), "--events"]]
        assert app.run_path.parent.parent == tmp_path / "runs"  # the replayed run, where the child put it
        if name == "tgap.toml":  # stage names with spaces ('gap before') got bars of their own
            assert app.query(f"#bar-{stage_id('gap before')}") and app.query(f"#bar-{stage_id('gap after')}")
        assert app.query_one("#views", TabbedContent).active == "results"

    drive(GearlabApp(Path("scenarios")), script, size)


def test_the_tiny_scenarios_cover_every_kind(kinds_folder):
    from gearlab.engine import load_scenario
    from gearlab.kinds import SCENARIO_KINDS

    kinds = {load_scenario(kinds_folder / name).kind for name, _ in EVERY_KIND}
    assert kinds == set(SCENARIO_KINDS)


@pytest.mark.slow
@pytest.mark.parametrize("size", SIZES[1:])
def test_every_shipped_scenario_runs_from_the_tui(tmp_path, monkeypatch, size):
    """The shipped files themselves: quick runs of each kind (several minutes, datasets cold)."""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    shutil.copytree(REPO / "scenarios", tmp_path / "scenarios")

    async def script(pilot):
        for name in (
            "gap_expB.toml",
            "gap_benchmark.toml",
            "ch4_noise.toml",
            "dataset_B.toml",
            "stiffness_verification.toml",
            "quick.toml",
        ):
            await run_to_the_end(pilot, name, key="k")

    drive(GearlabApp(Path("scenarios")), script, size)


def test_stage_ids_are_valid_and_distinct_whatever_the_name():
    from textual.widgets import Label

    names = ["gap before", "gap-before", "gap_before", "gap round 2", "trial 3/40", "ü", "#x.y", "runs", "9"]
    ids = [stage_id(n) for n in names]
    assert len(set(ids)) == len(ids)
    for i in ids:
        Label(id=f"bar-{i}")  # Textual refuses an invalid id


def test_an_internal_error_of_the_app_exits_1(cli, folder, monkeypatch):
    from textual.app import App

    def broken(self):
        raise RuntimeError("a bug in the TUI")

    monkeypatch.setattr(GearlabApp, "on_mount", broken)
    monkeypatch.setattr(GearlabApp, "run", lambda self: App.run(self, headless=True))
    code, _, _ = cli("tui", folder)
    assert code == 1


# ----------------------------------------------------------------------------- selection by identity


@pytest.fixture
def two_with_runs(folder, tmp_path):
    """stiff.toml with two past runs, and a second valid scenario, tail.toml, after it."""
    (folder / "tail.toml").write_text(
        STIFFNESS.replace('name = "stiff"', 'name = "other"').replace("{runs}", str(tmp_path / "runs"))
    )
    for stamp in ("20260101-000000-000000", "20260102-000000-000000"):
        run = tmp_path / "runs" / "stiff" / stamp
        run.mkdir(parents=True)
        shutil.copy(folder / "stiff.toml", run / "scenario.toml")
    return folder


STUB_ENGINE = "import json, time; print(json.dumps({'kind': 'log', 'message': 'stub'}), flush=True); time.sleep(0.05)"


@pytest.fixture
def stub_engine(monkeypatch):
    """For tests of what the TUI runs, not of the run: the child it starts is a stand-in that
    writes one event line and ends (exit 0) instead of `python -m gearlab ...`; the list
    returned gets the gearlab arguments of each start. test_run_fills_the_table_then_opens_the_results,
    cancel/resume and where runs go keep the real engine (a child, or in_process; the quick run key's
    replays its run)."""
    started, real = [], asyncio.create_subprocess_exec

    async def stand_in(program, *args, **kwargs):
        assert args[:2] == ("-m", "gearlab"), args
        started.append(list(args[2:]))
        return await real(program, "-c", STUB_ENGINE, **kwargs)

    monkeypatch.setattr(asyncio, "create_subprocess_exec", stand_in)
    return started


def ended(app, started: list) -> bool:
    """A stand-in run was started and has ended (it lives 50 ms: a poll may miss it)."""
    return bool(started) and text_of(app, "#run-status").startswith("finished")


def node_named(app, name: str):
    return next(n for n in app.query_one("#browser", Tree).root.children if str(n.label).endswith(name))


async def unfold(pilot, name: str):
    """The tree node of scenario file *name*, unfolded (its runs shown)."""
    node = node_named(pilot.app, name)
    node.expand()
    await pilot.pause()
    return node


def test_after_a_rescan_the_cursor_stays_on_the_same_scenario_and_r_runs_it(two_with_runs, stub_engine):
    async def script(pilot):
        app = pilot.app
        tree = app.query_one("#browser", Tree)
        await unfold(pilot, "stiff.toml")
        await select(pilot, "tail.toml")  # below the two runs of the unfolded stiff.toml
        await pilot.press("f5")
        await pilot.pause()
        assert tree.cursor_node.data.path.name == "tail.toml"
        assert node_named(app, "stiff.toml").is_expanded  # unfolded stays unfolded
        await pilot.press("r")
        await until(pilot, lambda: ended(app, stub_engine), 30)
        assert app.run_scenario.name == "other" and app.process is None
        (args,) = stub_engine
        assert args[:2] == ["run", str(two_with_runs / "tail.toml")] and "--quick" not in args
        # the run's end rescans: still on tail.toml, and r runs other again
        assert tree.cursor_node.data.path.name == "tail.toml"

    drive(GearlabApp(two_with_runs), script, NARROW)


def test_u_resumes_only_the_highlighted_run(two_with_runs, stub_engine, tmp_path):
    async def script(pilot):
        app = pilot.app
        tree = app.query_one("#browser", Tree)
        stiff = await unfold(pilot, "stiff.toml")
        tree.move_cursor(stiff.children[1])
        await pilot.press("enter")  # opens the older unfinished run
        await pilot.pause()
        assert app.opened.path.name == "20260101-000000-000000"
        await select(pilot, "tail.toml")  # the cursor moves away: u must not resume what was opened
        await pilot.press("u")
        await pilot.pause()
        assert app.process is None and not stub_engine
        await pilot.press("f5")
        await pilot.pause()
        tree.move_cursor(node_named(app, "stiff.toml").children[0])
        await pilot.pause()
        await pilot.press("u")
        await until(pilot, lambda: ended(app, stub_engine), 30)
        assert app.run_path.name == "20260102-000000-000000" and app.process is None
        resumed = tmp_path / "runs" / "stiff" / "20260102-000000-000000"
        assert stub_engine == [["run", "--resume", str(resumed), "--events"]]  # the first u started none

    drive(GearlabApp(two_with_runs), script, NARROW)


# ----------------------------------------------------------------------------- where the runs are


def test_runs_are_found_where_gearlab_run_puts_them_whatever_the_folder(tmp_path, monkeypatch, cli, unrendered_figures):
    """`gearlab tui /elsewhere/scenarios` started in a project folder: a scenario's relative
    [output] dir is taken from that folder, as `gearlab run` there takes it, for the runs the
    TUI starts and for those it lists."""
    scenarios = tmp_path / "elsewhere" / "scenarios"
    scenarios.mkdir(parents=True)
    (scenarios / "stiff.toml").write_text(STIFFNESS.replace("{runs}", "my_runs"))
    project = tmp_path / "project"
    project.mkdir()
    monkeypatch.chdir(project)
    code, out, err = cli("run", scenarios / "stiff.toml", "--quick")
    assert code == 0, err
    (by_cli,) = (project / "my_runs" / "stiff").iterdir()
    started = in_process(monkeypatch, tmp_path, tmp_path / "go")  # the run the TUI starts, made in this process

    async def script(pilot):
        app = pilot.app
        node = node_named(app, "stiff.toml")
        assert [c.data.path for c in node.children] == [by_cli]
        await select(pilot, "stiff.toml")
        assert f"1 past run(s) in {Path('my_runs') / 'stiff'};" in text_of(app, "#scenario-status")
        await pilot.press("k")
        await until(pilot, lambda: app.process is not None, 30)
        (args,) = started
        assert args[args.index("--out") + 1] == str(project / "my_runs") and "--quick" in args
        (tmp_path / "go").touch()
        await until(pilot, lambda: app.process is None)
        assert app.run_path.parent == project / "my_runs" / "stiff"
        assert len(node_named(app, "stiff.toml").children) == 2

    drive(GearlabApp(scenarios), script, NARROW)


# ----------------------------------------------------------------------------- 80 x 24


def test_at_80x24_the_footer_the_sidebar_and_the_tables_fit(repo_scenarios):
    from textual.widgets import Footer

    async def script(pilot):
        app = pilot.app
        footer = app.query_one(Footer)

        def keys():
            return {str(k.description): k.region for k in footer.query("FooterKey")}

        # the footer composes its keys after the screen's bindings settle: on a slow machine
        # that is later than the first pause, so wait for it (it fails if Quit never appears)
        await until(pilot, lambda: "Quit" in keys())
        assert keys()["Quit"].right <= 80
        tree = app.query_one("#browser", Tree)
        longest = max(len(str(n.label)) for n in tree.root.children)
        assert tree.content_region.width >= longest + tree.guide_depth  # no name is cut
        await pilot.press("b")  # the sidebar folds away and comes back
        await pilot.pause()
        assert not tree.display
        await pilot.press("escape")
        await pilot.pause()
        assert tree.display
        await pilot.press("p")
        await pilot.pause()
        table = app.query_one("#plugin-table", DataTable)
        kind, name, package, _ = table.columns.values()
        # the sidebar folds away; kind, name and package are seen whole, long kinds wrapped in their column
        assert not tree.display and kind.width + name.width + package.width + 6 <= table.content_region.width
        assert name.width >= len("shaft_eccentricity") and kind.width >= len("tooth-shift")
        assert rows(table)[0][0] == "fault" and any("symmetry" in r[0] for r in rows(table))

    drive(GearlabApp(repo_scenarios), script, (80, 24))


# ----------------------------------------------------------------------------- charts, verdict, extras


@pytest.fixture(scope="module")
def finished_runs(tmp_path_factory, kind_streams):
    """Two finished runs of the tiny transfer scenario and the run of the tiny gap scenario, all three
    the every-kind runs (kind_streams): the transfer run twice, under two time stamps, as if run from
    this folder. The same scenario and seeds give the same records (tests/test_crash_safety.py), and
    these tests check the TUI's view of two runs, not the engine."""
    base = tmp_path_factory.mktemp("finished_tui")
    folder = base / "scenarios"
    shutil.copytree(KINDS_DIR, folder)
    (folder / "transfer.toml").write_text(TRANSFER.replace("{runs}", str(base / "runs")))
    made = Path(kind_streams["transfer.toml"][0])
    runs = []
    for later in (0, 1):
        run = base / "runs" / made.parent.name / f"{made.name[:-6]}{int(made.name[-6:]) + later:06d}"
        shutil.copytree(made, run)
        for name in ("scenario.toml", "scenario.original.toml"):
            (run / name).write_text((run / name).read_text().replace('dir = "runs"', f'dir = "{base / "runs"}"'))
        (run / "run.json").write_text((run / "run.json").read_text().replace(str(made.parents[2]), str(base)))
        runs.append(run)
    return folder, runs, Path(kind_streams["tgap.toml"][0])


@pytest.mark.parametrize("size", SIZES)
def test_categorical_charts_are_labelled_bars_and_say_which_of_how_many(finished_runs, size):
    folder, _, gap_run = finished_runs

    async def script(pilot):
        app = pilot.app
        app.show_results(run_entry(gap_run))
        await pilot.pause()
        chart = app.query_one("#chart")
        assert app.charts[0].categories is not None and "mesh" in app.charts[0].categories
        drawn = str(chart.render())
        assert f"chart 1/{len(app.charts)}" in drawn and "mesh" in drawn and "tsa_residual"[:8] in drawn
        await pilot.press("n")
        assert "chart 2/" in str(chart.render())
        assert text_of(app, "#verdict").startswith("The simulator and the target")

    drive(GearlabApp(folder), script, size)


def test_results_open_with_the_verdict_and_o_opens_the_report(finished_runs, monkeypatch):
    folder, (run, _), _ = finished_runs
    opened = []
    monkeypatch.setattr("webbrowser.open", lambda url: opened.append(url) or True)

    async def script(pilot):
        app = pilot.app
        app.show_results(run_entry(run))
        await pilot.pause()
        verdict = text_of(app, "#verdict")
        assert " is best at " in verdict and "points ahead of" in verdict
        await pilot.press("o")
        assert opened == [(run / "report.html").resolve().as_uri()]

    drive(GearlabApp(folder), script)


def test_two_marked_runs_are_compared_and_escape_closes_the_comparison(finished_runs):
    folder, (a, b), _ = finished_runs

    async def script(pilot):
        app = pilot.app
        node = node_named(app, "transfer.toml")
        node.expand()
        await pilot.pause()
        tree = app.query_one("#browser", Tree)
        for child in node.children:
            tree.move_cursor(child)
            await pilot.pause()
            await pilot.press("m")
        assert sorted(app.marked) == sorted([a, b])
        await pilot.press("C")
        await pilot.pause()
        assert app.comparing and "comparison" in text_of(app, "#results-status")
        head = [str(c.label) for c in app.query_one("#results-table", DataTable).columns.values()]
        assert head[:4] == ["method", "k", "A", "B"]
        assert all(" (runs A, B)" in c.title for c in app.charts)
        assert {cv.label.split(":")[0] for cv in app.charts[0].curves} == {"A", "B"}
        await pilot.press("escape")
        await pilot.pause()
        assert not app.comparing

    drive(GearlabApp(folder), script, NARROW)


def test_keys_panel_form_palette_and_notification(kinds_folder, replayed, tmp_path):
    from gearlab.tui.screens import KeysScreen, RunOptionsScreen

    async def script(pilot):
        app = pilot.app
        await pilot.press("question_mark")
        await pilot.pause()
        assert isinstance(app.screen, KeysScreen)
        keys = app.screen.rows
        assert ("C", "Compare the marked runs (two or more, one kind)") in keys
        assert ("f", "Run with options: --quick, --executor, --device, a benchmark's --trials and --seed") in keys
        await pilot.press("escape")
        await pilot.pause()
        assert not isinstance(app.screen, KeysScreen)
        titles = [c.title for c in app.get_system_commands(app.screen)]
        assert {"Run stiff.toml", "Quick run stiff.toml", "Validate stiff.toml"} <= set(titles)
        # the form: quick and an executor, then Run
        await select(pilot, "tbench.toml")
        await pilot.press("f")
        await pilot.pause()
        assert isinstance(app.screen, RunOptionsScreen)
        app.screen.query_one("#quick").value = True
        app.screen.query_one("#executor").value = "local"
        app.screen.query_one("#trials").value = "1"
        app.screen.query_one("#seed").value = "5"
        args = []
        app.follow = lambda a: args.append(a)  # what would run, without running it
        app.screen.query_one("#go").press()
        await pilot.pause()
        (given,) = args
        assert given[:2] == ["gap", str(Path("scenarios") / "tbench.toml")]
        assert given[given.index("--trials") + 1] == "1" and given[given.index("--seed") + 1] == "5"
        assert "--quick" in given and given[given.index("--executor") + 1] == "local"
        assert given[given.index("--out") + 1] == str(Path.cwd() / "runs")
        del app.follow
        # a run's end is notified (the engine's stiff.toml run replayed: the TUI's notice is what is
        # tested; the real child's runs are test_run_fills_the_table_then_opens_the_results's and the others').
        # Each notice is recorded as given: Textual forgets one 5 s of wall time after it was raised, and
        # on a loaded machine the run's end was checked 8.7 s after its notice (the test failed).
        notices, notify = [], app.notify
        app.notify = lambda message, **kw: notices.append(message) or notify(message, **kw)
        await run_to_the_end(pilot, "stiff.toml", then=(tmp_path / "go").touch)
        await pilot.pause()  # the notice is a message the app handles after the status it checks
        assert any("finished" in n for n in notices)

    drive(GearlabApp(Path("scenarios")), script)


def test_results_lines_leave_out_the_tables_and_their_headings():
    from gearlab.tui.app import other_lines

    summary = [
        "gap before 10 -> after 1",
        "per-view gap:",
        "| view | gap |\n|---|---|\n| mesh | 1 |",
        "accuracy:",
        "| model | acc |",
        "note: something",
    ]
    assert other_lines(summary) == ["gap before 10 -> after 1", "note: something"]
