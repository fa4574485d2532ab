"""Widgets of the gearlab TUI: a markdown table shown as a DataTable, a terminal chart, stage bars."""

from __future__ import annotations

import plotext
from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import DataTable, Label, ProgressBar, Static

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
        self.add_columns(*(tables[0][0] + [""] * (width - len(tables[0][0]))))
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

    def show(self, chart: Chart | None) -> None:
        self.chart = chart
        self.refresh(layout=True)

    def render(self):
        chart = self.chart
        if chart is None:
            return Text("no chart", style="dim")
        curves = [c for c in chart.curves if len(c.x)]  # plotext cannot draw an empty series
        if not curves:
            return Text(f"{chart.title}: " + ("; ".join(chart.notes) or "nothing to draw yet"), style="dim")
        plotext.clf()
        plotext.plotsize(max(self.size.width, 20), max(self.size.height, 8))
        plotext.theme("pro")
        for i, curve in enumerate(curves):
            x, y = [float(v) for v in curve.x], [float(v) for v in curve.y]
            color = COLORS[i % len(COLORS)]
            plotext.plot(x, y, label=curve.label, marker="braille", color=color)
            if curve.err is not None:
                plotext.error(x, y, yerr=[float(v) for v in curve.err], color=color)
        if chart.xticks is not None:
            plotext.xticks(list(chart.xticks))
        plotext.title(chart.title)
        plotext.xlabel(chart.xlabel)
        plotext.ylabel(chart.ylabel)
        try:
            return Text.from_ansi(plotext.build())
        except Exception as exc:  # noqa: BLE001 - a chart that cannot be drawn must not take the TUI down
            return Text(f"{chart.title}: cannot draw it at this size ({type(exc).__name__})", style="dim")


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
            self.mount(Label(message or stage, id=f"label-{stage}"), ProgressBar(total=total or None, id=f"bar-{stage}",
                                                                           show_eta=False))
        else:
            self.query_one(f"#label-{stage}", Label).update(message or stage)
            bar.update(total=total or None, progress=0)

    def advance(self, stage: str, done: int, total: int) -> None:
        bar = self._bar(stage)
        if bar is not None:
            bar.update(total=total or None, progress=done)

    def _bar(self, stage: str) -> ProgressBar | None:
        found = self.query(f"#bar-{stage}")
        return found.first(ProgressBar) if found else None
