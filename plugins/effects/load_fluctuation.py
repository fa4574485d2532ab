"""load_fluctuation: a shaft-synchronous ripple of the load torque.

Physical mismatch. The thesis applies a constant load torque at steady state (eq. 2.110,
2.111). Driven machines pulsate — a reciprocating compressor, a pump's vanes, a cutting
process, a crank — and "dynamic loads" are among the industrial effects the thesis names
(chapter 4 introduction). A load ripple modulates the mesh force and with it the amplitude
of every mesh harmonic (sidebands at q shaft orders).

Realisation. T_l(t) = T_l (1 + eps sin(q Omega t + phi)), Omega = 2 pi f, on the load DOF
(the load inertia, or the gear in the six-DOF model); the static equilibrium and the
mesh-load estimate stay at the mean. Whole orders q of the input shaft keep the response
periodic in one revolution (a ripple at the output shaft's own orders, q Z1/Z2, would not
be; it is left out).

Symmetry. Locked to the shaft angle, not to the tooth pitch: breaks the tooth-shift symmetry.

Bounds. eps 0 (constant load) to 1 (the torque swings between 0 and twice its mean: more
would unload and reverse the teeth, which the linear mesh cannot model, decision 23);
q = 1..64; phase 0..360 deg. Default 10 % once per revolution.
"""

import math

import numpy as np

from gearlab.api import hookimpl, setting_of
from gearlab_plugins.effects.speed_fluctuation import GUESS_PHASES, ShaftRipple, sideband_ripple


class LoadFluctuation(ShaftRipple):
    name = "load_fluctuation"
    doc = "load torque ripple eps at whole input-shaft order q"
    params = ShaftRipple.ripple_params("load torque", 0.1, 1.0, 64)

    def rippled(self, exc, eps, q, phi):
        ripple = eps * exc.load_nm * np.sin(2 * math.pi * q * exc.speed_hz * exc.t + phi)
        return exc.with_load(exc.load + ripple)

    def guesses(self, target_X, speed_hz):
        """The ripple's order and amplitude from the mesh sidebands (sideband_ripple of
        speed_fluctuation): the mesh harmonics scale with the load, so the sidebands' modulation
        index is the load's ripple eps; tried at each of speed_fluctuation's GUESS_PHASES."""
        found = sideband_ripple(target_X, int(setting_of(self.params, "order").high))
        if found is None:
            return []
        order, eps = found
        amplitude = setting_of(self.params, "amplitude")
        eps = min(max(eps, amplitude.low), amplitude.high)
        return [{"order": order, "amplitude": eps, "phase": phase} for phase in GUESS_PHASES]


@hookimpl
def gearlab_effects():
    return [LoadFluctuation()]
