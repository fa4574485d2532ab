"""Uncalibrated baseline 1 (thesis 5.4.2): a CNN trained with Adam on the labelled source only.

It sees no target data at all, so its target predictions are fully unsupervised: it
measures what the physics model alone is worth.
"""

from __future__ import annotations

from gearlab.api import Adapter, hookimpl


class SourceOnly(Adapter):
    """The base adapter's defaults: no parameters, not calibrated, trained on the source with Adam."""

    name = "source_only"
    doc = "Uncalibrated baseline: train on the labelled source domain only (Adam), no target data."
    supervision = ("unsupervised",)


@hookimpl
def gearlab_adapters():
    return [SourceOnly()]
