"""The chapter-5 transfer protocol (thesis 5.4.2) and the `transfer` kind's runs.

Small synthetic datasets (short signals, the `fast` network) and a few epochs keep the unit
tests quick; the run tests use tiny simulated datasets through a scenario file.
"""

import json
import os
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from tiny import BASELINES_AND_MMD, bare_dataset, protocol, run_once
from tiny import transfer as tiny_scenario

from gearlab.data.cache import load_or_build
from gearlab.data.spec import Dataset
from gearlab.engine import load_scenario, run_scenario
from gearlab.errors import GearlabInputError
from gearlab.kinds import transfer
from gearlab.kinds.common import planned_counts
from gearlab.learn import calibration as C
from gearlab.learn import protocol as P
from gearlab.learn import training as T
from gearlab.learn.calibration import RECIPE, THESIS
from gearlab.learn.protocol import (
    Counts,
    Protocol,
    StateStore,
    check,
    check_data,
    run_unit,
    split,
    train_method,
)
from gearlab.parts import training
from gearlab.parts.bound import BOUND
from gearlab.runs import RunDir

pytestmark = pytest.mark.usefixtures("one_torch_thread", "trained_once")


def synthetic(faults: int, healthy: int, length: int = 256, seed: int = 0, offset: float = 0.0) -> Dataset:
    """Healthy rows: a tone in noise; fault rows add an impulse train. Fault rows come first."""
    rng = np.random.default_rng(seed)
    n = faults + healthy
    fault = (np.arange(n) < faults).astype(np.int8)
    X = rng.normal(size=(n, length)) + np.sin(np.arange(length) / 5.0) + offset
    X[fault == 1, ::32] += 4.0
    return bare_dataset(X.astype(np.float32), fault)


SOURCE = synthetic(20, 30, seed=1)
TARGET = synthetic(12, 28, seed=2, offset=0.5)


def method(adapter: str, supervised: bool = False, **params):
    return training.method({"adapter": adapter, "supervised": supervised, "params": params}, "test")


METHODS = (
    method("source_only"),
    method("target_only", True),
    method("mmd"),
    method("mmd", True),
    method("dann"),
    method("coral", True),
    method("finetune", True, variant="classifier"),
    method("matched_filter"),
    method("matched_filter", True),
    method("likelihood_ratio"),
    method("likelihood_ratio", True),
)


def tiny(**changes) -> Protocol:
    base = protocol(METHODS, ks=(0, 2), repetitions=2, baseline_epochs=3, max_epochs=3, dropout=0.1)
    return replace(base, **changes)


def same_record(a: dict, b: dict) -> bool:
    keep = lambda r: {k: v for k, v in r.items() if k != "_latent"}  # noqa: E731
    return keep(a) == keep(b) and all(np.array_equal(a["_latent"][d], b["_latent"][d]) for d in a.get("_latent", {}))


# ----------------------------------------------------------------------------- split


@pytest.mark.parametrize("k", [0, 1, 2, 4, 12])
@pytest.mark.parametrize("rep", [0, 3])
def test_split_has_k_faults_and_disjoint_covering_target_sets(k, rep):
    p = tiny()
    s = split(p, SOURCE, TARGET, rep, k)
    assert (TARGET.fault[s.target_train] == 1).sum() == k
    assert (TARGET.fault[s.target_train] == 0).sum() == p.target_train - k
    assert np.intersect1d(s.target_train, s.target_test).size == 0
    assert np.array_equal(np.union1d(s.target_train, s.target_test), np.arange(len(TARGET)))
    assert np.intersect1d(s.source_train, s.source_val).size == 0
    assert np.array_equal(np.union1d(s.source_train, s.source_val), np.arange(len(SOURCE)))


def test_splits_are_nested_across_k_and_the_history_core_is_in_every_training_set():
    p = tiny(ks=(0, 1, 2, 4))
    splits = [split(p, SOURCE, TARGET, 1, k) for k in p.ks]
    for small, large in zip(splits, splits[1:]):
        grown = np.setdiff1d(large.target_train, small.target_train)
        assert (TARGET.fault[grown] == 1).all()  # k grows by faults, healthy ones make room
        assert np.isin(np.setdiff1d(small.target_train, large.target_train), np.flatnonzero(TARGET.fault == 0)).all()
    core = splits[0].history_core
    assert len(core) == p.target_train - max(p.ks) and (TARGET.fault[core] == 0).all()
    assert all(np.isin(core, s.target_train).all() and not np.isin(core, s.target_test).any() for s in splits)
    assert all(np.array_equal(core, s.history_core) for s in splits)


@pytest.mark.parametrize("ks", [(0, 11), (12,)])
def test_a_k_that_leaves_no_history_core_is_refused_with_the_key(ks):
    with pytest.raises(
        GearlabInputError,
        match=r"s.toml: \[protocol\] key 'ks': k = 1[12] fault samples do not fit .* 2 healthy ones left",
    ):
        check(tiny(ks=ks), "s.toml")
    check(tiny(ks=(0, 10)), "s.toml")  # 2 healthy left: runs


def test_split_is_fixed_by_seed_repetition_and_k():
    p = tiny()
    a, b = split(p, SOURCE, TARGET, 1, 2), split(p, SOURCE, TARGET, 1, 2)
    assert all(np.array_equal(getattr(a, f), getattr(b, f)) for f in a.__dataclass_fields__)
    others = [
        split(p, SOURCE, TARGET, 2, 2),
        split(p, SOURCE, TARGET, 1, 4),
        split(replace(p, seed=5), SOURCE, TARGET, 1, 2),
    ]
    assert all(not np.array_equal(a.target_train, o.target_train) for o in others)
    # the source split belongs to the repetition: every k of it is primed on the same samples
    assert np.array_equal(a.source_train, others[1].source_train)
    assert not np.array_equal(a.source_train, others[0].source_train)


# ----------------------------------------------------------------------------- leak-proofness


def scrambled_test_set(dataset: Dataset, test: np.ndarray, signals: bool) -> Dataset:
    """The dataset with every target *test* label flipped (and, with *signals*, its rows replaced)."""
    fault = dataset.fault.copy()
    fault[test] = 1 - fault[test]
    X = dataset.X.copy()
    if signals:
        X[test] = np.random.default_rng(99).normal(size=(len(test), X.shape[1])) * 7
    return replace(dataset, X=X, fault=fault, label=fault.copy())


@pytest.mark.parametrize(
    "calibration, network",
    [(THESIS, "burst"), (RECIPE, "burst"), (RECIPE, "shapes")],
    ids=["thesis", "recipe", "recipe-shapes"],
)
@pytest.mark.parametrize("m", METHODS, ids=lambda m: m.key)
def test_target_test_samples_cannot_reach_training_stopping_or_selection(m, calibration, network, monkeypatch):
    """With the split fixed, flipping the target test labels and replacing the test signals
    changes nothing of the trained model, its training curves or the epoch kept; only the
    score. No training function is ever handed a target test row: not the networks' training,
    nor the calibration's references, noise level and history threshold (gearlab's recipe),
    nor the `shapes` network's templates (built at the data's length, 256 samples)."""
    p, k = tiny(calibration=calibration, network=network), 2
    fixed = split(p, SOURCE, TARGET, 0, k)
    monkeypatch.setattr(P, "split", lambda *args: fixed)
    models, handed = [], []
    train_method = P.train_method

    def keep_model(*args, **kwargs):
        model, history, extra = train_method(*args, **kwargs)
        models.append({name: t.clone() for name, t in model.state_dict().items()})
        return model, history, extra

    def spy(fn):
        def wrapped(*args, **kwargs):
            handed.extend(a for a in [*args, *kwargs.values()] if isinstance(a, (np.ndarray, tuple)))
            return fn(*args, **kwargs)

        return wrapped

    monkeypatch.setattr(P, "train_method", keep_model)
    # the protocol imports these where it trains (start-up time): spied on in their modules
    for module, name in ((T, "fit_supervised"), (T, "fit_adaptation"), (T, "embed"), (C, "prepare"), (C, "calibrate")):
        monkeypatch.setattr(module, name, spy(getattr(module, name)))
    registry = P.get_registry()
    for name in registry.names("detector"):  # every detector: its arrays are its training
        detector = registry.get("detector", name)
        monkeypatch.setattr(detector, "fit", spy(detector.fit))
    # target rows carry their index in the first sample, to be recognised wherever they go
    marked = replace(TARGET, X=TARGET.X.copy())
    marked.X[:, 0] = 1000 + np.arange(len(marked))
    runs = [
        run_unit(p, SOURCE, data, 0, k, m, StateStore(None))
        for data in (
            marked,
            scrambled_test_set(marked, fixed.target_test, signals=False),
            scrambled_test_set(marked, fixed.target_test, signals=True),
        )
    ]

    for model in models[1:]:
        assert model.keys() == models[0].keys()
        assert all(torch.equal(model[name], models[0][name]) for name in model)
    for r in runs[1:]:
        assert r["history"] == runs[0]["history"]
        assert r["source_val_accuracy"] == runs[0]["source_val_accuracy"]
        if "_latent" in r:
            assert all(np.array_equal(r["_latent"][d], runs[0]["_latent"][d]) for d in r["_latent"])
    # the same predictions scored against flipped labels: the test set is used, for the score only
    assert runs[1]["accuracy"] == pytest.approx(100.0 - runs[0]["accuracy"])
    assert runs[1]["confusion"] == [runs[0]["confusion"][1], runs[0]["confusion"][0]]

    test_marks = 1000 + fixed.target_test
    rows = [
        a for x in handed for a in (x if isinstance(x, tuple) else (x,)) if isinstance(a, np.ndarray) and a.ndim == 2
    ]
    assert rows, "the spies saw no training arrays"
    assert not any(np.isin(a[:, 0], test_marks).any() for a in rows)
    if m.adapter != "source_only":  # the spies do see the target training rows
        assert any(np.isin(a[:, 0], 1000 + fixed.target_train).any() for a in rows)


# ----------------------------------------------------------------------------- priming, determinism


def test_shared_states_are_made_once_per_repetition_and_change_no_result(tmp_path):
    p = tiny(methods=(method("source_only"), method("mmd"), method("finetune", True, variant="last")))
    made = []

    class Counting(StateStore):
        def get(self, name, make):
            return super().get(name, lambda: made.append(name) or make())

    store = Counting(tmp_path / "states")
    records = [
        run_unit(p, SOURCE, TARGET, rep, k, m, store) for rep in range(p.repetitions) for k in p.ks for m in p.methods
    ]
    assert sorted(made) == ["rep0_primed", "rep0_source_only", "rep1_primed", "rep1_source_only"]
    # a unit gives the same record run alone (making the priming), after others (sharing it)
    # and in a new process (loading it from disk, as a resumed run does)
    last = records[-1]
    rep, k, m = p.repetitions - 1, p.ks[-1], p.methods[-1]
    assert same_record(run_unit(p, SOURCE, TARGET, rep, k, m, StateStore(None)), last)
    assert same_record(run_unit(p, SOURCE, TARGET, rep, k, m, StateStore(tmp_path / "states")), last)
    first_calibrated = records[1]
    assert same_record(
        run_unit(p, SOURCE, TARGET, 0, 0, p.methods[1], StateStore(tmp_path / "states")), first_calibrated
    )


def test_the_recipe_primes_once_per_repetition_from_the_history_core(tmp_path, monkeypatch):
    """The recipe's priming carries the target history's noise level and reference; it reads
    them off the history core (the healthy samples every k's training set shares), so one
    priming serves every k and every calibrated method of the repetition, and it never sees
    a row that some k tests on."""
    p = tiny(methods=(method("mmd"), method("dann"), method("finetune", True, variant="last")), calibration=RECIPE)
    made, primed_on = [], []

    class Counting(StateStore):
        def get(self, name, make):
            return super().get(name, lambda: made.append(name) or make())

    real = C.prepare
    monkeypatch.setattr(C, "prepare", lambda c, Xs, ys, Xt, yt: primed_on.append(Xt) or real(c, Xs, ys, Xt, yt))
    store = Counting(tmp_path / "states")
    for rep in range(p.repetitions):
        for k in p.ks:
            for m in p.methods:
                run_unit(p, SOURCE, TARGET, rep, k, m, store)
    assert sorted(made) == ["rep0_primed", "rep1_primed"]
    tested = [TARGET.X[split(p, SOURCE, TARGET, 0, k).target_test] for k in p.ks]
    core = TARGET.X[split(p, SOURCE, TARGET, 0, 0).history_core]
    assert any(np.array_equal(X, core) for X in primed_on)
    assert not any((row == X).all(1).any() for X in tested for row in core)


def _finetuned_weights_moved(variant: str, network: str = "burst") -> set[str]:
    """The state entries a finetune *variant* changed from the repetition's priming."""
    p = tiny(methods=(method("finetune", True, variant=variant),), network=network)
    store = StateStore(None)
    s = split(p, SOURCE, TARGET, 0, 2)
    source = (SOURCE.X[s.source_train], SOURCE.fault[s.source_train].astype(np.int64))
    val = (SOURCE.X[s.source_val], SOURCE.fault[s.source_val].astype(np.int64))
    target = (TARGET.X[s.target_train], TARGET.fault[s.target_train].astype(np.int64))
    net, _, _ = train_method(p, p.methods[0], source, val, target, 0, 2, store, torch.device("cpu"))
    primed = store.memory["rep0_primed"]
    return {
        name
        for name, value in net.state_dict().items()
        if value.dtype.is_floating_point and not torch.equal(value, primed[name])
    }


@pytest.mark.parametrize(
    "variant, changed",
    [("all", {"features", "classifier"}), ("classifier", {"classifier"}), ("last", {"classifier.3"})],
)
def test_finetune_variants_retrain_only_their_layers_from_the_priming(variant, changed):
    moved = _finetuned_weights_moved(variant)
    assert moved and all(any(name.startswith(c + ".") for c in changed) for name in moved)
    if variant == "last":
        assert moved == {"classifier.3.weight", "classifier.3.bias"}


def test_finetune_last_of_shapes_retrains_its_mixture_weights_only():
    """`shapes`' classifier is one layer (the mixture): 'last' retrains its log weights, no template."""
    assert _finetuned_weights_moved("last", network="shapes") == {"classifier.log_weight"}


def test_adapter_parameters_reach_training():
    p = tiny(methods=(method("mmd"), method("mmd", lambda_max=0.2)))
    default, capped = (run_unit(p, SOURCE, TARGET, 0, 0, m, StateStore(None)) for m in p.methods)
    assert max(default["history"]["lam"]) == 1.0
    assert max(capped["history"]["lam"]) == 0.2


@pytest.mark.parametrize("m", [method("target_only", True), method("dann", True)], ids=lambda m: m.key)
def test_same_seed_same_record_on_cpu(m):
    p = tiny()
    a, b = (run_unit(p, SOURCE, TARGET, 1, 2, m, StateStore(None)) for _ in range(2))
    assert same_record(a, b)
    c = run_unit(replace(p, seed=3), SOURCE, TARGET, 1, 2, m, StateStore(None))
    assert c["history"] != a["history"]


# ----------------------------------------------------------------------------- checks on the data


@pytest.mark.parametrize(
    "source, target, changes, message",
    [
        (Counts("s", 256, 30, 20), Counts("t", 128, 28, 12), {}, "different lengths (256 and 128)"),
        (
            Counts("s", 256, 30, 20),
            Counts("t", 256, 28, 1),
            {},
            "k = 2 target fault samples asked for, the target 't' has",
        ),
        (Counts("s", 256, 30, 20), Counts("t", 256, 11, 12), {}, "needs 12 healthy samples, the target 't' has 11"),
        (Counts("s", 256, 30, 20), Counts("t", 256, 12, 0), {"ks": (0,)}, "leaves no target test samples"),
        (Counts("s", 256, 2, 2), Counts("t", 256, 28, 12), {}, "larger than the source training set (3 of the 4"),
    ],
)
def test_data_the_protocol_cannot_use_is_refused(source, target, changes, message):
    with pytest.raises(GearlabInputError, match=re.escape(message)):
        check_data(tiny(**changes), source, target, "s.toml")


def test_protocol_that_cannot_fit_is_refused():
    with pytest.raises(GearlabInputError, match="k = 16 fault samples do not fit"):
        check(tiny(ks=(0, 16)), "s.toml")
    with pytest.raises(GearlabInputError, match="'batch': 13 is larger than the target training set"):
        check(tiny(batch=13), "s.toml")


def test_labels_and_keys_show_only_what_the_scenario_set():
    assert method("mmd").label == "mmd (unsupervised)"
    assert method("finetune", True, variant="classifier").label == "finetune (supervised, variant=classifier)"
    assert method("finetune", True, variant="classifier").key == "finetune-sup-variant=classifier"
    assert dict(method("mmd").params)["lambda_step"] == 0.05  # training still gets every parameter
    assert dict(method("finetune", True, variant="classifier").params) == {"variant": 1}


# ----------------------------------------------------------------------------- runs


def test_results_store_skips_cut_and_damaged_lines_without_hiding_later_ones(tmp_path):
    run = RunDir(tmp_path)
    run.append({"unit": "a"})
    with open(run.results_path, "a") as f:
        f.write('{"unit": "damag\n')
    run.append({"unit": "b"})
    with open(run.results_path, "a") as f:
        f.write('{"unit": "c", "accu')  # killed mid-write
    assert [r["unit"] for r in run.records()] == ["a", "b"]
    run.truncate_partial()
    assert run.results_path.read_text().endswith('"b"}\n')
    run.append({"unit": "c"})
    assert [r["unit"] for r in run.records()] == ["a", "b", "c"]


TINY = tiny_scenario(
    BASELINES_AND_MMD
    + """
[[methods]]
adapter = "finetune"
supervised = true
params = { variant = "classifier" }
""",
    repetitions=2,
)
UNITS = [
    f"rep{r}/k{k}/{m}"
    for r in (0, 1)
    for k in (0, 2)
    for m in ("source_only-unsup", "target_only-sup", "mmd-unsup", "finetune-sup-variant=classifier")
]


@pytest.fixture
def tiny_toml(write_scenario, module_cache):
    return write_scenario(TINY, "tiny.toml")


@pytest.fixture(scope="module")
def finished(tmp_path_factory, module_cache):
    return run_once(tmp_path_factory.mktemp("finished"), "tiny.toml", TINY, module_cache)


def lines_of(run: Path) -> list[str]:
    return (run / "results.jsonl").read_text().splitlines(keepends=True)


def by_unit(run: Path) -> dict[str, dict]:
    return {r["unit"]: r for r in map(json.loads, lines_of(run))}


@pytest.fixture
def no_transfer_figures(monkeypatch) -> None:
    """A transfer run's figures not drawn (gearlab.kinds.transfer_figures.draw), for a test that reads
    only its records, summary and tables; test_summary_table_and_report reads the figures of `finished`."""
    monkeypatch.setattr("gearlab.kinds.transfer_figures.draw", lambda *args: None)


def test_two_workers_give_the_records_of_one(finished, tiny_toml, no_transfer_figures):
    tiny_toml.write_text(TINY.replace("workers = 1", "workers = 2"))
    parallel = by_unit(run_scenario(tiny_toml, out=tiny_toml.parent / "runs").path)
    assert parallel == by_unit(finished)


def test_planned_class_counts_are_those_built(finished, tiny_toml):
    spec = load_scenario(tiny_toml).spec
    for side, data in (("source", spec.source), ("target", spec.target)):
        built, cached = load_or_build(data)
        assert cached
        assert planned_counts(data, side) == Counts.of(built)


def test_summary_table_and_report(finished, cli):
    summary = json.loads((finished / "summary.json").read_text())
    labels = [
        "source_only (unsupervised)",
        "mmd (unsupervised)",
        "target_only (supervised)",
        "finetune (supervised, variant=classifier)",
    ]
    assert summary["methods"] == labels  # Table 5.4's column order: unsupervised, then supervised
    assert set(summary["table"]) == set(labels)
    records = by_unit(finished)
    assert sorted(records) == sorted(UNITS)
    for label in labels:
        assert set(summary["table"][label]) == {"0", "2"}
        for k, cell in summary["table"][label].items():
            acc = [r["accuracy"] for r in records.values() if r["method"] == label and r["k"] == int(k)]
            assert cell["mean"] == pytest.approx(np.mean(acc)) and cell["std"] == pytest.approx(np.std(acc, ddof=1))
    # the reference column: the Bayes detector on the same test sets (the tiny target is noisy)
    bound = summary["bound"]
    assert bound["noise"] == "laplace" and set(bound["accuracy"]) == {"0", "2"}
    assert all(50.0 <= c["mean"] <= 100.0 and c["n"] == 2 for c in bound["accuracy"].values())
    assert set(summary["balanced_accuracy"]) == set(labels) and set(summary["detection_at_1pct"]) == set(labels)
    for r in records.values():
        healthy, faulty = r["confusion"]
        recall = 50.0 * (healthy[0] / sum(healthy) + faulty[1] / sum(faulty))
        assert r["balanced_accuracy"] == pytest.approx(recall)
    md = (finished / "table.md").read_text().splitlines()
    md = md[: md.index("")]  # the accuracy table; the balanced accuracy and detection rates follow
    assert md[0] == "| k (target fault samples) | " + " | ".join([*labels, BOUND]) + " |"
    assert [row.split("|")[1].strip() for row in md[2:]] == ["0", "2"]
    assert all(re.fullmatch(r"\d+\.\d\d ± \d+\.\d", c.strip()) for row in md[2:] for c in row.split("|")[2:-1])

    (finished / "report.html").unlink()
    code, _, err = cli("report", finished)
    assert code == 0, err
    html = (finished / "report.html").read_text()
    assert "finetune (supervised, variant=classifier)" in html and "data:image/png;base64," in html


def test_killed_run_resumes_without_losing_or_repeating_a_unit(
    finished, tiny_toml, cli, monkeypatch, no_transfer_figures
):
    # Killed inside the first calibrated unit, after its priming was saved; then a record cut
    # short mid-write, as a kill leaves it.
    with monkeypatch.context() as mp:

        def killed(*args, **kwargs):
            raise KeyboardInterrupt

        mp.setattr(T, "fit_adaptation", killed)  # the protocol imports it where it trains
        with pytest.raises(KeyboardInterrupt):
            run_scenario(tiny_toml, out=tiny_toml.parent / "runs")
    (run,) = (tiny_toml.parent / "runs" / "tiny").iterdir()
    before = lines_of(run)
    kept = [json.loads(line)["unit"] for line in before]
    assert kept and set(kept) < set(UNITS)
    assert (run / "states" / "rep0_primed.pt").exists()  # one priming per repetition, saved before the unit died
    with open(run / "results.jsonl", "a") as f:
        f.write(json.dumps({"unit": next(u for u in UNITS if u not in kept), "accuracy": 0.0})[:25])

    ran = []
    real = training.run_unit
    monkeypatch.setattr(training, "run_unit", lambda *a, **kw: ran.append(a[3:5]) or real(*a, **kw))
    code, out, err = cli("run", "--resume", run)
    assert code == 0, err
    assert out.splitlines()[-1] == f"run directory: {run}"
    assert len(ran) == len(UNITS) - len(kept)
    after = lines_of(run)
    assert after[: len(before)] == before  # finished units untouched
    assert all(line.endswith("\n") for line in after)
    assert sorted(json.loads(line)["unit"] for line in after) == sorted(UNITS)  # each exactly once
    # nothing differs from the run that was never interrupted
    assert by_unit(run) == by_unit(finished)
    assert (
        json.loads((run / "summary.json").read_text())["table"]
        == json.loads((finished / "summary.json").read_text())["table"]
    )
    assert (run / "table.md").read_text() == (finished / "table.md").read_text()


def test_last_line_of_a_run_is_the_run_directory(finished, tiny_toml, cli, monkeypatch, unrendered_figures):
    # A finished run resumed: nothing left to train, the outputs rewritten (the figures unrendered:
    # test_summary_table_and_report reads the figures of `finished`).
    monkeypatch.setattr(training, "run_unit", lambda *a, **kw: pytest.fail("a finished unit ran again"))
    code, out, err = cli("run", tiny_toml, "--resume", finished)
    assert code == 0, err
    assert out.splitlines()[-1] == f"run directory: {finished}"
    assert re.search(r"^[│┃] 0 +[│┃]", out, re.M)  # the accuracy table's row k = 0, drawn by rich


# ----------------------------------------------------------------------------- bad input


def edit(text: str, old: str, new: str) -> str:
    assert old in text
    return text.replace(old, new, 1)


BAD = {
    "network": (
        ('name = "fast"', 'name = "fsat"'),
        "[network] key 'name': unknown network 'fsat' (did you mean 'fast'?); known networks: cnn3, fast",
    ),
    "adapter": (
        ('adapter = "mmd"', 'adapter = "mdd"'),
        "unknown adapter 'mdd' (did you mean 'mmd'?); known adapters: ",
    ),
    "variant": (
        ("supervised = true\nparams", "supervised = false\nparams"),
        "[[methods]] #4 key 'supervised': adapter 'finetune' has no unsupervised variant (it has: supervised)",
    ),
    "param": (
        ('variant = "classifier"', 'varient = "classifier"'),
        "unknown parameter 'varient' (did you mean 'variant'?)",
    ),
    "same method": (
        ('adapter = "finetune"\nsupervised = true\nparams = { variant = "classifier" }', 'adapter = "mmd"'),
        "[[methods]] #4: mmd (unsupervised) is the same method as #3, mmd (unsupervised)",
    ),
    "same method spelt otherwise": (
        ('adapter = "mmd"', 'adapter = "finetune"\nsupervised = true\nparams = { variant = 1 }'),
        "[[methods]] #4: finetune (supervised, variant=classifier)"
        " is the same method as #3, finetune (supervised, variant=1)",
    ),
    "detector false_alarm": (
        ('adapter = "mmd"', 'adapter = "matched_filter"\nparams = { false_alarm = 0.05 }'),
        "[[methods]] #3 key 'params': false_alarm is set once for the scenario: [protocol] false_alarm",
    ),
    "k > faults": (
        ("ks = [0, 2]", "ks = [0, 4]"),
        "[protocol] key 'ks': k = 4 target fault samples asked for, the target 'B-8-ch5' has 3",
    ),
    "k > target_train": (("ks = [0, 2]", "ks = [0, 9]"), "k = 9 fault samples do not fit"),
    "healthy": (("target_train = 8", "target_train = 10"), "needs 10 healthy samples, the target 'B-8-ch5' has 9"),
    "batch > target_train": (
        ("batch = 4", "batch = 9"),
        "[protocol] key 'batch': 9 is larger than the target training set (target_train = 8)",
    ),
    "batch > source": (
        ("faults = { crack = [13] }\nhealthy = 9", "faults = { crack = [13] }\nhealthy = 1"),
        "'batch': 4 is larger than the source training set (3 of the 4 samples of 'B-6-ch5')",
    ),
    "protocol key": (
        ("repetitions = 2", "repetitons = 2"),
        "[protocol] key 'repetitons': unknown key (did you mean 'repetitions'?)",
    ),
    **{
        f"ks {case}": (("ks = [0, 2]", f"ks = {ks}"), "[protocol] key 'ks': expected a list of distinct whole numbers")
        for case, ks in (("fraction", "[0, 1.5]"), ("repeated", "[2, 2]"), ("empty", "[]"))
    },
    "ks text": (("ks = [0, 2]", 'ks = "0, 2"'), "[protocol] key 'ks': expected a list, got str"),
    "epochs": (("min_epochs = 2", "min_epochs = 5"), "[protocol] key 'min_epochs': 5 is larger than max_epochs = 3"),
}


def assert_refused(code: int, err: str, message: str, runs: Path, alone: bool = True) -> None:
    """Exit code 2, the error as one line (the only output of a run refused before any work),
    and no run files left."""
    assert code == 2, err
    lines = err.splitlines()
    assert lines[-1].startswith("error: ") and message in lines[-1], err
    assert not alone or len(lines) == 1, err
    assert not runs.exists() or not any(runs.rglob("*")), "a refused run left files behind"


@pytest.mark.parametrize("case", list(BAD))
def test_bad_scenario_is_refused_before_any_work(case, tiny_toml, cli, monkeypatch):
    (old, new), message = BAD[case]
    tiny_toml.write_text(edit(TINY, old, new))
    monkeypatch.setattr(transfer, "load_or_build", lambda *a, **kw: pytest.fail("a dataset was built"))
    code, _, err = cli("run", tiny_toml, "--out", tiny_toml.parent / "runs")
    assert_refused(code, err, message, tiny_toml.parent / "runs")
    code, _, err = cli("validate", tiny_toml)
    assert code == 2 and message in err


def test_the_protocols_false_alarm_rate_is_the_detectors_too(tiny_toml):
    """One false-alarm rate a scenario: [protocol] false_alarm thresholds the 'history' networks and
    every detector; it is not a detector's parameter shown in its label or unit key."""
    tiny_toml.write_text(
        edit(
            edit(TINY, 'adapter = "mmd"', 'adapter = "matched_filter"'),
            "ks = [0, 2]",
            "ks = [0, 2]\nfalse_alarm = 0.05",
        )
    )
    protocol = load_scenario(tiny_toml).spec.protocol
    (detector,) = [m for m in protocol.methods if m.is_detector]
    assert protocol.calibration.false_alarm == dict(detector.params)["false_alarm"] == 0.05
    assert detector.label == "matched_filter (unsupervised)" and detector.key == "matched_filter-unsup"


def test_datasets_found_unfit_once_built_leave_no_run_behind(tiny_toml, cli, monkeypatch):
    # Measured data are only known once imported: here a target of another sample length.
    monkeypatch.setattr(
        transfer, "load_or_build", lambda spec, *a: (synthetic(3, 9, 4096 if spec.name == "B-6-ch5" else 2048), True)
    )
    runs = tiny_toml.parent / "runs"
    code, _, err = cli("run", tiny_toml, "--out", runs)
    assert_refused(code, err, "samples have different lengths (4096 and 2048)", runs, alone=False)
    # a run beside it is left alone
    older = runs / "tiny" / "older" / "results.jsonl"
    older.parent.mkdir(parents=True)
    older.write_text("{}\n")
    code, _, err = cli("run", tiny_toml, "--out", runs)
    assert code == 2 and [p for p in runs.rglob("*") if p.is_file()] == [older]


def test_unwritable_output_directory_is_refused(tiny_toml, cli):
    a_file = tiny_toml.parent / "a_file"
    a_file.write_text("")
    for out in (a_file, a_file / "runs"):
        code, _, err = cli("run", tiny_toml, "--out", out)
        assert_refused(code, err, f"cannot write the run directory under '{out}'", tiny_toml.parent / "nothing")
    assert a_file.read_text() == ""


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write to a read-only directory")
def test_read_only_output_directory_is_refused(tiny_toml, cli):
    locked = tiny_toml.parent / "locked"
    locked.mkdir(mode=0o555)
    try:
        code, _, err = cli("run", tiny_toml, "--out", locked / "runs")
        assert_refused(code, err, "cannot write the run directory", locked)
    finally:
        locked.chmod(0o755)


def test_resume_with_another_scenario_is_refused(finished, tiny_toml, cli):
    tiny_toml.write_text(edit(TINY, "max_epochs = 3", "max_epochs = 4"))
    code, _, err = cli("run", tiny_toml, "--resume", finished)
    assert code == 2 and "differs from the scenario the run in" in err


def test_resume_keeps_the_runs_quick_setting(finished, cli):
    assert RunDir.open(finished).quick is False
    code, _, err = cli("run", "--resume", finished, "--quick")
    assert code == 2 and "was started without --quick" in err


def test_no_training_step_moves_the_weights_further_than_the_clipped_gradient_allows():
    """A DANN unit of the full Experiment A run went from a loss of 1 to 5e20 and NaN (its
    network then called everything healthy). Every step is now bounded: the weights move by at
    most lr x MAX_GRAD_NORM. Plain SGD at lr 30 moved them by 3e10 in one epoch of 4 steps."""
    from gearlab.learn.networks import build_network
    from gearlab.learn.training import MAX_GRAD_NORM, fit_supervised

    rng = np.random.default_rng(0)
    X = rng.standard_normal((32, 512)).astype(np.float32)
    y = np.arange(32) % 2
    torch.manual_seed(0)
    net = build_network("fast", 2, length=512)
    start = [p.detach().clone() for p in net.parameters()]
    history = fit_supervised(
        net, X, y, rng=rng, device=torch.device("cpu"), epochs=1, batch=8, optimizer="sgd", lr=30.0, patience=None
    )
    moved = float(torch.sqrt(sum(((p.detach() - q) ** 2).sum() for p, q in zip(net.parameters(), start))))
    assert moved <= 4 * 30.0 * MAX_GRAD_NORM * (1 + 1e-5)
    assert np.all(np.isfinite(history.train_loss))


@pytest.mark.parametrize("law", ["gaussian", "laplace", "student_t"])
def test_shapes_scores_its_templates_in_the_history_noise_law(law):
    """The `shapes` network's law is read off the target history (its residuals' kurtosis), as
    `likelihood_ratio`'s is: a target with Gaussian or Student-t noise is not scored as Laplace."""
    from gearlab.learn.networks import ShapeLikelihood

    rng = np.random.default_rng(5)
    noise = {
        "gaussian": rng.normal,
        "laplace": rng.laplace,
        "student_t": lambda size: rng.standard_t(2, size=size),
    }[law](size=TARGET.X.shape)
    target = replace(TARGET, X=(np.sin(np.arange(256) / 5.0) + noise).astype(np.float32))
    p, k = tiny(calibration=RECIPE, network="shapes"), 0
    s = split(p, SOURCE, target, 0, k)
    model, _, _ = train_method(
        p,
        method("mmd"),
        (SOURCE.X[s.source_train], SOURCE.fault[s.source_train].astype(np.int64)),
        (SOURCE.X[s.source_val], SOURCE.fault[s.source_val].astype(np.int64)),
        (target.X[s.target_train], target.fault[s.target_train].astype(np.int64)),
        0,
        k,
        StateStore(None),
        "cpu",
        core=target.X[s.history_core],
    )
    laws = {m.law for m in model.modules() if isinstance(m, ShapeLikelihood)}
    assert laws == {law}


def test_a_worker_reads_each_dataset_once(finished, tiny_toml, no_transfer_figures, monkeypatch):
    """A process's units share its two datasets, read from the cache once (issue 42: each unit read
    and checked both again, 30 ms of CPU each time), read-only; the records are the same."""
    from types import SimpleNamespace

    from gearlab.data import cache

    loads = []
    spy = lambda *a, **kw: loads.append(a[0].name) or cache.load(*a, **kw)  # noqa: E731
    monkeypatch.setattr(training, "_LOADED", {})
    monkeypatch.setattr(training, "cache", SimpleNamespace(load=spy, entry_key=cache.entry_key, ARRAYS=cache.ARRAYS))
    run_scenario(tiny_toml, out=tiny_toml.parent / "runs")
    (run,) = (tiny_toml.parent / "runs" / "tiny").iterdir()
    assert by_unit(run) == by_unit(finished)
    assert sorted(loads) == ["B-6-ch5", "B-8-ch5"]  # the units' reads, for 16 units
    assert all(not d.X.flags.writeable for _, d in training._LOADED.values())
