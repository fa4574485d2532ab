"""A simulator configuration (which DOFs, parameter values, sensor channel, mesh damping
model) and the lumped model a model-level effect derives from a registered one.

Plain values: a ModelConfig is hashable and picklable and knows no registry. Looking up the
registered model a configuration names is gearlab.effects.config_of / model_of (above the
plugin registry).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

from ..errors import GearlabInputError
from .model import CHANNEL_DOFS, DOF_ORDER, MESH_DAMPING_MODELS, DynamicModel


@dataclass(frozen=True)
class ModelConfig:
    """A simulator configuration: which DOFs, which parameter values, where the sensor sits.

    *base* is the registered model whose presets give the gear pair and the operating point;
    the DOFs may be more than the base model's (a model-level effect added some). *values*
    holds every lumped parameter of the configuration in SI, sorted by name, so the
    configuration is hashable and two equal configurations simulate identically.
    """

    base: str
    preset: str
    dofs: tuple[str, ...]
    input_dof: str  # the fixed-speed (tacho) DOF
    load_dof: str  # where the load torque acts
    channel: str  # the measured channel, e.g. pinion_x, casing_x
    values: tuple[tuple[str, float], ...]
    mesh_damping: str = "proportional"  # one of MESH_DAMPING_MODELS: c(t) = mu k(t) (eq. 2.108) or c_m (eq. 2.107)

    def __post_init__(self):
        if self.mesh_damping not in MESH_DAMPING_MODELS:
            raise GearlabInputError(
                f"mesh damping model must be one of {', '.join(MESH_DAMPING_MODELS)}, got {self.mesh_damping!r}"
            )

    @property
    def params(self) -> dict[str, float]:
        return dict(self.values)

    @property
    def channels(self) -> tuple[str, ...]:
        return tuple(c for c, dof in CHANNEL_DOFS.items() if dof in self.dofs)

    def has(self, *dofs: str) -> bool:
        return all(d in self.dofs for d in dofs)

    def with_values(self, **values: float) -> ModelConfig:
        return dataclasses.replace(self, values=sorted_values({**self.params, **values}))

    def with_dofs(self, *added: str, input_dof: str | None = None, load_dof: str | None = None) -> ModelConfig:
        """More DOFs (kept in the order of eq. 2.96); optionally a new input or load DOF."""
        unknown = [d for d in added if d not in DOF_ORDER]
        if unknown:
            raise ValueError(f"unknown DOF(s) {unknown}; the DOFs are {DOF_ORDER}")
        dofs = tuple(d for d in DOF_ORDER if d in self.dofs or d in added)
        return dataclasses.replace(
            self, dofs=dofs, input_dof=input_dof or self.input_dof, load_dof=load_dof or self.load_dof
        )

    def replace(self, **changes) -> ModelConfig:
        return dataclasses.replace(self, **changes)

    def overrides(self, model: DynamicModel) -> dict[str, float]:
        """The values as overrides for Simulator/DynamicModel.resolve of *model* (the model of this
        configuration, gearlab.effects.model_of): only the model's own parameters."""
        names = set(model.param_names())
        return {k: v for k, v in self.values if k in names}


def sorted_values(values: Mapping[str, float]) -> tuple[tuple[str, float], ...]:
    return tuple(sorted((k, float(v)) for k, v in values.items()))


class DerivedModel(DynamicModel):
    """A lumped model with the DOFs a model-level effect asked for, on its base model's presets.

    The assembly is the same restriction of the 10-DOF model (eq. 2.97-2.104) that every
    registered model uses (dynamics.model.lumped_assembly); nothing is assembled twice.
    """

    def __init__(self, name: str, dofs: tuple[str, ...], input_dof: str, load_dof: str, presets: Mapping, doc: str):
        self.name, self.dofs, self.input_dof, self.load_dof, self.doc = name, dofs, input_dof, load_dof, doc
        self.presets = presets
