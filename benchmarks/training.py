"""Training throughput of the default networks against a plain PyTorch loop and the machine's
limit, measured side by side in one run.

    python benchmarks/training.py [--rounds N] [--steps S] [--threads T] [--clock wall|cpu]
                                  [--device cpu|cuda] [--networks shapes,fast] [--compile MODES]

For each default network (`shapes`: scenarios/quick.toml, expB.toml, transfer_benchmark.toml, at 2
classes and, as `shapes/5`, at quick.toml's 5; `fast`: scenarios/phm09_chip.toml, 2048 points) at its
scenario's batch (40) with its optimiser
(Adam, the priming and the baselines) and loss (cross-entropy), and for `fast` in the joint step
of the calibrated methods (`fast+coral`, `fast+mmd`: a source and a target batch embedded
together, SGD, cross-entropy plus the CORAL or the MMD loss; phm09_chip's coral, mmd and dann units
took 2,650 of its units' 2,737 s at 5e2310c, source_only 72), three figures, alternated round by round so that
all see the same machine load, the median of the rounds printed (a joint step's samples are its
source and target rows):

* gearlab: samples per second of `gearlab.learn.training.fit_supervised` (one epoch of S
  batches a round, its own batching, clipping and loss bookkeeping);
* plain: the same network, batch, optimiser and loss in the plainest loop (tensors made once,
  a random order, zero_grad / forward / backward / step);
* limit: the network's forward + backward FLOPs per sample divided by the peaks measured in the
  same round: a matrix product (n x n) and a friendly conv1d (64 -> 64 channels), at T threads.
  Counted: convolutions and dense layers (2 FLOPs a multiply-add forward; backward the weights'
  gradient, and the input's where the input needs one), against the conv1d and the matmul peak;
  `shapes`' template distances |r_n - t_jn| (a subtraction, an absolute value and a sum forward,
  a sign, a product and a sum for the templates' gradient: 6 FLOPs a sample and template
  element) against the matmul peak (a CPU issues those as many vector operations per cycle as
  fused multiply-adds). Normalisation, activations, pooling and the optimiser are not counted,
  so the limit is optimistic: a ratio gearlab / limit of 1 cannot be reached;
* roof: the roofline of the same network, each layer (every module without children:
  normalisations, activations and pooling too) at the slower of its FLOPs at their peak and its
  bytes at a copy's bandwidth measured in the same round: the maps into and out of the layer
  forward, the gradients of both and its saved input backward (the input's gradient only where
  it needs one), its weights read twice and their gradient written once a step (divided among
  the step's samples), 4 bytes a value; a view moves nothing. `roof/s` takes the bandwidth of
  4 MiB buffers (beyond a core's L2, within the L3: a step's maps at batch 40-80 are 0.3-0.7 MB
  each, 3-6 MB saved for the backward), `dram/s` that of 64 MiB ones (every map from memory).

Where the distance to the limit lies: gearlab is timed at batch 2 as well (`SMALL`, the same
steps), and a step's time taken as a + b * batch through the two: `step ms` is a, the cost of a
step whatever its batch (operator dispatch, the autograd engine, the optimiser, Python), `GF/s`
the counted FLOPs per sample over b, the speed of the work that grows with the batch.

Below the table, each row's distance to the roof split in two: a step's time as fixed + batch x
per sample (the same two timings), against batch x the roof's per sample; `with the fixed cost
alone` is the ratio gearlab / roof were the per-sample part at the roof (the fixed cost the only
loss), `with the cost per sample alone` the other way round. One thread, this machine (AMD EPYC
family 26, AVX-512; 2 cores shared with other work, load 8-11, CPU clock, 6 runs, min-max): conv1d
150-180 GFLOP/s (oneDNN), matmul 89-97 (MKL and numpy's OpenBLAS alike run their AVX2 kernels on this
CPU: half the rate), copies 27-34 GB/s (memory) and 88-105 (cache). `fast` moves 292 KB a sample, its
roof 74-99 k samples/s (FLOP limit 91-126 k, dram 50-71 k); gearlab/roof 0.107-0.129 (median 0.113)
for `fast`, 0.118-0.169 (0.141) fast+coral, 0.138-0.155 (0.145) fast+mmd, 0.085-0.116 (0.106)
`shapes` (77 KB: its roof is its FLOPs). The fixed cost alone holds them to 0.18-0.22 (fast),
0.26-0.34 (joint), 0.20-0.36 (shapes): 1.5-2.7 ms a step, ~770 operator calls in `fast`'s step at
batch 40 and ~880 in a joint one, each ~1-2 us of dispatch whatever its size; the cost per sample
alone to 0.17-0.27 (43-65 us a sample against 10-13 at the roof: the products at MKL's AVX2 rate,
the normalisations' and pair maxima's passes over maps in the caches), so no batch reaches 0.33.
Within 3x of the roof needs both, the fixed cost and the cost per sample, cut by 1.5-2x.

Measured against these steps on one thread and not adopted (no gain beyond the load's noise, or
a loss): 3 or 8 units' `fast` as one network of grouped convolutions (16.4-16.9 against
17.1-19.2 ms for 3 steps, 42.6-44.8 against 42.5-47.0 for 8) or torch.func.vmap over stacked
weights (21-22 against 16-18 ms for 3); `fast` channels-last with its convolutions as
products of windows (3.76 against 3.43 ms for the layers); its stride-2 convolutions as batched
products (1.41 against 1.87 ms at batch 2, 4.77 against 4.30 at 40); oneDNN off (5.77 against
4.95 ms); batch normalisation or the `shapes` mixture by hand-written gradients. For the joint
step's batch of 80 (CPU time, load ~10): the stride-2 convolutions as one product of channels-last
windows 1.10 and 1.59 against 1.19 and 1.79 ms forward + backward (0.3 ms of a 10 ms step, gradients
apart by rounding), as broadcast products, conv2d or a 1 x 1 convolution of windows slower; their
backward's input gradient by conv_transpose1d or weight gradient by a product of windows 0.35-0.48
against 0.36-0.53 ms (oneDNN's own). Of a 10.8 ms `fast+coral` step in a run (fit_adaptation's, with
draws): embedding 3.2, backward 4.8, the epoch's validation 0.9 a step, the rest under 0.4 each.
Also not adopted (CPU time, load 4-10): `fast`'s first layer as one product of its 16-sample blocks
and a sum of 4 shifted slices (no 4-fold copy of windows; K = 16 products) 7.2-8.0 against 2.5-2.9 ms
forward + backward at batch 80; the validation set made tensors once and passed in inference mode
1.72 against 1.89 ms an epoch, with a joint step's rows gathered straight into one batch (no cat)
and its labels by index_select: a phm09-shaped unit's CPU unchanged within noise (3 pairs, +-5 %).

Adopted: `fast` with frozen normalisation (every joint step, every evaluation) as one autograd
function of window products (gearlab/learn/fast_frozen.py): fast+coral 10.4-10.8 -> 9.2-9.4 ms a
step, 0.13-0.14 -> 0.16-0.17 of the limit (side by side, load ~9, results apart by rounding). The
same function for normalisation in training mode (primings, supervised baselines): fast 4.0-4.4 ->
3.3-3.7 ms a step, 0.076-0.081 -> 0.098-0.111 of the limit (CPU time, side by side, load ~11; its
statistics in two passes: torch's own kernel for channels-last rows took as long and sums them in
float32 one after the other, 2e-6 from float64's). MMD's pooled kernel (gearlab/learn/losses.py):
its loss forward + backward 0.97 -> 0.40 ms, an mmd epoch of a phm09-shaped training 25.2 -> 20.9 ms.

The products of that function by oneDNN's inner product (fast_frozen.product): MKL's matrix product
runs its AVX2 kernels on this AMD CPU (103-112 GFLOP/s at 512 x 512, one thread) and oneDNN its
AVX-512 ones (228-245); `fast`'s 8 products 593 -> 418 us at batch 40, 1,180 -> 775 at 80 (min of
7); a step, in one process alternated with MKL's (CPU time, load 2-4, 4 runs): fast 1.91-2.25 ->
1.79-2.14 ms, fast+coral 4.67 -> 4.29, fast+mmd 5.07 -> 4.95. oneDNN's call costs ~10 us whatever
its size (MKL's 2.5-7 for these products at batch 2), so products under 2^20 multiply-adds stay
MKL's (fast_frozen.INNER_MIN; a step at batch 2 1.09 ms with all 8 by oneDNN, 0.75). The limit's matrix-product peak is
the faster of the two since (`shapes`' templates are held against it: its gearlab/limit 0.15 -> 0.07
for the same speed; `fast`'s limit and roof are its convolutions' and keep their figures).

Where a joint step's time goes now (CPU time, 40+40 x 2048, load ~10): `fast` forward + backward as
the function 4.0 ms, of which its 8 matrix products 1.3 ms at 75-92 GFLOP/s (the matmul peak; the
limit's conv1d peak is 170); the rest of the function (window copies, normalisations, ReLU and pair
gradients, ~60 operator calls) ~2 ms; outside it ~0.8 ms (classifier, losses, clipping, optimiser,
rows). Not adopted: CORAL's gradient written out (one node: 0.26 -> 0.18 ms of a ~5 ms step), MMD's
(0.39 -> 0.31 ms), the first layer's windows copied into a reused buffer (4.04 vs 4.19 ms).

Also not adopted (CPU time of the function + classifier + cross-entropy backward, the variant
alternated with the shipped one in one process, 25 rounds, min, 4 runs, load 4-11): the convolutions by
oneDNN at its AVX-512 rate (conv2d of height 1 on channels-last maps, no window copies; input and weight
gradients by convolution_backward; the first layer's weight gradient a product of windows, oneDNN's 3x
slower) 1.94-3.39 against 1.72-2.85 ms at batch 40 (training), 2.68-4.24 against 2.85-4.13 at 80
(frozen): 0-20 % slower, and 600-1,500 page faults a step where glibc's allocator returns its memory;
only the first layer's forward by oneDNN (alone 98 against 184 us at 40) 4.1 against 2.4 ms a step;
the windows' input gradient as two products and one shifted sum (no scatter; gradients bit for bit
equal) 2.84-3.32 against 3.04-3.57 ms at 40, 4.01-5.29 against 3.91-4.93 at 80: within the noise;
glibc's allocator told to keep its memory (mallopt): a training faults 0.1-3 times a step (0-0.06
ms of system time) without it. The first layer as a product of its windows without copying them
(an as_strided view of the padded signals, rows 16 values apart): BLAS needs a row stride of at
least the row's 64 values, so torch copies it all the same.

Adopted: the optimiser's parameters as views of one flat vector (gearlab.learn.training._Flat): the
clipping's norm and fused Adam / SGD once on it, where for `fast`'s 13 parameters torch's foreach
kernels issued ~145 calls within (13 norms and their stack, 13 step-count copies and reads); `shapes`' 2
keep the per-parameter path. In-process A/B (CPU time, load 8-10): fast 1.71 -> 1.49 ms a step at batch
2, 3.78 -> 3.49 at 40, fast+coral 5.41 -> 5.38. This benchmark alternated with 81c1d4a's (3 pairs,
--rounds 15 --clock cpu, load 6.6-13.5): gearlab/roof fast 0.104-0.112 -> 0.114-0.120, fast+coral
0.145-0.151 -> 0.150-0.154, fast+mmd 0.136-0.147 -> 0.143-0.152, shapes 0.049-0.052 -> 0.052-0.053 (its
path unchanged); `fast`'s fixed cost 1.53-1.79 -> 1.22-1.69 ms, gearlab/plain 1.08-1.10 -> 1.12-1.18.
What is left of it: ~250 operator calls a step from Python at ~2-3 us each (at batch 2: the
normalisations' 93 forward and backward, the window gradients' scatter 34, the function's other ~65, the
classifier's autograd nodes and parameters' 30); and its cost per sample alone (52 against 10 us at the
roof, 32 against 9.2 at load 1) holds `fast` to 0.19-0.29 of the roof: 0.33 needs both cut (at load 1,
the fixed cost halved and the cost per sample cut 1.9x: 0.43 ms + 40 x 17 us = 40 x 9.2 us / 0.33). Not
adopted: the gradients left in a flat vector by autograd (each parameter's grad a view of it, one zero_
a step; autograd then adds into it, 13 adds, and a parameter without a gradient would take a step): the
one copy they replace takes 5 us; the function's running statistics by three foreach calls for all three
normalisations, its rows less their mean kept for the backward and the window gradients' scatter as pair
copies (fewer operator calls; gradients and statistics bit for bit): fast 1.46 against 1.46 ms a step at
batch 2, 3.45 against 3.40 at 40, fast+coral 5.11 against 5.20 (in-process A/B, CPU time, load ~10), no
gain.

`shapes` (gearlab/roof 0.05-0.07): its roof holds 3 FLOPs a sample and template element (|r - t|
summed) against the matrix product's peak, which counts a fused multiply-add as 2 FLOPs; its loops
issue a vector operation or more per FLOP, so half that roof at most is reachable. A step at batch 40
(CPU time, load ~10, min of 7): the template loops 0.68 ms (forward 0.40 at 39 GFLOP/s counted, backward
0.28 at 57), each revolution's noise scale (the median of |r|: no gradient, not counted) 0.40, the
mixture's logsumexp and the cross-entropy 0.37, the rest ~1 ms (the autograd engine, the templates'
scaling by SHAPE_STEP over their 131 k weights forward and back, the circular padding, Adam 0.06).
The noise scale, a function of the revolution alone, is now computed once a training for the rows
it trains on (Network.row_state; rows fresh noise changes at each step excepted): 0.053-0.056 ->
0.057-0.060 of the roof side by side (3 pairs, --rounds 5, CPU clock, load ~7), the same numbers.
At quick.toml's 5 classes (`shapes/5`: 1,024 templates) the mixture's logsumexp over (40, 1,025, 5), a
strided reduction of which 4 in 5 terms are non-members' -inf, took ~3.0 ms of a 12 ms step forward +
backward; each class's sum over its own members (a per-class maximum by scatter_reduce, exp, index_add;
networks.ShapeMixture) ~0.6 ms: shapes/5 12.1-12.5 -> 8.8-10.1 ms a step, gearlab/roof 0.057-0.061 ->
0.077-0.083 (3 pairs with 4f0f8ab, --rounds 5, CPU clock, load ~4.5), logits apart by float rounding
(quick.toml's accuracies all equal, its training losses apart by < 5e-5). The templates' scaling by
SHAPE_STEP done in the loops, each template as it is used (kernels.laplace_gain_scaled: no scaled copy
of the bank forward, none of its gradient back; bit for bit the same numbers): shapes/5 8.76-9.14 ->
8.57-8.68 ms a step (fixed cost 2.13-2.22 -> 1.80-1.84), shapes 3.21-3.34 -> 3.12-3.14 (3 pairs, CPU
clock, load ~4.2). The circular padding's copy (20 us) is left. Not adopted: the loops' sum
of |r| taken once per row (prefix sums) instead of once per template, 0.90x (367 against 406 us).

A compiled step (`--compile MODES`: the plain loop with the network's modules compiled by
torch.compile in each mode, in the same alternated rounds; `compile s` is the first epoch's wall
clock: the first compilation in the process includes dynamo's and inductor's imports, 4.5 s, and
later ones reuse the kernels it left in inductor's cache). Not adopted: CPU clock, load 6-9, 7
rounds, 2 runs, cold caches: compiled/gearlab `fast` 0.59-0.73, `shapes` 0.65-0.79, default and
max-autotune-no-cudagraphs alike, so never repaid; 12-86 s to compile. The modules, since gearlab's
forward breaks dynamo's graph at `fast`'s autograd function (its backward writes into strided
views): compiled as it is, only the classifier is (3.44 against 3.21 ms a step). That function's
forward and backward written again as pure tensor functions and compiled by inductor (the pointwise
passes fused, the products left to MKL; gradients 1e-6 of their largest from the shipped ones), 3
runs (2 default, 1 max-autotune-no-cudagraphs): 2.75-3.00 against 2.92-3.18 ms a step (6 %), 38-61 s to
compile cold, 7 s warm, again for each batch shape a worker meets (full and last batches, the joint
steps' 80 rows, evaluation's 256): 0.2 ms a step against 7-38 s a shape, for a second copy of the
function to keep equal to the first and a C++ compiler in every install. torch.jit.trace + freeze of
`fast`'s evaluation (batch normalisation folded into the convolutions): 3.76 against the modules'
4.91 ms a batch of 256 (the shipped function's as long), after 3.1 s to trace and freeze, again for
each epoch's weights (torch.compile of it 3.45 ms, 63 s).
On an NVIDIA H200 (torch 2.11, 5 rounds, 4 runs, the compiled loops in one): gearlab `fast` 3.3-4.0
ms a step, fast+coral 6.1, fast+mmd 5.6, nearly all of it fixed cost (gearlab/plain 0.84-1.05);
`shapes` 2.29 ms (gearlab/plain 0.93), 17.5-21.1 before its templates' windows were gathered in one
pass (networks._laplace_windows; a loop over their offsets before); compiled (default,
max-autotune-no-cudagraphs, reduce-overhead) `fast` 0.83-0.88 of gearlab, `shapes` 0.67-1.07 (of the
looping path). There scenarios/quick.toml takes 32.0 s on CUDA (53.0 with the loop) against 21.4 s
on the machine's CPU, every figure of its summary.json equal to the CPU's (and this one's).

Units of a run train one torch thread each (gearlab.parts.training.train_unit), one per core:
samples/s per core is the 1-thread figure (T = 1, the default); with T threads it is divided by T.
On a machine other work shares, `--clock cpu` times this process's CPU seconds instead of the
wall clock: the figures then hold for a free core. About 40 s with the defaults.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import time
from collections.abc import Callable

import numpy as np
import torch
from torch import nn

from gearlab.learn import fast_frozen
from gearlab.learn.networks import ShapeLikelihood, build_network, matched_start
from gearlab.learn.training import fit_adaptation, fit_supervised
from gearlab.registry import METHODS, get_registry

# row name, network, samples per revolution, batch, the adapter of a joint step (None: supervised),
# where it is the default
CASES = (
    ("shapes", "shapes", 4096, 40, None, "quick, expB, transfer_benchmark"),
    ("shapes/5", "shapes", 4096, 40, None, "quick's 5 classes: 1,024 templates"),
    ("fast", "fast", 2048, 40, None, "phm09_chip"),
    ("fast+coral", "fast", 2048, 40, "coral", "phm09_chip's coral, dann"),
    ("fast+mmd", "fast", 2048, 40, "mmd", "phm09_chip's mmd"),
)
CLASSES = {"shapes/5": 5}  # a row's classes where not 2 (the mixture's cost grows with them)
CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}  # cpu: this process's CPU seconds
clock = CLOCKS["wall"]
JOINT_LR = 0.003  # fit_adaptation's SGD learning rate (Table 5.3)
SMALL = 2  # the second batch of gearlab's timing: a step's fixed cost and its per-sample speed
MATMUL = 512  # n of the n x n matrix product: large enough to be compute-bound
CONV = (8, 64, 64, 5, 1024)  # batch, channels in and out, kernel, length of the friendly conv1d
# bytes of each buffer of the bandwidths' copies: 64 MiB, beyond the caches (memory: twice the
# L3 of a 32 MiB one), and 4 MiB, beyond a core's L2 and within the L3, as a step's maps are (cache)
STREAM, CACHE = 1 << 26, 1 << 22
COPIES = 16  # copies of CACHE bytes timed at once (one takes ~0.1 ms)


def synchronize(device: torch.device) -> None:
    if device.type == "cuda":
        torch.cuda.synchronize()


def flops_per_sample(net: nn.Module, length: int, device: torch.device) -> dict[str, float]:
    """Forward + backward FLOPs of one sample (see the module's docstring), by the peak they are
    held against: ``{"conv": ..., "matmul": ...}``."""
    counts = {"conv": 0.0, "matmul": 0.0}
    for kind, flops, _ in layer_costs(net, length, device, batch=2):
        if kind:
            counts[kind] += flops
    return counts


def layer_costs(net: nn.Module, length: int, device: torch.device, batch: int) -> list[tuple[str, float, float]]:
    """Per layer (module without children) of one sample's forward + backward at *batch*: the peak
    its FLOPs are held against ("conv", "matmul", or "" for none counted), its FLOPs and its bytes
    (see the module's docstring: the maps in and out of it forward, the gradients of both and its
    saved input backward, the weights and their gradient once a step; a view, 0)."""
    costs: list[tuple[str, float, float]] = []
    hooks = []

    def hook(module, inputs, output):
        x = inputs[0]
        kind, flops = "", 0.0
        if isinstance(module, (nn.Conv1d, nn.Linear)):
            kind = "conv" if isinstance(module, nn.Conv1d) else "matmul"
            macs = output.numel() // len(output) * (module.weight[0].numel())
            # forward, the weights' gradient, and the input's when it needs one
            flops = 2 * macs * (3 if x.requires_grad else 2)
        elif isinstance(module, ShapeLikelihood):
            kind, flops = "matmul", 6 * module.weight.numel()
        if output.untyped_storage().data_ptr() == x.untyped_storage().data_ptr():
            costs.append((kind, flops, 0.0))  # a view: nothing moves
            return
        maps = 2 * (x.numel() + output.numel()) / len(x) + (x.numel() / len(x) if x.requires_grad else 0)
        weights = 3 * sum(p.numel() for p in module.parameters(recurse=False)) / batch
        costs.append((kind, flops, 4.0 * (maps + weights)))

    for module in net.modules():
        if not any(True for _ in module.children()):
            hooks.append(module.register_forward_hook(hook))
    # through the modules (Network.embed may run `fast` as one function, which no hook sees); two
    # samples: batch normalisation needs them
    net.train()
    net.classifier(net.features(torch.randn(2, length, device=device)))
    for h in hooks:
        h.remove()
    return costs


def bandwidth(device: torch.device, size: int) -> float:
    """Bytes per second of copies between two buffers of *size* bytes, read and written (STREAM's
    copy), the best of three times `COPIES`."""
    if size not in _buffers or _buffers[size][0].device != device:
        _buffers[size] = torch.ones(2, size // 4, device=device).unbind(0)
    src, dst = _buffers[size]
    times = []
    for _ in range(3):
        synchronize(device)
        t = clock()
        for _ in range(max(1, COPIES * CACHE // size)):
            dst.copy_(src)
        synchronize(device)
        times.append((clock() - t) / max(1, COPIES * CACHE // size))
    return 2 * size / min(times)


_buffers: dict[int, tuple[torch.Tensor, torch.Tensor]] = {}


def roofline(costs: list[tuple[str, float, float]], peak: dict[str, float], bw: float) -> float:
    """Seconds of one sample at the roofline: each layer at the slower of its FLOPs at its peak and
    its bytes at the memory bandwidth *bw*."""
    return sum(max(flops / peak[kind] if kind else 0.0, moved / bw) for kind, flops, moved in costs)


def peaks(device: torch.device) -> dict[str, float]:
    """FLOP/s of an n x n matrix product (torch's, or on a CPU oneDNN's inner product where faster) and
    of a friendly conv1d, the best of three each."""
    a, b = torch.randn(MATMUL, MATMUL, device=device), torch.randn(MATMUL, MATMUL, device=device)
    n, c_in, c_out, k, length = CONV
    x, w = torch.randn(n, c_in, length, device=device), torch.randn(c_out, c_in, k, device=device)
    conv_flops = 2 * n * c_out * (length - k + 1) * c_in * k

    def best(f: Callable[[], object], flops: float) -> float:
        f()
        times = []
        for _ in range(3):
            synchronize(device)
            t = clock()
            f()
            synchronize(device)
            times.append(clock() - t)
        return flops / min(times)

    products = [lambda: a @ b]
    if device.type == "cpu":  # and oneDNN's, which gearlab's `fast` uses (fast_frozen.product)
        products.append(lambda: fast_frozen.product(a, b))
    return {
        "matmul": max(best(f, 2 * MATMUL**3) for f in products),
        "conv": best(lambda: torch.nn.functional.conv1d(x, w), conv_flops),
    }


def network(name: str, length: int, device: torch.device, classes: int = 2) -> nn.Module:
    """*name* for *classes* classes; `shapes` started on decaying bursts at random angles (as
    Experiment B's faults), 256 a fault class, so that its templates sit in as many windows as in a run."""
    net = build_network(name, classes, length=length, seed=0)
    if name == "shapes":
        rng = np.random.default_rng(0)
        faults = np.zeros((256 * (classes - 1), length))
        for row in faults:
            at = rng.integers(length)
            row[(at + np.arange(200)) % length] = rng.normal(size=200) * np.exp(-np.arange(200) / 40.0)
        matched_start(net, faults, seed=0, classes=1 + np.arange(len(faults)) // 256, law="laplace")
    return net.to(device)


def gearlab_run(s: dict, rows: int, batch: int, epochs: int, device: torch.device) -> float:
    """Seconds of gearlab's training on the first *rows* of the case *s* for *epochs* (one call, as a
    priming or an adaptation is): supervised, or joint with its adapter (the source's first batch
    its validation set, the target unlabelled)."""
    X, y, rng = s["X"][:rows], s["y"][:rows], np.random.default_rng(0)
    synchronize(device)
    t = clock()
    if s["adapter"] is None:
        fit_supervised(s["gearlab"], X, y, rng=rng, device=device, epochs=epochs, batch=batch, val=None, patience=None)
    else:
        fit_adaptation(
            s["gearlab"], s["adapter"], s["modules"], (X, y), (X[:batch], y[:batch]), (s["X_target"][:rows], None),
            rng=rng, device=device, batch=batch, min_epochs=epochs, max_epochs=epochs, params=s["params"],
        )  # fmt: skip
    synchronize(device)
    return clock() - t


def plain_run(s: dict, batch: int, epochs: int, loop: tuple | None = None) -> float:
    """Seconds of the plainest loop over the case *s* for *epochs* (tensors already on the device):
    a joint step embeds a source and a target batch together and adds the adapter's loss at full
    weight. *loop*: (network, optimiser, forward) of a supervised case's compiled loop, where
    forward stands for the network's."""
    net, opt, forward = loop or (s["plain"], s["opt"], s["plain"])
    X, y, X_target = s["Xt"], s["yt"], s["Xt_target"]
    loss_fn = nn.CrossEntropyLoss()
    net.train()
    synchronize(X.device)
    t = clock()
    for _ in range(epochs):
        order = torch.randperm(len(X), device=X.device)
        for i in range(0, len(X), batch):
            idx = order[i : i + batch]
            opt.zero_grad()
            if s["adapter"] is None:
                loss = loss_fn(forward(X[idx]), y[idx])
            else:
                z = net.embed(torch.cat([X[idx], X_target[idx]]))
                z_s, z_t = z[: len(idx)], z[len(idx) :]
                loss = loss_fn(net.classifier(z_s), y[idx]) + s["adapter"].domain_loss(
                    z_s, z_t, s["plain_modules"], 1.0, s["params"]
                )
            loss.backward()
            opt.step()
    synchronize(X.device)
    return clock() - t


def compiled_loop(name: str, length: int, mode: str, device: torch.device) -> tuple:
    """(network, Adam, forward) of *name* with its modules compiled by torch.compile in *mode*, one
    shape (the loop's batches are all full). The modules, not gearlab's forward: on the CPU that runs
    `fast` as one autograd function dynamo cannot trace (a graph break: its backward writes into
    strided views), so only the classifier would be compiled."""
    net = network(name, length, device)
    model = nn.Sequential(net.features, net.classifier)
    return net, torch.optim.Adam(net.parameters(), lr=1e-3), torch.compile(model, mode=mode, dynamic=False)


def compile_first(s: dict, batch: int, mode: str) -> float | str:
    """Wall seconds of the compiled loop's first epoch in *mode* (the compilation: inductor runs its
    C++ compiler in other processes, which a CPU clock would not see), or the first line of why it
    failed (no C++ compiler, say): the benchmark goes on without that loop."""
    t = time.perf_counter()
    try:
        plain_run(s, batch, 1, s["compiled"][mode])
    except Exception as error:  # torch.compile compiles on the first call, and fails there
        del s["compiled"][mode]
        return f"failed: {type(error).__name__}: {str(error).strip().splitlines()[0] if str(error).strip() else ''}"
    return time.perf_counter() - t


def repaid_after(compile_s: float, step: float, compiled_step: float) -> float:
    """Steps after which a compilation of *compile_s* seconds is repaid by a step of *compiled_step*
    seconds against *step*; inf where the compiled step is no faster."""
    return compile_s / (step - compiled_step) if compiled_step < step else math.inf


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="alternated rounds (median); 15 for a steadier figure")
    parser.add_argument("--steps", type=int, default=20, help="training steps per figure and round")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (1: as each unit of a run trains)")
    parser.add_argument("--device", default="cpu", choices=("cpu", "cuda"))
    parser.add_argument(
        "--clock",
        default="wall",
        choices=tuple(CLOCKS),
        help="wall time, or this process's CPU time (steadier where other work shares the cores)",
    )
    parser.add_argument(
        "--networks",
        default=",".join(c[0] for c in CASES),
        help="comma-separated, of: " + ", ".join(c[0] for c in CASES),
    )
    parser.add_argument(
        "--compile",
        default="",
        help="comma-separated torch.compile modes (default, max-autotune-no-cudagraphs, reduce-overhead): "
        "the supervised networks' plain loop compiled in each, beside the others",
    )
    args = parser.parse_args()
    global clock
    clock = CLOCKS[args.clock]
    torch.set_num_threads(args.threads)
    device = torch.device(args.device)
    cases = [c for c in CASES if c[0] in args.networks.split(",")]
    rng = np.random.default_rng(1)
    setups = {}
    # an epoch of up to 5 batches, repeated: a call's set-up is spread over its S steps as a
    # priming's over its epochs, without copying S batches of data
    per_epoch = min(args.steps, 5)
    epochs = -(-args.steps // per_epoch)
    for row, name, length, batch, adapter, _ in cases:
        X, X_target = rng.standard_normal((2, per_epoch * batch, length)).astype(np.float32)
        classes = CLASSES.get(row, 2)
        y = rng.integers(0, classes, len(X))
        gearlab_net, plain_net = (network(name, length, device, classes) for _ in range(2))
        s = setups[row] = dict(X=X, y=y, X_target=X_target, gearlab=gearlab_net, plain=plain_net, adapter=None)
        s.update(Xt=torch.as_tensor(X, device=device), yt=torch.as_tensor(y, device=device))
        s.update(Xt_target=torch.as_tensor(X_target, device=device))
        s["opt"] = torch.optim.Adam(plain_net.parameters(), lr=1e-3)
        if adapter is not None:  # as gearlab's joint training: its SGD at its learning rate
            plugin = get_registry().get(METHODS, adapter, "benchmark")
            s.update(adapter=plugin, params=plugin.resolve({}, "benchmark"))
            s.update(modules=plugin.extra_modules(gearlab_net.latent_dim, s["params"]).to(device))
            s["plain_modules"] = plugin.extra_modules(plain_net.latent_dim, s["params"]).to(device)
            weights = list(plain_net.parameters()) + list(s["plain_modules"].parameters())
            s["opt"] = torch.optim.SGD(weights, lr=JOINT_LR)
        s["rows"] = batch * (1 if adapter is None else 2)  # through the network in a step
        s["costs"] = layer_costs(network(name, length, device, classes), length, device, s["rows"])
        s["flops"] = {k: sum(f for kind, f, _ in s["costs"] if kind == k) for k in ("conv", "matmul")}
        s["bytes"] = sum(moved for _, _, moved in s["costs"])
        s["times"] = {"gearlab": [], "plain": [], "limit": [], "roof": [], "dram": [], "small": []}
        modes = [m for m in args.compile.split(",") if m] if adapter is None else []
        s["compiled"] = {mode: compiled_loop(name, length, mode, device) for mode in modes}
        s["compile_s"] = {mode: compile_first(s, batch, mode) for mode in modes}
        s["times"].update({f"compiled {mode}": [] for mode in s["compiled"]})
    peak_rounds: dict[str, list[float]] = {"matmul": [], "conv": [], "memory": [], "cache": []}
    for _ in range(args.rounds):  # alternated: a load that comes and goes hits every figure alike
        for row, _, _, batch, _, _ in cases:
            s = setups[row]
            samples = epochs * per_epoch * s["rows"]
            s["times"]["gearlab"].append(gearlab_run(s, len(s["X"]), batch, epochs, device) / samples)
            # as many steps at batch SMALL
            small = gearlab_run(s, per_epoch * SMALL, SMALL, epochs, device)
            s["times"]["small"].append(small / (samples * SMALL // batch))
            s["times"]["plain"].append(plain_run(s, batch, epochs) / samples)
            for mode, loop in s["compiled"].items():
                s["times"][f"compiled {mode}"].append(plain_run(s, batch, epochs, loop) / samples)
            peak = peaks(device)
            bw = {"memory": bandwidth(device, STREAM), "cache": bandwidth(device, CACHE)}
            for kind, value in (*peak.items(), *bw.items()):
                peak_rounds[kind].append(value)
            s["times"]["limit"].append(sum(s["flops"][kind] / peak[kind] for kind in peak))
            s["times"]["roof"].append(roofline(s["costs"], peak, bw["cache"]))
            s["times"]["dram"].append(roofline(s["costs"], peak, bw["memory"]))
    matmul, conv, memory, cache = (statistics.median(peak_rounds[k]) for k in peak_rounds)
    load = f", load average {os.getloadavg()[0]:.1f}" if hasattr(os, "getloadavg") else ""
    print(
        f"training throughput on {args.device}, {args.threads} torch thread(s) of {os.cpu_count()} CPUs{load}; "
        f"{args.clock} clock, median of {args.rounds} alternated rounds of {args.steps} steps"
    )
    print(
        f"peaks at {args.threads} thread(s): matmul {matmul / 1e9:.1f} GFLOP/s, conv1d {conv / 1e9:.1f} GFLOP/s, "
        f"copy bandwidth {memory / 1e9:.1f} GB/s (memory), {cache / 1e9:.1f} GB/s ({CACHE >> 20} MiB buffers: cache)"
    )
    header = (
        f"{'network':10s} {'input':>14s} {'MFLOP/sa':>8s} {'KB/sa':>5s} {'gearlab/s':>9s} {'plain/s':>9s} "
        f"{'limit/s':>9s} {'roof/s':>9s} {'dram/s':>9s} {'gl/core':>8s} {'ms/step':>7s} {'step ms':>7s} {'GF/s':>5s} "
        f"{'gearlab/plain':>13s} {'gearlab/limit':>13s} {'gearlab/roof':>12s}"
    )
    print(header)
    for row, _, length, batch, adapter, where in cases:
        s = setups[row]
        rate = {k: 1.0 / statistics.median(v) for k, v in s["times"].items()}
        rows = s["rows"]
        fixed, per_sample, _ = distance(s, batch)
        flops = sum(s["flops"].values())
        shape = f"{batch} x {length}" if adapter is None else f"{batch}+{batch} x {length}"
        print(
            f"{row:10s} {shape:>14s} {flops / 1e6:8.2f} {s['bytes'] / 1e3:5.0f} {rate['gearlab']:9.0f} "
            f"{rate['plain']:9.0f} {rate['limit']:9.0f} {rate['roof']:9.0f} {rate['dram']:9.0f} "
            f"{rate['gearlab'] / args.threads:8.0f} "
            f"{1e3 * rows / rate['gearlab']:7.2f} {1e3 * fixed:7.2f} {flops / per_sample / 1e9:5.1f} "
            f"{rate['gearlab'] / rate['plain']:13.2f} {rate['gearlab'] / rate['limit']:13.3f} "
            f"{rate['gearlab'] / rate['roof']:12.3f}   ({where})"
        )
    print(
        "(samples/s; gl/core = gearlab's per thread; the limit counts convolutions, dense layers and templates only; "
        "roof / dram: each layer at the slower of its FLOPs and its KB at the cache's / memory's bandwidth)"
    )
    print(
        f"(step ms: a step's cost whatever its batch, GF/s: the counted FLOPs' speed in the rest, from gearlab at "
        f"batch {SMALL} and at the network's)"
    )
    _buffers.clear()  # the bandwidths' 136 MB
    print("where the distance to the roof lies (a step = its fixed cost + batch x its cost per sample):")
    for row, _, _, batch, _, _ in cases:
        s = setups[row]
        fixed, per_sample, roof = distance(s, batch)
        rows = s["rows"]
        print(
            f"  {row}: a step {1e3 * (fixed + rows * per_sample):.2f} ms = {1e3 * fixed:.2f} + {rows} x "
            f"{1e6 * per_sample:.1f} us, at the roof {rows} x {1e6 * roof:.1f} us; gearlab/roof with the fixed "
            f"cost alone {rows * roof / (fixed + rows * roof):.2f}, with the cost per sample alone "
            f"{roof / per_sample:.2f}"
        )
    compiled_table(setups, cases)


def compiled_table(setups: dict, cases: list) -> None:
    """The compiled loops (--compile) beside gearlab's step: compile seconds (wall, the first epoch),
    samples/s, and the steps that repay the compilation."""
    rows = [(row, mode) for row, *_ in cases for mode in setups[row]["compile_s"]]
    if not rows:
        return
    print(
        "torch.compile of the network's modules in the plain loop (compile s: its first epoch, wall clock; "
        "repaid after: the steps whose saving against gearlab's step pays the compilation):"
    )
    print(
        f"  {'network':10s} {'mode':28s} {'compile s':>9s} {'compiled/s':>10s} {'ms/step':>7s} "
        f"{'compiled/gearlab':>16s} {'compiled/plain':>14s} {'compiled/roof':>13s} {'repaid after':>12s}"
    )
    for row, mode in rows:
        s, batch = setups[row], next(c[3] for c in cases if c[0] == row)
        compile_s = s["compile_s"][mode]
        if isinstance(compile_s, str):
            print(f"  {row:10s} {mode:28s} {compile_s}")
            continue
        median = {k: statistics.median(v) for k, v in s["times"].items()}
        compiled = median[f"compiled {mode}"]
        repaid = repaid_after(compile_s, batch * median["gearlab"], batch * compiled)
        print(
            f"  {row:10s} {mode:28s} {compile_s:9.1f} {1 / compiled:10.0f} {1e3 * batch * compiled:7.2f} "
            f"{median['gearlab'] / compiled:16.2f} {median['plain'] / compiled:14.2f} "
            f"{median['roof'] / compiled:13.3f} "
            f"{'never' if math.isinf(repaid) else f'{repaid:.0f} steps':>12s}"
        )


def distance(s: dict, batch: int) -> tuple[float, float, float]:
    """Of the case *s* (medians of its rounds): a step's fixed seconds and seconds per sample
    (split), and a sample's seconds at the roof."""
    median = {k: statistics.median(v) for k, v in s["times"].items()}
    rows, small_rows = s["rows"], s["rows"] * SMALL // batch
    return (*split(rows * median["gearlab"], small_rows * median["small"], rows, small_rows), median["roof"])


def split(step: float, small_step: float, rows: int, small_rows: int) -> tuple[float, float]:
    """A step's seconds as a + b * rows through *step* (of *rows*) and *small_step* (of
    *small_rows*): (a, b), the fixed cost of a step and the seconds per sample."""
    per_sample = (step - small_step) / (rows - small_rows)
    return step - per_sample * rows, per_sample


if __name__ == "__main__":
    main()
