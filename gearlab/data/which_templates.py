"""The simulated events gearlab.signals.which_template compares a record's with: per gear of a
two-gear shaft, the synchronous mean of a tooth fault on it less the healthy one, simulated from the
gearbox description at the record's speed (noise-free; the description's load: the record's is not
known), with the effects of the simulator it stands for (a detection scenario's [corrected] one: the
gap diagnosis's fitted structure, which the events' shapes follow). Simulated once per (description,
effects, speed, rate, fault) in this process (functools cache); each template is read at the caller's
layout, and kept for later calls at that layout (which_gear_cache)."""

from __future__ import annotations

import json
import math
from functools import lru_cache

import numpy as np

from ..errors import GearlabInputError

# the event's shape differs by kind: the best fit of the kinds counts. Pits and broken tips are events of their own:
# read against a chip's, spall's and crack's phases only, a 24T pinion's pits stood at cos -0.4..-0.96 at its 1st
# and 3rd mesh harmonics, 25-40 dB clear of the noise (development seed 41, bearings 0.5x and 2x)
KINDS = ("chip", "spall", "crack", "pit", "broken_tip")
STEP = 16  # a mid ladder step: the shape, not the size, is compared
PERIODS = 3  # grand periods simulated (noise-free: the mean of a few is exact)
# turns of the slowest shaft simulated for a layout of per-shaft TSAs (a train whose grand period is
# long: 3 of the 19/58 + 25/67 fan's are 11,658 input turns, 382 MB and 36 s per event; 8 output turns
# are 66, the means within 3e-5 of them)
SHAFT_TURNS = 8
SIM_FS = 60_000.0  # a description's model integrated at least this fast: a logger's rate is too low for stiff modes
SPEED_DIGITS = 3  # a record's speed to 3 significant digits: takes at 30.01 and 30.02 Hz share one simulation


def placement_word(gear) -> str:
    """A localise.Gear as a fault placement's 'gear' (e.g. 'idler pinion', 'intermediate gear')."""
    return f"{gear.shaft} {'pinion' if gear.role == 'pinion' else 'gear'}"


@lru_cache(maxsize=64)
def _revolutions(
    gearbox, speed_hz: float, fs: float, sim_fs, revolutions: int, fault, effects: str = "[]"
) -> tuple[np.ndarray, int]:
    from ..signals import cut_revolutions
    from .simulated import simulated_record

    faults = [] if fault is None else [{"name": fault[1], "gear": fault[0], "tooth": 1, "step": STEP}]
    extra = {} if gearbox is None else {"gearbox": gearbox, "sim_fs": sim_fs}
    extra["effects"] = json.loads(effects)  # a JSON list of effect tables: hashable for the cache
    rec = simulated_record(faults, speed_hz=speed_hz, revolutions=revolutions + 2, snr_db=None, seed=7, fs=fs, **extra)
    cut = cut_revolutions(rec.vibration, rec.fs, pulses=rec.tacho, transient="none")
    return cut.revolutions, (math.floor(rec.start) + 1) % rec.period if rec.period > 1 else 0


def simulated_templates(
    table, speed_hz: float, fs: float, *, gearbox: str | None = None, sim_fs: float | None = None, effects=()
):
    """A function of a localisation layout giving {"healthy": the healthy mean, "gears": {gear name:
    [template per fault kind]}} for every gear on a two-gear shaft of *table* (localise's
    *templates*), or {"not simulated": why}. *gearbox*: the description (None: the PHM 2009 rig's preset);
    *effects*: effect tables ({"name": ..., parameter: SI value}) the records are simulated with."""
    tables = json.dumps(list(effects), sort_keys=True)
    from ..signals import localise as L
    from . import which_gear_cache as C

    gears = [g for on in L.gears_of(table).values() if len(on) == 2 for g in on]
    period = int(table.train_period)
    slowest = min(float(o) for o in table.shaft_orders)

    def at(lay) -> dict:
        # kept between calls (which_gear_cache): an inspect or score of the next take reads them, not simulates
        how = (KINDS, STEP, PERIODS, SHAFT_TURNS)  # what is simulated: a caller's own kinds are another entry
        key = C.key_of("events", C.description_bytes(gearbox), gearbox, speed_hz, fs, sim_fs, tables, table, lay, how)
        if (kept := C.load("events", key)) is not None:
            return C.events_of(kept, len(KINDS))
        made = simulated(lay)
        if "not simulated" not in made:
            C.save("events", key, C.events_arrays(made))
        return made

    def simulated(lay) -> dict:
        # grand periods for a grand-period layout; else a few turns of the slowest shaft
        revs = max(PERIODS * period if lay.mode == "grand" else math.ceil(SHAFT_TURNS / slowest), 12)

        def mean(fault):
            r, first = _revolutions(gearbox, float(speed_hz), float(fs), sim_fs, revs, fault, tables)
            if lay.mode == "grand":
                r = r[: (r.shape[0] // period) * period]
            # noise-free: a fault's difference from the healthy run holds no other shaft's lines to take out
            return L.content(r, lay, first, sweeps=0).mean

        try:
            healthy = mean(None)
        except GearlabInputError as exc:  # e.g. a description without a load to simulate at: the width decides
            return {"not simulated": str(exc)}
        return {
            "healthy": healthy,
            "gears": {g.name: [mean((placement_word(g), k)) - healthy for k in KINDS] for g in gears},
        }

    return at


def two_gear_shafts(table) -> bool:
    """Whether *table* has a shaft carrying two gears (the only shafts the templates tell apart)."""
    from ..signals import localise as L

    return any(len(on) == 2 for on in L.gears_of(table).values())


def simulated_as(description: str) -> str | None:
    """simulated_record's *gearbox* for a description named as a dataset's preset (a reference
    'gearbox:NAME#HASH': simulated as the source simulates it; the rig's model preset 'phm09') or as
    a Gearbox's source (its file); None: the PHM 2009 rig's preset, which the rig's scenarios
    simulate (the built-in description phm09, `--gearbox phm09`, names the same gearbox)."""
    from pathlib import Path

    from ..gearbox import builtin_gearboxes
    from ..gearbox.simulation import PREFIX

    if description.startswith(PREFIX):
        return description.removeprefix(PREFIX).rpartition("#")[0]
    rig = builtin_gearboxes()["phm09"]
    return None if description == "phm09" or Path(description).resolve() == rig.resolve() else description


def effect_tables(effects) -> list[dict]:
    """A DatasetSpec's effects ((name, ((parameter, SI value), ...)), ...) as simulated_record's tables."""
    return [{"name": name, **dict(params)} for name, params in effects]


def record_templates(table, description: str, speed_hz: float, fs: float, effects=()):
    """simulated_templates for a record at *speed_hz* and *fs* of the gearbox *description*
    (simulated_as) with *effects* (effect tables); None where *table* has no two-gear shaft (nothing to
    simulate: the width rule is not needed either). The simulation runs only when localise asks (a
    two-gear shaft flagged)."""
    if not two_gear_shafts(table):
        return None
    speed = float(f"{float(speed_hz):.{SPEED_DIGITS}g}")
    gearbox = simulated_as(description)
    sim_fs = None if gearbox is None else max(float(fs), SIM_FS)
    return simulated_templates(table, speed, float(fs), gearbox=gearbox, sim_fs=sim_fs, effects=effects)
