"""Where a fault sits: a gear of the train, by stage and role or by the words of its shafts.

A fault placement names the fault plugin and the gear that carries it, as a table:

    { name = "chip", gear = "wheel", stage = 2, tooth = 5, step = 20 }
    { name = "chip", gear = "output gear", teeth = [1, 5], steps = [18, 20] }

Stage k's pinion (gear 1, the driver) sits on shaft k and drives its wheel (gear 2) on shaft
k + 1 (docs/gearbox.md); shaft 1 is the input, the last the output. ``gear`` is "pinion" (the
default) or "wheel" of ``stage`` (default 1), or the words "SHAFT pinion" / "SHAFT gear" (or
"SHAFT wheel") with the shaft's name in the model preset's gearbox description: on the PHM 2009
rig (phm09: shafts input, idler, output) the 32T "input pinion", the 96T "idler gear", the 48T
"idler pinion" and the 80T "output gear". The default shaft names (input, intermediate,
output) are understood on every model. A bad value is one line naming the key.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction

from ..errors import GearlabInputError, did_you_mean, shown
from ..gearbox.description import SHAFT_NAMES, gear_name
from ..gearbox.simulation import shaft_names
from ..physics.stiffness import GEARS, gear_label
from ..registry import get_registry

WHEEL_WORDS = ("gear", "wheel")  # "output gear" and "output wheel" name the same gear


def model_shafts(model: str, preset: str, where: str = "") -> tuple[str, ...]:
    """shaft_names of a registered model's preset."""
    return shaft_names(preset, get_registry().get("model", model, where).stages)


def gear_words(shafts: tuple[str, ...]) -> dict[str, tuple[int, str]]:
    """Word -> (stage, gear) for every gear of a train whose shafts are *shafts* (input first); the
    default names (SHAFT_NAMES) are understood beside the description's."""
    stages = len(shafts) - 1
    out: dict[str, tuple[int, str]] = {}
    for names in (SHAFT_NAMES.get(stages, shafts), shafts):
        for k in range(1, stages + 1):
            out[f"{names[k - 1]} pinion"] = (k, "pinion")
            for word in WHEEL_WORDS:
                out[f"{names[k]} {word}"] = (k, "wheel")
    return out


def resolve_gear(gear, stage, shafts: tuple[str, ...], where: str) -> tuple[int, str]:
    """(stage, "pinion" | "wheel") of a placement's ``gear`` and ``stage`` keys (None: not given)."""
    stages = len(shafts) - 1
    if stage is not None and (isinstance(stage, bool) or not isinstance(stage, int) or not 1 <= stage <= stages):
        raise GearlabInputError(
            f"{where} key 'stage': expected a stage number in 1..{stages} (the model has {stages} stage(s)), "
            f"got {shown(stage)}"
        )
    gear = "pinion" if gear is None else gear
    if not isinstance(gear, str):
        raise GearlabInputError(f"{where} key 'gear': expected a gear name, got {shown(gear)}")
    if gear in GEARS:
        return (1 if stage is None else stage), gear
    words = gear_words(shafts)
    key = " ".join(gear.lower().split())
    if key not in words:
        known = ", ".join([*GEARS, *(gear_name(k, g, shafts) for k in range(1, stages + 1) for g in GEARS)])
        # the nearest word understood, by the name the list shows ('input wheel' of a one-stage train: 'output gear',
        # not its alias 'output wheel')
        named = {w: gear_name(k, g, shafts) for w, (k, g) in words.items()}
        raise GearlabInputError(
            f"{where} key 'gear': unknown gear {shown(gear)}{did_you_mean(key, list(words), named)}; known: {known}"
        )
    found = words[key]
    if stage is not None and stage != found[0]:
        raise GearlabInputError(
            f"{where} key 'stage': {stage} contradicts gear {shown(gear)}, which is on stage {found[0]}"
        )
    return found


def gear_of(entry: Mapping, shafts: tuple[str, ...], where: str) -> tuple[int, str]:
    """(stage, gear) of a placement table (keys 'gear', 'stage')."""
    return resolve_gear(entry.get("gear"), entry.get("stage"), shafts, where)


def train_pairs(model, preset: str, where: str = "") -> tuple:
    """The gear pairs of a model preset, stage 1 first (a multi-stage model's further meshes)."""
    pair, values = model.resolve(preset, where=where)
    return (pair, *(m.pair for m in model.assemble(pair, values).meshes))


# --- a dataset's fault classes -------------------------------------------------------------------
#
# A dataset's `faults` maps a class key to ladder steps: the fault plugin's name for the input
# pinion (stage 1, as always), "NAME@GEAR" for another gear, GEAR its gear_label ("wheel",
# "s2-pinion", "s2-wheel", ...), which the class name then says.


def fault_key(name: str, stage: int, gear: str) -> str:
    """The class key of fault *name* on (stage, gear): "chip", "chip@wheel", "chip@s2-wheel"."""
    return name if (stage, gear) == (1, "pinion") else f"{name}@{gear_label(stage, gear)}"


def parse_fault_key(key: str, shafts: tuple[str, ...], where: str) -> tuple[str, int, str]:
    """(plugin name, stage, gear) of a class key (fault_key, or "NAME@WORDS": "chip@output gear")."""
    name, at, where_on = key.partition("@")
    if not at:
        return key, 1, "pinion"
    stage, gear = None, where_on.strip()
    labelled = re.fullmatch(r"s(\d+)-(pinion|wheel)", gear)
    if labelled:
        stage, gear = int(labelled.group(1)), labelled.group(2)
    stage, gear = resolve_gear(gear, stage, shafts, f"{where}, fault '{key}'")
    return name.strip(), stage, gear


def fault_parts(key: str, shafts: tuple[str, ...], where: str) -> tuple[tuple[str, int, str], ...]:
    """(plugin name, stage, gear) of each fault of a class key: one (parse_fault_key), or two joined by
    '+' on the pinion and the wheel of one stage, pinion first ("chip+chip@wheel": pinion tooth n and
    the wheel tooth n it meets, the TVMS over the hunting-tooth period)."""
    if "+" not in key:
        return (parse_fault_key(key, shafts, where),)
    parts = [parse_fault_key(part.strip(), shafts, where) for part in key.split("+")]
    if (
        len(parts) != 2
        or not all(name for name, _, _ in parts)
        or len({(s, g) for _, s, g in parts}) != 2
        or (parts[0][1] != parts[1][1])
    ):
        raise GearlabInputError(
            f"{where}, fault '{key}': '+' joins a fault on a stage's pinion and one on its wheel, "
            "e.g. 'chip+chip@wheel' or 'chip@s2-pinion+spall@s2-wheel'"
        )
    return tuple(sorted(parts, key=lambda part: part[2] != "pinion"))


def fault_words(parts, shafts: tuple[str, ...]) -> str:
    """A class key in the words a user writes it ("chip@output gear"), not its canonical form ("chip@s2-wheel")."""
    return "+".join(f"{name}@{gear_name(stage, gear, shafts)}" for name, stage, gear in parts)


def canonical_faults(raw, shafts: tuple[str, ...], where: str) -> tuple[tuple[str, tuple[int, ...]], ...]:
    """A scenario's `faults`, ``{chip = [18, 20], "chip@output gear" = [20]}`` or a list of tables
    ``[{name = "chip", gear = "wheel", stage = 2, steps = [20]}]``, as (class key, ladder steps)
    pairs with canonical keys (fault_key)."""
    where = f"{where} key 'faults'"
    if isinstance(raw, Mapping):
        items = [(key, steps, f"{where}: '{key}' must map to a list of ladder steps") for key, steps in raw.items()]
    elif isinstance(raw, list):
        items = []
        for i, entry in enumerate(raw, start=1):
            here = f"{where} #{i}"
            if not isinstance(entry, Mapping) or not isinstance(entry.get("name"), str):
                raise GearlabInputError(
                    f'{here}: expected a table {{name = "chip", gear = "output gear", steps = [20]}}, '
                    f"got {shown(entry)}"
                )
            unknown = [k for k in entry if k not in ("name", "gear", "stage", "steps")]
            if unknown:
                raise GearlabInputError(f"{here}: unknown key {shown(unknown[0])}; known: name, gear, stage, steps")
            stage, gear = gear_of(entry, shafts, here)
            if "steps" not in entry:
                raise GearlabInputError(f"{here}: missing 'steps' (ladder steps 1..20, e.g. steps = [18, 20])")
            what = f"{here} key 'steps': expected a list of ladder steps"
            items.append((fault_key(entry["name"], stage, gear), entry["steps"], what))
    else:
        raise GearlabInputError(f"{where}: expected {{fault = [steps]}} or a list of tables, got {shown(raw)}")
    out: dict[str, tuple[int, ...]] = {}
    for key, steps, what in items:
        if not isinstance(steps, list) or not all(isinstance(s, int) and not isinstance(s, bool) for s in steps):
            # a gear's name among the steps ("broken_tip" = ["intermediate gear", 12]): the key names the gear
            named = [g for g in steps if isinstance(g, str)] if isinstance(steps, list) else []
            on = f' (on a gear: "{key}@{named[0]}" = {[x for x in steps if x not in named]})' if named else ""
            raise GearlabInputError(f"{what}, got {shown(steps)}{on}")
        parts = fault_parts(key, shafts, where)
        canonical = "+".join(fault_key(*part) for part in parts)
        if canonical in out:
            raise GearlabInputError(f"{where}: fault '{fault_words(parts, shafts)}' is listed twice")
        out[canonical] = tuple(steps)
    return tuple(out.items())


@dataclass(frozen=True)
class FaultClass:
    """A dataset's fault class: its plugin on one gear of the train, and the teeth it is put on; a
    class of two faults ('+', fault_parts): the pinion's here, the wheel's in *mates*."""

    key: str
    name: str  # the fault plugin
    stage: int
    gear: str  # "pinion" | "wheel"
    teeth: tuple[int, ...]
    pair: object  # the stage's GearPair (pinion = its gear 1)
    period: int = 1  # input revolutions after which the train with this damage repeats
    mates: tuple = ()  # (plugin, stage, gear) of the wheel's fault of a two-gear class

    @property
    def parts(self) -> tuple[tuple[str, int, str], ...]:
        return ((self.name, self.stage, self.gear), *self.mates)


# Input revolutions of a steady response simulated whole (its period): damage on the output gear of a
# train of co-prime tooth counts (21/53 then 29/61) repeats only after 3233 turns, minutes of simulation;
# a train repeating after more is simulated as a stretch of steady revolutions (builder.steady_stretch).
MAX_PERIOD = 1000


def train_period(pairs, stage: int, gear: str) -> int:
    """Input revolutions after which a train with damage on (stage, gear) repeats: the least number
    that turns the faulted gear and engages every mesh a whole number of times (exact tooth ratios)."""
    turns, periods = Fraction(1), []
    for k, pair in enumerate(pairs, start=1):
        mesh = turns * pair.Z1  # mesh periods per input turn
        periods.append(mesh.denominator)
        if k == stage:
            periods.append((turns * (Fraction(pair.Z1, pair.Z2) if gear == "wheel" else 1)).denominator)
        turns *= Fraction(pair.Z1, pair.Z2)
    return math.lcm(*periods)


def gear_turns(pairs, stage: int, gear: str) -> Fraction:
    """Turns of the gear (stage, gear) per input turn: 1 for the input pinion, 1/3 for the PHM 2009 rig's idler."""
    turns = Fraction(1)
    for pair in pairs[: stage - 1]:
        turns *= Fraction(pair.Z1, pair.Z2)
    return turns * (Fraction(pairs[stage - 1].Z1, pairs[stage - 1].Z2) if gear == "wheel" else 1)


def gear_period(pairs, stage: int, gear: str) -> int:
    """Input revolutions after which the gear (stage, gear) has turned a whole number of times: 1 for the
    input pinion, 3 for the PHM 2009 rig's 96T idler gear (Simulator.period of damage on it)."""
    return gear_turns(pairs, stage, gear).denominator


def mesh_cycle_of(pairs) -> int:
    """Input revolutions after which every mesh of the train repeats (builder.mesh_cycle, from the
    tooth counts): 1 when each later mesh is a whole input order (the PHM 2009 rig's 16), 59 for a
    17/59 then 26/83 train (its later mesh at 442/59 orders)."""
    turns, cycle = Fraction(1), 1
    for pair in pairs:
        cycle = math.lcm(cycle, (turns * pair.Z1).denominator)
        turns *= Fraction(pair.Z1, pair.Z2)
    return cycle


def fault_classes(model, preset: str, faults, teeth, where: str) -> dict[str, FaultClass]:
    """Each class key of a dataset's *faults* resolved on *model*/*preset*: its gear, and its teeth:
    *teeth* (each checked against that gear) or, when None, every tooth of that gear."""
    pairs = train_pairs(model, preset, where)
    shafts = shaft_names(preset, len(pairs))
    out = {}
    for key, _ in faults:
        parts = fault_parts(key, shafts, where)
        name, stage, gear = parts[0]
        pair = pairs[stage - 1]
        Z = pair.Z1 if gear == "pinion" else pair.Z2
        chosen = tuple(range(1, Z + 1)) if teeth is None else tuple(teeth)
        for n in chosen:
            if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= Z:
                words = fault_words(parts, shafts)
                on = "" if (stage, gear) == (1, "pinion") else f" of the {gear_name(stage, gear, shafts)} ('{words}')"
                raise GearlabInputError(f"{where} key 'teeth': tooth {n!r} is outside 1..{Z}{on}")
        period = math.lcm(*(train_period(pairs, s, g) for _, s, g in parts))
        out[key] = FaultClass(key, name, stage, gear, chosen, pair, period, parts[1:])
    return out
