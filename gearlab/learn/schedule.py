"""Two-phase scheduling of training units that share a state.

Several units of a protocol start from the same trained state (a repetition's primed network,
its source-only model: learn.protocol.shared_state). The first pending unit that needs a state
not yet on disk makes it in phase 1; every other unit runs in phase 2 and loads it, so no
state is trained twice however many workers run side by side, and a resumed run makes only
the states that are missing.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from pathlib import Path
from typing import TypeVar

Unit = TypeVar("Unit", bound=Hashable)


def two_phases(pending: Sequence[Unit], state_file: Callable[[Unit], Path | None]) -> tuple[list[Unit], list[Unit]]:
    """(phase 1, phase 2) of *pending*: phase 1 holds, for each state file that does not exist
    yet, the first unit needing it; phase 2 everything else, in the given order.
    *state_file(unit)*: the file of the state the unit starts from, or None when it needs none."""
    makers: dict[Path, Unit] = {}
    for unit in pending:
        path = state_file(unit)
        if path is not None and not path.exists():
            makers.setdefault(path, unit)
    first = list(makers.values())
    return first, [unit for unit in pending if unit not in first]


def longest_first(phase: Sequence[Unit], cost: Callable[[Unit], object]) -> list[Unit]:
    """*phase* in decreasing *cost* (any sortable key), ties in the given order. A pool takes its
    units in order, so the short ones fill in behind the long ones instead of one worker idling
    while another ends a long unit handed out last (phm09_chip: a core stood 13-15 s at the end
    of each phase, a joint training started behind a row of short ones)."""
    return sorted(phase, key=cost, reverse=True)  # stable: equal costs keep their order
