"""MMD-CNN (thesis 5.2): λ · MMD² between the source and target latent features (eq. 5.11/5.12).

The biased estimate of eq. 5.9 with a multi-bandwidth Gaussian kernel (median heuristic
× 0.25…4, scaled by ``bandwidth_scale``); the domain loss reaches the feature extractor
only. The discrepancy used for stopping is MMD² itself (ideal 0).
"""

from __future__ import annotations

from gearlab.api import Adapter, hookimpl, parameters, schedule_settings, setting

# torch (via gearlab.learn.losses) is imported inside the methods: the registry imports this
# module on every gearlab command, and only training needs the losses.


class MMD(Adapter):
    name = "mmd"
    doc = "MMD-CNN: λ·MMD² (biased, multi-bandwidth Gaussian kernel) on the latent features (eq. 5.9-5.12)."
    params = parameters(
        bandwidth_scale=setting(
            float, 1.0, low=0.01, high=100.0, doc="factor on the median-heuristic kernel bandwidths"
        ),
        **schedule_settings(),
    )
    calibrated = True
    supervision = ("unsupervised", "supervised")
    train_on = "joint"
    optimizer = "sgd"

    def domain_loss(self, z_s, z_t, modules, lam, params=None):
        from gearlab.api import mmd2

        scale = float(self.values(params)["bandwidth_scale"])
        return lam * mmd2(z_s, z_t, scale=scale)

    def domain_terms(self, z_s, z_t, modules, lam, params=None):
        """The loss and, from the same MMD² value, the batch's discrepancy (computed once)."""
        from gearlab.api import mmd2

        value = mmd2(z_s, z_t, scale=float(self.values(params)["bandwidth_scale"]))
        return lam * value, float(value.detach())

    def discrepancy(self, z_s, z_t, modules, params=None) -> float:
        import torch

        from gearlab.api import mmd2

        scale = float(self.values(params)["bandwidth_scale"])
        with torch.no_grad():
            return float(mmd2(z_s, z_t, scale=scale))


@hookimpl
def gearlab_adapters():
    return [MMD()]
