"""Which gear, in the detection kind (gearlab.kinds.detection): every test record's localised change
named against its condition's history records (gearlab.signals.localise), and a flag on a record
whose change lies on another gear than the one the scenario watches reported as other damage.

The watched gear is the source's faulty gear: the gear its fault classes sit on (the 32T input
pinion for scenarios/phm09_chip.toml). A test record is read whole (its complete revolutions as
cut from the tacho or the found speed, before the detection's standardisation and alignment, which rotate each
revolution and so break the slower shafts' continuity) and localised against the raw history
records of its condition, orders up to the condition's band. What a method's flag on one of its
units then means:

    the record's change named on a watched gear, or on the shaft of    a watched-gear fault
    one with both its gears (which of the two undecided)
    named on another gear (another shaft's, or the other of a shaft's  other damage: <that gear>
    two, told apart by the simulated events)
    nothing localised, the non-synchronous residual changed            other damage: non-synchronous
    (signals.nonsync: beyond its history's threshold)                  (bearing-like), at order X.XX
    ... its line on a mains harmonic, locked to time (sharper in Hz    not a gear fault: mains hum
    than in orders over the take's speed spread, or at the same Hz     (no watched gear's, counted as
    in a history take at another speed: nonsync.hum_or_bearing)       no gear fault)
    ... on a mains harmonic, not told from a bearing's (a steady       other damage: non-synchronous
    speed, no history take at another speed holding it)                (bearing-like) or mains hum, ...
    nothing localised, no non-synchronous change                       a watched-gear fault (not
                                                                       localised: no evidence of where)
    ... the take's level more than LEVEL_OFF off its history's         level changed by a factor of X.XX
    (level_call: a sensor, gain or load changed; `gearlab score` too)  (...): no damage, set aside
    a watched gear's shaft and another shaft over their thresholds     a watched-gear fault; also
    (a pinion and its wheel both damaged)                              other damage: <that gear>
    a gear named and a non-synchronous line at no product of its       ...; also other damage: non-
    shaft's gear fault (signals.nonsync.beside: a bearing's beside a   synchronous (bearing-like), ...
    tooth's)

The watched gears are those the source's fault classes sit on: both of a pinion-and-wheel class
("chip+chip@wheel"). A record with damage on a watched gear and on another is counted as both (the
verdict counts it as the watched gear's fault; the calls table in both columns).

A shaft's two gears are told apart by the description's simulated tooth-fault events at each
record's speed and rate (gearlab.data.which_templates, the same in `gearlab score`), simulated as the
scenario's [corrected] simulator is where it has one (its description and effects: the gap diagnosis's
fitted structure), else as the source: a structure other than the gearbox's misnames them; where the
history's mesh harmonics differ from the simulation's, and for a source without a description, by the
event's width (signals.localise, "Which gear on a shaft").
A change no shaft's synchronous average carries is no gear's: a bearing's strikes come at a rate
that is no shaft's order, and slip, so the detectors may flag them while no shaft's TSA changed. The
record less every shaft's synchronous average (signals.nonsync) is read against the history's: a line
of its envelope beyond the history's threshold is other damage at that strike order, never the
watched gear's. Only where neither is found, the take at its history's level, is a flag the watched
gear's, said as not localised.
The localisation uses the records' signals only; the labels come in with the tables (summarise).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..data import which_gear as W
from ..data.spec import DatasetSpec
from ..data.which_templates import effect_tables
from ..errors import GearlabInputError
from ..gearbox.simulation import PREFIX, gearbox_of, is_reference, reference
from ..parts.roc import auc
from ..signals import POINTS
from ..signals import envelope_sync as E
from ..signals import localise as L
from ..signals import nonsync as NS
from ..signals import which_template as T
from .detection_level import LEVEL_CHANGED, LEVEL_WORDS, level_change, level_factor
from .detection_records import longest_tsa
from .detection_saved import saved_histories

WATCHED, OTHER = "watched-gear fault", "other damage"
NOT_LOCALISED = f"{WATCHED} (not localised)"  # a flag with no evidence of where: counted as the watched gear's
# a flag on a record too short for the which-gear check (data.which_gear's 'unread'): an alarm of no gear, not the
# watched gear's: a 2 s take with damage on another gear, flagged, was reported as the watched gear's fault
UNDETERMINED = "fault, gear not determined"
NOT_FLAGGED = "not flagged (no method's units over its threshold)"
NOT_CALLED = "nothing called (no method's decision a fault)"  # a scored take's call where no method called it


def watched_gears(source: DatasetSpec, table) -> list[str]:
    """Names (signals.localise.Gear.name) of the gears the source's fault classes sit on: both gears of
    a class on a pinion and its wheel ("chip+chip@wheel")."""
    on = {(stage, gear) for c in source.fault_classes().values() for _, stage, gear in c.parts}
    gears = [g for shaft in L.gears_of(table).values() for g in shaft]
    return [g.name for g in gears if (g.stage, g.role) in on]


ALSO = "; also other damage: "  # a record localised on a watched gear and on another
ENVELOPE = "in the envelope: "  # before a record's z per shaft where they are its envelope's (signals.envelope_sync)


def call_of(found: dict, watched: list[str], nonsync: dict | None = None, speed_hz: float | None = None) -> str:
    """What a flag on a record means, from its localisation (Localisation.describe()) and its
    non-synchronous change (signals.nonsync.NonSync.describe(); None: not read): a watched-gear
    fault where any shaft over its threshold names a watched gear, with the other gears flagged beside
    it ("watched-gear fault: input pinion 32T (stage 1); also other damage: idler gear 96T (stage 1)");
    else other damage, every flagged gear named; nothing localised, other damage where the
    non-synchronous residual changed ("other damage: non-synchronous (bearing-like), at order 3.57"),
    a mains hum's line no gear's fault (*speed_hz*: the take's, its line in Hz), a record too short to be read a
    fault of no gear ("fault, gear not determined: 5.73 turns of the output
    shaft, 8 needed"), else the watched gear's, not localised."""
    shafts = W.flagged_shafts(found)
    if not shafts:
        if nonsync and nonsync["changed"]:
            hz = None if speed_hz is None else nonsync["order"] * speed_hz
            return NS.call(nonsync["order"], hz, nonsync.get("locked", ""), nonsync.get("why", ""))
        if unread := found.get("unread"):
            turns, shaft, need = unread["turns"], unread["shaft"], unread["needed"]
            return f"{UNDETERMINED}: {turns:.3g} turns of the {shaft} shaft, {need} needed"
        return NOT_LOCALISED
    mine, others = [], []
    for ev in shafts:
        # one gear of a two-gear shaft named by its event: only that gear; both: either, or the first listed where the
        # mesh phases lean (which_template.EVEN_LEAD)
        on = T.callable_gears(ev)
        (mine if any(g in watched for g in on) else others).append(ev["gear"] + L.weakly(ev))
    flagged = [ev["shaft"] for ev in shafts]
    if bearing := NS.beside(nonsync, speed_hz, flagged):  # a bearing's strikes beside a gear's damage: both said
        others.append(bearing)
    if mine:
        return f"{WATCHED}: {'; '.join(mine)}" + (ALSO + "; ".join(others) if others else "")
    return f"{OTHER}: {'; '.join(others)}"


def is_other(call: str | None) -> bool:
    """A record's call (call_of) names damage on another gear than the watched ones (only)."""
    return bool(call) and call.startswith((OTHER, NS.HUM))  # a mains hum is no watched gear's either


def is_level_change(call: str | None) -> bool:
    """A take's decision or call says its level changed, nothing localised (detection_level.level_change): no damage."""
    return bool(call) and call.startswith(LEVEL_CHANGED)


def is_undetermined(call: str | None) -> bool:
    """A record's call says its gear could not be read (a take too short for the which-gear check)."""
    return bool(call) and call.startswith(UNDETERMINED)


def unwatched(rows: list[dict]) -> dict[str, str]:
    """{file: note} of the scored takes whose change is localised on a gear no method watches (their call other
    damage) while no method's decision called it (their units under threshold: each row 'healthy', of the watched
    gear), as the terminal says under such a take (terminal.score_tables): the history and the trend say so too."""
    calls: dict[str, str] = {}
    for r in rows:
        if is_other(r.get("call")):
            calls.setdefault(r["file"], r["call"])
    called = {r["file"] for r in rows if is_other(r["decision"])}
    said = "on a gear this run does not watch; no method called it"
    return {f: f"{c}, {said}" for f, c in calls.items() if f not in called}


def is_also_other(call: str | None) -> bool:
    """A record's call names damage on another gear beside the watched one's: counted as both."""
    return bool(call) and call.startswith(WATCHED) and ALSO in call


def decided_call(call: str | None, called: bool) -> str | None:
    """A take's call as decided: NOT_CALLED where no method's decision calls it (*called*) and *call* names no gear (a
    flag's name alone: 'watched-gear fault (not localised)', 'fault, gear not determined' of a take too short for
    the which-gear check, or a level change); else *call* (a gear or a bearing-like line named stays said). A run's
    summary and `gearlab score`'s rows say it alike."""
    unnamed = call == NOT_LOCALISED or is_undetermined(call) or is_level_change(call)
    return NOT_CALLED if not called and unnamed else call


def judged_unit(records: list[dict], path: str, unit: str) -> str:
    """The unit a take is judged at: *unit* (the run's longest TSA), or the longest a take too short for it fills."""
    filled = [u for r in records for u, v in ((r.get("test_scores") or {}).get(path) or {}).items() if len(v)]
    return unit if unit in filled else longest_tsa(filled) or unit


def called_takes(records: list[dict]) -> set[str]:
    """The test takes some method's decision calls (detection_level.most_called at judged_unit), as the verdict
    (detection_summary.take_lines) and `gearlab score` decide; an ensemble's members (seed or fold) are no method."""
    from .detection_level import most_called

    judged = [r for r in records if r.get("seed") is None and r.get("fold") is None]
    unit = longest_tsa(u for r in judged for u in r["thresholds"])
    out = set()
    for path in {p for r in judged for p in r["test_scores"]}:
        at = judged_unit(judged, path, unit)
        for r in judged:
            units, threshold = r["test_scores"].get(path) or {}, r["thresholds"].get(at)
            if units.get(at) and threshold is not None and most_called(units[at], threshold):
                out.add(path)
    return out


def level_call(call: str | None, ratio: float | None) -> str | None:
    """What a flag on a take means, its level *ratio* to its history's read: level_change where its *call*
    (call_of) localises nothing (no gear, no bearing-like line, not a take too short to read) and
    the ratio is more than LEVEL_OFF off; else *call* (a gear localised: its damage at any level). The one rule that
    `gearlab score`'s decisions (decision_of) and a detection run's tables (with_levels) call a level change by: a
    healthy take at twice its history's gain was NA4's false alarm in the run, 'level changed' in score."""
    return (call == NOT_LOCALISED and level_change(ratio)) or call


def with_levels(loc: dict | None, conditions: dict | None) -> dict | None:
    """localisation.json *loc* with each test take's call as level_call reads it at its level over its history's
    (conditions.json's "level_ratio": none in a run from before it was kept), for the run's tables and verdict; the
    stored file keeps the localisation's own call (what `gearlab score` of the take compares its own with)."""
    if not loc:
        return loc
    ratios = {p: r for c in (conditions or {}).values() for p, r in (c.get("level_ratio") or {}).items()}
    records = loc.get("records") or {}
    return {**loc, "records": {p: {**r, "call": level_call(r.get("call"), ratios.get(p))} for p, r in records.items()}}


def decision_of(called: bool, call: str | None, ratio: float | None = None) -> str:
    """A record's decision (`gearlab score`) from its units' majority called and its call (call_of),
    by the rule the detection run's tables count its flags with (calls_by_label): not called,
    healthy; called on a record whose change lies on another gear, that other damage ("other damage:
    output gear 71T (stage 1)"); called on a record too short to be localised, a fault of no gear ("fault, gear not
    determined: ..."); called with nothing localised and its level *ratio* to its history's more than LEVEL_OFF off,
    a level change (level_call, the run's tables' rule too: a sensor, gain or load changed), not
    damage; otherwise a fault of the watched gear (localised on it, at any level, or nowhere)."""
    if not called:
        return "healthy"
    if is_other(call) or is_undetermined(call):
        return call
    said = level_call(call, ratio)
    return said if is_level_change(said) else "fault"


def evidence(found: dict, nonsync: dict | None = None) -> str:
    """The localisation's evidence in a line: each shaft's z of its localised change over its
    threshold, strongest first, the tooth of the named shaft's gears, and the non-synchronous
    residual's z over its threshold with its strike order."""
    z = ", ".join(f"{s['shaft']} z {s['z']:.1f}/{s['threshold']:.1f}" for s in found["shafts"]) or found["summary"]
    z = f"{ENVELOPE}{z}" if found.get("seen") == "envelope" else z  # the z are the envelope's, not the averages'
    tooth = _tooth(found)
    return z + ("" if tooth == "–" else f"; tooth {tooth}") + _which(found) + "; " + nonsync_words(nonsync)


def nonsync_words(ns: dict | None) -> str:
    """A record's non-synchronous change (signals.nonsync) in words: z over the threshold, the order."""
    if not ns:
        return "non-synchronous: not read"
    if "note" in ns:  # why it was not read (signals.nonsync.too_short)
        return ns["note"]
    over = f" ({NS.PASSED})" if ns["z"] > ns["threshold"] else ""
    older = f" ({ns['threshold_from']})" if ns.get("threshold_from") else ""  # not today's rule (NonSyncHistory)
    return f"non-synchronous z {ns['z']:.1f}/{ns['threshold']:.1f}{over}{older} at order {ns['order']:.2f}"


def nonsync_history(takes: list[W.Take], table) -> NS.NonSyncHistory | None:
    """The history of the non-synchronous residual (signals.nonsync) of the history *takes*; None where they are too
    short for it (the call then rests on the shafts alone)."""
    speeds = None if any(t.speed_hz is None for t in takes) else [t.speed_hz for t in takes]
    try:
        return NS.history([t.revolutions for t in takes], table, speeds)
    except GearlabInputError:
        return None


def nonsync_of(revolutions, hist: NS.NonSyncHistory | None, table, speeds=None) -> dict | None:
    """A take's non-synchronous change against *hist* (NonSync.describe(); *speeds*: its revolutions', where read);
    None: not read; a take too short for it: why, unchanged ({"note", "changed"})."""
    if hist is None:
        return None
    try:
        return NS.nonsync(revolutions, hist, table, speeds).describe()
    except GearlabInputError as exc:
        return {"note": str(exc), "changed": False}


def localise_target(
    source: DatasetSpec, conditions: dict, histories: dict | None = None, simulator: DatasetSpec | None = None
) -> dict | None:
    """Every test record of every condition localised against the condition's history records
    (conditions as detection_records.read_target makes them, with each record's raw revolutions in
    cond["raw"]); None when the source simulates no gearbox description. *histories*, when given,
    receives each condition's (signals.localise.History, signals.nonsync.NonSyncHistory or None): what
    `gearlab score` localises with.
    *simulator*: the spec whose description and effects the which-gear events are simulated from (the
    scenario's [corrected] one: the gap diagnosis's fitted structure); None: the source's."""
    box = gearbox_of(source)
    if box is None:
        return None
    from ..gearbox import order_table

    table = order_table(box)
    watched = watched_gears(source, table)
    sim = source if simulator is None or gearbox_of(simulator) is None else simulator
    out = {"gearbox": box.name, "preset": source.preset, "watched": watched, "conditions": {}, "records": {}}
    out["shaft_orders"] = dict(zip(table.shafts, map(float, table.shaft_orders)))  # a bearing's line per shaft
    # what the events are simulated from (localise_scored simulates them alike)
    made = out["events"] = W.events(sim.preset, effect_tables(sim.effects))
    # where a tooth index counts from: the tacho mark, or without a tacho the record's first sample
    tacho = all(cond.get("tacho", True) for cond in conditions.values())
    marks = max(cond.get("marks", 1) for cond in conditions.values())
    out["tooth_from"] = (
        ("the first history record's first tacho mark" if marks > 1 else "the first tacho mark")
        if tacho
        else "each record's first sample (no tacho: a relative index)"
    )
    for name, cond in conditions.items():
        takes = {f.path: _take(cond, f.path) for role in ("history", "test") for f, _ in cond[role]}
        top = min(float(cond["max_order"]), 0.45 * POINTS)
        try:  # records too short for a spread or a band without every shaft's orders: said, not fatal
            marks = cond.get("marks", 1)  # each take turned to the first history record's tacho mark
            shaft = (cond.get("tacho_shaft", ""), cond.get("pulses", 1))  # where a tooth counts from the mark
            hist = W.history_of([takes[f.path] for f, _ in cond["history"]], table, marks, top, *shaft)
        except GearlabInputError as exc:
            out["conditions"][name] = {"history": [f.path for f, _ in cond["history"]], "note": f"not localised: {exc}"}
            continue
        out["conditions"][name] = {
            "history": [f.path for f, _ in cond["history"]],
            "thresholds": dict(zip(hist.layout.shafts, map(float, hist.thresholds))),
            "note": hist.note,
        }
        quiet = nonsync_history([takes[f.path] for f, _ in cond["history"]], table)
        out["conditions"][name]["nonsync_threshold"] = None if quiet is None else quiet.threshold
        if histories is not None:
            histories[name] = (hist, quiet)
        for f, _ in cond["test"]:
            take = takes[f.path]
            ns = nonsync_of(take.revolutions, quiet, table, take.speeds)
            made_here = None if take.speed_hz is None or take.fs is None else made
            found = W.which_gear(take, hist, table, made_here, envelope=not (ns or {}).get("changed"))
            found["turned"] = cond.get("turned", {}).get(f.path, 0)  # read off its tacho's mark: turned_tooth
            call = call_of(found, watched, ns, take.speed_hz)
            out["records"][f.path] = {"condition": name, **found, "nonsync": ns, "call": call}
    return out


def store_localisation(run, source: DatasetSpec, conditions: dict, simulator: DatasetSpec | None = None) -> None:
    """localisation.json (localise_target; the events simulated from *simulator*, the [corrected] one
    where given) and each condition's history state for `gearlab score` (scoring/localisation<i>.npz,
    named in localisation.json's condition entry as "state")."""
    from ..parts import scoring

    histories: dict = {}
    found = localise_target(source, conditions, histories, simulator)
    if found is None:
        return
    for i, (name, (hist, quiet)) in enumerate(histories.items()):
        file = f"localisation{i}.npz"
        arrays = {**hist.state(), **E.state(hist.envelope), **(quiet.state() if quiet else {})}
        scoring.save_arrays(run.file("scoring", file), **arrays)
        found["conditions"][name]["state"] = file
    described = source.preset.removeprefix(PREFIX).rpartition("#")[0] if is_reference(source.preset) else ""
    if Path(described).is_absolute():  # the user's description as simulated (a built-in's name is no file), for a
        kept = run.file(*KEPT)  # folder moved or a description edited since
        kept.parent.mkdir()
        kept.write(Path(described).read_bytes())
    run.write_json("localisation.json", found)


# The run's copy of the gearbox description it simulated (store_localisation, localisation_of)
KEPT = ("scoring", "gearbox.toml")


def localisation_of(run) -> dict | None:
    """localisation.json, its description's reference turned to the run's copy (KEPT) where the file it names is
    gone or changed: a project folder moved after the run stopped `gearlab score` with '/old/path/box.toml: no such
    gearbox description'."""
    meta = run.read_json("localisation.json")
    if not meta or not is_reference(meta.get("preset", "")):
        return meta
    spec, _, digest = meta["preset"].removeprefix(PREFIX).rpartition("#")
    kept = run.file(*KEPT)
    if (Path(spec).is_file() and reference(spec) == meta["preset"]) or not kept.exists():
        return meta
    copy = f"{PREFIX}{Path(str(kept.path)).resolve()}#{digest}"
    events = meta.get("events", W.events(meta["preset"]))
    return {**meta, "preset": copy, "events": {**events, "preset": copy}}


def _take(cond: dict, path: str) -> W.Take:
    """A record of a condition (detection_records.read_target: cond["raw"] its revolutions as cut and the
    first one's number from the angle's zero, its speed, rate and revolutions' speeds) as data.which_gear
    localises it."""
    revs, first = cond["raw"][path]
    turns = cond.get("turn_speeds", {}).get(path)  # as many as its revolutions, or none
    speeds = turns if turns is not None and len(turns) == len(revs) else None
    return W.Take(revs, int(first), cond.get("speeds", {}).get(path), cond.get("fs", {}).get(path), speeds)


def localise_scored(run, records: dict[str, list], turned: dict[str, int] | None = None) -> dict[str, dict]:
    """{path: {"named", "summary", "nonsync", "call", "evidence"}} of new records ({condition: [(path,
    data.which_gear.Take)]}) localised with the run's stored histories (store_localisation) and the
    description's simulated events at each record's speed, as the run localised its own
    (data.which_gear.which_gear); {} for a run without them. *turned*: {path: its tacho's marks a turn} of the
    takes read off their tacho's mark (their tooth: turned_tooth)."""
    from ..gearbox import order_table
    from ..parts import scoring

    meta = localisation_of(run)
    box = gearbox_of(meta["preset"]) if meta else None
    if box is None:
        return {}
    table = order_table(box)
    out = {}
    for name, recs in records.items():
        state = meta["conditions"].get(name, {}).get("state")
        if state is None:
            continue
        # the envelope's history: None for a run stored before it was read (the synchronous averages alone); the
        # residual's, None for a run stored before it was read; one this gearlab cannot read: why, in every row
        hist, quiet, why, unread = saved_histories(scoring.load_arrays(run.file("scoring", state)), table)
        # a run stored before the events' simulator was said: the source's description, no effects
        made = meta.get("events", W.events(meta["preset"]))
        for path, take in recs:
            if hist is None:
                out[path] = not_read(why)
                continue
            ns = nonsync_of(take.revolutions, quiet, table, take.speeds)
            found = W.which_gear(take, hist, table, made, envelope=not (ns or {}).get("changed"))
            found["turned"] = (turned or {}).get(path, 0)
            out[path] = {
                "named": W.named_gears(found),  # damage on two shafts: both, as the run's table names them
                "summary": found["summary"],
                "nonsync": ns,
                "call": call_of(found, meta["watched"], ns, take.speed_hz),
                "evidence": evidence(found, ns) + (f"; {unread}" if unread else ""),
            }
    return out


def not_read(why: str) -> dict:
    """localise_scored's entry of a take not localised against its condition's history, *why* in words ("+10.0 %
    off the history's 33.00 Hz"): no gear named, a flag on it a fault of no gear (decision_of)."""
    return {
        "named": None,
        "summary": f"not read: {why}",
        "nonsync": None,
        "call": f"{UNDETERMINED}: {why}",
        "evidence": f"not read: {why}",
    }


def stale_calls(run, localised: dict[str, dict]) -> dict[str, str]:
    """{path: a line} for each of the run's own test takes (its localisation.json's records, their paths under the run's
    base) that *localised* (localise_scored: `gearlab score` of them now) calls otherwise than the run's table did:
    the table was decided by the which-gear rule of the day the run was made, score by today's, on the same stored
    history (box T's 24T spall: the run's 'undecided (63T 0.17 / 24T 0.15)', made before the rule read a two-gear
    shaft's own sidebands first, against score's '24T')."""
    from pathlib import Path

    made, base = run.read_json("localisation.json") or {}, run.base()
    own = {}
    for path, found in (made.get("records") or {}).items():
        at = Path(path) if base is None or Path(path).is_absolute() else base / path
        own[str(at.resolve())] = found.get("call")
    out = {}
    for path, found in localised.items():
        was = own.get(str(Path(path).resolve()), found["call"])
        if was != found["call"]:
            out[path] = (
                f"the run's table called it '{was}' when the run was made; this gearlab's which-gear rule "
                f"calls it '{found['call']}': run the scenario again for its table to read as score does"
            )
    return out


def _tooth(found: dict) -> str:
    if found["named"] is None:
        return "–"
    ev = next(s for s in found["shafts"] if s["shaft"] == found["named_shaft"])
    on = [ev["which"]] if ev.get("which") else ev["gears"]
    marks = found.get("turned")  # read off its tacho's mark, of so many marks a turn: turned_tooth
    teeth = [ev["tooth"][g] for g in on if g in ev["tooth"]]
    words = [turned_tooth(t, marks) if marks else L.tooth_words(t) for t in teeth]
    return " / ".join(words) or "–"


def turned_tooth(t: dict, marks: int = 1) -> str:
    """The tooth *t* of a take read off its tacho's mark (signals.checks.off_mark_line: the box running the other
    way?), where fixed to the mark: its teeth pass the mark the other way, so the count from it is the tooth's mirror,
    z - pitches, as its history counts (within a tooth: the tacho triggers on the mark's other edge); the count the way
    the take turns beside it. A 16/37 + 28/71 box's input pinion chipped 0.37 turn on: '11 of 16' read alone. With
    *marks* > 1 a turn the take is turned to whichever mark its average matches best, so the mirror is about no known
    point: the tiny test box's chip (2 of 25 forward, 10 marks a turn) read '19 of 25' so; the count as it turns."""
    if not t.get("mark"):
        return L.tooth_words(t)
    if marks > 1:
        return (
            f"{t['tooth']} of {t['of']} counted the way this take turns (read off its tacho's mark: which of its "
            f"{marks} marks a turn its history counts from is not known)"
        )
    mirrored = int(math.floor(t["of"] - t["pitches"])) % t["of"] + 1
    return (
        f"{mirrored} of {t['of']} if the box runs the other way (counted from the tacho's mark as its history turns, "
        f"within a tooth; {t['tooth']} of {t['of']} counted the way this take turns)"
    )


def _which(found: dict) -> str:
    """The named shaft's evidence for which of its two gears ("" for a one-gear shaft)."""
    if found["named"] is None:
        return ""
    ev = next(s for s in found["shafts"] if s["shaft"] == found["named_shaft"])
    return L.which_line(ev.get("stage_evidence", {}), ev.get("which"))


def flagged_takes(records: list[dict]) -> set[str]:
    """The test takes some method flagged: a unit of the longest TSA over that method's threshold (the units
    calls_by_label counts)."""
    unit = longest_tsa(u for r in records for u in r["thresholds"])
    return {
        path
        for r in records
        if unit in r["thresholds"]
        for path, units in r["test_scores"].items()
        if np.any(np.asarray(units[unit], dtype=np.float64) > r["thresholds"][unit])
    }


def records_md(loc: dict, labels: dict, flagged: set[str]) -> str:
    """Per test record: its label, the gear its change is localised on with the evidence (each
    shaft's z against its threshold, the tooth, the non-synchronous residual's z against its threshold
    and its strike order), and what a flag on it would be called: 'not flagged' where no method
    flagged it (*flagged*, flagged_takes), as a healthy take's call alone read as a fault."""
    if not loc or not loc["records"]:
        return ""
    out = [
        f"\nWhich gear (each test record against its condition's history; watched: {', '.join(loc['watched'])}; "
        "z of each shaft's localised change over its threshold; the tooth counted from "
        f"{loc.get('tooth_from', 'the first tacho mark')}; a flag on a record whose change lies on another gear "
        "is other damage; which of a shaft's two gears: the rule and its evidence; non-synchronous: the envelope of "
        "the record less every shaft's synchronous average, z / threshold at its strike order in input orders, a "
        f"change there without a localised one is other damage ({NS.PASSED}))\n",
        "| condition | file | label | localised on | z / threshold per shaft | tooth | which gear | non-synchronous "
        "z / threshold (order) | a flag would be called |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for path, r in loc["records"].items():
        z = ", ".join(f"{s['shaft']} {s['z']:.1f}/{s['threshold']:.1f}" for s in r["shafts"])
        z = f"{ENVELOPE}{z}" if r.get("seen") == "envelope" else z
        on = "; ".join(e["gear"] for e in W.flagged_shafts(r))  # every gear over its threshold, the named first
        # not read (a take too short for the check): said so, not 'nothing' beside a call with no evidence
        unread = not r["shafts"] and r.get("summary", "").startswith("not localised: ")
        on = on or (r["summary"].replace("not localised: ", "not read: ", 1) if unread else "nothing")
        out.append(
            f"| {r['condition']} | {path} | {labels.get(path, '')} | {on} | {z} | "
            f"{_tooth(r)} | {_which(r).removeprefix('; ') or '–'} | {_nonsync_cell(r.get('nonsync'))} | "
            f"{r['call'] if path in flagged else NOT_FLAGGED} |"
        )
    return "\n".join(out) + "\n"


def _nonsync_cell(ns: dict | None) -> str:
    return "–" if not ns or "note" in ns else f"{ns['z']:.1f}/{ns['threshold']:.1f} ({ns['order']:.2f})"


def calls_by_label(loc: dict, records: list[dict], labels: dict, positive: str = "fault") -> list[dict]:
    """Per condition and method, for the longest TSA: of each test label's units, the % called a
    watched-gear fault, the % called other damage (the record's change localised elsewhere; on a
    watched gear and another gear: counted in both), the % called a fault of no gear (``undetermined``:
    a record too short for the which-gear check) and the % called a level change (``level``: nothing localised, the
    take's level off its history's: with_levels, its takes ``level_changes``: {path: call}), the
    units, and those on records called neither other damage nor a level change (``judged``: what a false alarm is
    counted of); the AUC of the same units the detected and false-alarm figures count (``auc``: every *positive*
    take's against the other labels' judged takes) and the takes it leaves out (``left_out``: {path: call})."""
    if not loc or not records:
        return []
    unit = longest_tsa(u for r in records for u in r["thresholds"])
    out = []
    for r in records:
        if unit is None or unit not in r["thresholds"]:
            continue
        thr = r["thresholds"][unit]
        watched: dict[str, list[int]] = {}
        other: dict[str, list[int]] = {}
        undetermined: dict[str, list[int]] = {}
        level: dict[str, list[int]] = {}
        level_changes: dict[str, str] = {}
        judged: dict[str, int] = {}
        ranked: dict[bool, list] = {True: [], False: []}  # the positive takes' units, the judged negatives'
        left_out: dict[str, str] = {}
        for path, units in r["test_scores"].items():
            s = np.asarray(units[unit], dtype=np.float64)
            flagged = s > thr
            call = loc["records"].get(path, {}).get("call")
            elsewhere, also = is_other(call), is_also_other(call)  # also: the watched gear's and other damage
            unread, moved = is_undetermined(call), is_level_change(call)
            label = labels[path]
            watched.setdefault(label, []).extend((flagged & ~elsewhere & ~unread & ~moved).astype(int).tolist())
            undetermined.setdefault(label, []).extend((flagged & unread).astype(int).tolist())
            other.setdefault(label, []).extend((flagged & (elsewhere or also)).astype(int).tolist())
            level.setdefault(label, []).extend((flagged & moved).astype(int).tolist())
            if moved:
                level_changes[path] = call
            judged[label] = judged.get(label, 0) + (0 if elsewhere or moved else len(s))
            # a negative take called other damage or a level change leaves the AUC as it leaves the false alarms (it
            # counted as a negative there, its flags ranked as false alarms the false-alarm figure does not count)
            if label == positive or not (elsewhere or moved):
                ranked[label == positive].append(s)
            else:
                left_out[path] = call
        out.append(
            {
                "condition": r["condition"],
                "method": r["method"],
                "unit": unit,
                "watched": {k: 100.0 * float(np.mean(v)) if v else None for k, v in watched.items()},
                "other": {k: 100.0 * float(np.mean(v)) if v else None for k, v in other.items()},
                "undetermined": {k: 100.0 * float(np.mean(v)) if v else None for k, v in undetermined.items()},
                "level": {k: 100.0 * float(np.mean(v)) if v else None for k, v in level.items()},
                "level_changes": level_changes,
                "units": {k: len(v) for k, v in watched.items()},
                "judged": judged,
                "auc": auc(*(np.concatenate(ranked[k] or [np.empty(0)]) for k in (False, True))),
                "left_out": left_out,
            }
        )
    return out


def calls_md(calls: list[dict]) -> str:
    """calls_by_label as a table: 'watched % / other %' per label, '/ not determined %' beside them where a record
    was too short for the which-gear check, '/ level change %' where a take's level was off its history's with nothing
    localised (its takes counted under the table: the raw called % is labels_md's)."""
    if not calls:
        return ""
    labels = list(dict.fromkeys(k for c in calls for k in c["watched"]))
    unit = calls[0]["unit"]
    unread = any(v for c in calls for v in (c.get("undetermined") or {}).values())
    moved = {p: w for c in calls for p, w in (c.get("level_changes") or {}).items()}
    head, said = ("", "")
    if unread:
        head, said = " / not determined", "; gear not determined: a record too short for the which-gear check"
    if moved:
        head += " / level change"
        said += f"; level change: {LEVEL_WORDS}, set aside from the watched gear's rates (the raw: the 'det % / "
        said += "FA %' and 'called %' tables)"
    out = [
        f"\nUnits called (% of each test label's {unit} units): a watched-gear fault / other damage (the "
        f"record's change localised on another gear; on a watched gear and another: counted in both){said}\n",
        f"| {unit}: condition | method | " + " | ".join(f"'{k}' watched / other{head} %" for k in labels) + " |",
        "|---|---|" + "---|" * len(labels),
    ]
    for c in calls:
        cells = []
        for k in labels:
            w, o, u = c["watched"].get(k), c["other"].get(k), (c.get("undetermined") or {}).get(k)
            level = f" / {(c.get('level') or {}).get(k) or 0:.0f}" if moved else ""
            cells.append("–" if w is None else f"{w:.0f} / {o:.0f}" + (f" / {u or 0:.0f}" if unread else "") + level)
        out.append(f"| {c['condition']} | {c['method']} | " + " | ".join(cells) + " |")
    if moved:
        takes = ", ".join(f"{p} ({level_factor(w)} x)" for p, w in moved.items())
        out.append(f"\nSet aside as a level change: {len(moved)} take{'s' * (len(moved) > 1)}: {takes}")
    return "\n".join(out) + "\n"


def which_gear_summary(loc: dict | None, records: list[dict], labels: dict, positive: str = "fault") -> dict:
    """What summary.json and table.md say of it: each test record's localisation and call, the
    units called a watched-gear fault or other damage per method and label (*positive*: the fault's
    label), and their tables."""
    if not loc:
        return {}
    calls, called = calls_by_label(loc, records, labels, positive), called_takes(records)
    return {
        "gearbox": loc["gearbox"],
        "watched": loc["watched"],
        "shaft_orders": loc.get("shaft_orders"),
        # each take's call as decided: no flag's name on a take no method calls (decided_call), as `gearlab score` says
        "records": {
            p: {k: r.get(k) for k in ("condition", "named", "summary", "nonsync")}
            | {"call": decided_call(r.get("call"), p in called)}
            for p, r in loc["records"].items()
        },
        "calls": calls,
        "md": records_md(loc, labels, flagged_takes(records)) + calls_md(calls),
    }
