"""A measured record's calibration and its tacho marks: what the PHM 2009 text records (one
whitespace-separated text a record, zipped, voltages as measured, no sampling rate) need besides
the read, which is the one import path's (gearlab.data.recordings, gearlab.data.readers.text).

* vibration in m/s² = volts / sensitivity: :func:`parse_sensitivity` (pint, "10 mV/g"), a gain
  per file unit :func:`gain_quantity`, both of a table: :func:`calibration`;
* two records of one shaft start at any of a tacho's N marks, 2πm/N apart (the j-th rising edge
  is at θ = 2πj/N, :func:`gearlab.signals.angle_from_pulses` divided by N): :func:`align_to` finds m.

Every bad value raises :class:`GearlabInputError` naming where it is and what was expected.
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import GearlabInputError, shown
from ..units import to_si
from .channel_units import STANDARD_GRAVITY, BareGain, FileUnitGain

__all__ = ["align_to", "calibration", "gain_quantity", "parse_sensitivity"]

# V per m/s²: accelerometers span 0.01 mV/g (shock) to 10 V/g (seismic); outside it, a unit is wrong
SENSITIVITY_RANGE = (1e-5 / STANDARD_GRAVITY, 10.0 / STANDARD_GRAVITY)


# --- sensor sensitivity ------------------------------------------------------------------

# "g" in a sensitivity or gain is standard gravity, never the gram: pint's name for it is g_n; after a digit too
# ("5g", a data sheet's full scale) and with milli ("1 mg": counts of a milli-g), never in a word ("kg").
_GRAVITY = re.compile(r"(?<![A-Za-z_.])(m?)g(?!\w)")


def parse_sensitivity(value, where: str) -> float:
    """An accelerometer sensitivity ("10 mV/g", "1.02 mV/(m/s^2)", its inverse "10 g/V", or a number in
    V/(m/s²)) as volts per m/s²."""
    written = value if isinstance(value, str) else None  # messages quote the user's text
    try:
        number, unit = _quantity(value, ("V*s^2/m", "m/s^2/V"), where)
    except GearlabInputError as exc:
        charge = _charge_per_acceleration(value, where)  # a charge accelerometer's data sheet: '10 pC/g'
        said = f"{exc} (volts per acceleration; g is standard gravity)"  # its example given by the quantity's line
        raise GearlabInputError(charge or said) from None
    s = number if unit == "V*s^2/m" or not number > 0 else 1.0 / number
    if not s > 0:
        raise GearlabInputError(
            f"{where}: expected a positive sensitivity such as '10 mV/g', got {shown(value)}"
            + (" (an inverting amplifier's: give its magnitude, the same for every take)" if s < 0 else "")
        )
    if not SENSITIVITY_RANGE[0] <= s <= SENSITIVITY_RANGE[1]:
        # a bare number is V per m/s²: '100' meant as 100 mV/g would scale the record by ~1000
        said = f"{shown(value if written is None else written)} ({s:.3g} V per m/s²)"
        raise GearlabInputError(
            f"{where}: {said} is no accelerometer's sensitivity (0.01 mV/g to 10 V/g); expected one with its unit, "
            "e.g. '100 mV/g'"
        )
    return s


def _charge_per_acceleration(value, where: str) -> str | None:
    """The line for a sensitivity given as charge per acceleration ('10 pC/g': it was 'has the wrong dimension;
    expected a quantity in V*s^2/m'), naming the amplifier's gain it needs; None for any other text."""
    try:
        _quantity(value, ("C*s^2/m",), where)
    except GearlabInputError:
        return None
    return (
        f"{where}: {shown(value)} is a charge accelerometer's sensitivity (charge per acceleration); expected volts "
        "per acceleration at the logger: it times the charge amplifier's gain, e.g. 10 pC/g at 10 mV/pC is '100 mV/g'"
    )


def _quantity(value, units: tuple[str, ...], where: str) -> tuple[float, str]:
    """(value in SI, which of *units* it has): the first unit whose dimension the text has; a bare
    number is in units[0]. Else the error of units[0] (the form most people write)."""
    written = value if isinstance(value, str) else None
    text = _GRAVITY.sub(r"\1g_n", value) if isinstance(value, str) else value
    first = None
    for unit in units:
        try:
            return to_si(text, unit, where, as_written=written), unit
        except GearlabInputError as exc:
            first = first or exc
    raise first


# A gain by its dimension: volts per file unit (beside a sensitivity), an acceleration per volt (a
# sensitivity's inverse) or an acceleration per file unit (a WAV's full scale, "50 g"; counts of "1 mg").
GAIN_UNITS = ("V", "m/s^2/V", "m/s^2")
CALIBRATION = ("sensitivity", "gain")


def gain_quantity(value, where: str) -> tuple[float, str]:
    """(SI value, which of GAIN_UNITS) of a 'gain', else one line naming *where* (calibration: positive)."""
    try:
        number, unit = _quantity(value, GAIN_UNITS, where)
    except GearlabInputError:
        raise GearlabInputError(
            f"{where}: cannot read {shown(value)} as a gain; expected volts per file unit with a sensitivity "
            "(e.g. '0.3 mV'), or an acceleration per volt (e.g. '10 g/V') or per file unit (a full scale, e.g. "
            "'50 g'); g is standard gravity"
        ) from None
    return number, unit


def calibration(given: dict, at) -> dict:
    """'sensitivity' (V per m/s²) and 'gain' (V per file unit) from the keys *given* of them (None or
    "": not given), as the readers take them (recordings.channel_scale: m/s² = value x gain /
    sensitivity): a gain in g per volt is a sensitivity; a gain in g per file unit is that file unit
    read as 1 V at the sensitivity 1/gain, so that both set every reading of a file alike. *at(key)*
    names a key in the one-line errors; a gain in g beside a sensitivity is one."""
    values = {key: None if given.get(key) in (None, "") else given[key] for key in CALIBRATION if key in given}
    out = dict(values)
    if values.get("sensitivity") is not None:
        out["sensitivity"] = parse_sensitivity(values["sensitivity"], at("sensitivity"))
    if values.get("gain") is None:
        return out
    number, unit = gain_quantity(values["gain"], at("gain"))
    if not number > 0:
        raise GearlabInputError(
            f"{at('gain')}: expected a positive voltage per file unit such as '0.3 mV', got {shown(values['gain'])} "
            "(or a positive acceleration per volt or per file unit, e.g. '50 g')"
        )
    if unit == "V":  # a bare number kept so (BareGain): on decimal values in volts, channel_scale refuses it
        bare = not isinstance(values["gain"], str) or re.fullmatch(r"\s*[-+.\deE]+\s*", values["gain"])
        return out | {"gain": BareGain(number) if bare else number}
    if values.get("sensitivity") is not None:
        per = "volt" if unit == "m/s^2/V" else "file unit"
        raise GearlabInputError(
            f"{at('gain')}: {shown(values['gain'])} is an acceleration per {per}, which the sensitivity "
            f"{shown(values['sensitivity'])} would scale again; expected no sensitivity (or a gain in volts, "
            "e.g. '2 V')"
        )
    if unit == "m/s^2/V":
        return {"sensitivity": parse_sensitivity(values["gain"], at("gain")), "gain": None}
    return {"sensitivity": 1.0 / number, "gain": FileUnitGain(1.0)}


# Up to this many marks, each is tried in turn (as cheap as the FFT, and the first of equal correlations kept);
# more are tried at once (align_to).
_MARKS_LOOPED = 4096


def align_to(reference: np.ndarray, signal: np.ndarray, marks: int) -> tuple[int, np.ndarray]:
    """(m, *signal* advanced by m/*marks* of a turn), m = 0 … marks-1 the advance whose mean
    revolution correlates best with *reference* (rows of *signal*: revolutions).

    Two records of one shaft may start at different tacho marks, i.e. 2πm/N apart; the shift
    is done in the order domain (exact for a periodic, band-limited revolution)."""
    best = align_turn(reference, signal, marks)
    orders = np.arange(reference.shape[-1] // 2 + 1)
    phase = np.exp(2j * np.pi * orders * best / marks)
    shifted = np.fft.irfft(np.fft.rfft(signal, axis=-1) * phase, n=reference.shape[-1], axis=-1)
    return best, shifted.astype(signal.dtype, copy=False)


def align_turn(reference: np.ndarray, signal: np.ndarray, marks: int) -> int:
    """align_to's m alone: a record advanced as one signal (parts.measured.aligned, continuous) needs no row
    turned on itself (align_to's FFT of every revolution)."""
    R = np.fft.rfft(reference)
    S = np.fft.rfft(np.mean(np.atleast_2d(signal), axis=0))
    orders = np.arange(R.size)
    if marks <= _MARKS_LOOPED:
        best, best_corr = 0, -np.inf
        for m in range(marks):
            phase = np.exp(2j * np.pi * orders * m / marks)  # x(θ) -> x(θ + 2πm/marks)
            corr = float(np.real(np.sum(np.conj(R) * S * phase)))
            if corr > best_corr:
                best, best_corr = m, corr
    else:
        # corr(m) = Re Σ_k conj(R_k) S_k e^(2πi k m / marks) at every m at once: the products folded onto k mod
        # marks, one inverse FFT of length marks (a 60-mark encoder on a three-stage box's output: 605880 marks,
        # minutes a take looped)
        folded = np.zeros(marks, dtype=complex)
        np.add.at(folded, orders % marks, np.conj(R) * S)
        best = int(np.argmax(np.real(np.fft.ifft(folded))))
    return best
