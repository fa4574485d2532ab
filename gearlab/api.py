"""The public API for plugin authors: everything a fault, model, adapter, detector or effect plugin may
import from gearlab. A plugin imports from here and nowhere else in gearlab, so gearlab's
modules can move without breaking plugins (docs/plugins.md, docs/architecture.md).

    from gearlab.api import Effect, hookimpl, parameters, setting

    @hookimpl
    def gearlab_effects():
        return [MyEffect()]

The torch-based helpers (``mmd2``, ``coral_loss``, ``grad_reverse``, ``median_distance``,
``template_statistic``, ``likelihood_statistic``, ``template_detector``, ``likelihood_detector``)
are resolved on first use (PEP 562 ``__getattr__``): importing this module, as the registry
does for every command, never pays torch's import time. Import them inside the method that
trains, e.g. ``from gearlab.api import mmd2``.
"""

from __future__ import annotations

import importlib

from .dynamics.config import ModelConfig
from .dynamics.excitation import Excitation
from .dynamics.model import DOF_ORDER, Assembly, DynamicModel, Mesh, add_spring, drive_dofs
from .effect_contract import Effect, SignalContext
from .errors import GearlabInputError
from .gearbox.simulation import DescribedPresets
from .learn.adapters import Adapter, schedule_settings
from .learn.detector_contract import Detector, DetectorParams, path_setting
from .learn.path import PATHS
from .physics.faults import Fault, region, scaled_ladder
from .physics.presets import gear_pair
from .physics.sections import healthy_section
from .physics.stiffness import fillet_compliance
from .registry import hookimpl
from .settings import DEG, KHZ, MM, UM, NoParams, declared, parameters, setting, setting_of
from .signals import NOISE_KINDS, SNR_DB_RANGE, add_noise

# name -> module, imported on first access (torch)
_LAZY = {
    "mmd2": "gearlab.learn.losses",
    "coral_loss": "gearlab.learn.losses",
    "grad_reverse": "gearlab.learn.losses",
    "median_distance": "gearlab.learn.losses",
    "template_statistic": "gearlab.learn.detectors",
    "likelihood_statistic": "gearlab.learn.detectors",
    "template_detector": "gearlab.learn.detectors",
    "likelihood_detector": "gearlab.learn.detectors",
}

__all__ = [
    "DEG",
    "KHZ",
    "MM",
    "UM",
    "DOF_ORDER",
    "NOISE_KINDS",
    "PATHS",
    "SNR_DB_RANGE",
    "Adapter",
    "Assembly",
    "DescribedPresets",
    "Detector",
    "DynamicModel",
    "Effect",
    "Excitation",
    "Fault",
    "GearlabInputError",
    "Mesh",
    "ModelConfig",
    "NoParams",
    "DetectorParams",
    "SignalContext",
    "add_noise",
    "declared",
    "parameters",
    "path_setting",
    "schedule_settings",
    "setting",
    "setting_of",
    "add_spring",
    "drive_dofs",
    "fillet_compliance",
    "gear_pair",
    "healthy_section",
    "hookimpl",
    "region",
    "scaled_ladder",
    *_LAZY,
]


def __getattr__(name: str):
    if name in _LAZY:
        # start-up time: torch is imported only by a plugin method that trains
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'gearlab.api' has no attribute '{name}'")
