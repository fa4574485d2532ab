"""The adapter contract and the losses shared by the domain-adaptation methods (thesis ch. 5).

An adapter plugin is an :class:`Adapter` registered through the ``gearlab`` entry-point
group (hook ``gearlab_adapters``). The trainer asks it for

- ``extra_modules(latent_dim)`` — trainable modules beyond the network (DANN's domain
  classifier), optimised together with the network;
- ``domain_loss(z_s, z_t, modules, lam)`` — the term added to the classification loss on
  the latent features of a joint source/target batch (eq. 5.12, 5.18), λ and any gradient
  reversal already applied;
- ``discrepancy(z_s, z_t, modules)`` — the domain discrepancy measure used for stopping
  (Table 5.3: "domain discrepancy measure minimum"), a plain float;
- ``lambda_schedule(epoch)`` — λ for an epoch of joint training (Table 5.3);
- ``trainable(network)`` — the network parameters the adapter's training step updates.

``calibrated`` adapters are primed on the full source set and then adapted (thesis 5.4.2);
``train_on`` says which data the (post-priming) training step sees: "source", "target" or
"joint" (40 source + 40 target samples a batch); ``optimizer`` is "adam" (TensorFlow
defaults) for the uncalibrated baselines and "sgd" (lr 0.003) for the calibrated methods.

Every method taking ``params`` accepts ``None`` (the schema defaults) or a mapping as
returned by :meth:`Adapter.resolve`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import torch
from torch import nn

from gearlab.params import Param, resolve_params

SUPERVISIONS = ("unsupervised", "supervised")
TRAIN_ON = ("source", "target", "joint")

# Table 5.3: λ starts at 0 and grows by 0.05 every 25 epochs up to 1.
LAMBDA_STEP = 0.05
LAMBDA_EVERY = 25
LAMBDA_MAX = 1.0

SCHEDULE_PARAMS = (
    Param("lambda_step", "", LAMBDA_STEP, 0.0, 1.0, "increase of the domain-loss weight λ at each step (Table 5.3)"),
    Param("lambda_every", "", LAMBDA_EVERY, 1, 10_000, "epochs of joint training between λ steps (Table 5.3)", integer=True),
    Param("lambda_max", "", LAMBDA_MAX, 0.0, 10.0, "largest domain-loss weight λ (Table 5.3)"),
)

MMD_SCALES = (0.25, 0.5, 1.0, 2.0, 4.0)  # multiples of the median pairwise distance


# ----------------------------------------------------------------------------- schedule


def lambda_schedule(
    epoch: int, step: float = LAMBDA_STEP, every: int = LAMBDA_EVERY, maximum: float = LAMBDA_MAX
) -> float:
    """λ after *epoch* epochs of joint training: 0, then +*step* every *every* epochs, capped at *maximum*."""
    if epoch < 0:
        raise ValueError(f"epoch must be >= 0, got {epoch}")
    return float(min(maximum, round(step * (int(epoch) // int(every)), 12)))


# ----------------------------------------------------------------------------- losses


def _flat(x: torch.Tensor) -> torch.Tensor:
    return x.reshape(x.shape[0], -1)


def pairwise_sq_dists(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Squared Euclidean distances between the rows of *a* (M, D) and *b* (N, D): (M, N).

    Written out (not ``torch.cdist``) so that the gradient stays finite at zero distance.
    """
    d = (a * a).sum(1, keepdim=True) + (b * b).sum(1).unsqueeze(0) - 2.0 * a @ b.T
    return d.clamp_min(0.0)


def _median_of(d_xx: torch.Tensor, d_yy: torch.Tensor, d_xy: torch.Tensor) -> float:
    """Median of the pooled pairwise distances, given the squared-distance blocks; 1 if undefined."""
    with torch.no_grad():
        m, n = d_xx.shape[0], d_yy.shape[0]
        iu_x = torch.triu_indices(m, m, offset=1, device=d_xx.device)
        iu_y = torch.triu_indices(n, n, offset=1, device=d_yy.device)
        pooled = torch.cat([d_xx[iu_x[0], iu_x[1]], d_yy[iu_y[0], iu_y[1]], d_xy.reshape(-1)])
        if pooled.numel() == 0:
            return 1.0
        median = float(pooled.median().sqrt())
    return median if median > 0.0 and math.isfinite(median) else 1.0


def median_distance(x: torch.Tensor, y: torch.Tensor) -> float:
    """Median pairwise distance within the pooled sample x ∪ y (the median heuristic); 1 if undefined."""
    x, y = _flat(x).detach(), _flat(y).detach()
    return _median_of(pairwise_sq_dists(x, x), pairwise_sq_dists(y, y), pairwise_sq_dists(x, y))


def mmd2(
    x: torch.Tensor,
    y: torch.Tensor,
    bandwidths: float | Sequence[float] | None = None,
    scale: float = 1.0,
) -> torch.Tensor:
    """Biased squared MMD between samples *x* (M, D) and *y* (N, D), thesis eq. 5.9.

    The kernel is Gaussian, k(a, b) = exp(-|a - b|² / (2σ²)), summed over the bandwidths σ
    (a multi-bandwidth kernel is still characteristic). By default σ = *scale* × the median
    pairwise distance of the pooled sample × (0.25, 0.5, 1, 2, 4); the bandwidths carry no
    gradient. M and N may differ (eq. 5.9); with M = N this is eq. 5.10.
    """
    x, y = _flat(x), _flat(y)
    if x.shape[0] == 0 or y.shape[0] == 0:
        raise ValueError("mmd2 needs at least one sample from each domain")
    d_xx, d_yy, d_xy = pairwise_sq_dists(x, x), pairwise_sq_dists(y, y), pairwise_sq_dists(x, y)
    if bandwidths is None:
        median = _median_of(d_xx, d_yy, d_xy)
        sigmas = [scale * median * s for s in MMD_SCALES]
    elif isinstance(bandwidths, (int, float)):
        sigmas = [float(bandwidths)]
    else:
        sigmas = [float(s) for s in bandwidths]
    if not sigmas or min(sigmas) <= 0.0:
        raise ValueError(f"bandwidths must be positive, got {sigmas}")
    total = x.new_zeros(())
    for sigma in sigmas:
        gamma = 1.0 / (2.0 * sigma * sigma)
        total = total + torch.exp(-gamma * d_xx).mean() + torch.exp(-gamma * d_yy).mean() - 2.0 * torch.exp(-gamma * d_xy).mean()
    return total


def coral_loss(x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """CORAL loss (Sun & Saenko 2016): |C_x - C_y|²_F / (4 d²) with unbiased covariances.

    For a wide latent space (d larger than the batches, e.g. cnn3's 31 872 features) the
    d × d covariances are never formed: the Frobenius norms are computed from the Gram
    matrices of the centred batches, |XᵀX|² = |XXᵀ|² and tr(XᵀX YᵀY) = |XYᵀ|². Computed
    in float64, returned in the input's dtype.
    """
    x, y = _flat(x), _flat(y)
    m, n, d = x.shape[0], y.shape[0], x.shape[1]
    if m < 2 or n < 2:
        raise ValueError("coral_loss needs at least two samples from each domain")
    if y.shape[1] != d:
        raise ValueError(f"coral_loss: feature dimensions differ ({d} vs {y.shape[1]})")
    xc = (x - x.mean(0)).double()
    yc = (y - y.mean(0)).double()
    if d <= max(m, n):
        diff = xc.T @ xc / (m - 1) - yc.T @ yc / (n - 1)
        frob2 = (diff * diff).sum()
    else:
        frob2 = (
            (xc @ xc.T).pow(2).sum() / (m - 1) ** 2
            + (yc @ yc.T).pow(2).sum() / (n - 1) ** 2
            - 2.0 * (xc @ yc.T).pow(2).sum() / ((m - 1) * (n - 1))
        ).clamp_min(0.0)
    return (frob2 / (4.0 * d * d)).to(x.dtype)


class GradientReversal(torch.autograd.Function):
    """Identity forward; gradient multiplied by -coeff backward (Ganin & Lempitsky 2015)."""

    @staticmethod
    def forward(ctx, x: torch.Tensor, coeff: float = 1.0) -> torch.Tensor:
        ctx.coeff = float(coeff)
        return x.view_as(x)

    @staticmethod
    def backward(ctx, grad: torch.Tensor):
        return -ctx.coeff * grad, None


def grad_reverse(x: torch.Tensor, coeff: float = 1.0) -> torch.Tensor:
    return GradientReversal.apply(x, coeff)


# ----------------------------------------------------------------------------- contract


class Adapter:
    """Base of every adapter plugin; the defaults are those of a method without domain loss."""

    name: str = ""
    doc: str = ""
    params: tuple[Param, ...] = ()
    calibrated: bool = False
    supervision: tuple[str, ...] = SUPERVISIONS
    train_on: str = "source"
    optimizer: str = "adam"

    # ---- parameters

    def coerce(self, given: Mapping[str, object], where: str) -> dict:
        """Turn scenario values that are not numbers (e.g. names of choices) into numbers."""
        return dict(given)

    def resolve(self, given: Mapping[str, object] | None = None, where: str = "") -> dict:
        """Defaults filled, units parsed, names and bounds checked (GearlabInputError otherwise)."""
        where = where or f"adapter '{self.name}'"
        return resolve_params(self.params, self.coerce(given or {}, where), where)

    def values(self, params: Mapping[str, object] | None) -> dict:
        values = {p.name: p.default for p in self.params}
        values.update(params or {})
        return values

    # ---- training

    def extra_modules(self, latent_dim: int, params: Mapping | None = None) -> nn.ModuleDict:
        """Trainable modules beyond the network (optimised with it); none by default."""
        return nn.ModuleDict()

    def domain_loss(
        self,
        z_s: torch.Tensor,
        z_t: torch.Tensor,
        modules: nn.ModuleDict,
        lam: float,
        params: Mapping | None = None,
    ) -> torch.Tensor:
        """The term added to the classification loss; zero for a method without domain loss."""
        return z_s.new_zeros(())

    def discrepancy(
        self, z_s: torch.Tensor, z_t: torch.Tensor, modules: nn.ModuleDict, params: Mapping | None = None
    ) -> float:
        """Domain discrepancy of two latent batches (lower is better); MMD² unless the method has its own."""
        with torch.no_grad():
            return float(mmd2(z_s, z_t))

    def lambda_schedule(self, epoch: int, params: Mapping | None = None) -> float:
        """λ after *epoch* epochs of joint training (after priming); Table 5.3 by default."""
        v = self.values(params)
        return lambda_schedule(
            epoch,
            step=float(v.get("lambda_step", LAMBDA_STEP)),
            every=int(v.get("lambda_every", LAMBDA_EVERY)),
            maximum=float(v.get("lambda_max", LAMBDA_MAX)),
        )

    def trainable(self, network: nn.Module, params: Mapping | None = None) -> list[nn.Parameter]:
        """The network parameters this method's training step updates; all of them by default."""
        return list(network.parameters())

    # ---- description

    def describe(self) -> dict:
        return {
            "doc": self.doc,
            "params": [p.describe() for p in self.params],
            "calibrated": self.calibrated,
            "supervision": list(self.supervision),
            "train_on": self.train_on,
            "optimizer": self.optimizer,
        }

    def __repr__(self) -> str:
        return f"<adapter {self.name}>"


__all__ = [
    "Adapter",
    "GradientReversal",
    "LAMBDA_EVERY",
    "LAMBDA_MAX",
    "LAMBDA_STEP",
    "MMD_SCALES",
    "SCHEDULE_PARAMS",
    "SUPERVISIONS",
    "TRAIN_ON",
    "coral_loss",
    "grad_reverse",
    "lambda_schedule",
    "median_distance",
    "mmd2",
    "pairwise_sq_dists",
]
