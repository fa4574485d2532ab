"""Widgets of the gearlab TUI: a markdown table shown as a DataTable, a terminal chart, stage bars."""

from __future__ import annotations

import math

import plotext
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import DataTable, Label, ProgressBar, Static, Tree

from ..charts import Chart

COLORS = ("blue+", "red+", "green+", "magenta+", "cyan+", "yellow+", "orange", "white", "blue", "red", "green")


def markdown_tables(text: str) -> list[list[list[str]]]:
    """The markdown pipe tables of *text* (as the kinds write table.md; blank lines part
    them), each a list of rows of cells, the header first."""
    tables, rows = [], []
    for line in text.strip().splitlines() + [""]:
        if line.strip():
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not all(set(c) <= set("-:") for c in cells):  # not the |---| rule
                rows.append(cells)
        elif rows:
            tables.append(rows)
            rows = []
    return tables


class ResultTable(DataTable):
    """A kind's results tables (markdown), redrawn whole as records arrive: the first table's
    header heads the columns, a later table's header is a bold row."""

    DEFAULT_CSS = "ResultTable { height: auto; max-height: 10; }"

    def show_markdown(self, text: str) -> None:
        tables = markdown_tables(text)
        self.clear(columns=True)
        if not tables:
            return
        width = max(len(row) for table in tables for row in table)
        head = tables[0][0] + [""] * (width - len(tables[0][0]))
        # a long name with a qualifier ('mmd (unsupervised)', 'Bayes bound (target's own ...)')
        # heads its column on two lines: the columns stay as wide as their numbers need
        split = [h.split(" (", 1) if " (" in h and len(h) > 14 else [h] for h in head]
        self.header_height = 2 if any(len(parts) > 1 for parts in split) else 1
        for parts in split:
            label = Text(parts[0] + ("\n(" + parts[1] if len(parts) > 1 else ""))
            self.add_column(
                label,
                width=max(
                    min(max(len(line) for line in label.plain.splitlines()), 24),
                    max(
                        (len(row[i]) for t in tables for row in t[1:] for i in [len(self.columns)] if i < len(row)),
                        default=1,
                    ),
                ),
            )
        for i, table in enumerate(tables):
            if i:
                self.add_row(*([""] * width))
                self.add_row(*(Text(c, style="bold") for c in table[0] + [""] * (width - len(table[0]))))
            for row in table[1:]:  # cells are data, not markup
                self.add_row(*(Text(c) for c in row + [""] * (width - len(row))))


class ChartView(Static):
    """One chart drawn with plotext to the widget's size; `notes` say what could not be drawn."""

    DEFAULT_CSS = "ChartView { height: 18; }"

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.chart: Chart | None = None
        self.place = ""

    def show(self, chart: Chart | None, place: str = "") -> None:
        """Draw *chart*; *place* ("chart 2/3") heads it, so a user knows there are more."""
        self.chart, self.place = chart, place
        self.refresh(layout=True)

    def render(self):
        chart = self.chart
        if chart is None:
            return Text("no chart", style="dim")
        head = f"{self.place}: {chart.title}" if self.place else chart.title
        curves = [c for c in chart.curves if len(c.y)]  # plotext cannot draw an empty series
        if not curves:
            return Text(f"{head}: " + ("; ".join(chart.notes) or "nothing to draw yet"), style="dim")
        plotext.clf()
        plotext.plotsize(max(self.size.width, 20), max(self.size.height, 8))
        plotext.theme("pro")
        if chart.categories is not None:
            self._bars(chart, curves)
        else:
            self._lines(chart, curves)
        plotext.title(head)
        try:
            return Text.from_ansi(plotext.build())
        except Exception as exc:  # noqa: BLE001 - a chart that cannot be drawn must not take the TUI down
            return Text(f"{head}: cannot draw it at this size ({type(exc).__name__})", style="dim")

    @staticmethod
    def _lines(chart: Chart, curves) -> None:
        for i, curve in enumerate(curves):
            x, y = [float(v) for v in curve.x], [float(v) for v in curve.y]
            color = COLORS[i % len(COLORS)]
            plotext.plot(x, y, label=curve.label, marker="braille", color=color)
            if curve.err is not None:
                plotext.error(x, y, yerr=[float(v) for v in curve.err], color=color)
        if chart.xticks is not None:
            plotext.xticks(list(chart.xticks))
        plotext.xlabel(chart.xlabel)
        plotext.ylabel(chart.ylabel)

    @staticmethod
    def _bars(chart: Chart, curves) -> None:
        """Named categories as horizontal bars, the names on the left (they can be long:
        'uncorrected source_only'); several curves side by side per category."""
        names = [str(n) for n in chart.categories]
        values = [[float(v) for v in c.y] for c in curves]
        label = chart.ylabel
        positive = [v for row in values for v in row if v > 0]
        if positive and min(v for row in values for v in row) >= 0 and max(positive) > 1e3 * min(positive):
            # values over many decades (a noise gap beside a mesh gap): bars of their logarithm,
            # or all but the largest would be invisible
            floor = min(positive) / 10
            values = [[math.log10(max(v, floor)) - math.log10(floor) for v in row] for row in values]
            label = f"log10({chart.ylabel}) above {floor:.3g}"
        if len(values) == 1:
            plotext.bar(names, values[0], orientation="horizontal", color=COLORS[0], width=0.6)
        else:
            plotext.multiple_bar(
                names,
                values,
                labels=[c.label for c in curves],
                orientation="horizontal",
                color=[COLORS[i % len(COLORS)] for i in range(len(values))],
            )
        plotext.xlabel(label)  # horizontal bars: the values run along x


class BrowserTree(Tree):
    """The sidebar's tree with the file browsers' arrows: → unfolds a node (or, unfolded, goes
    to its first child), ← folds it (or, folded, goes to its parent)."""

    BINDINGS = [
        Binding("right", "unfold", "Unfold", show=False),
        Binding("left", "fold", "Fold", show=False),
    ]

    def action_unfold(self) -> None:
        node = self.cursor_node
        if node is None:
            return
        if node.allow_expand and not node.is_expanded:
            node.expand()
        elif node.is_expanded and node.children:
            self.move_cursor(node.children[0])

    def action_fold(self) -> None:
        node = self.cursor_node
        if node is None:
            return
        if node.is_expanded and node.children:
            node.collapse()
        elif node.parent is not None and not node.parent.is_root:
            self.move_cursor(node.parent)


def stage_id(stage: str) -> str:
    """A widget id for a stage name: any name ('gap before', 'gap round 2', 'trial 3/40')
    maps to letters, digits, '-' and '_' only, and two names never share an id (the hex
    code of every other character is spelled out)."""
    return "".join(c if c.isascii() and (c.isalnum() or c == "_") else f"-{ord(c):x}-" for c in stage)


class Stages(Vertical):
    """A labelled progress bar per stage of a run (datasets, simulate, priming, runs, ...)."""

    DEFAULT_CSS = """
    Stages { height: auto; }
    Stages > Label { width: 1fr; }
    """

    def compose(self) -> ComposeResult:
        return iter(())

    def reset(self) -> None:
        self.remove_children()

    def start(self, stage: str, message: str, total: int) -> None:
        bar = self._bar(stage)
        if bar is None:
            key = stage_id(stage)
            self.mount(
                Label(message or stage, id=f"label-{key}"),
                ProgressBar(total=total or None, id=f"bar-{key}", show_eta=True),  # counts, % and ETA
            )
        else:
            self.query_one(f"#label-{stage_id(stage)}", Label).update(message or stage)
            bar.update(total=total or None, progress=0)

    def advance(self, stage: str, done: int, total: int) -> None:
        bar = self._bar(stage)
        if bar is not None:
            bar.update(total=total or None, progress=done)

    def _bar(self, stage: str) -> ProgressBar | None:
        found = self.query(f"#bar-{stage_id(stage)}")
        return found.first(ProgressBar) if found else None
