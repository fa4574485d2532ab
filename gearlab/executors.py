"""Where units of work run: in this process, or in a local process pool (default: all cores).

An executor maps a picklable top-level function over a list of items and returns the
results in input order, reporting each finished item to an optional callback, so the
results never depend on the order in which workers finish.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed

from .errors import GearlabInputError

EXECUTORS = ("local",)


class LocalExecutor:
    def __init__(self, workers: int | None = None):
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise GearlabInputError(f"workers must be a whole number >= 1, got {workers!r}")
        self.workers = workers or os.cpu_count() or 1

    def map(self, fn: Callable, items: Sequence, on_done: Callable[[int, object], None] | None = None) -> list:
        items = list(items)
        results: list = [None] * len(items)
        if self.workers == 1 or len(items) <= 1:
            for i, item in enumerate(items):
                results[i] = fn(item)
                if on_done:
                    on_done(i, results[i])
            return results
        # forkserver: children start from a clean process (no inherited threads from torch or BLAS).
        context = multiprocessing.get_context("forkserver" if os.name == "posix" else "spawn")
        with ProcessPoolExecutor(max_workers=min(self.workers, len(items)), mp_context=context) as pool:
            futures = {pool.submit(fn, item): i for i, item in enumerate(items)}
            for future in as_completed(futures):
                i = futures[future]
                results[i] = future.result()
                if on_done:
                    on_done(i, results[i])
        return results


def make_executor(name: str = "local", workers: int | None = None) -> LocalExecutor:
    if name != "local":
        raise GearlabInputError(f"unknown executor '{name}'; known: {', '.join(EXECUTORS)}")
    return LocalExecutor(workers)
