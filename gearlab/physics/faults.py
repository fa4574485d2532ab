"""The fault contract of the generalised formulation (thesis 2.2.5, Table 2.2).

A fault plugin is a subclass of :class:`Fault` that declares its parameters and
implements three functions:

* ``apply(section, params, pair)``: return the tooth section with h_x, A_x, I_x, L(x) changed;
* ``rfa(params, pair)``: its relative fault area, eq. 2.113;
* ``ladder_endpoints(pair)``: the healthy and worst parameters of its 20-step intensity
  ladder (Tables 2.5 and 2.6 are the presets for the two thesis gear pairs);

and, where a parameter's limit depends on the gear pair (a crack deeper than the tooth is
thick, a spall past the tip), ``check(params, pair)``. Nothing else in gearlab needs to
know about a fault type. Every function works on gear 1 of the *pair* it is given: for a fault
on the wheel gearlab passes the pair seen from the wheel (``GearPair.seen_from``), so a plugin
written for the pinion serves any gear of any stage unchanged.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from ..errors import GearlabInputError
from ..settings import declared, plugin_description, resolve_params
from .geometry import GearPair
from .sections import ToothSection, healthy_section
from .stiffness import GEARS, PlacedFault

LADDER_STEPS = 20


class Fault:
    name: ClassVar[str]
    doc: ClassVar[str] = ""
    params: ClassVar[type]  # a settings dataclass (gearlab.settings)

    # --- to implement ---------------------------------------------------------------
    def apply(self, section: ToothSection, params: Mapping[str, float], pair: GearPair) -> ToothSection:
        raise NotImplementedError

    def ladder_endpoints(self, pair: GearPair) -> tuple[dict[str, float], dict[str, float]]:
        raise NotImplementedError

    def check(self, params: Mapping[str, float], pair: GearPair, where: str) -> None:
        """Raise GearlabInputError when *params* are impossible on *pair* (default: nothing to check)."""

    def rfa(self, params: Mapping[str, float], pair: GearPair) -> float:
        """Relative fault area (eq. 2.113). Default: share of the tooth face plane taken by the fault."""
        healthy = healthy_section(pair.pinion, pair.face_width)
        removed = self.apply(healthy, params, pair).face_area_removed()
        return float(np.clip(removed / (pair.face_width * healthy.tooth_height), 0.0, 1.0))

    # --- provided ---------------------------------------------------------------------
    def resolve(self, given: Mapping[str, object], pair: GearPair, where: str = "") -> dict[str, float]:
        """Defaults filled, units parsed, static bounds and the pair-dependent limits checked."""
        where = where or f"fault '{self.name}'"
        params = resolve_params(self.params, given, where)
        self.check(params, pair, where)
        return params

    def ladder(self, pair: GearPair, steps: int = LADDER_STEPS) -> list[dict[str, float]]:
        """Parameters of intensity steps 1..steps: step 1 healthy, the last the worst (linear)."""
        low, high = self.ladder_endpoints(pair)
        out = []
        for i in range(steps):
            w = i / (steps - 1)
            values = {}
            for name, (p, _) in declared(self.params).items():
                lo, hi = low[name], high[name]
                v = hi if i == steps - 1 else lo + w * (hi - lo)  # exact endpoints
                values[name] = int(round(v)) if p.integer else v
            out.append(values)
        return out

    def at_step(self, pair: GearPair, step: int, where: str = "") -> dict[str, float]:
        if not 1 <= step <= LADDER_STEPS:
            raise GearlabInputError(f"{where or self.name}: intensity step must lie in 1..{LADDER_STEPS}, got {step}")
        return self.ladder(pair)[step - 1]

    def place(
        self,
        tooth: int,
        params: Mapping[str, float],
        pair: GearPair,
        where: str = "",
        gear: str = "pinion",
        stage: int = 1,
    ) -> PlacedFault:
        """The fault on *tooth* of *gear* ("pinion" or "wheel") of *pair*, the train's stage *stage*."""
        where = where or f"fault {self.name}@{tooth}"
        Z = pair.seen_from(gear).Z1
        if isinstance(tooth, bool) or not isinstance(tooth, int) or not 1 <= tooth <= Z:
            raise GearlabInputError(f"{where}: tooth must be a {gear} tooth number in 1..{Z}, got {tooth!r}")
        return PlacedFault(fault=self, tooth=tooth, params=dict(params), gear=gear, stage=stage)

    def describe(self) -> dict:
        return plugin_description(self)


def region(section: ToothSection, start: float, end: float) -> np.ndarray:
    """Boolean mask of the section nodes with start <= x <= end."""
    return (section.x >= start) & (section.x <= end)


def scaled_ladder(pair: GearPair, table: Mapping[str, tuple[dict, dict]], reference: str) -> tuple[dict, dict]:
    """The table row for *pair*; for other pairs the *reference* row scaled to the tooth.

    Lengths along the profile and depths scale with the module, widths with the face width.
    Keys ending in '_w' in the table rows are widths; the rest are lengths or pure numbers.
    """
    if pair.name in table:
        low, high = table[pair.name]
        return dict(low), dict(high)
    ref = table[reference]
    ref_pair_module, ref_face_width = _REFERENCE_SCALES[reference]
    k_len, k_w = pair.module / ref_pair_module, pair.face_width / ref_face_width
    return tuple(
        {
            key: value * (k_w if key in _WIDTH_KEYS else k_len if key in _LENGTH_KEYS else 1.0)
            for key, value in row.items()
        }
        for row in ref
    )


# Scales of the reference pairs used to carry Tables 2.5 / 2.6 to other pairs.
_REFERENCE_SCALES = {"luo2019": (3.175e-3, 16e-3), "meng2020": (2e-3, 20e-3)}
_WIDTH_KEYS = {"c", "w_s", "L_c"}
_LENGTH_KEYS = {"b", "l_s", "h_s", "x_1", "u", "sigma_u", "r", "sigma_r", "q0", "q2"}


def place_fault(
    registry,
    pair: GearPair,
    kind: str,
    tooth,
    step=None,
    params: Mapping | None = None,
    where: str = "",
    gear: str = "pinion",
    stage: int = 1,
) -> PlacedFault:
    """Resolve a fault by plugin name on *tooth* of *gear* ("pinion" or "wheel") of *pair* (stage
    *stage* of the train): a ladder *step* (1..20) or explicit *params*. The plugin's ladder, bounds
    and checks see the pair from the faulted gear (GearPair.seen_from), i.e. that gear's geometry."""
    where = where or f"fault {kind}@{tooth}"
    fault = registry.get("fault", kind, where)
    if gear not in GEARS:
        raise GearlabInputError(f"{where}: gear must be one of {', '.join(GEARS)}, got {gear!r}")
    view = pair.seen_from(gear)
    if step is not None and params:
        raise GearlabInputError(f"{where}: give either a ladder step or explicit parameters, not both")
    if step is not None:
        if isinstance(step, bool) or not isinstance(step, int):
            raise GearlabInputError(
                f"{where}: intensity step must be a whole number in 1..{LADDER_STEPS}, got {step!r}"
            )
        resolved = fault.resolve(fault.at_step(view, step, where), view, where)
    else:
        resolved = fault.resolve(params or {}, view, where)
    return fault.place(tooth, resolved, pair, where, gear=gear, stage=stage)


FAULT_SYNTAX = "KIND@TOOTH=STEP (ladder step 1..20, 1 = healthy) or KIND@TOOTH:NAME=VALUE,... (explicit, with units)"


def place_fault_option(registry, pair: GearPair, text: str, where: str) -> PlacedFault:
    """A --fault option placed on *pair*: KIND@TOOTH..., a pinion tooth, or KIND@GEAR:TOOTH... (GEAR
    pinion or wheel, as PlacedFault.label writes it: 'chip@wheel:5=12')."""
    kind, at, rest = text.partition("@")
    on = re.fullmatch(r"\s*(pinion|wheel)\s*:(.*)", rest, re.S) if at else None
    gear = on.group(1) if on else "pinion"
    return place_fault(
        registry, pair, *parse_fault_option(f"{kind}@{on.group(2)}" if on else text), where=where, gear=gear
    )


def parse_fault_option(text: str) -> tuple[str, int, int | None, dict[str, str] | None]:
    """Parse 'crack@5=12' or 'crack@5:q0=2 mm,q2=1.5mm,nu=80 deg' into (kind, tooth, step, params)."""
    bad = GearlabInputError(f"--fault {text!r}: expected {FAULT_SYNTAX}")
    kind, at, rest = text.partition("@")
    if not at or not kind.strip():
        raise bad
    kind = kind.strip()
    if ":" in rest:
        tooth_text, _, body = rest.partition(":")
        params = {}
        for item in filter(None, (s.strip() for s in body.split(","))):
            name, eq, value = item.partition("=")
            if not eq or not name.strip() or not value.strip():
                raise bad
            params[name.strip()] = value.strip()
        step = None
    elif "=" in rest:
        tooth_text, _, step_text = rest.partition("=")
        try:
            step = int(step_text.strip())
        except ValueError:
            raise GearlabInputError(f"--fault {text!r}: STEP must be a whole number in 1..{LADDER_STEPS}") from None
        params = None
    else:
        raise bad
    try:
        tooth = int(tooth_text.strip())
    except ValueError:
        raise GearlabInputError(
            f"--fault {text!r}: TOOTH must be a tooth number (KIND@TOOTH on the pinion, KIND@wheel:TOOTH on the wheel)"
        ) from None
    return kind, tooth, step, params
