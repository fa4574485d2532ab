"""sensor_noise: broadband measurement noise at a signal-to-noise ratio (thesis 4.1.1).

Physical mismatch. A real accelerometer signal carries noise from the sensor, its cable,
the amplifier and the digitiser, and from unrelated vibration of the structure; the
simulation has none. The thesis's chapter 4 models it as additive noise of a standard
distribution rescaled to an SNR (eq. 4.1-4.5): Gaussian, or heavier-tailed Laplace and
Student-t (nu = 2) for the impulsive noise of industrial gearboxes (Zak et al. 2017).
Each revolution of the record is scaled to its own RMS, exactly as gearlab.signals.add_noise
does for the thesis's datasets, so TSA over the J revolutions averages it down.

Bounds. SNR from -20 dB (noise ten times the signal RMS: beyond the 0 dB stress test of
chapter 4) to 80 dB (noise 1e-4 of the signal: a laboratory sensor, practically clean)
(gearlab.signals.SNR_DB_RANGE). Default 10 dB: a usable industrial measurement, milder than the
thesis's 0 dB. The one way a scenario declares a recording's noise: in a dataset table's
``effects`` with a ``seed``, it is the dataset's noise, drawn from that seed after every other
effect (gearlab.kinds.common.effects_and_noise); without one, at its place among the signal
effects, drawn from the effects' streams (what a gap diagnosis fits).
"""

from gearlab.api import NOISE_KINDS, SNR_DB_RANGE, Effect, add_noise, hookimpl, parameters, setting

SNR_DB_DOC = "signal-to-noise ratio in dB, 10 log10 (RMS_s / RMS_n)^2"


class SensorNoise(Effect):
    name = "sensor_noise"
    doc = "additive measurement noise (Gaussian, Laplace or Student-t nu=2) at an SNR, per revolution (eq. 4.1-4.5)"
    noise = True
    params = parameters(snr_db=setting(float, 10.0, low=SNR_DB_RANGE[0], high=SNR_DB_RANGE[1], doc=SNR_DB_DOC))
    options = {"kind": NOISE_KINDS}

    def apply_signal(self, x, params, ctx):
        return add_noise(x, params["snr_db"], params["kind"], ctx.rng)


@hookimpl
def gearlab_effects():
    return [SensorNoise()]
