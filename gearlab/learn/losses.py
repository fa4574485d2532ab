"""The torch losses shared by the domain-adaptation methods (thesis ch. 5).

Kept apart from the adapter contract (:mod:`gearlab.learn.adapters`) so that the contract,
and with it every adapter plugin module, imports without torch: ``gearlab plugins`` and
``gearlab stiffness`` never pay torch's import time. Adapter plugins import this module
inside the methods that compute a loss.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch

MMD_SCALES = (0.25, 0.5, 1.0, 2.0, 4.0)  # multiples of the median pairwise distance


def _flat(x: torch.Tensor) -> torch.Tensor:
    return x.reshape(x.shape[0], -1)


def pairwise_sq_dists(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Squared Euclidean distances between the rows of *a* (M, D) and *b* (N, D): (M, N).

    Written out (not ``torch.cdist``) so that the gradient stays finite at zero distance.
    """
    d = (a * a).sum(1, keepdim=True) + (b * b).sum(1).unsqueeze(0) - 2.0 * a @ b.T
    return d.clamp_min(0.0)


def _pooled_median(d: torch.Tensor) -> float:
    """Median of the pairwise distances of a pooled sample x ∪ y, given its squared-distance
    matrix: its upper triangle holds each pair once (within x, within y and across); 1 if
    undefined."""
    with torch.no_grad():
        upper = torch.triu_indices(len(d), len(d), offset=1, device=d.device)
        if upper.shape[1] == 0:
            return 1.0
        median = float(d[upper[0], upper[1]].median().sqrt())
    return median if median > 0.0 and math.isfinite(median) else 1.0


def median_distance(x: torch.Tensor, y: torch.Tensor) -> float:
    """Median pairwise distance within the pooled sample x ∪ y (the median heuristic); 1 if undefined."""
    z = torch.cat([_flat(x), _flat(y)]).detach()
    return _pooled_median(pairwise_sq_dists(z, z))


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

    Computed on the pooled sample at once: its squared distances (M + N)², every bandwidth's
    kernel from them in one call, and eq. 5.9 as the quadratic form wᵀKw with w = 1/M on x's rows
    and -1/N on y's (the three means of the equation, the cross term twice). The pooled matrix's
    upper triangle holds the distances the median heuristic pools (within x, within y, across).
    """
    x, y = _flat(x), _flat(y)
    m, n = x.shape[0], y.shape[0]
    if m == 0 or n == 0:
        raise ValueError("mmd2 needs at least one sample from each domain")
    z = torch.cat([x, y])
    d = pairwise_sq_dists(z, z)
    if bandwidths is None:
        median = _pooled_median(d)
        sigmas = [scale * median * s for s in MMD_SCALES]
    elif isinstance(bandwidths, (int, float)):
        sigmas = [float(bandwidths)]
    else:
        sigmas = [float(s) for s in bandwidths]
    if not sigmas or min(sigmas) <= 0.0:
        raise ValueError(f"bandwidths must be positive, got {sigmas}")
    gamma = torch.tensor([-1.0 / (2.0 * s * s) for s in sigmas], dtype=d.dtype, device=d.device)
    kernel = torch.exp(gamma[:, None, None] * d).sum(0)
    w = torch.cat([torch.full((m,), 1.0 / m, dtype=d.dtype, device=d.device),
                   torch.full((n,), -1.0 / n, dtype=d.dtype, device=d.device)])  # fmt: skip
    return w @ kernel @ w


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


__all__ = [
    "MMD_SCALES",
    "GradientReversal",
    "coral_loss",
    "grad_reverse",
    "median_distance",
    "mmd2",
    "pairwise_sq_dists",
]
