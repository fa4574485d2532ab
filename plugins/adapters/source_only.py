"""Uncalibrated baseline 1 (thesis 5.4.2): a CNN trained with Adam on the labelled source only.

It sees no target data at all, so its target predictions are fully unsupervised: it
measures what the physics model alone is worth.
"""

from __future__ import annotations

from gearlab.api import Adapter, hookimpl


class SourceOnly(Adapter):
    name = "source_only"
    doc = "Uncalibrated baseline: train on the labelled source domain only (Adam), no target data."
    params = ()
    calibrated = False
    supervision = ("unsupervised",)
    train_on = "source"
    optimizer = "adam"


@hookimpl
def gearlab_adapters():
    return [SourceOnly()]
