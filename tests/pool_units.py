"""The functions tests map on a local pool's workers. A worker imports the module of the function it
is sent: this one imports nothing heavy (a test module imports pytest, half a second of CPU at each
worker's start, and test_executors' pools start theirs again and again)."""

import os
import sys
import time
from pathlib import Path

from gearlab.errors import GearlabInputError
from gearlab.executors import unshared


def square(x: int) -> int:
    return x * x


def waited_for(path: Path, pattern: str) -> bool:
    """Whether a file matching *pattern* came into *path* within a minute (a hung test's bound)."""
    deadline = time.monotonic() + 60.0
    while not any(path.glob(pattern)):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def first_is_slow(marks: Path | None, x: int) -> int:
    """Item 0 finishes after another one: on_done sees the finishing order, the results keep the input
    order. With *marks* (two workers or more) item 0 runs until the caller's on_done has heard of
    another item (it marks that in *marks*), not for a fixed time that a loaded machine's second
    worker may not start within, nor until another item merely started (its result may come after
    item 0's). A minute at most."""
    if x == 0 and marks is not None:
        waited_for(marks, "heard-*")
    return x * x


def refuse_three(x: int) -> int:
    if x == 3:
        raise GearlabInputError("item 3 is not allowed")
    return x


def divide(x: int) -> float:
    return 1 / x


def read_shared(item) -> tuple[int, float]:
    """What a unit reads of its Shared arrays."""
    i, shared = item
    X, rows = unshared(shared)
    return i, float(X.sum()) + float(rows["r"].sum())


def sum_then_spoil(item) -> tuple[int, float]:
    """What a unit reads of its Shared arrays; then it writes over them (no other unit may see that;
    on Ray its arrays are read-only)."""
    seen = read_shared(item)
    X, rows = unshared(item[1])
    X[:] = -1.0
    rows["r"][:] = -1
    return seen


def both_workers_took_one(marks: Path) -> None:
    """Mark this worker's process in *marks*, then wait until two workers have (a minute at most):
    an item of a two-worker map that calls this runs on each worker, however the machine schedules."""
    (marks / str(os.getpid())).touch()
    deadline = time.monotonic() + 60.0
    while len(list(marks.iterdir())) < 2 and time.monotonic() < deadline:
        time.sleep(0.01)


def module_loaded(marks: Path, name: str) -> bool:
    """Whether *name* was loaded in this worker, once both workers took an item: one worker cannot
    take every item while the other still runs its warm-ups (a worker that took both, then was
    descheduled)."""
    both_workers_took_one(marks)
    return name in sys.modules


LOADED_IN = os.getpid()  # the process that imported this module: a worker, or the forkserver it was forked from


def loaded_in(marks: Path, x: int) -> tuple[int, int, int]:
    """(the process that imported this module, this worker's, its parent's: the forkserver), once both
    workers took an item."""
    both_workers_took_one(marks)
    return LOADED_IN, os.getpid(), os.getppid()


def mark_then_wait(task):
    """Unit 0 fails once another unit runs beside it; the others mark that they started (with their
    process id, whole once seen: unit 0's failure stops them at once, maybe inside the write) and run
    until stopped: a minute, never told to end, then they mark that they ended."""
    folder, i = task
    if i == 0:
        waited_for(Path(folder), "started-*")
        raise GearlabInputError("unit 0 is bad")
    (Path(folder) / f"writing-{i}").write_text(str(os.getpid()))
    (Path(folder) / f"writing-{i}").rename(Path(folder) / f"started-{i}")
    waited_for(Path(folder), "never")
    (Path(folder) / f"ended-{i}").touch()
    return i


def worker_pid(marks: Path, x: int) -> int:
    both_workers_took_one(marks)
    return os.getpid()


def evaluations(n: int) -> int:
    """A gap fit's stand-in (test_progress_steps): n score evaluations."""
    from gearlab.gap.tally import counted

    for _ in range(n):
        counted()
    return n
