"""Progress events: what a run tells its front-end (the CLI's bars, the TUI's widgets).

A run sends :class:`Event` objects to one callback (an :data:`EventSink`); a unit running in
another process reports through a small file (:class:`UnitProgress`) that the run engine
watches (gearlab.engine.ProgressWatcher), a unit on a Ray cluster's node through the board its
executor gives it (:func:`units_report_to`: the nodes share no disk). Low level: the data builder,
the gap diagnosis and the learners send events without knowing the engine.
"""

from __future__ import annotations

import contextvars
import functools
import json
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import asdict, dataclass
from pathlib import Path

from .confined import Confined
from .errors import GearlabInputError


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


def clock(seconds: float | None) -> str:
    """1:02:03, 2:03 or 0:05; '-:--' when unknown."""
    if seconds is None or seconds != seconds or seconds < 0:
        return "-:--"
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, s = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{s:02d}" if hours else f"{minutes}:{s:02d}"


class Pace:
    """Rate and time left of a stage from its counts: the steps done since the stage was first
    seen (a resumed run starts with some done), over the time since then."""

    def __init__(self, done: int = 0, now: float | None = None):
        self.start = time.monotonic() if now is None else now
        self.done0 = done
        self.done = done

    def update(self, done: int) -> None:
        if done < self.done0:  # counted afresh
            self.done0 = done
        self.done = done

    def rate(self, now: float | None = None) -> float | None:
        """Steps a second, None before the first step."""
        now = time.monotonic() if now is None else now
        steps = self.done - self.done0
        return steps / max(now - self.start, 1e-9) if steps > 0 else None

    def left(self, total: int | None, now: float | None = None) -> float | None:
        rate = self.rate(now)
        if not total or rate is None:
            return None
        return max(total - self.done, 0) / rate

    def rate_text(self, now: float | None = None) -> str:
        rate = self.rate(now)
        if rate is None:
            return ""
        return f"{rate:.1f}/s" if rate >= 1 else f"{clock(1 / rate)}/step"


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
    stage it starts becomes the unit's progress line, when one listens, and counts there with its
    ETA after the first step ('gap: round 1, fitting 13 effects: 3 of 13, ETA 2:54'), as the
    run's own bars do (issue 41: a trial's line showed the stage's name alone for minutes). What a
    step that cannot count says beside its stage (a 'unit' event of :func:`standing`: the fits'
    score evaluations) follows on the same line, '...: 3 of 13, ETA 2:54; fitting: 577 evaluations,
    5.8/s (99 s)', as it stands under the stage's bar when the run itself diagnoses."""
    stages = _stages.get()
    if stages is None:  # no unit listening
        return
    if event.kind == "stage":
        stages[event.stage] = _Stage(event.message or event.stage, Pace(event.done), event.total)
    elif event.kind not in ("advance", "unit") or event.stage not in stages:
        return
    stage = stages[event.stage]
    if event.kind == "advance":
        stage.pace.update(event.done)
        stage.total = event.total
    elif event.kind == "unit":
        stage.aside = event.message  # empty: the step ended
    unit_says(stage.line(eta=event.kind != "stage"))


@dataclass
class _Stage:
    """A stage of the work inside a unit: its text, its steps (Pace), their total, and what a step
    that cannot count says beside it."""

    text: str
    pace: Pace
    total: int
    aside: str = ""

    def line(self, eta: bool) -> str:
        text, done = self.text, self.pace.done
        if self.total:
            left = self.pace.left(self.total) if eta and done < self.total else None
            text += f": {done} of {self.total}" + ("" if left is None else f", ETA {clock(left)}")
        return f"{text}; {self.aside}" if self.aside else text


_stages: ContextVar[dict[str, _Stage] | None] = ContextVar("stages", default=None)


@contextmanager
def saying(progress: Callable[[str], None]) -> Iterator[None]:
    """unit_says and stages_to_unit reach *progress* (a UnitProgress) while the unit runs."""
    token, stages = _said.set(progress), _stages.set({})
    try:
        yield
    finally:
        _stages.reset(stages)
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
_figures: ContextVar[_Figures | None] = ContextVar("figures", default=None)


class _Figures:
    """The 'report' stage of the run in progress: i of n, n being the figures the kind said it
    would draw (figures_ahead) and report.html; figures drawn unannounced count with no total."""

    def __init__(self, on_event: EventSink):
        self.on_event = on_event
        self.planned = self.drawn = 0
        self.started = False

    @property
    def total(self) -> int:
        """The figures and report.html; 0 (unknown) while no figure was announced."""
        return max(self.planned, self.drawn) + 1 if self.planned else 0

    def _say(self, message: str = "figures and report.html") -> None:
        if not self.started:
            self.started = True
            self.on_event(Event("stage", stage=REPORT, done=self.drawn, total=self.total, message=message))
        else:
            self.on_event(Event("advance", stage=REPORT, done=self.drawn, total=self.total))

    def ahead(self, count: int) -> None:
        self.planned = max(self.planned, self.drawn) + count
        self._say()

    def written(self) -> None:
        self.drawn += 1
        self._say()

    def finish(self) -> None:
        self.planned = self.drawn = max(self.planned, self.drawn)  # a figure announced, not drawn
        if not self.started:
            self._say("figures and report.html" if self.drawn else "report.html")
        n = self.drawn + 1
        self.on_event(Event("advance", stage=REPORT, done=n, total=n))


def report_begins() -> None:
    """Called by a kind before it loads its drawing code (matplotlib: 2-3 s on a busy machine): the
    run in progress (if any) starts its 'report' stage, its total told by figures_ahead."""
    figures = _figures.get()
    if figures is not None and not figures.started:
        figures._say()


def figures_ahead(count: int) -> None:
    """Called by a kind's drawing code before it draws *count* figures: the run in progress (if any)
    starts its 'report' stage, or extends it, so that it counts i of n with an ETA from the first
    figure on (issue 41: a count that grew as the figures came had no total, so no ETA)."""
    figures = _figures.get()
    if figures is not None and count > 0:
        figures.ahead(count)


def figure_written(name: str) -> None:
    """Called by gearlab.plots.save for each figure it writes: counted by the run in progress, if any."""
    figures = _figures.get()
    if figures is not None:
        figures.written()


@contextmanager
def telling_figures(on_event: EventSink) -> Iterator[Callable[[], None]]:
    """While a run's kind runs and its report is written: a 'report' stage that counts the figures
    drawn, i of the figures announced (figures_ahead) and report.html (a run's end drew its figures
    for seconds, a detection run's a dozen, with no sign of life: issue 41). It starts when the kind
    announces its figures, else with the first figure written, else for report.html alone. Yields
    the call that ends the stage once report.html is written."""
    figures = _Figures(on_event)
    token = _figures.set(figures)
    try:
        yield figures.finish
    finally:
        _figures.reset(token)


STANDING_S = 3.0  # a unit's line that stood this long says for how long, each second


class Board:
    """Where units report their lines when not through the run directory's progress/ folder (a Ray
    cluster's nodes share no disk with the driver: gearlab.executors gives its tasks an actor's
    board). *space* tells runs apart: the run directory's path as the unit was given it."""

    def say(self, space: str, unit: str, text: str) -> None:
        raise NotImplementedError

    def end(self, space: str, unit: str) -> None:
        """The unit ended: its line goes (returns once the board holds that, so that a driver that
        learns of the unit's end after this does not still see its line)."""
        raise NotImplementedError


_board: ContextVar[Board | None] = ContextVar("board", default=None)


@contextmanager
def units_report_to(board: Board | None) -> Iterator[None]:
    """The UnitProgress opened inside report to *board* (None: to files, the default)."""
    token = _board.set(board)
    try:
        yield
    finally:
        _board.reset(token)


class UnitProgress:
    """What a unit in progress reports ('epoch 120, validation accuracy 88 %'), written to a
    small file in the run directory's progress/ folder, from whichever process runs the unit;
    the engine watches the folder (ProgressWatcher) and sends 'unit' events. A unit that runs
    where units report to a board (:func:`units_report_to`: a Ray task) says it there instead.
    Use as a context manager: the file (or the board's line) goes when the unit ends.

    While it is open a thread keeps the file current: a report that came within *every* of the
    last write is written when that time is up (it was dropped before, and the line showed an
    older step), and a report that stood STANDING_S says for how long ('starting: importing
    torch (7 s)'), so that a step that cannot count (an import, a first epoch on a busy machine)
    is not silent (issue 41)."""

    def __init__(self, run_path: Path, unit: str, every: float = 0.5):
        self.file = Confined(run_path, (PROGRESS, unit.replace("/", "__") + ".txt"))
        self.board, self.space, self.unit = _board.get(), str(run_path), unit
        self.every, self.last = every, -every
        self.text, self.since, self.shown = "", 0.0, ""
        self.lock = threading.Lock()
        self.closed = threading.Event()
        self.keeper: threading.Thread | None = None

    @property
    def path(self) -> Path:
        return self.file.path

    def __call__(self, text: str) -> None:
        with self.lock:
            if text != self.text:
                self.text, self.since = text, time.monotonic()
            if time.monotonic() - self.last >= self.every:  # a few writes a second at most
                self._write(text)

    def _write(self, text: str) -> None:
        if self.board is None:
            self.file.write(text, durable=False)  # a line of the moment, not a result
        else:
            self.board.say(self.space, self.unit, text)
        self.last, self.shown = time.monotonic(), text

    def _keep(self) -> None:
        while not self.closed.wait(max(self.every, 0.05)):
            with self.lock:
                if self.closed.is_set() or not self.text:
                    continue
                stood = time.monotonic() - self.since
                line = self.text if stood < STANDING_S else f"{self.text} ({stood:.0f} s)"
                if line != self.shown:
                    try:
                        self._write(line)
                    except (OSError, GearlabInputError):  # the unit's own next report says so
                        pass

    def __enter__(self) -> UnitProgress:
        self.keeper = threading.Thread(target=self._keep, daemon=True)
        self.keeper.start()
        return self

    def __exit__(self, *exc) -> None:
        self.closed.set()
        if self.keeper is not None:
            self.keeper.join()
        if self.board is None:
            self.file.unlink()
        elif self.shown:
            self.board.end(self.space, self.unit)


def _next_look(done: threading.Event) -> bool:
    """Wait a second for a standing line's next look; True once its step ended. (The tests step the
    looks themselves, with a clock of their own: a wait of real seconds raced a loaded machine.)"""
    return done.wait(1.0)


@contextmanager
def standing(on_event: EventSink, name: str, text: str | Callable[[], str]) -> Iterator[None]:
    """A step of the run's own process that cannot count (importing torch: 2-5 s on a busy machine) as
    a unit's line under the bars, 'name: text', that says for how long each second once it stood
    STANDING_S, as a unit's own line does (UnitProgress); the line goes when the step ends. *text* may
    be a call, asked again each second: a count the step's own stages cannot give as steps (the gap
    fits' score evaluations, gearlab.gap.tally). An empty text says nothing (no line yet)."""
    done = threading.Event()
    say = text if callable(text) else lambda: text
    said = say()
    shown = bool(said)
    if shown:
        on_event(Event("unit", stage=name, message=said))

    def keep() -> None:
        nonlocal said, shown
        began = time.monotonic()
        while not _next_look(done):
            stood, line = time.monotonic() - began, say()
            if line and stood >= STANDING_S:
                on_event(Event("unit", stage=name, message=f"{line} ({stood:.0f} s)"))
            elif line != said:
                on_event(Event("unit", stage=name, message=line))
            said, shown = line, shown or bool(line)

    # in this context: a unit's stages_to_unit (its ContextVars) hears the thread's lines too
    keeper = threading.Thread(target=contextvars.copy_context().run, args=(keep,), daemon=True)
    keeper.start()
    try:
        yield
    finally:
        done.set()
        keeper.join()
        if shown:  # the line goes
            on_event(Event("unit", stage=name))
