"""`gearlab tui [DIR]`: browse scenarios, run one and watch it, read results, list plugins.

A run is the CLI's own `gearlab run SCENARIO --events` in a child process: the TUI reads its
progress events (JSON lines, gearlab.runs.Event) and draws them, so the TUI and the CLI share
one run engine and one event stream. Cancelling stops the child's whole process group; the
units it finished are already in the run directory, and `u` resumes the run.
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
import sys
from pathlib import Path

from rich.markup import escape
from rich.syntax import Syntax
from rich.text import Text
from textual import work
from textual.app import App, ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.widgets import DataTable, Footer, RichLog, Static, TabbedContent, TabPane, Tree

from ..errors import GearlabInputError
from ..kinds import KINDS
from ..runs import Event, RunDir
from ..scenario import Scenario
from .catalog import RunEntry, ScenarioEntry, error_line, run_entry, scan
from .widgets import ChartView, ResultTable, Stages


class GearlabApp(App):
    TITLE = "gearlab"
    CSS = """
    #browser { width: 26; border-right: solid $primary-darken-2; }
    #views { width: 1fr; }
    #scenario-status, #run-status, #results-status, #units { padding: 0 1; }
    #toml { padding: 0 1; }
    #log { height: 1fr; min-height: 4; border-top: solid $primary-darken-2; }
    #results-lines { padding: 0 1; height: auto; }
    #plugin-table { height: 1fr; }
    #problems { height: auto; padding: 0 1; color: $error; }
    """
    BINDINGS = [
        Binding("r", "run(False)", "Run"),
        Binding("k", "run(True)", "Quick run"),
        Binding("c", "cancel", "Cancel"),
        Binding("u", "resume", "Resume"),
        Binding("n", "next_chart", "Next chart"),
        Binding("1", "show('scenario')", "Scenario", show=False),
        Binding("2", "show('run')", "Progress", show=False),
        Binding("3", "show('results')", "Results", show=False),
        Binding("p", "show('plugins')", "Plugins"),
        Binding("f5", "rescan", "Rescan"),
        Binding("q", "quit", "Quit"),
    ]

    def __init__(self, directory: Path | str = "scenarios"):
        super().__init__()
        self.directory = Path(directory)
        self.entries: list[ScenarioEntry] = []
        self.selected: ScenarioEntry | None = None  # the scenario on show
        self.opened: RunEntry | None = None  # the run whose results are on show
        self.process: asyncio.subprocess.Process | None = None
        self.cancelled = False
        self.run_scenario: Scenario | None = None  # the scenario of the run in progress, as it runs
        self.run_path: Path | None = None
        self.records: list[dict] = []
        self.running: dict[str, str] = {}  # units in progress: how far each is
        self.charts: list = []
        self.chart_index = 0

    # ------------------------------------------------------------------ layout
    def compose(self) -> ComposeResult:
        with Horizontal():
            yield Tree("scenarios", id="browser")
            with TabbedContent(id="views", initial="scenario"):
                with TabPane("Scenario", id="scenario"):
                    with VerticalScroll():
                        yield Static("select a scenario", id="scenario-status")
                        yield Static("", id="toml")
                with TabPane("Progress", id="run"):
                    yield Static("no run yet: select a scenario and press r (or k for a quick run)", id="run-status")
                    yield Stages(id="stages")
                    yield Static("", id="units")
                    yield ResultTable(id="live")
                    yield RichLog(id="log", wrap=True, markup=False)
                with TabPane("Results", id="results"):
                    with VerticalScroll():
                        yield Static("select a run in the tree (under its scenario)", id="results-status")
                        yield ResultTable(id="results-table")
                        yield ChartView(id="chart")
                        yield Static("", id="results-lines")
                with TabPane("Plugins", id="plugins"):
                    yield DataTable(id="plugin-table", cursor_type="row")
                    yield Static("", id="problems")
        yield Footer()

    def on_mount(self) -> None:
        self.rescan()
        self.fill_plugins()

    # ------------------------------------------------------------------ browser
    def action_rescan(self) -> None:
        self.rescan()

    def rescan(self) -> None:
        tree = self.query_one("#browser", Tree)
        tree.clear()
        tree.root.set_label(str(self.directory))
        tree.root.expand()
        if not self.directory.is_dir():
            tree.root.add_leaf(Text(f"no such directory: {self.directory}", style="red"))
            self.entries = []
            return
        self.entries = scan(self.directory)
        if not self.entries:
            tree.root.add_leaf(Text("no scenario files (*.toml) here", style="dim"))
        for entry in self.entries:
            name = str(entry.path.relative_to(self.directory))
            label = Text.assemble(("✓ " if entry.ok else "✗ ", "green" if entry.ok else "red"), name)
            node = tree.root.add(label, data=entry, expand=False, allow_expand=bool(entry.runs))
            for run in entry.runs:
                node.add_leaf(self._run_label(run), data=run)
        if self.selected is not None:  # keep showing the same file after a rescan
            self.selected = next((e for e in self.entries if e.path == self.selected.path), None)
            self.show_scenario(self.selected)

    @staticmethod
    def _run_label(run: RunEntry) -> Text:
        name = run.path.name  # YYYYmmdd-HHMMSS-ffffff: shown as mm-dd HH:MM:SS
        when = f"{name[4:6]}-{name[6:8]} {name[9:11]}:{name[11:13]}:{name[13:15]}" if len(name) >= 15 else name
        return Text.assemble(("● " if run.finished else "◐ ", "green" if run.finished else "yellow"),
                             when, ("" if run.finished else f" {run.units} units", "dim"))

    def on_tree_node_highlighted(self, event: Tree.NodeHighlighted) -> None:
        self._open(event.node.data, switch=False)  # moving through the tree only fills the views

    def on_tree_node_selected(self, event: Tree.NodeSelected) -> None:
        self._open(event.node.data, switch=True)

    def _open(self, data, switch: bool) -> None:
        if not self.query("#views"):  # a highlight queued while the app closes: the views are gone
            return
        if isinstance(data, ScenarioEntry):
            self.selected = data
            self.show_scenario(data, switch)
        elif isinstance(data, RunEntry):
            self.selected = next((e for e in self.entries if data in e.runs), self.selected)
            self.show_results(data, switch)

    # ------------------------------------------------------------------ scenario view
    def show_scenario(self, entry: ScenarioEntry | None, switch: bool = False) -> None:
        status = self.query_one("#scenario-status", Static)
        toml = self.query_one("#toml", Static)
        if entry is None:
            status.update("select a scenario")
            toml.update("")
            return
        try:
            text = entry.path.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            text = f"# cannot read {entry.path}: {exc}"
        if entry.ok:
            s = entry.scenario
            runs = f"{len(entry.runs)} past run(s)" if entry.runs else "no past runs"
            status.update(Text.assemble(("✓ valid", "bold green"), f"  {s.name} ({s.kind}): {s.description}\n",
                                        KINDS[s.kind].describe(s), f"\n{runs}; r run, k quick run"))
            marked = set()
        else:
            status.update(Text.assemble(("✗ invalid  ", "bold red"), entry.error))
            line = error_line(text, entry.error)
            marked = {line} if line else set()
        toml.update(Syntax(text, "toml", line_numbers=True, highlight_lines=marked, word_wrap=True))
        if switch:
            self.query_one("#views", TabbedContent).active = "scenario"

    # ------------------------------------------------------------------ runs
    def action_run(self, quick: bool) -> None:
        entry = self.selected
        if self.process is not None:
            self.notify("a run is in progress; c cancels it", severity="warning")
        elif entry is None or not entry.ok:
            self.notify("select a valid scenario first", severity="warning")
        else:
            self.start(["run", str(entry.path)] + (["--quick"] if quick else []), entry.path, resume=None)

    def action_resume(self) -> None:
        run = self.opened
        if self.process is not None:
            self.notify("a run is in progress; c cancels it", severity="warning")
        elif run is None or run.finished:
            self.notify("select an unfinished run in the tree to resume it", severity="warning")
        else:
            self.start(["run", "--resume", str(run.path)], None, resume=run.path)

    def action_cancel(self) -> None:
        if self.process is None:
            self.notify("no run in progress")
            return
        self.cancelled = True
        try:
            os.killpg(self.process.pid, signal.SIGTERM)  # the run and its worker processes
        except ProcessLookupError:
            pass
        self.query_one("#log", RichLog).write("cancelling ...")

    def start(self, args: list[str], scenario_path: Path | None, resume: Path | None) -> None:
        self.cancelled = False
        self.records = []
        self.run_path = resume
        self.run_scenario = None
        try:
            if resume is not None:
                run = RunDir.open(resume)
                self.run_scenario = run.scenario()
                self.records = run.records()
            else:
                from ..scenario import load_scenario

                self.run_scenario = load_scenario(scenario_path)
                if "--quick" in args:
                    KINDS[self.run_scenario.kind].quick(self.run_scenario)
        except GearlabInputError as exc:
            self.notify(str(exc), severity="error")
            return
        self.query_one("#stages", Stages).reset()
        self.running = {}
        self.query_one("#units", Static).update("")
        self.query_one("#log", RichLog).clear()
        self.query_one("#run-status", Static).update(
            f"{'resuming' if resume else 'running'} {self.run_scenario.name} ({self.run_scenario.kind}); c cancels")
        self.refresh_live()
        self.query_one("#views", TabbedContent).active = "run"
        self.follow(args)

    @work(exclusive=True, group="run")
    async def follow(self, args: list[str]) -> None:
        """Run `gearlab ... --events` in a child process and draw its events until it ends."""
        log = self.query_one("#log", RichLog)
        self.process = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "gearlab", *args, "--events",
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
            start_new_session=True,  # its own process group, so that cancel reaches its workers
            limit=1 << 26,  # a record line carries training curves
        )
        errors = asyncio.create_task(self.process.stderr.read())
        async for raw in self.process.stdout:
            line = raw.decode(errors="replace").rstrip("\n")
            try:
                event = Event.from_json(line)
            except (json.JSONDecodeError, TypeError):
                log.write(line)
                continue
            self.on_run_event(event)
        code = await self.process.wait()
        stderr = (await errors).decode(errors="replace").strip()
        self.process = None
        self.finish(code, stderr)

    def on_run_event(self, event: Event) -> None:
        stages = self.query_one("#stages", Stages)
        if event.kind == "run":
            self.run_path = Path(event.message)
        elif event.kind == "stage":
            stages.start(event.stage, event.message, event.total)
        elif event.kind == "advance":
            stages.advance(event.stage, event.done, event.total)
        elif event.kind == "unit":  # a unit in progress says how far it is; empty: it ended
            if event.message:
                self.running[event.stage] = event.message
            else:
                self.running.pop(event.stage, None)
            self.query_one("#units", Static).update(
                Text("\n".join(f"▸ {unit}: {text}" for unit, text in sorted(self.running.items())), style="dim"))
        elif event.kind == "record" and event.record is not None:
            self.records.append(event.record)
            self.refresh_live()
        elif event.kind == "log":
            self.query_one("#log", RichLog).write(event.message)

    def refresh_live(self) -> None:
        if self.run_scenario is not None:
            kind = KINDS[self.run_scenario.kind]
            self.query_one("#live", ResultTable).show_markdown(kind.records_table(self.run_scenario, self.records))

    def finish(self, code: int, stderr: str) -> None:
        self.running = {}
        self.query_one("#units", Static).update("")
        log = self.query_one("#log", RichLog)
        status = self.query_one("#run-status", Static)
        where = f" in {self.run_path}" if self.run_path else ""
        if self.cancelled:
            status.update(f"cancelled: {len(self.records)} finished unit(s) kept{where}; select the run, u resumes it")
        elif code == 0:
            status.update(Text(f"finished: {len(self.records)} unit(s){where}", style="green"))
        else:
            last = stderr.splitlines()[-1] if stderr else f"exit code {code}"
            status.update(Text(f"failed (exit {code}): {last}", style="red"))
            log.write(stderr)
        self.rescan()
        if self.run_path is not None and (self.run_path / "scenario.toml").is_file():
            self.show_results(run_entry(self.run_path), switch=code == 0 and not self.cancelled)

    # ------------------------------------------------------------------ results
    def show_results(self, run: RunEntry, switch: bool = True) -> None:
        self.opened = run
        status = self.query_one("#results-status", Static)
        table = self.query_one("#results-table", ResultTable)
        lines = self.query_one("#results-lines", Static)
        try:
            rundir = RunDir.open(run.path)
            scenario = rundir.scenario()
            kind = KINDS[scenario.kind]
            table.show_markdown(kind.records_table(scenario, rundir.records()))
            self.charts = kind.charts(scenario, rundir)
            summary = kind.summary_lines(rundir) if run.finished else []
        except (GearlabInputError, OSError, ValueError, KeyError) as exc:
            status.update(Text(f"{run.path}: cannot show this run: {exc}", style="red"))
            table.clear(columns=True)
            self.charts = []
            self.query_one("#chart", ChartView).show(None)
            return
        state = "finished" if run.finished else f"not finished ({run.units} units kept; u resumes it)"
        status.update(Text.assemble((f"{scenario.name} ", "bold"), f"({scenario.kind}), {run.path.name}: {state}"))
        # the table is above; summary_lines repeats it as markdown, so keep only the other lines
        lines.update(escape("\n".join(line for line in summary if not line.lstrip().startswith("|"))))
        self.chart_index = 0
        self.show_chart()
        if switch:
            self.query_one("#views", TabbedContent).active = "results"

    def show_chart(self) -> None:
        chart = self.charts[self.chart_index] if self.charts else None
        self.query_one("#chart", ChartView).show(chart)

    def action_next_chart(self) -> None:
        if self.charts:
            self.chart_index = (self.chart_index + 1) % len(self.charts)
            self.show_chart()

    # ------------------------------------------------------------------ plugins
    def fill_plugins(self) -> None:
        from ..registry import get_registry, kind_text, params_text

        registry = get_registry()
        table = self.query_one("#plugin-table", DataTable)
        table.add_columns("kind", "name", "package", "parameters")
        for row in registry.describe():
            # Text, not str: a DataTable reads "[mm]" in a string as markup
            table.add_row(kind_text(row), row["name"], row["package"], Text(params_text(row) or "-"), height=None)
        problems = [f"problem: {p}" for p in registry.problems]
        self.query_one("#problems", Static).update(Text("\n".join(problems)))

    def action_show(self, tab: str) -> None:
        self.query_one("#views", TabbedContent).active = tab

    async def action_quit(self) -> None:
        if self.process is not None:  # leave no orphan run behind; its finished units stay
            self.action_cancel()
        self.exit()


def run_tui(directory: Path | str = "scenarios") -> None:
    GearlabApp(directory).run()
