"""Fine-tuning (Han et al. 2019b), beyond the seed: prime the network on the source, then
train on the labelled target samples with only some layers unfrozen.

Han et al.'s three transfer strategies, parameter ``variant``:

- ``all`` (0): every layer of the primed network is trained on the target;
- ``classifier`` (1): the feature extractor is frozen, the dense classifier is retrained;
- ``last`` (2): only the output layer is retrained.

Parameters are numbers in gearlab, so ``variant`` is stored as its code 0/1/2; scenarios
may give the name, which :meth:`Finetune.coerce` (called by ``resolve``) translates.
Frozen parts should be kept in ``eval()`` mode so that their batch-norm statistics stay
those of the source.
"""

from __future__ import annotations

from collections.abc import Mapping

from gearlab.api import Adapter, hookimpl, parameters, setting

VARIANTS = ("all", "classifier", "last")


VARIANT_DOC = "layers retrained on the target: 0 = all, 1 = classifier, 2 = last"


class Finetune(Adapter):
    name = "finetune"
    doc = (
        "Fine-tuning (Han et al. 2019b): prime on the source, retrain all layers, the classifier or the last layer "
        "on the labelled target."
    )
    params = parameters(variant=setting(int, 0, low=0, high=len(VARIANTS) - 1, doc=VARIANT_DOC))
    calibrated = True
    supervision = ("supervised",)
    train_on = "target"
    optimizer = "sgd"
    choices = {"variant": VARIANTS}

    def variant(self, params: Mapping | None = None) -> str:
        value = self.values(params)["variant"]
        if isinstance(value, str):
            value = self.coerce({"variant": value}, f"adapter '{self.name}'")["variant"]
        return VARIANTS[int(value)]

    def trainable(self, network, params: Mapping | None = None) -> list:
        variant = self.variant(params)
        if variant == "all":
            return list(network.parameters())
        if variant == "classifier":
            return list(network.classifier.parameters())
        # the last layer that holds weights: a dense layer, or a classifier that is one layer (shapes' mixture)
        last = [m for m in network.classifier.modules() if any(True for _ in m.parameters(recurse=False))][-1]
        return list(last.parameters())


@hookimpl
def gearlab_adapters():
    return [Finetune()]
