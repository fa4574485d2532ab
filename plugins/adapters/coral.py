"""Deep CORAL (Sun & Saenko 2016), beyond the seed: λ · CORAL between the latent features.

CORAL = |C_s - C_t|²_F / (4 d²) aligns the second-order statistics of the two domains.
Note the 1/(4 d²) factor: on cnn3's 31 872-feature latent the loss is tiny, so a larger
``lambda_max`` may be wanted there. The discrepancy used for stopping is CORAL itself.
"""

from __future__ import annotations

from gearlab.api import Adapter, hookimpl, parameters, schedule_settings

# torch (via gearlab.learn.losses) is imported inside the methods: the registry imports this
# module on every gearlab command, and only training needs the losses.


class Coral(Adapter):
    name = "coral"
    doc = "Deep CORAL (Sun & Saenko 2016): λ·|C_s - C_t|²_F / (4d²) on the latent features."
    params = parameters(**schedule_settings())
    calibrated = True
    supervision = ("unsupervised", "supervised")
    train_on = "joint"
    optimizer = "sgd"

    def domain_loss(self, z_s, z_t, modules, lam, params=None):
        from gearlab.api import coral_loss

        return lam * coral_loss(z_s, z_t)

    def domain_terms(self, z_s, z_t, modules, lam, params=None):
        """The loss and, from the same CORAL value, the batch's discrepancy (computed once)."""
        from gearlab.api import coral_loss

        value = coral_loss(z_s, z_t)
        return lam * value, float(value.detach())

    def discrepancy(self, z_s, z_t, modules, params=None) -> float:
        import torch

        from gearlab.api import coral_loss

        with torch.no_grad():
            return float(coral_loss(z_s, z_t))


@hookimpl
def gearlab_adapters():
    return [Coral()]
