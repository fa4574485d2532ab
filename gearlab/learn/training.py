"""Training loops: supervised (the uncalibrated baselines, priming, fine-tuning) and joint
domain-adaptation training (the calibrated methods, thesis 5.2-5.4).

Nothing here ever sees a target *test* sample: the loops receive the training arrays
only, stop on source validation accuracy and on the domain discrepancy between the
training sets, and return the selected model. Evaluation is a separate function the
protocol calls afterwards (tests/test_protocol.py proves test labels cannot leak).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np
import torch
from torch import nn

from ..errors import GearlabInputError

RAMP_EPOCHS = 500  # Table 5.3: lambda rises by 0.05 every 25 epochs, reaching 1 after 500
MAX_GRAD_NORM = 100.0  # far above a stable step's gradient norm (3-30 on Experiment A); see _step
# Table 5.3's early stopping was set for validation sets of 10 % of 120 samples or more; below that
# size (_chance) a model no better than the majority class does not start the patience
SMALL_VALIDATION = 12


def pick_device(name: str = "auto") -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise GearlabInputError("device 'cuda' was asked for but no CUDA device is available; use auto or cpu")
    if name not in ("cpu", "cuda"):
        raise GearlabInputError(f"unknown device '{name}'; expected auto, cpu or cuda")
    return torch.device(name)


@dataclass
class History:
    """Per-epoch curves (Figure 5.7) and the epoch that was kept."""

    train_loss: list[float] = field(default_factory=list)
    val_acc: list[float] = field(default_factory=list)
    discrepancy: list[float] = field(default_factory=list)
    lam: list[float] = field(default_factory=list)
    best_epoch: int = -1
    stopped_epoch: int = -1

    def as_dict(self) -> dict:
        return {
            k: getattr(self, k) for k in ("train_loss", "val_acc", "discrepancy", "lam", "best_epoch", "stopped_epoch")
        }


def _tensor(x: np.ndarray, device) -> torch.Tensor:
    return torch.as_tensor(np.ascontiguousarray(x), dtype=torch.float32, device=device)


def _labels(y: np.ndarray, device) -> torch.Tensor:
    return torch.as_tensor(np.asarray(y), dtype=torch.long, device=device)


@torch.no_grad()
def predict(net: nn.Module, X: np.ndarray, device, batch: int = 256) -> np.ndarray:
    net.eval()
    out = [net(_tensor(X[i : i + batch], device)).argmax(1).cpu().numpy() for i in range(0, len(X), batch)]
    return np.concatenate(out) if out else np.empty(0, dtype=np.int64)


@torch.no_grad()
def embed(net: nn.Module, X: np.ndarray, device, batch: int = 256) -> torch.Tensor:
    net.eval()
    return torch.cat([net.embed(_tensor(X[i : i + batch], device)) for i in range(0, len(X), batch)])


def accuracy(net: nn.Module, X: np.ndarray, y: np.ndarray, device) -> float:
    return float((predict(net, X, device) == np.asarray(y)).mean()) if len(X) else float("nan")


def train_mode(net: nn.Module, freeze_norm: bool = False) -> None:
    """Training mode; with *freeze_norm*, batch-norm layers keep normalising with the statistics
    they were primed with. Adapting a primed network needs this: joint source + target batches
    would otherwise blend both domains into the running statistics that evaluation uses, and
    the source validation accuracy that decides when to stop would swing from batch to batch."""
    net.train()
    if freeze_norm:
        for layer in net.modules():
            if isinstance(layer, nn.modules.batchnorm._BatchNorm):
                layer.eval()


def _rows(X: torch.Tensor, index: torch.Tensor, draws: np.random.Generator | None) -> tuple[torch.Tensor, torch.Tensor]:
    """Training rows *index* of X and where they lie among `_flat(X)`'s rows: X (n, L), or
    (n, D, L) holding D noise draws of each sample, of which each row takes one at random. A noisy
    source drawn once is learned by heart, noise and all (a few hundred samples against 4096 values
    each); fresh draws leave only the signal to learn (the PHM 2009 corrected source:
    docs/real_data.md). index_select, not X[index]: the same rows in a fifth to a tenth of the time
    on a CPU (advanced indexing's general path)."""
    if X.ndim == 3:
        pick = torch.as_tensor(draws.integers(X.shape[1], size=len(index)), device=X.device)
        index = index * X.shape[1] + pick
    return _flat(X).index_select(0, index), index


def _flat(X: torch.Tensor) -> torch.Tensor:
    return X.flatten(0, 1) if X.ndim == 3 else X


def _row_state(net: nn.Module, X: torch.Tensor, augment: Callable | None) -> torch.Tensor | None:
    """The network's `row_state` of every row X can give (`_rows`), computed once, or None: a
    network without one, or rows that *augment* changes at every step."""
    state = getattr(net, "row_state", None)
    return None if state is None or augment is not None else state(_flat(X))


def _give(net: nn.Module, parts: list[tuple[torch.Tensor | None, torch.Tensor]]) -> None:
    """Tell *net* the `row_state` of the next batch, made of (state, flat index) *parts* in order
    (NaN for a part whose state is None: the network computes those)."""
    known = [state for state, _ in parts if state is not None]
    if not known:
        return
    given = [
        state.index_select(0, i) if state is not None else known[0].new_full((len(i),), math.nan) for state, i in parts
    ]
    net.give_rows(torch.cat(given) if len(given) > 1 else given[0])


def _draws(X: np.ndarray, rng: np.random.Generator) -> np.random.Generator | None:
    """The generator of the rows' draws, spawned from *rng* only for a source with draws (so the
    stream of every other training stays as it was)."""
    return np.random.default_rng(int(rng.integers(2**62))) if X.ndim == 3 else None


def _batches(n: int, batch: int, rng: np.random.Generator) -> Iterable[np.ndarray]:
    order = rng.permutation(n)
    for i in range(0, n, batch):
        yield order[i : i + batch]


def fit_supervised(
    net: nn.Module,
    X: np.ndarray,
    y: np.ndarray,
    *,
    rng: np.random.Generator,
    device: torch.device,
    epochs: int = 200,
    batch: int = 40,
    optimizer: str = "adam",
    lr: float = 1e-3,
    val: tuple[np.ndarray, np.ndarray] | None = None,
    patience: int | None = 20,
    parameters: Iterable[torch.nn.Parameter] | None = None,
    freeze_norm: bool = False,
    augment: Callable | None = None,
    on_epoch: Callable[[int, History], None] | None = None,
) -> History:
    """Cross-entropy training; with *val*, keep the epoch of best validation accuracy and stop
    after *patience* epochs without improvement (Table 5.3: 'validation accuracy maximum'); on a
    validation set of fewer than SMALL_VALIDATION samples not while the best is no better than its
    majority class (_chance), the latest such epoch kept.
    *X*: (n, L), or (n, D, L) with D noise draws of each sample (_rows). *freeze_norm*: see
    train_mode. *augment(batch, generator)*: applied to every training batch (fresh sensor
    noise, gearlab.learn.calibration), never to the validation set."""
    if batch > len(X):
        raise GearlabInputError(f"batch size {batch} is larger than the training set ({len(X)} samples)")
    net.to(device)
    params = list(parameters) if parameters is not None else list(net.parameters())
    opt = _optimizer(optimizer, params, lr)
    loss_fn = nn.CrossEntropyLoss()
    Xt, yt = _tensor(X, device), _labels(y, device)
    generator = _generator(rng) if augment else None  # drawn only then: the thesis path stays as it was
    draws = _draws(X, rng)
    state = _row_state(net, Xt, augment)
    history, best_state, best = History(), None, -math.inf
    chance = _chance(val)
    for epoch in range(epochs):
        train_mode(net, freeze_norm)
        total = _zero(device)
        for idx in _batches(len(X), batch, rng):
            index = torch.as_tensor(idx, device=device)
            xb, flat = _rows(Xt, index, draws)
            xb = augment(xb, generator) if augment else xb
            _give(net, [(state, flat)])
            opt.zero_grad()
            loss = loss_fn(net(xb), yt.index_select(0, index))
            _step(opt, params, loss)
            total.add_(loss.detach(), alpha=len(idx))  # in float64: the same sum as loss.double() * len(idx)
        history.train_loss.append(total.item() / len(X))
        if val is not None:
            acc = accuracy(net, *val, device)
            history.val_acc.append(acc)
            waiting = chance is not None and best <= chance
            if acc > best or (waiting and acc == best):
                best, best_state, history.best_epoch = acc, copy.deepcopy(net.state_dict()), epoch
            elif patience is not None and not waiting and epoch - history.best_epoch >= patience:
                history.stopped_epoch = epoch
                break
        if on_epoch:
            on_epoch(epoch, history)
    _release(opt)
    return _keep_best(net, history, best_state)


def _chance(val: tuple[np.ndarray, np.ndarray] | None) -> float | None:
    """The accuracy of calling every sample of a validation set of fewer than SMALL_VALIDATION
    samples its majority class (None for a larger one: Table 5.3's rule). Below it a network that
    has learnt nothing the set can see scores that for as long as its batch-normalisation
    statistics lag the data's (momentum 0.1 a step from a variance of 1): with a 65-sample source
    of a slow shaft's chip (59 trained on, batch 40: 2 steps an epoch) source_only's validation
    accuracy stayed 0.5 for 20 epochs and its epoch-0 model was kept; left to train it reached
    1.0 by epoch 40."""
    if val is None or len(val[1]) >= SMALL_VALIDATION:
        return None
    counts = np.unique(np.asarray(val[1]), return_counts=True)[1]
    return float(counts.max() / counts.sum())


def fit_adaptation(
    net: nn.Module,
    adapter,
    modules: nn.ModuleDict,
    source: tuple[np.ndarray, np.ndarray],
    source_val: tuple[np.ndarray, np.ndarray],
    target: tuple[np.ndarray, np.ndarray | None],
    *,
    rng: np.random.Generator,
    device: torch.device,
    batch: int = 40,
    lr: float = 0.003,
    min_epochs: int = 500,
    max_epochs: int = 800,
    window: int = 25,
    params: Mapping | None = None,
    augment: Callable | None = None,
    alignment: str = "marginal",
    on_epoch: Callable[[int, History], None] | None = None,
) -> History:
    """Joint training on a source batch and a target batch of equal size (thesis 5.4.2).

    loss = CE(source) [+ CE(target) when target labels are given] + the adapter's domain loss
    at the scheduled lambda. SGD at lr 0.003. The adapter's lambda ramp (500 epochs in Table 5.3)
    is stretched or shrunk to end at *min_epochs* (500 by default); after it
    training stops when the source validation accuracy falls clearly below its best or the
    domain discrepancy (between the two *training* sets, averaged over the epoch's batches)
    has stopped moving. The kept model is the post-ramp epoch with the best source validation
    accuracy, ties broken by the lower discrepancy.

    The source's rows may hold noise draws (fit_supervised). *augment(batch, generator)* is
    applied to every source batch. *alignment* ``marginal``
    (thesis) feeds the adapter all source and all target features of a batch; ``healthy``
    only the source's healthy ones against the target's (unsupervised: the whole history;
    supervised: its healthy ones, and the two domains' faults against each other as well),
    see gearlab.learn.calibration.
    """
    Xs, ys = source
    Xt, yt = target
    n = min(len(Xs), len(Xt))
    if batch > n:
        raise GearlabInputError(f"batch size {batch} is larger than the training sets ({n} samples)")
    net.to(device)
    modules.to(device)
    weights = list(net.parameters()) + list(modules.parameters())
    opt = _optimizer("sgd", weights, lr)
    ce = nn.CrossEntropyLoss()
    Xs_t, ys_t, Xt_t = _tensor(Xs, device), _labels(ys, device), _tensor(Xt, device)
    yt_t = _labels(yt, device) if yt is not None else None
    history = History()
    generator = _generator(rng) if augment else None  # drawn only then: the thesis path stays as it was
    draws = _draws(Xs, rng)
    states = _row_state(net, Xs_t, augment), _row_state(net, Xt_t, None)
    best_key, best_state = None, None
    for epoch in range(max_epochs):
        lam = adapter.lambda_schedule(epoch * RAMP_EPOCHS / min_epochs, params)  # the ramp ends at min_epochs
        train_mode(net, freeze_norm=True)
        modules.train()
        total, discrepancy, batches = _zero(device), 0.0, 0
        for s_idx, t_idx in zip(_batches(len(Xs), batch, rng), _batches(len(Xt), batch, rng)):
            m = min(len(s_idx), len(t_idx))
            s = torch.as_tensor(s_idx[:m], device=device)
            t = torch.as_tensor(t_idx[:m], device=device)
            xs, s_flat = _rows(Xs_t, s, draws)
            xs = augment(xs, generator) if augment else xs
            xt, t_flat = _rows(Xt_t, t, None)
            _give(net, [(states[0], s_flat), (states[1], t_flat)])
            opt.zero_grad()
            z = net.embed(torch.cat([xs, xt]))
            z_s, z_t = z[:m], z[m:]
            loss = ce(net.classifier(z_s), ys_t[s])
            if yt_t is not None:
                loss = loss + ce(net.classifier(z_t), yt_t[t])
            pairs = _aligned(z_s, z_t, ys_t[s], yt_t[t] if yt_t is not None else None, alignment)
            terms = [adapter.domain_terms(a, b, modules, lam, params) for a, b in pairs]
            for term, _ in terms:
                loss = loss + term
            _step(opt, weights, loss)
            total += loss.detach().double()
            # The epoch's discrepancy is measured on the latent batches it trained on: every
            # training sample once, with no extra pass through the network (and, where the
            # adapter gave it with its loss, no second computation of it).
            discrepancy += sum(
                adapter.discrepancy(a.detach(), b.detach(), modules, params) if gap is None else gap
                for (a, b), (_, gap) in zip(pairs, terms)
            )
            batches += 1
        history.train_loss.append(total.item())
        history.lam.append(lam)
        history.val_acc.append(accuracy(net, *source_val, device))
        history.discrepancy.append(discrepancy / batches)
        if epoch >= min_epochs - 1:
            key = (history.val_acc[-1], -history.discrepancy[-1])
            if best_key is None or key > best_key:
                best_key, best_state, history.best_epoch = key, copy.deepcopy(net.state_dict()), epoch
            if _should_stop(history, min_epochs, window):
                history.stopped_epoch = epoch
                break
        if on_epoch:
            on_epoch(epoch, history)
    _release(opt)
    return _keep_best(net, history, best_state)


def _generator(rng: np.random.Generator) -> torch.Generator:
    """A torch generator drawn from *rng*, for augmentation noise (reproducible per unit)."""
    return torch.Generator().manual_seed(int(rng.integers(2**62)))


def _aligned(
    z_s: torch.Tensor, z_t: torch.Tensor, y_s: torch.Tensor, y_t: torch.Tensor | None, alignment: str
) -> list[tuple[torch.Tensor, torch.Tensor]]:
    """The (source, target) latent batches the domain loss compares (see fit_adaptation); a
    class with fewer than 2 samples on either side is left out of that batch."""
    if alignment == "marginal":
        return [(z_s, z_t)]
    pairs = [(z_s[y_s == 0], z_t if y_t is None else z_t[y_t == 0])]
    if y_t is not None:
        pairs.append((z_s[y_s == 1], z_t[y_t == 1]))
    return [(a, b) for a, b in pairs if len(a) >= 2 and len(b) >= 2]


def _optimizer(name: str, params: list, lr: float):
    """Adam or SGD (no momentum, no weight decay), fused: one kernel updates every parameter,
    where the default loops over them op by op. On one CPU thread Adam's step takes a fifth of
    the time for `fast` (benchmarks/training.py); the updates are the same to rounding (3e-8
    apart after 5 steps), so trainings drift apart within their seeds' spread. A device torch has
    no fused kernel for takes torch.optim's default."""
    if all(p.device.type in ("cpu", "cuda") and p.is_floating_point() for p in params):
        return _Fused(name, params, lr)
    if name == "adam":
        return torch.optim.Adam(params, lr=lr)
    return torch.optim.SGD(params, lr=lr)


class _Fused:
    """torch.optim's Adam / SGD with fused=True: the same kernels (torch._fused_adam_,
    torch._fused_sgd_) with torch's defaults (betas 0.9/0.999, eps 1e-8, no weight decay, no
    momentum), a parameter without a gradient left out of a step as torch does.
    Not torch.optim itself: its Optimizer imports torch._dynamo on first use (torch 2.13:
    add_param_group and step are dynamo-disabled), 1.6-3.7 s in every process that trains, for
    a compiler gearlab never uses (tests/test_training_optimizer.py holds both points).

    The parameters are made views of one flat tensor (_Flat): while every one of them has a
    gradient, the clipping and the step are then a handful of operator calls on one vector
    (the gradients gathered into one by a single copy), where per parameter each costs an
    operator call or more (a `fast` step's 13 parameters: 0.1 of its fixed cost). The update is
    Adam's, element by element; the kernel's vector and scalar passes round a moment differently
    (1 ulp), so the numbers equal torch's fused Adam on the flat vector bit for bit, and its
    per-parameter call to rounding. A step where a parameter has no gradient leaves the flat
    path for good: the moments stay (views of the flat ones), each parameter gets its step count."""

    def __init__(self, name: str, params: list, lr: float):
        self.adam, self.params, self.lr = name == "adam", list(params), lr
        self.state: dict[torch.nn.Parameter, tuple[torch.Tensor, torch.Tensor, torch.Tensor]] = {}
        self.flat = _Flat.of(self.params, self.adam)

    def zero_grad(self) -> None:
        for p in self.params:
            p.grad = None

    def flat_grad(self) -> torch.Tensor | None:
        """Every parameter's gradient in one vector (a copy), where the flat path holds; else None."""
        return self.flat.grad(self.params) if self.flat is not None else None

    @torch.no_grad()
    def step(self, grad: torch.Tensor | None = None) -> None:
        """One update from the parameters' gradients, or from *grad*, their flat_grad (clipped)."""
        if self.flat is not None:
            grad = grad if grad is not None else self.flat.grad(self.params)
            if grad is not None:
                self.flat.step(grad, self.lr)
                return
            self._leave_flat()
        groups: dict[tuple, list[torch.Tensor]] = {}
        for p in self.params:
            if p.grad is not None:
                groups.setdefault((p.device, p.dtype), []).append(p)
        for params in groups.values():
            grads = [p.grad for p in params]
            if not self.adam:
                _sgd(params, grads, self.lr)
                continue
            state = [self.state.get(p) or self._new(p) for p in params]
            steps = [s[0] for s in state]
            torch._foreach_add_(steps, 1)
            _adam(params, grads, [s[1] for s in state], [s[2] for s in state], steps, self.lr)

    def _new(self, p: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """A parameter's step count (float32, on its device, as torch keeps it for fused), first
        and second moments."""
        step = torch.zeros((), dtype=torch.float32, device=p.device)
        self.state[p] = (step, torch.zeros_like(p), torch.zeros_like(p))
        return self.state[p]

    def release(self) -> None:
        """Each parameter in its own memory again (its value kept), as the network had it: a model
        saved whole then holds its own weights only, not the flat vector's other parameters."""
        if self.flat is None:
            return
        self._leave_flat()
        for p in self.params:
            p.data = p.data.clone()

    def _leave_flat(self) -> None:
        """Per parameter from here on: its moments views of the flat ones, its own step count."""
        if self.flat.moments is not None:
            first, second = (self.flat.views(m, self.params) for m in self.flat.moments)
            for p, m, v in zip(self.params, first, second):
                self.state[p] = (self.flat.count.clone(), m, v)
        self.flat = None


class _Flat:
    """The parameters as views of one flat vector on their device (their values kept), each from
    a multiple of ALIGN elements (the memory alignment torch's allocator gives a tensor of its
    own, which a matrix product's rounding can depend on), with a vector of their gradients and
    Adam's moments and step count."""

    def __init__(self, params: list, adam: bool):
        self.spans, end = [], 0
        for p in params:
            self.spans.append((end, p.numel()))
            end += -(-p.numel() // ALIGN) * ALIGN
        self.vector = torch.zeros(end, dtype=params[0].dtype, device=params[0].device)
        for p, view in zip(params, self.views(self.vector, params)):
            view.copy_(p.detach())
            p.data = view
        self.where = [p.data_ptr() for p in params]
        self.gradient = torch.zeros_like(self.vector)  # between the spans zeros, which no step moves
        self.grads = self.views(self.gradient, params)
        self.count = torch.zeros((), dtype=torch.float32, device=self.vector.device)
        self.moments = (torch.zeros_like(self.vector), torch.zeros_like(self.vector)) if adam else None

    def views(self, vector: torch.Tensor, params: list) -> list[torch.Tensor]:
        return [vector[start : start + n].view_as(p) for (start, n), p in zip(self.spans, params)]

    @staticmethod
    def of(params: list, adam: bool) -> _Flat | None:
        """For FLAT_MIN or more distinct dense floating parameters of one device and dtype, which
        torch has fused kernels for; else None."""
        if len(params) < FLAT_MIN or len({id(p) for p in params}) < len(params):
            return None
        first = params[0]
        if first.device.type not in ("cpu", "cuda") or not first.is_floating_point():
            return None
        if any(p.device != first.device or p.dtype != first.dtype or p.layout != torch.strided for p in params):
            return None
        return _Flat(params, adam)

    def grad(self, params: list) -> torch.Tensor | None:
        """The gradients as one vector (copied in, one call), where every parameter has one and
        still lies in the vector (a later `to` or a second optimiser moves them: the flat step
        would miss them)."""
        grads = [p.grad for p in params]
        if any(g is None for g in grads) or [p.data_ptr() for p in params] != self.where:
            return None
        torch._foreach_copy_(self.grads, grads)
        return self.gradient

    def step(self, grad: torch.Tensor, lr: float) -> None:
        if self.moments is None:
            _sgd([self.vector], [grad], lr)
            return
        self.count.add_(1)
        _adam([self.vector], [grad], [self.moments[0]], [self.moments[1]], [self.count], lr)


ALIGN = 16  # elements: 64 bytes of float32, as torch's CPU allocator aligns a tensor
FLAT_MIN = 3  # parameters from which the flat path pays its gradients' copy (`shapes`' 2 do not)


def _sgd(params: list, grads: list, lr: float) -> None:
    torch._fused_sgd_(
        params, grads, [], weight_decay=0.0, momentum=0.0, lr=lr, dampening=0.0,
        nesterov=False, maximize=False, is_first_step=False,
    )  # fmt: skip


def _adam(params: list, grads: list, first: list, second: list, steps: list, lr: float) -> None:
    torch._fused_adam_(
        params, grads, first, second, [], steps, amsgrad=False,
        lr=lr, beta1=0.9, beta2=0.999, weight_decay=0.0, eps=1e-8, maximize=False,
    )  # fmt: skip


def _release(opt) -> None:
    if isinstance(opt, _Fused):
        opt.release()


def _zero(device) -> torch.Tensor:
    """A float64 loss sum on *device*: adding each batch's loss there, not as a Python number,
    spares a device synchronisation per step (loss.item()); the same float64 sum."""
    return torch.zeros((), dtype=torch.float64, device=device)


def _step(opt, params: list, loss: torch.Tensor) -> None:
    """One optimiser step, the gradient norm clipped at MAX_GRAD_NORM. A stable run never reaches
    it, so its numbers do not change (its gradients are scaled by exactly 1). The adversarial
    game of DANN sometimes does: in a full Experiment A run one unit of 330 jumped from a loss of
    0.65 to 36 in its third step (gradient norm 1.6e3) and, when lambda reached 1, to 5e20 and
    NaN, which left a network that called everything healthy. On a CPU, with the optimiser's flat
    vector of gradients (_Fused.flat_grad), one norm decides; near the limit, or not finite,
    torch's clipping of the parameters' gradients (_clip) scales them, and the step takes them.
    On another device _clip, whose comparison stays on the device (no synchronisation)."""
    loss.backward()
    grad = opt.flat_grad() if isinstance(opt, _Fused) and params[0].device.type == "cpu" else None
    if grad is not None and not _clipped(grad):
        opt.step(grad)
        return
    _clip(params)
    opt.step()


def _clipped(grad: torch.Tensor) -> bool:
    """Whether torch's clipping could scale the gradients of norm |grad|: one norm of the flat
    vector, where the parameters' norms and their norm differ from it by rounding (1e-7), so
    below MAX_GRAD_NORM by 1e-4 of it the factor is >= 1 either way."""
    norm = float(torch.linalg.vector_norm(grad, 2.0))
    return not norm < MAX_GRAD_NORM * (1.0 - 1e-4)


def _clip(params: list) -> None:
    """nn.utils.clip_grad_norm_(params, MAX_GRAD_NORM, foreach=True), the same numbers, for the
    gradients on the CPU in one precision: its steps without its grouping of tensors by device,
    and without its multiplication by a factor of exactly 1 (every stable step; a NaN norm still
    multiplies, as there). It took 0.3-0.6 ms of a 6-9 ms step. Elsewhere torch's, which avoids
    the device synchronisation the comparison needs."""
    grads = [p.grad for p in params if p.grad is not None]
    if not grads or any(g.device.type != "cpu" or g.dtype != grads[0].dtype for g in grads):
        nn.utils.clip_grad_norm_(params, MAX_GRAD_NORM, foreach=_foreach(params))
        return
    total = torch.linalg.vector_norm(torch.stack(torch._foreach_norm(grads, 2.0)), 2.0)
    factor = MAX_GRAD_NORM / (total + 1e-6)
    if not factor >= 1.0:
        torch._foreach_mul_(grads, factor.clamp(max=1.0))


def _foreach(params: list) -> bool | None:
    """True where torch has the foreach kernels for every parameter's device, else its default."""
    return all(p.device.type in ("cpu", "cuda") for p in params) or None


def _keep_best(net: nn.Module, history: History, best_state: dict | None) -> History:
    """Load the selected epoch's weights; a run that never stopped early ran to its last epoch."""
    if best_state is not None:
        net.load_state_dict(best_state)
    if history.stopped_epoch < 0:
        history.stopped_epoch = len(history.train_loss) - 1
    return history


def _should_stop(h: History, min_epochs: int, window: int) -> bool:
    """After the ramp: stop on a clear drop of source validation accuracy, or when the domain
    discrepancy's moving average over *window* epochs changes by less than 1 %."""
    post = h.val_acc[min_epochs - 1 :]
    if len(post) >= 2 and post[-1] < max(post) - 0.05:
        return True
    d = h.discrepancy
    if len(d) < min_epochs + window:
        return False
    recent, before = np.mean(d[-window:]), np.mean(d[-2 * window : -window])
    return abs(recent - before) <= 0.01 * max(abs(before), 1e-12)
