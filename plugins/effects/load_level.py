"""load_level: the mean load torque, when the rig's is not published.

Physical mismatch. The simulator runs at the load torque of its preset; a real record was
taken at whatever torque the brake or generator applied, which data sets often give only as
"high" or "low" (the PHM 2009 rig). In the lumped model the mesh force, and with it every
vibration the mesh excites, grows in proportion to the transmitted torque (the static mesh
deflection is T_l / (R_b k) and k(t) does not depend on it), so a wrong torque scales the
whole gear vibration: the first thing a model update against a measured record must fit.

Realisation. The load torque series T_l(t) of the excitation is multiplied by the factor;
the change enters the equations of motion as the load-torque variation
(Excitation.force_terms), so the steady state is the one at the new torque.

Bounds (log scale). 0.2 to 5: a preset's torque is a guess of the right order (from the drive's
rating, for the PHM 2009 rig 20 N*m at the output), so the true one lies within five times it
either way; a wider range only costs the search its budget. Default 1 (the preset's torque).
"""

from gearlab.api import Effect, hookimpl, parameters, setting


class LoadLevel(Effect):
    name = "load_level"
    doc = "mean load torque multiplied by a factor (an unpublished load, fitted)"
    opt_in = True  # a quantity of the rig not published: fitted when a scenario names it
    params = parameters(factor=setting(float, 1.0, low=0.2, high=5.0, doc="load torque / the preset's load torque"))
    log_scale = frozenset({"factor"})

    def apply_excitation(self, exc, params):
        if params["factor"] == 1.0:
            return exc
        return exc.with_load(exc.load * params["factor"])


@hookimpl
def gearlab_effects():
    return [LoadLevel()]
