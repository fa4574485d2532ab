"""Widgets of the gearlab TUI: a markdown table shown as a DataTable, a terminal chart, the tree.
The Progress tab's stage bars are in gearlab.tui.progress."""

from __future__ import annotations

import math
import re
import textwrap
from collections import OrderedDict

import numpy as np
from rich.console import Console
from rich.syntax import Syntax
from rich.text import Text
from textual.binding import Binding
from textual.widgets import DataTable, Static, Tree

from ..charts import Chart

COLORS = ("blue+", "red+", "green+", "magenta+", "cyan+", "yellow+", "orange", "white", "blue", "red", "green")
# the same colours in rich's names, for the legend drawn under a plot
RICH_COLORS = (
    "bright_blue",
    "bright_red",
    "bright_green",
    "bright_magenta",
    "bright_cyan",
    "bright_yellow",
    "dark_orange",
    "white",
    "blue",
    "red",
    "green",
)


def legend(labels: list[str], width: int) -> list[Text]:
    """Lines of '━━ label' entries in the curves' colours, as many to a line as *width* holds;
    a label too long for a line wraps (it is never cut)."""
    lines, line = [], Text()
    for i, label in enumerate(labels):
        entry = Text.assemble(("━━ ", RICH_COLORS[i % len(RICH_COLORS)]), label)
        if line and line.cell_len + 3 + entry.cell_len > width:
            lines.append(line)
            line = Text()
        line = Text.assemble(line, "   ", entry) if line else entry
    lines.append(line)
    return [part for one in lines for part in one.wrap(Console(width=width), width)]


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


def cell(text: str) -> Text:
    """A table cell as data (never markup), Markdown's **bold** (the gap benchmark's 'all' row) in bold."""
    shown = Text()
    for i, part in enumerate(re.split(r"\*\*(.+?)\*\*", text)):
        shown.append(part, style="bold" if i % 2 else "")
    return shown


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
        # every cell below the first header: the data, and the later tables' headers (bold rows)
        below = [row for n, table in enumerate(tables) for row in (table[1:] if n == 0 else table)]
        labels = []
        for i, h in enumerate(head):
            # a long name with a qualifier ('mmd (unsupervised)', 'Bayes bound (target's own
            # shapes and noise law)') heads its column on more lines, wrapped, never cut: the
            # column stays as wide as its numbers need, 24 cells at least for a long name
            parts = h.split(" (", 1) if " (" in h and len(h) > 14 else [h]
            parts = parts[:1] + [f"({p}" for p in parts[1:]]
            data = max((len(row[i]) for row in below if i < len(row)), default=1)
            longest_word = max((len(w) for w in h.split()), default=1)
            cells = max(min(max(len(p) for p in parts), 24), data, longest_word)
            labels.append((Text("\n".join(line for p in parts for line in textwrap.wrap(p, cells) or [""])), cells))
        self.header_height = max(len(label.plain.splitlines()) for label, _ in labels)
        for label, cells in labels:
            self.add_column(label, width=cells)
        for i, table in enumerate(tables):
            if i:
                self.add_row(*([""] * width))
                self.add_row(*(Text(c, style="bold") for c in table[0] + [""] * (width - len(table[0]))))
            for row in table[1:]:  # cells are data, not markup
                self.add_row(*(cell(c) for c in row + [""] * (width - len(row))))


class TomlSyntax(Syntax):
    """A scenario's TOML, numbered, highlighted and wrapped, drawn once per width: Textual draws
    a widget of auto height to measure it and again to show it, at each width the scroll bar
    leaves (5 draws, 3 alike, of the TUI's first screen; the view was 0.1 s of its CPU, issue 42).
    With line numbers and word wrap, rich's Syntax reads of the options only the width, the
    console's encoding and legacy_windows (each line is wrapped with height=None)."""

    def __init__(self, code: str, **kwargs) -> None:
        super().__init__(code, "toml", line_numbers=True, word_wrap=True, **kwargs)
        self._drawn: dict[tuple, list] = {}

    def __rich_console__(self, console, options):
        key = (id(console), options.max_width, options.encoding, options.legacy_windows)
        if key not in self._drawn:
            parts = super().__rich_console__(console, options)  # one Segments over a generator
            self._drawn[key] = [segment for part in parts for segment in console.render(part, options)]
        yield from self._drawn[key]


# The charts drawn last, by what they show (drawn_key), heading and width: a run opened again, or a
# width seen before, is not drawn again (issue 42: test_tui_edges drew 26 of its 45 charts a second
# time, 2.5 of its 4.2 s of plotext).
DRAWN: OrderedDict[tuple, Text] = OrderedDict()
DRAWN_KEPT = 32


def drawn_key(chart: Chart, curves) -> tuple:
    """What ChartView._draw reads of *chart* and its drawable *curves*: their floats as bytes."""

    def floats(values) -> bytes | None:
        return None if values is None else np.asarray([float(v) for v in values]).tobytes()

    ticks = None if chart.xticks is None else repr(list(chart.xticks))  # plotext's labels: as given
    names = None if chart.categories is None else tuple(str(n) for n in chart.categories)
    lines = tuple((c.label, floats(c.x), floats(c.y), floats(c.err)) for c in curves)
    return chart.title, chart.xlabel, chart.ylabel, ticks, names, lines, tuple(float(h) for h in chart.hlines)


class ChartView(Static):
    """One chart drawn with plotext to the widget's width, its legend under the plot (plotext
    draws its own over the curves' top left corner, hiding them); `notes` say what could not
    be drawn."""

    DEFAULT_CSS = "ChartView { height: auto; }"
    PLOT_HEIGHT = 18  # rows of the plot itself, title and axis labels included

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.chart: Chart | None = None
        self.place = ""
        # the last drawing, what it was drawn for, and its chart (held: its id is not reused)
        self.drawn: tuple[tuple, Text, Chart] | None = None

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
        width = max(self.size.width, 20)
        # plotext takes a tenth of a second or more for a long curve, and Textual renders a
        # widget of auto height for its layout and again to draw it: drawn once per chart and width,
        # and a chart of the same content at a width seen before not again (DRAWN)
        key = (id(chart), self.place, width)
        if self.drawn is None or self.drawn[0] != key:
            self.drawn = (key, self._drawn(chart, curves, head, width), chart)
        return self.drawn[1]

    def _drawn(self, chart: Chart, curves, head: str, width: int) -> Text:
        key = (drawn_key(chart, curves), head, width, self.PLOT_HEIGHT)
        drawing = DRAWN.get(key)
        if drawing is None:
            drawing = DRAWN[key] = self._draw(chart, curves, head, width)
            while len(DRAWN) > DRAWN_KEPT:
                DRAWN.popitem(last=False)
        else:
            DRAWN.move_to_end(key)
        return drawing

    def _draw(self, chart: Chart, curves, head: str, width: int) -> Text:
        import plotext  # on the first chart: not at the TUI's start (issue 42)

        plotext.clf()
        plotext.limitsize(False, False)  # the widget's size, not the terminal's (a test has none)
        plotext.plotsize(width, self.PLOT_HEIGHT)
        plotext.theme("pro")
        if chart.categories is not None:
            self._bars(chart, curves)
        else:
            self._lines(chart, curves)
        try:
            plot = Text.from_ansi(plotext.build().rstrip("\n"))
        except Exception as exc:  # noqa: BLE001 - a chart that cannot be drawn must not take the TUI down
            return Text(f"{head}: cannot draw it at this size ({type(exc).__name__})", style="dim")
        # the heading over the plot, wrapped to its width: plotext draws no title longer than its canvas is wide, and
        # none at all of a score trend's (its 'first called' line, 'chart 2/2, n next' with it)
        parts = [part for line in head.splitlines() for part in textwrap.wrap(line, width)]
        heading = [Text(part.center(width).rstrip()) for part in parts]
        named = len(curves) > 1 or chart.categories is None  # one series of bars: the axis names it
        return Text("\n").join([*heading, plot, *(legend([c.label for c in curves], width) if named else [])])

    @staticmethod
    def _lines(chart: Chart, curves) -> None:
        import plotext

        for i, curve in enumerate(curves):
            x, y = [float(v) for v in curve.x], [float(v) for v in curve.y]
            color = COLORS[i % len(COLORS)]
            plotext.plot(x, y, marker="braille", color=color)  # no label: the legend goes under the plot
            if curve.err is not None:
                plotext.error(x, y, yerr=[float(v) for v in curve.err], color=color)
        if chart.hlines:
            # plotext scales to the curves alone: a trend all above its threshold hid the line
            ys = [
                float(v) + s * float(e)
                for c in curves
                for v, e in zip(c.y, [0] * len(c.y) if c.err is None else c.err)
                for s in (-1, 1)
            ]
            ys += [float(h) for h in chart.hlines]
            low, high = min(ys), max(ys)
            pad = 0.05 * (high - low) or 0.5
            plotext.ylim(low - pad, high + pad)
            for h in chart.hlines:
                plotext.hline(float(h), "gray")
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
        import plotext

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
                orientation="horizontal",
                color=[COLORS[i % len(COLORS)] for i in range(len(values))],
            )
        plotext.xlabel(label)  # horizontal bars: the values run along x


def shorten(text: Text, width: int) -> Text:
    """*text* in at most *width* cells: cut in the middle ('✓ stiffness_ver…ion.toml'), so that
    both a name's start and its end (which tells apart 'gap_expA' and 'gap_expB') stay."""
    if text.cell_len <= width or width < 8:
        return text
    tail = (width - 1) // 2
    head = width - 1 - tail
    return Text.assemble(text[:head], "…", text[len(text) - tail :])


class BrowserTree(Tree):
    """The sidebar's tree with the file browsers' arrows: → unfolds a node (or, unfolded, goes
    to its first child), ← folds it (or, folded, goes to its parent). The sidebar is as wide as
    its longest line needs (up to a share of the screen, app CSS); a label wider than that is
    cut in its middle, never at its end, and the highlighted node's whole name is its tooltip
    and heads the Scenario tab."""

    BINDINGS = [
        Binding("right", "unfold", "Unfold", show=False),
        Binding("left", "fold", "Fold", show=False),
    ]
    DEFAULT_CSS = "BrowserTree { scrollbar-size-vertical: 1; }"

    def render_label(self, node, base_style, style) -> Text:
        label = super().render_label(node, base_style, style)
        depth = 0
        while node.parent is not None:
            node, depth = node.parent, depth + 1
        return shorten(label, self.scrollable_content_region.width - depth * self.guide_depth)

    def fit_width(self) -> int:
        """The cells the tree needs to show every line whole (border and scrollbar included)."""
        lines = [(self.root, 0)] + [(n, 1) for n in self.root.children]
        lines += [(c, 2) for n in self.root.children for c in n.children]
        icons = len(self.ICON_NODE)
        widths = [depth * self.guide_depth + n.label.cell_len + (icons if n.allow_expand else 0) for n, depth in lines]
        return max(widths) + 2  # the right border and a one-cell scrollbar

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


def summary_view(summary: list[str], width: int):
    """A run's summary lines as the terminal prints them (terminal.results: each table under its caption, its
    columns fitted to *width*); a table whose words cannot stay whole in *width* a block per row, its first two
    cells, then each other column as 'name: value'. A detection run's which-gear table at 80 columns was nine
    columns of five cells, every word and file name cut."""
    from rich.console import Group
    from rich.table import Table

    from ..terminal import _narrowest, results

    console = Console(width=max(width, 20), force_terminal=True)
    shown = []
    for item in results(summary, console):
        if not isinstance(item, Table) or _narrowest(console, item) <= console.width:
            shown.append(item)
            continue
        heads = [Text(c.header).plain if isinstance(c.header, str) else c.header.plain for c in item.columns]
        cells = [[c.plain if isinstance(c, Text) else str(c) for c in column.cells] for column in item.columns]
        if item.title:
            shown.append(Text(item.title.plain if isinstance(item.title, Text) else str(item.title), style="bold"))
        for row in zip(*cells):
            shown.append(Text(" · ".join(c for c in row[:2] if c), style="bold"))
            shown.extend(Text(f"  {h}: {c}") for h, c in zip(heads[2:], row[2:]) if c not in ("", "–"))
    return Group(*shown)


class SummaryView(Static):
    """A run's summary lines (summary_view), drawn again at each new width: the Results tab's is known once the tab
    is shown, and changes as the sidebar folds (tables fitted to an estimate were cut at their right edge)."""

    summary: list[str] | None = None
    drawn_at = 0

    def show(self, summary: list[str] | None, text: str = "") -> None:
        self.summary, self.drawn_at = summary, 0
        if summary:
            self.draw()
        else:
            self.update(text)

    def draw(self) -> None:
        width = self.content_size.width or self.app.size.width - 4
        if self.summary and width != self.drawn_at:
            self.drawn_at = width
            self.update(summary_view(self.summary, width))

    def on_resize(self) -> None:
        self.draw()
