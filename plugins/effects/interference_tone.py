"""interference_tone: a non-synchronous tone from a nearby machine (thesis chapter 4 introduction).

Physical mismatch. "Data captured on an industrial gearbox may be affected by ... vibrational
excitation from nearby machines": a motor, pump or fan on the same foundation adds a line at
its own running frequency, which is not a multiple of the gearbox's shaft speed. It is a
sinusoid of fixed amplitude in time,

    x(t) += sqrt(2) A_rms sin(2 pi f_i t),   A_rms = ratio x RMS of the domain's healthy signal,

with t the time of the record (t0 is random per record, so its phase differs from sample to
sample). In the order domain it is a line at the non-integer order f_i / f_shaft in every
revolution, and TSA over J revolutions attenuates it (it is not shaft-synchronous). Its
level is given relative to the healthy signal's RMS so the same parameters mean the same
thing on a pinion (~100 m/s^2) and a casing (~0.1 m/s^2) channel.

Bounds. Frequency from 1 Hz to 20 kHz (foundation-borne vibration of other machines and the
usable band of accelerometers); it must lie below the Nyquist frequency of the record
(4096 x shaft speed / 2). Level ratio 0 (no tone) to 10 (a neighbour far louder than the
gearbox). Defaults: 24.75 Hz, a 4-pole induction motor on 50 Hz mains at 1 % slip, and a
ratio of 0.5.
"""

import numpy as np

from gearlab.effects import Effect
from gearlab.errors import GearlabInputError
from gearlab.params import Param
from gearlab.registry import hookimpl


class InterferenceTone(Effect):
    name = "interference_tone"
    doc = "non-synchronous sinusoid from a nearby machine, level relative to the healthy signal RMS"
    level = "signal"
    breaks_symmetry = False
    params = (
        Param("frequency", "Hz", 24.75, 1.0, 2e4, "frequency of the interfering machine's line"),
        Param("ratio", "", 0.5, 0.0, 10.0, "tone RMS / RMS of the domain's healthy signal"),
    )
    log_scale = frozenset({"frequency"})

    def apply_signal(self, x, params, ctx):
        f = params["frequency"]
        if f >= ctx.fs / 2:
            raise GearlabInputError(
                f"effect 'interference_tone': frequency {f:g} Hz is above the Nyquist frequency {ctx.fs / 2:g} Hz "
                f"of the record (4096 samples per revolution at {ctx.speed_hz:g} Hz)"
            )
        record = np.asarray(x, dtype=float)
        t = ctx.time(record.size).reshape(record.shape)
        amplitude = np.sqrt(2.0) * params["ratio"] * ctx.reference_rms
        return record + amplitude * np.sin(2 * np.pi * f * t)


@hookimpl
def gearlab_effects():
    return [InterferenceTone()]
