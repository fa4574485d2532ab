"""casing_path: the transfer path from the gears to a sensor on the casing (Experiment A's mismatch).

Physical mismatch. Models and most of the literature report the vibration of the gear
blocks, but an accelerometer goes on the casing (thesis 2.3, 2.4): the bearings pass the
vibration to a casing of its own mass, mounted on bolts of finite stiffness and damping,
which changes both amplitude and shape (Figure 2.28). A classifier trained on pinion
vibration fails on casing vibration (Experiment A, thesis 5.5).

Realisation. The effect adds the casing DOFs xf, yf (eq. 2.96) when the model lacks them —
the bearings then connect the gear blocks to the casing instead of to ground (eq. 2.100,
2.101) — sets the casing's mass and mounting, and moves the sensor from the gear block to
the casing in the same direction (pinion_x -> casing_x, pinion_y -> casing_y). On the
ten_dof model (Dataset A) only the sensor moves and the casing takes these values: with the
defaults, A-pinion becomes A-casing.

Bounds (log-scale search for mass and stiffness). Casing mass 0.1 to 1000 kg (a light
cover to a heavy industrial housing; Table 2.3: 18.5 kg); mounting stiffness 1e5 to 1e11 N/m
(rubber mounts to a rigid foundation; Table 2.3: 2e8); damping 0 to 1e6 N*s/m.
Defaults: Table 2.3 (Luo et al. 2019b).
"""

from gearlab.api import Effect, Param, hookimpl


class CasingPath(Effect):
    name = "casing_path"
    doc = "casing mass and mounting between the bearings and the sensor; the sensor moves to the casing"
    level = "model"
    breaks_symmetry = False
    params = (
        Param("mf", "kg", 18.509, 0.1, 1000.0, "mass of the gearbox casing"),
        Param("k_xf", "N/m", 1.9912e8, 1e5, 1e11, "casing mounting stiffness, x"),
        Param("k_yf", "N/m", 2.036e8, 1e5, 1e11, "casing mounting stiffness, y"),
        Param("c_xf", "N*s/m", 1995.56, 0.0, 1e6, "casing mounting damping, x"),
        Param("c_yf", "N*s/m", 2005.80, 0.0, 1e6, "casing mounting damping, y"),
    )
    log_scale = frozenset({"mf", "k_xf", "k_yf"})

    def apply_model(self, config, params):
        if not config.has("xf", "yf"):
            config = config.with_dofs("xf", "yf")
        direction = config.channel.rsplit("_", 1)[-1]  # x or y: the sensor keeps its direction
        return config.with_values(**params).replace(channel=f"casing_{direction}")


@hookimpl
def gearlab_effects():
    return [CasingPath()]
