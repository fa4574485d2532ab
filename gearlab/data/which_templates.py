"""The simulated events gearlab.signals.which_template compares a record's with: per gear of a
two-gear shaft, the synchronous mean of a tooth fault on it less the healthy one, simulated from the
gearbox description at the record's speed (noise-free; the description's load: the record's is not
known). Simulated once per (description, speed, rate, fault) in this process (functools cache);
each template is read at the caller's layout."""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

KINDS = ("chip", "spall", "crack")  # the event's shape differs by kind: the best fit of the three counts
STEP = 16  # a mid ladder step: the shape, not the size, is compared
PERIODS = 3  # grand periods simulated (noise-free: the mean of a few is exact)


def placement_word(gear) -> str:
    """A localise.Gear as a fault placement's 'gear' (e.g. 'idler pinion', 'intermediate gear')."""
    return f"{gear.shaft} {'pinion' if gear.role == 'pinion' else 'gear'}"


@lru_cache(maxsize=64)
def _revolutions(gearbox, speed_hz: float, fs: float, sim_fs, revolutions: int, fault) -> tuple[np.ndarray, int]:
    from ..signals import cut_revolutions
    from .simulated import simulated_record

    faults = [] if fault is None else [{"name": fault[1], "gear": fault[0], "tooth": 1, "step": STEP}]
    extra = {} if gearbox is None else {"gearbox": gearbox, "sim_fs": sim_fs}
    rec = simulated_record(faults, speed_hz=speed_hz, revolutions=revolutions + 2, snr_db=None, seed=7, fs=fs, **extra)
    cut = cut_revolutions(rec.vibration, rec.fs, pulses=rec.tacho, transient="none")
    return cut.revolutions, (math.floor(rec.start) + 1) % rec.period if rec.period > 1 else 0


def simulated_templates(table, speed_hz: float, fs: float, *, gearbox: str | None = None, sim_fs: float | None = None):
    """A function of a localisation layout giving {"healthy": the healthy mean, "gears": {gear name:
    [template per fault kind]}} for every gear on a two-gear shaft of *table* (localise's
    *templates*). *gearbox*: the description (None: the PHM 2009 rig's preset)."""
    from ..signals import localise as L

    gears = [g for on in L.gears_of(table).values() if len(on) == 2 for g in on]
    period = int(table.train_period)
    revs = max(PERIODS * period, 12)

    def at(lay) -> dict:
        def mean(fault):
            r, first = _revolutions(gearbox, float(speed_hz), float(fs), sim_fs, revs, fault)
            if lay.mode == "grand":
                r = r[: (r.shape[0] // period) * period]
            return L.content(r, lay, first).mean

        healthy = mean(None)
        return {
            "healthy": healthy,
            "gears": {g.name: [mean((placement_word(g), k)) - healthy for k in KINDS] for g in gears},
        }

    return at
