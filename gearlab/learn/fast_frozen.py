"""`fast`'s feature extractor with frozen batch normalisation as one autograd function.

A joint (domain-adaptation) training, a fine-tuning and every evaluation run `fast` with its
batch normalisation frozen (``training.train_mode(net, freeze_norm=True)``, or ``eval()``): each
normalisation is then a fixed affine map per channel. phm09_chip's trainings are nearly all such
steps. Through the modules a step is dozens of operators on maps of 80 x 16 x 128 values at
most, and oneDNN's stride-2 convolutions and their gradients at these sizes run at a third to a
quarter of the machine's matrix-product speed. Here the same network is 3 matrix products
forward and 5 backward on channels-last windows (each convolution a product of its windows), the
normalisations multiply-adds, ReLU and the pair maximum one pass, the gradients written by hand:
the same function and gradients, the sums in another order (rounding: 1e-7 to 1e-5 of each
gradient's largest element, tests/test_fast_frozen.py). Batch normalisation in training mode (a
priming, a supervised baseline), another layout of layers, device or shape keep the modules.
"""

from __future__ import annotations

import torch
from torch.nn import functional as F


def features(parts: tuple | None, x: torch.Tensor) -> torch.Tensor | None:
    """`fast`'s feature extractor of *x* by _Frozen, its *parts* (conv1, norm1, conv2, norm2,
    conv3, norm3: networks.fast_parts) with every batch normalisation in evaluation mode; None
    where it does not apply (no parts: another layout of layers; normalisation training, a signal
    whose first map has an odd length, an input that needs a gradient, a device other than the
    CPU, another dtype)."""
    if x.dim() == 3 and x.shape[1] == 1:
        x = x[:, 0]
    if parts is None or x.dim() != 2 or x.device.type != "cpu" or x.dtype != torch.float32 or x.requires_grad:
        return None
    if any(n.training or n.running_mean is None for n in parts[1::2]):
        return None
    conv1 = parts[0]
    (size,), (stride,), (pad,) = conv1.kernel_size, conv1.stride, conv1.padding
    first = (x.shape[1] + 2 * pad - size) // stride + 1
    if first < 2 or first % 2:
        return None
    c1, n1, c2, n2, c3, n3 = parts
    return _Frozen.apply(
        x, c1.weight, n1.weight, n1.bias, c2.weight, n2.weight, n2.bias, c3.weight, n3.weight, n3.bias,
        (n1, n2, n3), (size, stride, pad),
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


def _as_matrix(weight: torch.Tensor) -> torch.Tensor:
    """A (C_out, C_in, 3) convolution weight as (C_out, 3 * C_in), in _windows' order."""
    return weight.permute(0, 2, 1).reshape(weight.shape[0], -1)


class _Frozen(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x, w1, g1, b1, w2, g2, b2, w3, g3, b3, norms, geometry):
        size, stride, pad = geometry
        b = x.shape[0]
        inv = [torch.rsqrt(n.running_var + n.eps) for n in norms]
        means = [n.running_mean for n in norms]
        scale = [g * i for g, i in zip((g1, g2, g3), inv)]
        shift = [beta - m * s for beta, m, s in zip((b1, b2, b3), means, scale)]
        win = F.pad(x, (pad, pad)).unfold(1, size, stride)  # (B, L1, size): a view
        l1 = win.shape[1]
        win = win.reshape(b * l1, size)  # the copy networks.WindowConv1d's product makes too
        h1 = win @ w1[:, 0].T  # (B * L1, C1), channels last
        z1 = torch.addcmul(shift[0], h1, scale[0]).view(b, l1 // 2, 2, -1)
        pair = z1[:, :, 0] - z1[:, :, 1]  # > 0: the first of a pair is the maximum (MaxPool2)
        p = torch.maximum(z1[:, :, 0], z1[:, :, 1]).clamp_(min=0)  # the pair maximum of ReLU's output
        l2 = (l1 // 2 - 1) // 2 + 1
        col2 = _windows(p, l2)
        h2 = col2 @ _as_matrix(w2).T
        r2 = torch.addcmul(shift[1], h2, scale[1]).clamp_(min=0)
        l3 = (l2 - 1) // 2 + 1
        col3 = _windows(r2.view(b, l2, -1), l3)
        h3 = col3 @ _as_matrix(w3).T
        r3 = torch.addcmul(shift[2], h3, scale[2]).clamp_(min=0)
        ctx.save_for_backward(win, h1, pair, p, col2, h2, r2, col3, h3, r3, w2, w3, *scale, *means, *inv)
        ctx.sizes = (b, l1, l2, l3)
        return r3.view(b, l3, -1).mean(1)

    @staticmethod
    def backward(ctx, grad):
        win, h1, pair, p, col2, h2, r2, col3, h3, r3, w2, w3, *rest = ctx.saved_tensors
        scale, means, inv = rest[0:3], rest[3:6], rest[6:9]
        b, l1, l2, l3 = ctx.sizes
        relu = torch.ops.aten.threshold_backward
        g = relu((grad / l3)[:, None, :].expand(b, l3, -1), r3.view(b, l3, -1), 0.0).view(b * l3, -1)
        d3 = _normalised(g, h3, scale[2], means[2], inv[2])
        g = g * scale[2]
        dw3 = (g.T @ col3).view(w3.shape[0], 3, -1).permute(0, 2, 1)
        g = relu(_unwindows(g @ _as_matrix(w3), b, l3, l2).reshape(b * l2, -1), r2, 0.0)
        d2 = _normalised(g, h2, scale[1], means[1], inv[1])
        g = g * scale[1]
        dw2 = (g.T @ col2).view(w2.shape[0], 3, -1).permute(0, 2, 1)
        g = relu(_unwindows(g @ _as_matrix(w2), b, l2, l1 // 2), p, 0.0)  # (B, L1 / 2, C1)
        out = torch.empty(b, l1 // 2, 2, g.shape[-1])
        first = relu(g, pair, 0.0)
        out[:, :, 0] = first
        torch.sub(g, first, out=out[:, :, 1])
        g = out.view(b * l1, -1)
        d1 = _normalised(g, h1, scale[0], means[0], inv[0])
        dw1 = ((g * scale[0]).T @ win)[:, None, :]
        return None, dw1, *d1, dw2, *d2, dw3, *d3, None, None


def _normalised(grad: torch.Tensor, h: torch.Tensor, scale, mean, inv) -> tuple[torch.Tensor, torch.Tensor]:
    """The gradients of a frozen normalisation's weight and bias: sum of grad * (h - mean) * inv
    and sum of grad over the rows."""
    return ((h - mean) * grad).sum(0) * inv, grad.sum(0)
