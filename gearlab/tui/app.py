"""`gearlab tui [DIR]`: browse scenarios, run one and watch it, read results, compare runs, list plugins.

A run is the CLI's own `gearlab run SCENARIO --events` in a child process: the TUI reads its
progress events (JSON lines, gearlab.events.Event) and draws them, so the TUI and the CLI share
one run engine and one event stream. Cancelling stops the child's whole process group; the
units it finished are already in the run directory, and `u` resumes the run.

Every action works on what the tree highlights (found again by path after each rescan), so
that a key never acts on another scenario or run than the one the user sees.
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
import sys
from collections.abc import Iterable
from pathlib import Path

from rich.markup import escape
from rich.text import Text
from textual import work
from textual.app import App, ComposeResult, SystemCommand
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.screen import Screen
from textual.widgets import Footer, RichLog, Static, TabbedContent, TabPane, Tree

from ..errors import GearlabInputError
from ..events import Event
from ..kinds import OVERRIDES_COMMAND, SCENARIO_KINDS
from ..notebook import load_scenario
from ..runs import RunDir
from ..scenario import Scenario
from ..verdict import verdict_lines, verdict_table
from .catalog import RunEntry, ScenarioEntry, Validated, check, error_line, listing, run_entry, runs_base
from .checking import Checking, scenario_label
from .plugins import PluginsPane
from .progress import Stages
from .screens import KeysScreen, RunOptions, RunOptionsScreen, ScoreScreen
from .validating import Validating, ValidatingLine
from .widgets import BrowserTree, ChartView, ResultTable, SummaryView, TomlSyntax

# Below this many columns the sidebar folds away while a run or results are on show.
NARROW = 100


class GearlabApp(Checking, Validating, App):
    TITLE = "gearlab"
    CSS = """
    #browser { width: 34; min-width: 20; max-width: 45%; border-right: solid $primary-darken-2; }
    #browser.folded { display: none; }
    #views { width: 1fr; }
    #scenario-status, #run-status, #results-status, #units { padding: 0 1; }
    #toml { padding: 0 1; }
    #log { height: 1fr; min-height: 4; border-top: solid $primary-darken-2; }
    #verdict { padding: 0 1; margin-bottom: 1; height: auto; }
    #results-lines { padding: 0 1; height: auto; }
    """
    # The footer shows the first few (q first, so that it is never cut off at 80 columns);
    # `?` lists them all.
    BINDINGS = [
        Binding("q", "quit", "Quit", tooltip="Quit (a run in progress is cancelled; its finished units stay)"),
        Binding("question_mark", "keys", "Keys", key_display="?", tooltip="This list of keys"),
        Binding(
            "r", "run(False)", "Run", tooltip="Run the highlighted scenario (or the scenario of the highlighted run)"
        ),
        Binding("k", "run(True)", "Quick", tooltip="Quick run (--quick: the scenario shrunk for a smoke run)"),
        Binding("c", "cancel", "Cancel", tooltip="Cancel the run in progress (its finished units stay)"),
        Binding(
            "u", "resume", "Resume", tooltip="Resume the highlighted unfinished run (cancelled, killed or crashed)"
        ),
        Binding("o", "open_report", "Report", tooltip="Open the highlighted (else the shown) run's report.html"),
        Binding(
            "f",
            "run_with_options",
            "Run with options…",
            show=False,
            tooltip="Run with options: --quick, --executor, --device, a benchmark's --trials and --seed",
        ),
        Binding(
            "m",
            "mark",
            "Mark a run for comparison",
            show=False,
            tooltip="Mark or unmark the highlighted run for comparison (▣)",
        ),
        Binding(
            "C",
            "compare",
            "Compare the marked runs",
            show=False,
            tooltip="Compare the marked runs (two or more, one kind)",
        ),
        Binding("n", "next_chart", "Next chart", show=False, tooltip="Next chart in the Results tab"),
        Binding(
            "s",
            "score",
            "Score new recordings",
            show=False,
            tooltip="Score new recordings with the highlighted (else the shown) finished detection run (gearlab score)",
        ),
        Binding("b", "toggle_sidebar", "Fold or show the sidebar", show=False),
        Binding("1", "show('scenario')", "Scenario tab", show=False),
        Binding("2", "show('run')", "Progress tab", show=False),
        Binding("3", "show('results')", "Results tab", show=False),
        Binding("p", "show('plugins')", "Plugins tab", show=False),
        Binding(
            "f5",
            "rescan",
            "Rescan the folder",
            show=False,
            tooltip="Rescan the folder (validation status and past runs)",
        ),
        Binding(
            "escape",
            "close",
            "Close the comparison, show the sidebar",
            show=False,
            tooltip="Close a panel, then the comparison, then unfold the sidebar",
        ),
    ]

    def __init__(self, directory: Path | str = "scenarios"):
        super().__init__()
        self.directory = Path(directory)
        # Runs start in this folder, and a scenario's relative [output] dir is taken from it,
        # as `gearlab run` started here would (catalog.runs_base).
        self.cwd = Path.cwd()
        self.entries: list[ScenarioEntry] = []
        self.validated = Validated()  # each scenario validated once per state of its files
        self.opened: RunEntry | None = None  # the run whose results are on show
        self.marked: list[Path] = []  # runs marked for comparison, in marking order
        self.comparing: list[Path] = []  # the runs of the comparison on show
        self.process: asyncio.subprocess.Process | None = None
        self.cancelled = False
        self.run_scenario: Scenario | None = None  # the scenario of the run in progress, as it runs
        self.run_path: Path | None = None
        self.records: list[dict] = []
        self.running: dict[str, str] = {}  # units in progress: how far each is
        self.charts: list = []
        self.chart_index = 0
        self.toml_shown: tuple[str, set[int]] | None = None  # the scenario TOML on show, its highlighted lines

    # ------------------------------------------------------------------ layout
    def compose(self) -> ComposeResult:
        with Horizontal():
            yield BrowserTree("scenarios", id="browser")
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
                        yield Static("", id="verdict")
                        yield ResultTable(id="results-table")
                        yield ChartView(id="chart")
                        yield SummaryView("", id="results-lines")
                with TabPane("Plugins", id="plugins"):
                    yield PluginsPane()
        yield ValidatingLine()
        yield Footer()

    def on_mount(self) -> None:
        self.tree.guide_depth = 2  # the narrowest guides Textual draws: room for the file names
        self.rescan()

    # ------------------------------------------------------------------ browser
    @property
    def tree(self) -> Tree:
        return self.query_one("#browser", Tree)

    def highlighted(self) -> ScenarioEntry | RunEntry | None:
        """What the tree's cursor is on: a scenario, one of its runs, or nothing."""
        node = self.tree.cursor_node
        return node.data if node is not None and isinstance(node.data, (ScenarioEntry, RunEntry)) else None

    def scenario_of(self, item: ScenarioEntry | RunEntry | None) -> ScenarioEntry | None:
        if isinstance(item, RunEntry):
            return next((e for e in self.entries if any(r.path == item.path for r in e.runs)), None)
        return item

    def action_rescan(self) -> None:
        self.rescan()

    def rescan(self) -> None:
        """Read the folder again; the cursor stays on the same file or run (by path), and the
        scenarios that were unfolded stay unfolded."""
        tree = self.tree
        keep = getattr(self.highlighted(), "path", None)
        unfolded = {n.data.path for n in tree.root.children if isinstance(n.data, ScenarioEntry) and n.is_expanded}
        tree.clear()
        tree.root.set_label(str(self.directory))
        tree.root.expand()
        if not self.directory.is_dir():
            tree.root.add_leaf(Text(f"no such directory: {self.directory}", style="red"))
            self.entries = []
            return
        self.entries = listing(self.directory)
        for entry in self.entries:  # files as Validated last saw them marked at once, the others pending
            check(entry, self.validated, self.cwd, wait=False)
        if not self.entries:
            tree.root.add_leaf(Text("no scenario files (*.toml) here", style="dim"))
        target = None
        for entry in self.entries:
            name = str(entry.path.relative_to(self.directory))
            node = tree.root.add(scenario_label(entry, name), data=entry, expand=False, allow_expand=bool(entry.runs))
            target = node if entry.path == keep else target
            for run in entry.runs:
                leaf = node.add_leaf(self._run_label(run), data=run)
                if run.path == keep:
                    target, unfolded = leaf, unfolded | {entry.path}
            if entry.path in unfolded and entry.runs:
                node.expand()
        tree.styles.width = tree.fit_width()  # every name whole, up to the CSS's max-width
        line = self._line_of(target) if target is not None else None
        # nothing kept (the first scan, or the file went): the first scenario, not the folder
        tree.cursor_line = line if line is not None else (1 if self.entries else 0)
        self._check_pending()

    def _line_of(self, target) -> int | None:
        """The tree line a node is drawn on (the root is line 0; folded children have none)."""
        line = 0

        def walk(node) -> int | None:
            nonlocal line
            for child in node.children:
                line += 1
                if child is target:
                    return line
                if child.is_expanded:
                    found = walk(child)
                    if found is not None:
                        return found
            return None

        return walk(self.tree.root)

    def _run_label(self, run: RunEntry) -> Text:
        name = run.path.name  # YYYYmmdd-HHMMSS-ffffff: shown as mm-dd HH:MM:SS
        when = f"{name[4:6]}-{name[6:8]} {name[9:11]}:{name[11:13]}:{name[13:15]}" if len(name) >= 15 else name
        mark = ("▣ ", "cyan") if run.path in self.marked else ("● ", "green") if run.finished else ("◐ ", "yellow")
        return Text.assemble(mark, when, ("" if run.finished else f" {run.units} units", "dim"))

    def on_tree_node_highlighted(self, event: Tree.NodeHighlighted) -> None:
        # the whole name of what the cursor is on, whatever the sidebar's width cut of it
        path = getattr(event.node.data, "path", None)
        self.tree.tooltip = str(self._shown(path)) if path is not None else None
        self._open(event.node.data, switch=False)  # moving through the tree only fills the views

    def on_tree_node_selected(self, event: Tree.NodeSelected) -> None:
        self._open(event.node.data, switch=True)

    def _open(self, data, switch: bool) -> None:
        if not self.query("#views"):  # a highlight queued while the app closes: the views are gone
            return
        if isinstance(data, ScenarioEntry):
            if switch:
                self._check_now(data)
            self.show_scenario(data, switch)
        elif isinstance(data, RunEntry):
            self.show_scenario(self.scenario_of(data))
            self.show_results(data, switch)

    # ------------------------------------------------------------------ scenario view
    def show_scenario(self, entry: ScenarioEntry | None, switch: bool = False) -> None:
        status = self.query_one("#scenario-status", Static)
        toml = self.query_one("#toml", Static)
        if entry is None:
            status.update("select a scenario")
            toml.update("")
            self.toml_shown = None
            return
        try:
            text = entry.path.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            text = f"# cannot read {entry.path}: {exc}"
        if not entry.checked:
            status.update(
                Text.assemble(("· not validated yet", "dim"), f"  {self._shown(entry.path)}: its mark comes shortly")
            )
            marked = set()
        elif entry.gearbox:
            status.update(
                Text.assemble(
                    ("✓ valid", "bold green"),
                    f"  {entry.gearbox.removeprefix('OK: ')}\nnothing to run: a scenario's [source] "
                    f'gearbox = "{entry.path.name}" uses it (docs/your_gearbox.md)',
                )
            )
            marked = set()
        elif entry.ok:
            s = entry.scenario
            runs = f"{len(entry.runs)} past run(s)" if entry.runs else "no past runs"
            status.update(
                Text.assemble(
                    ("✓ valid", "bold green"),
                    f"  {self._shown(entry.path)}\n{s.name} ({s.kind}): {s.description}\n",
                    SCENARIO_KINDS[s.kind].describe(s),
                    f"\n{runs} in {self._shown(runs_base(s, self.cwd) / s.name)}; r run, k quick run, "
                    "f run with options",
                )
            )
            marked = set()
        else:
            status.update(Text.assemble(("✗ invalid  ", "bold red"), entry.error))
            line = error_line(text, entry.error)
            marked = {line} if line else set()
        if self.toml_shown != (text, marked):  # the same TOML (its mark come, the cursor back on it): drawn once
            self.toml_shown = (text, marked)
            toml.update(TomlSyntax(text, highlight_lines=marked))
        if switch:
            self.switch_to("scenario")

    def _shown(self, path: Path) -> Path:
        """A path as short as it is clear: relative to the folder the TUI started in when inside it."""
        return path.relative_to(self.cwd) if path.is_relative_to(self.cwd) else path

    # ------------------------------------------------------------------ runs
    def action_run(self, quick: bool) -> None:
        entry = self._runnable()
        if entry is not None:
            self.start(self._run_args(entry, RunOptions(quick=quick)), entry.path, resume=None)

    def action_run_with_options(self) -> None:
        entry = self._runnable()
        if entry is None:
            return

        def chosen(options: RunOptions | None) -> None:
            if options is not None:
                self.start(self._run_args(entry, options), entry.path, resume=None)

        self.push_screen(RunOptionsScreen(entry.scenario), chosen)

    def _runnable(self) -> ScenarioEntry | None:
        """The highlighted scenario (or the scenario of the highlighted run), when it can run."""
        entry = self.scenario_of(self.highlighted())
        self._check_now(entry)
        if self.process is not None:
            self.notify("a run is in progress; c cancels it", severity="warning")
        elif entry is not None and entry.gearbox is not None:
            self.notify("a gearbox description runs in a scenario ([source] gearbox = ...)", severity="warning")
        elif entry is None or not entry.ok:
            self.notify("highlight a valid scenario in the tree first", severity="warning")
        else:
            return entry
        return None

    def _run_args(self, entry: ScenarioEntry, options: RunOptions) -> list[str]:
        """The command line of a run: `gearlab run FILE` (the command that sets a kind's OVERRIDES,
        kinds.OVERRIDES_COMMAND, for a benchmark given trials or seed), into the folder where the tree
        looks for its runs."""
        args = ["run", str(entry.path)]
        if options.trials is not None or options.seed is not None:
            args = [OVERRIDES_COMMAND, str(entry.path)]
            args += ["--trials", str(options.trials)] if options.trials is not None else []
            args += ["--seed", str(options.seed)] if options.seed is not None else []
        args += ["--out", str(runs_base(entry.scenario, self.cwd))]
        args += ["--quick"] if options.quick else []
        args += ["--executor", options.executor] if options.executor else []
        args += ["--device", options.device] if options.device else []
        return args

    def action_resume(self) -> None:
        run = self.highlighted()
        if self.process is not None:
            self.notify("a run is in progress; c cancels it", severity="warning")
        elif not isinstance(run, RunEntry) or run.finished:
            self.notify("highlight an unfinished run in the tree to resume it", severity="warning")
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
                self.run_scenario = load_scenario(run=run)
                self.records = run.records()
            else:
                self.run_scenario = load_scenario(scenario_path)
                if "--quick" in args:
                    SCENARIO_KINDS[self.run_scenario.kind].quick(self.run_scenario)
        except GearlabInputError as exc:
            self.notify(str(exc), severity="error")
            return
        self.query_one("#stages", Stages).reset()
        self.running = {}
        self.query_one("#units", Static).update("")
        self.query_one("#log", RichLog).clear()
        self.query_one("#run-status", Static).update(
            f"{'resuming' if resume else 'running'} {self.run_scenario.name} ({self.run_scenario.kind}); c cancels"
        )
        self.refresh_live()
        self.switch_to("run")
        self.follow(args)

    @work(exclusive=True, group="run")
    async def follow(self, args: list[str]) -> None:
        """Run `gearlab ... --events` in a child process and draw its events until it ends."""
        log = self.query_one("#log", RichLog)
        self.process = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "gearlab",
            *args,
            "--events",
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
            cwd=self.cwd,
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
            stages.start(event.stage, event.message, event.total, event.done)
        elif event.kind == "advance":
            stages.advance(event.stage, event.done, event.total)
        elif event.kind == "unit":  # a unit in progress says how far it is; empty: it ended
            if event.message:
                self.running[event.stage] = event.message
            else:
                self.running.pop(event.stage, None)
            self.query_one("#units", Static).update(
                Text("\n".join(f"▸ {unit}: {text}" for unit, text in sorted(self.running.items())), style="dim")
            )
        elif event.kind == "record" and event.record is not None:
            self.records.append(event.record)
            self.refresh_live()
        elif event.kind == "log":
            self.query_one("#log", RichLog).write(event.message)

    def refresh_live(self) -> None:
        if self.run_scenario is None:
            return
        kind = SCENARIO_KINDS[self.run_scenario.kind]
        live = self.query_one("#live", ResultTable)
        try:
            live.show_markdown(kind.records_table(self.run_scenario, self.records))
            return
        except (KeyError, TypeError, ValueError):
            pass
        # An event may carry a shortened record (the gap kind's diagnosis leaves its arrays out):
        # the run directory holds them whole, appended before the event was sent.
        try:
            if self.run_path is not None:
                self.records = RunDir(self.run_path).records()
            live.show_markdown(kind.records_table(self.run_scenario, self.records))
        except Exception as exc:  # noqa: BLE001 - a table that cannot be drawn must not take the run view down
            self.query_one("#log", RichLog).write(f"(the live table cannot be drawn: {type(exc).__name__}: {exc})")

    def finish(self, code: int, stderr: str) -> None:
        self.query_one("#stages", Stages).stop()  # no bar moves once the run has ended
        self.running = {}
        self.query_one("#units", Static).update("")
        log = self.query_one("#log", RichLog)
        status = self.query_one("#run-status", Static)
        where = f" in {self.run_path}" if self.run_path else ""
        name = self.run_scenario.name if self.run_scenario else "the run"
        if self.cancelled:
            status.update(f"cancelled: {len(self.records)} finished unit(s) kept{where}; select the run, u resumes it")
            self.notify(f"{name}: cancelled, {len(self.records)} finished unit(s) kept", severity="warning")
        elif code == 0:
            status.update(Text(f"finished: {len(self.records)} unit(s){where}", style="green"))
            self.notify(f"{name}: finished, {len(self.records)} unit(s); o opens its report", title="run finished")
        else:
            last = stderr.splitlines()[-1] if stderr else f"exit code {code}"
            status.update(Text(f"failed (exit {code}): {last}", style="red"))
            log.write(stderr)
            self.notify(f"{name}: failed (exit {code}): {last}", severity="error", title="run failed")
        self.rescan()
        if self.run_path is not None and (self.run_path / "scenario.toml").is_file():
            self.show_results(run_entry(self.run_path), switch=code == 0 and not self.cancelled)

    # ------------------------------------------------------------------ results
    def show_results(self, run: RunEntry, switch: bool = True) -> None:
        self.opened, self.comparing = run, []
        status = self.query_one("#results-status", Static)
        table = self.query_one("#results-table", ResultTable)
        lines = self.query_one("#results-lines", SummaryView)
        verdict = self.query_one("#verdict", Static)
        try:
            rundir = RunDir.open(run.path)
            scenario = self.validated.of_run(rundir)
            kind = SCENARIO_KINDS[scenario.kind]
            records = rundir.records()
            headline = verdict_table(rundir)
            self.charts = kind.charts(scenario, rundir)
            summary = kind.summary_lines(rundir) if run.finished else []
            said = verdict_lines(rundir) if run.finished else []
            # a kind with no headline table (detection: its AUC, units-called, which-gear and learned tables)
            # shows its summary's tables under their captions, as the terminal prints them; the records table
            # (a detection run's 'unit | method', no numbers) stood in for them, and other_lines dropped them
            own = headline is None and any("|" in line for line in summary)
            table.display = not own
            table.show_markdown("" if own else headline or kind.records_table(scenario, records))
        except (GearlabInputError, OSError, ValueError, KeyError) as exc:
            status.update(Text(f"{run.path}: cannot show this run: {exc}", style="red"))
            table.clear(columns=True)
            table.display = True
            verdict.update("")
            lines.show(None)
            self.charts = []
            self.query_one("#chart", ChartView).show(None)
            return
        state = "finished" if run.finished else f"not finished ({run.units} units kept; u resumes it)"
        status.update(Text.assemble((f"{scenario.name} ", "bold"), f"({scenario.kind}), {run.path.name}: {state}"))
        verdict.update(Text(" ".join(said)))
        verdict.display = bool(said)
        lines.show(summary if own else None, escape("\n".join(other_lines(summary))))
        self.chart_index = 0
        self.show_chart()
        if switch:
            self.switch_to("results")

    def show_chart(self) -> None:
        chart = self.charts[self.chart_index] if self.charts else None
        place = f"chart {self.chart_index + 1}/{len(self.charts)}" + (", n next" if len(self.charts) > 1 else "")
        self.query_one("#chart", ChartView).show(chart, place)

    def action_next_chart(self) -> None:
        if self.charts:
            self.chart_index = (self.chart_index + 1) % len(self.charts)
            self.show_chart()

    def action_score(self) -> None:
        """`gearlab score RUN FILE...` with the highlighted (else the shown) finished detection run: its output in
        the Progress tab, then the run's Results, whose last chart is the scoring trend."""
        run = self.highlighted()
        run = run if isinstance(run, RunEntry) else self.opened
        if self.process is not None:
            self.notify("a run is in progress; c cancels it", severity="warning")
        elif run is None or not (run.path / "scoring.json").is_file():
            self.notify("highlight a finished detection run (it keeps scoring.json) first", severity="warning")
        else:

            def chosen(typed: str | None) -> None:
                if typed:
                    self.scored = typed
                    self.score(run, typed)

            self.push_screen(ScoreScreen(str(self._shown(run.path)), getattr(self, "scored", "")), chosen)

    @work(exclusive=True, group="run")
    async def score(self, run: RunEntry, typed: str) -> None:
        import shlex

        log, status = self.query_one("#log", RichLog), self.query_one("#run-status", Static)
        log.clear()
        status.update(f"scoring with {self._shown(run.path)}; c cancels")
        self.switch_to("run")
        self.cancelled = False
        scored_before = self._scored(run)
        self.process = await asyncio.create_subprocess_exec(
            *(sys.executable, "-m", "gearlab", "score", str(run.path), *shlex.split(typed)),
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT,
            cwd=self.cwd,  # the files typed are read from the folder the TUI started in, as the shell would
            start_new_session=True,
        )
        lines = []
        async for raw in self.process.stdout:
            lines.append(raw.decode(errors="replace").rstrip("\n"))
            log.write(lines[-1])
        code, self.process = await self.process.wait(), None
        last = lines[-1] if lines else f"exit code {code}"
        # of several takes, score scores those it can and exits 2, the others kept in not_scored.jsonl
        partly = code != 0 and not self.cancelled and self._scored(run) > scored_before
        if code == 0 or partly:
            status.update(Text(f"scored: {typed}" if code == 0 else f"scored in part: {last}", style="green"))
            self.show_results(run_entry(run.path))  # the trend chart, with the new takes
            self.chart_index = len(self.charts) - 1
            self.show_chart()
        if partly:
            self.notify(f"gearlab score: {last}", severity="warning")
        elif code != 0:
            status.update(Text(f"{'cancelled' if self.cancelled else f'failed (exit {code})'}: {last}", style="red"))
            self.notify(f"gearlab score: {last}", severity="error")

    @staticmethod
    def _scored(run: RunEntry) -> int:
        """The takes refused of a batch whose others were scored (nothing is written when all are refused): what
        tells a partly scored batch from a refused one."""
        from ..parts import scoring  # numpy and the scoring files: only once a take is scored

        return len(scoring.read_skipped(RunDir(run.path)))

    def action_open_report(self) -> None:
        """Open report.html of the highlighted run (else the run on show) in the web browser."""
        run = self.highlighted()
        run = run if isinstance(run, RunEntry) else self.opened
        report = run.path / "report.html" if run is not None else None
        if report is None or not report.is_file():
            self.notify("highlight a finished run (its report.html) first", severity="warning")
            return
        import webbrowser  # on first use: not at the first screen's start (issue 42)

        if not webbrowser.open(report.resolve().as_uri()):
            self.notify(f"no web browser found; the report is {report}", severity="warning")
        else:
            self.notify(f"opened {report}")

    # ------------------------------------------------------------------ comparison
    def action_mark(self) -> None:
        run = self.highlighted()
        if not isinstance(run, RunEntry):
            self.notify("highlight a run in the tree to mark it for comparison", severity="warning")
            return
        if run.path in self.marked:
            self.marked.remove(run.path)
        else:
            self.marked.append(run.path)
        self.tree.cursor_node.set_label(self._run_label(run))
        self.notify(f"{len(self.marked)} run(s) marked" + ("; C compares them" if len(self.marked) > 1 else ""))

    def action_compare(self, paths: Iterable[Path] | None = None) -> None:
        paths = list(paths if paths is not None else self.marked)
        if len(paths) < 2:
            self.notify("mark two or more runs with m (in the tree), then C compares them", severity="warning")
            return
        from ..compare import compare_charts, compare_lines, compare_markdown, differences_text, load_runs

        try:
            runs = load_runs(paths)
        except GearlabInputError as exc:
            self.notify(str(exc), severity="error")
            return
        self.comparing = paths
        self.query_one("#results-status", Static).update(
            Text.assemble(("comparison ", "bold"), f"of {len(runs)} {runs[0].kind} runs; escape closes it")
        )
        lines = compare_lines(runs)  # which run is which, what differs in their scenarios, their verdicts
        lines.insert(len(runs), differences_text(runs))
        self.query_one("#verdict", Static).update(Text("\n".join(lines)))
        self.query_one("#verdict", Static).display = True
        self.query_one("#results-table", ResultTable).display = True  # a detection run's view hides it
        self.query_one("#results-table", ResultTable).show_markdown(compare_markdown(runs))
        self.query_one("#results-lines", SummaryView).show(None)
        self.charts, self.chart_index = compare_charts(runs), 0
        self.show_chart()
        self.switch_to("results")

    def action_close(self) -> None:
        """Escape: close the comparison (back to the run on show), then unfold the sidebar."""
        if self.comparing:
            self.comparing = []
            if self.opened is not None:
                self.show_results(self.opened, switch=False)
            else:
                self.query_one("#results-status", Static).update("select a run in the tree (under its scenario)")
        elif self.tree.has_class("folded"):
            self.action_toggle_sidebar()

    # ------------------------------------------------------------------ panels
    def switch_to(self, tab: str) -> None:
        self.query_one("#views", TabbedContent).active = tab
        # a narrow terminal gives the run and its results the whole width
        if self.size.width < NARROW and tab in ("run", "results", "plugins"):
            self.tree.add_class("folded")
        elif tab == "scenario":
            self.tree.remove_class("folded")

    def action_toggle_sidebar(self) -> None:
        self.tree.toggle_class("folded")
        if not self.tree.has_class("folded"):
            self.tree.focus()

    def action_keys(self) -> None:
        self.push_screen(KeysScreen(self.BINDINGS))

    def get_system_commands(self, screen: Screen) -> Iterable[SystemCommand]:
        """Command-palette entries (ctrl+p): run, open a run, compare, validate."""
        yield from super().get_system_commands(screen)
        for entry in self.entries:
            name = str(entry.path.relative_to(self.directory))
            if entry.ok or not entry.checked:  # a pending one is validated as it is run (_runnable)
                yield SystemCommand(f"Run {name}", "run this scenario", lambda e=entry: self._palette_run(e, False))
                yield SystemCommand(
                    f"Quick run {name}", "run it shrunk (--quick)", lambda e=entry: self._palette_run(e, True)
                )
            yield SystemCommand(
                f"Validate {name}", "check the file without running it", lambda e=entry: self._validate(e)
            )
            for run in entry.runs:
                yield SystemCommand(
                    f"Open run {name} {run.path.name}", "show its results", lambda r=run: self._palette_open(r)
                )
        if len(self.marked) > 1:
            yield SystemCommand(
                f"Compare the {len(self.marked)} marked runs",
                "tables side by side, curves overlaid",
                self.action_compare,
            )

    def _palette_run(self, entry: ScenarioEntry, quick: bool) -> None:
        self._move_to(entry.path)
        self.action_run(quick)

    def _palette_open(self, run: RunEntry) -> None:
        self._move_to(run.path)
        self.show_results(run)

    def _move_to(self, path: Path) -> None:
        for node in self.tree.root.children:
            if getattr(node.data, "path", None) == path:
                self.tree.cursor_line = self._line_of(node)
                return
            if any(r.path == path for r in getattr(node.data, "runs", [])):
                node.expand()
                self.tree.cursor_line = self._line_of(next(c for c in node.children if c.data.path == path))
                return

    def action_show(self, tab: str) -> None:
        self.switch_to(tab)
        # the keys go where the tab is read: ↑ ↓ in the plugin table, in the tree for a scenario
        if tab == "plugins":
            self.query_one("#plugin-table").focus()
        elif tab == "scenario":
            self.tree.focus()

    async def action_quit(self) -> None:
        if self.process is not None:  # leave no orphan run behind; its finished units stay
            self.action_cancel()
        self.exit()


def other_lines(summary: list[str]) -> list[str]:
    """A kind's summary lines without its tables (the results table shows them) and without
    the headings of those tables ('per-view gap:'), which would head nothing."""
    rows = [line.splitlines() for line in summary]
    flat = [line for block in rows for line in block]
    return [
        line
        for i, line in enumerate(flat)
        if not line.lstrip().startswith("|")
        and not (line.rstrip().endswith(":") and i + 1 < len(flat) and flat[i + 1].lstrip().startswith("|"))
    ]


def run_tui(directory: Path | str = "scenarios") -> int:
    """Run the app; its exit code (1 when it ended on an internal error)."""
    app = GearlabApp(directory)
    app.run()
    return app.return_code or 0
