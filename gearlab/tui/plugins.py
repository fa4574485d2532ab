"""The Plugins tab: every registered plugin in a table, and under it the highlighted plugin's
description with each parameter's doc, unit (the one shown and the SI one stored), default
and bounds; the problems of broken third-party plugins, named by package, at the bottom.

The table's parameter column is as wide as the tab leaves it (its cells wrap, never cut);
the detail pane wraps to any width.
"""

from __future__ import annotations

from rich.console import Group
from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical, VerticalScroll
from textual.widgets import DataTable, Static

from ..units import display

PADDING = 2  # cells a DataTable column adds to its width (one each side)


def value_text(param: dict, value: float) -> str:
    """A value in the parameter's display unit ('50 mm'; a pure number alone)."""
    return display(value, param["unit"], param["display_unit"])


def unit_text(param: dict) -> str:
    """'mm (SI: m)', 'kg' (the same), or '-' (a pure number)."""
    shown, si = param["display_unit"] or param["unit"], param["unit"]
    if not shown:
        return "-"
    return shown if shown == si else f"{shown} (SI: {si or '-'})"


def bounds_text(param: dict) -> str:
    low, high = value_text(param, param["low"]), value_text(param, param["high"])
    unit = param["display_unit"] or param["unit"]
    low = low.removesuffix(f" {unit}") if unit else low  # '0 .. 50 mm', the unit once
    return f"{low} .. {high}" + (" (whole numbers)" if param.get("integer") else "")


def detail(row: dict) -> Group:
    """What a plugin is and what each parameter means: the row of Registry.describe() in words."""
    from .. import registry as plugins

    head = Text.assemble((row["name"], "bold"), f"  {plugins.kind_text(row)}, package {row['package']}")
    parts = [head, Text(row.get("doc") or "(no description)")]
    if row["params"]:
        table = Table(box=None, padding=(0, 1), show_edge=False, header_style="bold")
        table.add_column("parameter", no_wrap=True)
        table.add_column("what it is", ratio=1)
        table.add_column("unit")
        table.add_column("default")
        table.add_column("bounds")
        for p in row["params"]:
            table.add_row(p["name"], p["doc"] or "-", unit_text(p), value_text(p, p["default"]), bounds_text(p))
        parts.append(table)
    else:
        parts.append(Text("no parameters", style="dim"))
    for name, choices in (row.get("options") or {}).items():
        parts.append(Text(f"{name}: one of {', '.join(choices)}"))
    return Group(*parts)


class PluginsPane(Vertical):
    """The table of plugins, the highlighted one's detail, and the broken plugins' problems."""

    DEFAULT_CSS = """
    PluginsPane #plugin-table { height: 1fr; min-height: 5; }
    PluginsPane #plugin-detail-scroll { height: auto; max-height: 45%; border-top: solid $primary-darken-2; }
    PluginsPane #plugin-detail { padding: 0 1; }
    PluginsPane #problems { height: auto; padding: 0 1; color: $error; }
    """

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.rows: list[dict] = []
        self.params_width = 0
        self.filled = False

    def compose(self) -> ComposeResult:
        yield DataTable(id="plugin-table", cursor_type="row")
        with VerticalScroll(id="plugin-detail-scroll"):
            yield Static("", id="plugin-detail")
        yield Static("", id="problems")

    def on_show(self) -> None:
        """Filled when the tab is first shown: a table of ~50 wrapped rows measured on a hidden
        tab was 0.1 s of the TUI's first screen (issue 42)."""
        if self.filled:
            return
        self.filled = True
        # the registry (the effects' and dynamics' modules, 0.1 s of CPU) imported when the tab is first shown,
        # not before the first screen
        from .. import registry as plugins

        registry = plugins.get_registry()  # looked up at call time: a test may give its own registry
        self.rows = registry.describe()
        self.fill(40)
        problems = [f"problem: {p}" for p in registry.problems]
        self.query_one("#problems", Static).update(Text("\n".join(problems)))
        self.on_resize()  # the width the tab leaves, as a resize of a filled table gives

    def on_resize(self) -> None:
        """The parameter column takes what the tab leaves it (kind, name and package first)."""
        table = self.query_one("#plugin-table", DataTable)
        if not self.size.width or not table.columns:
            return
        others = sum(c.width + PADDING for c in list(table.columns.values())[:3])
        width = max(24, min(60, self.size.width - 2 - others - PADDING))  # 2: the vertical scrollbar
        if width != self.params_width:
            self.fill(width)

    def fill(self, params_width: int) -> None:
        from .. import registry as plugins

        table = self.query_one("#plugin-table", DataTable)
        row_at = table.cursor_row
        table.clear(columns=True)
        self.params_width = params_width
        # fixed widths, the cells wrapped in them (rows as high as they need): the long kinds
        # ("effect (excitation, breaks tooth-shift symmetry)") and the parameters are read
        # whole, and kind, name and package fit beside the folded sidebar at 80 columns
        kinds = [plugins.kind_text(row) for row in self.rows]
        table.add_column("kind", width=max(16, *(len(w) for k in kinds for w in k.split())))
        table.add_column("name", width=max((len(row["name"]) for row in self.rows), default=4))
        table.add_column("package", width=max((len(row["package"]) for row in self.rows), default=7))
        table.add_column("parameters", width=params_width)
        for kind, row in zip(kinds, self.rows):
            # Text, not str: a DataTable reads "[mm]" in a string as markup
            table.add_row(Text(kind), row["name"], row["package"], Text(plugins.params_text(row) or "-"), height=None)
        if self.rows:
            table.move_cursor(row=min(row_at, len(self.rows) - 1))
            self.show(min(row_at, len(self.rows) - 1))

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        if event.data_table.id == "plugin-table":
            self.show(event.cursor_row)

    def show(self, index: int) -> None:
        if 0 <= index < len(self.rows):
            self.query_one("#plugin-detail", Static).update(detail(self.rows[index]))
