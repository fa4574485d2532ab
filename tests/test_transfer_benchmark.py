"""The `transfer_benchmark` kind: random unseen targets drawn from documented ranges, the recipe
frozen for all of them, each trial beside its own Bayes bound (or told unavailable), and the
selection rule printed with every run."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from tiny import EXECUTION, SCHEDULE

from gearlab.engine import load_scenario, run_scenario
from gearlab.kinds import SCENARIO_KINDS
from gearlab.kinds import transfer_benchmark as tb
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
    other = tb.trials({**spec, "benchmark": {**spec["benchmark"], "seed": 1000}})
    assert [t[2] for t in other] != [t[2] for t in drawn]
    laws, sensors, models, tones = set(), set(), set(), 0
    for _, source, target, a in drawn:
        assert source.speed_hz == target.speed_hz and source.load_nm == spec["source"].load_nm  # load unknown
        assert tb.SPEED_HZ[0] <= a["speed_hz"] <= tb.SPEED_HZ[1] and tb.LOAD_NM[0] <= a["load_nm"] <= tb.LOAD_NM[1]
        assert tb.SNR_DB[0] <= a["snr_db"] <= tb.SNR_DB[1]
        assert 2 <= len(a["faults"]) <= 4 and set(a["faults"]) <= {n for n, _ in spec["source"].faults}
        fault_rows = sum(len(s) for _, s in target.faults) * len(target.teeth)
        assert target.healthy == spec["protocol"].target_train + fault_rows  # the test set is half faulty
        for effect, params in a["effects"].items():
            ranges = {**tb.MODEL_EFFECTS, **tb.SENSORS, "interference_tone": tb.TONE}[effect]
            for key, value in params.items():
                assert ranges[key][0] <= value <= ranges[key][1], (effect, key)
        laws.add(a["noise"])
        sensors.add(a["sensor"])
        models.add(a["model"])
        tones += a["tone"]
    # 24 trials cover every law, sensor and model mismatch, and some tones
    assert laws == {"gaussian", "laplace", "student_t"} and sensors == set(tb.SENSORS)
    assert models == set(tb.MODEL_EFFECTS) and 0 < tones < len(drawn)


def test_registered_validated_and_a_supervised_method_refused(tiny, cli):
    assert SCENARIO_KINDS["transfer_benchmark"] is tb
    code, out, err = cli("validate", tiny)
    assert code == 0, err
    assert "2 random targets" in out and "development" in out
    tiny.write_text(TINY.replace('adapter = "mmd"', 'adapter = "mmd"\nsupervised = true'))
    code, _, err = cli("validate", tiny)
    assert code == 2 and "\n" not in err.strip()
    assert "[[methods]] #3 key 'supervised'" in err and str(tiny) in err


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
        for acc in t["accuracy"].values():
            assert 0.0 <= acc <= 100.0
    for label, m in summary["per_method"].items():
        assert m["trials"] == 2 and m["median"] == pytest.approx(
            np.median([t["accuracy"][label] for t in summary["trials"].values()])
        )
    assert set(summary["domain_gain"]) == {"source_only (unsupervised)", "mmd (unsupervised)"}
    lines = SCENARIO_KINDS["transfer_benchmark"].summary_lines(RunDir.open(run))
    assert lines[0].startswith("selection rule") and "seed 3 (development)" in lines[0]
    assert (run / "figures" / "transfer_benchmark.png").exists() and "<img" in (run / "report.html").read_text()
