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

import functools
from collections.abc import Mapping

from ..errors import GearlabInputError, shown
from ..gearbox.description import SHAFT_NAMES
from ..params import did_you_mean
from ..physics.stiffness import GEARS

WHEEL_WORDS = ("gear", "wheel")  # "output gear" and "output wheel" name the same gear


@functools.lru_cache(maxsize=64)
def shaft_names(preset: str, stages: int) -> tuple[str, ...]:
    """The shafts of a model preset, input first: its gearbox description's names when the preset
    is one (a built-in description or a gearbox reference), else the default names."""
    from ..gearbox import builtin_gearboxes, resolve_gearbox
    from ..gearbox.simulation import is_reference, referenced

    box = None
    if is_reference(preset):
        box = referenced(preset)
    elif preset in builtin_gearboxes():
        box = resolve_gearbox(preset)
    if box is not None and len(box.shafts) == stages + 1:
        return tuple(box.shafts)
    return SHAFT_NAMES[stages] if stages in SHAFT_NAMES else tuple(f"shaft {i + 1}" for i in range(stages + 1))


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


def gear_name(stage: int, gear: str, shafts: tuple[str, ...]) -> str:
    """The words for a gear: "input pinion", "output gear", "idler gear", ..."""
    return f"{shafts[stage - 1]} pinion" if gear == "pinion" else f"{shafts[stage]} gear"


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
        raise GearlabInputError(
            f"{where} key 'gear': unknown gear {shown(gear)}{did_you_mean(key, list(words))}; known: {known}"
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
