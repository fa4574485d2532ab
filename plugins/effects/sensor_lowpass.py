"""sensor_lowpass: the acquisition's low-pass (anti-alias) filter, Butterworth of order n.

Physical mismatch. Between the sensor and the converter a real record passes the signal
conditioner's and the converter's anti-alias filter: a low-pass of several poles, usually a
Butterworth (maximally flat) of order 2 to 8 with its corner below the converter's Nyquist
frequency. The simulation reports the acceleration unfiltered. sensor_bandwidth models the
sensor's own second-order response (a mounted resonance, or a 2-pole low-pass); a filter of
higher order rolls off at -20 n dB/decade and cannot be imitated by a second-order one (a
4th-order 5 kHz filter fitted as a second-order one came back as a peaked filter at 2.9 kHz).
Its response, corner f_c, order n:

    H(s) = 1 / prod_k (s / (2 pi f_c) - p_k),   p_k = exp(j pi (2k + n - 1) / (2n)),  k = 1..n,

|H(f)|^2 = 1 / (1 + (f / f_c)^(2n)), applied as the steady-state response (a multiplication of
the record's spectrum, as sensor_bandwidth does: exact for the shaft-synchronous content).

Bounds. f_c from 100 Hz to 100 kHz (above the simulations' band: no effect), as sensor_bandwidth;
n from 1 to 8 poles (what acquisition front ends use). Default 5 kHz, 4 poles.
"""

import numpy as np

from gearlab.api import KHZ, Effect, hookimpl, parameters, setting
from gearlab_plugins.effects.sensor_bandwidth import steady_state


def frequency_response(f: np.ndarray, f_c: float, order: int) -> np.ndarray:
    """H(f) of a Butterworth low-pass of *order* poles and corner *f_c* (Hz)."""
    s = 2j * np.pi * np.asarray(f, dtype=float) / (2 * np.pi * f_c)  # s / omega_c
    k = np.arange(1, int(order) + 1)
    poles = np.exp(1j * np.pi * (2 * k + int(order) - 1) / (2 * int(order)))
    return 1.0 / np.prod(s[..., None] - poles, axis=-1)


class SensorLowpass(Effect):
    name = "sensor_lowpass"
    doc = "the acquisition's anti-alias low-pass: Butterworth of order n with corner f_c"
    params = parameters(
        f_c=setting(float, 5e3, low=100.0, high=1e5, **KHZ, doc="corner (-3 dB) frequency of the filter"),
        order=setting(int, 4, low=1, high=8, doc="number of poles n (roll-off -20 n dB/decade)"),
    )
    log_scale = frozenset({"f_c"})

    def apply_signal(self, x, params, ctx):
        return steady_state(x, ctx.fs, frequency_response, params["f_c"], params["order"])


@hookimpl
def gearlab_effects():
    return [SensorLowpass()]
