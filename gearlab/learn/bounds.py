"""How well can a noisy simulated target be told apart at all? The Bayes detector.

A chapter-5 target revolution is ``x = h + a + n``: the domain's healthy revolution ``h``,
for a faulty one the fault's response ``a`` (one of the target's own noise-free fault
shapes ``t_1..t_J``), and sensor noise ``n`` drawn independently at every sample from the
dataset's noise law (thesis 4.1.1: Gaussian, Laplace, or Student-t with ν = 2) at a scale
set per revolution (eq. 4.3-4.5). Knowing ``h``, the shapes and the law, the most powerful
test of "fault" against "healthy" (Neyman-Pearson) thresholds the likelihood ratio, here a
mixture over the shapes with equal prior weights:

    Λ(x) = (1/J) Σ_j  Π_n p(r_n - t_j,n) / p(r_n),        r = x - h

    log p(n) = -|n| / b                      Laplace, scale b
             = -n² / (2σ²)                   Gaussian
             = -(ν + 1)/2 · ln(1 + n²/(ν s²))  Student-t, ν = 2, scale s

(constants cancel). The scale of each revolution is estimated from its own residual by its
median absolute value, which the few samples a fault touches barely move: b = med|r| / ln 2,
σ = med|r| / 0.6745, s = med|r| / √(2/3) (the medians of |n| for unit scale).

No detector of these data can do better at any false-alarm rate, so the accuracy of Λ with
the best threshold is an upper bound for every method gearlab trains or builds (it uses the
target's own shapes and the test labels, which no method may). It needs the target's
noise-free twin (the same dataset without noise), so it exists for simulated targets only.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..errors import GearlabInputError
from .history import NOISE_LAWS

if TYPE_CHECKING:
    import torch

# median of |n| for unit scale: Laplace ln 2, Gaussian 0.6745, Student-t(2) sqrt(2/3)
_MEDIAN_ABS = {"laplace": math.log(2.0), "gaussian": 0.6744897501960817, "student_t": math.sqrt(2.0 / 3.0)}
_NU = 2.0  # Student-t degrees of freedom of the thesis's noise (4.1.1)


def _log_density(n: torch.Tensor, scale: torch.Tensor, kind: str) -> torch.Tensor:
    """log p(n) up to a constant, elementwise, for noise of *kind* at *scale* (broadcast)."""
    import torch  # here, not at the top: start-up time (checking a scenario loads no torch)

    if kind == "laplace":
        return -n.abs() / scale
    if kind == "gaussian":
        return -0.5 * (n / scale) ** 2
    return -0.5 * (_NU + 1.0) * torch.log1p((n / scale) ** 2 / _NU)


def shape_llr(R: torch.Tensor, shapes: torch.Tensor, scale: torch.Tensor, kind: str, chunk: int = 16) -> torch.Tensor:
    """``(rows, J)``: log p(r - t_j) - log p(r) summed over the samples, for residual rows *R*,
    *shapes* (J rows) and each row's noise *scale*. Laplace and Gaussian reduce to distances, which
    torch computes without the (rows, J, samples) array: for Laplace
    (||r||_1 - ||r - t_j||_1) / b, for Gaussian (2<r, t_j> - ||t_j||^2) / (2 sigma^2)
    (15-40 times faster than elementwise, the same numbers to rounding)."""
    import torch  # start-up time, as above

    s = scale[:, None]
    if kind == "laplace":
        if _compiled(R, shapes):
            return _laplace_gains(R, shapes) / s
        return (R.abs().sum(1, keepdim=True) - torch.cdist(R, shapes, p=1.0)) / s
    if kind == "gaussian":
        return (2.0 * R @ shapes.T - (shapes**2).sum(1)[None]) / (2.0 * s**2)
    out = []
    for i in range(0, len(R), chunk):  # Student-t: no distance form
        r, si = R[i : i + chunk, None, :], s[i : i + chunk, :, None]
        out.append((_log_density(r - shapes[None], si, kind) - _log_density(r, si, kind)).sum(-1))
    return torch.cat(out)


def _compiled(R: torch.Tensor, shapes: torch.Tensor) -> bool:
    """Whether the Laplace distances go to the compiled loop: CPU rows and shapes of one floating
    precision, no gradient wanted through them (a detector's scores, the bound; a training's
    whole-revolution templates keep torch's path)."""
    import torch  # start-up time, as above

    wants_grad = torch.is_grad_enabled() and (R.requires_grad or shapes.requires_grad)
    return (
        not wants_grad
        and R.device.type == "cpu"
        and shapes.device.type == "cpu"
        and R.dtype == shapes.dtype
        and R.dtype in (torch.float32, torch.float64)
        and R.dim() == 2
        and shapes.dim() == 2
        and R.shape[1] == shapes.shape[1]
    )


def _laplace_gains(R: torch.Tensor, shapes: torch.Tensor) -> torch.Tensor:
    """``(rows, J)``: sum_n |r_n| - |r_n - t_j,n|, each shape over the whole row, by the `shapes`
    network's compiled loop (gearlab.learn.kernels.laplace_gain, one window from sample 0). The
    ||r||_1 - cdist form cancels two sums of thousands of terms: at Experiment B's detector's size
    (555 rows x 270 shapes of 4096, random) its float32 gains were up to 0.014 off the float64
    ones (of up to 227), the loop's sums of differences 1.4e-5; in 0.14 s of CPU against cdist's
    0.55 (float64: 0.09 against 0.57, the same to 7e-13)."""
    import torch  # start-up time, as above

    from . import kernels  # numba: loaded when first needed (start-up time)

    # rows padded to a multiple of four: the loop sums four rows a pass and a lone row in another
    # order (fastmath), so a row's gain would depend on the rows scored with it (the bound scores
    # its rows a tenth at a time and must give the scores of all at once)
    r, t = R.detach(), shapes.detach().contiguous()
    r = torch.cat([r, r.new_zeros((-len(r) % 4, r.shape[1]))]).contiguous()
    out = torch.empty(len(r), len(t), dtype=r.dtype)
    kernels.laplace_gain(r.numpy(), t.numpy(), np.zeros(len(t), dtype=np.int64), out.numpy())
    return out[: len(R)]


def lower_median(x: torch.Tensor) -> torch.Tensor:
    """``x.median(dim=-1, keepdim=True).values`` (the lower of the two middle values), by a
    partial sort on the CPU: numpy's introselect is about 5 times faster than torch's median
    there, which made the burst network's limiter a sixth to a third of a training step, and the
    `shapes` network's scale half of one (benchmarks/training.py); float32 rows (training's) take
    kernels.lower_median32, the same element in a fifth to a half of numpy's time. No gradient
    flows through it (the network's input needs none), so a tensor that needs one takes torch's path."""
    import torch  # start-up time, as above

    if x.device.type != "cpu" or x.requires_grad:
        return x.median(dim=-1, keepdim=True).values
    if x.dtype == torch.float32 and x.dim() > 0 and x.shape[-1] > 0:  # training's precision: compiled
        from . import kernels  # numba: loaded when first needed (start-up time)

        out = torch.empty(*x.shape[:-1], 1, dtype=x.dtype)
        kernels.lower_median32(x.reshape(-1, x.shape[-1]).contiguous().numpy(), out.view(-1).numpy())
        return out
    middle = (x.shape[-1] - 1) // 2
    return torch.from_numpy(np.partition(x.numpy(), middle, axis=-1)[..., middle : middle + 1])


def abs_median(R: torch.Tensor) -> torch.Tensor:
    """``(rows,)``: each row's lower median of |r|, the statistic `noise_scale` reads."""
    return lower_median(R.abs())[:, 0]


def noise_scale(R: torch.Tensor, kind: str, median: torch.Tensor | None = None) -> torch.Tensor:
    """Each residual row's noise scale from its median absolute value, which the few samples a
    fault touches barely move; *median*: the rows' `abs_median`, where the caller holds it."""
    return ((abs_median(R) if median is None else median) / _MEDIAN_ABS[kind]).clamp_min(1e-12)


def likelihood_ratio(X: np.ndarray, healthy: np.ndarray, shapes: np.ndarray, kind: str) -> np.ndarray:
    """log Λ of each row of *X* (revolutions) given the healthy revolution *healthy*, the fault
    *shapes* (J rows, responses added to *healthy*) and the noise *kind*."""
    if kind not in NOISE_LAWS:
        raise GearlabInputError(f"unknown noise kind '{kind}'; known: {', '.join(NOISE_LAWS)}")
    import torch  # start-up time, as above

    T = torch.as_tensor(np.asarray(shapes, dtype=np.float64))
    R = torch.as_tensor(np.asarray(X, dtype=np.float64)) - torch.as_tensor(np.asarray(healthy, dtype=np.float64))
    llr = shape_llr(R, T, noise_scale(R, kind), kind)
    return (torch.logsumexp(llr, dim=1) - math.log(len(T))).numpy()


def gain(noisy_healthy: np.ndarray, clean_healthy: np.ndarray) -> float:
    """The factor that maps the clean twin's standardised signal onto the noisy dataset's
    (each dataset is standardised by its own healthy statistics, eq. 4.6): the least-squares
    fit of the noisy healthy reference by the clean one."""
    c = np.asarray(clean_healthy, dtype=np.float64)
    return float(np.dot(np.asarray(noisy_healthy, dtype=np.float64), c) / np.dot(c, c))


# The noise-free healthy revolutions of a target the bound can model are one revolution: they differ
# from their median by rounding only (measured 0 on Datasets A and B, with a sensor resonance, speed
# fluctuation or run-out added; 0.26 of the RMS with a non-synchronous tone).
TWIN_SPREAD = 1e-6


def twin_problem(clean) -> str | None:
    """Why the Bayes detector's model does not hold for the noise-free twin *clean* (a Dataset),
    or None. The detector takes every healthy revolution as one noise-free revolution plus i.i.d.
    noise: an effect realised anew in each revolution (a non-synchronous tone, noise given as an
    effect) makes the twin's healthy revolutions differ, and the "bound" then falls below what
    methods reach. Such a target's bound is unavailable, never a wrong number."""
    healthy = np.asarray(clean.X[clean.fault == 0], dtype=np.float64)
    if len(healthy) < 2:
        return None
    reference = np.median(healthy, axis=0)
    spread = float(np.median(np.sqrt(((healthy - reference) ** 2).mean(axis=1))) / max(_rms(reference), 1e-300))
    if spread <= TWIN_SPREAD:
        return None
    return (
        f"the target's noise-free healthy revolutions differ from one another ({100 * spread:.3g} % of their RMS): "
        "an effect realised anew in each revolution (a non-synchronous tone, noise given as an effect) lies "
        "outside the Bayes detector's model"
    )


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def bayes_scores(X: np.ndarray, history: np.ndarray, clean, kind: str) -> np.ndarray:
    """log Λ of the revolutions *X* of a noisy target whose noise-free twin is the Dataset
    *clean*; *history* (noisy healthy revolutions) fixes the scale between the two."""
    clean_healthy = np.median(clean.X[clean.fault == 0], axis=0)
    g = gain(np.median(history, axis=0), clean_healthy)
    shapes = g * (clean.X[clean.fault != 0] - clean_healthy)
    return likelihood_ratio(X, g * clean_healthy, shapes, kind)


def best_accuracy(score: np.ndarray, y: np.ndarray) -> float:
    """Accuracy (%) of the best threshold on *score* (higher = fault) for labels *y* (1 = fault)."""
    score, y = np.asarray(score), np.asarray(y)
    order = np.argsort(-score, kind="stable")
    s, yy = score[order], y[order]
    # calling the top i revolutions faulty: correct = faults among them + healthy below them
    tp = np.concatenate([[0], np.cumsum(yy == 1)])
    tn_below = (yy == 0).sum() - np.concatenate([[0], np.cumsum(yy == 0)])
    cut = np.concatenate([[True], s[1:] != s[:-1], [True]])  # thresholds between distinct scores
    return float(100.0 * ((tp + tn_below)[cut]).max() / len(y))


def detection_at(score: np.ndarray, y: np.ndarray, false_alarm: float) -> float:
    """Share (%) of faults scoring above the (1 - *false_alarm*) quantile of the healthy scores."""
    score, y = np.asarray(score), np.asarray(y)
    threshold = np.quantile(score[y == 0], 1.0 - false_alarm)
    return float(100.0 * (score[y == 1] > threshold).mean())


def class_bound_steps(label: np.ndarray, chunk: int = 256) -> int:
    """The steps class_bound says through its *on_step*: one per class and block of *chunk* rows."""
    return len(np.unique(label)) * -(-len(label) // chunk)


def class_bound(
    X: np.ndarray, clean: np.ndarray, label: np.ndarray, kind: str, chunk: int = 256, on_step=lambda done: None
) -> np.ndarray:
    """The predicted class of each row of *X* by the Bayes classifier that knows the true
    shapes: *clean* is the noise-free twin of *X* (row i the same revolution without noise),
    *label* the classes. The chapter-4 model (thesis 4.1.1, eq. 4.3-4.5): a row is
    ``x = α·c + n``, its clean revolution ``c`` one of its class's distinct clean rows (equally
    likely), and noise of law *kind* whose scale follows the revolution's own RMS (the SNR is
    set per revolution). α (the noisy dataset's standardisation against the clean one's) and
    the noise-to-signal ratio are read off the paired rows by medians. The class posterior is
    the class's share times the mean likelihood over its shapes, the prediction its arg max.
    It knows every shape and the noise law, so its accuracy is a bound, not a method's.
    Student-t has no distance form and is summed elementwise: a chapter-4 dataset takes
    minutes (Gaussian and Laplace seconds).
    Rows are taken *chunk* at a time, so memory stays near the two arrays given; *on_step(done)*
    after each class and block of rows (class_bound_steps in all)."""
    if kind not in NOISE_LAWS:
        raise GearlabInputError(f"unknown noise kind '{kind}'; known: {', '.join(NOISE_LAWS)}")
    import torch  # start-up time, as above

    label = np.asarray(label)
    rows = [slice(i, i + chunk) for i in range(0, len(X), chunk)]

    def pair(r: slice) -> tuple[torch.Tensor, torch.Tensor]:
        return torch.as_tensor(np.asarray(X[r], dtype=np.float64)), torch.as_tensor(
            np.asarray(clean[r], dtype=np.float64)
        )

    fits = [((x * c).sum(1), (c * c).sum(1)) for x, c in map(pair, rows)]
    alpha = float(torch.median(torch.cat([xc / cc.clamp_min(1e-300) for xc, cc in fits])))
    ratio = torch.cat(
        [noise_scale(x - alpha * c, kind) / (c**2).mean(1).sqrt().clamp_min(1e-300) for x, c in map(pair, rows)]
    )
    ratio = float(torch.median(ratio))
    classes = np.unique(label)
    log_post = torch.empty(len(X), len(classes), dtype=torch.float64)
    for j, c in enumerate(classes):
        shapes = torch.as_tensor(np.unique(np.asarray(clean[label == c], dtype=np.float64), axis=0))
        scale = (ratio * (shapes**2).mean(1).sqrt()).clamp_min(1e-12)
        S = alpha * shapes
        norm = X.shape[1] * torch.log(scale)[None]  # the densities' normalisation, per shape
        for r in rows:
            x = torch.as_tensor(np.asarray(X[r], dtype=np.float64))
            if kind == "laplace":
                ll = -torch.cdist(x, S, p=1.0) / scale[None]
            elif kind == "gaussian":
                ll = -(torch.cdist(x, S) ** 2) / (2.0 * scale[None] ** 2)
            else:  # Student-t: no distance form
                ll = _elementwise(x, S, scale, kind)
            log_post[r, j] = torch.logsumexp(ll - norm, dim=1) - math.log(len(S))
            on_step(j * len(rows) + r.start // chunk + 1)
        log_post[:, j] += math.log((label == c).mean())
    return classes[log_post.argmax(dim=1).numpy()]


def _elementwise(
    x: torch.Tensor, shapes: torch.Tensor, scale: torch.Tensor, kind: str, block: int = 16
) -> torch.Tensor:
    """``(rows, shapes)``: the log-likelihood sum over the samples of x - shape at each shape's
    scale, elementwise, in float32 blocks of *block* shapes (a sum over 4096 samples keeps
    about 1e-3 nats, far below the class margins; float64 took 5 times as long)."""
    import torch  # start-up time, as above

    x32 = x.float()[:, None, :]
    out = torch.empty(len(x), len(shapes), dtype=torch.float64)
    for k in range(0, len(shapes), block):
        n = x32 - shapes[k : k + block].float()[None]
        out[:, k : k + block] = _log_density(n, scale[k : k + block].float()[None, :, None], kind).sum(-1).double()
    return out
