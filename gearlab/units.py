"""Quantities with units: SI numbers or strings such as "3.175 mm", "20 deg", "25.2 Hz".

Parsing goes through pint; everything inside gearlab is a float in SI base units. The units
scenarios use are read from a table of pint's own factors first: building pint's registry takes
0.2-0.3 s, a third of `gearlab validate` (issue 42), and the table gives the same floats. A unit
written bare ('V', 'mV': a column named for its unit, 'acc_gear_V') is one of it, as pint reads it.
"""

from __future__ import annotations

import functools
import math
import re

from .errors import GearlabInputError, shown


@functools.cache
def _ureg():
    import pint  # 0.3 s with its registry: only for the units FACTORS does not hold

    return pint.UnitRegistry(autoconvert_offset_to_baseunit=True)


# FACTORS[to][written]: pint's conversion factor from the unit *written* to the unit *to*, so that
# a number times it is the float pint returns (pint converts a magnitude by one multiplication).
# Written out, not computed, so that common quantities need no registry; tests/test_units.py checks
# every entry and many numbers against pint. A unit spelled otherwise still goes through pint.
FACTORS = {
    "m": {"m": 1.0, "mm": 0.001, "um": 1e-06, "cm": 0.01, "km": 1000.0, "in": 0.0254},
    "mm": {"m": 1000.0},
    "um": {"m": 1000000.0},
    "rad": {"rad": 1.0, "deg": 0.017453292519943295},
    "deg": {"rad": 57.29577951308232},
    "Hz": {"Hz": 1.0, "kHz": 1000.0, "MHz": 1000000.0},
    "kHz": {"Hz": 0.001},
    "revolution/s": {"rpm": 0.016666666666666666, "rad/s": 0.15915494309189535, "deg/s": 0.002777777777777778},
    "N*m": {"N*m": 1.0, "kN*m": 1000.0},
    "N": {"N": 1.0, "kN": 1000.0},
    "N/m": {"N/m": 1.0},
    "N*s/m": {"N*s/m": 1.0},
    "N*m/rad": {"N*m/rad": 1.0},
    "N*m*s/rad": {"N*m*s/rad": 1.0},
    "V": {"V": 1.0, "mV": 0.001, "uV": 1e-06},
    "V*s^2/m": {"V*s^2/m": 1.0, "mV/g_n": 0.00010197162129779284, "V/g_n": 0.10197162129779283, "mV/(m/s^2)": 0.001},
    "s": {"s": 1.0, "ms": 0.001, "us": 1e-06},
    "kg": {"kg": 1.0, "g": 0.001},
    "kg*m^2": {"kg*m^2": 1.0},
    "kg/m^3": {"kg/m^3": 1.0},
    "Pa": {"Pa": 1.0, "kPa": 1000.0, "MPa": 1000000.0, "GPa": 1000000000.0},
    "W": {"W": 1.0, "kW": 1000.0, "mW": 0.001},
    "m/s^2": {"m/s^2": 1.0, "g_n": 9.80665},
}  # fmt: skip

# An unsigned number as pint reads it (a signed one, whose integer zero pint keeps unsigned, and
# Python's other literals go through pint), or none (a bare unit: one of it), then the unit as written.
_QUANTITY = re.compile(
    r"\s*(?P<number>(?:0|[1-9]\d*)(?:\.\d*)?(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)?\s*(?P<unit>.*?)\s*"
)


def _from_table(text: str, unit: str) -> float | None:
    """*text* in *unit* by FACTORS, or None when the table cannot say (pint then decides)."""
    match = _QUANTITY.fullmatch(text)
    if match is None:
        return None
    written, digits = match.group("unit"), match.group("number")
    if digits is None and not written:
        return None
    factor = FACTORS.get(unit, {}).get(written) if written else 1.0  # a bare number is SI already
    if factor is None:
        return None
    # a bare unit is one of it, as pint reads it: each process that read a column named 'acc_gear_V' or
    # 'acc [mV]' (channel_units.name_unit) built the registry for it, 0.5-0.7 s of CPU with pint's import
    number = (1.0 if digits is None else float(digits)) * factor
    return number if math.isfinite(number) else None  # pint's own words for an overflow


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


# A sampling rate's units: a data sheet's samples per second ('51.2 kS/s', 'Sa/s'; pint's S is the siemens)
# are hertz; one with an angle (rpm, rad/s, deg/s, turns, cycles) is a shaft's speed, which pint reads in
# radians ('6400 rpm' as 670 Hz), never a sampling rate.
_SAMPLES_PER_SECOND = re.compile(r"(?<![A-Za-z])([kMG]?)(?:S|Sa)/s\b")
_ANGULAR = re.compile(r"rpm|rev|turn|rad|deg|cycle|°", re.IGNORECASE)


def rate_hz(value: object, where: str) -> float:
    """A sampling rate in Hz (to_si): 'S/s' read as Hz; a unit with an angle refused in one line naming
    *where*."""
    if not isinstance(value, str):
        return to_si(value, "Hz", where)
    if _ANGULAR.search(value):
        raise GearlabInputError(
            f"{where}: {shown(value)} is a rotational speed, not a sampling rate; expected samples per second "
            "in Hz, e.g. '51.2 kHz' or '51.2 kS/s'"
        )
    return to_si(_SAMPLES_PER_SECOND.sub(r"\1Hz", value), "Hz", where, as_written=value)


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
    text = text.strip().replace("µ", "u").replace("μ", "u")
    known = _from_table(text, unit)
    if known is not None:
        return known
    import pint

    ureg = _ureg()
    try:
        quantity = ureg.Quantity(text)
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
    factor = FACTORS.get(display_unit, {}).get(unit)
    if factor is not None:
        return f"{value * factor:.6g} {display_unit}"
    ureg = _ureg()
    shown = ureg.Quantity(value, unit or "dimensionless").to(display_unit).magnitude
    return f"{shown:.6g} {display_unit}"
