"""The score evaluations of a diagnosis stage's fits, counted while they run, in whichever process
runs them (issue 41: a fit takes 14-27 s on a busy machine, and the stage's line said 'fitting
(12 s)' with no sign of how far the fits had come).

Every score evaluation (:meth:`gearlab.gap.scoring.Scorer.score`) calls :func:`counted`. A fit run
through :class:`Tallied` writes its count, at most every WRITE_EVERY seconds and when it ends, to
a small file of its own in a folder the stage made; the stage's line sums the folder
(:func:`evaluations_in`). The files are what crosses from a worker process to the run's process:
the local pool's workers and an in-process fit write the same way; a fit on another machine (a Ray
cluster) cannot reach the folder and is not counted (the line says the time alone).

A diagnosis's total (:func:`so_far`, read at its start and end) is its own process's evaluations
outside the fits and, as each batch of fits ends (:func:`fits_ended`), the sum of its folder.
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Callable
from pathlib import Path

from ..files import atomic_write

WRITE_EVERY = 0.5  # s between two writes of one fit's count


class _Count:
    """This process's fit in progress: its evaluations, and where they are written (None: nowhere);
    the evaluations made outside a fit, and those of the fits that ended (summed from their folders)."""

    def __init__(self):
        self.n, self.file, self.written = 0, None, 0.0
        self.inside, self.outside, self.fitted = False, 0, 0

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
    if not _count.inside:
        _count.outside += 1
        return
    _count.n += 1
    if _count.file is not None and time.monotonic() - _count.written >= WRITE_EVERY:
        _count.write()


class Tallied:
    """*work* (an executor's unit: a picklable top-level function) that writes its score evaluations
    to a file of its own in *folder* as it runs. Picklable, so that a worker process runs it."""

    def __init__(self, work: Callable, folder: str):
        self.work, self.folder = work, folder

    def __call__(self, task):
        _count.n, _count.file, _count.inside = 0, Path(self.folder) / f"{uuid.uuid4().hex}.n", True
        try:
            return self.work(task)
        finally:
            _count.write()
            _count.file, _count.inside = None, False


def evaluations_in(folder: str) -> int:
    """The score evaluations written to *folder* so far, by the fits running and the fits done."""
    total = 0
    for file in Path(folder).glob("*.n"):
        try:
            total += int(file.read_text())
        except (OSError, ValueError):  # a file replaced while read: counted at the next look
            pass
    return total


def fits_ended(folder: str) -> int:
    """A batch of fits ended: their evaluations (*folder*'s sum) join this process's total."""
    n = evaluations_in(folder)
    _count.fitted += n
    return n


def so_far() -> int:
    """This process's score evaluations so far: outside the fits, and the fits' that ended
    (:func:`fits_ended`). A diagnosis's total is the difference between its end and its start."""
    return _count.outside + _count.fitted
