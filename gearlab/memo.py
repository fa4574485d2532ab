"""A bounded least-recently-used cache of arrays computed once and shared read-only: the healthy
mesh stiffness of a pair (gearlab.physics.stiffness) and the deterministic rows of a gap search's
source set (gearlab.gap.scoring). Base layer: imports nothing of gearlab."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable


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
