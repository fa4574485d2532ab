"""Gearbox descriptions (docs/gearbox.md): a TOML file a user writes once, checked with ISO 21771
geometry, from which gearlab derives the gear pairs of the stiffness model and the order table.

    box = resolve_gearbox("my_gearbox.toml")       # or a built-in: "luo2019", "meng2020", "phm09"
    gear_pairs(box)                                 # GearPair per stage (gearlab.physics.geometry)
    order_table(box)                                # shaft and mesh orders, sidebands, hunting tooth
"""

from __future__ import annotations

from pathlib import Path

from ..errors import GearlabInputError, did_you_mean
from .checks import StageGeometry, check_stage, stage_geometry
from .derive import StagePair, gear_pair, gear_pairs
from .description import Gearbox, GearSpec, Material, Sensor, Stage, load_gearbox, parse_gearbox, speed_hz
from .orders import OrderTable, StageOrders, order_table

PRESETS = Path(__file__).resolve().parent / "presets"


def builtin_gearboxes() -> dict[str, Path]:
    """The built-in descriptions: the thesis's pairs and the PHM 2009 rig, by name."""
    return {p.stem: p for p in sorted(PRESETS.glob("*.toml"))}


def resolve_gearbox(spec: str | Path) -> Gearbox:
    """A description from a file path or the name of a built-in one."""
    text = str(spec)
    builtin = builtin_gearboxes()
    if text in builtin and not Path(text).exists():
        return load_gearbox(builtin[text])
    if not text.endswith(".toml") and not Path(text).exists():
        raise GearlabInputError(
            f"--gearbox {text!r}: no such file and no built-in description{did_you_mean(text, list(builtin))}; "
            f"expected a .toml description or one of {', '.join(builtin)}"
        )
    return load_gearbox(text)


def validated_description(path: Path) -> str | None:
    """`gearlab validate` of a TOML gearbox description ([gearbox] or [[stages]], no [scenario]): its OK line
    (a mistake: resolve_gearbox's one-line error); None for any other file (a scenario)."""
    import tomllib

    try:
        tables = tomllib.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError):
        return None  # the scenario's reading says what is wrong (nested too deeply, too)
    if "scenario" in tables or not ("stages" in tables or "gearbox" in tables):
        return None
    box = resolve_gearbox(path)
    stages = ", ".join(f"{s.pinion_teeth}/{s.wheel_teeth}" for s in order_table(box).stages)
    return f"OK: {path}: gearbox description '{box.name}', stages {stages}"


__all__ = [
    "Gearbox",
    "GearSpec",
    "Material",
    "OrderTable",
    "Sensor",
    "Stage",
    "StageGeometry",
    "StageOrders",
    "StagePair",
    "builtin_gearboxes",
    "check_stage",
    "gear_pair",
    "gear_pairs",
    "load_gearbox",
    "order_table",
    "parse_gearbox",
    "resolve_gearbox",
    "speed_hz",
    "stage_geometry",
    "validated_description",
]
