"""The chapter-5 transfer protocol (thesis 5.4.2, Table 5.3).

Binary healthy/fault detection. For each repetition r and each k in (0, 1, 2, 4, 8, 16):
the target training set is 120 target samples, k random faults and 120 - k random healthy
ones; the target test set is every other target sample. The draws are nested across k (one
order of faults and one of healthy samples per repetition, k taken from the front of each):
the k columns are paired comparisons, and the healthy samples every k shares (the *history
core*) can calibrate one priming per repetition. Methods:

* uncalibrated (Adam, stop on a 10 % validation split): source_only (labelled source only,
  trained once per repetition) and target_only (the 120 labelled target samples);
* calibrated: primed 100 epochs on the full source training set (one priming per
  repetition, shared by every calibrated run of it), then SGD at 0.003 on batches of 40
  source + 40 target samples drawn from 120 of each, lambda rising by 0.05 every 25
  epochs; unsupervised (no target labels) or supervised (target labels used).

A unit of work is (repetition, k, method). Its training code receives the training arrays
only; the target test set is used once, afterwards, to score the returned model.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..confined import Confined
from ..errors import GearlabInputError
from ..events import unit_says
from ..registry import get_registry
from ..settings import MAX_EPOCHS, MAX_REPETITIONS, MAX_SEED, setting
from .bounds import detection_at
from .config import DEFAULT_DROPOUT, DEFAULT_NETWORK, THESIS, Calibration
from .runner import cut, generator, orders, put_first
from .runner import run_unit as held_out

# torch, the networks, the training loops and the calibrated model are imported inside the
# functions that train (start-up time): checking a scenario reads this module's settings only.

KS = (0, 1, 2, 4, 8, 16)
TARGET_DRAW = 1  # seeds the repetition's target orders apart from its source split
HISTORY_DRAW = 2  # seeds a history fixed across repetitions (history_of) apart from both
LATENT_REPETITION = 0  # the repetition whose latent features a run keeps (Figure 5.9's maps)
ADAM_LR = 1e-3  # TensorFlow's default, which the thesis's Adam runs used (Table 5.3)


@dataclass(frozen=True)
class Method:
    """An adapter with its supervision and parameters. *params* are the resolved ones (every
    parameter, defaults filled) that training uses; *shown* those the scenario set, which are
    all that tells two methods of one adapter apart in labels and unit keys."""

    adapter: str
    supervised: bool
    params: tuple[tuple[str, object], ...] = ()
    shown: tuple[tuple[str, object], ...] = ()

    @property
    def label(self) -> str:
        extra = "".join(f", {k}={v}" for k, v in self.shown)
        return f"{self.adapter} ({'supervised' if self.supervised else 'unsupervised'}{extra})"

    @property
    def key(self) -> str:
        extra = "".join(f"-{k}={v}" for k, v in self.shown)
        return f"{self.adapter}-{'sup' if self.supervised else 'unsup'}{extra}"

    @property
    def is_detector(self) -> bool:
        """A detector plugin (gearlab.learn.detector_contract), not an adapter: no network is
        trained, the model is fitted on the training arrays (`adapter` names either kind)."""
        return get_registry().kind_of(self.adapter) == "detector"


@dataclass
class Protocol:
    """Everything a transfer run needs besides the data (defaults: Table 5.3)."""

    methods: tuple[Method, ...]
    network: str = DEFAULT_NETWORK  # [network] (NetworkSettings)
    dropout: float = DEFAULT_DROPOUT
    ks: tuple[int, ...] = KS
    # the [protocol] keys: Table 5.3's training settings (gearlab.scenario.keys_of)
    repetitions: int = setting(
        int, 5, low=1, high=MAX_REPETITIONS, quick=2, doc="repetitions, each with its own split and seed"
    )
    target_train: int = setting(int, 120, low=2, doc="samples in the target training set")
    batch: int = setting(int, 40, low=1, doc="mini-batch size, per domain")
    lr: float = setting(float, 0.003, low=1e-9, high=10.0, doc="SGD learning rate of the calibrated methods")
    prime_epochs: int = setting(
        int, 100, low=0, high=MAX_EPOCHS, quick=30, doc="priming on the full source set, shared within a repetition"
    )
    baseline_epochs: int = setting(
        int, 200, low=1, high=MAX_EPOCHS, quick=60, doc="at most, for the Adam-trained baselines and fine-tuning"
    )
    patience: int = setting(
        int, 20, low=1, high=MAX_EPOCHS, doc="stop after this many epochs without a better validation accuracy"
    )
    min_epochs: int = setting(int, 500, low=1, high=MAX_EPOCHS, quick=60, doc="end of the lambda ramp")
    max_epochs: int = setting(int, 800, low=1, high=MAX_EPOCHS, quick=90, doc="most epochs of an adaptation run")
    val_fraction: float = 0.1
    seed: int = setting(int, 0, low=0, high=MAX_SEED, doc="seeds torch as 1000 * seed + repetition")
    device: str = "auto"
    calibration: Calibration = THESIS
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Split:
    """Indices into the source and target datasets for one (repetition, k)."""

    source_train: np.ndarray
    source_val: np.ndarray
    target_train: np.ndarray
    target_test: np.ndarray
    history_core: np.ndarray  # target training rows of every k of the repetition (all healthy)

    @property
    def test(self) -> np.ndarray | None:
        return self.target_test

    def training(self) -> Split:
        """The split as a method's training sees it: no target test row (gearlab.learn.runner)."""
        return replace(self, target_test=None)


@dataclass(frozen=True)
class Counts:
    """What the protocol asks of a dataset: its name, sample length and class sizes."""

    name: str
    length: int
    healthy: int
    faults: int

    @classmethod
    def of(cls, dataset) -> Counts:
        return cls(
            dataset.spec.name if dataset.spec is not None else "",
            int(dataset.X.shape[1]),
            int((dataset.fault == 0).sum()),
            int((dataset.fault == 1).sum()),
        )


def _n_val(protocol: Protocol, n: int) -> int:
    return max(1, round(protocol.val_fraction * n))


def check(protocol: Protocol, where: str) -> None:
    """Refuse a protocol that cannot run whatever the data (*where*: the scenario file)."""
    # every k's training set keeps the history core, at least 2 healthy samples: the priming's
    # reference and noise level are read off them
    if max(protocol.ks) > protocol.target_train - 2:
        raise GearlabInputError(
            f"{where}: [protocol] key 'ks': k = {max(protocol.ks)} fault samples do not fit in a target "
            f"training set of target_train = {protocol.target_train} with 2 healthy ones left"
        )
    if protocol.batch > protocol.target_train:
        raise GearlabInputError(
            f"{where}: [protocol] key 'batch': {protocol.batch} is larger than the target "
            f"training set (target_train = {protocol.target_train})"
        )


def check_data(protocol: Protocol, source: Counts, target: Counts, where: str) -> None:
    """Refuse datasets the protocol cannot split or batch (checked before any training)."""
    if source.length != target.length:
        raise GearlabInputError(
            f"{where}: source '{source.name}' and target '{target.name}' samples have different "
            f"lengths ({source.length} and {target.length})"
        )
    k = max(protocol.ks)
    if k > target.faults:
        raise GearlabInputError(
            f"{where}: [protocol] key 'ks': k = {k} target fault samples asked for, the target "
            f"'{target.name}' has {target.faults}"
        )
    healthy = protocol.target_train - min(protocol.ks)
    if healthy > target.healthy:
        raise GearlabInputError(
            f"{where}: [protocol] key 'target_train': a target training set of "
            f"{protocol.target_train} with k = {min(protocol.ks)} needs {healthy} healthy "
            f"samples, the target '{target.name}' has {target.healthy}"
        )
    if protocol.target_train >= target.healthy + target.faults:
        raise GearlabInputError(
            f"{where}: [protocol] key 'target_train': {protocol.target_train} leaves no target "
            f"test samples (the target '{target.name}' has {target.healthy + target.faults})"
        )
    n = source.healthy + source.faults
    source_train = n - _n_val(protocol, n)
    if protocol.batch > source_train:
        raise GearlabInputError(
            f"{where}: [protocol] key 'batch': {protocol.batch} is larger than the source "
            f"training set ({source_train} of the {n} samples of '{source.name}')"
        )


def history_of(protocol: Protocol, target) -> np.ndarray:
    """A target history fixed across repetitions: target_train - max(ks) healthy rows drawn once.
    What a kind fits on the target besides its networks (the gap diagnosis) reads these rows and
    passes them to `split`, which keeps them in every repetition's training set: never a test row."""
    rng = np.random.default_rng([protocol.seed, HISTORY_DRAW])
    healthy = rng.permutation(np.flatnonzero(target.fault == 0))
    return np.sort(healthy[: protocol.target_train - max(protocol.ks)])


def split(protocol: Protocol, source, target, rep: int, k: int, history: np.ndarray | None = None) -> Split:
    """Random source validation split and target orders (per repetition, gearlab.learn.runner); the
    target training set takes the first k faults and the first target_train - k healthy samples of
    the orders. The history core is the first target_train - max(ks) healthy ones: in every k's
    training set, in no k's test set. *history* (`history_of`): healthy rows that come first in
    every repetition's order, so that the core is exactly they."""
    one = np.zeros(len(source.X), dtype=np.int64)  # the source split is not stratified: one class
    source_val, source_train = cut(orders(one, (0,), generator(protocol.seed, rep)), {0: (_n_val(protocol, len(one)),)})
    rng = generator(protocol.seed, rep, TARGET_DRAW)
    drawn = orders(target.fault, (1, 0), rng)  # faults first: the stream's order
    if history is not None:
        drawn[0] = put_first(drawn[0], history, rng)
    train, test = cut(drawn, {1: (k,), 0: (protocol.target_train - k,)})
    core, _ = cut({0: drawn[0]}, {0: (protocol.target_train - max(*protocol.ks, k),)})
    return Split(source_train, source_val, train, test, core)


class StateStore:
    """Per-repetition network states shared by runs (the priming, the source-only model):
    torch state dicts in the run directory's states/ folder (a Confined: no link followed),
    loaded with weights_only=True."""

    def __init__(self, directory: Confined | Path | None):
        if isinstance(directory, Path):  # a folder of its own (a test, a benchmark): its parent is trusted
            directory = Confined(directory.parent, (directory.name,))
        self.directory = directory
        self.memory: dict[str, dict] = {}

    def get(self, name: str, make: Callable[[], dict]) -> dict:
        if name in self.memory:
            return self.memory[name]
        path = self.directory / f"{name}.pt" if self.directory else None
        if path is not None and path.exists():
            state = load_state(path)
        else:
            # Making a state draws from torch's global generator; fork it so that the caller
            # continues exactly as when the state is loaded (a resumed run, a later unit).
            import torch  # start-up time

            with torch.random.fork_rng():
                state = make()
            if path is not None:
                buf = io.BytesIO()
                torch.save(state, buf)  # into memory; written whole through the run directory
                path.write(buf.getvalue())
        self.memory[name] = state
        return state


def load_state(path: Confined) -> dict:
    """A stored network state; a damaged file (cut short, overwritten) is one line that says
    how to recover, not a traceback: weights_only=True runs no code of the file either way."""
    import torch  # start-up time

    data = path.read_bytes()
    try:
        state = torch.load(io.BytesIO(data), weights_only=True, map_location="cpu")
    except Exception as exc:  # noqa: BLE001 - UnpicklingError, RuntimeError, EOFError, ... of a damaged file
        raise GearlabInputError(
            f"{path}: damaged network state ({type(exc).__name__}); remove the file and resume: "
            "the state is trained again"
        ) from None
    if not isinstance(state, dict):
        raise GearlabInputError(f"{path}: not a network state (a {type(state).__name__}); remove it and resume")
    return state


def unit_key(rep: int, k: int, method: Method) -> str:
    return f"rep{rep}/k{k}/{method.key}"


def domain_adapting(name: str) -> bool:
    """Whether method *name* adapts the domains: an adapter trained on joint source and target
    batches with a domain loss (not a detector, nor a source- or target-only training)."""
    registry = get_registry()
    return registry.kind_of(name) == "adapter" and registry.get("adapter", name).train_on == "joint"


def shared_state(method: Method, rep: int, k: int, protocol: Protocol) -> str | None:
    """The name of the shared state a method starts from, if any (see train_method): one per
    repetition (a priming that depends on the target history reads the history core, which
    every k shares)."""
    if method.is_detector:  # nothing trained, nothing shared
        return None
    adapter = get_registry().get("adapter", method.adapter)
    if adapter.train_on == "source":
        return f"rep{rep}_source_only"
    return f"rep{rep}_primed" if adapter.calibrated else None


def _net(protocol: Protocol, seed: int, device, length: int):
    import torch  # start-up time

    from .networks import build_network

    torch.manual_seed(seed)
    return build_network(protocol.network, n_classes=2, dropout=protocol.dropout, length=length).to(device)


def _cpu_state(net) -> dict:
    return {k: v.detach().cpu().clone() for k, v in net.state_dict().items()}


def run_unit(
    protocol: Protocol,
    source,
    target,
    rep: int,
    k: int,
    method: Method,
    states: StateStore,
    on_epoch: Callable | None = None,
    history: np.ndarray | None = None,
) -> dict:
    """Train one method for one (repetition, k) and score it on the target test set (*history*:
    see `split`), as every unit runs (gearlab.learn.runner.run_unit)."""

    def fit(s: Split, device):
        Xs, ys = source.X[s.source_train], source.fault[s.source_train].astype(np.int64)
        val = (source.X[s.source_val], source.fault[s.source_val].astype(np.int64))
        Xt = target.X[s.target_train]
        yt = target.fault[s.target_train].astype(np.int64)
        made = train_method(
            protocol, method, (Xs, ys), val, (Xt, yt), rep, k, states, device, on_epoch, core=target.X[s.history_core],
            latent=rep == LATENT_REPETITION,
        )  # fmt: skip
        return val, *made

    def score(fitted, test: np.ndarray, device) -> dict:
        from .training import accuracy  # start-up time

        val, model, trained, extra = fitted
        X_test, y_test = target.X[test], target.fault[test].astype(np.int64)
        score = fault_score(model, X_test, device)
        pred = (score > 0).astype(np.int64)
        confusion = [[int(((y_test == a) & (pred == b)).sum()) for b in (0, 1)] for a in (0, 1)]
        val_acc = extra.pop("source_val_accuracy", None)
        return {
            "unit": unit_key(rep, k, method),
            "rep": rep,
            "k": k,
            "method": method.label,
            "adapter": method.adapter,
            "supervised": method.supervised,
            "accuracy": 100.0 * float((pred == y_test).mean()),
            "healthy_share": 100.0 * float((y_test == 0).mean()),
            "predicted_fault_share": 100.0 * float((pred == 1).mean()),
            "confusion": confusion,
            "n_test": int(len(y_test)),
            "source_val_accuracy": 100.0 * accuracy(model, *val, device) if val_acc is None else val_acc,
            "history": trained.as_dict() if trained is not None else None,
            **detection_rates(score, y_test, target.label[test], class_names(target)),
            **extra,
        }

    return held_out(split(protocol, source, target, rep, k, history), fit, score, protocol.device)


def fault_score(model, X: np.ndarray, device, batch: int = 256) -> np.ndarray:
    """logit(fault) - logit(healthy) of each revolution: > 0 is a fault call (the arg-max)."""
    import torch  # start-up time

    model.eval()
    out = []
    with torch.no_grad():
        for i in range(0, len(X), batch):
            rows = torch.as_tensor(np.ascontiguousarray(X[i : i + batch]), dtype=torch.float32, device=device)
            logits = model(rows)
            out.append((logits[:, 1] - logits[:, 0]).cpu().numpy())
    return np.concatenate(out) if out else np.empty(0)


def class_names(dataset) -> list[str] | None:
    names = getattr(dataset.spec, "class_names", None)
    return list(names) if names else None


def detection_rates(score: np.ndarray, y: np.ndarray, label: np.ndarray, names: list[str] | None = None) -> dict:
    """Measures that do not hinge on the test set's healthy share: the balanced accuracy (%) of
    the method's own calls, and the share (%) of faults, per fault class, found at the threshold
    that lets 1 % of the test set's healthy revolutions through (an evaluation with the test
    labels, after the model is fixed; the method never sees it)."""
    called = score > 0
    healthy, faulty = y == 0, y == 1
    balanced = 50.0 * (float((~called[healthy]).mean()) + float(called[faulty].mean()))
    per_class = {}
    for c in np.unique(label[faulty]):
        name = names[int(c)] if names and int(c) < len(names) else str(int(c))
        keep = healthy | (label == c)
        per_class[name] = detection_at(score[keep], y[keep], 0.01)
    return {
        "balanced_accuracy": balanced,
        "detection_at_1pct": detection_at(score, y, 0.01),
        "detection_at_1pct_by_class": per_class,
    }


def train_method(
    protocol: Protocol,
    method: Method,
    source,
    source_val,
    target,
    rep: int,
    k: int,
    states: StateStore,
    device,
    on_epoch=None,
    core: np.ndarray | None = None,
    latent: bool = False,
):
    """The model a method makes from the training arrays (no target test data here). *core*:
    the target training rows the repetition's priming is calibrated on (default: all of them).
    *latent*: an adapted network's latent features of its training rows go with it (`_latent`,
    for the maps of `LATENT_REPETITION`; two passes through the network a unit, which every
    other repetition's and every detection unit's training made for nothing).
    The source's X may be (n, D, L), D noise draws of each sample: the networks train on a draw
    at random per row and batch (training._rows); the calibration, a network's input length and
    the latent maps take the first draw; a detector is built from each sample's mean over its draws."""
    import torch  # start-up time

    from .calibration import history_law, prepare
    from .networks import matched_start, use_law
    from .training import accuracy, fit_adaptation, fit_supervised

    registry = get_registry()
    params = dict(method.params)
    drawn, ys = source
    if method.is_detector:  # no network: a model fitted on the training arrays
        # its shapes: each sample's mean over its draws, the least noisy estimate of its shape
        # (single draws as templates would be noisy, and 16 times as many of them)
        shapes = (drawn.mean(axis=1), ys) if drawn.ndim == 3 else source
        target = (target[0], target[1] if method.supervised else None)
        return registry.get("detector", method.adapter).fit(shapes, target, params).to(device), None, {}
    adapter = registry.get("adapter", method.adapter)
    rng = generator(protocol.seed, rep, k, 7)
    Xs = drawn[:, 0] if drawn.ndim == 3 else drawn  # one draw of each source sample
    Xt, yt = target
    seed = 1000 * protocol.seed + rep
    # The calibration of a calibrated method (gearlab.learn.calibration; the thesis's recipe
    # changes nothing): references and noise from the target training set taken as history
    # whatever the supervision; the priming's from the history core, so that one priming
    # serves every method and every k of the repetition.
    if adapter.calibrated:  # seconds on a busy machine (the path's fit): the unit's line says so
        unit_says("calibration: the references, the transfer path and the noise law")
    inputs = prepare(protocol.calibration, Xs, ys, Xt, None) if adapter.calibrated else None
    augment = inputs.augment if inputs is not None and inputs.noise_law else None
    # `shapes` scores its templates in the noise law of the history the priming reads, as
    # `likelihood_ratio` does: the target's law is found, never assumed.
    law = history_law(Xt if core is None else core) if adapter.calibrated else None

    def told(what: str, epochs: int):
        """on_epoch for a shared state's training (the priming, the source model): a minute or
        more on a full source before the unit's own epochs, so it says what it trains and how far."""
        if on_epoch is None:
            return None
        return lambda epoch, history: on_epoch(epoch, history, f"{what}, epoch {epoch + 1} of {epochs}")

    def primed() -> dict:
        unit_says("priming: calibration on the history core")
        start = prepare(protocol.calibration, Xs, ys, Xt if core is None else core, None)
        net = _net(protocol, seed, device, Xs.shape[1])
        if protocol.calibration.start == "faults":
            unit_says("priming: matched start of the filter bank")
            matched_start(net, start.source(Xs[np.asarray(ys) != 0]), seed, law=law)
        unit_says(f"priming, epoch 1 of {protocol.prime_epochs}: training")
        fit_supervised(
            net,
            each_draw(start.source, drawn),
            ys,
            rng=generator(protocol.seed, rep, 1),
            device=device,
            epochs=protocol.prime_epochs,
            batch=protocol.batch,
            optimizer="adam",
            val=None,
            patience=None,
            augment=start.augment if start.noise_law else None,
            on_epoch=told("priming", protocol.prime_epochs),
        )
        return _cpu_state(net)

    if adapter.train_on == "source":  # the uncalibrated source model: it never depends on k

        def trained() -> dict:
            net = _net(protocol, seed, device, Xs.shape[1])
            fit_supervised(
                net,
                drawn,
                ys,
                rng=generator(protocol.seed, rep, 2),
                device=device,
                epochs=protocol.baseline_epochs,
                batch=protocol.batch,
                val=source_val,
                patience=protocol.patience,
                on_epoch=told("source model", protocol.baseline_epochs),
            )
            return _cpu_state(net)

        net = _net(protocol, seed, device, Xs.shape[1])
        net.load_state_dict(states.get(shared_state(method, rep, k, protocol), trained))
        return net, None, {}
    if adapter.calibrated:
        net = _net(protocol, seed, device, Xs.shape[1])
        net.load_state_dict(states.get(shared_state(method, rep, k, protocol), primed))
        use_law(net, law)
        Xt_in = inputs.target(Xt)
        Xv, yv = source_val
        Xv = inputs.source(Xv)
        if augment is not None:  # the source validation set carries the target's noise too, drawn once
            Xv = augment(torch.as_tensor(Xv), torch.Generator().manual_seed(seed)).numpy()
        source_val = (Xv, yv)
    else:
        net = _net(protocol, seed + 17, device, Xs.shape[1])
        Xt_in = Xt
    if adapter.train_on == "target":  # target_only from scratch, finetune from the primed network
        # 10 % of the labelled target training samples decide when to stop (Table 5.3)
        order = rng.permutation(len(Xt))
        n_val = _n_val(protocol, len(order))
        sgd = adapter.optimizer == "sgd"
        history = fit_supervised(
            net,
            Xt_in[order[n_val:]],
            yt[order[n_val:]],
            rng=rng,
            device=device,
            epochs=protocol.baseline_epochs,
            batch=min(protocol.batch, len(order) - n_val),
            optimizer=adapter.optimizer,
            lr=protocol.lr if sgd else ADAM_LR,
            val=(Xt_in[order[:n_val]], yt[order[:n_val]]),
            patience=protocol.patience,
            parameters=adapter.trainable(net, params),
            freeze_norm=adapter.calibrated,
            on_epoch=on_epoch,
        )
        extra = {"source_val_accuracy": 100.0 * accuracy(net, *source_val, device)} if adapter.calibrated else {}
        return _calibrated(net, inputs, Xt, yt, source_val, device), history, extra
    modules = adapter.extra_modules(net.latent_dim, params)
    take = generator(protocol.seed, rep, k, 3).permutation(len(Xs))[: len(Xt)]
    history = fit_adaptation(
        net,
        adapter,
        modules,
        (each_draw(inputs.source, drawn[take]), ys[take]),
        source_val,
        (Xt_in, yt if method.supervised else None),
        rng=rng,
        device=device,
        batch=protocol.batch,
        lr=protocol.lr,
        min_epochs=protocol.min_epochs,
        max_epochs=protocol.max_epochs,
        params=params,
        augment=augment,
        alignment=protocol.calibration.alignment,
        on_epoch=on_epoch,
    )
    model = _calibrated(net, inputs, Xt, yt if method.supervised else None, source_val, device)
    extra = {
        "latent_dim": int(net.latent_dim),
        # the kept epoch's own figure: the network is that epoch's (training.fit_adaptation keeps
        # one after the ramp), scored on the same rows, so the same number without another pass
        "source_val_accuracy": 100.0
        * (history.val_acc[history.best_epoch] if history.best_epoch >= 0 else accuracy(net, *source_val, device)),
    }
    if latent:
        extra["_latent"] = latent_features(net, inputs.source(Xs[take]), Xt_in, ys[take], yt, augment, seed, device)
    return model, history, extra


def latent_features(net, Xs_in, Xt_in, ys, yt, augment, seed: int, device) -> dict:
    """An adapted network's latent features of its source and target training rows, with their
    labels (the maps mark the classes too)."""
    import torch  # start-up time

    from .training import embed

    if augment is not None:
        # the source as training showed it: with the target's noise (drawn once, as the validation
        # set's). A noise-free source residual has a noise scale of ~0, so the `shapes` network's
        # likelihood ratios (divided by that scale) were ~1e14 against the target's ~1e2, and
        # every map a line (issue 41)
        Xs_in = augment(torch.as_tensor(Xs_in), torch.Generator().manual_seed(seed + 1)).numpy()
    with torch.no_grad():
        return {
            "source": embed(net, Xs_in, device).cpu().numpy(),
            "target": embed(net, Xt_in, device).cpu().numpy(),
            "source_label": ys,
            "target_label": yt,
        }


def each_draw(f: Callable, X: np.ndarray) -> np.ndarray:
    """f of each draw of X (n, D, L), or of X (n, L)."""
    if X.ndim == 2:
        return f(X)
    return np.stack([f(X[:, d]) for d in range(X.shape[1])], axis=1)


def _calibrated(net, inputs, Xt, yt, source_val, device):
    """A calibrated method's model: the network as the thesis uses it, or behind the target's
    reference and the history threshold when the protocol asks for them."""
    from .calibration import calibrate  # start-up time

    settings = inputs.settings if inputs is not None else THESIS
    if settings.residual or settings.threshold != "argmax":
        return calibrate(net, inputs, Xt, yt, device)
    return net
