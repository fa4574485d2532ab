"""Scenario kind `detection` with a [corrected] source: its methods trained a second time on the
simulator with effects added (noise draws, history TSAs), the bound of its noise-free twin, and the
domain losses that align the history with a point."""

import json

import numpy as np
import pytest
from detection_scenario import run, scenario, scores


@pytest.fixture
def cache(module_cache):
    """One dataset cache for the module (content-addressed): most tests simulate the same tiny source,
    and none asserts on whether a dataset was built or found."""
    return module_cache


def test_a_corrected_source_trains_every_method_a_second_time(cli, tmp_path, cache):
    """[corrected] effects: the source with them added is simulated too (its own dataset), and
    each method is trained on it as well, its rows named '<method> (<label>)'."""
    corrected = (
        '[corrected]\nlabel = "noisy"\ntsa = 3\neffects = [{ name = "sensor_noise", kind = "gaussian", snr_db = 20 }]\n'
    )
    path = scenario(tmp_path, methods=("source_only", "matched_filter"), extra=corrected)
    code, out, err = cli("validate", path)
    assert code == 0, err
    assert "source_only (noisy: + sensor_noise)" in out
    run_dir = run(cli, path, tmp_path / "runs")
    rows = scores(run_dir)
    methods = {r["method"] for r in rows}
    assert methods == {"source_only", "matched_filter", "source_only (noisy)", "matched_filter (noisy)", "fm4", "na4"}
    plain = [r["score"] for r in rows if r["method"] == "source_only"]
    noisy = [r["score"] for r in rows if r["method"] == "source_only (noisy)"]
    assert len(plain) == len(noisy) and plain != noisy
    conditions = json.loads((run_dir / "conditions.json").read_text())
    (sources,) = [c["sources"] for c in conditions.values()]
    assert set(sources) == {"source", "noisy"} and sources["noisy"] != sources["source"]
    path.write_text(path.read_text().replace('name = "sensor_noise"', 'name = "sensor_nosie"'))
    code, _, err = cli("validate", path)
    assert code == 2 and "[corrected]" in err and "sensor_nosie" in err


def test_the_corrected_source_may_train_on_the_historys_tsas(cli, tmp_path, cache, handed, no_figures):
    """[corrected] history_units = "tsa": the corrected source's methods are handed the history's TSAs
    of `tsa` revolutions (as the corrected samples are averaged), the plain source's methods its
    revolutions — every row handed over is one of those, as the methods see them; a wrong value is
    refused with the choices."""
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import learned_input, read_target, tsa_units

    corrected = (
        '[corrected]\ntsa = 3\nhistory_units = "tsa"\n'
        'effects = [{ name = "sensor_noise", kind = "gaussian", snr_db = 20 }]\n'
    )
    path = scenario(tmp_path, methods=("source_only",), extra=corrected)
    run(cli, path, tmp_path / "runs")
    spec = load_scenario(path).spec
    ((_, cond),) = read_target(spec.target, spec.detection.blocks, lambda e: None).items()
    shown = learned_input(spec.detection.input, spec.detection.points, spec.classical, cond["max_order"])
    revolutions = np.concatenate([shown(r) for _, r in cond["history"]])
    tsas = np.concatenate([shown(tsa_units(r, 3, 1)) for _, r in cond["history"]])

    def among(rows, pool) -> bool:
        return all(np.abs(pool - row).max(axis=1).min() < 1e-6 for row in rows)

    assert len(handed) == 2  # the plain source's training and the corrected one's
    assert sorted((among(rows, revolutions), among(rows, tsas)) for rows in handed) == [(False, True), (True, False)]
    path.write_text(path.read_text().replace('history_units = "tsa"', 'history_units = "tsas"'))
    code, _, err = cli("validate", path)
    assert code == 2 and "history_units" in err and "revolution, tsa" in err


def test_a_corrected_source_with_draws_trains_each_row_on_a_draw_of_its_own_sample(
    cli, tmp_path, cache, monkeypatch, no_figures
):
    """[corrected] draws = 3: the corrected source holds three noise draws of each sample; its
    networks are handed them as (n, 3, L), split by sample (no draw of a held-out sample is trained
    on), and a batch row is always a draw of its own sample; its detector's shapes are the
    samples' noise-free twins;
    the held-out counts are samples, not draws. The plain source keeps one draw."""
    import torch

    import gearlab.api as api
    import gearlab.learn.protocol as P
    import gearlab.learn.training as T

    handed, rows = [], []
    train_method, pick = P.train_method, T._rows

    def spy(protocol, method, source, source_val, target, *args, **kwargs):
        handed.append((method.adapter, np.array(source[0], copy=True), np.array(source_val[0], copy=True)))
        return train_method(protocol, method, source, source_val, target, *args, **kwargs)

    def rows_spy(X, index, draws):
        out, flat = pick(X, index, draws)
        if X.ndim == 3:  # every row one of its own sample's draws
            own = X[index]
            assert torch.all((own == out[:, None]).all(dim=2).any(dim=1))
            rows.append(int(torch.all(own[:, 0] == out)))
        return out, flat

    templates = []
    template_statistic = api.template_statistic

    def detector_spy(Xs, ys, *args, **kwargs):
        templates.append(np.array(Xs, copy=True))
        return template_statistic(Xs, ys, *args, **kwargs)

    monkeypatch.setattr(P, "train_method", spy)
    monkeypatch.setattr(T, "_rows", rows_spy)
    monkeypatch.setattr(api, "template_statistic", detector_spy)
    corrected = (
        '[corrected]\nlabel = "noisy"\ntsa = 3\ndraws = 3\n'
        'effects = [{ name = "sensor_noise", kind = "gaussian", snr_db = 20 }]\n'
    )
    path = scenario(tmp_path, methods=("source_only", "matched_filter"), extra=corrected)
    run_dir = run(cli, path, tmp_path / "runs")
    nets = [(X, V) for adapter, X, V in handed if adapter == "source_only"]
    assert sorted(X.ndim for X, _ in nets) == [2, 3]
    ((X, V),) = [(X, V) for X, V in nets if X.ndim == 3]
    assert X.shape[1] == 3 and V.ndim == 2  # one draw of the held-out samples decides when to stop
    assert not np.array_equal(X[:, 0], X[:, 1])  # the draws differ
    trained = X.reshape(-1, X.shape[-1])
    assert all(np.abs(trained - v).max(axis=1).min() > 1e-3 for v in V)  # held-out samples: no draw trained on
    assert rows and 0 in rows  # batches took other draws than the first
    # its detector: one row a sample, the noise-free twin's (test_corrected_detector_shapes), not the draws' mean
    assert [D.ndim for adapter, D, _ in handed if adapter == "matched_filter"] == [2, 2]
    assert not any(t.shape == X[:, 0].shape and np.allclose(t, X.mean(axis=1), atol=1e-6) for t in templates)
    records = [json.loads(line) for line in (run_dir / "results.jsonl").read_text().splitlines()]
    (noisy,) = [r for r in records if r["method"] == "source_only (noisy)" and r.get("seed") is None]
    (plain,) = [r for r in records if r["method"] == "source_only" and r.get("seed") is None]
    assert noisy["source_units"] == [3 * n for n in plain["source_units"]]  # every draw of the held-out samples
    # the bound of each source: the noisy one's from its noise-free twin, none for the noise-free one
    (cond,) = json.loads((run_dir / "conditions.json").read_text()).values()
    assert cond["source_bound"]["source"] is None and "noisy" in cond["source_bound"]  # numbers: the next test
    learned = {r["method"]: r for r in json.loads((run_dir / "summary.json").read_text())["learned"]}
    assert learned["source_only (noisy)"]["source_bound"] == cond["source_bound"]["noisy"]
    assert "| bound |" in (run_dir / "table.md").read_text()
    path.write_text(path.read_text().replace("draws = 3", "draws = 0"))
    code, _, err = cli("validate", path)
    assert code == 2 and "[corrected] key 'draws'" in err


def test_the_source_bound_is_the_likelihood_ratio_with_the_noise_free_shapes(cache):
    """source_bound: the ROC AUC of the detector that knows the source's noise-free fault shapes
    (its twin without the noise effect) on every draw of the held-out samples: near 1 where the
    noise is weak, lower where it buries the chip, and none for a source without a noise effect."""
    from gearlab.data.cache import load_or_build
    from gearlab.data.spec import DATASET_PRESETS
    from gearlab.effects import effect_spec
    from gearlab.kinds.detection_units import source_bound
    from gearlab.learn.protocol import Method, Protocol

    protocol = Protocol(methods=(Method("source_only", False),))
    base = DATASET_PRESETS["B-6-ch5"].with_(faults=(("chip", (20,)),), teeth=tuple(range(1, 17)), healthy=16)
    bound = {}
    for snr in (40.0, -15.0):
        spec = base.with_(
            effects=(effect_spec("sensor_noise", kind="gaussian", snr_db=snr),),
            tsa=True,
            revolutions=3,
            duplicates=4,
            healthy=64,
            name=f"noisy{snr:g}",
        )
        bound[snr] = source_bound(spec, load_or_build(spec)[0], protocol, 4, None, lambda e: None)
    assert bound[40.0] > 0.95 and 0.5 < bound[-15.0] < bound[40.0] - 0.1
    assert source_bound(base, load_or_build(base)[0], protocol, 1, None, lambda e: None) is None


def test_the_noise_free_twin_holds_each_run_of_draws_without_its_noise(cache):
    """noise_free_twin: sample i of the twin is the signal of draws i·D ... (i + 1)·D - 1 of the
    noisy source without their noise. In the units both share (each dataset is standardised by its
    own healthy reference), the draws' mean less the twin's sample is the noise averaged over D
    draws; against another sample (the pairing off by one) the chip's difference is added."""
    from gearlab.data.cache import load_or_build
    from gearlab.data.spec import DATASET_PRESETS
    from gearlab.effects import effect_spec
    from gearlab.kinds.detection_units import noise_effects, noise_free_twin

    draws = 4
    spec = DATASET_PRESETS["B-6-ch5"].with_(
        faults=(("chip", (20,)),),
        teeth=tuple(range(1, 9)),
        effects=(effect_spec("sensor_noise", kind="gaussian", snr_db=30.0),),
        tsa=True,
        revolutions=3,
        duplicates=draws,
        healthy=8 * draws,
        name="noisy",
    )
    twin = noise_free_twin(spec, draws)
    assert noise_effects(spec) and not noise_effects(twin)
    noisy, clean = load_or_build(spec)[0], load_or_build(twin)[0]

    def physical(data):
        mean, std = data.reference
        return data.X.astype(np.float64) * std + mean

    X, C = physical(noisy).reshape(len(clean), draws, -1), physical(clean)
    assert np.array_equal(noisy.fault[::draws], clean.fault) and np.array_equal(noisy.tooth[::draws], clean.tooth)
    deviation = X - X.mean(axis=1, keepdims=True)
    averaged_noise = np.sqrt(np.mean(deviation**2) * draws / (draws - 1) / draws)
    paired = np.sqrt(np.mean((X.mean(axis=1) - C) ** 2))
    chipped = np.flatnonzero(clean.fault == 1)
    off_by_one = np.sqrt(np.mean((X.mean(axis=1)[chipped] - C[np.roll(chipped, 1)]) ** 2))
    assert paired < 1.2 * averaged_noise < off_by_one


def test_a_domain_loss_that_aligns_the_history_with_one_input_is_named():
    """aligned_to_a_point, from the training arrays alone: a joint adapter (coral, mmd, dann) whose
    source rows for the alignment are one input over and over -- the zero difference signal of a
    noise-free simulator's healthy revolutions -- aligns the history with a point; healthy rows
    that differ (sensor noise, or noise draws of them), fresh noise on every batch, all rows under
    marginal alignment (the chips differ) or a method without a domain loss do not."""
    from gearlab.kinds.detection_units import aligned_to_a_point
    from gearlab.learn.calibration import Calibration
    from gearlab.learn.protocol import Method, Protocol

    rng = np.random.default_rng(0)
    ys = np.r_[np.zeros(20, dtype=np.int64), np.ones(20, dtype=np.int64)]
    chips = rng.normal(size=(20, 256))
    plain = np.r_[np.zeros((20, 256)), chips]  # healthy: the mesh tones removed leave nothing
    noisy = plain + 0.1 * rng.normal(size=plain.shape)
    drawn = np.repeat(plain[:, None], 4, axis=1) + 0.1 * rng.normal(size=(40, 4, 256))

    def protocol(**calibration) -> Protocol:
        return Protocol(methods=(Method("coral", False),), calibration=Calibration(**calibration))

    healthy = protocol(alignment="healthy")
    for adapter in ("coral", "mmd", "dann"):
        assert aligned_to_a_point(healthy, Method(adapter, False), plain, ys)
    assert aligned_to_a_point(healthy, Method("coral", False), np.r_[np.ones((20, 256)), chips], ys)  # one input
    assert not aligned_to_a_point(healthy, Method("coral", False), noisy, ys)
    assert not aligned_to_a_point(healthy, Method("coral", False), drawn, ys)
    assert not aligned_to_a_point(protocol(alignment="marginal"), Method("coral", False), plain, ys)
    assert not aligned_to_a_point(protocol(alignment="healthy", source_noise="auto"), Method("coral", False), plain, ys)
    for other in ("source_only", "matched_filter", "likelihood_ratio"):
        assert not aligned_to_a_point(healthy, Method(other, False), plain, ys)


def test_a_training_that_aligns_the_history_with_a_point_ends_at_its_ramp(cli, tmp_path, cache, no_figures):
    """Against a single point the domain discrepancy never settles, so such a training (the plain
    source's coral here: its healthy difference signals are all zero) ends at the ramp's end
    (min_epochs) and keeps that epoch; the same method on a source whose healthy rows differ (the
    corrected one, with sensor noise) is left to the stopping rule."""
    corrected = (
        '[corrected]\nlabel = "noisy"\ntsa = 3\neffects = [{ name = "sensor_noise", kind = "gaussian", snr_db = 20 }]\n'
    )
    path = scenario(tmp_path, methods=("coral",), extra=corrected)
    protocol = 'max_epochs = 30\nalignment = "healthy"\nsource_noise = "off"\nresidual = false'
    path.write_text(path.read_text().replace("max_epochs = 2", protocol))
    out = run(cli, path, tmp_path / "runs")
    records = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    trained = {r["method"]: r for r in records if r.get("history") and r["history"]["train_loss"]}
    plain, noisy = trained["coral"], trained["coral (noisy)"]
    assert plain["aligned_to_a_point"] and not noisy["aligned_to_a_point"]
    assert len(plain["history"]["train_loss"]) == 2 and plain["history"]["best_epoch"] == 1
    assert len(noisy["history"]["train_loss"]) > 2
