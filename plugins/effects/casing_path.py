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
ten_dof model (Dataset A) only the sensor moves and the casing takes these values; a diagnosis
starts there from the model's own casing (gearlab.gap.diagnose.Space), so with the source's values
A-pinion becomes A-casing.

Bounds (log-scale search for all five). Casing mass 0.1 to 1000 kg (a light cover to a heavy
industrial housing; Table 2.3: 18.5 kg); mounting stiffness 1e5 to 1e11 N/m (rubber mounts to
a rigid foundation; Table 2.3: 2e8); damping 1 to 1e6 N*s/m (a bolted joint is never undamped:
1 N*s/m is a damping ratio of 1e-5 for 18.5 kg on 2e8 N/m; Table 2.3's 2000 is 0.016). On a
linear scale from 0 a search's design put every point at damping ratios of 0.5-10 (an
over-damped casing), far from any mounting's.
Defaults: round values of a small cast housing (10 kg on 1e8 N/m mounts, 1e3 N*s/m), none of them a
preset's: an effect's defaults are where a diagnosis starts, and a start at the answer would be found
without being identified.

Where a diagnosis looks (guesses). A mounting's natural frequency f_m = sqrt(k / m_f) / 2 pi
splits the casing's response: below f_m the casing follows the bearings (stiffness-controlled),
above it its acceleration is the bearing forces over its mass (mass-controlled), with one
mode per direction in between. That is what tells a casing path from a sensor resonance (one
mode after the whole structure, scaling every line alike). The score's valleys run along f_m
and m_f, which a design of a few points over 12 decades of stiffness rarely hits: the search
first tries GUESS_MOUNTINGS isotropic mountings of the default mass, f_m log-spaced over
GUESS_FREQUENCIES (not read off the target: the casing's signature is a ratio to the source's,
which an effect's guesses do not see). On five development casings (5-21 kg, 5e7-8e8 N/m) a
budget-16 search without them lost to a damped 0.9-1.6 kHz sensor resonance twice; with them (and
its five-parameter budget, gearlab.gap.diagnose.MODEL_DIMS) its score fell 31-131 times lower.
"""

import numpy as np

from gearlab.api import Effect, hookimpl, parameters, setting

GUESS_MOUNTINGS = 10
GUESS_FREQUENCIES = (30.0, 1e4)  # Hz: from below a 40 Hz shaft speed to well inside the mesh harmonics


class CasingPath(Effect):
    name = "casing_path"
    doc = "casing mass and mounting between the bearings and the sensor; the sensor moves to the casing"
    params = parameters(
        mf=setting(float, 10.0, low=0.1, high=1000.0, unit="kg", doc="mass of the gearbox casing"),
        k_xf=setting(float, 1e8, low=1e5, high=1e11, unit="N/m", doc="casing mounting stiffness, x"),
        k_yf=setting(float, 1e8, low=1e5, high=1e11, unit="N/m", doc="casing mounting stiffness, y"),
        c_xf=setting(float, 1e3, low=1.0, high=1e6, unit="N*s/m", doc="casing mounting damping, x"),
        c_yf=setting(float, 1e3, low=1.0, high=1e6, unit="N*s/m", doc="casing mounting damping, y"),
    )
    log_scale = frozenset({"mf", "k_xf", "k_yf", "c_xf", "c_yf"})

    def apply_model(self, config, params):
        if not config.has("xf", "yf"):
            config = config.with_dofs("xf", "yf")
        direction = config.channel.rsplit("_", 1)[-1]  # x or y: the sensor keeps its direction
        return config.with_values(**params).replace(channel=f"casing_{direction}")

    def guesses(self, target_X, speed_hz):
        """Isotropic mountings of the default mass, natural frequencies log-spaced (see the module)."""
        mass = self.params().mf
        return [
            {"k_xf": k, "k_yf": k} for k in mass * (2 * np.pi * np.geomspace(*GUESS_FREQUENCIES, GUESS_MOUNTINGS)) ** 2
        ]


@hookimpl
def gearlab_effects():
    return [CasingPath()]
