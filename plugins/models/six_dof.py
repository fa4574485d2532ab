"""The six-DOF model of Meng et al. (2020), thesis 2.4.2 and Table 2.4 (Dataset B-6).

No motor and no load: the pinion turns at the fixed input speed and the load torque acts
on the driven gear directly.
"""

from gearlab.api import DescribedPresets, DynamicModel, drive_dofs, hookimpl
from gearlab_plugins.models.presets import MENG2020


class SixDof(DynamicModel):
    name = "six_dof"
    doc = "pinion and gear blocks (x, y, rotation); torques on the gears; Meng et al. 2020"
    dofs = ("x1", "y1", "theta12", "x2", "y2", "theta21")
    input_dof, load_dof = drive_dofs(dofs)


SixDof.presets = DescribedPresets(SixDof(), {"meng2020": MENG2020})


@hookimpl
def gearlab_models():
    return [SixDof()]
