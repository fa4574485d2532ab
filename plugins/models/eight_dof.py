"""The eight-DOF model of thesis 2.4.2: the 10-DOF model without the casing (Dataset B-8)."""

from gearlab.api import DOF_ORDER, DescribedPresets, DynamicModel, drive_dofs, hookimpl
from gearlab_plugins.models.presets import MENG2020


class EightDof(DynamicModel):
    name = "eight_dof"
    doc = "pinion and gear blocks (x, y, rotation), motor and load; bearings grounded; Meng et al. 2020"
    dofs = DOF_ORDER[:8]
    input_dof, load_dof = drive_dofs(dofs)


EightDof.presets = DescribedPresets(EightDof(), {"meng2020": MENG2020})


@hookimpl
def gearlab_models():
    return [EightDof()]
