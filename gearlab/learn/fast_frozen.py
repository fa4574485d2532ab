"""`fast`'s feature extractor as one autograd function, its batch normalisation frozen or training.

A joint (domain-adaptation) training, a fine-tuning and every evaluation run `fast` with its
batch normalisation frozen (``training.train_mode(net, freeze_norm=True)``, or ``eval()``): each
normalisation is then a fixed affine map per channel. A priming and a supervised baseline train
it with the batch's own statistics (training mode), the running ones updated as BatchNorm1d does.
Through the modules a step is dozens of operators on maps of 80 x 16 x 128 values at most, and
oneDNN's stride-2 convolutions and their gradients at these sizes run at a third to a quarter of
the machine's matrix-product speed. Here the same network is 3 matrix products forward and 5
backward on channels-last windows (each convolution a product of its windows, oneDNN's), the
normalisations multiply-adds (in training mode with each channel's mean and variance over the
batch's rows and their gradient terms), ReLU and the pair maximum one pass, the gradients written
by hand: the same function, gradients and running statistics, the sums in another order
(rounding: 1e-7 to 1e-5 of each gradient's largest element, tests/test_fast_frozen.py). Another
layout of layers, normalisations in mixed modes or without running statistics, a device or shape
keep the modules.
"""

from __future__ import annotations

import torch
from torch.nn import functional as F


def features(parts: tuple | None, x: torch.Tensor) -> torch.Tensor | None:
    """`fast`'s feature extractor of *x* by _Frozen, its *parts* (conv1, norm1, conv2, norm2,
    conv3, norm3: networks.fast_parts) with every batch normalisation in evaluation mode, or every
    one in training mode (the running statistics updated); None where it does not apply (no parts:
    another layout of layers; normalisations in mixed modes, without running statistics or with a
    cumulative average (momentum None); a signal whose first map has an odd length, a training
    batch of one value per channel, an input that needs a gradient, a device other than the CPU,
    another dtype)."""
    if x.dim() == 3 and x.shape[1] == 1:
        x = x[:, 0]
    if parts is None or x.dim() != 2 or x.device.type != "cpu" or x.dtype != torch.float32 or x.requires_grad:
        return None
    norms = parts[1::2]
    training = norms[0].training
    if any(n.training != training or n.running_mean is None or n.momentum is None for n in norms):
        return None
    conv1 = parts[0]
    (size,), (stride,), (pad,) = conv1.kernel_size, conv1.stride, conv1.padding
    first = (x.shape[1] + 2 * pad - size) // stride + 1
    if first < 2 or first % 2 or (training and len(x) * _lengths(first)[1] < 2):
        return None  # (torch refuses to normalise one value per channel by its own statistics)
    c1, n1, c2, n2, c3, n3 = parts
    return _Frozen.apply(
        x, c1.weight, n1.weight, n1.bias, c2.weight, n2.weight, n2.bias, c3.weight, n3.weight, n3.bias,
        (n1, n2, n3), (size, stride, pad), training,
    )  # fmt: skip


def _windows(x: torch.Tensor, length: int) -> torch.Tensor:
    """The size-3, stride-2 windows of channels-last maps *x* (B, L, C) with one zero row either
    side, (B * length, 3 * C), each window's rows one after the other (a copy)."""
    b, _, c = x.shape
    padded = F.pad(x, (0, 0, 1, 1))
    return padded.as_strided((b, length, 3 * c), (padded.stride(0), 2 * c, 1)).reshape(b * length, 3 * c)


def _unwindows(grad: torch.Tensor, b: int, length: int, rows: int) -> torch.Tensor:
    """The gradient of the (B, rows, C) maps whose windows (_windows) got *grad* (B * length, 3 * C)."""
    g = grad.view(b, length, 3, -1)
    out = torch.empty(b, 2 * length + 1, g.shape[-1])  # the padded rows 0 .. 2 * length
    out[:, 0 : 2 * length : 2] = g[:, :, 0]
    out[:, 1 : 2 * length : 2] = g[:, :, 1]
    out[:, 2 * length] = 0.0
    out[:, 2 : 2 * length + 1 : 2] += g[:, :, 2]
    return out[:, 1 : rows + 1]


def _inner_product() -> object | None:
    """oneDNN's inner product (the op torch.compile's CPU code calls for a dense layer), where this
    torch has it."""
    try:
        return torch.ops.mkldnn._linear_pointwise.default if torch.backends.mkldnn.is_available() else None
    except (AttributeError, RuntimeError):
        return None


_INNER = _inner_product()


INNER_MIN = 1 << 20  # multiply-adds of the smallest product worth oneDNN's ~10 us a call (MKL's ~2.5)


def product(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """a @ b of float32 CPU matrices (either may be a transposed view) by oneDNN's inner product,
    where torch has it and the product has INNER_MIN multiply-adds or more: on an AMD CPU with
    AVX-512 MKL's matrix product runs its AVX2 kernels (103 GFLOP/s at 512 x 512 on one thread,
    oneDNN 245), so `fast`'s 8 products at batch 40 take 0.42 against 0.59 ms and a training step
    5 % less (the sums in another order: rounding); oneDNN's fixed cost a call is the larger, so a
    small product (batch 2: 0.3 M) stays MKL's."""
    if _INNER is None or a.shape[0] * a.shape[1] * b.shape[1] < INNER_MIN:
        return a @ b
    return _INNER(a, b.T, None, "none", [], "")


def _as_matrix(weight: torch.Tensor) -> torch.Tensor:
    """A (C_out, C_in, 3) convolution weight as (C_out, 3 * C_in), in _windows' order."""
    return weight.permute(0, 2, 1).reshape(weight.shape[0], -1)


def _lengths(first: int) -> tuple[int, int]:
    """The lengths of the second and third maps after a first map of *first* (even) values: the
    pair maximum halves it, each stride-2 convolution (size 3, padding 1) halves it rounding up."""
    l2 = (first // 2 - 1) // 2 + 1
    return l2, (l2 - 1) // 2 + 1


class _Frozen(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x, w1, g1, b1, w2, g2, b2, w3, g3, b3, norms, geometry, training):
        size, stride, pad = geometry
        b = x.shape[0]
        win = F.pad(x, (pad, pad)).unfold(1, size, stride)  # (B, L1, size): a view
        l1 = win.shape[1]
        l2, l3 = _lengths(l1)
        win = win.reshape(b * l1, size)  # the copy networks.WindowConv1d's product makes too
        h1 = product(win, w1[:, 0].T)  # (B * L1, C1), channels last
        z1, n1 = _Norm.of(h1, norms[0], g1, b1, training)
        z1 = z1.view(b, l1 // 2, 2, -1)
        pair = z1[:, :, 0] - z1[:, :, 1]  # > 0: the first of a pair is the maximum (MaxPool2)
        p = torch.maximum(z1[:, :, 0], z1[:, :, 1]).clamp_(min=0)  # the pair maximum of ReLU's output
        col2 = _windows(p, l2)
        h2 = product(col2, _as_matrix(w2).T)
        r2, n2 = _Norm.of(h2, norms[1], g2, b2, training)
        r2 = r2.clamp_(min=0)
        col3 = _windows(r2.view(b, l2, -1), l3)
        h3 = product(col3, _as_matrix(w3).T)
        r3, n3 = _Norm.of(h3, norms[2], g3, b3, training)
        r3 = r3.clamp_(min=0)
        ctx.save_for_backward(win, h1, pair, p, col2, h2, r2, col3, h3, r3, w2, w3)
        ctx.sizes, ctx.norms = (b, l1, l2, l3), (n1, n2, n3)
        return r3.view(b, l3, -1).mean(1)

    @staticmethod
    def backward(ctx, grad):
        win, h1, pair, p, col2, h2, r2, col3, h3, r3, w2, w3 = ctx.saved_tensors
        n1, n2, n3 = ctx.norms
        b, l1, l2, l3 = ctx.sizes
        relu = torch.ops.aten.threshold_backward
        g = relu((grad / l3)[:, None, :].expand(b, l3, -1), r3.view(b, l3, -1), 0.0).view(b * l3, -1)
        g, d3 = n3.backward(g, h3)
        dw3 = product(g.T, col3).view(w3.shape[0], 3, -1).permute(0, 2, 1)
        g = relu(_unwindows(product(g, _as_matrix(w3)), b, l3, l2).reshape(b * l2, -1), r2, 0.0)
        g, d2 = n2.backward(g, h2)
        dw2 = product(g.T, col2).view(w2.shape[0], 3, -1).permute(0, 2, 1)
        g = relu(_unwindows(product(g, _as_matrix(w2)), b, l2, l1 // 2), p, 0.0)  # (B, L1 / 2, C1)
        out = torch.empty(b, l1 // 2, 2, g.shape[-1])
        first = relu(g, pair, 0.0)
        out[:, :, 0] = first
        torch.sub(g, first, out=out[:, :, 1])
        g, d1 = n1.backward(out.view(b * l1, -1), h1)
        dw1 = product(g.T, win)[:, None, :]
        return None, dw1, *d1, dw2, *d2, dw3, *d3, None, None, None


class _Norm:
    """One batch normalisation of rows (N, C) per channel: its statistics (mean, inv = 1 / sqrt(var
    + eps)) and scale = weight * inv, for the gradients (backward)."""

    def __init__(self, mean: torch.Tensor, inv: torch.Tensor, weight: torch.Tensor, training: bool):
        self.mean, self.inv, self.scale, self.training = mean, inv, weight * inv, training

    @staticmethod
    def of(h: torch.Tensor, norm, weight: torch.Tensor, bias: torch.Tensor, training: bool) -> tuple:
        """(z, _Norm) of the rows *h*: z = h * scale + shift per channel, by the running statistics
        of *norm* (frozen), or in *training* by the rows' own mean and (biased) variance, the running
        ones updated by *norm*'s momentum with the unbiased variance, as BatchNorm1d does. The
        variance in two passes: torch's kernel for rows (N, C) sums them in float32 one after the
        other (mean and variance 2e-6 from float64's at 5120 rows, where its kernel for the modules'
        (B, C, L) is at 1e-7, and so is this), var_mean takes ten times as long."""
        if training:
            n = len(h)
            mean = h.sum(0) / n
            centred = h - mean
            var = (centred * centred).sum(0) / n
            norm.running_mean.lerp_(mean, norm.momentum)
            norm.running_var.lerp_(var * (n / (n - 1)), norm.momentum)
            norm.num_batches_tracked.add_(1)
        else:
            mean, var = norm.running_mean, norm.running_var
        out = _Norm(mean, torch.rsqrt(var + norm.eps), weight, training)
        return torch.addcmul(bias - mean * out.scale, h, out.scale), out

    def backward(self, grad: torch.Tensor, h: torch.Tensor) -> tuple[torch.Tensor, tuple[torch.Tensor, torch.Tensor]]:
        """The gradient of the rows *h* whose output got *grad*, and those of the normalisation's
        weight and bias: the sums of grad * (h - mean) * inv and of grad over the rows. In training
        the mean and the variance are the rows' own, and their gradient takes from each row's the
        rows' mean gradient and the part along h - mean: scale * (grad - (d_bias + (h - mean) *
        inv * d_weight) / N)."""
        d_weight, d_bias = ((h - self.mean) * grad).sum(0) * self.inv, grad.sum(0)
        if not self.training:
            return grad * self.scale, (d_weight, d_bias)
        n = len(h)
        along = self.scale * self.inv * d_weight / n
        level = self.mean * along - self.scale * d_bias / n
        return torch.addcmul(torch.addcmul(level, grad, self.scale), h, -along), (d_weight, d_bias)
