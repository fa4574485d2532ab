"""Panels of the gearlab TUI that open over the main screen: the key list (`?`), the
run-with-options form (`f`) and the scoring form (`s`). Escape closes each."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Button, Checkbox, Input, Label, Select, Static

from ..kinds import SCENARIO_KINDS
from ..scenario import EXECUTION_TABLE, Scenario


@dataclass(frozen=True)
class RunOptions:
    """What a run may override on its command line (None: the scenario's own value)."""

    quick: bool = False
    executor: str | None = None
    device: str | None = None
    trials: int | None = None  # a kind whose OVERRIDES has them only
    seed: int | None = None


def panel_css(screen: str, width: int, max_height: str = "95%") -> str:
    """The look the panels share: centred over the app, a bordered scrolling column of *width* cells."""
    return f"""
    {screen} {{ align: center middle; }}
    {screen} > VerticalScroll {{ width: {width}; max-width: 95%; height: auto; max-height: {max_height};
        border: thick $primary; background: $surface; padding: 0 1; }}
    """


class KeysScreen(ModalScreen):
    """Every key binding of the app, those the footer leaves out included, with what each does
    in words wrapped to the panel's width (never cut: the panel scrolls when they do not fit)."""

    BINDINGS = [Binding("escape,question_mark,q", "dismiss", "Close")]
    DEFAULT_CSS = panel_css("KeysScreen", width=72, max_height="90%") + "KeysScreen #keys { height: auto; }"

    # keys that are no binding of the app: the tree's own and the palette
    TREE = (
        ("↑ ↓", "move in the tree"),
        ("→ ←", "unfold a scenario (then go to its first run), fold it (or go back up to it)"),
        ("enter", "open a scenario (Scenario tab) or a past run (Results tab)"),
        ("ctrl+p", "command palette: run, quick run, validate a scenario; open a run; compare the marked runs"),
    )

    def __init__(self, bindings: Sequence[Binding]):
        super().__init__()
        self.rows = [(b.key_display or b.key, b.tooltip or b.description) for b in bindings] + list(self.TREE)

    def compose(self) -> ComposeResult:
        table = Table.grid(padding=(0, 2))
        table.add_column(no_wrap=True, style="bold")
        table.add_column(overflow="fold")  # words wrap; only a word longer than a line folds
        for key, what in self.rows:
            table.add_row(Text(key), Text(what))
        with VerticalScroll():
            yield Label(Text("keys (escape closes; ↑ ↓ scroll)", style="bold"))
            yield Static(table, id="keys")


def _choices(key: str) -> list[tuple[str, str]]:
    """The values an [execution] key takes, read from its own check (one_of), so that the
    form never offers what the scenario schema would refuse."""
    check = EXECUTION_TABLE.keys[key].check
    values = getattr(check, "choices", None) or ()
    return [(v, v) for v in values]


class RunOptionsScreen(ModalScreen[RunOptions | None]):
    """A small form: quick, executor, device, and a benchmark's trials and seed."""

    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]
    DEFAULT_CSS = (
        panel_css("RunOptionsScreen", width=60)
        + """
    RunOptionsScreen Label { margin-top: 1; }
    RunOptionsScreen Horizontal { height: auto; margin-top: 1; }
    #problem { color: $error; height: auto; }
    """
    )

    def __init__(self, scenario: Scenario):
        super().__init__()
        self.scenario = scenario
        self.benchmark = "trials" in SCENARIO_KINDS[scenario.kind].OVERRIDES  # the kind contract

    def compose(self) -> ComposeResult:
        execution = self.scenario.tables.get("execution", {})
        with VerticalScroll():
            yield Label(Text(f"run {self.scenario.name} ({self.scenario.kind}) with", style="bold"))
            yield Checkbox("quick (--quick: shrunk for a smoke run)", id="quick")
            yield Label(f"executor (scenario: {execution.get('executor', 'local')})")
            yield Select(_choices("executor"), prompt="the scenario's", id="executor")
            yield Label(f"device (scenario: {execution.get('device', 'auto')})")
            yield Select(_choices("device"), prompt="the scenario's", id="device")
            if self.benchmark:
                bench = self.scenario.tables.get("benchmark", {})
                yield Label(f"trials (scenario: {bench.get('trials')})")
                yield Input(placeholder="the scenario's", type="integer", id="trials")
                yield Label(f"seed of the hidden draws (scenario: {bench.get('seed')})")
                yield Input(placeholder="the scenario's", type="integer", id="seed")
            yield Static("", id="problem")
            with Horizontal():
                yield Button("Run", variant="primary", id="go")
                yield Button("Cancel", id="cancel")

    def on_button_pressed(self, event: Button.Pressed) -> None:
        if event.button.id == "cancel":
            self.dismiss(None)
            return
        try:
            options = self.options()
        except ValueError as exc:
            self.query_one("#problem", Static).update(str(exc))
            return
        self.dismiss(options)

    def on_input_submitted(self, event: Input.Submitted) -> None:
        self.query_one("#go", Button).press()

    def options(self) -> RunOptions:
        def chosen(name: str) -> str | None:
            value = self.query_one(f"#{name}", Select).value
            return value if isinstance(value, str) else None  # Select.BLANK: the scenario's own

        def number(name: str, low: int) -> int | None:
            if not self.benchmark:
                return None
            text = self.query_one(f"#{name}", Input).value.strip()
            if not text:
                return None
            value = int(text)
            if value < low:
                raise ValueError(f"{name}: expected a whole number >= {low}, got {value}")
            return value

        return RunOptions(
            quick=self.query_one("#quick", Checkbox).value,
            executor=chosen("executor"),
            device=chosen("device"),
            trials=number("trials", 1),
            seed=number("seed", 0),
        )


class ScoreScreen(ModalScreen[str | None]):
    """`gearlab score RUN ...` from the TUI: the recordings and options, as typed after the run directory."""

    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]
    DEFAULT_CSS = panel_css("ScoreScreen", width=90)

    def __init__(self, run: str, typed: str = ""):
        super().__init__()
        self.run, self.typed = run, typed

    def compose(self) -> ComposeResult:
        with VerticalScroll():
            yield Label(Text(f"gearlab score {self.run}", style="bold"))
            yield Label("recordings and options, as after the run directory (enter scores, escape closes):")
            yield Input(self.typed, placeholder="rec/next_week.csv --key vibration=acc_V", id="score-args")

    def on_mount(self) -> None:
        self.query_one(Input).focus()  # typed into at once

    def on_input_submitted(self, event: Input.Submitted) -> None:
        self.dismiss(event.value.strip() or None)
