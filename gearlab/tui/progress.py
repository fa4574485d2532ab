"""The Progress tab's stages: a line per stage with a bar, its counts, rate and ETA.

Drawn from the run's 'stage' and 'advance' events with the terminal's own Pace and clock
(gearlab.events, those gearlab.terminal draws with), so the TUI and `gearlab run` say the
same numbers. Nothing here moves by itself: the clock ticks once a second while a run is in
progress and stops with it, and a stage that cannot count its steps says so in words instead
of drawing an animated bar.
"""

from __future__ import annotations

import time

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import Static

from ..events import Pace, clock  # not through gearlab.terminal: its rich.progress is not needed here

BAR = 24  # cells of a stage's bar


class StageBar(Static):
    """One stage: its label, then the bar, 'done/total (percent)', the rate and the ETA."""

    DEFAULT_CSS = "StageBar { height: auto; padding: 0 1; }"

    def __init__(self, label: str, total: int, done: int = 0, **kwargs):
        super().__init__(**kwargs)
        self.label, self.total, self.done = label, total, done
        self.pace = Pace(done)
        self.state = "running"  # then 'done' or 'stopped' (the run ended before the stage did)
        self.ended: float | None = None

    def restart(self, label: str, total: int, done: int = 0) -> None:
        self.label, self.total, self.done = label, total, done
        self.pace, self.state, self.ended = Pace(done), "running", None
        self.refresh(layout=True)

    def advance(self, done: int, total: int) -> None:
        self.total = total
        self.done = done
        self.pace.update(done)
        if total and done >= total and self.state == "running":
            self.state, self.ended = "done", time.monotonic()
        self.refresh(layout=True)

    def stop(self) -> None:
        """The run ended: a stage still running stopped where it was."""
        if self.state == "running":
            self.state, self.ended = "stopped", time.monotonic()
            self.refresh(layout=True)

    def status(self, now: float | None = None) -> str:
        """The words beside the bar: '3/12 (25 %)  0.5/s  elapsed 0:06  ETA 0:18'."""
        now = time.monotonic() if now is None else now
        elapsed = clock((self.ended or now) - self.pace.start)
        count = f"{self.done}/{self.total} ({100 * self.done // self.total} %)" if self.total else f"{self.done} steps"
        if self.state == "done":
            return f"{count}  done in {elapsed}"
        if self.state == "stopped":
            return f"{count}  stopped after {elapsed}"
        if not self.total:  # nothing to count against: said, not animated
            return f"working, its steps not counted  elapsed {elapsed}"
        rate = self.pace.rate_text(now)
        if not rate:
            return f"{count}  elapsed {elapsed}  ETA after the first step"
        return f"{count}  {rate}  elapsed {elapsed}  ETA {clock(self.pace.left(self.total, now))}"

    def render(self) -> Text:
        text = Text(self.label + "\n", style="bold" if self.state == "running" else "")
        if self.total:
            filled = min(BAR, round(BAR * self.done / self.total))
            color = {"done": "green", "stopped": "yellow"}.get(self.state, "cyan")
            text.append("━" * filled, style=color)
            text.append("─" * (BAR - filled), style="grey42")  # thinner: told apart without colour
            text.append("  ")
        text.append(self.status(), style={"done": "green", "stopped": "yellow"}.get(self.state, ""))
        return text


def stage_id(stage: str) -> str:
    """A widget id for a stage name: any name ('gap before', 'gap round 2', 'trial 3/40')
    maps to letters, digits, '-' and '_' only, and two names never share an id (the hex
    code of every other character is spelled out)."""
    return "".join(c if c.isascii() and (c.isalnum() or c == "_") else f"-{ord(c):x}-" for c in stage)


class Stages(Vertical):
    """A StageBar per stage of a run (datasets, simulate, priming, runs, ...); `start` and
    `stop` bracket a run, and the clock ticks only between them."""

    DEFAULT_CSS = "Stages { height: auto; }"

    def compose(self) -> ComposeResult:
        return iter(())

    ticking = False  # a run is in progress: the clock refreshes the running stages

    def on_mount(self) -> None:
        self.clock = self.set_interval(1.0, self._tick, pause=True)

    def _tick(self) -> None:
        for bar in self.query(StageBar):
            if bar.state == "running":
                bar.refresh(layout=True)

    def reset(self) -> None:
        """A run starts: no stages yet, and the clock runs."""
        self.remove_children()
        self.clock.resume()
        self.ticking = True

    def stop(self) -> None:
        """The run ended (finished, cancelled or failed): every bar holds still."""
        self.clock.pause()
        self.ticking = False
        for bar in self.query(StageBar):
            bar.stop()

    def start(self, stage: str, message: str, total: int, done: int = 0) -> None:
        bar = self._bar(stage)
        if bar is None:
            self.mount(StageBar(message or stage, total, done, id=f"bar-{stage_id(stage)}"))
        else:
            bar.restart(message or stage, total, done)

    def advance(self, stage: str, done: int, total: int) -> None:
        bar = self._bar(stage)
        if bar is not None:
            bar.advance(done, total)

    def _bar(self, stage: str) -> StageBar | None:
        found = self.query(f"#bar-{stage_id(stage)}")
        return found.first(StageBar) if found else None
