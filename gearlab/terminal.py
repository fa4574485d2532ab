"""What `gearlab run` draws in the terminal: progress with counts, rate and ETA (rich bars on
a terminal, log lines otherwise), and at the end of a run its verdict and its tables as rich
tables. Also the table of `gearlab runs` and what `gearlab score` prints.

Loaded by the CLI's commands that run or list runs (rich only: no torch, numba or matplotlib).
"""

from __future__ import annotations

import re
import time
from collections.abc import Iterable
from pathlib import Path

from rich.cells import cell_len
from rich.console import Console, Group
from rich.measure import Measurement
from rich.progress import BarColumn, MofNCompleteColumn, Progress, ProgressColumn, Task, TextColumn, TimeElapsedColumn
from rich.table import Column, Table
from rich.text import Text

from .errors import GearlabInputError
from .events import Pace, clock

QUIET_S = 5.0  # a log line at least this often while a unit says how far it is


class PaceColumn(ProgressColumn):
    """'1.2/s ETA 0:42' (or '0:17/step ETA 3:10') from the task's Pace; the unit in progress
    beside a stage that cannot count yet."""

    def render(self, task: Task) -> Text:
        pace: Pace | None = task.fields.get("pace")
        note = task.fields.get("note") or ""
        if pace is None:
            return Text(note, style="dim")
        if task.finished:
            return Text("done", style="green")
        rate = pace.rate_text()
        if not rate:
            return Text(note or "ETA after the first step", style="dim")
        return Text(f"{rate} ETA {clock(pace.left(int(task.total or 0)))}", style="cyan")


class StageOnly(ProgressColumn):
    """A column drawn for stages only, never wrapped (a count, a time, an ETA)."""

    def __init__(self, column: ProgressColumn):
        super().__init__(table_column=Column(no_wrap=True))
        self.column = column

    def render(self, task: Task):
        return Text("") if task.fields.get("unit") else self.column.render(task)


class LabelColumn(TextColumn):
    """A stage's label, folded at its words within max_width cells (set by Bars as it draws)."""

    def __init__(self):
        super().__init__("{task.description}")
        self.max_width: int | None = None

    def get_table_column(self) -> Column:
        return Column(overflow="fold", max_width=self.max_width)


class Bars(Progress):
    """The stages' bars in one table, each unit's line under it, cut to one line. A unit's line
    in the bars' table set the width of their label column: at 80 columns quick.toml's 'rep0/k0/
    source_only-unsup: source model, epoch 46 of 60, ...' left no room for any bar, count or ETA,
    and at 120 the elapsed time read '0:00:…' and the ETA wrapped (issue 41). The counts, elapsed
    time and ETA keep their width; the bar gives way first (40 down to 6 cells), then the labels,
    which fold at their words."""

    def get_renderables(self):
        yield _Board(self)


class _Board:
    """What Bars draws, measured at the width it is drawn in."""

    def __init__(self, progress: Bars):
        self.progress = progress

    def __rich_console__(self, console, options):
        p = self.progress
        label, bar, *tail = p.columns
        stages = [t for t in p.tasks if t.visible and not t.fields.get("unit")]
        if stages:
            gaps = len(p.columns) - 1
            right = sum(max(cell_len(column(t).plain) for t in stages) for column in tail)
            labels = max(cell_len(str(t.description)) for t in stages)
            bar.column.bar_width = min(40, max(6, options.max_width - labels - right - gaps - 1))
            label.max_width = max(10, options.max_width - right - gaps - 1 - bar.column.bar_width)
            yield p.make_tasks_table(stages)
        for task in p.tasks:
            if task.visible and task.fields.get("unit"):
                line = Text(task.description) if isinstance(task.description, str) else task.description.copy()
                line.no_wrap, line.overflow = True, "ellipsis"
                yield line


class ProgressView:
    """Rich progress bars fed by the run engine's events: one bar per stage with its counts,
    rate, elapsed time and ETA; a line per unit in progress (what it says: 'epoch 12, ...')
    so that no stage stays silent. Not on a terminal (a log file, a pipe): one line per stage
    start, per tenth of a stage with its rate and ETA, and, every QUIET_S seconds at most,
    what the units in progress say."""

    def __init__(self, console: Console):
        self.console = console
        self.progress = Bars(
            LabelColumn(),
            StageOnly(BarColumn()),
            StageOnly(MofNCompleteColumn()),
            StageOnly(TimeElapsedColumn()),
            StageOnly(PaceColumn()),
            console=console,
            transient=False,
        )
        self.tasks: dict[str, int] = {}  # stage -> rich task id
        self.units: dict[str, int] = {}  # unit in progress -> rich task id (a line, no bar)
        self.paces: dict[str, Pace] = {}
        self.labels: dict[str, str] = {}
        self.told: dict[str, int] = {}  # log lines: stage -> last step told
        self.said: dict[str, float] = {}  # log lines: unit -> when it was last told
        self.started = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        # Started by the first stage only: a run refused before any work prints its error line alone.
        if self.started:
            for task in list(self.units.values()):
                self.progress.remove_task(task)
            self.units.clear()
            return self.progress.__exit__(*exc)
        return None

    def handle(self, event) -> None:
        if event.kind == "stage":
            self.paces[event.stage] = Pace(event.done)
            self.labels[event.stage] = event.message or event.stage
        elif event.kind == "advance" and event.stage in self.paces:
            self.paces[event.stage].update(event.done)
        if not self.console.is_terminal:  # a log file or a pipe: lines that keep their labels
            self._line(event)
            return
        if event.kind == "stage":
            if not self.started:
                self.progress.start()
                self.started = True
            label, total, pace = self.labels[event.stage], event.total or None, self.paces[event.stage]
            if event.stage in self.tasks:  # met again (each benchmark trial's diagnosis): its bar starts over
                self.progress.reset(
                    self.tasks[event.stage], total=total, completed=event.done, description=label, pace=pace
                )
            else:
                self.tasks[event.stage] = self.progress.add_task(label, total=total, pace=pace)
        elif event.kind == "advance" and event.stage in self.tasks:
            self.progress.update(self.tasks[event.stage], completed=event.done, total=event.total or None)
        elif event.kind == "unit" and self.started:
            self._unit(event)
        elif event.kind == "log":
            self.progress.console.print(event.message, markup=False, highlight=False)

    def _unit(self, event) -> None:
        """A unit in progress as a line under the bars (removed when it ends)."""
        text = f"  {event.stage}: {event.message.strip()}"
        if not event.message:
            task = self.units.pop(event.stage, None)
            if task is not None:
                self.progress.remove_task(task)
        elif event.stage in self.units:
            self.progress.update(self.units[event.stage], description=Text(text, style="dim"))
        else:
            self.units[event.stage] = self.progress.add_task(Text(text, style="dim"), total=None, unit=True)

    def _line(self, event) -> None:
        """One line per stage start, per tenth of a stage (at most) with rate and ETA, per
        log message; a unit in progress every QUIET_S seconds at most."""
        say = self.console.print
        if event.kind == "stage":
            self.told[event.stage] = event.done
            say(f"{self.labels[event.stage]}: started ({event.total or '?'} steps)", markup=False, highlight=False)
        elif event.kind == "advance" and event.stage in self.told:
            step = max(1, (event.total or 10) // 10)
            last = self.told[event.stage]
            if event.done > last and (event.done >= last + step or (event.total and event.done >= event.total)):
                self.told[event.stage] = event.done
                pace = self.paces[event.stage]
                rate = pace.rate_text()
                tail = (
                    ", done"
                    if event.total and event.done >= event.total
                    else f", {rate}, ETA {clock(pace.left(event.total))}"
                    if rate
                    else ""
                )
                say(
                    f"{self.labels[event.stage]}: {event.done}/{event.total or '?'}{tail}",
                    markup=False,
                    highlight=False,
                )
        elif event.kind == "unit" and event.message:
            now = time.monotonic()
            if now - self.said.get(event.stage, -QUIET_S) >= QUIET_S:
                self.said[event.stage] = now
                say(f"  {event.stage}: {event.message.strip()}", markup=False, highlight=False)
        elif event.kind == "log":
            say(event.message, markup=False, highlight=False)


# --------------------------------------------------------------------------- end of a run

_SEPARATOR = re.compile(r"^\|?\s*:?-{2,}:?\s*(\|\s*:?-{2,}:?\s*)*\|?\s*$")


def _cells(line: str) -> list[str]:
    line = line.strip()
    if line.startswith("|"):
        line = line[1:]
    if line.endswith("|"):
        line = line[:-1]
    return [cell.strip().replace("**", "") for cell in re.split(r"(?<!\\)\|", line)]


def markdown_tables(text: str) -> list[tuple[str, list[str], list[list[str]]]] | None:
    """The Markdown tables of *text* as (caption, header, rows) (a line before a table, when
    not a table line, is its caption); None when *text* holds no table."""
    lines = [line for line in text.splitlines() if line.strip()]
    found, i, caption = [], 0, ""
    while i < len(lines):
        if lines[i].lstrip().startswith("|") and i + 1 < len(lines) and _SEPARATOR.match(lines[i + 1].strip()):
            header = _cells(lines[i])
            rows, i = [], i + 2
            while i < len(lines) and lines[i].lstrip().startswith("|"):
                rows.append(_cells(lines[i]))
                i += 1
            found.append((caption, header, rows))
            caption = ""
        else:
            caption = lines[i].strip()
            i += 1
    return found or None


def rich_table(caption: str, header: list[str], rows: list[list[str]], console: Console | None = None) -> Table:
    """The table; on *console*'s terminal too narrow for its words (a transfer run's eight method
    columns cut 'matched_filt|er' and '(unsupervise|d)' at 120 columns: issue 41), turned, its
    columns as rows (one row a method, one column a k), when that keeps every word whole."""
    table = Table(title=Text(caption.rstrip(":"), style="bold") if caption else None, title_justify="left")
    for i, name in enumerate(header):
        table.add_column(Text(name), justify="left" if i == 0 else "right", overflow="fold")
    for row in rows:
        table.add_row(*(Text(cell) for cell in row[: len(header)]), *([""] * (len(header) - len(row))))
    if console is None or not console.is_terminal:
        return table
    if _narrowest(console, table) <= console.width:
        return _fitted(table, [header, *rows], console.width)
    full = [list(row[: len(header)]) + [""] * (len(header) - len(row)) for row in rows]
    turned_header = [f"{header[0]} →", *(row[0] for row in full)]
    turned_rows = [[name, *(row[i] for row in full)] for i, name in enumerate(header) if i]
    turned = rich_table(caption, turned_header, turned_rows)
    if _narrowest(console, turned) <= console.width:
        return _fitted(turned, [turned_header, *turned_rows], console.width)
    return table


def _fitted(table: Table, lines: list[list[str]], width: int) -> Table:
    """*table* with widths that keep every word whole within *width* cells, where its natural width
    is more: each column its longest word, the room left shared in proportion to what each lacks
    of its natural width. Rich gave like widths and cut words ('matched_fil|ter', '../data/f1|.zip'
    in a detection run's tables at 100 columns: issue 41)."""
    cells = [[str(c) for c in line] + [""] * (len(table.columns) - len(line)) for line in lines]
    columns = list(zip(*cells))
    least = [max((cell_len(w) for c in col for w in c.split()), default=1) for col in columns]
    most = [max(max((cell_len(c) for c in col), default=1), 1) for col in columns]
    frame = 3 * len(columns) + 1  # a border and a space either side of each column
    if sum(most) + frame <= width or sum(least) + frame > width:
        return table
    spare, lack = width - frame - sum(least), [m - n for m, n in zip(most, least)]
    for column, n, short in zip(table.columns, least, lack):
        column.width = n + (spare * short) // max(sum(lack), 1)
    return table


def _narrowest(console: Console, table: Table) -> int:
    """The width *table* needs to keep its longest words whole."""
    return Measurement.get(console, console.options.update_width(10_000), table).minimum


def results(lines: Iterable[str], console: Console | None = None) -> list:
    """The summary lines of a run as things to print: a Markdown table (with the line before
    it, its caption) as a rich table (fitted to *console*: rich_table), every other line as plain text."""
    shown: list = []
    pending: str | None = None  # a line that may be the caption of the table that follows
    for line in lines:
        tables = markdown_tables(line) if "|" in line else None
        if tables is None:
            if pending is not None:
                shown.append(Text(pending))
            pending = line
            continue
        for n, (caption, header, rows) in enumerate(tables):
            if n == 0 and not caption and pending is not None and pending.rstrip().endswith(":"):
                caption, pending = pending, None
            if pending is not None:
                shown.append(Text(pending))
                pending = None
            shown.append(rich_table(caption, header, rows, console))
    if pending is not None:
        shown.append(Text(pending))
    return shown


def print_results(console: Console, verdict: list[str], summary: list[str]) -> None:
    """The verdict first, then the run's tables and lines. A table wider than the terminal
    folds its cells (turned, where only so its words stay whole); off a terminal (a log, a pipe)
    it keeps its natural width."""
    if verdict:
        console.print(Text("Verdict", style="bold underline"))
        for line in verdict:
            console.print(Text(f"• {line}"))
        console.print()
    for item in results(summary, console):
        print_table(console, item) if isinstance(item, Table) else console.print(item)


def print_table(console: Console, table: Table) -> None:
    """On a terminal, folded to its width; elsewhere (a log, a pipe) at its natural width, so
    that no cell is cut into pieces for a reader that has no width."""
    if console.is_terminal:
        console.print(table)
    else:
        natural = Measurement.get(console, console.options.update_width(10_000), table).maximum
        # Console.print caps width at the console's own: a wide one for this table, same file
        Console(file=console.file, width=max(natural, console.width), soft_wrap=True).print(table)


_STATUS_STYLES = {"finished": "green", "failed": "red", "cancelled": "yellow", "stopped": "yellow", "running": "cyan"}


def runs_table(runs, console: Console | None = None):
    """`gearlab runs`: a table, a row a run; on *console*'s terminal narrower than the table, a
    block a run (its name, kind, start, duration and status on one line, its headline cut to a
    line under them, then its run directory whole), so that no word or path is folded into
    pieces (at 100 columns a row took 5-11 lines: 'likelihood_r|atio', '/tmp/helper|A/runs/...')."""
    from .runinfo import date_text, duration_text

    table = _runs_table(runs)
    natural = Measurement.get(console, console.options.update_width(10_000), table).maximum if console else 0
    if console is None or not console.is_terminal or natural <= console.width:
        return table
    header = ("name", "kind", "started", "duration", "status")
    rows = [(r.name, r.kind, date_text(r.started), duration_text(r.duration_s), r.status) for r in runs]
    widths = [max(cell_len(c) for c in column) for column in zip(header, *rows)]
    shown: list = [
        Text("gearlab runs", style="bold"),
        Text("  ".join(h.ljust(w) for h, w in zip(header, widths)).rstrip(), style="bold"),
    ]
    for r, row in zip(runs, rows):
        line = Text("  ".join(c.ljust(w) for c, w in zip(row[:-1], widths)) + "  ")
        line.append(row[-1], style=_STATUS_STYLES.get(r.status, ""))
        said = Text(f"  {r.problem or r.headline or '-'}", no_wrap=True, overflow="ellipsis")
        shown += [line, said, Text(f"  {r.path}", style="dim", overflow="fold")]
    return Group(*shown)


def _runs_table(runs) -> Table:
    from .runinfo import date_text, duration_text

    styles = _STATUS_STYLES
    table = Table(title=Text("gearlab runs", style="bold"), title_justify="left")
    for name in ("name", "kind", "started", "duration", "status", "headline", "run directory"):
        table.add_column(name, overflow="fold")
    for r in runs:
        table.add_row(
            Text(r.name),
            Text(r.kind),
            Text(date_text(r.started)),
            Text(duration_text(r.duration_s)),
            Text(r.status, style=styles.get(r.status, "")),
            Text(r.problem or r.headline or "-"),
            Text(str(r.path)),
        )
    return table


def all_scored(rows: list[dict], alarm: bool = False) -> None:
    """After `gearlab score` has shown its rows: the takes it refused among several named in one line (exit 2, as a
    run stopped by bad input keeps its finished units): the others are scored and kept, and the exit code says not
    every take was. *alarm* (--exit-code): every take scored, exit 1 where any row calls one (a fault, other damage),
    else 3 where a row says a take's level changed (a sensor, gain or load: record a new history), so that a script
    run weekly needs no JSON to tell an alarm from a level change or from none (0)."""
    skipped = [r["file"] for r in rows if r.get("skipped")]
    if skipped:
        given = len(dict.fromkeys(r["file"] for r in rows))
        raise GearlabInputError(f"{len(skipped)} of {given} takes not scored (each said above): {', '.join(skipped)}")
    from .kinds.detection_own import NOT_SCORED  # the kinds import this module: at call time
    from .kinds.detection_which_gear import is_level_change

    if not alarm:
        return
    said = [r["decision"] for r in rows if r["decision"] not in ("healthy", NOT_SCORED)]
    if any(not is_level_change(d) for d in said):
        raise SystemExit(1)
    if said:  # no damage called: the level changed
        raise SystemExit(3)


def score_tables(rows: list[dict], run_dir, width: int = 80) -> list:
    """What `gearlab score` prints (kinds.detection_scoring.score's rows): per scored file, a line
    with its speed and how it was found, its condition and the threshold rule, a line with the gear
    its change is localised on and the evidence, then a table that fits *width* columns (a terminal's):
    per method and unit the units called, the median score less the threshold (above 0: most units
    called) and the decision ("other damage: <gear>" when the change lies on a gear not watched)."""
    from .kinds.detection_which_gear import is_undetermined, unwatched  # the kinds import this module: at call time

    unread = "not localised: too short"  # a take the which-gear check could not read (data.which_gear)

    quiet = unwatched(rows)  # localised on a gear no method watches, no method's decision calling it
    shown: list = [Text(f"scored with {run_dir}", style="bold")]
    for file in dict.fromkeys(r["file"] for r in rows):
        mine = [r for r in rows if r["file"] == file]
        r0 = mine[0]
        if r0.get("skipped"):  # refused, of several takes given: the others are scored (all_scored: exit 2)
            shown.append(Text(f"{file}: not scored: {r0['skipped']}", style="yellow"))
            continue
        shown.append(
            Text(
                f"{file}: {r0['speed_hz']:.3f} Hz, from {r0['speed_from']}; condition {r0['condition']}"
                + (f" ({r0['condition_by']})" if r0.get("condition_by") else "")
                + "; "
                f"thresholds: {r0['rule']}"
            )
        )
        if r0.get("scored_on"):  # a run-up or coast-down: its revolutions at the history's speed (detection_scoring)
            shown.append(Text(r0["scored_on"]))
        if r0.get("gearbox"):  # a record of another gearbox than the run's description (detection_scoring)
            shown.append(Text(f"gearbox: {r0['gearbox']}"))
        if r0.get("level"):  # another load or gain than the history's: NA4 reads it as a change
            shown.append(Text(r0["level"]))
        for said in dict.fromkeys(r["history"] for r in mine if r.get("history")):  # one history take (one_take)
            shown.append(Text(f"warning: {said}", style="yellow"))
        if r0.get("values"):  # how its values became m/s², and whose keys read it: a wrong unit scores as healthy
            shown.append(
                Text(f"values: {r0['values']}" + (f"; read with {r0['read_with']}" if r0.get("read_with") else ""))
            )
        if r0.get("already"):  # a take scored before, under this name or another: one point of the trend
            shown.append(Text(r0["already"], style="yellow"))
        for flaw in r0.get("flaws") or ():  # clipped, a dropout, a drift taken out: never scored unsaid
            shown.append(Text(f"warning: {flaw}", style="yellow"))
        if r0.get("call") is not None:  # a run that localises (a source simulating a gearbox description)
            where = r0.get("localised") or ("not determined" if is_undetermined(r0["call"]) else "nothing")
            evidence = r0.get("evidence") or ""
            if evidence.startswith("not read: "):  # not localised at all (a take far off its history's speed)
                where, evidence = evidence, ""
            elif where == "nothing" and evidence.startswith(unread):  # too short, and no method called it
                where, evidence = evidence.replace(unread, "not read: too short", 1), ""
            shown.append(Text(f"which gear: {where}" + (f" ({evidence})" if evidence else "")))
            if r0.get("table_call"):  # the run's own take, its table decided by an older rule (detection_scoring)
                shown.append(Text(r0["table_call"], style="yellow"))
            if file in quiet:
                # a broken tooth on a gear no method watches, their units under threshold: each decision read
                # 'healthy' (a 74T output gear's broken tooth at z 155 over 2.7 beside twelve 'healthy' rows)
                said = f"{r0['call']}, on a gear this run does not watch: 'healthy' below is of the watched gear"
                shown.append(Text(said, style="yellow"))
        cells = [
            [
                r["method"],
                r["unit"],
                f"{r['called']}/{r['units']}",
                "-" if r["median_score"] is None else f"{r['median_score'] - r['threshold']:+.3g}",
                r["decision"],
            ]
            for r in mine
        ]
        header = ("method", "unit", "called", "median-thr", "decision")
        natural = [max(len(c) for c in col) for col in zip(header, *cells)]
        method_width, decision_width = None, None
        if sum(natural) + 3 * len(header) + 1 > width:  # too wide: method names wrap at their words,
            # a decision such as "other damage: output gear 71T (stage 1)" keeps two lines at most
            method_width = max(len(w) for c in cells for w in c[0].split())
            decision_width = min(natural[-1], max(22, width - 3 * len(header) - 1 - method_width - sum(natural[1:4])))
        table = Table()
        table.add_column("method", overflow="fold", max_width=method_width)
        table.add_column("unit", overflow="fold")
        table.add_column("called", justify="right", overflow="fold")
        table.add_column("median-thr", justify="right", overflow="fold")
        table.add_column("decision", overflow="fold", min_width=decision_width)
        for c, r in zip(cells, mine):
            colour = "green" if r["decision"] == "healthy" else "red" if r["decision"] == "fault" else "yellow"
            table.add_row(*(Text(x) for x in c[:4]), Text(c[4], style=colour))
        shown.append(table)
    return shown


def score_trend(run_dir) -> list:
    """The last lines `gearlab score` prints: the run's scoring history so far (the takes just scored in it) per
    condition in words, which take was first called, by which methods, on which gear and tooth
    (kinds.detection_trend)."""
    from .kinds.detection_trend import first_called
    from .parts.scoring import read_history
    from .runs import RunDir

    return [Text(f"trend: {line}") for line in first_called(read_history(RunDir.open(Path(run_dir))))]
