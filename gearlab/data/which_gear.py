"""Which gear: the one decision `gearlab inspect --history`, the detection kind and `gearlab score` make.

Each of them reads its records (cut into complete input revolutions, not standardised) and hands
them here as takes: the history read once (history_of: its band of orders, each take's first
revolution counted from the input angle's zero, turned to the first take's tacho mark), and each
record localised against it (which_gear: signals.localise, a two-gear shaft's gear by the
description's simulated events at the record's speed and rate, data.which_templates); where no shaft's average
names a change, the record's envelope is (signals.envelope_sync: a strike whose ring's phase wanders; not where
the flag is the train's products, signals.envelope_train). What a
flag then means to a scenario that watches a gear is the detection kind's (its call); which gear
carries the change is decided here only.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import GearlabInputError
from ..signals import POINTS
from ..signals import envelope_sync as E
from ..signals import envelope_train as TR
from ..signals import localise as L
from ..signals import nonsync as NS
from .chain import Chain
from .which_templates import record_templates


@dataclass(frozen=True)
class Take:
    """One record as localised: its complete input revolutions (R, points) as cut, the first one's number
    counted from the input angle's zero (recordings.CutRecording.first_revolution; any whole number),
    its mean speed, its sampling rate and each revolution's speed (Hz; None where not read: a non-synchronous line
    on a mains harmonic is then not told from a bearing's within the take, signals.nonsync.hum_or_bearing)."""

    revolutions: np.ndarray
    first: int
    speed_hz: float
    fs: float
    speeds: np.ndarray | None = None

    @classmethod
    def of(cls, rec) -> Take:
        """The take of a recordings.CutRecording: its revolutions clear of a followed angle's unsettled ends."""
        part = rec.settled or slice(0, len(rec.revolutions))
        speeds = None if rec.speeds is None else rec.speeds[part]
        return cls(rec.revolutions[part], int(rec.first_revolution) + part.start, float(rec.speed_hz), rec.fs, speeds)


def band(takes: list[Take]) -> float:
    """The highest input order localised: the one every take holds (data.chain.Chain.max_order, where the
    acquisition's anti-alias filter leaves data, as the detection kind reads its conditions), within the
    revolutions' points."""
    return float(min(min(Chain(fs=t.fs, speed=t.speed_hz).max_order for t in takes), 0.45 * POINTS))


def history_of(
    takes: list[Take], table, marks: int = 1, max_order: float | None = None, tacho: str | None = None, pulses: int = 1
) -> L.History:
    """The healthy history *takes* of the gearbox of order table *table* read for localisation, orders up
    to *max_order* (default: band(takes)); *marks*: the tacho's marks per input turn (a take is turned
    to the first take's); *tacho*: the shaft the tacho reads ("": none, a take's zero its first sample, so no
    tooth is fixed across takes; None: not said, the takes share a zero), *pulses*: its marks per turn
    (the tacho's own shaft counts its teeth from its mark). The takes' envelopes are read too (History.envelope:
    signals.envelope_sync), where they hold enough for it."""
    if not takes:
        raise GearlabInputError("no history record to localise against; expected healthy records of the same gearbox")
    period = int(table.train_period)
    shortest = min(len(t.revolutions) for t in takes)
    turns, shaft = NS.slowest_turns(shortest, table)
    if shortest // period < L.MIN_PERIODS and turns < NS.TURNS:  # each shaft's own average, as which_gear reads
        # a take: the history's units (half takes under 4) held too few turns of a slow shaft to be read at all
        raise GearlabInputError(
            f"the history's takes: too short for the which-gear check: {turns:.3g} {shaft}-shaft turns "
            f"({shortest} input revolutions), it needs {NS.TURNS}"
        )
    records = [t.revolutions for t in takes]
    options = {"first_revolutions": [t.first % period for t in takes], "marks": marks, "tacho": tacho or ""}
    options |= {"pulses": pulses, "free": tacho == ""}
    hist = L.history(records, table, max_order=band(takes) if max_order is None else max_order, **options)
    top = band(takes) if all(t.fs and t.speed_hz for t in takes) else max_order  # the demodulation bands' span
    try:  # the takes' envelopes: a strike whose ring's phase wanders, which every synchronous average cancels
        return dataclasses.replace(hist, envelope=E.history(records, table, top=top, **options))
    except GearlabInputError:  # too short for it, or no band of it holds every shaft's orders: the averages alone
        return hist


def events(description: str, effects=()) -> dict:
    """What a two-gear shaft's tooth-fault events are simulated from: the description (a dataset preset
    'gearbox:NAME#HASH', a description file or the rig's 'phm09': which_templates.simulated_as) and
    *effects* (effect tables: a [corrected] simulator's)."""
    return {"preset": description, "effects": list(effects)}


def templates_for(table, made: dict | None, take: Take):
    """The simulated events (events()) for a record at *take*'s speed and rate; None: by the width."""
    if made is None:
        return None
    return record_templates(table, made["preset"], take.speed_hz, take.fs, made["effects"])


def which_gear(take: Take, hist: L.History, table, made: dict | None, envelope: bool = True) -> dict:
    """*take* localised against *hist* (signals.localise.Localisation.describe()): the shafts ranked by
    their z, the gear named first (or None) with its evidence; a two-gear shaft's gear by the events
    *made* simulates (events(); None: by the event's width). A record that cannot be read against the
    history is said so ("not localised: ..."), not fatal; one too short for it carries 'unread' (its slowest
    shaft's turns, that shaft, the turns needed).
    *envelope*: False where the take's non-synchronous check calls (signals.nonsync): a strike at no shaft's order
    lifts the residual's envelope at every order, so the envelope names no shaft (bearing strikes at random orders were
    called a gear's fault first on 13 of 40 fresh takes, the watched input pinion on 4; synchronous calls unchanged)."""
    turns, shaft = NS.slowest_turns(len(take.revolutions), table)
    # each shaft's own average (signals.nonsync), or two grand periods (signals.localise), in turns of the slowest shaft
    lay = hist.layout
    need = NS.TURNS if lay.mode == "shafts" else 2 * round(lay.period * min(map(float, table.shaft_orders)))
    if turns < need - 1e-9:  # unread: a flag on it cannot be given a gear (detection_which_gear.call_of)
        said = f"{turns:.3g} {shaft}-shaft turns ({len(take.revolutions)} input revolutions), it needs {need}"
        if turns > 0 and (take.speed_hz or 0) > 0:  # in seconds too, where known (a 1 s take said turns alone)
            said += f" (a take of {need * len(take.revolutions) / turns / take.speed_hz:.2g} s or more)"
        unread = {"turns": turns, "shaft": shaft, "needed": need}
        return NOT_READ | {"summary": f"not localised: too short for the which-gear check: {said}", "unread": unread}
    try:
        first = take.first % int(table.train_period)
        found = L.localise(take.revolutions, hist, table, first, templates=templates_for(table, made, take))
    except GearlabInputError as exc:
        return NOT_READ | {"summary": f"not localised: {exc}"}
    if (
        found.named is None and envelope and hist.envelope is not None
    ):  # nothing synchronous: a strike the averages cancel?
        try:
            seen = E.localise(take.revolutions, hist.envelope, table, first)
        except GearlabInputError:
            return found.describe()
        if seen.named is not None and not E.elsewhere(found, seen.named_shaft):
            why = TR.of_the_train(take.revolutions, seen, hist.envelope, table, first)
            if why is None:
                return E.described(seen, found.summary())
            out = found.describe()  # the train's products, not a strike: nothing named (signals.envelope_train)
            return out | {"summary": f"{out['summary']}; {why}"}
    return found.describe()


NOT_READ = {"method": "", "named": None, "named_shaft": None, "shafts": []}  # which_gear of a record not localised


# A shaft beside the named one carries a change of its own where its z is over SECOND_TIMES its threshold
# and SECOND_SHARE of the named shaft's z: a strong change leaks into the other shafts' estimates (an
# output-gear crack at z 62,474 put 142 on the input shaft: 0.2 %; an output gear's impulse at z 478 and 399 put
# 24.1 and 25.9 on a shaft turning 4.93 times as fast, whose 14th and 15th harmonics its TSA passes within a bin of
# the comb's: 5.0 and 6.5 %), and a history of two records lets healthy shafts pass their thresholds (up to 2.3
# times them, development seeds); damage on two shafts' gears: a pinion chip with a chip on its wheel 93 and 66
# (71 %), a 106/127 pair chipped on both 1039 and 594 (57 %).
SECOND_TIMES, SECOND_SHARE = 3.0, 0.15


def flagged_shafts(found: dict) -> list[dict]:
    """The shafts of a localisation (Localisation.describe()) whose change is the record's own, the
    named one first: damage on two gears of different shafts (a pinion and its wheel) names both."""
    if found["named"] is None:
        return []
    named = [s for s in found["shafts"] if s["shaft"] == found["named_shaft"]]
    top = named[0]["z"]
    return named + [
        s
        for s in found["shafts"]
        if s["flagged"]
        and s["shaft"] != found["named_shaft"]
        and s["z"] > SECOND_TIMES * s["threshold"]
        and s["z"] > SECOND_SHARE * top
    ]


def named_gears(found: dict) -> str | None:
    """The gears of flagged_shafts as one line, the named first ("output gear 127T (stage 1); input pinion 106T
    (stage 1)"), or None: what `gearlab score` says a take's change lies on, as inspect's call and a run's table do."""
    return "; ".join(s["gear"] for s in flagged_shafts(found)) or None
