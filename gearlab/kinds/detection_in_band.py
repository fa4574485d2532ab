"""A run-up or coast-down in the detection kind (gearlab.kinds.detection): a test take whose speed varies is
scored on its longest stretch of revolutions at a condition's history speed, by the run itself
(detection_records.read_target) and by `gearlab score` (detection_scoring) alike: one rule, one set of words."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import GearlabInputError
from ..signals.checks import SPEED_VARIES, VARIES_WORDS

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
    """A varying take's speeds in words from its speed source *how* ('20.16 Hz .. 34.94 Hz over the take: a run-up or
    coast-down?'), without what a run once did with it (grouped at its mean speed)."""
    return how.split("; ")[-1].split(VARIES_WORDS)[0] + VARIES_WORDS


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
    said = f"scored on {part.stop - part.start} of {len(rec.speeds)}{whose} revolutions at {speeds.min():.2f} .. "
    said += f"{speeds.max():.2f} Hz (the history's {centre:.2f} Hz ± {IN_BAND:.1%}" + (
        f"; the longest run of its {inside} there)" if inside > len(speeds) else ")"
    )
    first = rec.first_revolution + part.start
    cut = replace(rec, revolutions=rec.revolutions[part], speed_hz=float(np.mean(speeds)), first_revolution=first)
    return InBand(name, centre, part, inside, replace(cut, speeds=speeds), said)


def cut_run_ups(files, records: dict, named: dict, blocks, turns: float, where: str) -> dict[str, str]:
    """A detection run's takes whose speed varies (read_target: *records* {path: CutRecording}, *named* {path:
    condition} as conditions_of grouped them, both changed here): a history take refused (its revolutions set its
    condition's speed, standardiser and thresholds); a test take cut to its longest stretch at a condition's history
    speed as `gearlab score` cuts one (in_band; its own 'condition', else every condition with a history), refused
    where that stretch is shorter than the longest [detection] block of the units' shaft (turning *turns* per input
    turn). {path: what was scored in words} of the test takes cut."""
    for f in files:
        how = records[f.path].angle_source
        if f.role == "history" and VARIES_WORDS in how:
            raise GearlabInputError(
                f"{where}: {f.path} (history; {span(how)}): a history take must run steady (its speed within "
                f"{SPEED_VARIES:.0%}): its revolutions set its condition's speed, standardiser and thresholds; "
                "expected a steady take as history (a run-up or coast-down as a test take, scored at a history's speed)"
            )
    speeds: dict[str, list[float]] = {}
    for f in files:
        if f.role == "history":
            speeds.setdefault(named[f.path], []).append(records[f.path].speed_hz)
    centres = {c: float(np.median(v)) for c, v in speeds.items()}
    need = max(1, math.ceil(max(blocks, default=1) / turns))  # input revolutions for a unit of every kind
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
            shaft = " revolutions" if turns == 1 else f" input revolutions ({max(blocks)} of the units' shaft)"
            raise GearlabInputError(
                f"{where}: {f.path} ({span(rec.angle_source)}): {mean}its longest run within {IN_BAND:.1%} of the "
                f"history's {got.centre:.2f} Hz ('{got.condition}') holds {n} of its {len(rec.speeds)} revolutions "
                f"({got.inside} in the band in all), a unit of every kind needs {need}{shaft}; expected a take that "
                "runs a while at a condition's speed, or shorter [detection] key 'blocks'"
            )
        records[f.path], named[f.path], out[f.path] = got.record, got.condition, got.said
    return out
