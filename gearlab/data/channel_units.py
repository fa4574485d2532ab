"""What a vibration channel's values are in: the unit its name ends in ('acc_V', 'acc [mg]') or its file
states (an HDF5 'units' attribute, a CSV row of units), or a scenario's 'unit' key, with the sensitivity and
gain (data.textzip.calibration), as the factor to m/s² and a line saying how (channel_scale)."""

from __future__ import annotations

import math
import re

import numpy as np

from ..errors import GearlabInputError, did_you_mean, shown
from ..units import to_si

STANDARD_GRAVITY = 9.80665  # m/s², the "g" of accelerometer units and sensitivities (ISO 80000-3)
# a take whose level (rms) is more than this factor off its history's median is said to be (another load or gain): NA4
# is a size, and called an outside lab's healthy 31/73 takes at 1.6 x the load in 50 % of their units
LEVEL_OFF = 1.25
# A level off by a unit's factor is that unit misread, before any load: a take in m/s² scored with a run's 'g'
# keys read 9.5 x its history's, said only '(another load or gain?)'. Within UNIT_NEAR of the factor.
UNIT_FACTORS = ((STANDARD_GRAVITY, "g and m/s²"), (1000.0, "V and mV"))
UNIT_NEAR = 1.25


def level_why(ratio: float) -> str:
    """What a take's level *ratio* to its history's, over LEVEL_OFF off, may be ("another load or gain?", or a unit's
    factor mixed up); "" within (a run's and score's warning, inspect --history's call)."""
    if 1 / LEVEL_OFF <= ratio <= LEVEL_OFF:
        return ""
    units = [w for f, w in UNIT_FACTORS if abs(abs(math.log(ratio)) - math.log(f)) < math.log(UNIT_NEAR)]
    return (
        f"{units[0]} mixed up? check its values: line; or another load or gain?" if units else "another load or gain?"
    )


# A unit at the end of a channel's name, after a separator or in brackets: acc_V, "acc [mV]",
# acc_ms2, "acc (m/s^2)", acc_g, acc_mg. Volts are case-sensitive (a 'v' ends many words).
_VOLT_NAME = re.compile(r"(?:^|[_\s\-.(\[])([mµu]?V)[)\]]?$")
_ACCELERATION_NAME = re.compile(
    r"(?:[_\s\-.(\[])(m/s\^?2|m/s²|m/s/s|m/s\*\*2|m[\s·]?s(?:\^?-2|⁻²)|ms2|mps2|m?g)[)\]]?$", re.IGNORECASE
)
# g in a unit is standard gravity, never the gram: '50 g' (a full scale: one file unit is 50 g), 'mg', 'G'
# ... and as ISO 80000 writes it, with a negative power: 'Beschleunigung [m s^-2]', 'a [ms-2]', 'm·s⁻²' were read as
# no unit ('values: unknown'), as was Python's 'm/s**2'; compared without blanks or '·', '**' as '^', '⁻²' as '^-2'
_METRES_PER_S2 = ("m/s^2", "m/s²", "m/s/s", "ms2", "mps2", "m/s2", "ms^-2", "ms-2")


# A volt or millivolt spelled out, compared in lower case without blanks: a 'unit' key's (declared_unit) and a file's
# (unit_scale) alike. NI's DAQ software states a voltage channel's unit as 'Volts' (a TDMS channel's unit_string, kept
# in its HDF5 export): it was 'values: unknown (the file's unit 'Volts' is not read ...)', read as m/s² where the
# sensitivity was left out, not refused for it as 'V' is
_VOLTS_SPELLED = {"volt": "V", "volts": "V", "millivolt": "mV", "millivolts": "mV"}


def _plain(unit: str) -> str:
    return re.sub(r"[\s·]", "", unit.lower()).replace("**", "^").replace("⁻²", "^-2")


_G_UNIT = re.compile(r"(?P<number>\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)?\s*(?P<prefix>[mµu]?)(?:g|g_n|gn)", re.IGNORECASE)


class FileUnitGain(float):
    """The gain of a full scale given as an acceleration per file unit ('50 m/s^2', '5 g'): data.textzip.calibration
    reads that file unit as 1 V at the sensitivity 1/full scale, and this 1 V is no voltage the user gave, so
    channel_scale's line says the full scale instead ('(1 V / 196.133 mV/g)' was told of gain = '50 m/s^2')."""


class BareGain(float):
    """A gain given as a bare number (gain = 10, --gain 10), read as volts per file unit: of integer counts, a count's
    volts; on decimal values of no stated unit (volts, beside a sensitivity) it is an amplifier's x10 given where
    the sensitivity takes it, their level 100 x too high, unsaid (channel_scale refuses it)."""


# JSON keeps a gain as a number: a run's scoring.json keeps a full scale's as these words, so that gearlab score reads
# and words a file as inspect does (it said '5 g a file unit (1 V / 200 mV/g)' of gain = '5g', the 1 V no one's)
FULL_SCALE = "full scale"


def kept_gain(gain):
    """*gain* as a run's scoring.json keeps it: a FileUnitGain as FULL_SCALE."""
    return FULL_SCALE if isinstance(gain, FileUnitGain) else gain


def read_gain(gain):
    """A gain as a run's scoring.json kept it (kept_gain), as the readers take it."""
    return FileUnitGain(1.0) if gain == FULL_SCALE else gain


def name_unit(name: str) -> tuple[str, str, float] | None:
    """(quantity, unit, SI factor) a channel's name declares: ("voltage", "mV", 1e-3),
    ("acceleration", "g", 9.80665), ...; None when it says none."""
    text = " ".join(str(name).split())
    match = _VOLT_NAME.search(text) or _ACCELERATION_NAME.search(text)
    if match is not None:
        return unit_scale(match.group(1))
    # any other acceleration in brackets ('acc [mm/s²]', 'a (in/s^2)', 'Beschl. [cm/s²]'): they were 'values:
    # unknown ... taken as m/s²', 1000 x or 39 x off, unsaid
    bracketed = _BRACKETED.search(text)
    found = unit_scale(bracketed.group(1)) if bracketed else None
    return found if found and found[0] == "acceleration" else None


def unit_scale(text: str) -> tuple[str, str, float] | None:
    """(quantity, unit, SI per file unit) of a unit a file states for a channel (an HDF5 'units' attribute, a
    CSV row of units) or a name ends in: "voltage" or "acceleration", its prefix and number read ('uV', 'mg',
    'cm/s^2', '50 g'); None for a unit of another quantity or none gearlab reads ('counts', 'EU', 'Pa')."""
    unit = " ".join(str(text).split()).strip("[]() ")
    g = _G_UNIT.fullmatch(unit)
    if g:
        prefix = {"": 1.0, "m": 1e-3}.get(g["prefix"].lower(), 1e-6)
        return "acceleration", unit, float(g["number"] or 1.0) * prefix * STANDARD_GRAVITY
    if _plain(unit) in _METRES_PER_S2:  # as names write it (ms2 is not ms², m/s2 not m per s2)
        return "acceleration", unit, 1.0
    if spelled := _VOLTS_SPELLED.get(re.sub(r"\s", "", unit).lower()):
        return "voltage", unit, 1e-3 if spelled == "mV" else 1.0
    if not re.search(r"[A-Za-zµ]", unit):
        return None
    for quantity, si in (("voltage", "V"), ("acceleration", "m/s^2")):
        try:
            return quantity, unit, to_si(unit.replace("²", "^2"), si, "")
        except GearlabInputError:
            continue
    return None


_BRACKETED = re.compile(r"[\[(]([^\[\]()]+)[\])]\s*$")  # a unit in brackets at a name's end: 'vel [mm/s]', 'v (in/s)'


def _other_quantity(name: str) -> tuple[str, str] | None:
    """(quantity, unit) where a channel's name ends in a bracketed velocity or displacement unit ('vel [mm/s]',
    'disp [um]'); else None."""
    match = _BRACKETED.search(str(name))
    if not (match and any(c.isalpha() for c in match.group(1))):
        return None  # an index ('data[1]', a MAT struct's field read by position) is no unit: a bare number is SI's
    for quantity, si in (("velocity", "m/s"), ("displacement", "m")):
        try:
            if to_si(match.group(1).strip(), si, "") > 0:
                return quantity, match.group(1).strip()
        except GearlabInputError:
            continue
    return None


class VoltsRead(str):
    """channel_scale's words where the file unit's volts are a key's to change (a sensitivity given, no gain, and no
    unit in the channel's name or the file): taken as 1 V where no 'unit' key said one, or given as a millivolt by
    it. level_hint checks the level these values come to; *other* is the key's other reading ('mV' or 'V')."""

    other: str


def _volts_read(how: str, other: str) -> VoltsRead:
    words = VoltsRead(how)
    words.other = other
    return words


# A level read through volts this far off a gearbox housing's is called out, with the unit that reads it 1000 x the
# other way. Over VOLTS_TOO_LOUD_G, of values taken as volts: a logger's millivolts read as volts come out 1000 x too
# large (100 mV/g logged in mV: RMS 470 g, unsaid; a 0.19 g box logged in mV reads 194 g: 50 g still leaves a factor
# of ten over a loud housing). Under MILLIVOLTS_TOO_QUIET_G, of values given as millivolts: volts read as millivolts
# come out 1000 x too small, under a general-purpose accelerometer's own noise (0.1-0.3 mg RMS broadband) (CP's slow
# 6 Hz box, 0.24 g at 100 mV/g given 'mV': 0.24 mg, unsaid)
VOLTS_TOO_LOUD_G = 50.0
MILLIVOLTS_TOO_QUIET_G = 1e-3
TOO_LOUD = "too loud for a gearbox"  # level_hint's words, which a detection run's warnings repeat
TOO_QUIET = "too quiet for a gearbox"


def level_hint(units: str, values: np.ndarray, key: str) -> str:
    """'' or, where *units* read the file's values through volts a key may change (VoltsRead) and *values* (m/s²)
    come to an RMS over VOLTS_TOO_LOUD_G as volts or under MILLIVOLTS_TOO_QUIET_G as millivolts, the words that say
    so and how to give the other unit (*key*: "--unit {}", "unit = '{}'")."""
    if not isinstance(units, VoltsRead) or values.size == 0:
        return ""
    rms = float(np.sqrt(np.mean(np.square(values - np.mean(values))))) / STANDARD_GRAVITY
    if units.other == "mV" and rms >= VOLTS_TOO_LOUD_G:
        said, other = TOO_LOUD, "millivolts"
    elif units.other == "V" and rms <= MILLIVOLTS_TOO_QUIET_G:
        said, other = TOO_QUIET, "volts"
    else:
        return ""
    return f"; RMS {rms:.3g} g, {said}: values in {other}? {key.format(units.other)}"


# What a measured entry's 'unit' key may say of a vibration channel whose name and file say nothing
# (a headerless text column): the quantity and factor are name_unit's, as if the name ended in it.
UNITS = ("m/s^2", "m/s²", "g", "V", "mV")
# ... and a volt or millivolt as it is spelled out ('volts', 'Volt', 'millivolts': _VOLTS_SPELLED), as a file states it
# too (unit_scale); the symbols themselves stay case-sensitive ('G' is no g, 'MV' no mV)


def declared_unit(value, where: str):
    """A 'unit' key's *value* as UNITS writes it ('volts' -> 'V'), None or '' as given (none declared), else one line
    naming *where*."""
    if value in (None, "") or value in UNITS:
        return value
    read = _VOLTS_SPELLED.get(re.sub(r"\s", "", value).lower()) if isinstance(value, str) else None
    if isinstance(value, str) and value.strip()[:1].isdigit():  # '50 g' was read as g, its 50 dropped: 50 x off
        raise GearlabInputError(
            f"{where}: {shown(value)} is a full scale, not a unit; expected a unit ({', '.join(UNITS)}), or no unit "
            f"and the full scale as the gain (gain = {shown(miscased(value) or value)})"
        )
    # any other acceleration or volt a name may end in ('mg', 'mm/s²', 'in/s^2', 'uV'): was refused; the symbols'
    # case stays as said above ('G', 'MV', 'mG' refused: miscased)
    cased = isinstance(value, str) and "G" not in value and not miscased(value)
    if read is None and cased and name_unit(f"[{value}]") is not None:
        return value
    if read is None:
        other = _other_quantity(f"[{value}]") if isinstance(value, str) else None
        if other:  # 'mm/s' was 'not one of ... (did you mean 'm/s²'?)'
            raise GearlabInputError(
                f"{where}: {shown(value)} is a {other[0]}; expected an acceleration (m/s², g, mg, mm/s², ...) or an "
                "accelerometer's volts (V, mV): record the accelerometer's own signal"
            )
        raise GearlabInputError(
            f"{where}: {shown(value)} is not one of {', '.join(UNITS)}, nor another acceleration or voltage unit "
            f"(e.g. 'mg', 'mm/s²'){_cased(value) or did_you_mean(str(value), UNITS)}"
        )
    return read


# The one rule of a unit's case, for a 'unit' key (--unit) and a unit a file states alike: a symbol's case is its
# meaning (G is giga or gauss, MV megavolt, mG milligauss), so one written in another case than these is refused with
# the symbol meant, never read as a guess. A file's unit is its DAQ's, outside the user's control: its refusal names
# the key that reads the file (unit = 'g', --unit g), which then wins over that unit (channel_scale), and the run's
# 'values:' line says so. (A channel's name is no unit's text: 'ACC_G', a logger's upper-cased name, reads as g.)
_SYMBOLS = UNITS + ("mg", "µg", "ug", "uV", "µV")


def miscased(value) -> str:
    """The symbol *value* writes in another case ('G' -> 'g', 'MV' -> 'mV', '50 G' -> '50 g', 'M/S^2' -> 'm/s^2'),
    else ''."""
    found = re.fullmatch(r"(\d+(?:\.\d*)?\s*)?(.+)", " ".join(value.split())) if isinstance(value, str) else None
    if found is None or found[2] in _SYMBOLS:
        return ""
    same = [u for u in _SYMBOLS if found[2].lower() == u.lower()]
    return (found[1] or "") + same[0] if same else ""


def _cased(value) -> str:
    """The refusal's hint where *value* is a symbol in the wrong case (miscased): difflib's likeness of 'G' to 'g'
    (none) does not see it."""
    meant = miscased(value)
    return f" (did you mean {meant!r}? a unit's symbol is case-sensitive)" if meant else ""


def _dropped(key: str) -> str:
    """How a key given for every file (a scenario's [target], a run's keys for gearlab score) is dropped for one file:
    said where a file's own unit refuses it, or the user is stuck (a WAV run's full-scale gain on a CSV in volts)."""
    return f'to drop one given for every file: {key} = "" in this file\'s entry; gearlab score: --key {key}='


def channel_scale(
    name: str,
    sensitivity: float | None,
    gain: float | None,
    where: str,
    integer: bool = False,
    unit: str | None = None,
    declared: str | None = None,
    flag=None,
    path: str = "",
) -> tuple[float, str]:
    """(m/s² per file value, how) of a vibration channel: gain / sensitivity, with what the channel's name -- or else
    the *unit* the file states for it (an HDF5 'units' attribute), or else the scenario's 'unit' key (*declared*, which
    neither may contradict) -- says of its unit (volts, and a gain in volts, need a sensitivity; m/s² or g have none;
    mV are volts / 1000). *where*: the scenario table, for the one-line errors naming its key (or *flag*(key): a
    command's option); *integer*: the channel holds integer counts (a sensitivity then needs a gain); *path*: the
    file, where *where* is not it."""
    of = f" of {path}" if path else ""

    def at(key: str) -> str:
        return f"{where}: {flag(key)}" if flag else f"{where} key '{key}'"

    for text, by in ((name, "as its name says"), (f"[{unit}]" if unit else "", f"as the file's unit '{unit}' says")):
        if other := _other_quantity(text):  # a velocity read as m/s² was no gearbox's acceleration, unsaid
            raise GearlabInputError(
                f"{at('vibration')}: channel '{name}'{of} ({by}); expected an acceleration (m/s², g) or an "
                f"accelerometer's volts, not a {other[0]} in {other[1]}: record the accelerometer's own signal"
            )
    said, says, keyed = name_unit(name), "as its name says", False
    if said is None and unit is not None and (meant := miscased(unit)):  # the rule above _SYMBOLS
        key = "gain" if meant[:1].isdigit() else "unit"  # a full scale ('50 G') is a gain's
        if (gain if key == "gain" else declared) is None:
            raise GearlabInputError(
                f"{at(key)}: missing; channel '{name}' of {path or where} states its unit as '{unit}', not "
                f"'{meant}' (a unit's symbol is case-sensitive); expected the unit its values are in, e.g. "
                + (f"{flag(key)} '{meant}'" if flag else f"{key} = '{meant}'")
            )
    elif said is None and unit is not None:
        said, says = unit_scale(unit), f"as the file's unit '{unit}' says"
    if declared is not None:
        declared = declared_unit(declared, at("unit"))
        given = name_unit(f"[{declared}]")
        if said is not None and (said[0], said[2]) != (given[0], given[2]):  # m/s^2 and ms2 agree
            raise GearlabInputError(
                f"{at('unit')}: '{declared}' contradicts channel '{name}'{of}, which is in {said[1]} ({says}); "
                f"expected no unit (or '{said[1]}')"
            )
        if said is None:
            said, says, keyed = given, "as " + (flag("unit") if flag else "key 'unit'") + " says", True
    if said is not None and said[0] == "voltage" and sensitivity is None:
        raise GearlabInputError(
            f"{at('sensitivity')}: missing; channel '{name}' is in volts ({said[1]}, {says}); "
            "expected the sensor's sensitivity, e.g. sensitivity = '100 mV/g'"
        )
    if said is not None and said[0] == "voltage" and gain is not None and not integer:
        # a gain is volts per file unit: on a channel in volts an amplifier's x10 multiplied the level by 10 where
        # the sensitivity was to be multiplied, a level 100 x off, unsaid
        raise GearlabInputError(
            f"{at('gain')}: channel '{name}' is in volts already ({said[1]}, {says}); expected no gain (an "
            f"amplifier's gain goes in the sensitivity: 100 mV/g at x10 is sensitivity = '1 V/g'; {_dropped('gain')})"
        )
    if said is None and isinstance(gain, BareGain) and not integer and sensitivity is not None:
        raise GearlabInputError(
            f"{at('gain')}: {gain:g} with no unit, on the decimal values of channel '{name}'{of}, read as volts; "
            "expected no gain (an amplifier's gain goes in the sensitivity: 100 mV/g at x10 is sensitivity = "
            "'1 V/g'), or the volts per file unit with its unit (e.g. '0.3 mV')"
        )
    if said is not None and said[0] == "acceleration":
        for key, value in (("gain", gain), ("sensitivity", sensitivity)):  # a gain in g is read as both
            if value is not None and declared is not None:  # which of the two is wrong, only the user knows
                raise GearlabInputError(
                    f"{at('unit')}: '{declared}' says channel '{name}' is an acceleration already; expected no {key} "
                    "(values in volts: unit = 'V' or 'mV' with the sensitivity; values in g at a full scale of N g: "
                    "no unit, gain = 'N g')"
                )
            if value is not None:
                # a key given for every file (a scenario's [target], a run's keys for gearlab score) is dropped for
                # one file by giving it empty: say how, or the user is stuck (an npz in m/s² scored on a volts run)
                raise GearlabInputError(
                    f"{at(key)}: channel '{name}' is an acceleration already ({said[1]}, {says}); expected no {key} "
                    f"({_dropped(key)})"
                )
        if said[2] == 1.0:
            return 1.0, f"m/s² (channel '{name}')"
        scale = f": one file unit is {said[1]}" if said[1][:1].isdigit() else ""  # '50 g', a full scale
        return said[2], f"m/s² = value x {said[2]:g} (channel '{name}' in {said[1]}{scale})"
    if integer and sensitivity is not None and gain is None:
        raise GearlabInputError(
            f"{at('gain')}: missing; channel '{name}' holds integer counts, so the sensitivity needs the "
            "volts per count (a WAV file's: the volts at its full scale, e.g. gain = '10 V'; an integer array's: "
            "e.g. gain = '0.3 mV')"
        )
    volts = gain if gain is not None else (said[2] if said is not None else 1.0)
    if sensitivity is None and gain is None:
        unread = f"the file's unit '{unit}' is not read; " if unit is not None and said is None else ""
        return 1.0, f"unknown ({unread}no sensitivity or gain given: the values are taken as m/s²)"
    if sensitivity is None:  # volts, not m/s²
        raise GearlabInputError(
            f"{at('gain')}: {gain:g} V per file unit gives volts; expected a sensitivity too (e.g. '100 mV/g'), or "
            "the gain in g per volt (e.g. '10 g/V') or in g per file unit (a full scale, e.g. '50 g')"
        )
    scale, per_g = volts / sensitivity, f"{sensitivity * STANDARD_GRAVITY * 1e3:.6g} mV/g"
    if isinstance(gain, FileUnitGain):  # no volt was given: the full scale, as the user meant it
        return (
            scale,
            f"m/s² = value x {scale:.6g}, {scale / STANDARD_GRAVITY:.6g} g a file unit (the gain, a full scale)",
        )
    # in g too, as a scenario gives them: a gain of '50 g' reads '50 g a file unit'
    how = f"m/s² = value x {scale:.6g}, {scale / STANDARD_GRAVITY:.6g} g a file unit ({volts:g} V / {per_g})"
    if gain is None and said is None:
        return scale, _volts_read(how, "mV")
    if gain is None and keyed and math.isclose(said[2], 1e-3):  # millivolts the 'unit' key gave
        return scale, _volts_read(how, "V")
    return scale, how
