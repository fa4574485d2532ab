"""mesh_damping: the mesh damping model and ratio (thesis future work, physics item 1).

Physical mismatch. The thesis calls damping "convenient but [not representing] the true
dynamics" and the first thing to improve (6.2). It uses a ratio zeta = 0.07 (Parker et al.
2000, Tian 2004) and makes the mesh damping proportional to the time-varying mesh
stiffness, c(t) = mu k(t) with mu = c_m / k_m (eq. 2.107-2.109); most other authors stop at a
constant c_m (thesis 2.3), and measured damping ratios of gear meshes range widely with
lubrication and load (Guilbault et al. 2012, Luo et al. 2019b).

Realisation. The configuration's zeta is replaced and the mesh damping follows the chosen
model: "constant" (c = c_m = 2 zeta sqrt(k_m m1 m2 / (m1 + m2)), eq. 2.107) or "proportional"
(c = mu k(t), eq. 2.108). The constant part joins the constant damping matrix Cc, so the
Newmark loop is unchanged.

Bounds. zeta from 0 (undamped mesh) to 0.3 (heavily damped; literature values lie between
0.03 and 0.17). Defaults: the constant model at the thesis's 0.07, i.e. only the damping
model differs from the thesis's source models.
"""

from gearlab.api import Effect, hookimpl, parameters, setting


class MeshDamping(Effect):
    name = "mesh_damping"
    doc = "mesh damping ratio zeta and model: constant c_m (eq. 2.107) or proportional to k(t) (eq. 2.108)"
    params = parameters(zeta=setting(float, 0.07, low=0.0, high=0.3, doc="mesh damping ratio (eq. 2.107)"))
    options = {"model": ("constant", "proportional")}

    def apply_model(self, config, params):
        return config.with_values(zeta=params["zeta"]).replace(mesh_damping=params["model"])


@hookimpl
def gearlab_effects():
    return [MeshDamping()]
