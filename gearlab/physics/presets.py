"""Gear-pair presets: the geometry and material rows of thesis Tables 2.3 and 2.4."""

from __future__ import annotations

import math

from ..errors import GearlabInputError
from ..params import did_you_mean
from .geometry import GearPair

# Table 2.3, Luo et al. (2019b): the 10-DOF model of Dataset A.
# Table 2.4, Meng et al. (2020): the 6/8-DOF models of Dataset B.
# The hub radius 9.76 mm is the thesis's own choice for both (footnotes 1 and 3).
PAIR_PRESETS: dict[str, dict] = {
    "luo2019": dict(Z1=16, Z2=48, module=3.175e-3, face_width=16e-3, pressure_angle=math.radians(20),
                    E=200e9, nu=0.3, hub_radius=9.76e-3),
    "meng2020": dict(Z1=25, Z2=30, module=2e-3, face_width=20e-3, pressure_angle=math.radians(20),
                     E=200e9, nu=0.3, hub_radius=9.76e-3),
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
