"""Progress events: what a run tells its front-end (the CLI's bars, the TUI's widgets).

A run sends :class:`Event` objects to one callback (an :data:`EventSink`); a unit running in
another process or on a cluster node reports through a small file (:class:`UnitProgress`)
that the run engine watches (gearlab.engine.ProgressWatcher). Low level: the data builder,
the gap diagnosis and the learners send events without knowing the engine.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
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
