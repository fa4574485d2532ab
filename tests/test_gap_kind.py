"""The `gap` scenario kind: validation, a tiny run end to end, summary fields, resume, live
tables and charts on a partial run, and bad input refused before any work.

Most tests replace gearlab.gap.diagnose by a stand-in that follows the shared contract: they
test the kind's plumbing (records, resume, summary, tables, figures, accuracy units), not the
search. One test runs the real diagnosis on a tiny scenario."""

from __future__ import annotations

import json
import re
import sys
import types
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from tiny import EXECUTION, domains, run_once, schedule

from gearlab.engine import load_scenario
from gearlab.gap.stats import gap_report
from gearlab.kinds import SCENARIO_KINDS, gap
from gearlab.parts.bound import BOUND
from gearlab.runs import RunDir

TINY = (
    """\
[scenario]
name = "tinygap"
kind = "gap"

"""
    + domains(healthy=14)
    + """
[diagnosis]
candidates = ["sensor_noise", "drive_inertias"]
budget = 2
max_effects = 1
healthy = 10
bootstrap = 10
permutations = 20
seed = 0

[accuracy]
methods = ["mmd", "matched_filter"]
repetitions = 1
"""
    + schedule().replace("target_train = 8", "target_train = 10")  # the history: >= 10 rows for the statistics
    + "\n"
    + EXECUTION
)

ACCURACY_UNITS = [
    "rep0/uncorrected/source_only-unsup",
    "rep0/corrected/source_only-unsup",
    "rep0/uncorrected/matched_filter-unsup",
    "rep0/corrected/matched_filter-unsup",
    "rep0/uncorrected/mmd-unsup",
]


# --- a stand-in for gearlab.gap.diagnose (the shared contract) ------------------------------------


def fake_module(calls: list) -> types.ModuleType:
    """diagnose() returning a contract-shaped result from real gap reports; it records what it
    was given, so that a test can check that nothing of the target but its rows goes in."""
    from dataclasses import dataclass

    mod = types.ModuleType("gearlab.gap.diagnose")

    @dataclass(frozen=True)
    class Settings:
        candidates: tuple = ()
        budget: int = 16
        max_effects: int = 3
        healthy: int = 40
        bootstrap: int = 200
        permutations: int = 500
        alpha: float = 0.05
        seed: int = 0
        reference: str = "source"
        consecutive: object = "auto"
        max_order: int = 0

    def diagnose(source, target_X, settings, executor=None, on_event=lambda e: None, chain=None):
        calls.append({"source": source, "target_X": target_X, "settings": settings, "chain": chain})
        rng = np.random.default_rng(0)
        scale = target_X.std()
        shifted = target_X[::-1] + 3 * scale  # a large gap before
        close = target_X[::-1] + 0.01 * scale * rng.standard_normal(target_X.shape)
        kw = dict(
            pair=(25, 30),
            bootstrap=settings.bootstrap,
            permutations=settings.permutations,
            alpha=settings.alpha,
            seed=settings.seed,
        )
        before, after = gap_report(shifted, target_X, **kw), gap_report(close, target_X, **kw)
        params = {"kind": "laplace", "snr_db": 0.5}
        return {
            "before": before,
            "after": after,
            "gap_before": before["total"]["gap"],
            "gap_after": after["total"]["gap"],
            "significant_before": before["significant"],
            "significant_after": after["significant"],
            "effects": [
                {
                    "name": "sensor_noise",
                    "share_removed": 0.9,
                    "params": params,
                    "intervals": {"snr_db": [0.0, 1.0]},
                    "round": 1,
                }
            ],
            "ranking": [
                {"name": "sensor_noise", "share_removed": 0.9, "params": params},
                {"name": "drive_inertias", "share_removed": 0.1, "params": {"I11": 0.004}},
            ],
            "unexplained": False,
            "corrected_effects": [["sensor_noise", [["kind", "laplace"], ["snr_db", 0.5]]]],
            "settings": {"budget": settings.budget},
            "evaluations": 1234,
        }

    def corrected_source(source, result):
        effects = tuple((name, tuple(tuple(p) for p in params)) for name, params in result["corrected_effects"])
        return source.with_(effects=source.effects + effects)

    mod.Settings, mod.diagnose, mod.corrected_source = Settings, diagnose, corrected_source
    return mod


@pytest.fixture
def calls(monkeypatch):
    log: list = []
    monkeypatch.setitem(sys.modules, "gearlab.gap.diagnose", fake_module(log))
    return log


@pytest.fixture
def tiny(write_scenario, module_cache):
    return write_scenario(TINY, "tinygap.toml")


@pytest.fixture(scope="module")
def finished(tmp_path_factory, module_cache):
    """One uninterrupted run of the tiny scenario with the stand-in diagnosis."""
    log: list = []
    base = tmp_path_factory.mktemp("finished")
    run = run_once(base, "tinygap.toml", TINY, module_cache, {"gearlab.gap.diagnose": fake_module(log)})
    return run, log


def records(run: Path) -> dict[str, dict]:
    return {r["unit"]: r for r in map(json.loads, (run / "results.jsonl").read_text().splitlines())}


# --- validation ------------------------------------------------------------------------------------


def test_registered_and_validates(tiny, cli):
    assert SCENARIO_KINDS["gap"] is gap
    code, out, err = cli("validate", tiny)
    assert code == 0, err
    assert "kind gap" in out and "2 candidate effects" in out


def test_shipped_gap_scenarios_validate(cli):
    root = Path(__file__).resolve().parents[1] / "scenarios"
    for name in ("gap_expA.toml", "gap_expB.toml"):
        code, out, err = cli("validate", root / name)
        assert code == 0, err
        s = load_scenario(root / name)
        assert s.spec.settings.candidates == ()  # every registered effect


def test_quick_shrinks(tiny):
    s = load_scenario(tiny.parent / "tinygap.toml")
    s.spec = replace(s.spec, settings=replace(s.spec.settings, budget=16))
    gap.quick(s)
    assert s.spec.settings.budget == 4 and s.spec.protocol.repetitions == 1


# --- a run -----------------------------------------------------------------------------------------


def test_run_summary_fields(finished):
    run, log = finished
    summary = json.loads((run / "summary.json").read_text())
    assert summary["kind"] == "gap" and summary["scenario"] == "tinygap"
    for key in ("gap_before", "gap_after", "auc_before", "auc_after", "p_before", "p_after"):
        assert isinstance(summary[key], float), key
    for key in ("unexplained", "significant_before", "significant_after"):
        assert isinstance(summary[key], bool), key
    assert summary["effects"][0]["name"] == "sensor_noise"
    assert set(summary["effects"][0]) >= {"name", "share_removed", "params"}
    assert [r["name"] for r in summary["ranking"]] == ["sensor_noise", "drive_inertias"]
    assert set(summary["views"]) >= {"shaft", "mesh", "sidebands", "noise_floor", "waveform"}
    for v in summary["views"].values():
        assert isinstance(v["gap_before"], float) and isinstance(v["gap_after"], float)
    assert summary["accuracy_order"] == [
        "source_only (uncorrected)",
        "source_only (corrected)",
        "matched_filter (uncorrected)",
        "matched_filter (corrected)",
        "mmd (unsupervised)",
        BOUND,  # the reference row: the target is simulated with noise
    ]
    for cell in summary["accuracy"].values():
        assert 0 <= cell["mean"] <= 100 and cell["n"] == 1
    assert summary["source"]["model"] == "six_dof" and summary["target"]["model"] == "eight_dof"
    assert sorted(records(run)) == sorted(["diagnosis", *ACCURACY_UNITS, "bound"])
    # the corrected source really is another dataset: the fitted effect was added to it
    corrected = records(run)["rep0/corrected/source_only-unsup"]
    assert corrected["variant"] == "corrected"
    # a detector matches the expected response: the fitted noise is left out of its fault shapes,
    # which here leaves the uncorrected source's
    detectors = [records(run)[f"rep0/{v}/matched_filter-unsup"] for v in ("uncorrected", "corrected")]
    assert (
        detectors[0]["accuracy"] == detectors[1]["accuracy"] and detectors[0]["confusion"] == detectors[1]["confusion"]
    )
    # outputs: three tables, the figures, the report with every figure inlined
    table = (run / "table.md").read_text()
    assert table.count("| view |") == 1 and "| effect |" in table and "source_only (corrected)" in table
    figures = {p.name for p in (run / "figures").glob("*.png")}
    assert figures == {"gap_per_view.png", "gap_effect_ranking.png", "gap_accuracy.png"}
    html = (run / "report.html").read_text()
    assert html.count("<table>") == 3 and html.count("<img") == 3


def test_diagnosis_sees_only_the_target_rows(finished):
    _, log = finished
    (call,) = log
    assert isinstance(call["target_X"], np.ndarray) and call["target_X"].shape == (10, 4096)
    assert call["source"].model == "six_dof" and not call["source"].effects and call["source"].noise is None
    assert call["settings"].candidates == ("sensor_noise", "drive_inertias") and call["settings"].budget == 2


def test_diagnosis_fits_on_the_history_and_no_test_row(finished):
    """The rows the diagnosis is given are the target history (the healthy rows every repetition
    trains on): none is a test row of any repetition the accuracy table or the bound scores, and
    no label goes in (rows only)."""
    from gearlab.data.cache import load_or_build
    from gearlab.learn.protocol import history_of, split

    run, log = finished
    (call,) = log
    spec = load_scenario(run / "scenario.toml").spec
    protocol = spec.protocol
    target, _ = load_or_build(spec.target)
    source, _ = load_or_build(spec.source)
    mean, std = target.reference
    physical = np.asarray(target.X, dtype=np.float64) * std + mean
    given = [int(np.flatnonzero(np.all(np.isclose(physical, row), axis=1))[0]) for row in call["target_X"]]
    history = history_of(protocol, target)
    assert sorted(given) == history.tolist()
    assert set(given) <= set(np.flatnonzero(target.fault == 0))
    for rep in range(protocol.repetitions):
        s = split(protocol, source, target, rep, 0, history)
        assert not set(given) & set(s.target_test.tolist())
        assert set(given) <= set(s.target_train.tolist())
    for r in records(run).values():
        if "n_test" in r:  # each accuracy unit scored the rows outside the history
            assert r["n_test"] == len(target.X) - protocol.target_train


def test_summary_lines(finished):
    run, _ = finished
    lines = gap.summary_lines(RunDir.open(run))
    assert lines[0].startswith("gap before") and any("sensor_noise" in line for line in lines)
    # what the diagnosis cost (issue 41: its total of score evaluations was given nowhere)
    assert json.loads((run / "summary.json").read_text())["evaluations"] == 1234
    assert lines[1].endswith("; verdict: explained; 1234 score evaluations"), lines[1]


def test_resume_skips_finished_units(finished, tiny, cli, calls):
    run, _ = finished
    # a run killed after the diagnosis and one accuracy unit
    partial = tiny.parent / "partial"
    partial.mkdir()
    for name in ("scenario.toml", "scenario.original.toml", "run.json"):
        (partial / name).write_bytes((run / name).read_bytes())
    lines = (run / "results.jsonl").read_text().splitlines(keepends=True)
    kept = [line for line in lines if json.loads(line)["unit"] in ("diagnosis", ACCURACY_UNITS[0])]
    (partial / "results.jsonl").write_text("".join(kept))
    code, out, err = cli("run", "--resume", partial)
    assert code == 0, err
    assert calls == []  # the diagnosis was not run again
    units = [json.loads(line)["unit"] for line in (partial / "results.jsonl").read_text().splitlines()]
    assert sorted(units) == sorted(["diagnosis", *ACCURACY_UNITS, "bound"])  # each unit once
    assert (partial / "summary.json").exists()


def test_partial_run_tables_and_charts(finished, tiny):
    run, _ = finished
    scenario = load_scenario(tiny)
    partial = tiny.parent / "p2"
    partial.mkdir()
    (partial / "scenario.toml").write_bytes((run / "scenario.toml").read_bytes())
    rd = RunDir.open(partial)
    # nothing finished yet
    assert "running" in gap.records_table(scenario, [])
    (chart,) = gap.charts(scenario, rd)
    assert chart.notes and not chart.curves
    # the diagnosis finished, no accuracy yet
    lines = (run / "results.jsonl").read_text().splitlines(keepends=True)
    (partial / "results.jsonl").write_text(lines[0])
    table = gap.records_table(scenario, rd.records())
    assert "| view |" in table and "| effect |" in table and "accuracy" not in table
    charts = gap.charts(scenario, rd)
    assert [c.title for c in charts] == ["per-view gap before/after", "effect ranking: share of the gap removed"]
    assert all(len(c.curves[0].x) == len(c.curves[0].y) > 0 for c in charts)
    # one accuracy unit
    (partial / "results.jsonl").write_text("".join(lines[:2]))
    assert "target test accuracy" in gap.records_table(scenario, rd.records())
    assert len(gap.charts(scenario, rd)) == 3


# --- bad input: one line naming file, table and key, exit code 2, no run directory -------------------


@pytest.mark.parametrize(
    "old, new, where",
    [
        (
            'candidates = ["sensor_noise", "drive_inertias"]',
            'candidates = ["sensor_nois"]',
            "[diagnosis] key 'candidates'",
        ),
        (
            'candidates = ["sensor_noise", "drive_inertias"]',
            'candidates = ["sensor_noise", 3]',
            "[diagnosis] key 'candidates'",
        ),
        ("healthy = 14\neffects", "healthy = 0\neffects", "[target] key 'healthy'"),
        ("healthy = 14\neffects", "healthy = 5\neffects", "[target] key 'healthy'"),
        ("budget = 2", "budget = 0", "[diagnosis] key 'budget'"),
        ("target_train = 10", "target_train = 6", "[accuracy] key 'target_train'"),  # a history too short
        ("healthy = 10\nbootstrap", "healthy = 3\nbootstrap", "[diagnosis] key 'healthy'"),
        ("seed = 0\n", "seed = 0\nalpha = 1.0\n", "[diagnosis] key 'alpha'"),
        ('methods = ["mmd", "matched_filter"]', 'methods = ["mdd"]', "[accuracy] key 'methods'"),
        ('methods = ["mmd", "matched_filter"]', 'methods = ["finetune"]', "[accuracy] key 'methods'"),
        (
            'effects = [{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }]',
            'effects = [{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }]\nfs = "2 kHz"',
            "[target] key 'fs'",
        ),
        ('preset = "B-8-ch5"', 'preset = "A-casing-ch5"\nchannel = "casing_x"', "[target] key 'preset'"),
        ("snr_db = 0.0, seed = 1 }]", "snr_db = 500, seed = 1 }]", "[target] key 'effects' #1 (sensor_noise)"),
        # a measured file names its channel as text: an index (a records' column) is refused with the fix
        (
            'preset = "B-8-ch5"\nteeth = [1, 2, 3]\nfaults = { crack = [13] }\nhealthy = 14\n'
            'effects = [{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }]',
            'file = "rec.wav"\nvibration = 0\nspeed = "40 Hz"',
            "[target] key 'vibration'",
        ),
    ],
)
def test_bad_input_refused(tiny, cli, old, new, where):
    text = TINY.replace(old, new, 1)
    assert text != TINY
    tiny.write_text(text)
    out_dir = tiny.parent / "runs"
    code, _, err = cli("run", tiny, "--out", out_dir)
    assert code == 2, err
    message = err.strip()
    assert "\n" not in message and str(tiny) in message and where in message, message
    if "vibration = 0" in new:
        assert 'vibration = "0"' in message
    assert not out_dir.exists()


def test_measured_target_with_too_few_revolutions_leaves_no_run(tiny, cli, calls):
    """A measured target is only checked once imported: the run is refused and its directory removed."""
    fs, speed, points = 20_000.0, 40.0, 500
    n = points * 6  # six revolutions: fewer than the 10 the statistics need
    t = np.arange(n) / fs
    np.savez(tiny.parent / "rec.npz", acc=np.sin(2 * np.pi * 25 * speed * t), fs=np.array(fs))
    tiny.write_text(
        TINY.replace(
            'preset = "B-8-ch5"\nteeth = [1, 2, 3]\nfaults = { crack = [13] }\nhealthy = 14\n'
            'effects = [{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }]',
            'file = "rec.npz"\nvibration = "acc"\nspeed = "40 Hz"\ntransient = "none"',
        )
    )
    out_dir = tiny.parent / "runs"
    code, _, err = cli("run", tiny, "--out", out_dir)
    assert code == 2, err
    assert "[target]" in err and "too few healthy target revolutions" in err and str(tiny) in err
    assert not out_dir.exists() and calls == []


@pytest.mark.parametrize("units, warned", [("", True), ('sensitivity = "10 mV/g"\ngain = "0.2 mV"\n', False)])
def test_a_measured_target_goes_with_its_chain_and_its_units(tiny, cli, calls, units, warned):
    """A measured file's acquisition (rate, speed, start fractions, int16 step) reaches the diagnosis
    with its rows; without sensitivity or gain the run warns in one line that the units are unknown."""
    fs, speed = 20_003.0, 40.0  # 500.075 samples per revolution: revolutions start between samples
    n = int(fs / speed * 30)
    t = np.arange(n) / fs
    counts = np.round(3000 * np.sin(2 * np.pi * 25 * speed * t)).astype(np.int16)
    np.savez(tiny.parent / "rec.npz", acc=counts, fs=np.array(fs))
    tiny.write_text(
        TINY.replace(
            'preset = "B-8-ch5"\nteeth = [1, 2, 3]\nfaults = { crack = [13] }\nhealthy = 14\n'
            'effects = [{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }]',
            'file = "rec.npz"\nvibration = "acc"\nspeed = "40 Hz"\ntransient = "none"\n' + units,
        ).replace("[accuracy]\n", "[accuracy]\nenabled = false\n")
    )
    code, out, err = cli("run", tiny, "--out", tiny.parent / "runs")
    assert code == 0, err
    chain = calls[0]["chain"]
    assert chain.fs == fs and chain.speed == pytest.approx(speed) and len(set(chain.fractions)) > 5
    scale = 2e-4 / (0.01 / 9.80665) if not warned else 1.0
    assert chain.step == pytest.approx(scale)
    assert calls[0]["settings"].max_order == int(0.9 * fs / speed / 2)
    run = Path(out.strip().splitlines()[-1].split("run directory: ")[1])
    note = records(run)["diagnosis"]["note"]
    assert ("WARNING: units unknown" in note) == warned


# --- the real diagnosis ----------------------------------------------------------------------------


def test_real_diagnosis_tiny(tiny, cli):
    """End to end with gearlab.gap.diagnose itself, without the accuracy."""
    tiny.write_text(
        TINY.replace('candidates = ["sensor_noise", "drive_inertias"]', 'candidates = ["sensor_noise"]').replace(
            "[accuracy]\n", "[accuracy]\nenabled = false\n"
        )
    )
    code, out, err = cli("run", tiny, "--out", tiny.parent / "runs")
    assert code == 0, err
    run = Path(out.strip().splitlines()[-1].split("run directory: ")[1])
    summary = json.loads((run / "summary.json").read_text())
    assert "accuracy" not in summary
    assert summary["gap_before"] >= 0 and isinstance(summary["unexplained"], bool)
    assert [r["name"] for r in summary["ranking"]] == ["sensor_noise"]
    n = summary["evaluations"]  # the log's line and the summary's say the same count
    assert n > 0 and re.search(rf"gap: {n} score evaluations in \d+ s", out + err) and f"; {n} score evaluations" in out


def test_the_summary_says_which_parameters_are_not_identifiable_and_what_the_data_pin():
    determined = {
        "mf": {"determined": False, "reason": "profile", "width": 0.5},
        "k_yf": {"determined": False, "reason": "profile", "width": 0.5},
        "c_yf": {"determined": True, "reason": None, "width": 0.01},
        "c_xf": {"determined": False, "reason": "fit leaves a gap", "width": 0.01},
    }
    text = gap.params_text({"mf": 40.0, "k_yf": 4e8, "c_yf": 2000.0, "c_xf": 10.0}, determined)
    assert "mf = 40 (not identifiable)" in text and "c_yf = 2000," in text
    assert "c_xf = 10 (not determined: the fit leaves a gap)" in text


def test_the_verdict_line_says_when_what_is_left_lies_within_the_noise():
    from gearlab.kinds.gap import verdict_text

    base = {"verdict": "explained", "unexplained": False, "explained_share": 0.977}
    within = {**base, "within_noise": True, "significant_after": True, "rms_effect_after": 0.411}
    assert verdict_text(within) == "explained (what is left within the noise: RMS effect 0.41)"
    assert verdict_text({**within, "significant_after": False}) == "explained"  # the test sees nothing
    assert verdict_text(base) == "explained"  # results before the noise width
    partly = {"verdict": "partly explained", "unexplained": True, "explained_share": 0.9986}
    assert verdict_text(partly) == "partly explained (100 % of the gap)"


def test_effects_accepted_then_not_named_are_said_with_the_reason():
    """The search's progress said 'sensor_noise ... (accepted)'; when the accepted set together
    removes under the share a named set must, none is named (stand-ins): the log line and the
    verdict say which were fitted and why they are not named, instead of a bare 'effects: none'."""
    from gearlab.kinds.gap_verdict import FINAL_FIT, gap_lines

    result = {
        "gap_before": 4.0e5,
        "gap_after": 2.8e4,
        "effects": [],
        "verdict": "unexplained",
        "unexplained": True,
        "dropped_effects": [{"name": "sensor_noise"}, {"name": "interference_tone"}],
        "dropped_share": 0.932,
        "dropped_below": 0.99,
    }
    line = gap.diagnosis_line(result)
    reason = "sensor_noise, interference_tone fitted, then not named: together 93 % of the gap, "
    reason += f"{FINAL_FIT}, under the 99 %"
    assert f"effects: none ({reason} a named set removes); unexplained" in line
    summary = {"gap_before": 4.0e5, "gap_after": 2.8e4, "unexplained": True, "dropped": gap.dropped_text(result)}
    assert any(s.startswith(f"Effects {reason}") for s in gap_lines(summary))
    assert not any("not named" in s for s in gap_lines({**summary, "dropped": None}))
    assert "not named" not in gap.diagnosis_line({**result, "dropped_effects": []})
    # a share that rounds to the level is shown with the decimals that tell them apart
    close = gap.dropped_text({**result, "dropped_share": 0.9874})
    assert f"together 98.7 % of the gap, {FINAL_FIT}, under the 99.0 %" in close
