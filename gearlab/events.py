"""Progress events: what a run tells its front-end (the CLI's bars, the TUI's widgets).

A run sends :class:`Event` objects to one callback (an :data:`EventSink`); a unit running in
another process or on a cluster node reports through a small file (:class:`UnitProgress`)
that the run engine watches (gearlab.engine.ProgressWatcher). Low level: the data builder,
the gap diagnosis and the learners send events without knowing the engine.
"""

from __future__ import annotations

import functools
import json
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import asdict, dataclass
from pathlib import Path

from .confined import Confined


@dataclass(frozen=True)
class Event:
    """A progress event. kind: 'run' (the run directory is ready; `message` is its path),
    'stage' (a stage starts), 'advance' (units done within the stage), 'record' (a unit
    finished; `record` holds it), 'unit' (a unit in progress says how far it is in `message`,
    `stage` names it; an empty message: it ended), 'log' (a line for people).

    `gearlab run --events` writes them as JSON lines: that is how the TUI follows a run."""

    kind: str
    stage: str = ""
    done: int = 0
    total: int = 0
    message: str = ""
    record: dict | None = None

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, line: str) -> Event:
        data = json.loads(line)
        return cls(**{k: data[k] for k in ("kind", "stage", "done", "total", "message", "record") if k in data})


EventSink = Callable[[Event], None]


def ignore_events(_: Event) -> None:
    pass


PROGRESS = "progress"  # the run directory's folder of units in progress

_said: ContextVar[Callable[[str], None] | None] = ContextVar("said", default=None)


def unit_says(text: str) -> None:
    """What the unit in progress is doing, for its progress line, when one listens (saying)."""
    tell = _said.get()
    if tell is not None:
        tell(text)


def stages_to_unit(event: Event) -> None:
    """An EventSink for work inside a unit (a benchmark trial's diagnosis, minutes of it): each
    stage it starts becomes the unit's progress line, when one listens."""
    if event.kind == "stage":
        unit_says(event.message or event.stage)


@contextmanager
def saying(progress: Callable[[str], None]) -> Iterator[None]:
    """unit_says and stages_to_unit reach *progress* (a UnitProgress) while the unit runs."""
    token = _said.set(progress)
    try:
        yield
    finally:
        _said.reset(token)


def told_unit(where: Callable) -> Callable:
    """Decorates a unit's function: while it runs, unit_says (and a diagnosis's stages_to_unit)
    reach its progress line; where(task) gives (run directory, unit name)."""

    def decorate(work: Callable) -> Callable:
        @functools.wraps(work)
        def told(task):
            with UnitProgress(*where(task)) as progress, saying(progress):
                return work(task)

        return told

    return decorate


REPORT = "report"  # the stage of a run's last step: its figures and report.html
_figures: ContextVar[Callable[[str], None] | None] = ContextVar("figures", default=None)


def figure_written(name: str) -> None:
    """Called by gearlab.plots.save for each figure it writes: counted by the run in progress, if any."""
    tell = _figures.get()
    if tell is not None:
        tell(name)


@contextmanager
def telling_figures(on_event: EventSink) -> Iterator[Callable[[], None]]:
    """While a run's kind runs and its report is written: a 'report' stage, started by the first
    figure, that counts the figures drawn (a run's end drew its figures for seconds, a detection
    run's a dozen, with no sign of life: issue 41). Yields the call that ends the stage once
    report.html is written."""
    drawn: list[str] = []

    def tell(name: str) -> None:
        if not drawn:
            on_event(Event("stage", stage=REPORT, message="figures and report.html"))
        drawn.append(name)
        on_event(Event("advance", stage=REPORT, done=len(drawn)))

    def finish() -> None:
        if not drawn:
            on_event(Event("stage", stage=REPORT, total=1, message="report.html"))
        n = max(len(drawn), 1)
        on_event(Event("advance", stage=REPORT, done=n, total=n))

    token = _figures.set(tell)
    try:
        yield finish
    finally:
        _figures.reset(token)


class UnitProgress:
    """What a unit in progress reports ('epoch 120, validation accuracy 88 %'), written to a
    small file in the run directory's progress/ folder, from whichever process or cluster node
    runs the unit; the engine watches the folder (ProgressWatcher) and sends 'unit' events.
    Use as a context manager: the file goes when the unit ends."""

    def __init__(self, run_path: Path, unit: str, every: float = 0.5):
        self.file = Confined(run_path, (PROGRESS, unit.replace("/", "__") + ".txt"))
        self.every, self.last = every, -every

    @property
    def path(self) -> Path:
        return self.file.path

    def __call__(self, text: str) -> None:
        if time.monotonic() - self.last >= self.every:  # a few writes a second at most
            self.file.write(text)
            self.last = time.monotonic()

    def __enter__(self) -> UnitProgress:
        return self

    def __exit__(self, *exc) -> None:
        self.file.unlink()
