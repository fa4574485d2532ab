"""What a detection run found, per test take, in the words a maintenance manager acts on: what is wrong and where
(the gear, its teeth, its stage, the tooth), how sure (how many methods call the take, the which-gear z over its
threshold) and what to do; and why the table's false alarms differ from the verdict's. It opens the verdict
(gearlab.kinds.detection's verdict_lines): report.html, the end of `gearlab run` and the TUI say the same lines.
A verdict opening with 'At record30 (...)' left a reader to find a take's gear in the fourth table. Every call
here is the run's (detection_which_gear, detection_verdict): this module words them, it decides nothing."""

from __future__ import annotations

import re
from collections.abc import Mapping

import numpy as np

from ..signals.nonsync import HUM
from .detection_level import LEVEL_WORDS, REVERSED_CALL, called_level, most_called
from .detection_records import longest_tsa
from .detection_verdict import OTHER_NONSYNC, detection_lines, watched_calls
from .detection_which_gear import OTHER, UNDETERMINED, WATCHED, is_level_change, judged_unit
from .record_effects import logged

# A median unit this many of its history's unit spreads or more off its threshold is said as '> +100 sd' with the
# median and the threshold themselves: past it the figure tells how alike the history's units are more than how far the
# take lies ('na4 +5281 sd' of a chipped take over two history takes, its NA4 units within 0.5 of each other; a
# history's units alike within 1e-5 read '+362843 sd'), and a person reads the two scores; below it, the figure
FAR_SD = 100
# a cut take's words of the side of its reversal scored (detection_in_band._words, signals.checks.reversal_words)
REVERSES = re.compile(r"(?:after|before|across) the shaft reverses in its turn of \S+ \.\. \S+ s")


def verdict(summary: Mapping, records: list[Mapping]) -> list[str]:
    """The verdict of a detection run (report.html, table.md, the end of `gearlab run`, the TUI): a line per test take
    (take_lines), why the two false-alarm rates differ (false_alarms_line), then the methods' lines (detection_lines),
    all at the rows' longest TSA (detection_records.longest_tsa); *records*: results.jsonl's."""
    unit = longest_tsa(r["unit"] for r in summary.get("rows") or [])
    if unit is None:
        return []
    reconciled = [line] if (line := false_alarms_line(summary, unit)) else []
    return take_lines(summary, judged(records), unit) + reconciled + detection_lines(summary, unit)


def judged(records: list[Mapping]) -> list[Mapping]:
    """results.jsonl's records of the methods a run judges: an ensemble's members (one training each, with their
    seed or fold) are kept there and shown only as the spread of their AUCs beside the ensemble's."""
    return [r for r in records if r.get("seed") is None and r.get("fold") is None]


def _name(path: str) -> str:
    return path.replace("\\", "/").rsplit("/", 1)[-1]


def _level(summary: Mapping, condition: str, path: str) -> str:
    """The run's warning that *path*'s level is off its history's (detection_records.level_warnings), as 'level 1.5 x
    its history's'; "" where none."""
    said = ((summary.get("conditions") or {}).get(condition) or {}).get("warnings") or []
    off = next((w for w in said if w.startswith(f"{path}: level ")), None)
    return "" if off is None else off.removeprefix(f"{path}: ").split(" (")[0]


def _drift(summary: Mapping, condition: str, path: str, called: bool, named) -> str:
    """detection_level.called_level's words of *path*'s level, from the run's conditions (their level_ratio and
    level_spread); "" where it says none or the run kept no ratio."""
    cond = (summary.get("conditions") or {}).get(condition) or {}
    ratio = (cond.get("level_ratio") or {}).get(path)
    takes = len(cond.get("history") or ()) or 2
    return "" if ratio is None else called_level(called, named, ratio, cond.get("level_spread"), takes)


def _clipped(summary: Mapping, condition: str, path: str) -> str:
    """The run's warnings that *path*'s vibration is clipped (gearlab.signals.spikes.acquisition), as '3000 samples
    flat at 5.397 m/s²' (each side: ' and '); "" where none."""
    said = ((summary.get("conditions") or {}).get(condition) or {}).get("warnings") or []
    flat = [w.removeprefix(f"{path}: ").split(" (")[0] for w in said if w.startswith(f"{path}: ") and "(clipped" in w]
    return " and ".join(flat)


def _reversed(summary: Mapping, condition: str, path: str) -> str:
    """The run's warning that *path*'s shaft reverses, as the part scored ('after the shaft reverses in its turn of 3
    .. 3.15 s': detection_in_band's words); "" where it turns one way."""
    said = ((summary.get("conditions") or {}).get(condition) or {}).get("warnings") or []
    found = (REVERSES.search(w) for w in said if w.startswith(f"{path}: "))
    return next((m[0] for m in found if m), "")


def _methods(records: list[Mapping], condition: str, path: str, unit: str) -> tuple[list[str], int]:
    """The methods whose record-level decision calls *path* at *unit* (most_called: over half its units over the
    threshold, as `gearlab score` decides), each with how far its median unit lies over its threshold in its history's
    unit spreads (over_sd: 'fm4 +5.1 sd'), and how many methods scored it there."""
    called, scored = [], 0
    for r in records:
        units = (r.get("test_scores") or {}).get(path) or {}
        threshold = r["thresholds"].get(unit)
        if r.get("condition") != condition or not units.get(unit) or threshold is None:
            continue
        scored += 1
        if not most_called(units[unit], threshold):
            continue
        called.append(r["method"] + over_sd(float(np.median(units[unit])), threshold, r, unit))
    return called, scored


def over_sd(median: float, threshold: float, record: Mapping, unit: str) -> str:
    """' +5.1 sd': how far a take's *median* unit lies over the *threshold* of *record*'s method at *unit*, in its
    history model's unit spreads, on the scale that model is fitted on (a size's, NA4's with three history takes or
    more: the log of the score over its floor, where its unit_sd is; the raw difference over it mixed the two). From
    FAR_SD on, ' > +100 sd (median 80.1, threshold 3.52)': the scores themselves. "" where the model has no spread."""
    model = (record.get("history_models") or {}).get(unit) or {}
    sd, floor = model.get("unit_sd"), model.get("floor")
    if not sd:
        return ""
    over = float(logged(median, floor) - logged(threshold, floor)) / sd
    if abs(over) < FAR_SD:
        return f" {over:+.1f} sd"
    beyond = f"> +{FAR_SD}" if over > 0 else f"< -{FAR_SD}"
    return f" {beyond} sd (median {median:.3g}, threshold {threshold:.3g})"


def _orders(order: float, shafts: Mapping[str, float]) -> str:
    """A non-synchronous line's input order *order* in each other shaft's orders: a bearing turns with its shaft,
    and a defect's order relative to it tells the shafts' bearings apart (' (= 1.33 output orders)')."""
    said = [f"{order / o:.2f} {s} orders" for s, o in shafts.items() if o > 0 and abs(o - 1.0) > 1e-9]
    return f" (= {', '.join(said)})" if said else ""


def take_lines(summary: Mapping, records: list[Mapping], unit: str) -> list[str]:
    """Per test take called or localised, a line: what is wrong, where, how sure, what to do; then the takes with
    nothing found. [] where the run localised nothing (no gearbox description)."""
    which = summary.get("which_gear") or {}
    takes = which.get("records") or {}
    if not takes:
        return []
    shafts = which.get("shaft_orders") or {}
    lines, quiet = [], []
    for path, take in takes.items():
        condition, call, ns = take.get("condition"), take.get("call") or "", take.get("nonsync") or {}
        # a take too short for the run's longest TSA is judged at the longest it fills, as the verdict's condition is
        at = judged_unit(records, path, unit)
        called, scored = _methods(records, condition, path, at)
        level = _level(summary, condition, path)
        sure = f"called by {len(called)} of {scored} methods at {at}"
        spreads = any(" sd" in c for c in called) * ": median unit over the threshold in history spreads"
        sure += f" ({', '.join(called)}{spreads})" if called else ""
        # a take off its history's level is recorded again first: its call may be the load's (a healthy take at 1.5 x
        # its one-load history's level was localised on the input pinion, z 3.89 over 2.58)
        said = []
        if take.get("named"):
            gear = take["summary"]  # 'input pinion 38T (stage 1): z = 3.89 (threshold 2.58), tooth 12 of 38 (...)'
            whose = "" if call.startswith(WATCHED) else ", a gear this run does not watch"
            said.append(f"damage on the {gear}{whose}; {sure}")
        if OTHER_NONSYNC in call:  # a bearing's line as the call says it (a gear's change may explain the residual)
            tone = f"bearing-like tone at {ns['order']:.2f} input orders{_orders(ns['order'], shafts)}"
            tone += f", z {ns['z']:.1f} over {ns['threshold']:.1f}"
            said.append(tone + ("" if take.get("named") else f": a bearing, not a gear; {sure}"))
        # a take too short for the which-gear check is a fault of no gear where a method calls it; uncalled, a take
        # where nothing was found, in a summary made before its calls were decided too (detection_which_gear.
        # decided_call: a healthy 2 s take under every threshold opened the verdict with an alarm's words)
        if call.startswith(HUM) or (call.startswith(UNDETERMINED) and called):
            said.append(f"{call}; {sure}")
        largest = take.get("summary", "").removeprefix("nothing localised ")  # '(largest: input z = 1.35, ...)'
        moved = is_level_change(call) and called  # its level, not damage (level_call): said so
        if moved:
            said.append(f"{call}; {sure}, on no gear localised {largest}: not counted as the watched gear's fault")
        # a take called on no gear at a level off its history's, within a level change's limit: its level said here
        # as gearlab score says it first (a healthy take at 1.2 x its one-load history's, called by NA4 and the
        # template methods, had its level among the warnings under the tables alone)
        drift = _drift(summary, condition, path, bool(called), take.get("named"))
        if not said and called:
            rule = f"{sure}, on no gear localised {largest}: the watched gear's fault by the run's rule"
            said.append(rule + (f"; its {drift}" if drift else ""))
        said = (
            [f"{level}: record a history at this load (or gain) before acting on what follows"]
            if level and not moved
            else []
        ) + said
        # a clipped mesh's flattened peaks change its shafts' averages (a healthy 39/61 take clipped over 5 % of its
        # samples: the input pinion, z 32 over 2.6)
        clip = _clipped(summary, condition, path) if said else ""
        said = ([f"clipped ({clip}): the call may be the clipping, record at a larger range"] if clip else []) + said
        # a take whose shaft stops and turns back is scored on one side: as gearlab score's rows (reversed_call)
        turned = _reversed(summary, condition, path) if said else ""
        said = ([f"scored on its turns {turned}: {REVERSED_CALL}"] if turned else []) + said
        if not said:
            quiet.append(_name(path))
            continue
        todo = "look at that gear" if take.get("named") else ""
        todo += (" and the bearings" if todo else "look at the bearings") if OTHER_NONSYNC in call else ""
        todo = todo or ("look at the watched gear" if called and call.startswith(WATCHED) else "")
        todo += ", or record a history at this take's load (or gain)" if todo and drift else ""
        todo = "" if level or clip or turned else todo
        lines.append(f"take {_name(path)}: " + "; ".join(said) + (f"; {todo}." if todo else "."))
    if quiet:
        lines.append(
            f"nothing found (no method calls it, no gear localised, level as its history's): {', '.join(quiet)}."
        )
    return lines


def false_alarms_line(summary: Mapping, unit: str) -> str | None:
    """Where the table's false alarms (every unit of a take not labelled the fault, other damage included) and the
    verdict's (watched_calls: a take whose change lies on another gear or is a bearing's, or a level change, is
    neither) differ at *unit*, one sentence saying why, with each such row's two rates; None where they agree."""
    differ = []
    for r in summary.get("rows") or []:
        if r["unit"] != unit or r.get("false_alarm") is None:
            continue
        verdict = watched_calls(r, summary)["false_alarm"]
        if verdict is not None and abs(verdict - r["false_alarm"]) >= 0.5:
            differ.append(f"{r['condition']} {r['method']} {r['false_alarm']:.0f} % in the table, {verdict:.0f} % here")
    if not differ:
        return None
    calls = (summary.get("which_gear") or {}).get("calls") or []
    moved = any(c.get("level_changes") for c in calls if c["unit"] == unit)
    return (
        f"False alarms at {unit}: the table counts every unit of a take not labelled the fault, other damage "
        f"{'and level changes ' * moved}included; the verdict below counts {OTHER} (another gear's change, a bearing's "
        f"line){' and a level change (' + LEVEL_WORDS + ')' if moved else ''} as neither a detection nor a false alarm "
        "of the watched gear: " + ", ".join(differ) + "."
    )
