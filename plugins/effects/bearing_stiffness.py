"""bearing_stiffness: a mismatch factor on the bearing stiffness and damping.

Physical mismatch. Lumped models take the bearings as linear springs with a catalogue or
textbook constant (thesis 1.2.1.3: "bearing stiffnesses are usually given as constants in
the literature"), the same in x and y. Real rolling-element bearings are stiffer or softer
with preload, clearance, load and speed, and the housing and shaft add compliance in
series; Feng et al. (2019) had to re-tune bearing and joint stiffnesses before their model's
natural frequencies matched the rig. The bearing stiffness sets the frequencies of the
translational modes that carry the mesh vibration to the sensor.

Realisation. k_b and c_b of the configuration (both shafts, x and y; eq. 2.100, 2.101) are
multiplied by the factors.

Bounds (log scale). 0.1 to 10 for either: an order of magnitude either way spans preload,
clearance and housing compliance. Defaults: k_factor 0.5 (real supports are usually softer
than the bearing alone, the housing being in series), c_factor 1.
"""

from gearlab.api import Effect, hookimpl, parameters, setting


class BearingStiffness(Effect):
    name = "bearing_stiffness"
    doc = "bearing stiffness and damping multiplied by mismatch factors"
    params = parameters(
        k_factor=setting(float, 0.5, low=0.1, high=10.0, doc="factor on the bearing stiffness k_b"),
        c_factor=setting(float, 1.0, low=0.1, high=10.0, doc="factor on the bearing damping c_b"),
    )
    log_scale = frozenset({"k_factor", "c_factor"})

    def apply_model(self, config, params):
        values = config.params
        return config.with_values(k_b=values["k_b"] * params["k_factor"], c_b=values["c_b"] * params["c_factor"])


@hookimpl
def gearlab_effects():
    return [BearingStiffness()]
