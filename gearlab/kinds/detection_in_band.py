"""A run-up, coast-down or drift in the detection kind (gearlab.kinds.detection): a test take whose speed varies is
scored on its longest stretch of revolutions at a condition's history speed, by the run itself
(detection_records.read_target) and by `gearlab score` (detection_scoring) alike: one rule, one set of words; a
history take that runs up first is used on its longest steady stretch (the same band about that stretch's own speed).
A take sampled too slowly for the orders its condition's history is read to is refused, by both alike (too_narrow)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..data.chain import Chain
from ..errors import GearlabInputError
from ..signals.checks import SPEED_VARIES, VARIES_WORDS, fmt_hz, reversal_words, varies_span

# A take whose speed varies beyond a steady take's (speed_varies: a run-up or coast-down) is scored on its
# revolutions within this share of its condition's history speed (the median of the history records' speeds: no
# label), either side, in a detection run's test takes and by `gearlab score` alike (in_band): a steady take's turns
# span at most SPEED_VARIES of its mean, so half of it either side of the history's speed is where a steady history
# may have run. A revolution farther off meets the gearbox's resonances at other orders than the history's did.
IN_BAND = SPEED_VARIES / 2


def stretch(speeds: np.ndarray, centre: float) -> slice:
    """The longest run of consecutive revolutions whose *speeds* lie within IN_BAND of *centre* (Hz): consecutive, as
    the units' shaft, the records' alignment and localisation read a take's revolutions."""
    inside = np.abs(speeds - centre) <= IN_BAND * centre
    edges = np.flatnonzero(np.diff(np.concatenate([[0], inside.astype(np.int8), [0]])))
    if not edges.size:
        return slice(0, 0)
    k = int(np.argmax(edges[1::2] - edges[::2]))
    return slice(int(edges[2 * k]), int(edges[2 * k + 1]))


def span(how: str) -> str:
    """A varying take's speeds in words from its speed source *how* ('20.16 Hz .. 34.94 Hz over the take: a run-up'),
    without what a run once did with it (grouped at its mean speed): signals.checks.varies_span."""
    return varies_span(how)


@dataclass(frozen=True)
class InBand:
    """in_band's answer: the *condition* of the longest stretch, its history speed *centre*, the *part* of the take's
    revolutions scored (empty: none in band), how many of them lay *inside* the band at all, the record cut to the
    part (*record*: revolutions, mean speed, first revolution, speeds) and what was scored in words (*said*)."""

    condition: str
    centre: float
    part: slice
    inside: int
    record: object
    said: str


def in_band(rec, centres: dict[str, float], whose: str = "") -> InBand:
    """A take *rec* whose speed varies (recordings.CutRecording with its revolutions' speeds) cut to its longest
    stretch of revolutions within IN_BAND of a condition's history speed (*centres*: {condition: Hz}, the one of the
    longest stretch chosen), its mean speed the part's: what a detection run's test take (read_target) and `gearlab
    score` score of a run-up or coast-down. *whose*: ' input' where the units are another shaft's revolutions."""
    stretches = {c: stretch(rec.speeds, hz) for c, hz in centres.items()}
    name = max(centres, key=lambda c: stretches[c].stop - stretches[c].start)
    part, centre = stretches[name], centres[name]
    inside = int(np.sum(np.abs(rec.speeds - centre) <= IN_BAND * centre))
    if part.stop == part.start:
        return InBand(name, centre, part, inside, rec, "")
    speeds = rec.speeds[part]
    said = f"scored on {_words(rec, part, whose)} (the history's {centre:.2f} Hz ± {IN_BAND:.1%}" + (
        f"; the longest run of its {inside} there)" if inside > len(speeds) else ")"
    )
    return InBand(name, centre, part, inside, _cut(rec, part), said)


def _words(rec, part: slice, whose: str) -> str:
    """'31 of 197 revolutions at 15.60 .. 16.35 Hz': the *part* of *rec*'s revolutions a run keeps, in the words a
    test take's score and a history take's steady part share; of a take whose shaft reverses (CutRecording.reverses),
    which side of the reversal the part lies on, and where that is."""
    speeds = rec.speeds[part]
    n = part.stop - part.start
    said = f"{n} of {len(rec.speeds)}{whose} revolutions at {speeds.min():.2f} .. {speeds.max():.2f} Hz"
    if not rec.reverses:
        return said
    k = rec.reverses[0]
    side = "after" if part.start >= k else "before" if part.stop <= k else "across"
    return f"{said}, {side} {reversal_words(rec.reverses)}"


def _cut(rec, part: slice):
    """*rec* cut to the revolutions *part*: its mean speed, first revolution and speeds the part's (a reversal said
    by _words, the part turning one way)."""
    speeds = rec.speeds[part]
    first = rec.first_revolution + part.start
    cut = replace(rec, revolutions=rec.revolutions[part], speed_hz=float(np.mean(speeds)), first_revolution=first)
    kept = rec.settled or slice(0, len(rec.revolutions))  # a followed angle's settled revolutions, within the part's
    settled = slice(max(kept.start - part.start, 0), max(min(kept.stop, part.stop) - part.start, 0))
    return replace(cut, speeds=speeds, reverses=(), settled=settled)


def steady(rec, whose: str = "") -> InBand:
    """A history take *rec* whose speed varies (a recording that starts with a run-up) cut to its longest stretch of
    revolutions within IN_BAND of that stretch's own median speed (stretch, as a test take's cut): its condition's
    speed, standardiser and thresholds come from the steady part alone. Every speed the take passes (on a grid of
    half a band) seeds a stretch, each moved to its own median until it stays (the band then centred on the part it
    holds); the longest kept. *said*: 'used N of M revolutions at .. Hz (steady part)'; an empty part where none."""
    speeds = rec.speeds
    low, high = float(np.min(speeds)), float(np.max(speeds))
    seeds = np.exp(np.arange(np.log(low), np.log(high) + IN_BAND, IN_BAND / 2)) if low > 0 else [np.median(speeds)]
    best, centre = slice(0, 0), float(np.median(speeds))
    for hz in seeds:
        part = stretch(speeds, float(hz))
        for _ in range(8):  # a few moves: the band's centre settles on the part's median
            if part.stop == part.start:
                break
            hz = float(np.median(speeds[part]))
            moved = stretch(speeds, hz)
            if moved == part:
                break
            part = moved
        if part.stop - part.start > best.stop - best.start:
            best, centre = part, float(hz)
    if best.stop == best.start:
        return InBand("", centre, best, 0, rec, "")
    said = f"used {_words(rec, best, whose)} (steady part)"
    return InBand("", centre, best, best.stop - best.start, _cut(rec, best), said)


def _need(blocks, turns: float) -> tuple[int, str]:
    """(input revolutions a unit of every kind needs, their words): the longest [detection] block of the units'
    shaft, turning *turns* per input turn."""
    need = max(1, math.ceil(max(blocks, default=1) / turns))
    return need, " revolutions" if turns == 1 else f" input revolutions ({max(blocks)} of the units' shaft)"


def steady_histories(files, records: dict, blocks, turns: float, where: str) -> dict[str, str]:
    """A detection run's history takes whose speed varies (read_target: *records* {path: CutRecording}, changed here,
    before the takes are grouped by speed): each cut to its longest steady stretch (steady), refused in one line where
    none holds the longest [detection] block of the units' shaft (turning *turns* per input turn) or the take has no
    revolutions' speeds. {path: what was used in words}."""
    need, shaft = _need(blocks, turns)
    out = {}
    for f in files:
        rec = records[f.path]
        if f.role != "history" or VARIES_WORDS not in rec.angle_source:
            continue
        got = steady(rec, "" if turns == 1 else " input") if rec.speeds is not None else None
        n = 0 if got is None else got.part.stop - got.part.start
        if n < need:
            held = ""  # no revolutions' speeds (no tacho): no steady part can be found
            if got is not None:
                held = (
                    f"; its longest stretch within {IN_BAND:.1%} of its own median speed ({got.centre:.2f} Hz) "
                    f"holds {n} of its {len(rec.speeds)} revolutions, a unit of every kind needs {need}{shaft}"
                )
            raise GearlabInputError(
                f"{where}: {f.path} (history; {span(rec.angle_source)}): a history take must run steady (its speed "
                f"within {SPEED_VARIES:.0%}) for a unit at least: its revolutions set its condition's speed, "
                f"standardiser and thresholds{held}; expected a history take steady for {need}{shaft} (a run-up or "
                "coast-down as a test take, scored at a history's speed)"
            )
        records[f.path], out[f.path] = got.record, got.said
    return out


def cut_run_ups(files, records: dict, named: dict, blocks, turns: float, where: str) -> dict[str, str]:
    """A detection run's test takes whose speed varies (read_target: *records* {path: CutRecording}, *named* {path:
    condition} as conditions_of grouped them, both changed here; its history takes already cut to their steady part:
    steady_histories): each cut to its longest stretch at a condition's history speed as `gearlab score` cuts one
    (in_band; its own 'condition', else every condition with a history), refused where that stretch is shorter than
    the longest [detection] block of the units' shaft (turning *turns* per input turn). {path: what was scored in
    words} of the test takes cut."""
    speeds: dict[str, list[float]] = {}
    for f in files:
        if f.role == "history":
            speeds.setdefault(named[f.path], []).append(records[f.path].speed_hz)
    centres = {c: float(np.median(v)) for c, v in speeds.items()}
    need, shaft = _need(blocks, turns)
    out = {}
    for f in files:
        rec = records[f.path]
        if f.role != "test" or VARIES_WORDS not in rec.angle_source or rec.speeds is None or not centres:
            continue
        asked = {f.condition: centres[f.condition]} if f.condition in centres else centres
        if f.condition and f.condition not in centres:
            continue  # its condition has no history: said so by read_target
        got = in_band(rec, asked, "" if turns == 1 else " input")
        n = got.part.stop - got.part.start
        if n < need:
            mean = "" if named[f.path] in centres else f"its mean speed {rec.speed_hz:.2f} Hz has no history record; "
            raise GearlabInputError(
                f"{where}: {f.path} ({span(rec.angle_source)}): {mean}its longest run within {IN_BAND:.1%} of the "
                f"history's {got.centre:.2f} Hz ('{got.condition}') holds {n} of its {len(rec.speeds)} revolutions "
                f"({got.inside} in the band in all), a unit of every kind needs {need}{shaft}; expected a take that "
                "runs a while at a condition's speed, or shorter [detection] key 'blocks'"
            )
        records[f.path], named[f.path], out[f.path] = got.record, got.condition, got.said
    return out


# A take whose band (where its acquisition's anti-alias filter leaves data: data.chain.Chain.max_order) ends more than
# this share below the input order its condition's history is read to is refused: the orders between hold nothing, and
# the learned methods read that as a change (a healthy 26/101 + 31/78 take at 10 kHz against a 25.6 kHz history, band
# 158 of 404 orders: the matched filter +0.0002 and the likelihood ratio +0.026 over their record30 thresholds, 1 of 2
# units called; the take at 25.6 kHz -0.007 and -10.5). A take at a speed up to 5 % off its history's (one condition)
# ends up to 5 % lower.
BAND_SHORT = 0.1


def too_narrow(path: str, fs: float, speed_hz: float, max_order: float, where: str) -> None:
    """Refuse, in one line, a take of *path* at *fs* and *speed_hz* whose band ends below *max_order* (its condition's
    history's) by over BAND_SHORT."""
    own = Chain(fs=fs, speed=speed_hz).max_order
    if own < (1 - BAND_SHORT) * max_order:
        raise GearlabInputError(
            f"{where}{path}: sampled at {fmt_hz(fs)}, its band ends at input order {own:.4g}, below the "
            f"{max_order:.4g} its condition's history is read to (the orders between would read as a change); expected "
            f"a rate of at least {fmt_hz(fs * max_order / own)}, or a history at this rate"
        )
