"""The 10-DOF model of Luo et al. (2019b), thesis 2.3 and Table 2.3: Dataset A."""

from gearlab.api import DOF_ORDER, DescribedPresets, DynamicModel, drive_dofs, hookimpl
from gearlab_plugins.models.presets import LUO2019


class TenDof(DynamicModel):
    name = "ten_dof"
    doc = "pinion and gear blocks (x, y, rotation), motor, load and casing (x, y); Luo et al. 2019b"
    dofs = DOF_ORDER
    input_dof, load_dof = drive_dofs(dofs)


TenDof.presets = DescribedPresets(TenDof(), {"luo2019": LUO2019})


@hookimpl
def gearlab_models():
    return [TenDof()]
