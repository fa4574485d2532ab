"""The score evaluations of a diagnosis stage's fits, counted while they run, in whichever process
runs them (issue 41: a fit takes 14-27 s on a busy machine, and the stage's line said 'fitting
(12 s)' with no sign of how far the fits had come).

Every score evaluation (:meth:`gearlab.gap.scoring.Scorer.score`) calls :func:`counted`. A fit run
through :class:`Tallied` writes its count, at most every WRITE_EVERY seconds and when it ends, to
a small file of its own in a folder the stage made; the stage's line sums the folder
(:func:`evaluations_in`). The files are what crosses from a worker process to the run's process:
the local pool's workers and an in-process fit write the same way; a fit on another machine (a Ray
cluster) cannot reach the folder and is not counted (the line says the time alone).
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Callable
from pathlib import Path

from ..files import atomic_write

WRITE_EVERY = 0.5  # s between two writes of one fit's count


class _Count:
    """This process's fit in progress: its evaluations, and where they are written (None: nowhere)."""

    def __init__(self):
        self.n, self.file, self.written = 0, None, 0.0

    def write(self) -> None:
        if self.file is None:
            return
        try:  # written whole, then renamed: the reader never sees half a number
            atomic_write(self.file, str(self.n))
        except OSError:  # the folder is not reachable from here (another machine): count no more
            self.file = None
        self.written = time.monotonic()


_count = _Count()


def counted() -> None:
    """One score evaluation of the fit in progress (nothing is written outside :class:`Tallied`)."""
    _count.n += 1
    if _count.file is not None and time.monotonic() - _count.written >= WRITE_EVERY:
        _count.write()


class Tallied:
    """*work* (an executor's unit: a picklable top-level function) that writes its score evaluations
    to a file of its own in *folder* as it runs. Picklable, so that a worker process runs it."""

    def __init__(self, work: Callable, folder: str):
        self.work, self.folder = work, folder

    def __call__(self, task):
        _count.n, _count.file = 0, Path(self.folder) / f"{uuid.uuid4().hex}.n"
        try:
            return self.work(task)
        finally:
            _count.write()
            _count.file = None


def evaluations_in(folder: str) -> int:
    """The score evaluations written to *folder* so far, by the fits running and the fits done."""
    total = 0
    for file in Path(folder).glob("*.n"):
        try:
            total += int(file.read_text())
        except (OSError, ValueError):  # a file replaced while read: counted at the next look
            pass
    return total
