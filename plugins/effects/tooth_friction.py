"""tooth_friction: sliding friction between the teeth, off the line of action.

Physical mismatch. The thesis leaves out inter-tooth friction (2.4.1, 2.4.2), which both of
its source models (Luo et al. 2019b, Meng et al. 2020) include. Away from the pitch point
the flanks slide; Coulomb friction mu_f W acts across the line of action, reverses at the
pitch point, and loads the bearings (x and y) and the shafts (torque) — an excitation at the
mesh frequency that the normal mesh force alone does not produce (Vaishya & Singh 2001;
Mohammed et al. 2015 found it is what gives the x-direction its vibration).

Realisation. For each tooth pair n in contact, on the TVMS grid over one revolution:

    W_n = W k_n / sum_m k_m                load share by stiffness, W = T_l / R_b2 the static mesh load
    rho1 = R_b1 tan(alpha_p),  rho2 = R_b2 tan(alpha_g)    roll distances of the contact point
    F_n = mu_f W_n sgn(tan alpha_p - tan alpha_g)           on the pinion, along q = (cos a0, -sin a0)

(q is perpendicular to the line of action n = (sin a0, cos a0) of eq. 2.104). By virtual work
the generalised forces are sum F_n q on the pinion block, -sum F_n q on the gear block,
-sum F_n rho1 on the pinion rotation and +sum F_n rho2 on the gear rotation; their power
on the rigid rotation is -mu_f W Omega R_b1 |tan alpha_p - tan alpha_g| <= 0 (friction
dissipates). The pattern is read at the shaft angle; it follows the load ripple when there
is one. A torque on a fixed-speed DOF is taken up by the drive.

Symmetry. The friction pattern is built from per-tooth load shares: a fault on tooth n
shifts it with the tooth, so the tooth-shift symmetry holds.

Bounds. mu_f from 0 to 0.3: lubricated steel gears run at 0.03-0.1, dry or boundary
lubrication up to ~0.3. Default 0.05.
"""

import math

import numpy as np

from gearlab.api import Effect, hookimpl, parameters, setting


def friction_pattern(exc, mu_f: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(sum F_n, pinion torque, gear torque) over one revolution on the TVMS grid, for a unit load ratio."""
    pair = exc.pair
    phi, in_mesh, k = exc.tooth_pairs()
    total = k.sum(axis=0)
    share = np.divide(k, total, out=np.zeros_like(k), where=total > 0)
    W = exc.load_nm / pair.gear.R_b  # static normal mesh load, N (eq. 2.111)
    tan_p = pair.roll_start_pinion + phi  # roll angles of the contact point (eq. 2.7, 2.8)
    tan_g = pair.roll_tip_gear - pair.Z1 / pair.Z2 * phi
    F = np.where(in_mesh, mu_f * W * share * np.sign(tan_p - tan_g), 0.0)
    return F.sum(axis=0), -(F * pair.pinion.R_b * tan_p).sum(axis=0), (F * pair.gear.R_b * tan_g).sum(axis=0)


class ToothFriction(Effect):
    name = "tooth_friction"
    doc = "Coulomb sliding friction mu_f across the line of action, reversing at the pitch point"
    params = parameters(mu_f=setting(float, 0.05, low=0.0, high=0.3, doc="friction coefficient between the flanks"))

    def apply_excitation(self, exc, params):
        mu_f = params["mu_f"]
        if mu_f == 0.0 or exc.load_nm == 0.0:
            return exc

        def forces(x):
            force, torque1, torque2 = friction_pattern(x, mu_f)
            scale = x.load / x.load_nm  # the load share follows a load ripple
            a0 = x.pair.working_pressure_angle  # the line of action (alpha_w for shifted gears)
            across = x.vector({"x1": math.cos(a0), "y1": -math.sin(a0), "x2": -math.cos(a0), "y2": math.sin(a0)})
            return [
                (across, scale * x.at_angle(force)),
                (x.vector({"theta12": 1.0}), scale * x.at_angle(torque1)),
                (x.vector({"theta21": 1.0}), scale * x.at_angle(torque2)),
            ]

        return exc.add_force(forces)


@hookimpl
def gearlab_effects():
    return [ToothFriction()]
