"""Uncalibrated baseline 2 (thesis 5.4.2): a CNN trained with Adam on the 120 labelled target
samples only, never shown source data — the purely data-driven (and optimistic) approach.
"""

from __future__ import annotations

from gearlab.api import Adapter, hookimpl


class TargetOnly(Adapter):
    name = "target_only"
    doc = "Uncalibrated baseline: train on the labelled target training samples only (Adam), no source data."
    supervision = ("supervised",)
    train_on = "target"  # the rest as the base adapter: no parameters, not calibrated, Adam


@hookimpl
def gearlab_adapters():
    return [TargetOnly()]
