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
    rows = padded.shape[0]
    n_templates, width = templates.shape
    for first in range(0, rows, ROWS):  # a block of rows stays in the cache while every template passes
        for j in range(n_templates):
            start = offset[j]
            t = templates[j]
            for b in range(first, min(first + ROWS, rows)):
                r = padded[b, start : start + width]
                acc = t[0] * 0  # in the templates' precision
                for n in range(width):
                    acc += abs(r[n]) - abs(r[n] - t[n])
                out[b, j] = acc


@numba.njit(cache=True, fastmath=FASTMATH)
def laplace_gain_grad(
    padded: np.ndarray, templates: np.ndarray, offset: np.ndarray, grad: np.ndarray, out: np.ndarray
) -> None:
    """out[j, n] = sum_b grad[b, j] sign(r_b,o_j+n - t_j,n): the templates' gradient given
    *grad* (B, J), the gradient of the scores g."""
    rows = padded.shape[0]
    n_templates, width = templates.shape
    for j in range(n_templates):
        start = offset[j]
        t = templates[j]
        o = out[j]
        o[:] = 0
        for b in range(rows):
            g = grad[b, j]
            r = padded[b, start : start + width]
            for n in range(width):
                o[n] += g * np.sign(r[n] - t[n])


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
        for i in range(n):
            k = bits[i]
            if k & np.uint32(0x7FFFFFFF) > np.uint32(0x7F800000):  # NaN: after everything
                keys[i] = np.uint32(0xFFFFFFFF)
            elif k & sign:  # negative: larger magnitude, smaller key
                keys[i] = ~k
            else:
                keys[i] = k | sign
        counts[:] = 0
        for i in range(n):
            counts[keys[i] >> shift] += 1
        below, top = 0, 0
        while below + counts[top] <= middle:
            below += counts[top]
            top += 1
        size = 0
        for i in range(n):
            if keys[i] >> shift == top:
                bucket[size] = keys[i]
                size += 1
        k = np.sort(bucket[:size])[middle - below]
        k = k ^ sign if k & sign else ~k
        out[b : b + 1].view(np.uint32)[0] = k
