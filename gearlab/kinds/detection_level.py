"""A take's level against its history's (gearlab.kinds.detection), by one rule wherever it is said: in a detection
run's warnings (level_warnings as it reads its takes, called_levels once its methods have called them) and in
`gearlab score`'s rows (level_line, called_level)."""

from __future__ import annotations

import math

import numpy as np

from ..data.channel_units import LEVEL_OFF, level_why


def level_warnings(cond: dict) -> list[str]:
    """A line (level_line) for each test record of *cond* (its "history" and "test": (file, revolutions in m/s²))
    whose standard deviation is more than LEVEL_OFF off the median of its history records' (another load, a gain
    left out)."""
    std = {f.path: take_level(r) for f, r in cond["history"] + cond["test"]}
    typical = history_level([r for _, r in cond["history"]])
    lines = {f.path: level_line(level_ratio(std[f.path], typical)) for f, _ in cond["test"]}
    said = [f"{path}: {line}" for path, line in lines.items() if line]
    # the history's own records at two loads: NA4's record-level threshold spans them (the 25/52 + 16/81 box's
    # history at 1 and 1.5 x: 259, its 16T chip's takes at 20-100 uncalled)
    low, high = (
        min(std[f.path] for f, _ in cond["history"]) / typical,
        max(std[f.path] for f, _ in cond["history"]) / typical,
    )
    if typical > 0 and high / low > LEVEL_OFF:
        said.append(
            f"the history's levels span {low:.2g} .. {high:.2g} x their median (two loads or gains?): NA4, a size, "
            "sets its threshold over them; a condition per load (condition = ...) compares like with like"
        )
    return said


def level_line(ratio: float) -> str:
    """A record's level *ratio* to its history's, in words where more than LEVEL_OFF off ("": within)."""
    if not (why := level_why(ratio)):
        return ""
    return (
        f"level {ratio:.2g} x its history's ({why}): NA4, a size, and the template methods (matched_filter, "
        "likelihood_ratio), which subtract the history's average, read it as a change; a history at that load, or its "
        "own condition (condition = ...), compares like with like (a sensor re-mounted: record a new history)"
    )


# a take called with nothing localised whose level is off its history's (level_line): its call (decision_of), not damage
LEVEL_CHANGED = "level changed by a factor of"


# the rule in words, where a table or the verdict sets such takes aside
LEVEL_WORDS = (
    f"a take called with nothing localised, its level over {LEVEL_OFF:g} x or under 1/{LEVEL_OFF:g} x its history's"
)


def level_factor(call: str) -> str:
    """The factor a level change's *call* (level_change) names, as written ('2.00')."""
    return call.removeprefix(LEVEL_CHANGED).split()[0]


def level_change(ratio: float | None) -> str:
    """A called take's decision where its level *ratio* to its history's is more than LEVEL_OFF off and no gear is
    localised: a sensor of 50 mV/g put in for one of 100 mV/g, the scenario kept, was called 'fault' on every
    matched_filter unit, though the level line said 0.5 x; "" within LEVEL_OFF or unread (None). Where nothing is
    localised: detection_which_gear.level_call, by which `gearlab score` and a detection run's tables call it alike."""
    if ratio is None or not level_why(ratio):
        return ""
    return f"{LEVEL_CHANGED} {ratio:.2f} (sensor, gain or load changed?): record a new history"


def level_spread(levels) -> float | None:
    """How far a history's own takes lie off their median level: the largest |log| of their *levels* (standard
    deviations, in any one scale) over its median; 0 for a history without a level; None for a history of one
    take, whose spread is unknown (its 0 put every take but its own off it: 'within 0.0 %' of a take at 1.0 x)."""
    levels = np.asarray(levels, dtype=np.float64)
    if levels.size < 2:
        return None
    typical = float(np.median(levels))
    return float(np.max(np.abs(np.log(levels / typical)))) if typical > 0 and np.all(levels > 0) else 0.0


def history_spread(history) -> float | None:
    """How far a history's levels reach off their median (level_spread): of two or more takes, their take_levels';
    of one take, its own turns' (each revolution's standard deviation): a healthy take at 1.2 x a one-take
    history's level, called by NA4 and the template methods with no gear named, was told nothing of its level, the
    history's spread unknown; its turns lie within what one load gives a turn. None where no turn is kept."""
    if len(history) > 1:
        return level_spread([take_level(r) for r in history])
    turns = np.asarray(history[0]) if len(history) else np.empty(0)
    return level_spread(np.std(turns, axis=-1)) if turns.ndim == 2 and len(turns) > 1 else None


def take_level(revs) -> float:
    """A take's level: the standard deviation of its revolutions in m/s² as read (spikes bridged; before its units'
    shaft, the standardiser and the alignment), the one measure a run's tables and `gearlab score` compare."""
    return float(np.std(revs))


def history_level(history) -> float:
    """The level a take's is compared with: the median take_level of a condition's *history* takes (revolutions
    each), kept in scoring.json ('level_reference') for `gearlab score`; a median, as one take at another load
    moves a pooled standard deviation (the standardiser's) by its own level and its mean."""
    return float(np.median([take_level(r) for r in history]))


def level_ratio(level: float, reference: float) -> float:
    """A take's *level* (take_level) over its history's *reference* (history_level); 1 where the history is
    silent."""
    return level / reference if reference > 0 else 1.0


# said of a run saved before scoring.json kept its history's level (level_reference)
OLD_LEVEL = (
    "a run saved before it kept its history's level: a take's level ratio is read off the stored history (its "
    "units' revolutions, standardised in float32), which may differ from the run's own table near the level-change "
    "limit; run the scenario again to keep it"
)


def kept_level(kept: dict, history, scale: float) -> tuple[float, str]:
    """(the history_level a take's level is compared with, "" or OLD_LEVEL): scoring.json's condition *kept* its
    'level_reference'; a run saved before: its stored *history* takes (standardised) times the standardiser's
    *scale*, said so."""
    if kept.get("level_reference") is not None:
        return kept["level_reference"], ""
    return history_level(history) * scale, OLD_LEVEL


def run_levels(cond: dict) -> tuple[dict[str, float], float | None, float]:
    """Of a run's condition *cond* (its "history" and "test": (file, revolutions in m/s²)): each test take's
    level_ratio (as level_warnings reads it), the history's level_spread (what called_levels reads once the run's
    methods have called the takes; both kept in conditions.json) and its history_level (kept for gearlab score)."""
    typical = history_level([r for _, r in cond["history"]])
    ratios = {f.path: level_ratio(take_level(r), typical) for f, r in cond["test"]}
    return ratios, history_spread([r for _, r in cond["history"]]), typical


def most_called(scores, threshold: float) -> bool:
    """Over half a take's unit *scores* of a kind over their *threshold* (a tie, 1 of 2: not): the take called by
    that method and unit, in `gearlab score`'s rows as in the run's level words."""
    s = np.asarray(scores, dtype=np.float64)
    return bool(s.size) and int(np.sum(s > threshold)) > s.size / 2


def _times(ratio: float) -> str:
    """*ratio* in two digits, three where two read it as 1 (1.008: '1.01', not '1', a level said off its history's)."""
    return f"{ratio:.2g}" if f"{ratio:.2g}" != "1" else f"{ratio:.3g}"


def called_level(called: bool, named, ratio: float, spread: float | None, takes: int = 2) -> str:
    """Of a take *called* a fault, *named* no gear and its level *ratio* to its history's further off than the
    history's levels reach (*spread*, history_spread: its *takes*' own or, of one take, its turns'), its level in
    words, where level_line says nothing (within LEVEL_OFF): a sensor's mount loosening -0.1 dB a day was called by
    the template methods from 0.83 x, its level said from 0.8 x only. The call is load-uncertain: a history of one
    load has not seen that level. "" otherwise, and where the spread is unknown (None)."""
    if not called or named or spread is None or level_line(ratio) or abs(math.log(ratio)) <= spread:
        return ""
    own = "its own takes" if takes > 1 else "its one take's turns"
    return (
        f"level {_times(ratio)} x its history's, {own} within {math.expm1(spread):.1%} of it: load-uncertain, "
        "called with no gear named at a level its history has not seen, the call may be the level's change (a "
        "sensor's mount or gain, another load?): NA4 and the template methods (matched_filter, likelihood_ratio), "
        "which subtract the history's average, read a level as a change"
    )


def called_levels(conditions: dict, records: list[dict], loc: dict | None) -> list[str]:
    """A detection run's called_level lines ('path: words'): per test take of *conditions* (conditions.json, its
    "level_ratio" and "level_spread"), called where a method's units of a kind are most over its threshold
    (most_called; *records*: the run's method records) and localised on no gear (*loc*: localisation.json)."""
    out = []
    found = (loc or {}).get("records") or {}
    for name, c in conditions.items():
        for path, ratio in (c.get("level_ratio") or {}).items():  # none kept by a run from before they were
            called = any(
                most_called(s, r["thresholds"][u])
                for r in records
                if r["condition"] == name and path in r["test_scores"]
                for u, s in r["test_scores"][path].items()
            )
            named = found.get(path, {}).get("named")
            if said := called_level(called, named, ratio, c["level_spread"], len(c.get("history") or ()) or 2):
                out.append(f"{path}: {said}")
    return out


def clipped_call(called: bool, flaws) -> list[str]:
    """A take's acquisition *flaws* (gearlab.signals.spikes.acquisition), each clipping's told, where the take is
    *called* (a fault or other damage), that the call may be the clipping: a healthy 39/61 take clipped over 5 % of
    its samples, its mesh's peaks once a turn (the input's modulation), was scored 'input pinion 39T, tooth 1' at
    z 18 over 2.6 by fm4 and likelihood_ratio, beside a plain 'clipped ...?' warning."""
    said = "; the take is called: a clipped mesh's flattened peaks change its shafts' averages, the call may be the "
    said += "clipping (record at a larger range)"
    return [f + said if called and "clipped" in f else f for f in flaws]


# A called take scored on one side of its shaft's reversal (detection_in_band's words): its averages may run the other
# way than its history's (the tiny run's healthy take scored after its reversal: na4 called it, the input pinion
# localised at z 30 over 2.6)
REVERSED_CALL = "the call may be the direction, where the history turned the other way; record a take turning its way"


def reversed_call(called: bool, scored_on: str | None) -> str | None:
    """A cut take's words *scored_on* (detection_in_band) with REVERSED_CALL after them where its shaft reverses and
    the take is *called* (a fault or other damage): `gearlab score`'s rows as the run's verdict (detection_summary)."""
    if not called or not scored_on or "the shaft reverses" not in scored_on:
        return scored_on
    return f"{scored_on}; the take is called: {REVERSED_CALL}"
