"""Scenario kind `detection`: simulated source, measured target files with roles; scores.csv;
the test files' labels (and signals) never reach training, thresholds or model selection."""

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import unrendered
from detection_scenario import FILES, flipped, run, run_in_module, scenario, scores

# its runs train the same tiny source and target again and again (the leak checks' flipped test files)
pytestmark = pytest.mark.usefixtures("trained_once")


@pytest.fixture
def cache(module_cache):
    """One dataset cache for the module (content-addressed): most tests simulate the same tiny source,
    and none asserts on whether a dataset was built or found."""
    return module_cache


@pytest.fixture(scope="module")
def plain_run(tmp_path_factory, module_cache) -> tuple[Path, Path]:
    """(scenario, run folder) of the tiny scenario as scenario() writes it, run from its records'
    folder (not the scenario's): the tests that read this run's outputs share it, none changes it."""
    folder = tmp_path_factory.mktemp("plain")
    path = scenario(folder)
    return path, run_in_module(path, folder / "runs", cwd=folder / "data")


@pytest.fixture(scope="module")
def three_seeds(tmp_path_factory, module_cache) -> Path:
    """The run folder of source_only trained with three seeds (an ensemble) beside the matched filter,
    on a source with both classes among its held-out tenth (every pinion tooth chipped, more healthy
    revolutions) and trained long enough to learn them: 10 epochs (each member's held-out AUC was 1.0 from 8
    epochs on, at 10 and 15 too, one member's 0.0 at 2; 40 took 9.1 s CPU, 15 5.5 s); the tests that read it share
    it."""
    folder = tmp_path_factory.mktemp("seeds")
    path = scenario(folder, methods=("source_only", "matched_filter"), detection="seeds = 3")
    text = path.read_text().replace("teeth = [1, 2, 3]", f"teeth = {list(range(1, 17))}")
    text = text.replace("healthy = 9", "healthy = 40").replace("baseline_epochs = 2", "baseline_epochs = 10")
    path.write_text(text.replace("patience = 2", "patience = 10"))
    return run_in_module(path, folder / "runs", figures=False)


def test_scores_csv_has_a_row_per_test_unit_and_method(plain_run):
    _, out = plain_run
    rows = scores(out)
    assert list(rows[0]) == ["file", "unit", "index", "method", "score", "decision"]
    assert {r["file"] for r in rows} == {"../data/h3.zip", "../data/f1.zip", "../data/f2.zip"}  # as written
    assert {r["method"] for r in rows} == {"source_only", "mmd", "matched_filter", "fm4", "na4"}
    assert {r["unit"] for r in rows} == {"revolution", "record5", "record10"}
    per = {}
    for r in rows:
        per.setdefault((r["file"], r["unit"], r["method"]), []).append(int(r["index"]))
    revs = len(per[("../data/f1.zip", "revolution", "fm4")])
    assert 38 <= revs <= 40
    for (_, unit, _), idx in per.items():
        n = {"revolution": revs, "record5": revs // 5, "record10": revs // 10}[unit]
        assert idx == list(range(n))
    assert {r["decision"] for r in rows} <= {"0", "1"}
    summary = json.loads((out / "summary.json").read_text())
    by = {(r["unit"], r["method"]): r for r in summary["rows"]}
    # the synthetic chip rings once a revolution: FM4 of the TSA finds every chipped record
    assert by[("record10", "fm4")]["auc"] == 1.0 and by[("record10", "fm4")]["detection"] == 100.0
    assert by[("record10", "fm4")]["false_alarm"] == 0.0
    table = (out / "table.md").read_text()
    assert table.count("record10 AUC | det % | FA %") == 1
    # how often each test label is called at the longest TSA: the healthy record never, the chipped ones always
    assert by[("record10", "fm4")]["called_by_label"] == {"healthy": 0.0, "fault": 100.0}
    assert "| record10: condition | method |" in table and "called % 'healthy'" in table
    assert "fm4" in (out / "report.html").read_text()


def test_the_report_draws_each_methods_roc_and_its_scores_per_record_and_in_time(plain_run):
    """Issue 41: the detection report has figures, each with an alt text and a caption, and titled
    tables. The ROC drawn of each method at the verdict's unit (the longest TSA) is made of the
    test scores the table's AUC is: the area under the drawn curve is the table's AUC, and the
    legend says it. The per-record figures split the history's scores by record (the units each
    history record gave) and place a test record's units at the revolution each starts at."""
    from gearlab.engine import load_scenario
    from gearlab.kinds import detection
    from gearlab.kinds.detection_figures import record_panels
    from gearlab.runs import RunDir

    path, out = plain_run
    figures = {p.name for p in (out / "figures").iterdir()}
    assert figures == {"detection_roc.png", "detection_scores_1.png", "detection_time_1.png"}
    html = (out / "report.html").read_text()
    for stem in ("detection_roc", "detection_scores_1", "detection_time_1"):
        figure = re.search(rf"<figure id='{stem}'><img alt='([^']+)' src='data:image/png;base64,[^']+'>"
                           r"<figcaption><b>Figure \d\.</b> ([^<]+)</figcaption>", html)  # fmt: skip
        assert figure and figure.group(1).startswith("Figure ") and "record10" in figure.group(2), stem
    assert "the legend gives each method&#x27;s ROC AUC" in html and "dashed: the method&#x27;s threshold" in html
    # every table titled by the kind (not made of its header), none left without one
    titles = re.findall(r"<caption><b>Table \d+\.</b> ([^<]+)</caption>", html)
    assert html.count("<table>") == len(titles) == 6
    assert titles[0].startswith("Condition 16 Hz: ROC AUC") and titles[1].startswith("Units called (%")
    # the which-gear tables (localisation of each test record, then the calls split by where)
    assert titles[2].startswith("Which gear (") and "watched: input pinion" in titles[2]
    assert titles[3].startswith("Units called (%") and "other damage" in titles[3]
    assert titles[4].startswith("What each method learned of the simulator")
    # each record's speed and how it was found (here the tacho's), and the turn that aligned it
    assert titles[5].startswith("Records: each record&#x27;s speed, how it was found")
    assert "| tacho " in (out / "table.md").read_text()
    # the column that was empty says what each domain loss aligns the history with
    summary = json.loads((out / "summary.json").read_text())
    aligned = {r["method"]: r["aligned_with"] for r in summary["learned"]}
    assert aligned["source_only"] == aligned["matched_filter"] == "– (no domain loss)"
    assert aligned["mmd"] in ("the source's healthy samples", "every source sample", "a point")

    rundir = RunDir(out)
    (roc,) = [c for c in detection.charts(load_scenario(path), rundir) if "ROC" in c.title]
    rows = {r["method"]: r for r in summary["rows"] if r["unit"] == "record10"}
    table = (out / "table.md").read_text()
    assert len(roc.curves) == len(rows) == 5
    for curve in roc.curves:
        method, shown = re.fullmatch(r"(.+) \(AUC ([0-9.]+)\)", curve.label).groups()
        assert float(shown) == pytest.approx(rows[method]["auc"], abs=5e-4)
        assert np.trapezoid(curve.y, curve.x) == pytest.approx(rows[method]["auc"], abs=1e-12)
        assert re.search(rf"\| {method} \| [0-9.]+ \| [0-9]+ \| [0-9]+ \| {shown} \|", table)  # record10's column
        assert curve.x[0] == curve.y[0] == 0.0 and curve.x[-1] == curve.y[-1] == 1.0
    # every chipped unit above every healthy one: all found before the first false alarm
    fm4 = next(c for c in roc.curves if c.label.startswith("fm4 "))
    assert rows["fm4"]["auc"] == 1.0 and max(y for x, y in zip(fm4.x, fm4.y) if x == 0.0) == 1.0

    conditions = json.loads((out / "conditions.json").read_text())
    ((_, panels),) = record_panels(summary, rundir.records(), conditions).items()
    records = {r["method"]: r for r in rundir.records()}
    for panel in panels:
        names = [name for name, _, _ in panel["records"]]
        assert names == ["h1", "h2", "h3", "f1", "f2"]  # the history's records, then the test's, negatives first
        assert [kind for _, kind, _ in panel["records"]] == ["history", "history", "healthy", "fault", "fault"]
        history = np.concatenate([s for _, kind, (_, s) in panel["records"] if kind == "history"])
        assert history.tolist() == records[panel["method"]]["history_scores"]["record10"]
        counts = conditions["16 Hz"]["history_units"]["record10"]
        assert [len(s) for _, kind, (_, s) in panel["records"] if kind == "history"] == counts
        _, _, (x, s) = panel["records"][3]
        assert s.tolist() == records[panel["method"]]["test_scores"]["../data/f1.zip"]["record10"]
        assert x.tolist() == [0, 10, 20][: len(s)]
        assert panel["threshold"] == records[panel["method"]]["thresholds"]["record10"]


@pytest.mark.parametrize("history_fit", ["all", "crossed"])
def test_test_labels_and_signals_never_reach_training_or_thresholds(
    cli, tmp_path, cache, handed, history_fit, monkeypatch
):
    """Flipping the test files' labels changes no score and no decision, only the figures; other
    test recordings change no history score, so no threshold and no trained model either. The
    networks are trained with two seeds (an ensemble) and thresholded by the random-effects
    model of the history's records: both see the history alone -- also when each history record
    is scored by the trainings that left it out (history_fit = "crossed")."""
    seen = handed
    runs = []
    if history_fit == "all":
        # the first run's figures built and written, not rendered (conftest.unrendered): those of a plain
        # history fit are rendered by test_verdict's and this module's report tests, the crossed fit's here
        monkeypatch.setattr("gearlab.plots.save", unrendered)
    for i, files in enumerate((FILES, flipped(FILES), flipped(FILES, signals=True))):
        folder = tmp_path / f"case{i}"
        folder.mkdir()
        detection = f'seeds = 2\nhistory_fit = "{history_fit}"'
        runs.append(run(cli, scenario(folder, files, detection=detection), tmp_path / "runs"))
        # the figures are drawn after every score is written, from the run's files, and nothing here
        # reads them: drawn in the first run (they must not fail for this setup), not again
        monkeypatch.setattr("gearlab.kinds.detection.draw_figures", lambda run: None)
    records = [{r["unit"]: r for r in map(json.loads, (d / "results.jsonl").read_text().splitlines())} for d in runs]
    first = scores(runs[0])
    for key in ("file", "unit", "index", "method", "score", "decision"):
        assert [r[key] for r in scores(runs[1])] == [r[key] for r in first]
    assert {u.rsplit("/", 1)[-1] for u in records[0]} >= {"seed0", "seed1"}  # an ensemble's members
    for rec in records[1:]:
        assert rec.keys() == records[0].keys()
        for unit, r in rec.items():
            assert r["history_scores"] == records[0][unit]["history_scores"]
            assert r.get("history") == records[0][unit].get("history")
            assert r["thresholds_by_rule"] == records[0][unit]["thresholds_by_rule"]
            assert r["history_models"] == records[0][unit]["history_models"]
    a, b = (json.loads((d / "summary.json").read_text()) for d in runs[:2])
    for ra, rb in zip(a["rows"], b["rows"]):
        assert ra["threshold"] == rb["threshold"]
        if ra["auc"] is not None:
            assert rb["auc"] == pytest.approx(1.0 - ra["auc"])
    # what training was handed: history revolutions only, the same in every run
    assert seen and all(np.array_equal(x, seen[i % (len(seen) // 3)]) for i, x in enumerate(seen))


def test_thresholds_cover_the_record_effect_and_an_ensemble_is_the_median_of_its_seeds(three_seeds):
    """Every threshold is the random-effects predictive quantile of the history's units split by
    record (recomputed here from results.jsonl); a method trained with three seeds scores the
    median of its members' scores standardised by their own history models, and only that
    ensemble reaches scores.csv and the table (with its members' AUC range)."""
    from gearlab.kinds.record_effects import WithinLaw, fit, independent_units, overlap_dof

    out = three_seeds
    records = {r["unit"]: r for r in map(json.loads, (out / "results.jsonl").read_text().splitlines())}
    n_hist = len(next(iter(records.values()))["history_scores"]["revolution"]) // 2  # two equal history records
    for r in records.values():
        for u, s in r["history_scores"].items():
            b, stride = {"revolution": (1, 1), "record5": (5, 1), "record10": (10, 1)}[u]
            per = len(s) // 2
            assert per == (n_hist - b) // stride + 1
            h = r["history_models"][u]
            # a detector's sigma_e is its scores' own within-record law's (detection_units.within_laws: TSAs drawn
            # again from every history revolution), and its quantile that law's, the normal one's times the record's
            # `tail`; every other method's sigma_e is its history units' and its quantile the normal one (tail 1)
            law = WithinLaw(np.zeros(0), h["unit_sd"] ** 2, h["unit_dof"]) if r["method"] == "matched_filter" else None
            m = fit(
                [s[:per], s[per:]],
                0.99,
                [independent_units(per, b, stride)] * 2,
                [overlap_dof(per, b, stride)] * 2,
                law=law,
            )
            if law is not None and u != "revolution":  # not the sliding TSAs' own spread
                assert h["unit_sd"] != pytest.approx(fit([s[:per], s[per:]], 0.99).unit_sd, rel=1e-3)
            tail = h["tail"]
            assert tail == 1.0 or r["method"] == "matched_filter"
            assert r["thresholds"][u] == pytest.approx(m.mean + (m.threshold - m.mean) * tail)
            assert r["thresholds_by_rule"]["records"][u] == r["thresholds"][u]
    ensemble = next(r for r in records.values() if r.get("members"))
    assert len(ensemble["members"]) == 3 and ensemble["method"] == "source_only"
    members = [records[m] for m in ensemble["members"]]
    assert {m["seed"] for m in members} == {0, 1, 2}
    assert len({json.dumps(m["history_scores"]) for m in members}) == 3  # three different trainings
    assert not any(r.get("members") for r in records.values() if r["method"] == "matched_filter")  # no seeds

    def z(m, scores, u):
        h = m["history_models"][u]
        sd = np.sqrt((h["record_sd"] or 0.0) ** 2 + h["unit_sd"] ** 2 + h["mean_se"] ** 2)
        return (np.asarray(scores) - h["mean"]) / sd

    for path, units in ensemble["test_scores"].items():
        for u, s in units.items():
            expected = np.median([z(m, m["test_scores"][path][u], u) for m in members], axis=0)
            assert s == pytest.approx(expected, rel=1e-6, abs=1e-9)
    rows = scores(out)
    assert {r["method"] for r in rows} == {"source_only", "matched_filter", "fm4", "na4"}
    assert len([r for r in rows if r["method"] == "source_only"]) == len([r for r in rows if r["method"] == "fm4"])
    assert re.search(r"\| source_only \| [0-9.]+ \([0-9.]+–[0-9.]+\) \|", (out / "table.md").read_text())
    summary = json.loads((out / "summary.json").read_text())
    row = next(r for r in summary["rows"] if r["method"] == "source_only" and r["unit"] == "record10")
    assert len(row["member_auc"]) == 3 and set(row["by_rule"]) == {"records", "pooled"}


def test_each_learned_row_keeps_what_it_learned_of_the_simulator_and_its_time(three_seeds):
    """Every training keeps the ROC AUC of a network's scores of the source's held-out revolutions
    (training data only) and its time; an ensemble the median of its members' AUCs and the sum of
    their times. Trained long enough, source_only ranks the noise-free simulator's held-out chips
    first; the matched filter, built on the history, has no source AUC. table.md lists the learned
    rows, not the classical ones, and the report's verdict judges every condition."""
    out = three_seeds
    records = {r["unit"]: r for r in map(json.loads, (out / "results.jsonl").read_text().splitlines())}
    ensemble = next(r for r in records.values() if r.get("members"))
    members = [records[m] for m in ensemble["members"]]
    assert all(m["source_auc"] >= 0.9 and m["seconds"] > 0 for m in members)
    assert ensemble["source_auc"] == pytest.approx(np.median([m["source_auc"] for m in members]))
    assert ensemble["part_source_auc"] == [m["source_auc"] for m in members]
    assert ensemble["seconds"] == pytest.approx(sum(m["seconds"] for m in members))
    # the held-out tenth of the 40 healthy and 16 chipped source revolutions, both classes in it
    assert ensemble["source_units"] == members[0]["source_units"] and sum(ensemble["source_units"]) == 6
    assert min(ensemble["source_units"]) >= 1
    matched = next(r for r in records.values() if r["method"] == "matched_filter")
    assert matched["source_auc"] is None and matched["seconds"] > 0
    assert not any("source_auc" in r for r in records.values() if r["method"] in ("fm4", "na4"))
    summary = json.loads((out / "summary.json").read_text())
    assert [r["method"] for r in summary["learned"]] == ["source_only", "matched_filter"]
    table = (out / "table.md").read_text()
    assert "| condition | method | source AUC | bound | training (s) | history aligned with |" in table
    # a noise-free source has no bound (every simulated fault differs from healthy)
    assert re.search(r"\| source_only \| [0-9.]+ \([0-9.]+–[0-9.]+\) \| – \| [0-9]+ \|", table)
    assert re.search(r"\| matched_filter \| – \| – \| [0-9]+ \|", table)
    report = (out / "report.html").read_text()
    assert "Verdict" in report and "best learned" in report


def test_crossed_history_fit_scores_each_history_record_by_the_training_that_left_it_out(
    cli, tmp_path, cache, handed, no_figures
):
    """history_fit = "crossed": one training per history record, handed the other records' revolutions
    only; the method's history scores are each record's scores by the training that left it out,
    standardised by that training's model of the records it trained on, its test scores the mean of
    the trainings' standardised scores, and its threshold the rule's on those history scores. Only
    the method (not its folds) reaches scores.csv. With one history record it is refused."""
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import learned_input, read_target
    from gearlab.kinds.record_effects import fit, independent_units, overlap_dof

    path = scenario(tmp_path, methods=("source_only",), detection='history_fit = "crossed"')
    out = run(cli, path, tmp_path / "runs")
    records = {r["unit"]: r for r in map(json.loads, (out / "results.jsonl").read_text().splitlines())}
    crossed = next(r for r in records.values() if r.get("folds"))
    folds = [records[u] for u in crossed["folds"]]
    assert [f["fold"] for f in folds] == [0, 1] and crossed["method"] == "source_only"
    # what each training was handed: revolutions of the history record it did not leave out
    spec = load_scenario(path).spec
    ((_, cond),) = read_target(spec.target, spec.detection.blocks, lambda e: None).items()
    shown = learned_input(spec.detection.input, spec.detection.points, spec.classical, cond["max_order"])
    history = [shown(r) for _, r in cond["history"]]

    def among(rows, pool) -> bool:
        return all(np.abs(pool - row).max(axis=1).min() < 1e-6 for row in rows)

    assert len(handed) == 2
    for k, rows in enumerate(handed):
        assert among(rows, history[1 - k]) and not among(rows, history[k])
    windows = {"revolution": (1, 1), "record5": (5, 1), "record10": (10, 1)}
    expected_hist = {}
    for u, (b, stride) in windows.items():
        per = len(folds[0]["history_scores"][u]) // 2  # two equal history records
        parts, tests = [], []
        for k, f in enumerate(folds):
            s = np.asarray(f["history_scores"][u])
            own, other = (s[:per], s[per:]) if k == 0 else (s[per:], s[:per])
            m = fit([other], 0.99, [independent_units(per, b, stride)], [overlap_dof(per, b, stride)])
            sd = np.sqrt(m.unit_sd**2 + m.mean_se**2)
            parts.append((own - m.mean) / sd)
            tests.append({p: (np.asarray(f["test_scores"][p][u]) - m.mean) / sd for p in f["test_scores"]})
        expected_hist[u] = np.concatenate(parts)
        assert crossed["history_scores"][u] == pytest.approx(expected_hist[u], rel=1e-6, abs=1e-9)
        for p, s in crossed["test_scores"].items():
            assert s[u] == pytest.approx((tests[0][p] + tests[1][p]) / 2, rel=1e-6, abs=1e-9)
        m = fit(
            [expected_hist[u][:per], expected_hist[u][per:]],
            0.99,
            [independent_units(per, b, stride)] * 2,
            [overlap_dof(per, b, stride)] * 2,
        )
        assert crossed["thresholds"][u] == pytest.approx(m.threshold, rel=1e-6)
    methods = [r["method"] for r in scores(out) if r["unit"] == "record10"]
    assert methods.count("source_only") == methods.count("fm4")  # the folds are not rows of their own
    one = [f for f in FILES if f[0] != "h2"]
    lone = tmp_path / "lone"
    lone.mkdir()
    code, _, err = cli("run", scenario(lone, one, detection='history_fit = "crossed"'), "--out", tmp_path / "r2")
    assert code == 2 and "[detection] key 'history_fit'" in err and "at least two" in err
    assert not list((tmp_path / "r2").rglob("results.jsonl"))
    # a training that leaves a record out has fewer history rows: a batch above them is refused up front
    # (the source large enough for that batch, which is checked first, from its spec)
    text = path.read_text().replace("target_train = 8\nbatch = 4", "target_train = 60\nbatch = 45")
    path.write_text(text.replace("faults = { chip = [20] }\nhealthy = 9", "faults = { chip = [20] }\nhealthy = 60", 1))
    code, _, err = cli("run", path, "--out", tmp_path / "r3")
    assert code == 2 and "[protocol] key 'batch': 45" in err and "left out" in err
    assert not list((tmp_path / "r3").rglob("results.jsonl"))


def test_the_learned_methods_see_the_points_per_revolution_asked_for(cli, tmp_path, cache, monkeypatch, no_figures):
    """[detection] points = 1024: every method is handed source, held-out and history rows of 1024
    samples, each the band-limited form of what it would see at 4096, and the test units it scores
    too; the classical rows are not touched. The band is the records' own: these hold 512 samples
    a revolution, so nothing above order 230 (90 % of their Nyquist order 256), and the simulated
    source is cut there too. Out of range: refused."""
    import gearlab.learn.protocol as P
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import learned_input, read_target

    handed, scored = [], []
    train_method, fault_score = P.train_method, P.fault_score

    def spy(protocol, method, source, source_val, target, *args, **kwargs):
        handed.append((np.array(source[0]), np.array(source_val[0]), np.array(target[0])))
        return train_method(protocol, method, source, source_val, target, *args, **kwargs)

    def score_spy(model, X, device, *args, **kwargs):
        scored.append(np.shape(X)[-1])
        return fault_score(model, X, device, *args, **kwargs)

    monkeypatch.setattr(P, "train_method", spy)
    monkeypatch.setattr("gearlab.kinds.detection_units.fault_score", score_spy)
    path = scenario(tmp_path, methods=("source_only", "matched_filter"), detection="points = 1024")
    out = run(cli, path, tmp_path / "runs")
    assert handed and all(x.shape[-1] == 1024 for rows in handed for x in rows)
    assert scored and set(scored) == {1024}
    spec = load_scenario(path).spec
    ((_, cond),) = read_target(spec.target, spec.detection.blocks, lambda e: None).items()
    assert cond["max_order"] == 230
    full = learned_input(spec.detection.input, 4096, spec.classical)
    history = np.concatenate([full(r) for _, r in cond["history"]])
    spectrum = np.fft.rfft(history, axis=-1)
    spectrum[..., 231:] = 0.0
    expected = np.fft.irfft(spectrum, n=4096, axis=-1)[..., ::4]  # the band-limited rows at every 4th angle
    rows = handed[0][2]
    assert all(np.abs(expected - row).max(axis=1).min() < 1e-5 for row in rows)
    for source, held_out, _ in handed:  # the simulated rows hold nothing above the records' band either
        for x in (source, held_out):
            power = np.abs(np.fft.rfft(x, axis=-1)) ** 2
            assert power[..., 231:].sum() < 1e-9 * power.sum() and power[..., 200:231].sum() > 0
    assert {r["method"] for r in scores(out)} >= {"fm4", "source_only", "matched_filter"}
    path.write_text(path.read_text().replace("points = 1024", "points = 32"))
    code, _, err = cli("validate", path)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "[detection] key 'points'" in err
    # in range, but fewer than the network takes: refused before any work too
    path.write_text(path.read_text().replace("points = 32", "points = 100").replace('name = "fast"', 'name = "cnn3"'))
    code, _, err = cli("validate", path)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "[detection] key 'points': 100 is too few" in err and "at least 113 samples" in err


def test_pinion_sync_runs_end_to_end_and_writes_which_shaft(cli, tmp_path, cache):
    """The detection kind with pinion_sync listed: scores.csv has its rows, shafts.csv names a
    shaft (or nothing) for every test unit with each shaft's strength, a called pinion fault on the
    input shaft, and table.md has the per-label attribution. Units too short for a shaft's turn (the
    output's 5 revolutions in a TSA5) give it no part, and the other shafts still decide."""
    path = scenario(tmp_path, methods=("matched_filter",))
    path.write_text(
        path.read_text().replace(
            "mesh_orders = [32]",
            'mesh_orders = [32]\nindicators = ["fm4", "pinion_sync"]\nshafts = { idler = 3, output = 5 }',
        )
    )
    out = run(cli, path, tmp_path / "runs")
    rows = [r for r in scores(out) if r["method"] == "pinion_sync"]
    assert rows and all(np.isfinite(float(r["score"])) for r in rows)
    with (out / "shafts.csv").open() as f:
        shafts = list(csv.DictReader(f))
    assert len(shafts) == len(rows)
    assert {r["shaft"] for r in shafts} <= {"input", "idler", "output", "nothing"}
    strength = {(r["file"], r["unit"], r["index"]): r for r in shafts}
    for r in rows:  # a called pinion fault is put on the input shaft, within the input TSA's content
        if r["decision"] == "1":
            s = strength[(r["file"], r["unit"], r["index"])]
            assert s["shaft"] == "input" and float(r["score"]) <= float(s["strength_input"]) + 1e-9, (r, s)
    assert any(r["decision"] == "1" for r in rows)
    assert all(r["strength_output"] == "nan" for r in shafts if r["unit"] == "record5")
    assert all(r["shaft"] == "input" for r in shafts if r["unit"] == "record10" and "f" in Path(r["file"]).stem)
    assert "Which shaft (pinion_sync, record10" in (out / "table.md").read_text()
    assert "Which shaft (pinion_sync, record10" in (out / "report.html").read_text()


@pytest.mark.parametrize(
    "key, value, message",
    [
        ("threshold", "pooeld", "'pooeld' is not one of records, pooled (did you mean 'pooled'?)"),
        ("source_speed", "record", "'record' is not one of records, source (did you mean 'records'?)"),
        ("input", "raw", "'raw' is not one of difference, revolution"),
    ],
)
def test_the_detection_choices_are_checked(cli, tmp_path, key, value, message):
    """[detection]'s threshold rule, source speed and input: one line naming the key, the value and
    the choices (checked with the key's type, before any other check of the scenario)."""
    path = scenario(tmp_path, methods=("matched_filter",), detection=f'{key} = "{value}"')
    code, _, err = cli("validate", path)
    assert code == 2 and f"[detection] key '{key}': {message}" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "protocol, methods, message",
    [
        ('threshold = "argmax"', "", "[protocol] key 'threshold': a detection scenario's one threshold rule is "
         "[detection] threshold ('records' or 'pooled')"),
        ("false_alarm = 0.05", "", "[protocol] key 'false_alarm': a detection scenario's one false-alarm rate is "
         "[detection] false_alarm"),
        ("", "params = { false_alarm = 0.05 }\n", "[[methods]] #1 key 'params': false_alarm is set once for the "
         "scenario: [detection] false_alarm"),
    ],
)  # fmt: skip
def test_one_threshold_rule_and_one_false_alarm_rate(cli, tmp_path, protocol, methods, message):
    """An older file's second threshold key or false-alarm rate is one line naming the one to use;
    the models' own thresholds keep gearlab's recipe (re-fixed on the history's units anyway)."""
    from gearlab.engine import load_scenario
    from gearlab.learn.config import RECIPE

    path = scenario(tmp_path, methods=("matched_filter",), detection="false_alarm = 0.05")
    spec = load_scenario(path).spec
    assert spec.detection.false_alarm == 0.05
    assert (spec.protocol.calibration.threshold, spec.protocol.calibration.false_alarm) == ("history", 0.01)
    assert dict(spec.protocol.methods[0].params)["false_alarm"] == RECIPE.false_alarm
    text = path.read_text().replace('adapter = "matched_filter"\n', f'adapter = "matched_filter"\n{methods}')
    path.write_text(text.replace("[protocol]\n", f"[protocol]\n{protocol}\n"))
    code, _, err = cli("validate", path)
    assert code == 2 and message in err and len(err.splitlines()) == 1, err


def test_relative_paths_follow_the_scenario_file_and_the_run_keeps_them(plain_run):
    _, out = plain_run  # run from the records' folder: anywhere but the scenario's
    from gearlab.engine import scenario_of
    from gearlab.runs import RunDir

    assert scenario_of(RunDir.open(out)).spec.target.files[0].path == "../data/h1.zip"


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda t: t.replace('role = "history"', 'role = "histroy"', 1), "role 'histroy' .*did you mean 'history'"),
        (lambda t: t.replace('label = "healthy" },', 'label = "healthy", lable = "x" },', 1), "unknown key 'lable'"),
        (lambda t: t.replace("../data/h1.zip", "../data/nope.zip"), "nope.zip: no such file"),
        (lambda t: t.replace("fs = ", "fz = "), "key 'fz': unknown key .*did you mean 'fs'"),
        (lambda t: t.replace('"10 mV/g"', '"10 mV"'), "key 'sensitivity'.*wrong dimension"),
        (lambda t: t.replace('adapter = "mmd"', 'adapter = "target_only"'), "no unsupervised variant"),
        (lambda t: t.replace('adapter = "mmd"', 'adapter = "mmd"\nsupervised = true'), "no labels a method may use"),
        (lambda t: t.replace("blocks = [5, 10]", "blocks = [1]"), "key 'blocks'"),
        (
            lambda t: t.replace("target_train = 8\nbatch = 4", "target_train = 14\nbatch = 12"),
            r"\[protocol\] key 'batch': 12 is larger than the source training set \(11 of the 12 samples.*; "
            r"expected batch <= 11: a smaller \[protocol\] batch, or more simulated samples \(\[source\] healthy",
        ),
        (
            lambda t: t.replace("mesh_orders = [32]", "mesh_orders = [32]\nslow_shafts = [1, 3]"),
            r"\[classical\] key 'slow_shafts': expected whole numbers of input revolutions 2",
        ),
        (
            lambda t: t.replace("mesh_orders = [32]", "mesh_orders = [32]\nshafts = { idler = 1.5 }"),
            r"\[classical\] key 'shafts': expected \{name = whole number of input revolutions 2",
        ),
        (
            lambda t: t.replace("mesh_orders = [32]", "mesh_orders = [32]\nshafts = { input = 3 }"),
            r"\[classical\] key 'shafts': 'input' and 'nothing' are taken",
        ),
        (
            lambda t: t.replace('preset = "B-6-ch5"', 'file = "../data/h1.zip"\nvibration = "0"\nspeed = 16.0'),
            r"\[source\] key 'file': the source is a simulator configuration",
        ),
    ],
)
def test_bad_target_is_refused_before_any_work(cli, tmp_path, change, message):
    path = scenario(tmp_path)
    path.write_text(change(path.read_text()))
    code, _, err = cli("validate", path)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert re.search(message, err), err


def test_a_condition_without_history_is_refused_and_leaves_no_run(cli, tmp_path, cache):
    path = scenario(tmp_path, methods=("matched_filter",))
    # the test records at another speed form a condition of their own, with no history
    path.write_text(path.read_text().replace('label = "fault" },', 'label = "fault", condition = "other" },'))
    code, _, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 2 and "condition 'other'" in err and "no history record" in err and str(path) in err
    assert not list((tmp_path / "runs").rglob("scores.csv"))


def test_blocks_longer_than_the_history_are_refused_and_leave_no_run(cli, tmp_path, cache):
    path = scenario(tmp_path, methods=("matched_filter",))
    path.write_text(path.read_text().replace("blocks = [5, 10]", "blocks = [5, 45]"))
    code, _, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 2 and "gives 0 'record45' units" in err and "shorter [detection] blocks" in err
    assert str(path) in err
    assert not list((tmp_path / "runs").rglob("scores.csv"))


def test_without_methods_every_label_free_adapter_runs(tmp_path):
    from gearlab.engine import load_scenario
    from gearlab.registry import get_registry

    path = scenario(tmp_path, methods=())
    spec = load_scenario(path).spec
    registry = get_registry()
    expected = {n for n in registry.names("adapter") if registry.get("adapter", n).train_on != "target"}
    expected |= set(registry.names("detector"))
    assert {m.adapter for m in spec.protocol.methods} == expected
    assert {"source_only", "mmd", "dann", "coral", "matched_filter"} <= expected


def test_scores_that_are_not_numbers_give_no_auc_and_are_counted():
    """A NaN compares false with everything: counted as a score it would read as AUC 0 (the
    faults ranked last), as likelihood_ratio's NaN scores once did. It gives no AUC, and the
    table says how many scores were not numbers."""
    from gearlab.kinds.detection_tables import table_md
    from gearlab.parts.roc import auc

    assert auc([0.1, 0.2], [0.3, 0.4]) == 1.0 and auc([0.3, 0.4], [0.1, 0.2]) == 0.0
    assert auc([0.1, np.nan], [0.3, 0.4]) is None and auc([0.1], [np.inf]) is None
    row = {"condition": "c", "unit": "record30", "detection": 0.0, "false_alarm": 0.0, "n_positive": 2}
    rows = [
        {**row, "method": "lr", "auc": None, "non_finite": 7, "n_negative": 2},
        {**row, "method": "fm4", "auc": 1.0, "non_finite": 0, "n_negative": 2},
    ]
    table = table_md(rows)
    assert "| lr | – |" in table and "not numbers" in table and "lr 7" in table and "fm4 0" not in table
