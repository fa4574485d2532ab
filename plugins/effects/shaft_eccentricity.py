"""shaft_eccentricity: run-out of the pinion, a once-per-revolution transmission error.

Physical mismatch. The model's pinion turns exactly about its geometric centre. A real one
has run-out — the bore off the pitch circle, a bent shaft, a loose fit — so its teeth come
closer to and move away from the gear once per revolution. Along the line of action this
is a displacement excitation (a geometric transmission error)

    e(theta) = e sin(theta + phi),

which enters the mesh force as k(t) (P u - e) + c(t) (P u' - e'), i.e. a force
(k(t) e + c(t) e') P^T on the right-hand side of eq. 2.95. Its product with the mesh
stiffness puts first-shaft-order sidebands around every mesh harmonic — the classic
signature of eccentricity — and a once-per-revolution component.

Symmetry. The run-out is fixed to the shaft angle, so a fault on tooth n passes the mesh at
another run-out phase than on tooth 1: breaks the tooth-shift symmetry.

Bounds. e from 0 to 200 um: ISO 1328 radial run-out tolerances of gears of this size range
from a few um (grade 4) to about 100 um (grade 11), plus bearing and shaft run-out; phase
0..360 deg. Default 20 um (a commercial-quality gear).
"""

import math

import numpy as np

from gearlab.api import DEG, UM, Effect, hookimpl, parameters, setting


class ShaftEccentricity(Effect):
    name = "shaft_eccentricity"
    doc = "pinion run-out e: once-per-revolution transmission error along the line of action"
    breaks_symmetry = True
    params = parameters(
        e=setting(float, 20e-6, low=0.0, high=200e-6, **UM, doc="run-out (eccentricity) of the pinion"),
        phase=setting(float, 0.0, low=0.0, high=2 * math.pi, **DEG, doc="angle of the run-out at the tacho zero"),
    )

    def apply_excitation(self, exc, params):
        e, phi = params["e"], params["phase"]
        if e == 0.0:
            return exc

        def force(x):
            theta = x.angle + phi
            k = x.stiffness_series()
            error = e * np.sin(theta)  # along the line of action
            error_rate = e * np.cos(theta) * x.speed_series()
            return x.P, k * error + x.damping_series(k) * error_rate

        return exc.add_force(force)


@hookimpl
def gearlab_effects():
    return [ShaftEccentricity()]
