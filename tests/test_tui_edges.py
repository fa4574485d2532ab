"""Issue 41, the TUI's rough edges, at 80x24 and 160x45 (Textual pilot): no bar moves when no
run is in progress; stage bars say counts, rate and ETA; the keys panel wraps its words; chart
legends under the plot; each plugin parameter's doc, unit and bounds; names whole or cut in
the middle with the whole name at hand; every key docs/tui.md lists does what it says.

Runs here are stubs (the engine is tested elsewhere): events fed to the app, a `follow` that
records the command line, two quick stiffness runs made once for the results, marks and
comparison.
"""

from __future__ import annotations

import asyncio
import re
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest
from conftest import ROOT, unrendered
from test_tui import checked
from textual.app import App
from textual.command import CommandPalette
from textual.geometry import Region
from textual.widgets import Input, LoadingIndicator, ProgressBar, Static, TabbedContent, Tabs, Tree

from gearlab import events, terminal
from gearlab.charts import Chart, Curve
from gearlab.events import Event
from gearlab.tui import GearlabApp, progress
from gearlab.tui.progress import StageBar, Stages
from gearlab.tui.screens import KeysScreen, RunOptionsScreen, ScoreScreen
from gearlab.tui.widgets import ChartView, ResultTable

SIZES = [(160, 45), (80, 24)]


def screen_text(app) -> str:
    """What the terminal shows, as text (the screen's composed lines)."""
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def widget_lines(widget) -> list[str]:
    """Every line a widget draws at its size, those scrolled out of view included."""
    return [s.text for s in widget.render_lines(Region(0, 0, *widget.outer_size))]


def table_rows(lines: list[str], columns: list[str]) -> dict[str, dict[str, str]]:
    """The rows of a table drawn as text under a header line naming *columns*, by their first
    cell: each cell's words gathered over the lines it wraps onto."""
    head = next(i for i, line in enumerate(lines) if all(c in line for c in columns))
    starts = [lines[head].index(c) for c in columns] + [None]
    rows, name = {}, None
    for line in lines[head + 1 :]:
        cells = [line[a:b] for a, b in zip(starts, starts[1:])]
        if cells[0].strip():
            name = cells[0].strip()
            rows[name] = dict.fromkeys(columns[1:], "")
        if name is not None:
            for column, cell in zip(columns[1:], cells[1:]):
                rows[name][column] = words(rows[name][column] + " " + cell)
    return rows


def words(text: str) -> str:
    return " ".join(text.split())


async def tab_underline_at_rest(pilot) -> None:
    """Until the tabs' underline lies still under the active tab. Textual slides it there over 0.3 s
    of wall time, begun by a 20 ms timer set at the switch; `pilot.press` waits only for animations
    already begun, so on a loaded machine it can return before that timer fires and the underline
    then moves between two reads of the screen (test_no_bar_moves_... failed so under pytest -n 2)."""
    app = pilot.app
    tabs = app.query_one("#views", TabbedContent).query_one(Tabs)
    underline = tabs.query_one("Underline")
    for _ in range(1000):  # 10 s at most
        tab = tabs.active_tab
        span = tab.virtual_region.shrink(tab.styles.gutter).column_span  # where Textual puts it
        moving = any(app.animator.is_being_animated(underline, a) for a in ("highlight_start", "highlight_end"))
        if (underline.highlight_start, underline.highlight_end) == span and not moving:
            await pilot.pause()
            return
        await pilot.pause(0.01)
    pytest.fail(f"the tab underline did not come to rest under {tabs.active!r} in 10 s")


@pytest.fixture
def clock(monkeypatch):
    """A clock the stage bars read (the Pace of gearlab.events, the terminal's and the TUI's bars),
    moved by hand."""
    now = SimpleNamespace(t=1000.0)
    fake = SimpleNamespace(monotonic=lambda: now.t)
    for module in (events, progress, terminal):
        monkeypatch.setattr(module, "time", fake)
    return now


# ----------------------------------------------------------------------------- progress


def test_a_stage_bar_says_counts_rate_and_eta_and_holds_still_once_the_run_ends(clock):
    class Host(App):
        def compose(self):
            yield Stages()

    async def main():
        async with Host().run_test(size=(100, 12)) as pilot:
            stages = pilot.app.query_one(Stages)
            stages.reset()
            stages.start("runs", "4 training runs", 4)
            stages.start("prime", "priming", 0)  # a stage that cannot count its steps
            await pilot.pause()
            runs, prime = pilot.app.query(StageBar)
            assert runs.status() == "0/4 (0 %)  elapsed 0:00  ETA after the first step"
            clock.t += 10
            stages.advance("runs", 1, 4)
            assert runs.status() == "1/4 (25 %)  0:10/step  elapsed 0:10  ETA 0:30"
            clock.t += 10
            stages.advance("runs", 3, 4)  # 3 steps in 20 s: 0:07 a step, 7 s left
            assert runs.status() == "3/4 (75 %)  0:07/step  elapsed 0:20  ETA 0:07"
            assert prime.status() == "working, its steps not counted  elapsed 0:20"
            await pilot.pause()
            drawn = screen_text(pilot.app)
            assert "4 training runs" in drawn and "3/4 (75 %)  0:07/step  elapsed 0:20  ETA 0:07" in drawn
            assert "━" * 18 + "─" * 6 in drawn  # 3/4 of the 24-cell bar
            stages.stop()  # cancelled: the unfinished stages stop where they were
            assert runs.status() == "3/4 (75 %)  stopped after 0:20"
            assert prime.status() == "0 steps  stopped after 0:20"
            await pilot.pause()
            before = screen_text(pilot.app)
            clock.t += 100
            stages._tick()
            await pilot.pause()
            assert screen_text(pilot.app) == before and not stages.ticking

    asyncio.run(main())


def test_a_finished_stage_says_done_with_its_time(clock):
    bar = StageBar("simulate", 2)
    clock.t += 4
    bar.advance(2, 2)
    clock.t += 50  # the run goes on with other stages: this one's time stays
    assert bar.status() == "2/2 (100 %)  done in 0:04"


@pytest.mark.parametrize("size", SIZES)
def test_no_bar_moves_when_no_run_is_in_progress(scenarios, clock, size):
    async def main():
        async with GearlabApp(scenarios).run_test(size=size) as pilot:
            app = pilot.app
            await checked(pilot)  # no mark lands between the frames compared
            await pilot.press("2")
            await tab_underline_at_rest(pilot)  # the switch's own motion ends before anything is compared
            # nothing runs: a line that says so, no bar and nothing animated
            assert "no run yet" in screen_text(app)
            assert not app.query(StageBar) and not app.query(ProgressBar) and not app.query(LoadingIndicator)
            # a run (its events, as the child process sends them) ...
            app.query_one(Stages).reset()
            app.on_run_event(Event("stage", stage="simulate", total=12, message="B-6-ch5: 12 simulations"))
            clock.t += 30
            app.on_run_event(Event("advance", stage="simulate", done=3, total=12))
            await pilot.pause()
            line = "3/12 (25 %)  0:10/step  elapsed 0:30  ETA 1:30"
            assert line in screen_text(app)  # whole at 80 columns
            # ... ends: the bars hold still
            app.cancelled = True
            app.finish(-15, "")
            await pilot.pause()
            still = screen_text(app)
            assert "3/12 (25 %)  stopped after 0:30" in still and "cancelled" in still
            clock.t += 100
            app.query_one(Stages)._tick()  # the one-second clock's tick, at once (not waited for 1.2 s)
            await pilot.pause()
            assert screen_text(app) == still

    asyncio.run(main())


# ----------------------------------------------------------------------------- keys panel


def docs_keys() -> list[str]:
    """The keys of docs/tui.md's table, one token each ('r', '↑', 'enter', 'ctrl+p', 'F5')."""
    text = (ROOT / "docs" / "tui.md").read_text()
    table = text.split("| key | what it does |")[1].split("\n\n")[0]
    keys = []
    for row in table.splitlines()[2:]:
        first = row.split("|")[1]
        ticked = re.findall(r"`([^`]+)`", first)
        keys += ticked or [t for t in first.split() if t != "/"]
    return keys


@pytest.mark.parametrize("size", SIZES)
def test_the_keys_panel_lists_every_documented_key_with_its_words_whole(scenarios, size):
    async def main():
        async with GearlabApp(scenarios).run_test(size=size) as pilot:
            await checked(pilot)
            await pilot.press("question_mark")
            await pilot.pause()
            panel = pilot.app.screen
            assert isinstance(panel, KeysScreen)
            listed = {token.lower() for key, _ in panel.rows for token in key.split()}
            assert {k.lower() for k in docs_keys()} <= listed
            # every description, wrapped at the panel's width, reads whole (no word cut)
            drawn = words(" ".join(widget_lines(panel.query_one("#keys", Static))))
            for key, what in panel.rows:
                assert words(what) in drawn, (key, what)
            assert "Cancel the run in progress (its finished units stay)" in drawn
            assert panel.query_one("#keys").region.right <= size[0]

    asyncio.run(main())


# ----------------------------------------------------------------------------- charts


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize("bars", [False, True], ids=["curves", "bars"])
def test_chart_legends_are_under_the_plot(size, bars):
    labels = ["A: source_only (unsupervised)", "A: mmd (unsupervised)", "B: dann (unsupervised, k-shot)"]
    chart = Chart(
        "accuracy against k",
        "k",
        "accuracy (%)",
        tuple(Curve(label, [0, 2, 4], [50 + i, 70 - i, 90]) for i, label in enumerate(labels)),
        categories=["mesh", "shaft", "noise_floor"] if bars else None,
    )

    class Host(App):
        def compose(self):
            yield ChartView()

    async def main():
        async with Host().run_test(size=size) as pilot:
            view = pilot.app.query_one(ChartView)
            view.show(chart, "chart 1/1")
            await pilot.pause()
            lines = widget_lines(view)
            bottom = max(i for i, line in enumerate(lines) if "└" in line)  # the plot's lower frame
            plot, below = lines[: bottom + 1], words(" ".join(lines[bottom + 1 :]))
            for label in labels:
                assert label in below  # whole, in the legend under the plot
                assert not any(label[:6] in line for line in plot)  # nothing drawn over the curves
            assert len(plot) >= ChartView.PLOT_HEIGHT - 2 and max(len(line.rstrip()) for line in lines) <= size[0]

    asyncio.run(main())


def test_a_chart_is_drawn_again_only_for_new_content_heading_or_width(monkeypatch):
    """A run opened again gives a new Chart of the same numbers: drawn once (plotext takes up to
    0.3 s a chart; test_tui_edges drew 26 of its 45 charts twice); any float, label, heading or
    width changed draws anew."""
    from gearlab.tui import widgets

    monkeypatch.setattr(widgets, "DRAWN", type(widgets.DRAWN)())
    drawn = []
    real = ChartView._draw

    def counted(self, chart, curves, head, width):
        drawn.append((head, width))
        return real(self, chart, curves, head, width)

    monkeypatch.setattr(ChartView, "_draw", counted)

    def chart(y=(1.0, 3.0, 2.0), label="a", title="t"):
        return Chart(title, "x", "y", (Curve(label, [0, 1, 2], list(y)), Curve("b", [0, 1, 2], [2, 2, 2])))

    def render(chart, place="", width=60):
        class Sized(ChartView):
            size = Region(0, 0, width, 20).size

        view = Sized()
        view.chart, view.place = chart, place
        return view.render()

    first = render(chart())
    assert render(chart()) is first and drawn == [("t", 60)]  # the same numbers in another Chart: kept
    others = [chart(y=(1.0, 3.0, 2.0 + 1e-12)), chart(label="c"), chart(title="u")]
    for n, other in enumerate(others, start=2):
        render(other)
        assert len(drawn) == n  # one float, a label, the title: drawn anew
    render(chart(), place="chart 2/3")
    render(chart(), width=80)
    assert drawn[-2:] == [("chart 2/3: t", 60), ("t", 80)]
    assert render(chart(label="c")).plain and len(drawn) == 6
    widgets.DRAWN.clear()
    assert render(chart()).plain == first.plain and len(drawn) == 7


# ----------------------------------------------------------------------------- plugins


@pytest.mark.parametrize("size", SIZES)
def test_plugin_parameters_show_their_doc_unit_and_bounds(scenarios, size):
    async def main():
        async with GearlabApp(scenarios).run_test(size=size) as pilot:
            app = pilot.app
            await checked(pilot)
            await pilot.press("p")
            await pilot.pause()
            table = app.query_one("#plugin-table")
            assert app.focused is table  # ↑ ↓ move in the table at once
            crack = next(i for i, row in enumerate(table.ordered_rows) if table.get_row(row.key)[1] == "crack")
            for _ in range(crack):
                await pilot.press("down")
            await pilot.pause()
            lines = widget_lines(app.query_one("#plugin-detail"))
            assert words(" ".join(lines)).startswith(
                "crack fault, package gearlab Root crack, parabolic across the face width (Chen & Shao 2011); "
                "full depth = broken tooth."
            )
            # each parameter: its doc, the unit shown and the SI one stored, default and bounds
            params = table_rows(lines, ["parameter", "what it is", "unit", "default", "bounds"])
            assert list(params) == ["q0", "q2", "L_c", "nu"]
            assert params["q0"] == {
                "what it is": "crack depth at the first tooth edge",
                "unit": "mm (SI: m)",
                "default": "0 mm",
                "bounds": "0 .. 50 mm",
            }
            assert params["nu"]["unit"] == "deg (SI: rad)" and params["nu"]["bounds"] == "1 .. 90 deg"
            seen = words(screen_text(app))
            assert "crack depth at the first" in seen  # on screen, not only in the pane's content
            # the table's columns, the parameters' included, are within the screen: wrapped, not cut
            used = sum(c.width + 2 for c in table.columns.values())
            assert used <= table.content_region.width
            await pilot.press("down")
            await pilot.pause()
            assert "parabolic" not in words(" ".join(widget_lines(app.query_one("#plugin-detail"))))

    asyncio.run(main())


# ----------------------------------------------------------------------------- names


LONG = "gap_expA_with_a_name_longer_than_any_sidebar_can_hold_at_either_size_of_the_tests_v2.toml"


@pytest.mark.parametrize("size", SIZES)
def test_names_stay_whole_or_are_cut_in_the_middle_with_the_whole_name_at_hand(scenarios, size):
    (scenarios / LONG).write_text((scenarios / "stiff.toml").read_text().replace('"stiff"', '"long"'))

    async def main():
        async with GearlabApp(scenarios).run_test(size=size) as pilot:
            app = pilot.app
            tree = app.query_one("#browser", Tree)
            # run_test returns with the first layout still pending (drawn when Textual's 1/60 s screen timer
            # fires): the screen read after it, not a frame that depends on whether that timer fired
            await checked(pilot)
            drawn = screen_text(app)
            # a scenario with runs (its ▶ takes two cells) and the longest shipped name: whole
            assert "▶ ✓ stiffness_verification.toml" in drawn
            node = next(n for n in tree.root.children if LONG in str(n.label))
            line = next(line for line in drawn.splitlines() if "gap_expA_with" in line)
            assert "…" in line and line.split("│")[0].rstrip().endswith("_tests_v2.toml")  # start and end kept
            tree.move_cursor(node)
            await pilot.pause()
            assert tree.tooltip == f"scenarios/{LONG}"
            assert f"scenarios/{LONG}" in words(str(app.query_one("#scenario-status").render())).replace(" ", "")

    asyncio.run(main())


def test_a_long_column_name_wraps_in_its_header_and_later_headers_are_not_cut():
    class Host(App):
        def compose(self):
            yield ResultTable()

    name = "Bayes bound (target's own shapes and noise law, best threshold)"
    text = f"| k | {name} |\n|---|---|\n| 0 | 100.00 ± 0.0 |\n\n"
    text += "| a much longer later header | b |\n|---|---|\n| 1 | 2 |\n"

    async def main():
        async with Host().run_test(size=(80, 24)) as pilot:
            table = pilot.app.query_one(ResultTable)
            table.show_markdown(text)
            await pilot.pause()
            k, bayes = table.columns.values()
            head = bayes.label.plain.splitlines()
            assert words(" ".join(head)) == name and max(len(h) for h in head) <= bayes.width
            assert table.header_height == len(head) >= 3
            assert k.width >= len("a much longer later header")

    asyncio.run(main())


# ----------------------------------------------------------------------------- every key


def stiff_text() -> str:
    """The shipped stiffness_verification.toml named stiff, its TVMS at 512 points instead of 4096:
    the results tab's chart of six curves then takes plotext 0.05 s to draw, not 0.2-0.3 s (the
    every-key walks draw it a dozen times each); the same cases, ladders and charts."""
    text = (ROOT / "scenarios" / "stiffness_verification.toml").read_text().split("[output]")[0]
    assert "points = 4096" in text
    return text.replace('name = "stiffness_verification"', 'name = "stiff"').replace("points = 4096", "points = 512")


@pytest.fixture(scope="module")
def made_runs(tmp_path_factory):
    """Two finished quick stiffness runs: one made once, twice (the scenarios fixture copies each
    under its own time stamp; the same scenario gives the same run, and these tests read the
    TUI's view of two runs, not the engine)."""
    from gearlab.engine import run_scenario

    base = tmp_path_factory.mktemp("edges")
    source = base / "stiff.toml"
    source.write_text(stiff_text())
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("gearlab.plots.save", unrendered)  # these tests show no figure's pixels
        return [run_scenario(source, out=base / "made", quick=True).path] * 2


@pytest.fixture
def scenarios(tmp_path, monkeypatch, made_runs):
    """scenarios/: stiff.toml with the two finished runs and an unfinished one, and the
    shipped stiffness_verification.toml with a past run (the longest name, with its ▶)."""
    monkeypatch.chdir(tmp_path)
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "stiff.toml").write_text(stiff_text() + '[output]\ndir = "runs"\n')
    shutil.copy(ROOT / "scenarios" / "stiffness_verification.toml", folder)
    for i, run in enumerate(made_runs):
        shutil.copytree(run, tmp_path / "runs" / "stiff" / f"2026010{i + 2}-000000-000000")
    unfinished = tmp_path / "runs" / "stiff" / "20260101-000000-000000"
    shutil.copytree(made_runs[0], unfinished)
    (unfinished / "summary.json").unlink()
    ver = tmp_path / "runs" / "stiffness_verification" / "20260101-000000-000000"
    ver.mkdir(parents=True)
    shutil.copy(folder / "stiffness_verification.toml", ver / "scenario.toml")
    return Path("scenarios")


KEY_NAMES = {"↑": "up", "↓": "down", "→": "right", "←": "left", "?": "question_mark", "F5": "f5"}
pressed: set[str] = set()


async def key(pilot, name: str) -> None:
    pressed.add(name)
    await pilot.press(name)
    await pilot.pause()


# The walks of every key, at 80x24 alone: what a key does is the same at 160x45, where the sidebar stays up for the
# run and its results; at 80x24 it folds away for them (switch_to), so that b there is pressed both from folded and
# from shown (the one branch the width adds). test_tui_arrows and test_tui's tests of the layout take both sizes.
NARROW = SIZES[1]


def test_every_key_of_the_docs_does_what_they_say(scenarios, monkeypatch):
    size = NARROW
    opened = []
    monkeypatch.setattr("webbrowser.open", lambda url: opened.append(url) or True)
    runs = Path.cwd() / "runs" / "stiff"
    pressed.clear()

    async def main():
        app = GearlabApp(scenarios)
        started = []
        app.follow = lambda args: started.append(args)  # the command line a run would be
        async with app.run_test(size=size) as pilot:
            await checked(pilot)
            tree = app.query_one("#browser", Tree)
            tabs = app.query_one("#views", TabbedContent)
            tree.focus()
            assert tree.cursor_node.data.path.name == "stiff.toml"  # the first scenario
            # ↓ ↑ move; → unfolds and enters, ← goes back up and folds
            await key(pilot, "down")
            assert tree.cursor_node.data.path.name == "stiffness_verification.toml"
            await key(pilot, "up")
            stiff = tree.cursor_node
            await key(pilot, "right")
            assert stiff.is_expanded and tree.cursor_node is stiff
            await key(pilot, "right")
            assert tree.cursor_node is stiff.children[0]
            await key(pilot, "left")
            await key(pilot, "left")
            assert tree.cursor_node is stiff and not stiff.is_expanded
            # enter opens a scenario in the Scenario tab
            await key(pilot, "enter")
            assert tabs.active == "scenario" and "✓ valid" in str(app.query_one("#scenario-status").render())
            # r, k: a run of the highlighted scenario, quick with k, into the folder the tree reads
            await key(pilot, "r")
            assert started[-1] == ["run", "scenarios/stiff.toml", "--out", str(Path.cwd() / "runs")]
            assert tabs.active == "run"
            await key(pilot, "k")
            assert started[-1][-1] == "--quick" and len(started) == 2
            # f: the form; escape closes it and nothing runs
            await key(pilot, "f")
            assert isinstance(app.screen, RunOptionsScreen)
            await key(pilot, "escape")
            assert not isinstance(app.screen, RunOptionsScreen) and len(started) == 2
            # c cancels the run in progress: its whole process group ends
            child = subprocess.Popen(["sleep", "30"], start_new_session=True)
            app.process = child
            await key(pilot, "c")
            assert child.wait(timeout=10) != 0
            app.process = None
            # enter on a run opens it in the Results tab; n cycles its charts
            await key(pilot, "1")
            tree.focus()
            stiff.expand()
            await pilot.pause()
            newest, older, unfinished = stiff.children
            tree.move_cursor(newest)
            await key(pilot, "enter")
            assert tabs.active == "results" and "finished" in str(app.query_one("#results-status").render())
            assert len(app.charts) == 2 and app.chart_index == 0
            await key(pilot, "n")
            assert app.chart_index == 1
            # o opens the highlighted run's report
            await key(pilot, "o")
            assert opened == [(runs / "20260103-000000-000000" / "report.html").resolve().as_uri()]
            # s scores with a finished detection run only: this stiffness run is refused, no form opens
            await key(pilot, "s")
            assert not isinstance(app.screen, ScoreScreen) and len(started) == 2
            # u resumes the highlighted unfinished run only
            await key(pilot, "u")
            assert len(started) == 2  # a finished run: refused
            tree.move_cursor(unfinished)
            await key(pilot, "u")
            assert started[-1] == ["run", "--resume", str(runs / "20260101-000000-000000")]
            # m marks, C compares, escape closes the comparison
            for run in (newest, older):
                tree.move_cursor(run)
                await key(pilot, "m")
            assert str(newest.label).startswith("▣") and len(app.marked) == 2
            await key(pilot, "C")
            assert app.comparing and tabs.active == "results"
            await key(pilot, "escape")
            assert not app.comparing
            # b folds the sidebar and shows it again; escape shows it too
            shown = tree.display
            await key(pilot, "b")
            assert tree.display is not shown
            if tree.display:
                await key(pilot, "b")
                assert not tree.display
            await key(pilot, "escape")
            assert tree.display
            # p, 1, 2, 3: the tabs
            for name, tab in (("p", "plugins"), ("1", "scenario"), ("2", "run"), ("3", "results")):
                await key(pilot, name)
                assert tabs.active == tab
            await key(pilot, "1")
            # F5 reads the folder again
            (scenarios / "zz.toml").write_text((scenarios / "stiff.toml").read_text())
            await key(pilot, "f5")
            assert str(tree.root.children[-1].label).endswith("zz.toml")
            # ? and ctrl+p open their panels, escape closes each
            await key(pilot, "question_mark")
            assert isinstance(app.screen, KeysScreen)
            await key(pilot, "escape")
            await key(pilot, "ctrl+p")
            assert isinstance(app.screen, CommandPalette)
            await key(pilot, "escape")
            assert not isinstance(app.screen, (KeysScreen, CommandPalette))
            # q quits
            await key(pilot, "q")
            assert app.return_code == 0
        assert {KEY_NAMES.get(k, k) for k in docs_keys()} <= pressed  # not one key of the docs left out

    asyncio.run(main())


def test_the_docs_finer_key_points_palette_escape_order_o_on_the_shown_run_and_q_during_a_run(scenarios, monkeypatch):
    """What the every-key walk leaves out of docs/tui.md's table: ctrl+p opens a run and compares
    the marked runs; escape closes a panel first, then the comparison, then unfolds the sidebar;
    `o` with a scenario highlighted opens the run on show; `q` cancels a run in progress."""
    opened = []
    monkeypatch.setattr("webbrowser.open", lambda url: opened.append(url) or True)
    runs = Path.cwd() / "runs" / "stiff"

    async def palette(pilot, command: str) -> None:
        await pilot.press("ctrl+p")
        await pilot.pause()
        screen = pilot.app.screen
        assert isinstance(screen, CommandPalette)
        screen.query_one(Input).value = command  # as typed, but searched once, not once a character
        await pilot.pause()
        # the palette searches in the background: until its searches ended (not a pause hoped long enough)
        for _ in range(6000):  # a minute at most
            if not any(w.node is screen and not w.is_finished for w in pilot.app.workers):
                break
            await pilot.pause(0.01)
        await pilot.press("down", "enter")
        await pilot.pause()

    async def main():
        app = GearlabApp(scenarios)
        async with app.run_test(size=NARROW) as pilot:
            await checked(pilot)
            tree = app.query_one("#browser", Tree)
            tabs = app.query_one("#views", TabbedContent)
            await palette(pilot, "Open run stiff.toml 20260103")
            assert tabs.active == "results" and app.opened.path.name == "20260103-000000-000000"
            tree.move_cursor(tree.root.children[0])  # a scenario highlighted: o opens the run on show
            await key(pilot, "o")
            assert opened == [(runs / "20260103-000000-000000" / "report.html").resolve().as_uri()]
            stiff = tree.root.children[0]
            for run in stiff.children[:2]:
                tree.move_cursor(run)
                await key(pilot, "m")
            await palette(pilot, "Compare the 2 marked")
            assert app.comparing and tabs.active == "results"
            app.tree.add_class("folded")
            await key(pilot, "question_mark")
            await key(pilot, "escape")  # the panel first
            assert not isinstance(app.screen, KeysScreen) and app.comparing and tree.has_class("folded")
            await key(pilot, "escape")  # then the comparison
            assert not app.comparing and tree.has_class("folded")
            await key(pilot, "escape")  # then the sidebar
            assert not tree.has_class("folded")
            child = subprocess.Popen(["sleep", "30"], start_new_session=True)
            app.process = child
            await key(pilot, "q")
            assert child.wait(timeout=10) != 0 and app.return_code == 0

    asyncio.run(main())
