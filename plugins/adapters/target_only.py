"""Uncalibrated baseline 2 (thesis 5.4.2): a CNN trained with Adam on the 120 labelled target
samples only, never shown source data — the purely data-driven (and optimistic) approach.
"""

from __future__ import annotations

from gearlab.api import Adapter, hookimpl


class TargetOnly(Adapter):
    name = "target_only"
    doc = "Uncalibrated baseline: train on the labelled target training samples only (Adam), no source data."
    params = ()
    calibrated = False
    supervision = ("supervised",)
    train_on = "target"
    optimizer = "adam"


@hookimpl
def gearlab_adapters():
    return [TargetOnly()]
