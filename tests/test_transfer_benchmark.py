"""The `transfer_benchmark` kind: random unseen targets drawn from documented ranges, the recipe
frozen for all of them, each trial beside its own Bayes bound (or told unavailable), and the
selection rule printed with every run."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from browser import check_report, chromium
from tiny import EXECUTION, SCHEDULE

from gearlab.engine import load_scenario, run_scenario
from gearlab.gap.diagnose import WITHHELD
from gearlab.kinds import SCENARIO_KINDS
from gearlab.kinds import transfer_benchmark as tb
from gearlab.kinds import transfer_benchmark_draw as draws
from gearlab.runs import RunDir

TINY = (
    """\
[scenario]
name = "tinybench"
kind = "transfer_benchmark"

[benchmark]
trials = 2
seed = 3

[source]
preset = "B-6-ch5"
teeth = [1, 2, 3]
faults = { crack = [13] }
healthy = 12

[network]
name = "fast"

[[methods]]
adapter = "source_only"

[[methods]]
adapter = "likelihood_ratio"

[[methods]]
adapter = "mmd"

[protocol]
repetitions = 1
"""
    + SCHEDULE.format(max_epochs=3)
    + "\n"
    + EXECUTION
)

# The same with the per-trial correction: a history of 10 rows (the diagnosis's statistics need 10),
# a small diagnosis (the tests below stand a recorder in for it).
CORRECTED = TINY.replace("target_train = 8", "target_train = 10").replace(
    "repetitions = 1\n",
    "repetitions = 2\ncorrect_source = true\n",
) + (
    """
[diagnosis]
candidates = ["sensor_noise", "bearing_stiffness"]
budget = 2
max_effects = 1
healthy = 10
bootstrap = 10
permutations = 20
"""
)
# what the stand-in diagnosis fits: a model effect (kept in the corrected source) and noise (left out)
FITTED = [
    ["bearing_stiffness", [["c_factor", 1.0], ["k_factor", 0.5]]],
    ["sensor_noise", [["kind", "gaussian"], ["snr_db", 3.0]]],
]


@pytest.fixture
def tiny(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "tinybench.toml"
    path.write_text(TINY)
    return path


def test_the_draw_is_fixed_by_the_seed_and_stays_in_its_ranges():
    spec = load_scenario(Path(__file__).parents[1] / "scenarios" / "transfer_benchmark.toml").spec
    drawn = tb.trials(spec)
    again = tb.trials(spec)
    assert [t[2] for t in drawn] == [t[2] for t in again]  # the same seed, the same targets
    other = tb.trials(replace(spec, benchmark=replace(spec.benchmark, seed=1000)))
    assert [t[2] for t in other] != [t[2] for t in drawn]
    laws, sensors, models, tones = set(), set(), set(), 0
    for _, source, target, a in drawn:
        assert source.speed_hz == target.speed_hz and source.load_nm == spec.source.load_nm  # load unknown
        assert draws.SPEED_HZ[0] <= a["speed_hz"] <= draws.SPEED_HZ[1]
        assert draws.LOAD_NM[0] <= a["load_nm"] <= draws.LOAD_NM[1]
        assert draws.SNR_DB[0] <= a["snr_db"] <= draws.SNR_DB[1]
        assert 2 <= len(a["faults"]) <= 4 and set(a["faults"]) <= {n for n, _ in spec.source.faults}
        fault_rows = sum(len(s) for _, s in target.faults) * len(target.teeth)
        assert target.healthy == spec.protocol.target_train + fault_rows  # the test set is half faulty
        for effect, params in a["effects"].items():
            ranges = {**draws.MODEL_EFFECTS, **draws.SENSORS, "interference_tone": draws.TONE}[effect]
            for key, value in params.items():
                assert ranges[key][0] <= value <= ranges[key][1], (effect, key)
        laws.add(a["noise"])
        sensors.add(a["sensor"])
        models.add(a["model"])
        tones += a["tone"]
    # 24 trials cover every law, sensor and model mismatch, and some tones
    assert laws == {"gaussian", "laplace", "student_t"} and sensors == set(draws.SENSORS)
    assert models == set(draws.MODEL_EFFECTS) and 0 < tones < len(drawn)


def test_registered_validated_and_a_supervised_method_refused(tiny, cli):
    assert SCENARIO_KINDS["transfer_benchmark"] is tb
    code, out, err = cli("validate", tiny)
    assert code == 0, err
    assert "2 random targets" in out and "development" in out
    tiny.write_text(TINY.replace('adapter = "mmd"', 'adapter = "mmd"\nsupervised = true'))
    code, _, err = cli("validate", tiny)
    assert code == 2 and "\n" not in err.strip()
    assert "[[methods]] #3 key 'supervised'" in err and str(tiny) in err
    tiny.write_text(TINY + '\n[diagnosis]\ncandidates = ["bearing_stifness"]\n')  # the correction's effects
    code, _, err = cli("validate", tiny)
    assert code == 2 and "\n" not in err.strip()
    assert "[diagnosis]" in err and "did you mean 'bearing_stiffness'" in err and str(tiny) in err


def test_a_tiny_benchmark_runs_end_to_end(tiny):
    run = run_scenario(tiny, out=tiny.parent / "runs").path
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    targets = [r for r in records if r["unit"].endswith("/target")]
    trained = [r for r in records if "accuracy" in r]
    assert [r["unit"] for r in targets] == ["trial000/target", "trial001/target"]
    assert len(trained) == 2 * 3  # trials x methods x one repetition
    summary = json.loads((run / "summary.json").read_text())
    assert summary["use"] == "development" and "seeds below 1000" in summary["selection_rule"]
    for t in summary["trials"].values():
        assert set(t["accuracy"]) == set(summary["methods"])
        assert (t["bound"] is None) == bool(t["unavailable"])  # a number, or why there is none
        if t["answers"]["tone"]:
            assert t["bound"] is None  # a tone lies outside the bound's model
        if t["bound"] is not None:  # the bound at the methods' threshold rule: never above the best threshold's
            assert 0.0 <= t["bound_at_rule"] <= t["bound"]
        for acc in t["accuracy"].values():
            assert 0.0 <= acc <= 100.0
    for label, m in summary["per_method"].items():
        assert m["trials"] == 2 and m["median"] == pytest.approx(
            np.median([t["accuracy"][label] for t in summary["trials"].values()])
        )
    assert set(summary["domain_gain"]) == {"source_only (unsupervised)", "mmd (unsupervised)"}
    bounded = [t for t in summary["trials"].values() if t["bound"] is not None]
    for label, m in summary["per_method"].items():  # the distance to the bound at the rule, beside the bound's
        gaps = [t["bound_at_rule"] - t["accuracy"][label] for t in bounded]
        assert m["median_gap_rule"] == (pytest.approx(np.median(gaps)) if gaps else None)
    assert "| at the rule |" in (run / "table.md").read_text()
    lines = SCENARIO_KINDS["transfer_benchmark"].summary_lines(RunDir.open(run))
    assert lines[0].startswith("selection rule") and "seed 3 (development)" in lines[0]
    assert (run / "figures" / "transfer_benchmark.png").exists() and "<img" in (run / "report.html").read_text()
    if chromium():  # the report as a reader gets it (issue 41: a browser test covers every kind)
        check_report(run / "report.html", tiny.parent / "browser")


# --- the per-trial corrected source ----------------------------------------------------------------


@pytest.fixture(scope="module")
def corrected(tmp_path_factory):
    """One run of the tiny benchmark with the correction; a recorder stands in for the diagnosis
    (what it fits is FITTED) and keeps what it was given."""
    calls: list[dict] = []

    def diagnose(source, target_X, settings, executor=None, on_event=None, chain=None):
        calls.append({"source": source, "target_X": np.array(target_X), "settings": settings, "chain": chain})
        effects = [{"name": n, "params": dict(p), "share_removed": 0.5} for n, p in FITTED]
        return {
            "gap_before": 10.0,
            "gap_after": 1.0,
            "unexplained": False,
            "effects": effects,
            "corrected_effects": FITTED,
            "evaluations": 57,
        }

    # the histories the training units and the bounds are given (one worker: in this process)
    train_unit, bayes_bound = tb.train_unit, tb.bayes_bound
    histories: dict[str, list] = {"units": [], "bounds": [], "logs": []}

    def unit(task):
        histories["units"].append((task[2][0].name, task[7]))
        return train_unit(task)

    def bound(target_spec, *args):
        histories["bounds"].append((target_spec.name, args[-1]))
        return bayes_bound(target_spec, *args)

    base = tmp_path_factory.mktemp("corrected")
    path = base / "corrected.toml"
    path.write_text(CORRECTED)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GEARLAB_CACHE", str(base / "cache"))
        mp.setattr("gearlab.gap.diagnose.diagnose", diagnose)
        mp.setattr(tb, "train_unit", unit)
        mp.setattr(tb, "bayes_bound", bound)
        logs = histories["logs"].append
        run = run_scenario(
            path, out=base / "runs", on_event=lambda e: logs(e.message) if e.kind == "log" else None
        ).path
    return run, calls, base / "cache", histories


def test_the_correction_fits_on_the_history_alone(corrected, monkeypatch):
    """Each trial's diagnosis is given the plain source and the target's history rows: healthy rows
    in every repetition's training set and in none's test set; rows only (no label, nothing of how
    the target was drawn). Every unit, plain or corrected, scores the rows outside the history."""
    from gearlab.data.cache import load_or_build
    from gearlab.learn.protocol import history_of, split

    run, calls, cache, histories = corrected
    monkeypatch.setenv("GEARLAB_CACHE", str(cache))
    spec = load_scenario(run / "scenario.toml").spec
    protocol = spec.protocol
    drawn = tb.trials(spec)
    assert len(calls) == len(drawn) == 2  # one diagnosis per trial
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    for (name, source_spec, target_spec, _), call in zip(drawn, calls, strict=True):
        assert call["source"] == source_spec and not call["source"].effects and call["chain"] is None
        assert call["settings"] == spec.diagnosis and call["settings"].budget == 2
        assert isinstance(call["target_X"], np.ndarray) and call["target_X"].shape == (10, 4096)
        target, _ = load_or_build(target_spec)
        source, _ = load_or_build(source_spec)
        mean, std = target.reference
        physical = np.asarray(target.X, dtype=np.float64) * std + mean
        given = [int(np.flatnonzero(np.all(np.isclose(physical, row), axis=1))[0]) for row in call["target_X"]]
        history = history_of(protocol, target)
        assert sorted(given) == history.tolist()
        assert not target.fault[given].any()
        for rep in range(protocol.repetitions):
            s = split(protocol, source, target, rep, 0, history)
            assert not set(given) & set(s.target_test.tolist())
            assert set(given) <= set(s.target_train.tolist())
        # the units and the bound split with that history: it stays out of every test set they score
        given_to = [h for target_name, h in histories["units"] + histories["bounds"] if target_name == name]
        assert len(given_to) == 2 * 2 * 3 + 1 and all(np.array_equal(h, history) for h in given_to)
        scored = [r for r in records if r.get("trial") == name and "n_test" in r]
        assert len(scored) == 2 * 2 * 3  # two sources x two repetitions x three methods
        assert {r["n_test"] for r in scored} == {len(target.X) - protocol.target_train}


def test_each_trials_correction_says_its_score_evaluations(corrected):
    """Issue 41: a diagnosis's total of score evaluations was given nowhere; a trial's correction
    record keeps it and its log line says it."""
    run, _, _, histories = corrected
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    assert {r["evaluations"] for r in records if r["unit"].endswith("/correction")} == {57}
    said = [m for m in histories["logs"] if "the diagnosis of its history" in m]
    assert len(said) == 2 and all(": gap 10 -> 1 (57 score evaluations, " in m for m in said), said
    # the per-trial table has a column for them, the value each trial's correction record holds
    head, _, *rows = [line.split(" | ") for line in (run / "table.md").read_text().split("\n\n")[-1].splitlines()]
    col = head.index("evaluations")
    assert head[col - 1] == "fitted effects" and len(rows) == 2
    assert {r["trial"]: str(r["evaluations"]) for r in records if r["unit"].endswith("/correction")} == {
        row[0].lstrip("| "): row[col] for row in rows
    }


def test_both_sources_reported_per_trial_and_in_distribution(corrected):
    run, *_ = corrected
    summary = json.loads((run / "summary.json").read_text())
    plain = ["source_only (unsupervised)", "likelihood_ratio (unsupervised)", "mmd (unsupervised)"]
    assert summary["corrected"] and summary["methods"] == plain + [tb.corrected_label(m) for m in plain]
    assert tb.corrected_label(plain[2]) == "mmd (unsupervised, corrected source)"
    for name, t in summary["trials"].items():
        assert set(t["accuracy"]) == set(summary["methods"])
        assert [e["name"] for e in t["correction"]["effects"]] == ["bearing_stiffness", "sensor_noise"]
        assert (run / "states" / f"{name}-corrected").is_dir()  # its own source-only model and priming
    assert set(summary["per_method"]) == set(summary["methods"])
    table = (run / "table.md").read_text()
    assert (
        "| mmd (unsupervised, corrected source) |" in table
        and "bearing_stiffness c_factor=1 k_factor=0.5; sensor_noise" in table
        and "; left out: sensor_noise (noise) |" in table
    )
    lines = tb.summary_lines(RunDir.open(run))
    assert "the corrections of the source fitted (trials): bearing_stiffness 2, sensor_noise 2" in lines
    # the stand-in explains the gap: the correction is applied, its rows trained on the corrected source
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    assert [r["withheld"] for r in records if r["unit"].endswith("/correction")] == ["", ""]
    assert all(not t["correction"]["withheld"] for t in summary["trials"].values())
    assert not any(r.get("same_as_plain") for r in records) and WITHHELD not in table
    assert not any(WITHHELD in line for line in lines)


# A diagnosis that leaves the gap unexplained with effects fitted and kept: partly explained, under the
# share that applies them (against the noise fitted alone, reference 'noise', 95 % of what it leaves).
PARTLY = {"verdict": "partly explained", "unexplained": True, "explained_share": 0.95}


def test_an_unexplained_gap_leaves_the_plain_source_and_says_so(tmp_path, monkeypatch):
    """A tiny corrected run whose diagnosis leaves the gap unexplained: its corrected rows repeat the
    plain ones (no training on the fitted source) and the record, the table and the summary say why."""

    def diagnose(source, target_X, settings, executor=None, on_event=None, chain=None):
        effects = [{"name": n, "params": dict(p), "share_removed": 0.5} for n, p in FITTED]
        return {"gap_before": 10.0, "gap_after": 1.0, **PARTLY, "effects": effects, "corrected_effects": FITTED}

    path = tmp_path / "unexplained.toml"
    path.write_text(CORRECTED.replace("repetitions = 2", "repetitions = 1").replace("seed = 3", "seed = 3\nonly = [0]"))
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr("gearlab.gap.diagnose.diagnose", diagnose)
    run = run_scenario(path, out=tmp_path / "runs").path
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    (fit,) = [r for r in records if r["unit"].endswith("/correction")]
    assert fit["withheld"] == f"{WITHHELD} (partly explained, 95.00 % of the gap removed)"
    plain = {r["method"]: r for r in records if r.get("variant") == "plain"}
    fixed = [r for r in records if r.get("variant") == "corrected"]
    assert len(plain) == len(fixed) == 3 and not (run / "states" / "trial000-corrected").exists()
    for r in fixed:
        assert r["same_as_plain"] and r["accuracy"] == plain[r["method"].replace(", corrected source", "")]["accuracy"]
    assert f"left out: sensor_noise (noise); {fit['withheld']} |" in (run / "table.md").read_text()
    lines = tb.summary_lines(RunDir.open(run))
    assert f"{WITHHELD.replace(':', ',')} (the plain source used): trial000" in lines


def test_the_correction_is_applied_only_where_the_gap_is_explained():
    from gearlab.gap.diagnose import APPLY_SHARE, correction_withheld

    spec = load_scenario(Path(__file__).parents[1] / "scenarios" / "transfer_benchmark.toml").spec
    _, source, _, _ = tb.trials(spec)[0]
    record = {"trial": "trial000", "corrected_effects": FITTED}
    for verdict, applied in [
        ({"verdict": "explained", "unexplained": False, "explained_share": 0.9999}, True),
        ({"verdict": "partly explained", "unexplained": True, "explained_share": APPLY_SHARE}, True),
        ({"verdict": "partly explained", "unexplained": True, "explained_share": 0.9998}, True),  # seed 1, trial 2
        ({"verdict": "structure differs", "unexplained": True, "explained_share": None}, False),
        (PARTLY, False),
        ({"verdict": "unexplained", "unexplained": True, "explained_share": 0.4}, False),
        ({"unexplained": True}, False),  # a record from before the verdicts: read from 'unexplained'
        ({"unexplained": False}, True),
    ]:
        fixed = tb.corrected_spec(source, {**record, **verdict})
        assert (fixed is not source) == applied and (correction_withheld(verdict) == "") == applied
        assert applied or correction_withheld(verdict).startswith(WITHHELD)
    assert correction_withheld({"verdict": "unexplained", "explained_share": 0.0}) == f"{WITHHELD} (unexplained)"


def test_the_corrected_source_keeps_the_model_effects_not_the_noise():
    spec = load_scenario(Path(__file__).parents[1] / "scenarios" / "transfer_benchmark.toml").spec
    assert spec.correct and spec.diagnosis.budget == 16  # shipped: on, with the shipped budget
    _, source, _, _ = tb.trials(spec)[0]
    fixed = tb.corrected_spec(source, {"trial": "trial000", "corrected_effects": FITTED})
    assert [name for name, _ in fixed.effects] == ["bearing_stiffness"] and fixed.noise == source.noise
    assert fixed.name == "trial000-corrected-source" and fixed.key() != source.key()
    # noise alone fitted: the corrected source is the plain one (its runs repeat the plain rows)
    assert tb.corrected_spec(source, {"trial": "trial000", "corrected_effects": FITTED[1:]}) is source


def test_a_fitted_tone_stays_out_of_the_corrected_source(tiny):
    """A tone is not the same in every revolution (outside the detectors' model, as noise is): of a
    fitted tone, a model effect and noise, only the model effect reaches the corrected source, and
    the record says what was left out and why. Fitted at seed 1011, trial 002, a kept 39 Hz tone
    took every corrected method to chance."""
    _, source, _, _ = tb.trials(load_scenario(tiny).spec)[0]
    tone = ["interference_tone", [["frequency", 39.4], ["ratio", 0.55]]]
    record = {"trial": "trial000", "corrected_effects": [tone, *FITTED]}
    record["left_out"] = tb.left_out(source, record)
    assert [(e["name"], e["why"]) for e in record["left_out"]] == [
        ("interference_tone", "not the same every revolution"),
        ("sensor_noise", "noise"),
    ]
    assert [name for name, _ in tb.corrected_spec(source, record).effects] == ["bearing_stiffness"]
    alone = {"trial": "trial000", "corrected_effects": [tone]}
    assert tb.corrected_spec(source, {**alone, "left_out": tb.left_out(source, alone)}) is source
    text = tb.fitted_text({"effects": [{"name": "interference_tone", "params": {}}], **record})
    assert (
        text == "interference_tone; left out: interference_tone (not the same every revolution), sensor_noise (noise)"
    )


def test_only_runs_the_named_trials_as_drawn_in_the_full_run(cli, tmp_path):
    spec = load_scenario(Path(__file__).parents[1] / "scenarios" / "transfer_benchmark.toml").spec
    full = tb.trials(spec)
    picked = tb.trials(replace(spec, benchmark=replace(spec.benchmark, only=[3, 9])))
    assert [t[2] for t in picked] == [full[3][2], full[9][2]]
    code, _, err = cli("transfer-benchmark", "--trials", "4", "--only", "5", "--out", tmp_path / "runs")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "[benchmark] key 'only'" in err and "from 0 to 3" in err and not (tmp_path / "runs").exists()


def test_the_correction_record_and_table_say_the_load_the_corrected_source_carries(monkeypatch):
    """The corrected source runs at the load read beside the kept effects; where the diagnosis's report
    compared at another (read beside an effect since taken back), the table names both. The record keeps
    round 1's ranking too (each candidate's fit alone)."""
    from types import SimpleNamespace

    load = {"factor": 3.12, "report": 2.9, "read": [2.9, 3.12]}

    def diagnose(source, target_X, settings, executor=None, on_event=None, chain=None):
        effects = [{"name": n, "params": dict(p)} for n, p in FITTED]
        return {"gap_before": 10.0, "gap_after": 1.0, **PARTLY, "effects": effects, "corrected_effects": FITTED}

    ranking = [{"name": "sensor_bandwidth", "share_removed": 0.98, "params": {"f_n": 7.9e3, "zeta": 0.14}}]
    fitted = {"load": load, "ranking": ranking}  # round 1's fit of every candidate: a rule reads a rival off it
    monkeypatch.setattr("gearlab.gap.diagnose.diagnose", lambda *a, **k: {**diagnose(*a, **k), **fitted})
    target = SimpleNamespace(reference=(0.0, 1.0), X=np.zeros((4, 8)))
    spec = load_scenario(Path(__file__).parents[1] / "scenarios" / "transfer_benchmark.toml").spec
    record = tb.correction(spec, "trial000", spec.source, target, np.arange(2), None, lambda e: None)
    assert record["load"] == load and record["ranking"] == ranking
    record["unit"] = "trial000/correction"
    target_record = {"unit": "trial000/target", "trial": "trial000", "answers": {}, "bound": None}
    trial = tb.per_trial([target_record, record])["trial000"]
    shown = tb.fitted_text(trial["correction"] | {"effects": [], "withheld": ""})
    assert shown == "load 3.12 x (the report's 2.9 x)"
    same = {"factor": 0.62, "report": 0.62, "read": [0.62]}
    assert tb.fitted_text({"effects": [], "load": same}) == "load 0.62 x"
    assert tb.fitted_text({"effects": [], "load": None}) == "none"  # no load read (or a record from before)
