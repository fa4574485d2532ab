"""Panels of the gearlab TUI that open over the main screen: the key list (`?`) and the
run-with-options form (`f`). Escape closes either."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Button, Checkbox, DataTable, Input, Label, Select, Static

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


class KeysScreen(ModalScreen):
    """Every key binding of the app, those the footer leaves out included."""

    BINDINGS = [Binding("escape,question_mark,q", "dismiss", "Close")]
    DEFAULT_CSS = """
    KeysScreen { align: center middle; }
    KeysScreen > Vertical { width: 64; max-width: 95%; height: auto; max-height: 90%;
                            border: thick $primary; background: $surface; padding: 0 1; }
    KeysScreen DataTable { height: auto; max-height: 20; }
    """

    def __init__(self, bindings: Sequence[Binding]):
        super().__init__()
        self.bindings = bindings

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Label(Text("keys (escape closes; ctrl+p: command palette)", style="bold"))
            yield DataTable(id="keys", cursor_type="none", show_header=False)

    def on_mount(self) -> None:
        table = self.query_one("#keys", DataTable)
        table.add_columns("key", "what it does")
        for b in self.bindings:
            table.add_row(Text(b.key_display or b.key), b.tooltip or b.description)
        table.add_row("↑ ↓ enter", "move in the tree; enter opens a scenario or a run")


def _choices(key: str) -> list[tuple[str, str]]:
    """The values an [execution] key takes, read from its own check (one_of), so that the
    form never offers what the scenario schema would refuse."""
    check = EXECUTION_TABLE.keys[key].check
    values = getattr(check, "choices", None) or ()
    return [(v, v) for v in values]


class RunOptionsScreen(ModalScreen[RunOptions | None]):
    """A small form: quick, executor, device, and a benchmark's trials and seed."""

    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]
    DEFAULT_CSS = """
    RunOptionsScreen { align: center middle; }
    RunOptionsScreen > VerticalScroll { width: 60; max-width: 95%; height: auto; max-height: 95%;
                                        border: thick $primary; background: $surface; padding: 0 1; }
    RunOptionsScreen Label { margin-top: 1; }
    RunOptionsScreen Horizontal { height: auto; margin-top: 1; }
    #problem { color: $error; height: auto; }
    """

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
