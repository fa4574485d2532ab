"""DANN (thesis 5.3, Ganin et al. 2016): a domain classifier on the latent features behind a
gradient reversal layer (eq. 5.16-5.23).

The domain classifier G_d (Linear(D, hidden)-ReLU-Linear(hidden, 1)) predicts the domain
of each latent vector (source 0, target 1) with a binary cross-entropy on logits,
``L_d = (L_d,s + L_d,t) / 2`` (eq. 5.2, 5.17). The returned loss is L_d evaluated on
``GRL_λ(z)``: minimising ``L_y + L_d`` therefore

- updates θ_d along -∂L_d/∂θ_d — the domain classifier learns to discriminate (eq. 5.20),
  also while λ is still 0, so the adversary is strong when the reversal sets in;
- updates θ_f along -∂L_y/∂θ_f + λ ∂L_d/∂θ_f — the feature extractor learns to confuse it
  (the -λ L_d term of eq. 5.18 as seen by θ_f, eq. 5.19/5.21).

The discrepancy used for stopping is |balanced domain accuracy - 0.5| (ideal 0, i.e. the
domain classifier is reduced to guessing).
"""

from __future__ import annotations

from gearlab.api import Adapter, hookimpl, parameters, schedule_settings, setting

# torch is imported inside the methods: the registry imports this module on every gearlab
# command, and only training needs torch.


class DANN(Adapter):
    name = "dann"
    doc = "DANN: domain classifier on the latent features behind a gradient reversal layer (eq. 5.16-5.23)."
    params = parameters(
        hidden=setting(int, 64, low=1, high=4096, doc="width of the domain classifier's hidden layer"),
        **schedule_settings(),
    )
    calibrated = True
    supervision = ("unsupervised", "supervised")
    train_on = "joint"
    optimizer = "sgd"

    def extra_modules(self, latent_dim, params=None):
        from torch import nn

        hidden = int(self.values(params)["hidden"])
        domain = nn.Sequential(nn.Linear(int(latent_dim), hidden), nn.ReLU(), nn.Linear(hidden, 1))
        for layer in domain:
            if isinstance(layer, nn.Linear):
                nn.init.kaiming_uniform_(layer.weight, nonlinearity="relu")
                nn.init.zeros_(layer.bias)
        return nn.ModuleDict({"domain": domain})

    @staticmethod
    def _logits(z_s, z_t, modules, lam: float):
        import torch

        from gearlab.api import grad_reverse

        z = torch.cat([z_s.reshape(z_s.shape[0], -1), z_t.reshape(z_t.shape[0], -1)])
        logits = modules["domain"](grad_reverse(z, lam)).squeeze(1)
        return logits[: z_s.shape[0]], logits[z_s.shape[0] :]

    def domain_loss(self, z_s, z_t, modules, lam, params=None):
        import torch
        import torch.nn.functional as F

        logit_s, logit_t = self._logits(z_s, z_t, modules, lam)
        loss_s = F.binary_cross_entropy_with_logits(logit_s, torch.zeros_like(logit_s))
        loss_t = F.binary_cross_entropy_with_logits(logit_t, torch.ones_like(logit_t))
        return 0.5 * (loss_s + loss_t)

    def domain_accuracy(self, z_s, z_t, modules) -> float:
        """Balanced accuracy of the domain classifier (mean of the per-domain accuracies)."""
        import torch

        with torch.no_grad():
            logit_s, logit_t = self._logits(z_s, z_t, modules, 1.0)
            return 0.5 * (float((logit_s < 0).float().mean()) + float((logit_t > 0).float().mean()))

    def discrepancy(self, z_s, z_t, modules, params=None) -> float:
        return abs(self.domain_accuracy(z_s, z_t, modules) - 0.5)


@hookimpl
def gearlab_adapters():
    return [DANN()]
