"""The chapter-4 protocol (thesis 4.2, 4.3): fault-type classification in noise, with and without TSA.

Each dataset (a noisy one keeping the first of J noisy revolutions, or its TSA twin averaging
all J) is a multi-class problem over healthy and the fault types (5 classes in Table 4.1).
One run:

* split the samples 66.7 / 33.3 into training and test, stratified by class, and hold out
  20 % of the training part (again stratified) for validation;
* train a network (dropout 0.1, batches of 256, Adam) and keep the epoch of best
  *validation* accuracy, stopping when it has not improved for `patience` epochs;
* only then score the kept model on the test part: overall accuracy, the 5 x 5 confusion
  matrix, per fault type the accuracy at each intensity step (and its RFA), and the share of
  fault samples predicted healthy (the anomaly-detector view of Figure 4.4's green curve).

Run r draws its split and initial weights from (seed, r) alone, so the noisy and the TSA
datasets of one noise type (same spec but for TSA, hence the same labels in the same order)
are compared on the same split from the same initial weights: a paired comparison.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from ..errors import GearlabInputError
from ..settings import MAX_EPOCHS, MAX_REPETITIONS, MAX_SEED, setting
from .config import STARTS
from .runner import cut, generator, orders
from .runner import run_unit as held_out

if TYPE_CHECKING:
    import torch

VARIANTS = ("noisy", "tsa")
# the network's start: random, matched to the training part's noisy faults, or to the same
# revolutions without noise (the simulator's own shapes: what a hybrid model knows; decision 22)
NOISE_STARTS = (*STARTS, "clean")


@dataclass(frozen=True)
class NoiseProtocol:
    """Everything a chapter-4 run needs besides the data (defaults: thesis 4.2)."""

    network: str = "fast"  # [network] (NetworkSettings, with these defaults)
    dropout: float = 0.1  # thesis 4.2: 10 %
    # the [protocol] keys of a noise_study scenario (gearlab.scenario.keys_of)
    runs: int = setting(int, 5, low=1, high=MAX_REPETITIONS, doc="runs with different splits and initial weights")
    test_fraction: float = setting(float, 0.333, low=0.01, high=0.9, doc="share of each class held out for testing")
    val_fraction: float = setting(
        float, 0.2, low=0.01, high=0.9, doc="share of the training part held out for validation"
    )
    batch: int = setting(int, 256, low=1, doc="mini-batch size")
    lr: float = setting(float, 1e-3, low=1e-9, high=10.0, doc="Adam learning rate")  # TensorFlow's default (Table 3.1)
    epochs: int = setting(int, 100, low=1, high=MAX_EPOCHS, doc="most epochs per run")
    patience: int = setting(
        int, 15, low=1, high=MAX_EPOCHS, doc="stop after this many epochs without a better validation accuracy"
    )
    seed: int = setting(int, 0, low=0, high=MAX_SEED, doc="seeds torch as 1000 * seed + run")
    residual: bool = setting(
        bool, False, doc="input = revolution minus the median healthy revolution of the training part"
    )
    start: str = setting(
        str,
        "random",
        choices=NOISE_STARTS,
        doc="the network's start (faults: matched to the training part's faults; clean: to their noise-free twins)",
    )
    device: str = "auto"


def noise_law(spec) -> str:
    """The noise law of a chapter-4 row: the dataset's own, but the mean of J Gaussian or
    Laplace draws (TSA) is Gaussian to within its kurtosis 3 + 3/J; a Student-t(2) mean keeps
    its heavy tail (infinite variance: no central limit). Noise-free rows: Laplace (any law)."""
    kind = spec.noise.kind if spec.noise is not None else "laplace"
    return "gaussian" if spec.tsa and kind == "laplace" else kind


def clean_faults(X: np.ndarray, clean: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct noise-free fault shapes of a training part and their classes, as the residual
    input sees them: α·(c - h), h the clean healthy revolution (the median of the healthy rows)
    and α the noisy rows' scale against the clean ones (the median of <x, c> / <c, c>, as
    gearlab.learn.bounds.class_bound reads it)."""
    X, C = np.asarray(X, dtype=np.float64), np.asarray(clean, dtype=np.float64)
    alpha = float(np.median((X * C).sum(1) / (C * C).sum(1).clip(min=1e-300)))
    faults = alpha * (C[y != 0] - np.median(C[y == 0], axis=0))
    _, first = np.unique(faults.round(9), axis=0, return_index=True)  # duplicates differ only by noise
    first = np.sort(first)
    return faults[first], y[y != 0][first]


@dataclass(frozen=True)
class Split:
    """Indices into one dataset; the three parts are disjoint."""

    train: np.ndarray
    val: np.ndarray
    test: np.ndarray | None

    def training(self) -> Split:
        """The split as the training sees it: no test row (gearlab.learn.runner)."""
        return replace(self, test=None)


def part_sizes(n: int, protocol: NoiseProtocol) -> tuple[int, int, int]:
    """(train, validation, test) sizes of a class of *n* samples; each part gets at least one."""
    n_test = max(1, round(n * protocol.test_fraction))
    n_val = max(1, round((n - n_test) * protocol.val_fraction))
    return n - n_test - n_val, n_val, n_test


def check_split(class_sizes: dict[str, int], protocol: NoiseProtocol, where: str) -> None:
    """Every class must reach the training, validation and test parts."""
    if len(class_sizes) < 2:
        raise GearlabInputError(f"{where}: a classification study needs healthy samples and at least one fault type")
    for name, n in class_sizes.items():
        if part_sizes(n, protocol)[0] < 1:
            raise GearlabInputError(
                f"{where}: class '{name}' has {n} samples; the train/validation/test split needs at least one "
                f"in each part (give more samples, or a smaller test_fraction or val_fraction)"
            )


def check_batch(class_sizes: dict[str, int], protocol: NoiseProtocol, where: str) -> None:
    n_train = sum(part_sizes(n, protocol)[0] for n in class_sizes.values())
    if protocol.batch > n_train:
        raise GearlabInputError(
            f"{where}: batch size {protocol.batch} is larger than the training set ({n_train} samples); "
            f"expected at most {n_train}"
        )


def split(label: np.ndarray, protocol: NoiseProtocol, run: int) -> Split:
    """Stratified split of run *run* (gearlab.learn.runner): per class, training, then validation,
    then test rows of the class's random order."""
    drawn = orders(label, np.unique(label), generator(protocol.seed, run))
    return Split(*cut(drawn, {c: part_sizes(len(rows), protocol)[:2] for c, rows in drawn.items()}))


def train(
    protocol: NoiseProtocol,
    train_set: tuple[np.ndarray, np.ndarray],
    val_set: tuple[np.ndarray, np.ndarray],
    n_classes: int,
    run: int,
    device: torch.device,
    on_epoch: Callable | None = None,
    clean: tuple[np.ndarray, np.ndarray] | None = None,
    law: str = "laplace",
):
    """The model of one run, made from the training and validation arrays only (and, for the
    `clean` start, the training part's noise-free fault shapes and classes *clean*,
    `clean_faults`; *law* the rows' noise law)."""
    import torch  # here, not at the top: start-up time (checking a scenario loads no torch)

    from .networks import build_network, matched_start
    from .training import embed, fit_supervised

    X, y = train_set
    seed = 1000 * protocol.seed + run
    torch.manual_seed(seed)  # dropout masks
    net = build_network(protocol.network, n_classes, protocol.dropout, length=X.shape[1], seed=seed)
    if protocol.start == "faults":  # the bursts: fault samples less the healthy training revolutions' median
        matched_start(net, X[y != 0] - np.median(X[y == 0], axis=0), seed)
    elif protocol.start == "clean":  # the Bayes classifier of the simulator's exact shapes, the training part's priors
        prior = np.bincount(y, minlength=n_classes) / len(y)
        matched_start(net, clean[0], seed, classes=clean[1], law=law, prior=prior)
    net = net.to(device)
    fitted, (Xv, yv) = net, val_set
    if protocol.start == "clean":
        # Learning the exact shapes again from noisy copies can only lose (docs/learning.md,
        # decision 22), so they stay fixed: their likelihoods are computed once, and only the
        # mixture trains on them.
        fitted, X, Xv = net.classifier, embed(net, X, device).cpu().numpy(), embed(net, Xv, device).cpu().numpy()
    history = fit_supervised(
        fitted,
        X,
        y,
        rng=generator(protocol.seed, run, 1),
        device=device,
        epochs=protocol.epochs,
        batch=protocol.batch,
        optimizer="adam",
        lr=protocol.lr,
        val=(Xv, yv),
        patience=protocol.patience,
        on_epoch=on_epoch,
    )
    return net, history


def scores(
    y: np.ndarray, pred: np.ndarray, intensity: np.ndarray, rfa: np.ndarray, class_names: tuple[str, ...]
) -> dict:
    """Test metrics of one run. Class 0 is healthy; per fault type, counts at each intensity
    step (so runs can be pooled or averaged later)."""
    n = len(class_names)
    confusion = np.zeros((n, n), dtype=np.int64)
    np.add.at(confusion, (y, pred), 1)
    fault = y > 0
    by_step = {}
    for c, name in enumerate(class_names[1:], start=1):
        rows: dict[str, list] = {"steps": [], "rfa": [], "n": [], "correct": [], "as_healthy": []}
        for step in np.unique(intensity[y == c]):
            m = (y == c) & (intensity == step)
            rows["steps"].append(int(step))
            rows["rfa"].append(float(rfa[m].mean()))
            rows["n"].append(int(m.sum()))
            rows["correct"].append(int((pred[m] == c).sum()))
            rows["as_healthy"].append(int((pred[m] == 0).sum()))
        by_step[name] = rows
    class_accuracy = {
        name: 100.0 * float(confusion[c, c] / confusion[c].sum()) if confusion[c].sum() else None
        for c, name in enumerate(class_names)
    }
    return {
        "accuracy": 100.0 * float((pred == y).mean()),
        "fault_as_healthy": 100.0 * float((pred[fault] == 0).mean()) if fault.any() else None,
        "healthy_as_fault": 100.0 * float((pred[~fault] != 0).mean()) if (~fault).any() else None,
        "class_accuracy": class_accuracy,
        "confusion": confusion.tolist(),
        "by_step": by_step,
    }


def run_unit(protocol: NoiseProtocol, dataset, run: int, on_epoch: Callable | None = None, twin=None) -> dict:
    """Train and score run *run* on *dataset* (*twin*: its noise-free twin, which the `clean`
    start needs; only its training part is read), as every unit runs (gearlab.learn.runner.run_unit)."""
    label = np.asarray(dataset.label, dtype=np.int64)

    def fit(s: Split, device):
        X = dataset.X
        clean = clean_faults(X[s.train], twin.X[s.train], label[s.train]) if protocol.start == "clean" else None
        if protocol.residual:  # the healthy reference from the training part's labels, never from the test part
            X = X - np.median(X[s.train[label[s.train] == 0]], axis=0).astype(X.dtype)
        start = time.perf_counter()
        net, history = train(
            protocol,
            (X[s.train], label[s.train]),
            (X[s.val], label[s.val]),
            len(dataset.spec.class_names),
            run,
            device,
            on_epoch,
            clean=clean,
            law=noise_law(dataset.spec),
        )
        return s, X, net, history, time.perf_counter() - start

    def score(fitted, test: np.ndarray, device) -> dict:
        from .training import predict  # start-up time

        s, X, net, history, seconds = fitted
        pred = predict(net, X[test], device)
        return {
            "run": run,
            "dataset": dataset.spec.name,
            "key": dataset.key,
            "classes": list(dataset.spec.class_names),
            "n_train": int(len(s.train)),
            "n_val": int(len(s.val)),
            "n_test": int(len(test)),
            "val_accuracy": 100.0 * history.val_acc[history.best_epoch],  # of the kept epoch
            "device": str(device),
            "best_epoch": history.best_epoch,
            "stopped_epoch": history.stopped_epoch,
            "train_seconds": seconds,
            "history": {"train_loss": history.train_loss, "val_acc": history.val_acc},
            **scores(
                label[test],
                pred,
                np.asarray(dataset.intensity)[test],
                np.asarray(dataset.rfa)[test],
                tuple(dataset.spec.class_names),
            ),
        }

    return held_out(split(label, protocol, run), fit, score, protocol.device)


def mean_std(values: list[float]) -> dict:
    """{mean, std (n - 1), n} of the values that are not None."""
    v = np.asarray([x for x in values if x is not None], dtype=float)
    if not len(v):
        return {"mean": None, "std": None, "n": 0}
    return {"mean": float(v.mean()), "std": float(v.std(ddof=1)) if len(v) > 1 else 0.0, "n": int(len(v))}


def _run_curves(record: dict) -> dict[str, dict[int, tuple]]:
    """{fault type or 'all': {step: (RFA, accuracy %, predicted-healthy %)}} of one run;
    'all' pools the fault types at each step."""
    out, pooled = {}, {}
    for f in record["classes"][1:]:
        rows = record["by_step"][f]
        out[f] = {}
        for s, a, n, ok, h in zip(rows["steps"], rows["rfa"], rows["n"], rows["correct"], rows["as_healthy"]):
            out[f][s] = (a, 100.0 * ok / n, 100.0 * h / n)
            p = pooled.setdefault(s, [0, 0, 0])
            p[0], p[1], p[2] = p[0] + n, p[1] + ok, p[2] + h
    out["all"] = {s: (None, 100.0 * ok / n, 100.0 * h / n) for s, (n, ok, h) in pooled.items()}
    return out


def aggregate(records: list[dict]) -> dict:
    """Mean ± std over the runs of one dataset (the records of one noise type and variant).

    Curves (Figure 4.4) hold, per fault type and for all fault types pooled ('all', the black
    curve), the accuracy at each intensity step and the share of those fault samples predicted
    healthy (the green curve); each a per-run value averaged over the runs.
    """
    classes = records[0]["classes"]
    runs = [_run_curves(r) for r in records]
    curves = {}
    for name in runs[0]:
        steps = sorted({s for c in runs for s in c[name]})
        values = [[c[name][s] for c in runs if s in c[name]] for s in steps]
        acc = [mean_std([v[1] for v in vs]) for vs in values]
        healthy = [mean_std([v[2] for v in vs]) for vs in values]
        curves[name] = {
            "steps": steps,
            "rfa": [vs[0][0] for vs in values],
            "accuracy_mean": [x["mean"] for x in acc],
            "accuracy_std": [x["std"] for x in acc],
            "as_healthy_mean": [x["mean"] for x in healthy],
            "as_healthy_std": [x["std"] for x in healthy],
        }
    return {
        "runs": len(records),
        "accuracy": mean_std([r["accuracy"] for r in records]),
        "fault_as_healthy": mean_std([r["fault_as_healthy"] for r in records]),
        "healthy_as_fault": mean_std([r["healthy_as_fault"] for r in records]),
        "class_accuracy": {c: mean_std([r["class_accuracy"][c] for r in records]) for c in classes},
        "classes": classes,
        "confusion": np.sum([r["confusion"] for r in records], axis=0).tolist(),  # Figure 4.6: runs compiled
        "curves": curves,
    }
