"""The score evaluations of a diagnosis stage's fits, counted while they run, in whichever process
runs them (issue 41: a fit takes 14-27 s on a busy machine, and the stage's line said 'fitting
(12 s)' with no sign of how far the fits had come).

Every score evaluation (:meth:`gearlab.gap.scoring.Scorer.score`) calls :func:`counted`. A fit run
through :class:`Tallied` reports its count, at most every WRITE_EVERY seconds and when it ends, to
the executor's counts (gearlab.executors.Counts: files on this machine, an actor on Ray, so that a
fit on another node of a cluster is counted too), whose total the stage's line says; and returns
its count with its result, which :func:`fits_ended` adds to the total of the process that mapped
the fits.

A diagnosis's total (:func:`so_far`, read at its start and end) is its own process's evaluations
outside the fits and, as each batch of fits ends (:func:`fits_ended`), the counts they returned.
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Callable

from ..executors import Counts

WRITE_EVERY = 0.5  # s between two reports of one fit's count


class _Count:
    """This process's fit in progress: its evaluations, where they are reported (None: nowhere) and
    under which key; the evaluations made outside a fit, and those of the fits that ended."""

    def __init__(self):
        self.n, self.counts, self.key, self.written = 0, None, "", 0.0
        self.inside, self.outside, self.fitted = False, 0, 0

    def write(self) -> None:
        if self.counts is None:
            return
        try:
            self.counts.report(self.key, self.n)
        except OSError:  # the counts cannot be reached from here: the result still carries the count
            self.counts = None
        self.written = time.monotonic()


_count = _Count()


def counted() -> None:
    """One score evaluation of the fit in progress (nothing is reported outside :class:`Tallied`)."""
    if not _count.inside:
        _count.outside += 1
        return
    _count.n += 1
    if _count.counts is not None and time.monotonic() - _count.written >= WRITE_EVERY:
        _count.write()


class Tallied:
    """*work* (an executor's unit: a picklable top-level function) that reports its score evaluations
    to *counts* as it runs, and returns (its result, its evaluations). Picklable, so that a worker
    process or a Ray task runs it."""

    def __init__(self, work: Callable, counts: Counts):
        self.work, self.counts = work, counts

    def __call__(self, task) -> tuple:
        _count.n, _count.counts, _count.key, _count.inside = 0, self.counts, uuid.uuid4().hex, True
        try:
            return self.work(task), _count.n
        finally:
            _count.write()
            _count.counts, _count.inside = None, False


def fits_ended(results: list[tuple]) -> list:
    """A batch of fits ended (*results*: what each :class:`Tallied` returned): their evaluations join
    this process's total; their results."""
    _count.fitted += sum(n for _, n in results)
    return [result for result, _ in results]


def so_far() -> int:
    """This process's score evaluations so far: outside the fits, and the fits' that ended
    (:func:`fits_ended`). A diagnosis's total is the difference between its end and its start."""
    return _count.outside + _count.fitted


# The rate behind a limited stage's ETA: the evaluations of the last RATE_WINDOW_S seconds. Its fits
# end one by one, and the last (a three-stage box's casing profile) runs alone at a third to a half of
# the rate all of them made: over the whole stage, the rate said '0:34' left for 5 minutes.
RATE_WINDOW_S = 15.0


class Left:
    """A stage whose fits make at most *most* score evaluations (--quick's profile): its line, 'n of at
    most M evaluations, r/s, ETA ≤ m:ss', the time left read off the recent rate, at most what the
    remaining evaluations take at it (a profile may end before its evaluations run out)."""

    def __init__(self, most: int, now: float):
        self.most = int(most)
        self.seen: list[tuple[float, int]] = [(now, 0)]

    def rate(self, n: int, now: float) -> float:
        """Evaluations a second over the last RATE_WINDOW_S seconds (*n* made by *now*)."""
        self.seen.append((now, n))
        while len(self.seen) > 2 and now - self.seen[1][0] >= RATE_WINDOW_S:
            self.seen.pop(0)
        t0, n0 = self.seen[0]
        return (n - n0) / max(now - t0, 1e-9)

    def left(self, n: int, now: float) -> float | None:
        """Seconds left at the recent rate, None before the first evaluation."""
        rate = self.rate(n, now)
        return max(self.most - n, 0) / rate if rate > 0 else None

    def line(self, n: int, now: float) -> str:
        from ..events import clock

        text = f"fitting: {n} of at most {self.most} evaluations"
        rate = self.rate(n, now)
        if rate <= 0:
            return text
        return f"{text}, {rate:.1f}/s, ETA ≤ {clock(max(self.most - n, 0) / rate)}"
