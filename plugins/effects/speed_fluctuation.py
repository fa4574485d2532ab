"""speed_fluctuation: a shaft-synchronous fluctuation of the input speed.

Physical mismatch. The thesis fixes the input speed exactly (2.3: "the shaft speed and
motor torque are fixed"). A real drive's speed ripples: a motor's torque pulsation against
the drive-train inertia, coupling misalignment (twice per revolution), a cardan joint. The
ripple moves the mesh stiffness in time (frequency modulation of every mesh harmonic:
sidebands at multiples of q shaft orders) and accelerates every rotating inertia.

Realisation. The input shaft follows

    omega(t) = Omega (1 + eps sin(q Omega t + phi)),  Omega = 2 pi f,
    theta(t) = Omega t + (eps / q) (cos phi - cos(q Omega t + phi)),
    alpha(t) = eps q Omega^2 cos(q Omega t + phi).

With whole orders q the shaft still turns exactly once per 1/f, so the response stays
periodic in one revolution. The TVMS is read at theta(t) (decision 19: at the input
shaft's angle), the tacho reports theta(t), and, since all rotations are measured relative
to the rigid-body rotation of the input shaft, each rotating DOF feels the inertial torque
-I_i r_i alpha(t) with r_i = 1 on the input side and Z1/Z2 on the output side. The
revolution is then resampled at the true angle (order tracking).

Symmetry. The fluctuation is locked to the shaft angle but not to the tooth pitch: a fault
on tooth n meets the mesh at another speed than on tooth 1, so it breaks the tooth-shift
symmetry.

Bounds. eps from 0 (no fluctuation) to 0.1 (10 % peak speed ripple, a badly tuned drive);
order q = 1..32 (once-per-revolution unbalance/run-out to motor slot and pole harmonics);
phase 0..360 deg. Default 1 % at once per revolution.
"""

import math

import numpy as np

from gearlab.api import Effect, Param, hookimpl


class SpeedFluctuation(Effect):
    name = "speed_fluctuation"
    doc = "input speed ripple eps at whole shaft order q: moved TVMS, tacho and inertial torques"
    level = "excitation"
    breaks_symmetry = True
    params = (
        Param("amplitude", "", 0.01, 0.0, 0.1, "relative peak speed fluctuation eps"),
        Param("order", "", 1, 1, 32, "fluctuation frequency in input-shaft orders q", integer=True),
        Param("phase", "rad", 0.0, 0.0, 2 * math.pi, "phase phi at the first tacho zero", "deg"),
    )

    def apply_excitation(self, exc, params):
        eps, q, phi = params["amplitude"], params["order"], params["phase"]
        if eps == 0.0:
            return exc
        omega = 2 * math.pi * exc.speed_hz
        wt = q * omega * exc.t + phi
        angle = exc.angle + eps / q * (math.cos(phi) - np.cos(wt))
        alpha = eps * q * omega**2 * np.cos(wt)
        return exc.with_angle(angle).add_force(lambda e: (-(e.M @ e.rigid_rotation()), alpha))


@hookimpl
def gearlab_effects():
    return [SpeedFluctuation()]
