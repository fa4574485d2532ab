"""Training the chapter-5 way, as every kind that trains does (transfer, gap, detection,
transfer_benchmark): the [protocol] training and calibration keys, the [network] table and the
[[methods]] keys, a [[methods]] entry resolved to a Method, and one training unit."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from ..data import cache
from ..errors import GearlabInputError
from ..events import UnitProgress, saying
from ..executors import one_thread
from ..learn.config import RECIPE, Calibration, NetworkSettings
from ..learn.protocol import Method, Protocol, StateStore, run_unit, unit_key
from ..registry import METHODS, get_registry
from ..scenario import Table, keys_of, location
from ..settings import setting

# Table 5.3's training settings: the keys of every kind that trains the chapter-5 way, declared
# on the Protocol dataclass
TRAINING = keys_of(
    Protocol,
    ("target_train", "batch", "lr", "prime_epochs", "baseline_epochs", "patience", "min_epochs", "max_epochs", "seed"),
)

# How calibrated methods use the target history (gearlab.learn.calibration); the defaults are
# gearlab's recipe, the thesis's is residual = false, start = "random", source_noise = "off",
# alignment = "marginal", threshold = "argmax" (scenarios/expA_thesis.toml, expB_thesis.toml).
CALIBRATION = keys_of(Calibration, **asdict(RECIPE))

# The [network] table of a kind that trains, and the keys of a [[methods]] entry.
NETWORK = Table(keys_of(NetworkSettings))


@dataclass(frozen=True, kw_only=True)
class MethodEntry:
    """A [[methods]] entry: resolved to a learn.protocol.Method by method()."""

    adapter: str = setting(
        str,
        doc="adapter (source_only, target_only, mmd, dann, coral, finetune) or detector plugin "
        "(likelihood_ratio, matched_filter)",
    )
    supervised: bool = setting(bool, False, doc="use the target training labels")
    params: dict = setting(dict, {}, doc="its parameters")


METHOD_KEYS = keys_of(MethodEntry)


def check_training(t: dict, path) -> None:
    """The [protocol] epochs of a kind that trains the chapter-5 way (transfer, detection)."""
    p = t["protocol"]
    if p["min_epochs"] > p["max_epochs"]:
        raise GearlabInputError(
            f"{location(path, 'protocol', 'min_epochs')}: {p['min_epochs']} is larger than "
            f"max_epochs = {p['max_epochs']}"
        )


def method(
    entry: dict, where: str, false_alarm: float | None = None, rate_key: str = "[protocol] false_alarm"
) -> Method:
    """A [[methods]] entry: the adapter or detector by name (one lookup: key 'adapter' names
    either), its supervision variant and parameters. A detector's false-alarm rate is the
    scenario's one (*false_alarm*, the value of *rate_key*; None: the detector's default), which
    an entry's params may not set again."""
    plugin = get_registry().get(METHODS, entry["adapter"], f"{where} key 'adapter'")
    mode = "supervised" if entry["supervised"] else "unsupervised"
    if mode not in plugin.supervision:
        raise GearlabInputError(
            f"{where} key 'supervised': {plugin.kind} '{plugin.name}' has no {mode} variant "
            f"(it has: {', '.join(plugin.supervision)})"
        )
    given = dict(entry["params"])
    if plugin.kind == "detector":
        if "false_alarm" in given:
            raise GearlabInputError(f"{where} key 'params': false_alarm is set once for the scenario: {rate_key}")
        if false_alarm is not None:
            given["false_alarm"] = false_alarm  # resolved as the detector's own, not shown in its label
    params = plugin.resolve(given, f"{where} key 'params'")
    return Method(
        plugin.name, entry["supervised"], tuple(sorted(params.items())), tuple(sorted(entry["params"].items()))
    )


_LOADED: dict = {}  # this process's datasets read from the cache: path -> (stamp, dataset)


def loaded(spec, path):
    """The cached dataset of *spec* at *path*, read once per process while its entry stays the
    same file (its key, size and modification time): a worker's units share their two datasets,
    which each read again and checked (sha256) for 30 ms of CPU, 14 s of Experiment B's 450 units
    (issue 42). Its arrays are made read-only: no unit may change what the next one reads."""
    if path is None:  # the spec's own entry: the cache finds it
        return cache.load(spec, path)
    try:
        stat = path.stat()
    except OSError:
        return cache.load(spec, path)  # gone: the cache's own answer
    stamp = (cache.entry_key(spec), stat.st_mtime_ns, stat.st_size)
    hit = _LOADED.get(path)
    if hit is not None and hit[0] == stamp:
        return hit[1]
    dataset = cache.load(spec, path)
    if dataset is not None:
        for name in cache.ARRAYS:
            getattr(dataset, name).setflags(write=False)
        if len(_LOADED) >= 4:
            _LOADED.pop(next(iter(_LOADED)))
        _LOADED[path] = (stamp, dataset)
    return dataset


def train_unit(task: tuple) -> dict:
    """One unit of work, in this process or a worker: the datasets come from the cache (they
    were built before), shared states from the run directory. One torch thread per unit,
    so that a result does not depend on how many workers run side by side. An eighth element,
    when there is one, is the fixed target history (gearlab.learn.protocol.split)."""
    protocol, (source_spec, source_path), (target_spec, target_path), rep, k, method, states, *history = task
    # states/ lies in the run directory, beside the progress/ folder the engine watches
    with UnitProgress(states.root, unit_key(rep, k, method)) as progress:
        # seconds in a fresh worker before any epoch (a quick run's 'starting' line stood 10 s at load
        # 9): each step says itself, and one that stands says for how long (UnitProgress)
        progress("starting: importing torch")
        # torch loads here, not at the top (checking a scenario loads none); the caller's thread count back after
        with one_thread():
            progress("starting: reading dataset 1 of 2 (source)")
            source = loaded(source_spec, source_path)
            progress("starting: reading dataset 2 of 2 (target)")
            target = loaded(target_spec, target_path)
            progress("starting: splitting the data")

            def report(epoch: int, history, what: str = "") -> None:
                acc = f", source validation accuracy {100 * history.val_acc[-1]:.1f} %" if history.val_acc else ""
                progress(f"{what or f'epoch {epoch + 1}'}{acc}")

            with saying(progress):  # the calibration's and the priming's steps (unit_says) reach the line too
                return run_unit(
                    protocol,
                    source,
                    target,
                    rep,
                    k,
                    method,
                    StateStore(states),
                    on_epoch=report,
                    history=next(iter(history), None),
                )
