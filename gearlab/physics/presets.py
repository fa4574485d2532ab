"""Gear-pair presets: the geometry and material rows of thesis Tables 2.3 and 2.4."""

from __future__ import annotations

import math

from ..errors import GearlabInputError, did_you_mean
from .geometry import GearPair

# Every preset is a 20 deg standard spur pair in steel (E = 200 GPa, nu = 0.3).
_STEEL_20DEG = dict(pressure_angle=math.radians(20), E=200e9, nu=0.3)

# Table 2.3, Luo et al. (2019b): the 10-DOF model of Dataset A.
# Table 2.4, Meng et al. (2020): the 6/8-DOF models of Dataset B.
# The hub radius 9.76 mm is the thesis's own choice for both (footnotes 1 and 3).
PAIR_PRESETS: dict[str, dict] = {
    "luo2019": dict(Z1=16, Z2=48, module=3.175e-3, face_width=16e-3, hub_radius=9.76e-3, **_STEEL_20DEG),
    "meng2020": dict(Z1=25, Z2=30, module=2e-3, face_width=20e-3, hub_radius=9.76e-3, **_STEEL_20DEG),
    # The PHM 2009 spur rig (docs/real_data.md, "The rig simulator"): tooth counts published,
    # the rest not. 32 + 96 = 48 + 80 = 128 teeth: with one module both centre distances are
    # equal, i.e. a reverted train (input and output coaxial), so one module serves both stages.
    # Module 2 mm (centre distance 128 mm, a small test rig), face width 20 mm (10 modules, the
    # middle of the usual 8-12; Table 2.4's pair), 20 deg standard pressure angle, steel, hub
    # radius 7.94 mm = the 5/8 in bore of the ER-10K bearings that carry the shafts.
    "phm09_stage1": dict(Z1=32, Z2=96, module=2e-3, face_width=20e-3, hub_radius=7.9375e-3, **_STEEL_20DEG),
    "phm09_stage2": dict(Z1=48, Z2=80, module=2e-3, face_width=20e-3, hub_radius=7.9375e-3, **_STEEL_20DEG),
}


def gear_pair(name: str) -> GearPair:
    try:
        values = PAIR_PRESETS[name]
    except KeyError:
        raise GearlabInputError(
            f"unknown gear-pair preset '{name}'{did_you_mean(name, list(PAIR_PRESETS))}; "
            f"known: {', '.join(PAIR_PRESETS)}"
        ) from None
    return GearPair(name=name, **values)
