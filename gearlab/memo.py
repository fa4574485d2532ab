"""A bounded least-recently-used cache of arrays computed once and shared read-only: the healthy
mesh stiffness of a pair (gearlab.physics.stiffness) and the deterministic rows of a gap search's
source set (gearlab.gap.scoring); what a record gives, keyed by its content (ArraysOf); a run's process keeping
the heap its arrays free (keep_freed_heap). Base layer: imports nothing of gearlab."""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable

import numpy as np


class SharedArrays(OrderedDict):
    """{key: tuple of arrays}, at most *size* entries, the least recently used dropped first. The
    arrays are made read-only when stored: every caller gets the same objects, so none may change
    them in place."""

    def __init__(self, size: int):
        super().__init__()
        self.size = size

    def get_or_make(self, key: Hashable, make: Callable[[], tuple]) -> tuple:
        hit = self.get(key)
        if hit is None:
            hit = make()
            for a in hit:
                a.setflags(write=False)
            self[key] = hit
            if len(self) > self.size:
                self.popitem(last=False)
        else:
            self.move_to_end(key)
        return hit


class ArraysOf(SharedArrays):
    """SharedArrays of what an input array gives, keyed by its content (digest, shape and type) and *extra*,
    safe across threads: the arrays are made outside the lock, so a read that takes seconds holds no other
    thread's up (two threads reading one record at once both make it; the first stored is kept)."""

    def __init__(self, size: int):
        super().__init__(size)
        self.lock = threading.Lock()

    def of(self, data: np.ndarray, extra: Hashable, make: Callable[[], tuple]) -> tuple:
        data = np.ascontiguousarray(data)
        key = (hashlib.blake2b(data, digest_size=20).digest(), data.shape, data.dtype.str, extra)
        with self.lock:
            hit = self.get(key)
            if hit is not None:
                self.move_to_end(key)
        if hit is None:
            made = make()
            with self.lock:
                hit = self.get_or_make(key, lambda: made)
        return hit


def keep_freed_heap() -> None:
    """This process keeps the memory of its freed arrays of up to 32 MB for the next ones (at most 128 MB of it
    idle). glibc's malloc maps an array of a few MB afresh and unmaps it when freed (its own threshold rises only
    until the heap's top is trimmed), so each temporary is new pages the kernel zeroes: a gap fit's features of 80
    revolutions of 4096 points (gap.views.waveform_view) took 1,900 page faults and 12 ms of CPU a call, 4 ms
    kept. Called where a run starts (gearlab.engine) and in each pool worker (gearlab.executors); nothing where
    the C library has no mallopt (macOS, Windows)."""
    import ctypes  # here: only a run's process needs it

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (AttributeError, OSError, TypeError):
        return
    mallopt(_M_MMAP_THRESHOLD, 32 << 20)
    mallopt(_M_TRIM_THRESHOLD, 128 << 20)


_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # mallopt's parameters (glibc's malloc.h)
