"""Which gear, in the envelope: a tooth strike whose ring's carrier phase wanders from turn to turn.

A damaged tooth may strike once per turn of its shaft and ring a structural resonance: a ring at a fixed frequency
in Hz, while the speed wanders a little and the strike's instant jitters by a fraction of a ring period from turn
to turn. The ring's carrier phase against the shaft's angle then wanders, and every shaft's time-synchronous average
cancels it (signals.localise reads nothing); the non-synchronous check (signals.nonsync) leaves out the envelope's
lines at the shafts' orders, since synchronous lines belong to the shafts. The ring's *envelope* keeps the strike:
its squared magnitude does not depend on the carrier's phase, and the strike comes back at one angle of its shaft
every turn.

So the record less every shaft's synchronous average (signals.nonsync.residual) is turned into its squared envelope
(|analytic signal|², over its mean: a level in units of the residual's own power), read at POINTS a revolution, and
that envelope is localised as a record is (signals.localise): each shaft's synchronous average of it at the orders
ORDERS, each order's excess over the healthy history's in sds of its null spread (signals.evidence), the shafts'
levels by least squares over the order classes in bands of BAND orders, each shaft's threshold the history's own
(the largest left-out z, at least the Gaussian quantile at the false-alarm rate shared among the shafts). A shaft
flagged so is named with its gear where it carries one; a shaft of two gears is named as the shaft (the envelope's
width follows the ring's decay, not the tooth's pitch: signals.which_template's rules do not apply). The tooth is
the envelope peak's angle on the shaft (signals.localise.tooth_index), later than the strike by the ring's decay.

data.which_gear reads it where the synchronous averages name nothing (and read no other shaft near its threshold:
elsewhere): a synchronous fault is named as before.

Everything is numpy: no torch, nothing from the layers above.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import GearlabInputError
from . import localise as L
from . import nonsync as NS
from .fft import analytic, rfft

POINTS = 256  # envelope samples per input revolution (orders up to 128: past ORDERS)
ORDERS = (0.5, 24.0)  # input orders of the envelope read: a strike's envelope lies at its shaft's first orders
BAND = 6.0  # input orders per band of the least squares over the order classes
# The thresholds' Gaussian floor, shared among the shafts: a second search, read where the averages named nothing,
# so a healthy take must hardly ever pass it. Healthy takes of the localisation benchmark's boxes read the envelope's
# shafts at z 0.02 +- 0.94, the largest of 128 takes 3.08, 3 over the averages' floor at 0.01 (2.71; dev seed 53);
# at that floor the benchmark named one of 40 healthy takes and one fault on another shaft (dev seed 52); a strike the
# averages cancel reads z 17-370 at 0.5-1 of the mesh amplitude (tests/jittered_strikes.py)
FALSE_ALARM = 1e-4
# A synchronous change under its threshold leaks into the envelope, and there may read on another shaft (a random
# train's output-gear chip, its average at z 2.4 of 2.71, put the intermediate shaft's envelope at 4.34 over 3.99, dev
# seed 54): the envelope names no shaft where another shaft's average reads over this share of its threshold (at 0.5
# a healthy shaft's average passes it about one take in ten: the jittered 39/61 strikes of tests/jittered_strikes.py
# named 14 -> 10 of 20 at 0.3 of the mesh amplitude; at 0.8 none lost, dev seed 55)
OTHER_SHARE = 0.8
SEEN = "seen in the envelope of the record less every shaft's synchronous average"


def envelope(revolutions: np.ndarray, table) -> np.ndarray:
    """The squared envelope (R', POINTS) over its mean of the record *revolutions* (R, points: consecutive input
    revolutions) less every shaft's synchronous average (nonsync.residual: R' <= R whole revolutions)."""
    revs = np.asarray(revolutions, dtype=np.float64)
    r = NS.residual(revs, table)
    e = np.abs(analytic(r)) ** 2
    if not e.mean() > 0:
        raise GearlabInputError("envelope: no residual left (the record is constant); expected a signal")
    count = r.size // revs.shape[1]
    E = rfft(e / e.mean())[: count * POINTS // 2 + 1]  # low-passed to POINTS / 2 orders
    return np.fft.irfft(E, n=count * POINTS).reshape(count, POINTS) * (POINTS / revs.shape[1])


def history(records: list[np.ndarray], table, **options) -> L.History:
    """The healthy history of the records' envelopes (signals.localise.history at ORDERS; *options*: its first
    revolutions, marks, tacho, pulses, free)."""
    lo, hi = ORDERS
    read = [envelope(r, table) for r in records]
    return L.history(read, table, min_order=lo, max_order=hi, band=BAND, false_alarm=FALSE_ALARM, **options)


def localise(revolutions: np.ndarray, hist: L.History, table, first_revolution: int = 0) -> L.Localisation:
    """The envelope of *revolutions* localised against *hist* (history()): a shaft of two gears named as the shaft."""
    found = L.localise(envelope(revolutions, table), hist, table, first_revolution)
    gears = L.gears_of(table)
    ranking = tuple(
        e if len(e.gears) == 1 else dataclasses.replace(e, gear=L.shaft_label(e.shaft, gears[e.shaft]), which=None)
        for e in found.ranking
    )
    ranking = tuple(dataclasses.replace(e, stage_evidence={}) for e in ranking)
    top = next((e for e in ranking if e.flagged), None)
    named, shaft = (None, None) if top is None else (top.gear, top.shaft)
    return L.Localisation(f"{SEEN}: {found.method}", ranking, named, shaft)


def elsewhere(synchronous: L.Localisation, shaft: str) -> bool:
    """The synchronous averages (*synchronous*, naming nothing) read another shaft than *shaft* over OTHER_SHARE of its
    threshold: the envelope's flag on *shaft* may be that change's leak, and names nothing."""
    return any(e.shaft != shaft and e.z > OTHER_SHARE * e.threshold for e in synchronous.ranking)


def described(found: L.Localisation, synchronous: str) -> dict:
    """*found* (localise()) as data.which_gear returns a localisation, each shaft marked as read in the envelope (its
    call's words: which_template.IN_ENVELOPE), its summary saying so beside the synchronous averages' *synchronous*
    summary."""
    out = found.describe()
    out["shafts"] = [s | {"seen": "envelope"} for s in out["shafts"]]
    out["summary"] = f"{found.summary()}; {SEEN} (the synchronous averages: {synchronous})"
    return out | {"seen": "envelope"}


def state(hist: L.History | None) -> dict:
    """The arrays (History.state) to save the envelope's history *hist* with, each key prefixed; {} for None."""
    return {} if hist is None else {f"envelope_{k}": v for k, v in hist.state().items()}


def restored(arrays: dict, table) -> L.History | None:
    """The envelope's history state() saved in *arrays*; None where none was (a run stored before it was read)."""
    mine = {k.removeprefix("envelope_"): v for k, v in arrays.items() if k.startswith("envelope_")}
    return L.History.restored(mine, table) if mine else None
