"""Quantities with units: SI numbers or strings such as "3.175 mm", "20 deg", "25.2 Hz".

Parsing goes through pint; everything inside gearlab is a float in SI base units.
"""

from __future__ import annotations

import functools
import math

import pint

from .errors import GearlabInputError


@functools.cache
def _ureg() -> pint.UnitRegistry:
    return pint.UnitRegistry(autoconvert_offset_to_baseunit=True)


def to_si(value: object, unit: str, where: str) -> float:
    """Convert *value* (a number already in *unit*, or a string with its own unit) to *unit*.

    *unit* is the SI unit the caller stores ("m", "rad", "Hz", "N*m", "" for a pure number).
    *where* names the place the value came from, for the error message.
    """
    if isinstance(value, bool):
        raise GearlabInputError(f"{where}: expected a number or a quantity with a unit of {_describe(unit)}, got {value!r}")
    if isinstance(value, (int, float)):
        number = float(value)
    elif isinstance(value, str):
        number = _parse(value, unit, where)
    else:
        raise GearlabInputError(
            f"{where}: expected a number or a quantity with a unit of {_describe(unit)}, got {type(value).__name__} {value!r}"
        )
    if not math.isfinite(number):
        raise GearlabInputError(f"{where}: expected a finite number, got {value!r}")
    return number


def _parse(text: str, unit: str, where: str) -> float:
    ureg = _ureg()
    try:
        quantity = ureg.Quantity(text.strip().replace("µ", "u").replace("μ", "u"))
    except Exception:
        raise GearlabInputError(f"{where}: cannot read {text!r} as a quantity; expected e.g. '3.175 mm' ({_describe(unit)})") from None
    target = ureg.Unit(unit) if unit else ureg.dimensionless
    if not isinstance(quantity, pint.Quantity) or quantity.unitless:
        return float(getattr(quantity, "magnitude", quantity))  # a bare number is already SI
    try:
        return float(quantity.to(target).magnitude)
    except pint.DimensionalityError:
        raise GearlabInputError(
            f"{where}: {text!r} has the wrong dimension; expected a quantity in {_describe(unit)}"
        ) from None


def _describe(unit: str) -> str:
    return unit if unit else "a pure number"


def display(value: float, unit: str, display_unit: str) -> str:
    """Format an SI value in a friendlier unit, e.g. 0.005 m -> '5 mm'."""
    if not display_unit or display_unit == unit:
        return f"{value:g} {unit}".strip()
    ureg = _ureg()
    shown = ureg.Quantity(value, unit or "dimensionless").to(display_unit).magnitude
    return f"{shown:.6g} {display_unit}"
