"""1-D CNNs for raw vibration signals (thesis 3.1.3-3.1.6), registered by name in ``NETWORKS``.

Every network is a :class:`Network`: a feature extractor ``.features`` (input ``(B, 1, L)``
or ``(B, L)`` -> flattened latent ``(B, D)``) followed by a classifier ``.classifier``
(latent -> logits). Adapters act on the latent space (thesis Fig. 5.1-5.3); the softmax
of Table 3.1 lives in the loss (cross-entropy on logits).

``cnn3`` — the seed's CNN3 (Han et al. 2019a/b as copied in thesis Fig. 3.1)
-----------------------------------------------------------------------------
Figure 3.1 with the kernel numbers is not part of the thesis text, so the feature
extractor is rebuilt from every constraint the text does give:

- conv–max-pool–dropout ("CPR") blocks; convolution stride 1 without padding, max-pool
  size 2 with stride 1 (Table 3.1, taken literally), ReLU, He-uniform weights and zero
  biases (Table 3.1; ``kaiming_uniform_(nonlinearity='relu')`` has TensorFlow's
  He-uniform bound sqrt(6 / fan_in));
- kernel count rising and kernel size falling with depth (3.1.3);
- the dropout layer omitted every second block (3.1.6), so an odd number of blocks shows
  both kinds; three blocks is the fewest that does, and the name CNN3 and "the minimum
  number of layers required" (3.1.3) point to three;
- a large latent space of about 30 000 features feeding dense 120 -> 64 -> classes (3.1.6).

With stride-1 pooling each block only shortens the signal by its kernel size, so a
4096-sample rotation leaves ~3 990 samples and a ~30 000-feature latent needs 8 kernels
in the last block. Halving the kernel size from block to block and doubling then holding
the kernel count gives

    block 1: Conv1d 4 x 64  -> ReLU -> MaxPool(2, stride 1) -> Dropout
    block 2: Conv1d 8 x 32  -> ReLU -> MaxPool(2, stride 1)            (no dropout)
    block 3: Conv1d 8 x 16  -> ReLU -> MaxPool(2, stride 1) -> Dropout
    latent:  8 x 3984 = 31 872 features
    classifier: Dense 120 -> ReLU -> Dropout -> Dense 64 -> ReLU -> Dropout -> Dense classes

(dropout 0.005, Han et al.'s 0.5 %, by default). 3.82 M of its 3.83 M weights sit in the
first dense layer, and its convolutions run over ~4 000 samples at full resolution,
which makes it slow on a CPU.

``fast`` — the CPU default (beyond the thesis)
----------------------------------------------
A WDCNN-style net (Zhang et al. 2017): a wide first kernel with a large stride compresses
the signal at once (one output per 16 samples, 16 per 256-sample mesh period of a 16-tooth
pinion), two small strided convolutions follow, and global average pooling gives a
64-feature latent that does not depend on where in the rotation a fault sits:

    Conv1d 16 x 64, stride 16, pad 24 -> BN -> ReLU -> MaxPool 2   (4096 -> 256 -> 128)
    Conv1d 32 x 3, stride 2, pad 1    -> BN -> ReLU                (-> 64)
    Conv1d 64 x 3, stride 2, pad 1    -> BN -> ReLU                (-> 32)
    global average pool -> latent: 64 features
    classifier: Dense 64 -> ReLU -> Dropout -> Dense classes

(convolutions followed by batch normalisation carry no bias). It accepts any signal of at
least 64 samples. A training step on a batch of 80 x 4096 is over 30 times faster than
cnn3's on one CPU thread (benchmarks/learning.py). Its batch normalisation keeps the
statistics of the priming while a primed network is adapted or fine-tuned
(``training.train_mode(net, freeze_norm=True)``), so that joint source + target batches do
not blend the two domains into the statistics evaluation uses.

``burst`` — the default of the transfer kind (beyond the thesis)
----------------------------------------------------------------
A chapter-5 fault is a burst of 40-160 samples at one tooth in a 4096-sample revolution, in
noise as strong as the signal (0 dB) and impulsive (Laplace). ``fast`` compresses the
revolution 16-fold at once and averages over it, which dilutes a burst 25-100-fold; the
detector the data call for (gearlab.learn.bounds) correlates the whole burst with a known
shape after limiting the noise's outliers. ``burst`` is the learned version of that:

    RobustLimiter: x / (1.4826 MAD(x)), then 1.5 tanh(z / 1.5)      (gain-free, impulses capped)
    AvgPool 2                                                        (4096 -> 2048; bursts lie below half Nyquist)
    Conv1d 32 x 33, stride 2, circular padding -> BN                 (a filter bank over the whole revolution)
    global max of |response| -> latent: 32 features                 (a burst anywhere counts in full)
    classifier: Dense 32 -> ReLU -> Dropout -> Dense classes

with PyTorch's default initialisation (``_torch_uniform``). Measured on Experiment B
(repetition 0, k = 0, trained on the noise-augmented source, history threshold): 80-81 %
against `fast`'s 73-75 % on the same recipe; on the perfectly corrected simulator 85 %
against `fast`'s 74-77 % (docs/learning.md, section 6).

``shapes`` — the Bayes detector's form, learnt (beyond the thesis)
-----------------------------------------------------------------
``burst`` finds 69.6 % of Experiment B's faults at 1 % false alarms where the likelihood ratio
of the simulated shapes finds 80.3 %: a bank of short filters and a maximum do not rank as a
mixture of whole-revolution likelihoods does. ``shapes`` has that form and learns it:

    ShapeLikelihood: z_j = (||r||_1 - ||r - t_j||_1) / b      256 templates t_j, each on its own
                                                              eighth of the revolution (zero
                                                              elsewhere), Laplace law,
                                                              b = median|r| / ln 2
    ShapeMixture:    logit_c = log Σ_j w_j,c exp(z_j)         healthy = the zero shape (z_0 = 0)

Its matched start (``[protocol] start = "faults"``) sets the templates to the source's fault
residuals and the weights equal, which is the `likelihood_ratio` detector exactly; training then
moves the templates at a tenth of the step (at the full step the priming pulled them off the
simulated shapes: Experiment B, repetition 0, k = 0, 81.4 % against 88.1 % at the start). From a
random start it learns slowly. It needs revolutions of the length it was built for.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import torch
from torch import nn

from gearlab.errors import GearlabInputError, did_you_mean

from . import fast_frozen
from .bounds import abs_median, lower_median, noise_scale, shape_llr
from .config import DEFAULT_DROPOUT, DEFAULT_LENGTH, DEFAULT_NETWORK, NetworkSettings  # noqa: F401 (re-exported)


class AsChannels(nn.Module):
    """``(B, L)`` -> ``(B, 1, L)``; a ``(B, C, L)`` batch passes unchanged."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x.unsqueeze(1) if x.dim() == 2 else x


class Network(nn.Module):
    """A feature extractor and a classifier: ``forward(x) = classifier(features(x))``."""

    def __init__(
        self,
        name: str,
        features: nn.Module,
        classifier: nn.Module,
        latent_dim: int,
        n_classes: int,
        length: int,
        fixed_length: bool,
    ):
        super().__init__()
        self.name = name
        self.features = features
        self.classifier = classifier
        self.latent_dim = int(latent_dim)
        self.n_classes = int(n_classes)
        self.length = int(length)
        self.fixed_length = fixed_length

    def embed(self, x: torch.Tensor) -> torch.Tensor:
        """The latent features ``(B, latent_dim)`` of a batch ``(B, L)`` or ``(B, 1, L)``."""
        if self.fixed_length and x.shape[-1] != self.length:
            raise GearlabInputError(
                f"network '{self.name}': built for signals of {self.length} samples, got {x.shape[-1]}"
            )
        if self.name == "fast" and (fused := fast_frozen.features(fast_parts(self.features), x)) is not None:
            return fused  # one autograd function, normalisation frozen or training (learn/fast_frozen.py)
        return self.features(x)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.classifier(self.embed(x))

    def row_state(self, X: torch.Tensor, chunk: int = 1024) -> torch.Tensor | None:
        """``(n,)``: what the network computes from each input row of *X* (n, L) alone, with no
        weight (`shapes`: each revolution's median |r|, its noise scale's), or None where it
        computes nothing such. A training loop that feeds the same rows epoch after epoch computes
        it once and gives each batch its rows' share (`give_rows`): the same numbers, once."""
        layer = self._row_layer()
        if layer is None:
            return None
        with torch.no_grad():
            return torch.cat([abs_median(rows.reshape(len(rows), -1)) for rows in X.split(chunk)])

    def give_rows(self, state: torch.Tensor) -> None:
        """The next forward's rows' `row_state` (NaN for a row not known: computed then), for that
        forward only."""
        layer = self._row_layer()
        if layer is not None:
            layer.known = state

    def _row_layer(self) -> ShapeLikelihood | None:
        """The layer that reads the input rows as they are (the `shapes` network's templates)."""
        f = self.features
        if isinstance(f, nn.Sequential) and len(f) == 2 and isinstance(f[0], AsChannels):
            return f[1] if isinstance(f[1], ShapeLikelihood) else None
        return None

    def describe(self) -> dict:
        return {
            "name": self.name,
            "latent_dim": self.latent_dim,
            "n_classes": self.n_classes,
            "length": self.length,
            "parameters": sum(p.numel() for p in self.parameters()),
        }


def _he_uniform(module: nn.Module, generator: torch.Generator | None) -> None:
    """He-uniform weights (TensorFlow's he_uniform: U(±sqrt(6 / fan_in))) and zero biases."""
    for layer in module.modules():
        if isinstance(layer, (nn.Conv1d, nn.Linear)):
            nn.init.kaiming_uniform_(layer.weight, nonlinearity="relu", generator=generator)
            if layer.bias is not None:
                nn.init.zeros_(layer.bias)


def _torch_uniform(module: nn.Module, generator: torch.Generator | None) -> None:
    """PyTorch's own default for convolutions and dense layers, U(±1/sqrt(fan_in)) for weights
    and biases, drawn from *generator*. For ``burst`` it trains better than He-uniform within
    the same epochs (Experiment B, k = 0, 30 priming epochs: 80.2 against 74.8 % accuracy): the
    bank is followed by batch normalisation, so only the weights' scale relative to Adam's
    fixed step size changes, and smaller weights move further per step."""
    for layer in module.modules():
        if isinstance(layer, (nn.Conv1d, nn.Linear, ShapeLikelihood)):
            bound = 1.0 / math.sqrt(layer.weight[0].numel())
            nn.init.uniform_(layer.weight, -bound, bound, generator=generator)
            if getattr(layer, "bias", None) is not None:
                nn.init.uniform_(layer.bias, -bound, bound, generator=generator)


def _latent_dim(features: nn.Module, length: int) -> int:
    with torch.no_grad():
        return int(features.eval()(torch.zeros(1, 1, length)).shape[1])


CNN3_BLOCKS = ((4, 64, True), (8, 32, False), (8, 16, True))  # (kernels, kernel size, dropout after)


def cnn3(n_classes: int, dropout: float, length: int) -> Network:
    """CNN3 of the thesis (Han et al. 2019a): three conv–max-pool(–dropout) blocks,
    ~30 000 latent features, dense 120 -> 64."""
    layers: list[nn.Module] = [AsChannels()]
    channels = 1
    for kernels, size, with_dropout in CNN3_BLOCKS:
        layers += [nn.Conv1d(channels, kernels, size, stride=1), nn.ReLU(), nn.MaxPool1d(2, stride=1)]
        if with_dropout:
            layers.append(nn.Dropout(dropout))
        channels = kernels
    layers.append(nn.Flatten())
    features = nn.Sequential(*layers)
    shortest = sum(size for _, size, _ in CNN3_BLOCKS) + 1
    if length < shortest:
        raise GearlabInputError(f"network 'cnn3': signals must have at least {shortest} samples, got {length}")
    latent = _latent_dim(features, length)
    classifier = nn.Sequential(
        nn.Linear(latent, 120),
        nn.ReLU(),
        nn.Dropout(dropout),
        nn.Linear(120, 64),
        nn.ReLU(),
        nn.Dropout(dropout),
        nn.Linear(64, n_classes),
    )
    return Network("cnn3", features, classifier, latent, n_classes, length, fixed_length=True)


class WindowConv1d(nn.Conv1d):
    """nn.Conv1d of a one-channel signal as a matrix product of its windows (unfold: a view, no
    copy): weight (C, K) @ windows (B, K, L_out). For `fast`'s wide strided first layer on one
    CPU thread, forward and the weights' gradient take 0.55 of the convolution's time
    (benchmarks/training.py); the same sums in another order (gradients apart by rounding).
    Any other case (channels, groups, dilation, padding mode) is nn.Conv1d's."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.in_channels != 1 or self.dilation != (1,) or self.padding_mode != "zeros" or x.dim() != 3:
            return super().forward(x)
        (size,), (stride,), (pad,) = self.kernel_size, self.stride, self.padding
        windows = nn.functional.pad(x[:, 0], (pad, pad)).unfold(1, size, stride)  # (B, L_out, K)
        y = self.weight[:, 0] @ windows.mT
        return y if self.bias is None else y + self.bias[:, None]


class MaxPool2(nn.Module):
    """nn.MaxPool1d(2, ceil_mode=True): on the CPU its backward needs the maxima's indices, which
    torch finds by a slow path (16 times the plain maximum for `fast`'s (40, 16, 128) map, and as
    long as its first convolution). Here the maximum is the plain pool and the gradient goes to
    the larger of each pair (to the second on a tie, where max_pool picks the first: after the
    ReLU in front, a tie is two zeros, whose gradient the ReLU stops either way)."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if x.shape[-1] % 2 or not x.requires_grad:
            return nn.functional.max_pool1d(x, 2, ceil_mode=True)
        return _PairMax.apply(x)


class _PairMax(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x: torch.Tensor) -> torch.Tensor:
        ctx.save_for_backward(x)
        return nn.functional.max_pool1d(x, 2)

    @staticmethod
    def backward(ctx, grad: torch.Tensor) -> torch.Tensor:
        (x,) = ctx.saved_tensors
        # the first of a pair takes the gradient where it is the larger (threshold_backward: grad
        # where first - second > 0, else 0), the second the rest: no boolean masks, which are
        # slow on the CPU
        out = torch.empty_like(x)
        first = torch.ops.aten.threshold_backward(grad, x[..., 0::2] - x[..., 1::2], 0.0)
        out[..., 0::2] = first
        torch.sub(grad, first, out=out[..., 1::2])
        return out


def fast(n_classes: int, dropout: float, length: int) -> Network:
    """The thesis recipe's CPU network: wide strided first kernel (16 x 64, stride 16), two small
    strided convolutions, global average pooling to 64 features."""
    if length < 64:
        raise GearlabInputError(f"network 'fast': signals must have at least 64 samples, got {length}")

    def block(c_in: int, c_out: int, size: int, stride: int, padding: int) -> list[nn.Module]:
        conv = WindowConv1d if c_in == 1 else nn.Conv1d
        return [
            conv(c_in, c_out, size, stride=stride, padding=padding, bias=False),
            nn.BatchNorm1d(c_out),
            nn.ReLU(),
        ]

    features = nn.Sequential(
        AsChannels(),
        *block(1, 16, 64, stride=16, padding=24),
        MaxPool2(),
        *block(16, 32, 3, stride=2, padding=1),
        *block(32, 64, 3, stride=2, padding=1),
        nn.AdaptiveAvgPool1d(1),
        nn.Flatten(),
    )
    classifier = nn.Sequential(nn.Linear(64, 64), nn.ReLU(), nn.Dropout(dropout), nn.Linear(64, n_classes))
    return Network("fast", features, classifier, 64, n_classes, length, fixed_length=False)


def fast_parts(layers: nn.Module) -> tuple | None:
    """(conv1, norm1, conv2, norm2, conv3, norm3) of *layers* when they are fast()'s feature
    extractor with its settings (learn/fast_frozen.py computes it from them), else None."""
    kinds = (AsChannels, WindowConv1d, nn.BatchNorm1d, nn.ReLU, MaxPool2, nn.Conv1d, nn.BatchNorm1d, nn.ReLU)
    kinds += (nn.Conv1d, nn.BatchNorm1d, nn.ReLU, nn.AdaptiveAvgPool1d, nn.Flatten)
    if not isinstance(layers, nn.Sequential) or len(layers) != len(kinds):
        return None
    if any(type(layer) is not kind for layer, kind in zip(layers, kinds)) or layers[11].output_size not in (1, (1,)):
        return None
    (c1, n1), (c2, n2), (c3, n3) = (layers[1], layers[2]), (layers[5], layers[6]), (layers[8], layers[9])
    if c1.in_channels != 1 or c1.padding_mode != "zeros" or not (n1.affine and n2.affine and n3.affine):
        return None
    if any(c.bias is not None or c.groups != 1 or c.dilation != (1,) for c in (c1, c2, c3)):
        return None
    if any(c.kernel_size != (3,) or c.stride != (2,) or c.padding != (1,) for c in (c2, c3)):
        return None
    return c1, n1, c2, n2, c3, n3


class RobustLimiter(nn.Module):
    """Per revolution: divide by the robust noise scale 1.4826·MAD, then limit softly,
    ``c·tanh(z / c)``. Impulsive (Laplace, Student-t) noise puts a few samples far out; the
    locally optimal detector for such noise passes small values and clips large ones (Kay,
    vol. II, ch. 10: the limiter is the score function of Laplace noise, tanh a smooth one),
    so one noise spike cannot outvote a burst spread over tens of samples. Dividing by the
    revolution's own scale makes the network gain-free: a sensor in other units, or a domain
    with another signal level, gives the same input."""

    def __init__(self, clip: float):
        super().__init__()
        self.clip = float(clip)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        centred = x - lower_median(x)
        scale = 1.4826 * lower_median(centred.abs())
        z = centred / scale.clamp_min(1e-12)
        return self.clip * torch.tanh(z / self.clip)


class NormMaxAbs(nn.BatchNorm1d):
    """``(B, C, L) -> (B, C)``: batch normalisation, then each filter's largest magnitude over
    the revolution, so that a burst anywhere in the revolution counts in full (an average over
    the revolution would dilute a 40-160-sample burst by a factor of 25-100).

    With the statistics fixed (evaluation, and the joint phase's frozen normalisation,
    gearlab.learn.training.train_mode) the normalisation is an affine map a·y + c per channel,
    so the largest |a·y + c| lies at the channel's largest or smallest y: those two are picked
    (no gradient flows through the picking) and only they are normalised. The same numbers as
    normalising the whole map, to rounding, and a joint-phase step takes 0.64-0.80 of the time
    (benchmarks/learning.py; the full-map normalisation, absolute value and maximum and their
    gradients were most of it). While the statistics are learnt the whole map is normalised, as BatchNorm1d does."""

    def forward(self, y: torch.Tensor) -> torch.Tensor:
        if self.training:
            return super().forward(y).abs().amax(dim=-1)
        with torch.no_grad():
            where = torch.stack((y.argmax(dim=-1), y.argmin(dim=-1)), dim=-1)
        a = self.weight * torch.rsqrt(self.running_var + self.eps)
        c = self.bias - self.running_mean * a
        return (a[:, None] * y.gather(-1, where) + c[:, None]).abs().amax(dim=-1)


BURST_FILTERS = 32  # learned filters in the bank
BURST_DECIMATE = 2  # the bursts' energy lies below half the Nyquist rate (90 % below 0.22 of it)
BURST_KERNEL = 33  # taps at the halved rate = 66 samples: most chapter-5 fault bursts (40-160 samples)
BURST_STRIDE = 2  # the bank's output every 4 samples of the revolution
BURST_CLIP = 1.5  # soft limit, in robust noise scales


def burst(n_classes: int, dropout: float, length: int) -> Network:
    """Bursts in impulsive noise: robust soft limiter, a bank of filters over the whole
    revolution (circular: a revolution is periodic), batch-normalised, global max of |response|,
    small classifier."""
    shortest = BURST_DECIMATE * BURST_KERNEL
    if length < shortest:
        raise GearlabInputError(f"network 'burst': signals must have at least {shortest} samples, got {length}")
    features = nn.Sequential(
        AsChannels(),
        RobustLimiter(BURST_CLIP),
        nn.AvgPool1d(BURST_DECIMATE),
        nn.Conv1d(
            1,
            BURST_FILTERS,
            BURST_KERNEL,
            stride=BURST_STRIDE,
            padding=BURST_KERNEL // 2,
            padding_mode="circular",
            bias=False,
        ),
        NormMaxAbs(BURST_FILTERS),
    )
    classifier = nn.Sequential(nn.Linear(BURST_FILTERS, 32), nn.ReLU(), nn.Dropout(dropout), nn.Linear(32, n_classes))
    network = Network("burst", features, classifier, BURST_FILTERS, n_classes, length, fixed_length=False)
    network.bank_layer = 3  # the filter bank's place in .features (matched_start); an int, not a second registration
    return network


SHAPES = 256  # templates of the `shapes` network per fault class (Experiment B's source has ~270 training faults)
SHAPE_REACH = 8  # a `shapes` template spans an eighth of a revolution (ShapeLikelihood)
SHAPE_STEP = 0.1  # templates learn at a tenth of the optimiser's step (docs/learning.md, section 6)
# a mixture term below e^-50 = 2e-22 of its class's largest is taken as that (its gradient 0): it moves
# the class's sum less than float64's rounding for up to 500 k terms, and exp of lower values, whose
# results lie near float32's smallest normal numbers, takes a slow path (0.69 ms against 15 us for a
# (40, 1,025) batch of terms far apart)
MIXTURE_FLOOR = -50.0


class LaplaceGain(torch.autograd.Function):
    """``(padded (B, L + width), templates (J, width), offset (J,), scale)`` -> ``(B, J)``: each
    local template's (times *scale*) Laplace score before the noise scale, sum_n |r_n| - |r_n - t_j,n|
    over its window, and the stored templates' gradient, by the compiled loops of
    gearlab.learn.kernels, which scale each template as they use it (no scaled copy of the bank
    forward, none of its gradient back; the same products as torch's). The same numbers as
    torch's path (`_laplace_windows`) to rounding (the sums' order differs; its
    tests compare the two), at a fifth of a training step's time (benchmarks/training.py)."""

    @staticmethod
    def applies(padded: torch.Tensor, templates: torch.Tensor) -> bool:
        """The loops serve CPU tensors of one floating precision whose revolutions need no
        gradient (a network's input); anything else takes torch's path."""
        return (
            padded.device.type == "cpu"
            and templates.device.type == "cpu"
            and padded.dtype == templates.dtype
            and padded.dtype in (torch.float32, torch.float64)
            and not padded.requires_grad
        )

    @staticmethod
    def forward(
        ctx, padded: torch.Tensor, templates: torch.Tensor, offset: torch.Tensor, scale: float = 1.0
    ) -> torch.Tensor:
        from . import kernels  # numba: loaded when a network first scores (start-up time)

        p, t = padded.detach().contiguous(), templates.detach().contiguous()
        o = offset.detach().to(torch.int64).contiguous()
        s = np.array([scale], dtype=t.numpy().dtype)  # in the templates' precision, as torch's product
        out = torch.empty(len(p), len(t), dtype=p.dtype)
        kernels.laplace_gain_scaled(p.numpy(), t.numpy(), s, o.numpy(), out.numpy())
        ctx.save_for_backward(p, t, o)
        ctx.scale = s
        return out

    @staticmethod
    def backward(ctx, grad: torch.Tensor):
        from . import kernels

        p, t, o = ctx.saved_tensors
        out = torch.empty_like(t)
        g = grad.contiguous()
        kernels.laplace_gain_grad_scaled(p.numpy(), t.numpy(), ctx.scale, o.numpy(), g.numpy(), out.numpy())
        return None, out, None, None


def _laplace_windows(padded: torch.Tensor, templates: torch.Tensor, offset: torch.Tensor) -> torch.Tensor:
    """LaplaceGain's sums by torch (a GPU, an input that needs a gradient): every template's window
    gathered at once, (B, J, width), and sum_n |r_n| - |r_n - t_j,n| over it. A few operators, where
    a loop over the distinct offsets took a handful each and a device synchronisation: on an H200 a
    `shapes` step at batch 40 took 17.5-21.1 ms that way, against ~2 ms on one CPU core."""
    index = offset[:, None] + torch.arange(templates.shape[1], device=offset.device)
    windows = padded[:, index]
    return windows.abs().sum(-1) - (windows - templates).abs().sum(-1)


class ShapeLikelihood(nn.Module):
    """``(B, L)`` residual revolutions -> ``(B, J)``: each template's log-likelihood ratio in
    the noise law *law* at the revolution's own scale (gearlab.learn.bounds, `shape_llr`); for
    Laplace noise (the law is the target history's, `calibration.history_law`)

        z_j = (||r||_1 - ||r - t_j||_1) / b,        b = median|r| / ln 2,

    so a sample far out (an impulse) moves z_j by at most |t_j,n| / b: the Laplace law's own
    limiter. Each template is *local*: it holds `width` samples from its `offset` on (circular;
    offsets on a grid of `width // 4`) and is zero elsewhere, where its samples add nothing to z_j
    (|r_n| - |r_n - 0| = 0), so z_j is summed over its window only, exactly. Why: a fault's
    response is local (Experiment B's weakest quarter of source faults keeps >= 99.3 % of its
    deflection sum t^2 / b^2 in its best window of 512 of 4096 samples), and the whole-revolution
    distance to every template was the network's cost (docs/learning.md, decision 21). The
    templates are stored divided by `SHAPE_STEP`, so that Adam's fixed step size moves them by a
    tenth of what it moves other weights. The law is the start's (`matched_start`), not a weight:
    a state dict does not carry it."""

    def __init__(self, n_shapes: int, length: int, law: str = "laplace", width: int | None = None):
        super().__init__()
        self.length = length
        self.width = length if width is None else min(width, length)
        self.stride = max(self.width // 4, 1)
        self.weight = nn.Parameter(torch.zeros(n_shapes, self.width))
        # until a start places them, the windows tile the revolution
        self.register_buffer("offset", (torch.arange(n_shapes) * self.stride) % length)
        self.law = law
        self.known: torch.Tensor | None = None  # the next forward's rows' median |r| (Network.give_rows)

    @property
    def shapes(self) -> torch.Tensor:
        """The templates as whole revolutions ``(J, L)``."""
        local = self.weight * SHAPE_STEP
        index = (self.offset[:, None] + torch.arange(self.width, device=local.device)) % self.length
        return torch.zeros(len(local), self.length, dtype=local.dtype, device=local.device).scatter(1, index, local)

    def place(self, shapes: np.ndarray) -> None:
        """Set the templates from whole revolutions ``(n, L)`` (the first n of the bank): each
        keeps its window on the grid that holds most of its energy."""
        S = np.asarray(shapes, dtype=np.float64)
        energy = np.concatenate([S**2, S[:, : self.width] ** 2], axis=1).cumsum(axis=1)
        energy = np.concatenate([np.zeros((len(S), 1)), energy], axis=1)
        grid = np.arange(0, self.length, self.stride)
        offset = grid[(energy[:, grid + self.width] - energy[:, grid]).argmax(axis=1)]
        index = (offset[:, None] + np.arange(self.width)) % self.length
        with torch.no_grad():
            self.offset[: len(S)] = torch.as_tensor(offset)
            self.weight[: len(S)] = torch.as_tensor(np.take_along_axis(S, index, axis=1) / SHAPE_STEP)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        r = x.reshape(len(x), -1)
        with torch.no_grad():  # the scale is the noise's, not a feature to learn
            known, self.known = self.known, None
            b = noise_scale(r, self.law, _medians(r, known))
        if self.width == self.length:
            return shape_llr(r, self.shapes, b, self.law)
        padded = torch.cat([r, r[:, : self.width]], dim=1)  # circular windows
        if self.law == "laplace" and LaplaceGain.applies(padded, self.weight):  # the loops scale as they go
            return LaplaceGain.apply(padded, self.weight, self.offset, SHAPE_STEP) / b[:, None]
        local = self.weight * SHAPE_STEP
        if self.law == "laplace":
            return _laplace_windows(padded, local, self.offset) / b[:, None]
        z = torch.empty(len(r), len(local), dtype=r.dtype, device=r.device)
        for start in torch.unique(self.offset).tolist():
            mine = torch.nonzero(self.offset == start).squeeze(1)
            z[:, mine] = shape_llr(padded[:, start : start + self.width], local[mine], b, self.law)
        return z

    def extra_repr(self) -> str:
        return f"{len(self.weight)} templates of {self.width} samples, {self.law} noise"


def _medians(r: torch.Tensor, known: torch.Tensor | None) -> torch.Tensor | None:
    """The rows' median |r|: *known*'s, those it lacks (NaN) computed; None where nothing is known."""
    if known is None:
        return None
    if known.shape != (len(r),):
        raise ValueError(f"given {tuple(known.shape)} row medians for a batch of {len(r)} rows")
    missing = torch.isnan(known)
    if not bool(missing.any()):
        return known
    out = known.clone()
    out[missing] = abs_median(r[missing])
    return out


class ShapeMixture(nn.Module):
    """``(B, J)`` -> ``(B, C)`` logits: class c's log mixture likelihood ratio against healthy,

        logit_c = log Σ_j w_j,c · exp(z_j),        z_0 = 0 (the healthy shape: no response),

    with learnt log weights ``log w`` (J + 1 x C) over a fixed membership: healthy is the zero
    shape alone, each fault class a mixture of its own templates. Started as the Bayes
    detector's mixture (gearlab.learn.bounds): each class's templates equally weighted."""

    def __init__(self, n_shapes: int, n_classes: int):
        super().__init__()
        self.log_weight = nn.Parameter(torch.zeros(n_shapes + 1, n_classes))
        self.register_buffer("member", torch.zeros(n_shapes + 1, n_classes, dtype=torch.bool))
        # a block of templates per fault class until a start says which template is whose
        self.use(1 + np.arange(n_shapes) * max(n_classes - 1, 1) // max(n_shapes, 1))

    def use(self, classes: np.ndarray, prior: np.ndarray | None = None) -> None:
        """Healthy = the zero shape; template j belongs to fault class ``classes[j]`` (the
        templates beyond ``len(classes)`` to none); each class's templates equally weighted,
        times the class's *prior* probability when given (the Bayes classifier's posterior)."""
        classes = np.asarray(classes, dtype=np.int64)
        log_prior = np.zeros(self.log_weight.shape[1]) if prior is None else np.log(np.asarray(prior, dtype=float))
        with torch.no_grad():
            self.member.zero_()
            self.member[0, 0] = True
            self.log_weight.zero_()
            self.log_weight[0, 0] = float(log_prior[0])
            for c in np.unique(classes):
                mine = 1 + np.flatnonzero(classes == c)
                self.member[mine, c] = True
                self.log_weight[mine, c] = float(log_prior[c]) - math.log(len(mine))

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        # each template is one class's at most (`use`): each class's log-sum over its own members,
        # where a logsumexp over (B, J + 1, C) did C times the work (at 5 classes 3.0 of a 9 ms step)
        z = torch.cat([torch.zeros_like(z[:, :1]), z], dim=1)
        n_classes = self.log_weight.shape[1]
        member = self.member
        which = torch.where(member.any(1), member.to(torch.uint8).argmax(1), n_classes)  # C: in no class
        # each template's own log weight (-inf where it has none); amax passes the gradient to it alone
        a = z + self.log_weight.masked_fill(~member, -math.inf).amax(1)
        at = which.expand(len(a), -1)
        with torch.no_grad():  # per class the largest term, as logsumexp shifts (an infinite one by 0)
            top = torch.full((len(a), n_classes + 1), -math.inf, dtype=a.dtype, device=a.device)
            top.scatter_reduce_(1, at, a, "amax")
            shift = top.nan_to_num(0.0, 0.0, 0.0)
        terms = torch.exp((a - shift.gather(1, at)).clamp(min=MIXTURE_FLOOR))
        sums = torch.zeros_like(top).index_add_(1, which, terms)
        return (top + torch.log(sums))[:, :n_classes]


def shapes(n_classes: int, dropout: float, length: int) -> Network:
    """The Bayes detector's form as a network: `SHAPES` local templates per fault class (an
    eighth of the revolution each, `SHAPE_REACH`) scored by their likelihood ratio, a learnt
    mixture per class. *dropout* is not used (there is no dense layer to drop)."""
    n_shapes = SHAPES * max(n_classes - 1, 1)
    features = nn.Sequential(AsChannels(), ShapeLikelihood(n_shapes, length, width=max(length // SHAPE_REACH, 1)))
    return Network(
        "shapes", features, ShapeMixture(n_shapes, n_classes), n_shapes, n_classes, length, fixed_length=True
    )


def use_law(network: nn.Module, law: str) -> None:
    """Score *network*'s `shapes` templates (if it has any) in the noise law *law*: the law is
    not a weight, so a network built again from a state dict is told it here."""
    for module in network.modules():
        if isinstance(module, ShapeLikelihood):
            module.law = law


def _start_shapes(
    network: Network, faults: np.ndarray, classes: np.ndarray, seed: int, law: str, prior: np.ndarray | None
) -> bool:
    """`shapes`' matched start: its templates are the fault residuals themselves (per class a
    seeded choice of `SHAPES` when there are more), the mixture, the class priors and the noise
    law those of the Bayes classifier."""
    rng = np.random.default_rng(seed)
    chosen = np.concatenate([rng.permutation(np.flatnonzero(classes == c))[:SHAPES] for c in np.unique(classes)])
    likelihood = network.features[1]
    if len(chosen) > len(likelihood.weight):
        raise ValueError(
            f"{len(chosen)} templates for a bank of {len(likelihood.weight)}: more fault classes than built"
        )
    likelihood.place(faults[chosen])
    likelihood.law = law
    network.classifier.use(classes[chosen], prior)
    return True


def matched_start(
    network: Network,
    faults: np.ndarray,
    seed: int,
    classes: np.ndarray | None = None,
    law: str | None = None,
    prior: np.ndarray | None = None,
) -> bool:
    """Start *network*'s filter bank as matched filters of the simulated *faults* (fault
    residuals, one revolution a row, as the network will see them; *classes* their fault
    classes, all 1 when not given; *law* the noise law and *prior* the class probabilities,
    healthy first, which only `shapes` uses): the k-means centroids of
    each fault's most energetic window of the bank's length, at the bank's rate (the 2-fold
    average pool), each normalised and turned so its largest sample is positive, at the norm
    of the random start. The soft limiter in front is left out: a burst below its clip passes
    it almost linearly. Filters beyond the distinct windows keep their random start; a network
    without a bank (cnn3, fast) keeps all of it (returns False). Why: trained from a random
    start, the bank learns the strong faults (cracks, spalls) and leaves the weak ones (pits,
    chips) to noise; started on them, it keeps them (docs/learning.md, decision 20)."""
    F = np.asarray(faults, dtype=np.float64)
    if len(F) == 0:
        return False
    if network.name == "shapes":
        if law is None:  # the law is the target history's (calibration.history_law), never assumed
            raise ValueError("matched_start: a `shapes` network needs the noise law of its history")
        classes = np.ones(len(F), np.int64) if classes is None else np.asarray(classes)
        return _start_shapes(network, F, classes, seed, law, prior)
    layer = getattr(network, "bank_layer", None)
    if layer is None:
        return False
    bank = network.features[layer]
    from sklearn.cluster import KMeans  # sklearn is slow to import; only priming needs it

    width = bank.kernel_size[0]
    F = F[:, : F.shape[1] // BURST_DECIMATE * BURST_DECIMATE].reshape(len(F), -1, BURST_DECIMATE).mean(-1)
    cumulative = np.cumsum(np.concatenate([np.zeros((len(F), 1)), F**2, F[:, :width] ** 2], axis=1), axis=1)
    energy = cumulative[:, width:] - cumulative[:, :-width]  # of the window starting at each sample, circular
    # windows that hold a whole burst tie: rounding makes the first of them win, not the last bit
    first = np.round(energy / energy.max(axis=1, keepdims=True).clip(min=1e-300), 9).argmax(axis=1)
    windows = np.take_along_axis(F, (first[:, None] + np.arange(width)) % F.shape[1], axis=1)
    norm = np.linalg.norm(windows, axis=1)
    windows = windows[norm > 0] / norm[norm > 0, None]
    windows *= np.sign(windows[np.arange(len(windows)), np.abs(windows).argmax(axis=1)])[:, None]
    distinct = len(np.unique(windows.round(6), axis=0))
    if distinct == 0:
        return False
    n = min(bank.out_channels, distinct)
    centres = KMeans(n, n_init=3, random_state=seed).fit(windows).cluster_centers_
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    with torch.no_grad():
        scale = bank.weight.norm(dim=-1).mean()
        bank.weight[:n, 0, :] = torch.as_tensor(centres, dtype=bank.weight.dtype) * scale
    return True


NETWORKS: dict[str, Callable[[int, float, int], Network]] = {
    "cnn3": cnn3,
    "fast": fast,
    "burst": burst,
    "shapes": shapes,
}
TORCH_INIT = (
    "burst",
    "shapes",
)  # initialised as PyTorch does (_torch_uniform); the thesis's nets He-uniform (Table 3.1)


def build_network(
    name: str,
    n_classes: int,
    dropout: float = DEFAULT_DROPOUT,
    length: int = DEFAULT_LENGTH,
    seed: int | None = None,
) -> Network:
    """Build network *name* for *n_classes* classes and signals of *length* samples.

    Weights are drawn from torch's global generator (so ``torch.manual_seed`` fixes them)
    or, when *seed* is given, from a private generator seeded with it.
    """
    if name not in NETWORKS:
        known = sorted(NETWORKS)
        raise GearlabInputError(
            f"unknown network '{name}'{did_you_mean(name, known)}; known networks: {', '.join(known)}"
        )
    if isinstance(n_classes, bool) or int(n_classes) != n_classes or n_classes < 2:
        raise GearlabInputError(f"network '{name}': n_classes must be a whole number >= 2, got {n_classes!r}")
    if not 0.0 <= dropout < 1.0:
        raise GearlabInputError(f"network '{name}': dropout must lie in [0, 1), got {dropout!r}")
    if isinstance(length, bool) or int(length) != length or length < 1:
        raise GearlabInputError(f"network '{name}': length must be a whole number of samples, got {length!r}")
    network = NETWORKS[name](int(n_classes), float(dropout), int(length))
    generator = torch.Generator().manual_seed(seed) if seed is not None else None
    (_torch_uniform if name in TORCH_INIT else _he_uniform)(network, generator)
    return network.train()
