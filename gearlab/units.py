"""Quantities with units: SI numbers or strings such as "3.175 mm", "20 deg", "25.2 Hz".

Parsing goes through pint; everything inside gearlab is a float in SI base units.
"""

from __future__ import annotations

import functools
import math
import re

import pint

from .errors import GearlabInputError, shown


@functools.cache
def _ureg() -> pint.UnitRegistry:
    return pint.UnitRegistry(autoconvert_offset_to_baseunit=True)


def to_si(value: object, unit: str, where: str, *, as_written: str | None = None) -> float:
    """Convert *value* (a number already in *unit*, or a string with its own unit) to *unit*.

    *unit* is the SI unit the caller stores ("m", "rad", "Hz", "N*m", "" for a pure number).
    *where* names the place the value came from, for the error message; *as_written*, the
    user's own text when the caller rewrote it before (messages quote what the user wrote).
    """
    if isinstance(value, bool):
        raise GearlabInputError(
            f"{where}: expected a number or a quantity with a unit of {_describe(unit)}, got {value!r}"
        )
    if isinstance(value, (int, float)):
        try:
            number = float(value)
        except OverflowError:  # an integer beyond any float (TOML integers have no size limit)
            raise GearlabInputError(f"{where}: expected a finite number, got {shown(value)}") from None
    elif isinstance(value, str):
        number = _parse(value, unit, where, as_written if as_written is not None else value)
    else:
        raise GearlabInputError(
            f"{where}: expected a number or a quantity with a unit of {_describe(unit)}"
            f", got {type(value).__name__} {shown(value)}"
        )
    if not math.isfinite(number):
        raise GearlabInputError(f"{where}: expected a finite number, got {value!r}")
    return number


# What a quantity's text may hold, checked before pint evaluates it: pint computes powers
# exactly, so "9**9**9 Hz" would never return. Units need only small powers (m^2, s**-1).
_MAX_TEXT = 100
_MAX_POWERS = 4  # with exponents up to 9, nested powers stay below 9**4 = 6561
_POWER = re.compile(r"(?:\*\*|\^)\s*(?P<exponent>[-+]?\s*\d+(?:\.\d*)?)?(?P<chained>\s*(?:\*\*|\^))?")


def _screen(text: str, unit: str, where: str) -> None:
    if len(text) > _MAX_TEXT:
        raise GearlabInputError(f"{where}: {text[:40]!r}... is too long for a quantity; expected e.g. '3.175 mm'")
    if "," in text:  # pint reads "1,5 mm" as 15 mm
        raise GearlabInputError(
            f"{where}: {text!r}: write the number with a decimal point and no commas, "
            f"e.g. '3.175 mm' ({_describe(unit)})"
        )
    powers = list(_POWER.finditer(text))
    for power in powers:
        exponent = power.group("exponent")
        if (
            len(powers) > _MAX_POWERS
            or exponent is None
            or power.group("chained")
            or abs(float(exponent.replace(" ", ""))) > 9
        ):
            raise GearlabInputError(
                f"{where}: {text!r}: a power in a quantity must be a small number, as in 'm^2' or 's**-1'"
            )


def _parse(text: str, unit: str, where: str, written: str | None = None) -> float:
    written = text if written is None else written
    _screen(text, unit, where)
    ureg = _ureg()
    try:
        quantity = ureg.Quantity(text.strip().replace("µ", "u").replace("μ", "u"))
    except Exception:
        raise GearlabInputError(
            f"{where}: cannot read {written!r} as a quantity; expected e.g. {example(unit)!r} ({_describe(unit)})"
            f"{_case_hint(written)}"
        ) from None
    target = ureg.Unit(unit) if unit else ureg.dimensionless
    try:
        if not isinstance(quantity, pint.Quantity):
            return float(quantity)
        if quantity.units == ureg.dimensionless:  # a bare number is already SI ("5 %" is not bare)
            return float(quantity.magnitude)
        return float(quantity.to(target).magnitude)
    except pint.DimensionalityError:
        raise GearlabInputError(
            f"{where}: {written!r} has the wrong dimension; expected a quantity in {_describe(unit)}, "
            f"e.g. {example(unit)!r}{_case_hint(written)}"
        ) from None
    except OverflowError:
        raise GearlabInputError(f"{where}: expected a finite number, got {written!r}") from None
    except (TypeError, ValueError, ArithmeticError):  # a complex magnitude, an offset unit's arithmetic, ...
        raise GearlabInputError(
            f"{where}: cannot read {written!r} as a quantity; expected e.g. {example(unit)!r} ({_describe(unit)})"
        ) from None


# An example quantity per stored unit, for messages (a length is no example of a frequency).
EXAMPLES = {
    "m": "3.175 mm",
    "rad": "20 deg",
    "Hz": "25 Hz",
    "N*m": "100 N*m",
    "N": "500 N",
    "N/m": "2e8 N/m",
    "V": "0.5 mV",
    "V*s^2/m": "10 mV/g",
    "s": "0.4 s",
    "kg": "1.2 kg",
    "kg*m^2": "0.002 kg*m^2",
    "Pa": "206 GPa",
    "W": "1.5 kW",
    "m/s^2": "9.81 m/s^2",
    "": "0.5",
}

# Units people type, in their case-sensitive spelling: '10 mv/g' is read as millivolt only when
# written 'mV' (pint's 'mv' is no unit; 'MM' would be megamolar).
_COMMON = (
    "mV", "uV", "V", "kV", "Hz", "kHz", "MHz", "mm", "um", "cm", "m", "km", "N", "kN", "rpm", "deg",
    "rad", "s", "ms", "us", "g", "kg", "Pa", "kPa", "MPa", "GPa", "W", "kW", "mW", "dB",
)  # fmt: skip


def example(unit: str) -> str:
    """An example quantity in *unit* for a message: '25 Hz' for Hz, '10 mV/g' for a sensitivity."""
    return EXAMPLES.get(unit.replace(" ", ""), f"1 {unit}" if unit else "0.5")


def _case_hint(text: str) -> str:
    """'; units are case-sensitive: mV' when *text* holds a common unit in the wrong case."""
    right = []
    for token in re.findall(r"[A-Za-z_]+", text):
        if token in _COMMON:
            continue
        match = next((c for c in _COMMON if c.lower() == token.lower()), None)
        if match and match not in right:
            right.append(match)
    return f"; units are case-sensitive: {', '.join(right)}" if right else ""


def _describe(unit: str) -> str:
    return unit if unit else "a pure number"


def display(value: float, unit: str, display_unit: str) -> str:
    """Format an SI value in a friendlier unit, e.g. 0.005 m -> '5 mm'."""
    if not display_unit or display_unit == unit:
        return f"{value:g} {unit}".strip()
    ureg = _ureg()
    shown = ureg.Quantity(value, unit or "dimensionless").to(display_unit).magnitude
    return f"{shown:.6g} {display_unit}"
