"""What a slow box costs to simulate, and the turns a unit's first steadiness check runs.

A unit's steady response is found by simulating whole periods of the train's cycle (builder.steady_response):
a first look of FIRST_LOOK periods, then four times as many until the last two agree. The integration rate is
the source's fs (200 kHz), not lowered for a slow box: at 28.4 kHz (10 steps in the stiffest mode's 2.84 kHz
period) a conveyor's healthy lines near its 1.1 kHz resonance moved by up to 30 % and 0.5 rad (35 % of the RMS).
So the steps a turn grow as the speed falls: a 45/119 + 28/123 conveyor at 0.743 Hz takes 269,000 steps an input
turn, and damage on its intermediate pinion repeats only every 119 turns. Its first look, 8 periods (952 turns),
was 254 M steps: 117 s a simulation on a shared core, 85 of them; the start-up transient dies in 23 turns. Where
the first look passes SLOW_STEPS it is cut to the fewest periods that hold the settle and the two compared: 3 for
the conveyor, 95 M steps, 56 s, its rows the same to 2e-10 of their peak."""

from __future__ import annotations

import math

from .placement import mesh_cycle_of

FIRST_LOOK = 8  # periods of the train's cycle a unit's first steadiness check simulates
SLOW_STEPS = 1 << 26  # steps of a first look over which a box is slow: fewer periods, and said up front
STEP_S = 0.42e-6  # seconds a step of a two-stage model takes on one core (measured: 1.6 M steps of the conveyor)


def first_blocks(per_rev: int, period: int, cycle: int, settle) -> int:
    """The periods of *cycle* input turns a unit whose damage repeats every *period* turns first simulates
    (*per_rev* steps a turn): FIRST_LOOK, or 3 where the cycle is a later mesh's (its start-up in the first);
    where they pass SLOW_STEPS, the fewest past the start-up's *settle*() input turns plus the two compared."""
    blocks = FIRST_LOOK if cycle == period else 3
    if blocks * cycle * per_rev <= SLOW_STEPS:
        return blocks
    return min(blocks, max(3, 2 + math.ceil(settle() / cycle)))


def next_blocks(blocks: int, period: int, cycle: int, settle, most: int) -> int:
    """The periods of *cycle* input turns the look after a look of *blocks* that was not steady simulates (at most
    *most* for a later mesh's cycle): four times as many; after a later mesh's first look of 3, the fewest past the
    start-up's *settle*() input turns plus the two compared. A short cycle's 3 end before its start-up has died away
    (21/63 + 18/54 + 15/45: a 3-turn cycle, a 15-turn settle): it went on to 12 cycles, 36 turns, now to 7, 21 (a
    longer look continues the shorter's integration, Simulator.tail: 21 turns integrated, not 36)."""
    if cycle == period:
        return 4 * blocks
    if blocks == 3:
        return min(most, max(4, 2 + math.ceil(settle() / cycle)))
    return most


def cost(fs: float, speed: float, pairs, periods, units: int | None, settle) -> str:
    """The up-front cost of a dataset's *units* simulations (None: not yet counted, gearlab validate) at *fs* (Hz)
    and *speed* (Hz), its longest unit's first look (the damage of *periods* input turns, the train's gear *pairs*;
    *settle* as first_blocks'), '' where that look is under SLOW_STEPS."""
    per_rev, mesh = round(fs / speed), mesh_cycle_of(pairs)
    period = max(periods, key=lambda p: math.lcm(p, mesh), default=1)
    cycle = math.lcm(period, mesh)
    turns = cycle * first_blocks(per_rev, period, cycle, settle)
    steps = turns * per_rev
    if steps <= SLOW_STEPS:
        return ""
    each = steps * STEP_S / 60
    return (
        f"; a slow box: each up to {turns} input turns at {fs / 1e3:.4g} kHz, {steps / 1e6:.0f} M steps, about "
        f"{each:.0f} min on one core ({f'{units * each / 60:.1f} h for {units}: ' if units else ''}fewer fault "
        "intensities or teeth, or more workers, cut it)"
    )
