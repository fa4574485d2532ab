"""sensor_bandwidth: the accelerometer's own dynamics, a low-pass with a mounted resonance.

Physical mismatch. The simulation returns the acceleration of a DOF exactly; a real sensor
reports it through its mounted resonance (a seismic mass on a stiff element, plus the
compliance of a stud, adhesive or magnet) and the acquisition's filters. Both behave, to a
first approximation, like a second-order system of natural frequency f_n and damping
ratio zeta:

    H(f) = 1 / (1 - r^2 + 2 j zeta r),   r = f / f_n,

flat well below f_n, a peak of 1/(2 zeta) at f_n when lightly damped (a resonance), and
-40 dB/decade above it; zeta = 0.707 is the maximally flat (Butterworth) low-pass of an
anti-alias filter. H is applied as the steady-state response: a multiplication of the
record's spectrum, i.e. a circular filter over the record's J revolutions, exact for the
shaft-synchronous content (the gear vibration) and for any record that is periodic.

Bounds. f_n from 100 Hz (a magnet on a painted, curved casing; a slow anti-alias filter) to
100 kHz (above the band of the simulations: no effect); zeta from 0.01 (an undamped
piezoelectric resonance, Q = 50) to 1 (over-damped). Default 5 kHz, 0.707: a 5 kHz
flat low-pass, a common usable bandwidth of a magnetically mounted sensor.
"""

from functools import lru_cache

import numpy as np

from gearlab.api import KHZ, Effect, hookimpl, parameters, setting

KEPT_SIZE = 1 << 20  # samples: a record's gain is kept up to this size (16 MB of complex bins)


def frequency_response(f: np.ndarray, f_n: float, zeta: float) -> np.ndarray:
    """H(f) of a second-order sensor: base acceleration in, reported acceleration out."""
    r = np.asarray(f, dtype=float) / f_n
    return 1.0 / (1.0 - r * r + 2j * zeta * r)


# A gap search filters every row of a candidate, and its healthy reference, through one filter: the gain on
# a record's bins is kept by (response, size, rate, parameters) instead of made again for each (3,297
# filterings in the 20 slowest test files, a quarter of their time the gain); read-only, as it is shared.
@lru_cache(maxsize=8)
def _gain(response, size: int, fs: float, params: tuple) -> np.ndarray:
    gain = response(np.fft.rfftfreq(size, d=1.0 / fs), *params)
    gain.flags.writeable = False
    return gain


def steady_state(x, fs: float, response, *params) -> np.ndarray:
    """The record *x* (J, P) through the filter *response(f, *params)* as its steady-state response: its
    spectrum (the J revolutions as one record) multiplied by H(f) (shared with sensor_lowpass); the gain kept
    up to KEPT_SIZE samples."""
    record = np.asarray(x, dtype=float)
    flat = record.reshape(-1)
    make = _gain if flat.size <= KEPT_SIZE else _gain.__wrapped__
    gain = make(response, flat.size, fs, params)
    return np.fft.irfft(np.fft.rfft(flat) * gain, n=flat.size).reshape(record.shape)


class SensorBandwidth(Effect):
    name = "sensor_bandwidth"
    doc = "second-order sensor response: low-pass (zeta ~ 0.7) or mounted resonance (small zeta) at f_n"
    params = parameters(
        f_n=setting(
            float, 5e3, low=100.0, high=1e5, **KHZ, doc="natural (corner) frequency of the sensor and its mounting"
        ),
        zeta=setting(
            float, 0.707, low=0.01, high=1.0, doc="damping ratio: 0.707 flat low-pass, small values a resonance peak"
        ),
    )
    log_scale = frozenset({"f_n", "zeta"})

    def apply_signal(self, x, params, ctx):
        return steady_state(x, ctx.fs, frequency_response, params["f_n"], params["zeta"])


@hookimpl
def gearlab_effects():
    return [SensorBandwidth()]
