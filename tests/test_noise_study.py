"""The chapter-4 protocol and the `noise_study` scenario kind (thesis 4.2-4.4; docs/learning.md):
stratified splits that keep test samples out of training and model selection, the records
and the summary, resume, quick, and bad input.

Networks train on synthetic datasets (short signals whose class shows as a bump that grows
with the intensity step, buried in less noise for the TSA variant), so the file runs in
seconds; the kind's dataset builder is replaced by one that makes them from the spec."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from browser import check_report, chromium
from conftest import ROOT

import gearlab.kinds.noise_study as kind
import gearlab.learn.networks as networks
import gearlab.learn.noise_study as ns
import gearlab.learn.training as training
from gearlab.data.cache import save
from gearlab.data.spec import Dataset, dataset_preset
from gearlab.engine import load_scenario
from gearlab.errors import GearlabInputError
from gearlab.learn.noise_study import NoiseProtocol, aggregate, part_sizes, run_unit, scores, split
from gearlab.runs import RunDir

LENGTH = 128  # samples per synthetic revolution: the fast network accepts any length >= 64


pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))


def synthetic(spec) -> Dataset:
    """A dataset laid out as the builder lays it out (healthy first, then fault x step x tooth x
    duplicate); the fault class shows as a bump whose height grows with the step."""
    teeth = spec.teeth or tuple(range(1, 17))
    label, intensity, tooth = [0] * spec.healthy, [0] * spec.healthy, [0] * spec.healthy
    for c, (_, steps) in enumerate(spec.faults, start=1):
        for step in steps:
            for n in teeth:
                label += [c] * spec.duplicates
                intensity += [step] * spec.duplicates
                tooth += [n] * spec.duplicates
    label, intensity = np.array(label), np.array(intensity)
    std = 0.0 if spec.noise is None else 0.3 if spec.tsa else 1.0  # noise None: the noise-free twin
    rng = np.random.default_rng(len(label))
    X = (std * rng.standard_normal((len(label), LENGTH))).astype(np.float32)
    X += np.sin(2 * np.pi * 4 * np.arange(LENGTH) / LENGTH).astype(np.float32)  # the mesh: a revolution is never zero
    for i, (c, step) in enumerate(zip(label, intensity)):
        if c:
            X[i, 16 * c : 16 * c + 12] += 3.0 * step / 20
    n = len(label)
    return Dataset(
        spec=spec,
        X=X,
        label=label.astype(np.int8),
        fault=(label > 0).astype(np.int8),
        intensity=intensity.astype(np.int8),
        tooth=np.array(tooth, dtype=np.int8),
        rfa=(intensity / 40).astype(np.float32),
        revolution=np.zeros(n, dtype=np.int16),
        domain=np.zeros(n, dtype=np.int8),
        domains=(spec.name,),
    )


def small_spec(tsa: bool = False, **changes):
    few = dict(
        faults=tuple((f, (5, 10, 15, 20)) for f in ("crack", "chip", "spall", "pit")),
        teeth=(1, 2),
        duplicates=3,
        healthy=96,
    )
    return dataset_preset("A-casing_TSA-gaussian" if tsa else "A-casing_noise-gaussian").with_(**{**few, **changes})


@pytest.fixture
def fake_builder(monkeypatch):
    """Replace the kind's dataset loader by the synthetic one; list the datasets loaded."""
    made = []

    def load_or_build(spec, executor=None, on_event=None):
        made.append(spec.name if spec.noise is not None else f"{spec.name} (noise-free twin)")
        dataset = synthetic(spec)
        save(dataset)  # the training units load their datasets from the cache
        return dataset, False

    monkeypatch.setattr(kind, "load_or_build", load_or_build)
    return made


FAST = NoiseProtocol(epochs=6, patience=6, batch=32, device="cpu")


# --- the protocol --------------------------------------------------------------------------------


def test_split_is_stratified_disjoint_and_complete():
    label = np.repeat([0, 1, 2, 3, 4], [300, 90, 91, 92, 7])
    protocol = NoiseProtocol()
    s = split(label, protocol, run=0)
    parts = [s.train, s.val, s.test]
    assert sum(len(p) for p in parts) == len(label)
    assert len(np.unique(np.concatenate(parts))) == len(label)
    for c, n in zip(range(5), (300, 90, 91, 92, 7)):
        assert [int((label[p] == c).sum()) for p in parts] == list(part_sizes(n, protocol))
    n_train, n_val, n_test = part_sizes(1600, protocol)  # a fault class of Table 4.1
    assert n_test == 533 and n_val == round(0.2 * (1600 - 533)) and n_train + n_val + n_test == 1600


def test_split_depends_on_seed_and_run_only():
    label = np.repeat([0, 1, 2], [50, 20, 20])
    a, b = split(label, NoiseProtocol(), 0), split(label.copy(), NoiseProtocol(lr=0.1), 0)
    assert all(np.array_equal(x, y) for x, y in zip((a.train, a.val, a.test), (b.train, b.val, b.test)))
    assert not np.array_equal(a.test, split(label, NoiseProtocol(), 1).test)
    assert not np.array_equal(a.test, split(label, NoiseProtocol(seed=3), 0).test)


def test_test_samples_never_reach_training_or_model_selection(monkeypatch):
    data = synthetic(small_spec())
    data.X[:, 0] = np.arange(len(data.X))  # each row carries its own index
    seen = []
    real = training.fit_supervised  # the study imports it where it trains (start-up time)

    def spy(net, X, y, *, val, **kw):
        seen.append((X[:, 0].astype(int), val[0][:, 0].astype(int)))
        return real(net, X, y, val=val, **kw)

    monkeypatch.setattr(training, "fit_supervised", spy)
    record = run_unit(FAST, data, run=1)
    test = split(np.asarray(data.label, dtype=np.int64), FAST, 1).test
    ((train_rows, val_rows),) = seen
    assert not set(test) & set(train_rows) and not set(test) & set(val_rows)
    assert not set(train_rows) & set(val_rows)
    assert record["n_test"] == len(test) and record["n_train"] == len(train_rows) and record["n_val"] == len(val_rows)


def test_the_healthy_reference_of_the_residual_comes_from_the_training_part(monkeypatch):
    """residual = true: the training and validation arrays are the revolutions minus the
    training part's healthy median; replacing every test revolution changes none of them."""
    from dataclasses import replace

    protocol = replace(FAST, residual=True, epochs=1)
    handed = []
    real = training.fit_supervised  # the study imports it where it trains (start-up time)

    def spy(net, X, y, *, val, **kw):
        handed.append((X.copy(), val[0].copy()))
        return real(net, X, y, val=val, **kw)

    monkeypatch.setattr(training, "fit_supervised", spy)
    data = synthetic(small_spec())
    s = split(np.asarray(data.label, dtype=np.int64), protocol, 0)
    healthy = np.median(data.X[s.train[np.asarray(data.label)[s.train] == 0]], axis=0)
    run_unit(protocol, data, run=0)
    data.X[s.test] = np.random.default_rng(5).normal(size=data.X[s.test].shape) * 9
    run_unit(protocol, data, run=0)
    (X0, V0), (X1, V1) = handed
    assert np.array_equal(X0, X1) and np.array_equal(V0, V1)
    assert np.allclose(X0, data.X[s.train] - healthy, atol=1e-5)


def test_run_unit_record_learns_and_is_consistent():
    data = synthetic(small_spec(tsa=True))
    r = run_unit(FAST, data, run=0)
    for key in (
        "accuracy",
        "fault_as_healthy",
        "healthy_as_fault",
        "class_accuracy",
        "confusion",
        "by_step",
        "val_accuracy",
        "best_epoch",
        "stopped_epoch",
        "history",
        "classes",
        "key",
        "train_seconds",
    ):
        assert key in r, key
    cm = np.array(r["confusion"])
    assert cm.shape == (5, 5) and cm.sum() == r["n_test"]
    assert r["accuracy"] == pytest.approx(100 * np.trace(cm) / cm.sum())
    assert r["fault_as_healthy"] == pytest.approx(100 * cm[1:, 0].sum() / cm[1:].sum())
    for c, name in enumerate(r["classes"][1:], start=1):
        rows = r["by_step"][name]
        assert rows["steps"] == [5, 10, 15, 20]
        assert sum(rows["n"]) == cm[c].sum() and sum(rows["correct"]) == cm[c, c]
        assert sum(rows["as_healthy"]) == cm[c, 0]
        assert rows["rfa"] == pytest.approx([s / 40 for s in rows["steps"]])
    assert r["accuracy"] > 70  # the synthetic TSA set is easy
    again = run_unit(FAST, data, run=0)
    assert again["confusion"] == r["confusion"]  # deterministic on the CPU


def test_scores_by_hand():
    y = np.array([0, 0, 1, 1, 1, 2, 2])
    pred = np.array([0, 1, 1, 0, 0, 2, 0])
    intensity = np.array([0, 0, 5, 5, 20, 5, 20])
    s = scores(y, pred, intensity, intensity / 100.0, ("healthy", "crack", "chip"))
    assert s["accuracy"] == pytest.approx(100 * 3 / 7)
    assert s["fault_as_healthy"] == pytest.approx(100 * 3 / 5)
    assert s["healthy_as_fault"] == pytest.approx(50)
    assert s["confusion"] == [[1, 1, 0], [2, 1, 0], [1, 0, 1]]
    assert s["by_step"]["crack"] == {
        "steps": [5, 20],
        "rfa": [0.05, 0.2],
        "n": [2, 1],
        "correct": [1, 0],
        "as_healthy": [1, 1],
    }
    assert s["class_accuracy"] == pytest.approx({"healthy": 50, "crack": 100 / 3, "chip": 50})


def test_aggregate_over_runs():
    def record(acc, correct):
        return {
            "classes": ["healthy", "crack"],
            "accuracy": acc,
            "fault_as_healthy": 100 - acc,
            "healthy_as_fault": 0.0,
            "class_accuracy": {"healthy": 100.0, "crack": acc},
            "confusion": [[4, 0], [4 - correct, correct]],
            "by_step": {
                "crack": {
                    "steps": [1, 20],
                    "rfa": [0.0, 1.0],
                    "n": [2, 2],
                    "correct": [0, correct],
                    "as_healthy": [2, 2 - correct],
                }
            },
        }

    a = aggregate([record(50.0, 1), record(100.0, 2)])
    assert a["runs"] == 2
    assert a["accuracy"]["mean"] == 75.0 and a["accuracy"]["std"] == pytest.approx(np.std([50, 100], ddof=1))
    assert a["confusion"] == [[8, 0], [5, 3]]
    crack = a["curves"]["crack"]
    assert crack["steps"] == [1, 20] and crack["rfa"] == [0.0, 1.0]
    assert crack["accuracy_mean"] == [0.0, 75.0] and crack["as_healthy_mean"] == [100.0, 25.0]
    assert a["curves"]["all"]["accuracy_mean"] == [0.0, 75.0]


# --- the scenario kind ---------------------------------------------------------------------------

TINY = """
[scenario]
name = "ch4_tiny"
kind = "noise_study"

[study]
noises = {noises}

[dataset]
faults = {faults}
teeth = [1, 2]
duplicates = 3
healthy = 96
revolutions = 4

[network]
name = "{network}"

[protocol]
runs = {runs}
batch = {batch}
epochs = 4
patience = 4

[execution]
device = "cpu"
workers = 1
"""


FOUR = "{ crack = [5, 10, 15, 20], chip = [5, 10, 15, 20], spall = [5, 10, 15, 20], pit = [5, 10, 15, 20] }"


def tiny(noises='["gaussian", "student_t"]', network="fast", runs=2, batch=32, faults=FOUR) -> str:
    return TINY.format(noises=noises, network=network, runs=runs, batch=batch, faults=faults)


def run_dir(out: str) -> Path:
    return Path(out.strip().splitlines()[-1].split(": ", 1)[1])


def test_run_writes_records_summary_tables_and_figures(cli, write_scenario, tmp_path, fake_builder):
    code, out, err = cli("run", write_scenario(tiny()), "--out", tmp_path / "runs")
    assert code == 0, err
    run = run_dir(out)
    records = RunDir(run).records()
    assert [r["unit"] for r in records] == [
        f"{n}/{v}/run{r}" for n in ("gaussian", "student_t") for r in (0, 1) for v in ("noisy", "tsa")
    ]
    assert fake_builder == [
        name
        for noise in ("gaussian", "student_t")
        for variant in ("noise", "TSA")
        for name in (f"A-casing_{variant}-{noise}", f"A-casing_{variant}-{noise} (noise-free twin)")
    ]  # each once, the twin for the Bayes bound after it
    assert {r["dataset"] for r in records} == {
        "A-casing_noise-gaussian",
        "A-casing_TSA-gaussian",
        "A-casing_noise-student_t",
        "A-casing_TSA-student_t",
    }
    summary = json.loads((run / "summary.json").read_text())
    assert summary["kind"] == "noise_study" and summary["units"] == 8
    assert summary["datasets"]["student_t"]["tsa"]["spec"]["noise"]["kind"] == "student_t"
    assert summary["datasets"]["student_t"]["tsa"]["spec"]["tsa"] is True
    assert summary["datasets"]["gaussian"]["noisy"]["spec"]["teeth"] == [1, 2]
    for noise in ("gaussian", "student_t"):
        res = summary["results"][noise]
        for v in ("noisy", "tsa"):
            assert res[v]["runs"] == 2
            assert {"mean", "std"} <= set(res[v]["accuracy"]) and {"mean", "std"} <= set(res[v]["fault_as_healthy"])
            assert set(res[v]["curves"]) == {"crack", "chip", "spall", "pit", "all"}
            assert res[v]["curves"]["pit"]["steps"] == [5, 10, 15, 20]
            assert np.array(res[v]["confusion"]).shape == (5, 5)
        assert res["tsa_gain"]["n"] == 2
        assert res["tsa"]["accuracy"]["mean"] > res["noisy"]["accuracy"]["mean"]  # less noise in the synthetic TSA set
    table = (run / "table.md").read_text()
    assert "| gaussian |" in table and "| student_t |" in table and "TSA accuracy" in table
    assert "TSA bound (%)" in table
    csv = (run / "table.csv").read_text().splitlines()
    assert csv[0].startswith("noise,noisy_accuracy_mean,noisy_accuracy_std") and len(csv) == 3
    assert csv[0].endswith(",runs,noisy_bound_mean,noisy_bound_std,tsa_bound_mean,tsa_bound_std")
    bound = json.loads((run / "bound.json").read_text())
    for noise in ("gaussian", "student_t"):
        for v in ("noisy", "tsa"):
            assert len(bound[noise][v]) == 2  # a run each
            # the classifier that knows the shapes beats the network trained for four epochs
            assert summary["bound"][noise][v]["mean"] >= summary["results"][noise][v]["accuracy"]["mean"]
    for name in ("accuracy_vs_intensity.png", "accuracy_vs_rfa.png", "confusion.png"):
        assert (run / "figures" / name).stat().st_size > 10_000
    assert "data:image/png;base64," in (run / "report.html").read_text()
    if chromium():  # the report as a reader gets it (issue 41: a browser test covers every kind)
        check_report(run / "report.html", tmp_path / "browser")
    assert "TSA accuracy" in out  # summary_lines


def test_resume_skips_finished_units(cli, write_scenario, tmp_path, fake_builder, monkeypatch, unrendered_figures):
    code, out, err = cli("run", write_scenario(tiny(noises='["laplace"]')), "--out", tmp_path / "runs")
    assert code == 0, err
    run = run_dir(out)
    records = RunDir(run).records()
    # a kill during the third unit: two records and a half-written line
    lines = (run / "results.jsonl").read_text().splitlines(keepends=True)
    (run / "results.jsonl").write_text("".join(lines[:2]) + '{"unit": "laplace/no')
    trained = []
    real = kind.run_unit

    def counting(protocol, dataset, r, *args, **kwargs):
        trained.append((dataset.spec.name, r))
        return real(protocol, dataset, r, *args, **kwargs)

    monkeypatch.setattr(kind, "run_unit", counting)
    fake_builder.clear()
    code, out, err = cli("run", "--resume", run)
    assert code == 0, err
    assert trained == [("A-casing_noise-laplace", 1), ("A-casing_TSA-laplace", 1)]
    again = RunDir(run).records()
    assert [r["unit"] for r in again] == [r["unit"] for r in records]
    assert again[:2] == records[:2]
    drop = ("train_seconds",)
    assert [{k: v for k, v in r.items() if k not in drop} for r in again[2:]] == [
        {k: v for k, v in r.items() if k not in drop} for r in records[2:]
    ]  # same seeds, same results
    trained.clear()
    fake_builder.clear()
    assert cli("run", "--resume", run)[0] == 0 and trained == [] and fake_builder == []  # nothing left to do
    assert json.loads((run / "summary.json").read_text())["results"]["laplace"]["tsa"]["runs"] == 2


def test_quick_shrinks_the_study():
    scenario = load_scenario(ROOT / "scenarios" / "ch4_noise.toml")
    kind.quick(scenario)
    assert list(scenario.spec.datasets) == ["gaussian"]
    protocol = scenario.spec.protocol
    assert protocol.runs == 1 and protocol.epochs <= 15
    noisy, tsa = scenario.spec.datasets["gaussian"]["noisy"], scenario.spec.datasets["gaussian"]["tsa"]
    assert noisy.with_(tsa=True, name=tsa.name, domain=tsa.domain) == tsa
    sizes = kind.class_sizes(noisy, "")
    assert sum(sizes.values()) <= 500 and sizes["healthy"] == sum(sizes.values()) // 2


def test_shipped_scenario_is_table_4_1(cli):
    code, out, err = cli("validate", ROOT / "scenarios" / "ch4_noise.toml")
    assert code == 0, err
    scenario = load_scenario(ROOT / "scenarios" / "ch4_noise.toml")
    assert list(scenario.spec.datasets) == ["gaussian", "laplace", "student_t"]
    for noise, variants in scenario.spec.datasets.items():
        assert variants["noisy"] == dataset_preset(f"A-casing_noise-{noise}")
        assert variants["tsa"] == dataset_preset(f"A-casing_TSA-{noise}")
        assert kind.class_sizes(variants["tsa"], "") == {
            "healthy": 6400,
            "crack": 1600,
            "chip": 1600,
            "spall": 1600,
            "pit": 1600,
        }
    p = scenario.spec.protocol
    assert (p.runs, p.batch, p.dropout, p.test_fraction, p.val_fraction) == (5, 256, 0.1, 0.333, 0.2)


def test_the_hybrid_scenario_is_the_same_study_with_the_simulator_s_shapes():
    """ch4_hybrid.toml differs from ch4_noise.toml only in the network and its start."""
    faithful = load_scenario(ROOT / "scenarios" / "ch4_noise.toml").spec
    hybrid = load_scenario(ROOT / "scenarios" / "ch4_hybrid.toml").spec
    assert hybrid.datasets == {n: faithful.datasets[n] for n in ("gaussian", "laplace")}
    p, q = hybrid.protocol, faithful.protocol
    assert (p.network, p.residual, p.start) == ("shapes", True, "clean")
    assert (p.runs, p.batch, p.test_fraction, p.val_fraction, p.epochs, p.patience, p.seed) == (
        q.runs,
        q.batch,
        q.test_fraction,
        q.val_fraction,
        q.epochs,
        q.patience,
        q.seed,
    )


@pytest.mark.parametrize(
    "text, where, message",
    [
        (tiny(noises='["gaussian", "pink"]'), "[study] key 'noises'", "unknown noise type 'pink'"),
        (tiny(noises='["gausian"]'), "[study] key 'noises'", "did you mean 'gaussian'"),
        (tiny(noises="[]"), "[study] key 'noises'", "non-empty"),
        (tiny(network="cnn4"), "[network] key 'name'", "did you mean 'cnn3'"),
        (tiny(network="shapes"), "[protocol] key 'residual'", "expected residual = true"),
        (tiny().replace("runs = 2", "runs = 2\nstart = 'clean'"), "[protocol] key 'start'", "expected [network] name"),
        (tiny().replace("runs = 2", "runs = 2\nstart = 'clear'"), "[protocol] key 'start'", "did you mean 'clean'"),
        (tiny(batch=4096), "[protocol] key 'batch'", "larger than the training set"),
        (tiny().replace("epochs = 4", "epoch = 4"), "[protocol] key 'epoch'", "did you mean 'epochs'"),
        (tiny().replace("runs = 2", "runs = 0"), "[protocol] key 'runs'", "outside"),
        (tiny().replace("runs = 2", "runs = 2\nstart = 'fault'"), "[protocol] key 'start'", "did you mean 'faults'"),
        (
            tiny().replace("teeth = [1, 2]", "teeth = [1, 2]\neffects = [{ name = 'sensor_noise', kind = 'laplace' }]"),
            "[dataset] key 'effects'",
            "the noise kind comes from [study]",
        ),
        (
            tiny().replace("duplicates = 3", "duplicates = 3\npreset = 'A-casing'"),
            "[dataset] key 'preset'",
            "unknown key",
        ),
        (
            tiny(faults="{ crack = [5, 10], pit = [20] }").replace("duplicates = 3", "duplicates = 1"),
            "[dataset]",
            "class 'pit' has 2 samples",
        ),
        (tiny() + "\n[studies]\n", "", "unknown table [studies]"),
    ],
)
def test_bad_input_is_one_line_naming_file_table_key(cli, write_scenario, text, where, message):
    path = write_scenario(text)
    code, out, err = cli("validate", path)
    assert code == 2, out
    assert len(err.strip().splitlines()) == 1, err
    assert str(path) in err and where in err and message in err, err
    with pytest.raises(GearlabInputError):
        load_scenario(path)


@pytest.mark.slow
def test_quick_run_of_the_shipped_scenario_builds_real_datasets(cli, tmp_path):
    code, out, err = cli("run", ROOT / "scenarios" / "ch4_noise.toml", "--quick", "--out", tmp_path)
    assert code == 0, err
    summary = json.loads((run_dir(out) / "summary.json").read_text())
    assert set(summary["results"]["gaussian"]) >= {"noisy", "tsa", "tsa_gain"}


def test_the_matched_start_takes_the_training_part_s_faults_only(monkeypatch):
    """start = "faults": the filter bank starts on the training part's fault revolutions less
    its healthy median (the bursts); the validation and test parts never reach it."""
    from dataclasses import replace

    protocol = replace(FAST, network="burst", start="faults", epochs=1)
    seen = []
    real = networks.matched_start  # imported where the study trains (start-up time)

    def spy(net, faults, seed):
        seen.append(np.array(faults))
        return real(net, faults, seed)

    monkeypatch.setattr(networks, "matched_start", spy)
    data = synthetic(small_spec(tsa=True))
    label = np.asarray(data.label, dtype=np.int64)
    s = split(label, protocol, 0)
    run_unit(protocol, data, run=0)
    train = s.train
    expected = data.X[train][label[train] != 0] - np.median(data.X[train][label[train] == 0], axis=0)
    ((faults,),) = [seen]
    assert np.allclose(faults, expected, atol=1e-5)
    assert run_unit(replace(protocol, start="random"), data, run=0) and len(seen) == 1  # random: no matched start


def test_the_clean_start_takes_the_training_part_s_noise_free_twin_only():
    """start = "clean": the network starts on the distinct noise-free fault shapes of the
    training part (α·(twin - its healthy median), with their classes) and the rows' noise law;
    replacing every validation and test row of the twin changes nothing."""
    from dataclasses import replace

    protocol = replace(FAST, network="shapes", residual=True, start="clean", epochs=1)
    spec = small_spec(tsa=True)
    data, twin = synthetic(spec), synthetic(spec.with_(noise=None))
    label = np.asarray(data.label, dtype=np.int64)
    s = split(label, protocol, 0)
    faults, classes = ns.clean_faults(data.X[s.train], twin.X[s.train], label[s.train])
    train_twin = twin.X[s.train]
    expected = train_twin[label[s.train] != 0] - np.median(train_twin[label[s.train] == 0], axis=0)
    assert len(faults) == len(np.unique(expected.round(6), axis=0)) == 4 * 4  # type x step (every tooth alike)
    assert set(classes) == {1, 2, 3, 4}
    # α = 1 here: the synthetic noisy rows are the twin plus zero-mean noise
    assert any(np.allclose(faults[0], e, rtol=0.05, atol=0.05) for e in expected)
    first = run_unit(protocol, data, run=0, twin=twin)
    others = np.setdiff1d(np.arange(len(label)), s.train)
    twin.X[others] = np.random.default_rng(2).normal(size=twin.X[others].shape) * 9
    assert run_unit(protocol, data, run=0, twin=twin)["accuracy"] == first["accuracy"]
    laws = {name: ns.noise_law(dataset_preset(name)) for name in ("A-casing_TSA-laplace", "A-casing_noise-laplace")}
    assert laws == {"A-casing_TSA-laplace": "gaussian", "A-casing_noise-laplace": "laplace"}  # a mean of 60 draws
    assert ns.noise_law(dataset_preset("A-casing_TSA-student_t")) == "student_t"  # keeps its heavy tail


def test_shapes_from_the_clean_start_come_near_the_bayes_classifier():
    """The shapes network started on the training part's noise-free shapes is the Bayes
    classifier of those shapes (up to the class priors, which one epoch learns): on the
    synthetic TSA set it comes within a few points of `class_bound`, which knows every shape
    of the test part too; a random start after one epoch is far below."""
    from dataclasses import replace

    from gearlab.learn.bounds import class_bound

    protocol = replace(FAST, network="shapes", residual=True, start="clean", epochs=1)
    spec = small_spec(tsa=True)
    data, twin = synthetic(spec), synthetic(spec.with_(noise=None))
    label = np.asarray(data.label, dtype=np.int64)
    test = split(label, protocol, 0).test
    bound = 100.0 * float((class_bound(data.X, twin.X, label, "gaussian")[test] == label[test]).mean())
    clean = run_unit(protocol, data, run=0, twin=twin)["accuracy"]
    random = run_unit(replace(protocol, start="random"), data, run=0)["accuracy"]
    assert clean >= bound - 3.0, (clean, bound)
    assert random < clean - 10.0, (random, clean)


def test_a_run_with_the_clean_start_hands_each_worker_the_twin(cli, write_scenario, tmp_path, fake_builder):
    text = tiny(noises='["gaussian"]', network="shapes", runs=1).replace(
        "runs = 1", "runs = 1\nresidual = true\nstart = 'clean'"
    )
    code, out, err = cli("run", write_scenario(text), "--out", tmp_path / "runs")
    assert code == 0, err
    records = RunDir(run_dir(out)).records()
    assert [r["unit"] for r in records] == ["gaussian/noisy/run0", "gaussian/tsa/run0"]
    assert all(r["accuracy"] > 60.0 for r in records), [r["accuracy"] for r in records]
