"""The eight-DOF model of thesis 2.4.2: the 10-DOF model without the casing (Dataset B-8)."""

from gearlab.api import DOF_ORDER, DynamicModel, hookimpl
from gearlab_plugins.models.presets import MENG2020, only


class EightDof(DynamicModel):
    name = "eight_dof"
    doc = "pinion and gear blocks (x, y, rotation), motor and load; bearings grounded; Meng et al. 2020"
    dofs = DOF_ORDER[:8]
    input_dof = "theta11"
    load_dof = "theta22"


EightDof.presets = {"meng2020": only(MENG2020, EightDof().param_names())}


@hookimpl
def gearlab_models():
    return [EightDof()]
