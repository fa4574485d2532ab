"""Compiled CPU loops of the `shapes` network's Laplace template scores (numba).

`ShapeLikelihood` scores J local templates t_j, each on its window of a revolution r (from
offset o_j, `width` samples), in Laplace noise by

    g_bj = sum_n |r_b,o_j+n| - |r_b,o_j+n - t_j,n|        (divided by the scale b afterwards)

and learns the templates from d g_bj / d t_j,n = sign(r_b,o_j+n - t_j,n). torch has no batched
form of it: a distance per window group (torch.cdist with p = 1), with the gathers and scatters
that assemble the groups and their gradients, made a training step of Experiment B's network
(256 templates of 512 samples, batch 40) about 30 ms on one thread, 20-70 times its arithmetic
(benchmarks/training.py). These two loops do the arithmetic only, vectorised by the compiler.
They run on the CPU, in the tensors' own precision (float32 in training), for revolutions that
need no gradient (a network's input); the module loads numba only when a network first uses them.
"""

from __future__ import annotations

import numba
import numpy as np

FASTMATH = {"reassoc", "contract", "arcp", "nsz"}  # as the simulator's loops (gearlab.dynamics.newmark)
ROWS = 16  # rows scored together: 16 whole float64 revolutions of 4096 samples fill half a 1 MiB cache


@numba.njit(cache=True, fastmath=FASTMATH)
def laplace_gain(padded: np.ndarray, templates: np.ndarray, offset: np.ndarray, out: np.ndarray) -> None:
    """out[b, j] = g_bj for revolutions *padded* (B, L + width: each row followed by its first
    `width` samples again, so a window that wraps round is contiguous), *templates* (J, width)."""
    laplace_gain_scaled(padded, templates, np.ones(1, templates.dtype), offset, out)


@numba.njit(cache=True, fastmath=FASTMATH)
def laplace_gain_scaled(
    padded: np.ndarray, templates: np.ndarray, scale: np.ndarray, offset: np.ndarray, out: np.ndarray
) -> None:
    """`laplace_gain` of the templates times *scale* (one value of the templates' precision: the
    products those of torch's ``templates * scale``, bit for bit), each template scaled as it is
    used: `ShapeLikelihood` stores its templates divided by SHAPE_STEP, and its step scaled the
    whole bank (131 k-524 k weights) forward and its gradient back, each pass a new array."""
    rows = padded.shape[0]
    n_templates, width = templates.shape
    s = scale[0]
    scaled = np.empty(width, templates.dtype)
    for first in range(0, rows, ROWS):  # a block of rows stays in the cache while every template passes
        last = min(first + ROWS, rows)
        for j in range(n_templates):
            start = offset[j]
            t = templates[j]
            if s != 1:
                for n in range(width):  # stored, then read: the product rounded as torch's, not fused
                    scaled[n] = t[n] * s
                t = scaled
            b = first
            while b + 4 <= last:  # four rows a pass: each template sample loaded once for four
                r0, r1 = padded[b, start : start + width], padded[b + 1, start : start + width]
                r2, r3 = padded[b + 2, start : start + width], padded[b + 3, start : start + width]
                a0 = a1 = a2 = a3 = t[0] * 0  # in the templates' precision
                for n in range(width):
                    tn = t[n]
                    a0 += abs(r0[n]) - abs(r0[n] - tn)
                    a1 += abs(r1[n]) - abs(r1[n] - tn)
                    a2 += abs(r2[n]) - abs(r2[n] - tn)
                    a3 += abs(r3[n]) - abs(r3[n] - tn)
                out[b, j], out[b + 1, j], out[b + 2, j], out[b + 3, j] = a0, a1, a2, a3
                b += 4
            for rest in range(b, last):
                r = padded[rest, start : start + width]
                acc = t[0] * 0
                for n in range(width):
                    acc += abs(r[n]) - abs(r[n] - t[n])
                out[rest, j] = acc


@numba.njit(cache=True, fastmath=FASTMATH)
def laplace_gain_grad(
    padded: np.ndarray, templates: np.ndarray, offset: np.ndarray, grad: np.ndarray, out: np.ndarray
) -> None:
    """out[j, n] = sum_b grad[b, j] sign(r_b,o_j+n - t_j,n): the templates' gradient given
    *grad* (B, J), the gradient of the scores g."""
    laplace_gain_grad_scaled(padded, templates, np.ones(1, templates.dtype), offset, grad, out)


@numba.njit(cache=True, fastmath=FASTMATH)
def laplace_gain_grad_scaled(
    padded: np.ndarray, templates: np.ndarray, scale: np.ndarray, offset: np.ndarray, grad: np.ndarray, out: np.ndarray
) -> None:
    """The gradient of `laplace_gain_scaled`'s scores with respect to the stored (unscaled)
    templates: `laplace_gain_grad` of the scaled templates, times *scale* (torch's order: the sum,
    then the product)."""
    rows = padded.shape[0]
    n_templates, width = templates.shape
    s = scale[0]
    scaled = np.empty(width, templates.dtype)
    for j in range(n_templates):
        start = offset[j]
        t = templates[j]
        if s != 1:
            for n in range(width):
                scaled[n] = t[n] * s
            t = scaled
        o = out[j]
        o[:] = 0
        b = 0
        while b + 4 <= rows:  # four rows a pass: the gradient row loaded and stored once for four
            g0, g1, g2, g3 = grad[b, j], grad[b + 1, j], grad[b + 2, j], grad[b + 3, j]
            r0, r1 = padded[b, start : start + width], padded[b + 1, start : start + width]
            r2, r3 = padded[b + 2, start : start + width], padded[b + 3, start : start + width]
            for n in range(width):
                tn = t[n]
                o[n] += (
                    g0 * np.sign(r0[n] - tn)
                    + g1 * np.sign(r1[n] - tn)
                    + g2 * np.sign(r2[n] - tn)
                    + g3 * np.sign(r3[n] - tn)
                )
            b += 4
        for rest in range(b, rows):
            g = grad[rest, j]
            r = padded[rest, start : start + width]
            for n in range(width):
                o[n] += g * np.sign(r[n] - t[n])
        if s != 1:
            for n in range(width):
                o[n] *= s


KEY_BITS = 12  # the first pass sorts float32 keys into 2**12 buckets by their top bits


@numba.njit(cache=True)
def lower_median32(x: np.ndarray, out: np.ndarray) -> None:
    """out[b] = the lower median of float32 row x[b] (the element np.partition puts in the
    middle; NaN counts as the largest, as there). A two-pass radix selection: each value's bits
    as an unsigned key in the order of the values, a count of the keys' top `KEY_BITS` bits finds
    the bucket that holds the median, and only that bucket (a few hundred of 4096) is sorted.
    numpy's introselect took 30-40 us a row of 4096, a sixth of a `shapes` training step."""
    n = x.shape[1]
    middle = (n - 1) // 2
    keys = np.empty(n, np.uint32)
    bucket = np.empty(n, np.uint32)
    counts = np.empty(1 << KEY_BITS, np.int64)
    sign, shift = np.uint32(0x80000000), 32 - KEY_BITS
    for b in range(x.shape[0]):
        bits = x[b].view(np.uint32)
        for i in range(n):  # without branches, so that the compiler vectorises the loop
            k = bits[i]
            flip = np.uint32(0) - (k >> np.uint32(31))  # negative: all bits flipped (larger magnitude, smaller key)
            nan = k & np.uint32(0x7FFFFFFF) > np.uint32(0x7F800000)  # NaN: after everything
            keys[i] = np.uint32(0xFFFFFFFF) if nan else k ^ (flip | sign)
        counts[:] = 0
        for i in range(n):
            counts[keys[i] >> shift] += 1
        below, top = 0, 0
        while below + counts[top] <= middle:
            below += counts[top]
            top += 1
        size = 0
        for i in range(n):  # every key written, kept where it lies in the median's bucket
            bucket[size] = keys[i]
            size += keys[i] >> shift == top
        k = np.sort(bucket[:size])[middle - below]
        k = k ^ sign if k & sign else ~k
        out[b : b + 1].view(np.uint32)[0] = k
