"""The detection kind's measured records (gearlab.kinds.detection): the target's records grouped
by operating condition, standardised against and aligned to each condition's history, cut into
the units that are scored (every revolution, TSAs of blocks of revolutions), and what a learned
method sees of them and of its training rows."""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ..data import which_gear as W
from ..data.chain import Chain
from ..data.channel_units import TOO_LOUD, TOO_QUIET
from ..data.spec import DatasetSpec
from ..errors import GearlabInputError
from ..events import Event
from ..executors import LocalExecutor
from ..learn.protocol import Protocol
from ..parts.measured import ROLES, Target, TargetFile, aligned
from ..scenario import location
from ..signals import Standardiser
from ..signals.angle import continued
from ..signals.checks import UNSEEN_WORDS, VARIES_WORDS, read_off_mark, turned_line
from ..signals.indicators import band_limited, difference_signal
from ..signals.shaft import shaft_revolutions, without_input_orders
from ..signals.spikes import without_spikes
from . import record_effects
from .common import SPEED_GROUP
from .detection_in_band import cut_run_ups, span, steady_histories, too_narrow
from .detection_level import level_warnings, run_levels
from .detection_settings import Classical

# Sliding TSA windows of the history: a new window every block/HISTORY_STRIDES revolutions.
HISTORY_STRIDES = 10
# Fewest history units of a kind that a threshold may be fitted to (by their quartiles).
MIN_HISTORY_UNITS = 8


def varies(how: str) -> str:
    """Of a record's speed source *how* (cut_recording's angle_source), its run-up words: ' (20.26 Hz .. 34.86 Hz
    over the take: a run-up: ...)', else ""."""
    return f" ({how.split('; ')[-1]})" if VARIES_WORDS in how or UNSEEN_WORDS in how else ""


def too_few_units(where: str, name: str, cond: dict, shaft, count: int, unit: str) -> str:
    """The line refusing condition *name*'s history of *count* '*unit*' units (MIN_HISTORY_UNITS needed), with its
    longest record's turns of the units' *shaft* and the steady part of each take cut to one."""
    longest = max(len(r) for _, r in cond["history"])
    on = "" if shaft is None else f" {shaft.name}-shaft"
    # a take cut to its steady part: how much of it, here (validate refuses it too, before any log line)
    used = cond.get("scored_on", {})
    cut = [
        f"{f.path}: " + used[f.path].removeprefix("used ").removesuffix(" (steady part)")
        for f, _ in cond["history"]
        if f.path in used
    ]
    steady = f"; steady parts used: {', '.join(cut)}" if cut else ""
    return (
        f"{where}: the history of condition '{name}' gives {count} '{unit}' units "
        f"(its longest record has {longest}{on} revolutions{steady}); expected at least "
        f"{MIN_HISTORY_UNITS}: longer records, or shorter [detection] blocks"
    )


@dataclass(frozen=True)
class UnitShaft:
    """The shaft whose revolutions the detection's units are (unit_shaft): its name, its turns per
    input turn, and the watched gear on it."""

    name: str
    ratio: Fraction
    gear: str

    def revolutions(self, revs: np.ndarray, max_order: float | None = None, first: int = 0) -> np.ndarray:
        """This shaft's complete revolutions from a record's consecutive input revolutions *revs*, the
        first its input revolution *first* (unit_revolutions)."""
        return unit_revolutions(revs, self.ratio.numerator, self.ratio.denominator, max_order, first=first)

    def said(self) -> str:
        return f"the {self.name} shaft ({self.gear}; {float(self.ratio):.4g} turns per input turn)"


# Fewest revolutions of the units' shaft a record needs for the input shaft's own content to be taken
# out of it (without_input_shaft): the input TSA then holds that shaft's content at 1/30 or less.
OTHER_SHAFT_TURNS = 30


def without_input_shaft(revs: np.ndarray, p: int, q: int) -> np.ndarray:
    """A record's consecutive input revolutions *revs* less what their average (the input TSA) holds at
    the input orders that are no whole order of a shaft turning p/q per input turn (p, q coprime: the
    input orders that are no multiple of p): the input shaft's own runout and mesh sidebands, which
    that shaft's TSA averages away only over many of its turns. A 54/107 reducer's output shaft
    (development box K) sees the input's second order at 1.981 of its own: a TSA of 30 output turns
    keeps it at 0.57 of a cycle of drift, the healthy record30 units' residual rms 0.162 m/s^2 where
    the chip's signature is 0.038 (FM4 of healthy and chipped units 5.5-7.2 alike); with it taken out,
    0.071, and the chipped units' kurtosis 7-40 against the healthy 4.4-5.3 (generator truth angles,
    12 takes each). The mesh harmonics (whole orders of both shafts) and the units' shaft's own
    content stay; a record of fewer than OTHER_SHAFT_TURNS turns of that shaft is left as it is."""
    if p == q or len(revs) * p < OTHER_SHAFT_TURNS * q:
        return revs
    return without_input_orders(revs, p).astype(revs.dtype)


def unit_revolutions(
    revs: np.ndarray, p: int, q: int, max_order: float | None, input_out: bool = True, first: int = 0
) -> np.ndarray:
    """The revolutions of a shaft turning p/q per input turn from a record's consecutive input revolutions *revs*
    (signals.shaft), with the input shaft's own content taken out first (*input_out*: without_input_shaft; a run
    made before it: False, as `gearlab score` reads it). *first*: revs[0]'s number from the take's angle zero
    (CutRecording.first_revolution): the shaft's turns counted from that zero, as the source's rows' are
    (data.builder.shaft_row), a take whose first revolutions are left out (a run-up's, a start-up's) is cut into
    the same turns as whole."""
    if input_out:
        revs = without_input_shaft(revs, p, q)
    return shaft_revolutions(revs, p / q, (first * p % q) / q, revs.shape[-1], max_order)


def unit_shaft(source: DatasetSpec) -> UnitShaft | None:
    """The shaft carrying the watched gear -- the gear the source's fault classes sit on -- when it
    is not the input shaft: a once-per-turn event of a slower shaft lands at another input angle
    every input revolution and an input TSA averages it away, so the units are that shaft's
    revolutions and TSAs (history, test and source alike). None: the input shaft (every unit as
    before), also when the faults sit on gears of more than one shaft."""
    from ..data.placement import gear_name, shaft_names, train_pairs

    classes = source.fault_classes().values()
    on = {(c.stage, c.gear) for c in classes}
    shafts = {stage - (gear == "pinion") for stage, gear in on}  # shaft index: input 0
    if len(shafts) != 1 or shafts == {0}:
        return None
    (index,) = shafts
    model, _, _ = source.check_model()
    pairs = train_pairs(model, source.preset)
    ratio = Fraction(1)
    for pair in pairs[:index]:
        ratio *= Fraction(pair.Z1, pair.Z2)
    names = shaft_names(source.preset, len(pairs))
    gears = ", ".join(dict.fromkeys(gear_name(stage, gear, names) for stage, gear in sorted(on)))
    return UnitShaft(names[index], ratio, gears)


# A user's gearbox whose watched gear, a later stage's pinion, the simulator takes tooth by tooth: the
# teeth simulated when the [source] names none (watched_teeth).
WATCHED_TEETH = 6


def watched_teeth(source: DatasetSpec, written: dict) -> DatasetSpec:
    """*source* (a [source] table *written* as the user wrote it) with WATCHED_TEETH teeth of its watched
    gear spread around it, each sample WATCHED_TEETH-fold fewer teeth's times as many duplicates, when
    the source simulates a gearbox description, its watched gear a later stage's pinion that the model
    takes one tooth at a time (no tooth-shift symmetry), and the table gives neither 'teeth' nor
    'duplicates'; else *source*. A cost bound, not a symmetry: each tooth's chip sits at its own angle
    of its shaft's revolution (data.builder's shaft rows, 5c7e946), so the rows hold WATCHED_TEETH
    angles of the gear, each its own simulation; every tooth of a 68/103 + 82/99 reducer's 82T
    intermediate pinion would be 82 x 3 sizes, 247 simulations (57 min at --quick on 2 cores), these
    19 (the detectors' shapes turned by the pitches between: tooth_gap). Kept whole: a wheel's teeth and
    the input pinion's, and a shaft whose meshes share a divisor g > 1 (shaft_symmetry turns the
    detectors' shapes by 1/g for the teeth simulated)."""
    if not written.get("gearbox") or "teeth" in written or "duplicates" in written or not source.faults:
        return source
    from ..data.placement import train_pairs

    model, _, _ = source.check_model()
    if not (source.effect_chain().breaks_symmetry or getattr(model, "breaks_symmetry", False)):
        return source  # one simulation a size serves every tooth
    classes = list(source.fault_classes().values())
    if {(c.stage > 1, c.gear) for c in classes} != {(True, "pinion")} or len({c.stage for c in classes}) != 1:
        return source
    shaft = unit_shaft(source)
    if shaft is None or math.gcd(*unit_mesh_orders(source, shaft)) > 1:
        return source
    z = train_pairs(model, source.preset)[classes[0].stage - 1].Z1
    if z <= WATCHED_TEETH:
        return source
    teeth = tuple(1 + (k * z) // WATCHED_TEETH for k in range(WATCHED_TEETH))
    return source.with_(teeth=teeth, duplicates=source.duplicates * math.ceil(z / WATCHED_TEETH))


def unit_mesh_orders(source: DatasetSpec, shaft: UnitShaft | None) -> list[int]:
    """The default [classical] mesh_orders of the units' shaft: the input pinion's teeth on the input
    shaft; on another, the watched gear's teeth first, then every mesh whose order on that shaft is
    whole (the other gear of the shaft, the meshes of the shafts beside it)."""
    _, pair, _ = source.check_model()
    if shaft is None:
        return [pair.Z1]
    from ..data.placement import train_pairs

    model, _, _ = source.check_model()
    pairs = train_pairs(model, source.preset)
    first = [c for c in source.fault_classes().values()][0]
    watched = pairs[first.stage - 1].Z1 if first.gear == "pinion" else pairs[first.stage - 1].Z2
    turns, orders = Fraction(1), [watched]
    for p in pairs:
        order = turns * p.Z1 / shaft.ratio
        if order.denominator == 1 and int(order) not in orders:
            orders.append(int(order))
        turns *= Fraction(p.Z1, p.Z2)
    return orders


def shaft_symmetry(source: DatasetSpec, shaft: UnitShaft) -> int:
    """g: the turns by 1/g of a revolution of the units' shaft that leave its synchronous healthy
    signal as it is -- g the greatest common divisor of the meshes whole on that shaft
    (unit_mesh_orders: 65 for a 27/88 + 22/65 hoist's output shaft, meshes 65 and 260; 1 for a
    26/73 + 33/59 reducer's intermediate one, 73 and 33). Turning a record into the source's
    frame by its healthy mean revolution knows its angle to 1/g turn only. 1 also when the
    source's teeth already hold every such turn of each other (each tooth's and those Z/g teeth
    on: every tooth, or every other tooth of the tests' 50T gear with g = 25), where more shapes
    of one place only raise the healthy revolutions' best correlation."""
    g = math.gcd(*unit_mesh_orders(source, shaft))
    for c in source.fault_classes().values():
        z = c.pair.Z1 if c.gear == "pinion" else c.pair.Z2
        teeth = set(c.teeth)
        if any((t - 1 + z // g) % z + 1 not in teeth for t in teeth):
            return g
    return 1


def tooth_gap(source: DatasetSpec) -> tuple[int, int]:
    """(Z, d): the watched gear's teeth and the widest gap, in tooth pitches, between two of its teeth the source
    simulates (1: every tooth). Each tooth's damage strikes at its own angle of its shaft's revolution (no
    tooth-shift symmetry on a later shaft: watched_teeth), so a detector whose shapes hold teeth 1 and 31 of a
    62T intermediate gear alone matched a broken tip on another tooth nowhere: [source] teeth = [1, 31], five
    such takes, matched_filter called 10 % of their record30 units, fm4 and na4 100 % (every tooth simulated,
    or the shapes turned by the pitches between, turned_faults: 100 %)."""
    first = next(iter(source.fault_classes().values()))
    z = first.pair.Z1 if first.gear == "pinion" else first.pair.Z2
    teeth = sorted(set(first.teeth))
    return z, max((b - a) % z or z for a, b in zip(teeth, teeth[1:] + teeth[:1]))


def turned_faults(X: np.ndarray, y: np.ndarray, g: int, count: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The fault rows of (*X*, *y*) (rows, or rows of draws) also turned by every k/g of a
    revolution, k = 1 ... count - 1 (*count*: g, every turn; an exact band-limited turn: the rows
    are periodic), appended: a detector's shapes then hold the damage at every angle the turn into
    the source's frame may put a record's (shaft_symmetry), or on every tooth of the watched gear
    (g its teeth, count the widest gap between those simulated: tooth_gap), where simulating every
    tooth of a gear on a slower shaft (which the two-stage models simulate one by one) costs a
    simulation a tooth."""
    faults = np.asarray(X)[np.asarray(y) != 0]
    count = g if count is None else min(count, g)
    if count <= 1 or not len(faults):
        return X, y
    n = faults.shape[-1]
    F = np.fft.rfft(faults, axis=-1)
    orders = np.arange(F.shape[-1])
    turned = [
        np.fft.irfft(F * np.exp(-2j * np.pi * orders * k / g), n=n, axis=-1).astype(faults.dtype)
        for k in range(1, count)
    ]
    ones = np.ones(len(faults) * (count - 1), dtype=np.asarray(y).dtype)
    return np.concatenate([X, *turned]), np.concatenate([y, ones])


def conditions_of(files: list[TargetFile], speeds: dict[str, float]) -> dict[str, str]:
    """{file path: condition}: the file's own 'condition', else its speed group. History records
    without one are grouped by speed -- the tacho's, declared, or found from the mesh orders -- (a
    group spans SPEED_GROUP of its slowest record's speed; named by its median, as measured: speed_name);
    a test record joins the group of nearest speed, or one of its own (which has no history) when none
    lies within SPEED_GROUP of it."""
    out = {f.path: f.condition for f in files if f.condition}
    groups: list[list[float]] = []
    for v in sorted(speeds[f.path] for f in files if not f.condition and f.role == "history"):
        if groups and v <= groups[-1][0] * (1 + SPEED_GROUP):
            groups[-1].append(v)
        else:
            groups.append([v])
    centres = [float(np.median(g)) for g in groups]
    for f in files:
        if f.condition:
            continue
        v = speeds[f.path]
        near = min(range(len(centres)), key=lambda i: abs(centres[i] - v)) if centres else None
        if near is not None and abs(centres[near] - v) <= SPEED_GROUP * centres[near]:
            v = centres[near]
        out[f.path] = speed_name(v)
    return out


def speed_name(hz: float) -> str:
    """A condition's name from its measured speed: to 1 Hz where that is within 0.5 % of it ('30 Hz'),
    else to 0.1 Hz or 0.01 Hz: a 1500 rpm motor slipping to 24.6 Hz is '24.6 Hz', not its nominal '25 Hz'."""
    for digits in (0, 1):
        if abs(round(hz, digits) - hz) <= 0.005 * hz:
            return f"{hz:.{digits}f} Hz"
    return f"{hz:.2f} Hz"


def tsa_units(revs: np.ndarray, block: int, stride: int | None = None) -> np.ndarray:
    """TSAs of *block* consecutive revolutions: non-overlapping blocks (stride = block), or sliding
    windows moved by *stride* revolutions."""
    stride = stride or block
    starts = range(0, revs.shape[0] - block + 1, stride)
    if not len(starts):
        return np.empty((0, revs.shape[1]), dtype=revs.dtype)
    return np.stack([revs[s : s + block].mean(axis=0) for s in starts]).astype(revs.dtype)


def unit_window(unit: str) -> tuple[int, int]:
    """(revolutions per unit, stride of the history's sliding windows) of a unit kind."""
    if unit == "revolution":
        return 1, 1
    b = int(unit.removeprefix("record"))
    return b, max(1, b // HISTORY_STRIDES)


def longest_tsa(units) -> str | None:
    """The record-level unit kind of the most revolutions among *units* ("record30" of
    "revolution", "record10", "record30"); None when there is none."""
    records = [u for u in dict.fromkeys(units) if u != "revolution"]
    return max(records, key=lambda u: unit_window(u)[0]) if records else None


def unit_sets(revs: np.ndarray, blocks, history: bool) -> dict[str, np.ndarray]:
    """{unit name: rows} of one record."""
    out = {"revolution": revs}
    for b in blocks:
        out[f"record{b}"] = tsa_units(revs, b, max(1, b // HISTORY_STRIDES) if history else None)
    return out


def read_target(
    target: Target,
    blocks,
    on_event,
    where: str = "[target] key 'files'",
    shaft: UnitShaft | None = None,
    continuous: bool = False,
    executor=None,
    structure=None,
) -> dict[str, dict]:
    """{condition: {"history": [(file, revolutions)], "test": [...], "speeds": {...}}}: every record
    read, standardised against its condition's history and aligned to its first history record.
    With a *shaft* (unit_shaft) the revolutions are that shaft's (cut from the record's input
    revolutions; cond["raw"] keeps those for the localisation), aligned by correlation: the input
    tacho's mark is no fixed angle of a slower shaft; *continuous*: each record shifted as one signal
    (aligned). Only the records' signals are used here (no label). *executor*: a local pool reads the
    records side by side (phm09_chip: 24 records, 6.8 s of CPU in this process, a core idle). *structure*:
    {name: cond} -> the line of what a condition's history contradicts in the description, or None
    (check_structure), said before a history too short for its units."""
    conditions: dict[str, dict] = {}
    total = len(target.files)
    on_event(Event("stage", stage="records", total=total, message="measured records"))
    done = iter(range(1, total + 1))

    def read(_: int, record) -> None:
        on_event(Event("advance", stage="records", done=next(done), total=total))

    # this machine's pool only (a Ray cluster's nodes may not see the files); else in this process
    pool = executor if isinstance(executor, LocalExecutor) else LocalExecutor(1)
    got = pool.map(target.read, target.files, on_done=read)
    records = {f.path: r for f, r in zip(target.files, got)}
    # a run-up or coast-down: a history one cut to its steady part before the takes are grouped by speed (a recording
    # that starts with a run-up: its mean speed is not its steady part's), refused where none holds a unit; a test
    # one cut to its revolutions at a history's speed (as `gearlab score` cuts one); before, scored whole
    turns = 1.0 if shaft is None else float(shaft.ratio)
    scored_on = steady_histories(target.files, records, blocks, turns, where)
    speeds = {p: r.speed_hz for p, r in records.items()}
    named = conditions_of(list(target.files), speeds)
    scored_on |= cut_run_ups(target.files, records, named, blocks, turns, where)
    speeds = {p: r.speed_hz for p, r in records.items()}
    for f in target.files:
        cond = conditions.setdefault(named[f.path], {"history": [], "test": [], "speeds": {}, "speed_from": {}})
        rec, turns = records[f.path], 1.0 if shaft is None else float(shaft.ratio)
        cond[f.role].append((f, without_spikes(rec.revolutions, rec.fs, rec.speed_hz, turns)))
        cond["speeds"][f.path] = speeds[f.path]
        cond.setdefault("fs", {})[f.path] = records[f.path].fs  # the rate the which-gear templates are read at
        # how the record's shaft angle was found: its tacho, a declared speed, the mesh orders
        cond["speed_from"][f.path] = records[f.path].angle_source
        if f.path in scored_on:  # its speeds' span, and the revolutions scored (in_band), as gearlab score says them
            how = records[f.path].angle_source
            cond["speed_from"][f.path] = f"{how.rsplit('; ', 1)[0]}; {span(how)}; {scored_on[f.path]}"
            cond.setdefault("scored_on", {})[f.path] = scored_on[f.path]
        # as cut: a run-up's speed is its steady part's, not its mean (a 15 % sweep about 30 Hz: 30.771 Hz)
        on_event(Event("log", message=f"{f.path}: {speeds[f.path]:.3f} Hz, from {cond['speed_from'][f.path]}"))
        # as cut, before standardising and aligning (which rotate each revolution): what
        # localisation reads (detection_which_gear), with the first revolution's number from the tacho
        # mark (on its own shaft; without a tacho, from the record's first sample)
        # (a followed angle's unsettled ends out: Take.of; each revolution's speed: a hum told from a bearing, nonsync)
        take = W.Take.of(records[f.path])
        cond.setdefault("raw", {})[f.path] = (take.revolutions, take.first)
        cond.setdefault("turn_speeds", {})[f.path] = take.speeds
    for name, cond in conditions.items():
        if not cond["history"]:
            # a history that contradicts the description said first: every take's speed read off its wrong tooth
            # count, a take lands where no history is (a 21/86 + 25/92 box described with 22 teeth: a damaged take
            # read at 5.76 Hz, '5 x M1', stopped the run with 'condition '5.76 Hz' ... has no history record')
            held = {n: {**c, "max_order": _max_order(c, records)} for n, c in conditions.items() if c["history"]}
            if structure is not None and held and (differs := structure(held)):
                raise GearlabInputError(differs)
            # a run-up's speeds said here too: the TUI shows a failed run's last line alone (gearlab score's does)
            files = ", ".join(f.path + varies(cond["speed_from"][f.path]) for f, _ in cond["test"])
            raise GearlabInputError(
                f"{where}: condition '{name}' ({files}) has no history record; "
                "each condition needs its own healthy history (give 'condition' to group files)"
            )
        # kept in conditions.json: the report and the TUI say them too; a run-up grouped by hand (condition = ...)
        # is one (its speed line alone said so, and the TUI's Results show no speed line where a tacho gave them)
        said = [(f.path, cond["speed_from"][f.path]) for f, _ in cond["history"] + cond["test"]]
        cut = cond.get("scored_on", {})
        cond["warnings"] = [
            f"{p}: {span(records[p].angle_source)}; {cut[p]}" if p in cut else f"{p}: {how.split('; ')[-1]}"
            for p, how in said
            if VARIES_WORDS in how or UNSEEN_WORDS in how  # a run-up without a tacho: read whole, warned of too
        ]
        # and each take's millivolts read as volts, or volts as millivolts (channel_units.level_hint)
        cond["warnings"] += level_warnings(cond)
        cond["level_ratio"], cond["level_spread"], cond["level_reference"] = run_levels(cond)  # said of a called take
        taken = [(f.path, records[f.path].units) for f, _ in cond["history"] + cond["test"]]
        cond["warnings"] += [f"{p}: {u.split('; ')[-1]}" for p, u in taken if TOO_LOUD in u or TOO_QUIET in u]
        cond["warnings"] += [f"{p}: {w}" for p, _ in taken for w in records[p].warnings]  # clipped, a dropout, a drift
        for line in cond["warnings"]:
            on_event(Event("log", message=f"warning: {line}"))
        # The highest order every history record holds, where the acquisition's anti-alias filter
        # leaves data (as the gap kind compares).
        cond["max_order"] = _max_order(cond, records)
        for f, _ in cond["test"]:  # sampled too slowly for that band: refused (too_narrow), as gearlab score does
            too_narrow(
                f.path, records[f.path].fs, speeds[f.path], cond["max_order"], f"{where} entry {f.entry} key 'file': "
            )
        # the same band in the units' shaft orders (what the learned methods see: learned_input)
        cond["unit_max_order"] = cond["max_order"] if shaft is None else int(cond["max_order"] / shaft.ratio)
        if shaft is not None:  # the units: that shaft's revolutions, in the records' band
            for role in ROLES:
                cond[role] = [
                    (f, shaft.revolutions(r, cond["max_order"], records[f.path].first_revolution))
                    for f, r in cond[role]
                ]
        if not any(len(r) for _, r in cond["history"]):  # not one turn of the units' shaft (a slow output, short takes)
            raise GearlabInputError(too_few_units(where, name, cond, shaft, 0, "revolution"))
        standardiser = Standardiser.fit(np.concatenate([r for _, r in cond["history"]]))
        reference = standardiser.apply(cond["history"][0][1]).mean(axis=0)
        cond["standardiser"], cond["reference"] = standardiser, reference  # kept for gearlab score
        # records aligned by the tacho's marks when every one has a tacho (else as records without one are)
        cond["shifts"], cond["tacho"] = {}, target.tacho_all
        cond["marks"] = target.marks if target.tacho_all else 1  # localisation turns to a mark
        pulses = max(target.keys_of(f)["pulses_per_rev"] for f in target.files)  # (which gear: one mark a turn?)
        cond["tacho_shaft"], cond["pulses"] = (
            ((target.read_as or "input") if target.tacho_all else ""),
            max(pulses, target.pulses_per_rev),
        )
        # the shaft the units are revolutions of, and whether their angle is a tacho's (else turned
        # into the source's frame: detection.run, register_to_source)
        cond["unit_shaft"] = "input" if shaft is None else shaft.name
        cond["unit_tacho"] = cond["tacho"] and shaft is None
        tacho = True if cond["unit_tacho"] else None  # aligned()'s flag: by the marks
        cond["continuous"], cond["blocks"] = continuous, tuple(blocks)
        if continuous and not cond["unit_tacho"]:  # register_to_source shifts them again, by both turns
            cond["standardised"] = {f.path: standardiser.apply(r) for role in ROLES for f, r in cond[role]}
        for role in ROLES:
            turned = []
            for f, revs in cond[role]:
                shift, revs = aligned(reference, standardiser.apply(revs), tacho, target.marks, continuous)
                cond["shifts"][f.path] = shift
                turned.append((f, revs))
            cond[role] = turned
        # a take reversed against the history (a sensor's leads swapped) is said, aligned by the marks or not; one
        # turned off its marks too (a box running the other way)
        flipped = [f"{f.path}: {w}" for f, r in cond["test"] if (w := turned_line(r, reference, tacho is None))]
        cond["warnings"] += flipped
        # read off its marks, not reversed: its tooth counted as the history counts it (detection_which_gear), at so
        # many marks a turn
        cond["turned"] = {f.path: target.marks for f, r in cond["test"] if read_off_mark(r, reference, tacho is None)}
        for line in flipped:
            on_event(Event("log", message=f"warning: {line}"))
        _units(cond)
        for u, X in cond["history_units"].items():
            if len(X) < MIN_HISTORY_UNITS:  # a threshold is fitted to their quartiles
                # a tacho read on the wrong shaft or marks counts other turns: said as that, not as short records (a
                # 19/47 + 29/71 reducer's output tacho read as the input's: '2 record30 units ... longer records')
                if structure is not None and (differs := structure({name: cond})):
                    raise GearlabInputError(differs)
                raise GearlabInputError(too_few_units(where, name, cond, shaft, len(X), u))
        for f, r in cond["test"]:
            short = short_blocks(len(r), blocks)
            if short and shaft is not None:  # a record of no unit of a kind: nothing to score it by
                raise GearlabInputError(
                    f"{where}: {f.path} gives {len(r)} {shaft.name}-shaft revolutions, fewer than record{short[0]}'s "
                    f"{short[0]}; expected a longer record, or shorter [detection] key 'blocks'"
                )
    return conditions


def _max_order(cond: dict, records: dict) -> int:
    """The highest order every history record of *cond* holds (*records*: each file's record)."""
    return min(Chain(fs=records[f.path].fs, speed=records[f.path].speed_hz).max_order for f, _ in cond["history"])


def short_blocks(turns: float, blocks) -> list[int]:
    """The record-level blocks a test record of *turns* revolutions of the units' shaft cannot fill: the run
    refuses such a record (read_target) and validate a take whose header says it is that short (short_takes)."""
    return [b for b in blocks if turns < b]


def short_takes(source: DatasetSpec, target: Target, blocks, where: str) -> None:
    """Refuse a test take whose header gives its length (samples and rate: a WAV, HDF5, npz or MAT array) too short
    for a record-level unit of the watched gear's shaft, as read_target would after reading every take, at the speed
    the run reads it at: the take's declared, else the [target]'s (a take without a tacho). A take with a tacho (or
    no declared speed: found from the mesh lines) at the source's or its description's [operation] speed is only
    warned of: the run reads its own speed, and a faster take holds more turns. A header without the length (a text
    file's) or no speed known: nothing said here (a history's tacho is read: detection_screen)."""
    from ..data.recordings import read_header
    from ..gearbox.simulation import gearbox_of

    shaft = unit_shaft(source)
    if shaft is None:  # the run refuses none on the input shaft: a short record scores fewer units
        return
    box = gearbox_of(source)
    nominal = source.speed_hz or (box.speed_hz if box is not None else None)
    for f in target.files:
        keys = target.keys_of(f)
        declared = None if keys.get("tacho") is not None else f.speed_hz or target.speed_hz
        speed = declared or nominal
        if f.role != "test" or not speed:
            continue
        seconds = read_header(f.resolved).seconds(str(keys["vibration"]), keys["fs"])
        turns = None if seconds is None else seconds * speed * float(shaft.ratio)
        short = [] if turns is None else short_blocks(turns, blocks)
        if short:
            need = max(short) / (speed * float(shaft.ratio))
            said = (
                f"{where}: {f.path}: {seconds:.3g} s at {speed:.4g} Hz holds ~{int(turns)} turns of the {shaft.name} "
                f"shaft; record{max(short)} needs {max(short)} (a take of >= {math.ceil(need * 10) / 10:g} s)"
            )
            if declared:
                raise GearlabInputError(said)
            warnings.warn(
                f"{said}, unless it runs faster than the description's speed (its own is read in the run)", stacklevel=2
            )


def _units(cond: dict) -> None:
    """cond's history and test units, from its aligned records."""
    blocks = cond["blocks"]
    per_record = [unit_sets(r, blocks, True) for _, r in cond["history"]]
    cond["history_units"] = {u: np.concatenate([s[u] for s in per_record]) for u in per_record[0]}
    # which history units come from which record (in order), and how many are independent:
    # the threshold models the record-to-record variation (record_effects)
    cond["history_records"] = {
        u: [(len(s[u]), record_effects.independent_units(len(s[u]), *unit_window(u))) for s in per_record]
        for u in per_record[0]
    }
    cond["test_units"] = {f.path: unit_sets(r, blocks, False) for f, r in cond["test"]}


def unaligned_why(target: Target, unit_shaft: str) -> str:
    """Why a condition's records were aligned by correlation, not by a tacho mark (register_to_source),
    as the log says it: no tacho, or one whose marks are not what the units start at (a shaft's)."""
    # each file's own tacho counts (a history whose files each name theirs was logged 'no tacho')
    tachos = sorted({t for t in [target.tacho, *(target.keys_of(f)["tacho"] for f in target.files)] if t is not None})
    if not tachos or not target.tacho_all:
        return "records without a tacho among them" if tachos else "no tacho"
    return (
        f"tacho {', '.join(map(repr, tachos))} on the {target.read_as} shaft, {target.pulses_per_rev} marks per turn; "
        f"the units, {unit_shaft}-shaft revolutions, are aligned by correlation, not by its marks"
    )


def register_to_source(cond: dict, source) -> int:
    """Without a tacho, a record's angle is zero where it starts, a place in the gears' turn the
    simulator knows nothing of, while the learned methods learned the simulated fault shapes in the
    source's frame (the chip at its angle within the mesh cycle). The condition -- its reference,
    every record and unit alike -- is turned by the whole-sample turn whose history mean revolution
    correlates best with the *source*'s healthy mean revolution; returns that turn (samples). With
    a tacho the records keep the frame of its mark. A *continuous* condition's records are shifted
    again from where they were read, each as one signal, by the sum of both turns (aligned)."""
    healthy = np.asarray(source.X)[np.asarray(source.fault) == 0].mean(axis=0)
    points = cond["reference"].size
    turn, _ = aligned(healthy, cond["reference"], None, 1)

    def turned(x: np.ndarray) -> np.ndarray:
        return np.roll(x, -turn, axis=-1)  # x(θ) -> x(θ + 2π turn / points), as align_to turns

    cond["reference"] = turned(cond["reference"])
    cond["shifts"] = {p: (m + turn) % points for p, m in cond["shifts"].items()}
    if cond.get("continuous"):
        for role in ROLES:
            cond[role] = [(f, continued(cond["standardised"][f.path], cond["shifts"][f.path])) for f, _ in cond[role]]
        del cond["standardised"]  # read once
        _units(cond)
        return turn
    for role in ROLES:
        cond[role] = [(f, turned(r)) for f, r in cond[role]]
    cond["history_units"] = {u: turned(x) for u, x in cond["history_units"].items()}
    cond["test_units"] = {p: {u: turned(x) for u, x in units.items()} for p, units in cond["test_units"].items()}
    return turn


def asynchronous_orders(source: DatasetSpec, shaft: UnitShaft | None = None) -> tuple[float, ...]:
    """The mesh orders of the *source*'s train that are no whole input order (17/59 then 26/83:
    its later mesh at 442/59 = 7.49), in input orders; () for a single-stage train and where every
    later mesh is whole (the PHM 2009 rig's 16). With a *shaft*, those of no whole order of that
    shaft, in its orders."""
    from ..data.placement import train_pairs

    model, _, _ = source.check_model()
    turns, out = Fraction(1), []
    for pair in train_pairs(model, source.preset):
        order = turns * pair.Z1 / (1 if shaft is None else shaft.ratio)
        if order.denominator > 1:
            out.append(float(order))
        turns *= Fraction(pair.Z1, pair.Z2)
    return tuple(out)


def without_asynchronous(X: np.ndarray, orders) -> np.ndarray:
    """*X* (rows: revolutions or TSAs) less the non-whole mesh *orders*: each row less its
    least-squares fit by every harmonic of them (`asynchronous_basis`, at the row's own amplitude
    and phase), then without the two whole orders beside each harmonic (where the sidebands of its
    shaft's turn lie). Such a mesh moves against the input from revolution to revolution (a
    hunting-tooth train's: gearlab.data.realise, "A train's cycle"): each revolution holds it at its
    own phase, and its harmonics near a whole order survive a TSA (2 x 7.49 = 14.98 turns by half a
    cycle in 30 revolutions). On the 17/59 + 26/83 development records it held 94 % of a TSA of 30's
    residual from the history's reference (45 % in the whole orders beside its harmonics, 49 % the
    offset that the median of revolutions holding it at their own phases takes from their mean) and
    85 % of the templates' energy, a chip 5 %: matched_filter's record30 AUC 0.54, fm4's 0.97.
    Zeroing those whole orders alone left what a revolution's mesh leaks beyond them (a sinusoid
    cut at a half order: 19 % of its energy), which on other records held most of the templates
    again (record30 AUC 0.14). A chip is broadband: it keeps most of itself."""
    X = np.asarray(X)
    if not len(orders):
        return X
    Y = X.astype(np.float64)
    Q = asynchronous_basis(X.shape[-1], tuple(float(o) for o in orders))
    F = np.fft.rfft(Y - (Y @ Q) @ Q.T, axis=-1)
    top = F.shape[-1] - 1
    for order in orders:
        for k in range(1, int(top / order) + 1):
            F[..., max(0, math.floor(k * order)) : min(top, math.ceil(k * order)) + 1] = 0.0
    return np.fft.irfft(F, n=X.shape[-1], axis=-1).astype(X.dtype, copy=False)


@functools.lru_cache(maxsize=8)
def asynchronous_basis(points: int, orders: tuple[float, ...]) -> np.ndarray:
    """Orthonormal columns (points, m) spanning the cosine and sine of every harmonic k x order
    below points / 2 over one revolution's *points* angles, for each of *orders*; a harmonic that
    falls on a whole order (59 x 442/59) is synchronous and left out."""
    theta = 2 * np.pi * np.arange(points) / points
    columns = []
    for order in orders:
        for k in range(1, int((points // 2 - 1) / order) + 1):
            f = k * order
            if abs(f - round(f)) > 1e-9:
                columns += [np.cos(f * theta), np.sin(f * theta)]
    Q, _ = np.linalg.qr(np.stack(columns, axis=1))
    Q.setflags(write=False)
    return Q


def learned_input(how: str, points: int, classical: Classical | None, max_order: int | None = None):
    """What the learned methods see of a revolution or TSA (source and target alike): as it is
    (*how* = [detection] input "revolution"), or its difference signal (the shaft orders, mesh
    harmonics and sidebands of *classical* removed, as for FM4), which leaves what one tooth adds
    and drops what every tooth and each build share; at *points* per revolution (band_limited: a
    network's step costs in proportion), and no order above *max_order*: the condition's records
    hold none there (read_target), while a simulated revolution, and the sensor noise added to it,
    reach order POINTS / 2."""
    if how == "revolution":
        return lambda X: band_limited(X, points, max_order)
    c = classical
    return lambda X: band_limited(
        difference_signal(X, c.mesh_orders, c.shaft_orders, c.sidebands).astype(np.float32),
        points,
        max_order,
    )


def synchronous_input(seen, later: tuple):
    """*seen* (`learned_input`) with the *later* mesh orders that are no whole input order
    (`asynchronous_orders`) taken out first (`without_asynchronous`), in the source's rows, the
    history's and the test units alike; *seen* itself when there are none (every whole-order train:
    its inputs, and so its figures, are unchanged)."""
    if not later:
        return seen
    return lambda X: seen(without_asynchronous(X, later))


# The source's speed, as a condition's history measured it, is kept to this step (Hz): one dataset (one
# cache key) for equal takes, and what the simulation holds in Hz (a mesh line, a resonance, a sensor's band)
# within a small part of a bin of the record's: 0.0005 Hz off at most, 0.016 Hz at a 33-tooth mesh, a tenth
# of a 6.6 s record's bin, 2e-5 of any order (to 1 Hz, a 1455 rpm motor's 24.25 Hz history was simulated at
# 24 Hz: its mesh line 55 bins off; to 0.01 Hz up to 1.1). A tacho's history keeps 1 Hz (SOURCE_STEP_TACHO):
# its conditions' datasets and figures (PHM 2009) as they were.
SOURCE_STEP, SOURCE_STEP_TACHO = 0.001, 1.0


def source_speed(cond: dict) -> float:
    """The speed a condition's source is simulated at: the median of its history records' speeds, to
    SOURCE_STEP (to SOURCE_STEP_TACHO where a tacho measured them)."""
    step = SOURCE_STEP_TACHO if cond.get("tacho", True) else SOURCE_STEP
    median = float(np.median([cond["speeds"][f.path] for f, _ in cond["history"]]))
    return float(round(round(median / step) * step, 6))


def source_for(source: DatasetSpec, cond: dict, how: str, shaft: UnitShaft | None = None) -> DatasetSpec:
    """The source simulated at the condition's speed (source_speed: the median of its history records'
    speeds, to 0.001 Hz; to 1 Hz from a tacho), or as given; with a *shaft*, its rows that shaft's
    revolutions (DatasetSpec.unit_shaft)."""
    if shaft is not None:
        on = f" ({shaft.name} shaft)"
        ratio = (shaft.ratio.numerator, shaft.ratio.denominator)
        source = source.with_(unit_shaft=ratio, name=source.name + on, domain=source.name + on)
    if how == "source":
        return source
    speed = source_speed(cond)
    return source.with_(speed_hz=speed, name=f"{source.name}@{speed:g}Hz", domain=f"{source.name}@{speed:g}Hz")


def history_training_rows(cond: dict, protocol: Protocol, condition: str, tsa: int = 0) -> np.ndarray:
    """The history revolutions a network trains on: target_train of them at random (seeded); with
    *tsa* > 1 the history's TSAs of *tsa* revolutions instead (sliding as its history units are)."""
    if tsa > 1:
        revs = np.concatenate([tsa_units(r, tsa, max(1, tsa // HISTORY_STRIDES)) for _, r in cond["history"]])
    else:
        revs = np.concatenate([r for _, r in cond["history"]])
    rng = np.random.default_rng([protocol.seed, sum(map(ord, condition))])
    take = rng.permutation(len(revs))[: protocol.target_train]
    return revs[np.sort(take)]


def folds_of(history_fit: str, cond: dict, condition: str, path) -> tuple:
    """The history records left out one at a time (history_fit = "crossed"), or (None,): one
    training on them all."""
    if history_fit == "all":
        return (None,)
    if len(cond["history"]) < 2:
        files = ", ".join(f.path for f, _ in cond["history"])
        raise GearlabInputError(
            f"{location(path, 'detection', 'history_fit')}: 'crossed' leaves out one history record at a "
            f"time and needs at least two per condition; condition '{condition}' has one ({files}); "
            "expected 'all' or another history record"
        )
    return tuple(range(len(cond["history"])))


def trained_on(cond: dict, fold: int | None) -> dict:
    """The condition as a training sees it: its history without record *fold* (history_fit =
    "crossed"), or whole."""
    if fold is None:
        return cond
    return {**cond, "history": [h for i, h in enumerate(cond["history"]) if i != fold]}


def check_structure(source: DatasetSpec, target: Target, conditions: dict, where: str) -> str | None:
    """Each condition's history against the [source]'s gear train, before any work: the gap
    diagnosis's structure check (gearlab.gap.structure.structure_line) on its records' input
    revolutions laid end to end, each turned into register with the first (as the gap reads its
    history). The one line of the first tooth count, tacho shaft or marks per turn the records
    contradict, or None: methods trained on a simulator of another gearbox score nothing of this one
    (a 23/61 description of a 24/61 fan's records gave a report, and no word of the difference)."""
    from ..data.builder import operating_point
    from ..gap.structure import structure_line
    from ..gap.views import gear_pair_of
    from .common import unconfirmed_speed

    pair, described = gear_pair_of(source), operating_point(source)[0]
    for name, cond in conditions.items():
        said = unconfirmed_speed({f.path: cond["speed_from"][f.path] for f, _ in cond["history"]}, cond["speeds"])
        if said:  # a declared speed read whole: the structure check below would read smeared lines at it
            return f"{where}: the history of condition '{name}' differs from the [source]'s gearbox or its speed: " + (
                f"{said[1]}; expected the records' speed and tooth counts (gearlab inspect {said[0]} --gearbox ...)"
            )
        rows = []
        # a history read with tachos (with or without one on the test records) aligns by their marks
        marked = all(target.keys_of(f)["tacho"] is not None for f, _ in cond["history"])
        from_mesh = not marked and bool(target.gearbox) and target.speed_hz is None
        for f, _ in cond["history"]:
            revs = cond["raw"][f.path][0]
            if rows:
                _, revs = aligned(rows[0].mean(axis=0), revs, marked or None, target.marks, continuous=True)
            rows.append(revs)
        first = cond["history"][0][0].path
        speed = float(np.average([cond["speeds"][f.path] for f, _ in cond["history"]], weights=[len(r) for r in rows]))
        chain = Chain(
            fs=cond["fs"][first],
            speed=speed,
            speed_from_mesh=from_mesh and all(f.speed_hz is None for f, _ in cond["history"]),
            described_speed=described,
            tacho_shaft=(target.read_as or "input") if marked else None,
            takes=tuple(len(r) for r in rows),
        )
        # the marks a turn the history was read with (one count for all: else told as a share of them)
        pulses = {target.keys_of(f)["pulses_per_rev"] for f, _ in cond["history"]} if marked else set()
        ppr = pulses.pop() if len(pulses) == 1 else None
        line = structure_line(np.concatenate(rows).astype(np.float64), pair, cond["max_order"], chain, None, {}, ppr)
        if line:
            return (
                f"{where}: the history of condition '{name}' differs from the [source]'s gearbox: {line}; "
                f"expected the records' gearbox (gearlab inspect {first} --gearbox ... says what differs)"
            )
    return None
