"""The blind benchmark of the gap diagnosis (gearlab/kinds/gap_benchmark/trials.py, kind `gap_benchmark`;
docs/gap_benchmark.md): the diagnosis never receives the generator's choices, trials are
drawn seeded in the documented mix, a written target round-trips through the importer, the
scoring on hand-made results, a tiny run through `gearlab run`, and bad input.

Everything but the last test replaces the diagnosis by a stand-in (it takes minutes); the
stand-in sees exactly what the real one would."""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import pickle
import re
import struct

import numpy as np
import pytest
from browser import check_report, chromium

from gearlab.data.builder import build_dataset
from gearlab.data.spec import dataset_preset
from gearlab.effects import default_candidates
from gearlab.gap.views import healthy_rows
from gearlab.kinds.gap_benchmark import trials as bench
from gearlab.registry import get_registry
from gearlab.settings import declared

LIBRARY = tuple(default_candidates(get_registry()))  # the shipped library: every effect but the opt-in ones
SOURCE = dataset_preset("B-6-ch5").with_(faults=(), healthy=12, noise=bench.BASE_NOISE)
SETTINGS = {"budget": 1, "max_effects": 1, "healthy": 12, "bootstrap": 5, "permutations": 10, "alpha": 0.05, "seed": 0}


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))


def fake_result(names=(), gap_before=10.0, gap_after=1.0, significant=True, unexplained=False, params=None):
    """A result in the contract of gearlab.gap.diagnose.diagnose (the fields the benchmark reads)."""
    params = params or {}
    effects = [
        {"name": n, "share_removed": 0.5, "params": params.get(n, {}), "intervals": {}, "round": i + 1}
        for i, n in enumerate(names)
    ]
    return {
        "before": {},
        "after": {},
        "gap_before": gap_before,
        "gap_after": gap_after,
        "significant_before": significant,
        "significant_after": False,
        "effects": effects,
        "ranking": [{"name": n, "share_removed": 0.5, "params": {}} for n in names],
        "unexplained": unexplained,
        "corrected_effects": [],
        "settings": {},
    }


class Spy:
    """Stands in for the diagnosis: keeps what it was given, names nothing."""

    def __init__(self):
        self.calls = []

    def __call__(self, source, target_X, settings, candidates, chain=None, max_order=0):
        self.calls.append((source, np.array(target_X), dict(settings), tuple(candidates), chain, max_order))
        return fake_result(significant=False, unexplained=True)


def trial_of(kind: str):
    return next(t for t in bench.draw_trials(40, 0, LIBRARY, SOURCE) if t.kind == kind)


# --- no leak -----------------------------------------------------------------------------------


def float_bytes(value: float) -> list[bytes]:
    return [struct.pack(">d", value), struct.pack("<d", value), struct.pack("<f", value), repr(value).encode()]


@pytest.mark.parametrize("kind", ["single", "pair", "withheld"])
def test_the_diagnosis_never_receives_the_generators_choices(kind, tmp_path, monkeypatch):
    spy = Spy()
    monkeypatch.setattr(bench, "_diagnose", spy)
    trial = trial_of(kind)
    folder = tmp_path / "trial"
    record = bench.trial_task(bench.TrialTask(trial, SOURCE, SETTINGS, str(folder), 12))
    assert record["kind"] == kind and len(spy.calls) == 1
    source, X, settings, candidates, chain, max_order = spy.calls[0]

    # 1. the diagnosing entry point takes the file, the source, the candidate names and the settings: no more
    assert list(inspect.signature(bench.diagnose_file).parameters) == ["path", "source", "candidates", "settings"]
    # 2. the source is the simulator configuration without the hidden effects; the settings are the scenario's
    assert source == SOURCE and source.effects == () and settings == SETTINGS
    # 3. the candidate list is the library, less the withheld effect (by design: that is the out-of-library case)
    assert candidates == tuple(e for e in LIBRARY if e != trial.withheld)
    # 4. the target reaches it only as the revolutions the importer reads from the written file ...
    # (with its measurement chain: rate, tacho speed, start fractions, step -- read off the same file)
    path = next(folder.glob("target.*"))
    rows, read_chain, read_order = bench.import_target(path)
    np.testing.assert_array_equal(X, rows)
    assert chain == read_chain and max_order == read_order
    if path.suffix == ".npz":
        with np.load(path) as f:
            assert sorted(f.files) == sorted([bench.VIBRATION, bench.TACHO, bench.LABEL, "fs"])
    # ... and no hidden parameter value appears anywhere in what it received
    payload = pickle.dumps((source, settings, candidates, chain, max_order)) + X.tobytes()
    hidden_values = [v for _, params in trial.hidden for _, v in params if isinstance(v, float) and v != 0.0]
    defaults = {d for e in LIBRARY for _, d in declared(get_registry().get("effect", e).params).values()}
    drawn = [v for v in hidden_values if v not in defaults]  # a default is no secret (nor drawn)
    assert drawn
    for v in drawn:
        assert not any(b in payload for b in float_bytes(v)), v
    # 5. the answers are written apart, and read back only to score
    answers = json.loads((folder / "answers.json").read_text())
    assert [h[0] for h in answers["hidden"]] == [name for name, _ in trial.hidden]
    assert record["hidden"] == answers["hidden"]


def test_the_trial_task_hands_the_diagnosis_only_public_values():
    """Every field of the task reaching diagnose_file is public: the task holds the Trial (it
    writes the target), but trial_task passes on only trial.candidates from it."""
    source = inspect.getsource(bench.trial_task)
    call = [line for line in source.splitlines() if "diagnose_file(" in line]
    assert call == ["    result = diagnose_file(path, task.source, candidates, task.settings)"]
    assert "candidates = task.trial.candidates" in source


def test_a_trial_in_progress_says_what_it_does(tmp_path, monkeypatch):
    """Issue 41 (no stage silent for more than 5 s): a trial takes minutes, up to eleven, inside one
    unit; its target, each stage its diagnosis starts (the diagnosis's default on_event) and the
    oracle's realisations reach the unit's progress line, and the line goes when the trial ends."""
    from gearlab.confined import Confined
    from gearlab.events import Event, UnitProgress, stages_to_unit
    from gearlab.gap import diagnose

    assert inspect.signature(diagnose.diagnose).parameters["on_event"].default is stages_to_unit
    said = []
    monkeypatch.setattr(UnitProgress, "__call__", lambda self, text: said.append((self.path.name, text)))

    def stand_in(source, target_X, settings, candidates, chain=None, max_order=0):
        stages_to_unit(Event("stage", stage="gap round 1", message="gap: round 1, fitting 2 effects"))
        return fake_result(significant=False)  # no gap seen: the oracle looks

    monkeypatch.setattr(bench, "_diagnose", stand_in)
    monkeypatch.setattr(bench, "ORACLE_REPEATS", 2)
    monkeypatch.setattr("gearlab.gap.scoring.plain_report", lambda *a, **k: {})
    monkeypatch.setattr("gearlab.gap.conclusion.gap_seen", lambda report: False)
    folder = Confined(tmp_path, ("targets", "trial_007"))  # as the kind hands it: below the run directory
    trial = trial_of("single")
    bench.trial_task(bench.TrialTask(trial, SOURCE, SETTINGS, folder, 12))
    line = f"trial {trial.index:03d}.txt"  # the progress/ file of the unit
    assert said == [
        (line, "simulating and writing the target"),
        (line, "gap: round 1, fitting 2 effects"),
        (line, "no gap seen: the oracle's realisation 1 of 2"),
        (line, "no gap seen: the oracle's realisation 2 of 2"),
    ]
    assert not (tmp_path / "progress" / line).exists()
    assert stages_to_unit(Event("stage", message="outside a unit")) is None  # no unit listening: nothing


# --- drawing ----------------------------------------------------------------------------------------


def test_trials_are_seeded_and_follow_the_documented_mix():
    a = bench.draw_trials(40, 3, LIBRARY, SOURCE)
    assert a == bench.draw_trials(40, 3, LIBRARY, SOURCE)
    assert a != bench.draw_trials(40, 4, LIBRARY, SOURCE)
    counts = {k: sum(t.kind == k for t in a) for k in bench.KINDS}
    assert counts == {"single": 20, "pair": 6, "null": 6, "withheld": 8} == bench.trial_counts(40)
    assert bench.trial_counts(4) == {"single": 1, "pair": 1, "null": 1, "withheld": 1}
    for n in (1, 2, 3, 7, 41, 100):
        assert sum(bench.trial_counts(n).values()) == n
    assert all(bench.trial_counts(n)[k] >= 4 for n in range(40, 60) for k in ("null", "withheld"))
    singles = [t.hidden[0][0] for t in a if t.kind == "single"]
    assert set(singles) == set(LIBRARY)  # round the library: every effect hidden alone at least once
    registry = get_registry()
    for t in a:
        names = [n for n, _ in t.hidden]
        assert len(names) == {"single": 1, "pair": 2, "null": 0, "withheld": 1}[t.kind]
        assert len(set(names)) == len(names)
        if t.kind == "withheld":
            assert t.withheld == names[0] and t.withheld not in t.candidates and len(t.candidates) == len(LIBRARY) - 1
        else:
            assert t.withheld is None and t.candidates == LIBRARY
        for name, params in t.hidden:
            registry.get("effect", name).resolve(dict(params))  # inside the bounds
            for key, rule in bench.RANGES[name].items():
                value = dict(params)[key]
                rules = rule if isinstance(rule, list) else [rule]
                assert any(lo <= value <= hi for lo, hi, _ in rules), (name, key, value)


# --- the written target ---------------------------------------------------------------------------


def test_a_written_target_round_trips_through_the_importer(tmp_path):
    trial = dataclasses.replace(trial_of("single"), acquisition=None)  # the angle-domain record
    path = bench.write_target(trial, SOURCE, tmp_path, 12)
    direct = healthy_rows(build_dataset(bench.target_spec(trial, SOURCE, 12)))
    imported, chain, _ = bench.import_target(path)
    assert chain is None
    assert imported.shape == direct.shape == (12, 4096)
    np.testing.assert_allclose(imported, direct, rtol=0, atol=2e-6 * np.abs(direct).max())
    # the target is its own noise realisation, not the source's
    assert bench.target_spec(trial, SOURCE, 12).noise.seed != SOURCE.noise.seed


@pytest.mark.parametrize("fmt", bench.FORMATS)
def test_a_null_target_acquired_as_a_measured_file_shows_no_gap(fmt, tmp_path):
    """Pipeline parity: a target with no effect, written at a rate where revolutions start
    between samples, with its tacho 7-200 degrees off the simulation's zero and (int16) quantised,
    imported -- against the source made through the same chain -- shows no significant gap, while
    the source without the chain shows a large one."""
    from gearlab.gap.diagnose import Rows
    from gearlab.gap.stats import gap_report
    from gearlab.signals.indicators import band_limited

    acquisition = bench.Acquisition(
        {"npz": 0.43, "npz-int16": 0.33, "wav": 0.61}[fmt],
        math.radians({"npz": 7.0, "npz-int16": 90.0, "wav": 200.0}[fmt]),
        fmt,
    )
    trial = bench.Trial(0, "null", (), None, tuple(LIBRARY), 11, acquisition)
    path = bench.write_target(trial, SOURCE, tmp_path, 60)
    rows, chain, max_order = bench.import_target(path)
    assert len(rows) >= 58 and 0 < max_order < 2048
    assert len(set(chain.fractions)) > 10  # revolutions start between samples
    assert (chain.step > 0) == (fmt != "npz")  # integer formats are quantised, at a known step
    target = band_limited(rows, max_order=max_order)
    search = SOURCE.with_(healthy=40, seed=123)
    pair = search.check_model()[1]
    matched = gap_report(
        Rows(max_order, dataclasses.replace(chain, reference=target.mean(axis=0)))(search),
        target,
        pair,
        seed=0,
        bootstrap=0,
        permutations=200,
        max_order=max_order,  # the record's passband, as the diagnosis compares it
    )
    plain = gap_report(
        Rows(max_order)(search), target, pair, seed=0, bootstrap=0, permutations=200, max_order=max_order
    )
    assert not matched["significant"], matched["p_value"]
    assert plain["significant"] and plain["total"]["gap"] > 100 * matched["total"]["gap"]


def test_the_tacho_offset_is_found_between_pitch_aliases():
    """A healthy gear's revolution nearly repeats every tooth pitch: the offset must be the true
    one, not a pitch away (the mesh orders alone cannot tell them apart)."""
    from gearlab.data.chain import fit_offset
    from gearlab.gap.scoring import source_rows

    clean = source_rows(SOURCE.with_(healthy=1, noise=None))[0]
    z1 = SOURCE.check_model()[1].Z1
    for degrees in (7.0, 123.4, 301.0):
        psi = math.radians(degrees)
        m = np.arange(2049)
        turned = np.fft.irfft(np.fft.rfft(clean) * np.exp(2j * np.pi * m * psi / (2 * np.pi)), n=4096)
        assert math.degrees(fit_offset(clean, turned, z1)) == pytest.approx(degrees, abs=0.01)


# --- scoring -----------------------------------------------------------------------------------------


def answers(kind, hidden=(), withheld=None):
    return {"kind": kind, "hidden": [[n, p] for n, p in hidden], "withheld": withheld}


def test_scoring_a_single_hit_and_its_parameter_error():
    hidden = [
        ("sensor_bandwidth", {"f_n": 1e4, "zeta": 0.1}),
    ]
    r = bench.score_trial(
        answers("single", hidden),
        fake_result(["sensor_bandwidth"], 10.0, 2.0, params={"sensor_bandwidth": {"f_n": 2e4, "zeta": 0.1}}),
    )
    assert r["top1"] and r["top3"] and r["identified"] == ["sensor_bandwidth"]
    assert r["shrink"] == pytest.approx(0.8)
    assert r["param_error"]["sensor_bandwidth"] == {"f_n": pytest.approx(math.log(2)), "zeta": 0.0}  # log scale
    assert r["param_error_median"] == pytest.approx(math.log(2) / 2)
    assert r["wrong_names"] == []


def test_an_effect_taken_back_at_the_end_is_listed_but_not_a_wrong_name():
    """needed_effects moves an extra the final fit does not need to unneeded_effects: the record lists
    it apart, and only what stays named counts as named (wrongly or not)."""
    result = fake_result(["load_fluctuation"], 10.0, 0.01)
    result["unneeded_effects"] = [{"name": "sensor_noise", "round": 1, "nuisance_of": "load_fluctuation"}]
    r = bench.score_trial(answers("single", [("load_fluctuation", {"amplitude": 0.1, "order": 2})]), result)
    assert r["accepted"] == ["load_fluctuation"] and r["unneeded"] == ["sensor_noise"]
    assert r["top1"] and r["wrong_names"] == []
    assert bench.score_trial(answers("null"), fake_result(significant=False))["unneeded"] == []


def test_scoring_misses_pairs_phases_and_options():
    miss = bench.score_trial(
        answers("single", [("tooth_friction", {"mu_f": 0.1})]), fake_result(["mesh_damping", "tooth_friction"])
    )
    assert not miss["top1"] and miss["top3"] and miss["wrong_names"] == ["mesh_damping"]
    assert miss["param_error"]["tooth_friction"] == {}  # accepted in round 2 without parameters: nothing to score
    pair = bench.score_trial(
        answers(
            "pair",
            [
                ("speed_fluctuation", {"amplitude": 0.01, "order": 2, "phase": 0.1}),
                ("sensor_noise", {"snr_db": 10.0, "kind": "laplace"}),
            ],
        ),
        fake_result(
            ["sensor_noise", "speed_fluctuation"],
            params={
                "sensor_noise": {"snr_db": 12.0, "kind": "gaussian"},
                "speed_fluctuation": {"amplitude": 0.01, "order": 2, "phase": 2 * math.pi - 0.1},
            },
        ),
    )
    assert pair["top1"] and set(pair["identified"]) == {"sensor_noise", "speed_fluctuation"}
    assert pair["param_error"]["sensor_noise"]["snr_db"] == pytest.approx(0.2)  # linear: relative to the true value
    assert pair["param_error"]["speed_fluctuation"]["phase"] == pytest.approx(0.2 / math.pi)  # wrapped
    assert pair["param_error"]["speed_fluctuation"]["order"] == 0.0
    assert pair["option_correct"]["sensor_noise"] == {"kind": False}


def test_scoring_null_and_out_of_library():
    ok = bench.score_trial(answers("null"), fake_result(significant=False, gap_before=0.5, gap_after=0.5))
    assert ok["null_correct"] is True and ok["top1"] is None
    assert bench.score_trial(answers("null"), fake_result(["sensor_noise"]))["null_correct"] is False
    held = answers("withheld", [("casing_path", {"mf": 10.0})], "casing_path")
    assert bench.score_trial(held, fake_result(unexplained=True))["out_of_library_unexplained"] is True
    wrong = bench.score_trial(held, fake_result(["drive_inertias"], unexplained=False))
    assert wrong["out_of_library_unexplained"] is False and wrong["wrong_names"] == ["drive_inertias"]


def test_summary_over_hand_made_records():
    recs = [
        bench.score_trial(
            answers("single", [("tooth_friction", {"mu_f": 0.1})]),
            fake_result(["tooth_friction"], 10, 1, params={"tooth_friction": {"mu_f": 0.12}}),
        ),
        bench.score_trial(answers("single", [("tooth_friction", {"mu_f": 0.1})]), fake_result(["mesh_damping"], 10, 5)),
        bench.score_trial(answers("null"), fake_result(significant=False)),
        bench.score_trial(
            answers("withheld", [("mesh_damping", {"zeta": 0.1})], "mesh_damping"), fake_result(unexplained=True)
        ),
    ]
    s = bench.summarise(recs, ["tooth_friction", "mesh_damping"])
    assert s["trials"] == 4 and s["top1"] == 0.5 and s["median_shrink"] == pytest.approx(0.9)
    assert s["null_correct"] == 1.0 and s["out_of_library_unexplained"] == 1.0
    assert s["per_effect"]["tooth_friction"]["trials"] == 2 and s["per_effect"]["tooth_friction"]["top1"] == 0.5
    assert s["per_effect"]["tooth_friction"]["median_param_error"] == pytest.approx(0.2)
    assert s["per_effect"]["mesh_damping"]["withheld"] == 1 and s["per_effect"]["mesh_damping"]["named_wrongly"] == 1
    assert s["met"] == {"top1": False, "median_shrink": True, "null_correct": True, "out_of_library_unexplained": True}
    assert s["explained_when_identified"] == 1.0 and s["extra_names_when_identified"] == 0.0


def test_saying_unexplained_or_naming_extras_when_right_is_counted_against_the_diagnosis():
    friction = answers("single", [("tooth_friction", {"mu_f": 0.1})])
    recs = [
        bench.score_trial(friction, fake_result(["tooth_friction"], unexplained=True)),
        bench.score_trial(friction, fake_result(["tooth_friction", "sensor_noise"])),
        bench.score_trial(friction, fake_result(["tooth_friction"])),
        bench.score_trial(friction, fake_result(["mesh_damping"], unexplained=True)),
    ]  # a miss: not counted
    s = bench.summarise(recs, ["tooth_friction", "mesh_damping", "sensor_noise"])
    assert s["explained_when_identified"] == pytest.approx(2 / 3)
    assert s["extra_names_when_identified"] == pytest.approx(1 / 3)


# --- the scenario kind --------------------------------------------------------------------------------

TINY = """
[scenario]
name = "tiny"
kind = "gap_benchmark"
description = "tiny"

[execution]
workers = 1

[benchmark]
trials = {trials}
seed = 1
library = {library}
target_revolutions = 12

[search]
budget = 1
max_effects = 1
healthy = 12
bootstrap = 5
permutations = 10
"""


def tiny(trials=3, library='["sensor_noise", "interference_tone", "tooth_friction"]', extra=""):
    return TINY.format(trials=trials, library=library) + extra


def test_a_tiny_benchmark_runs_into_summary_json(cli, write_scenario, tmp_path, monkeypatch):
    def stand_in(
        source, target_X, settings, candidates, chain=None, max_order=0
    ):  # names the first candidate when the target is noisy
        result = fake_result([candidates[0]], 10.0, 2.0, params={candidates[0]: {"snr_db": 5.0}})
        return {**result, "evaluations": 20 + len(candidates)}  # 23 on three candidates, 22 when one is withheld

    monkeypatch.setattr(bench, "_diagnose", stand_in)
    path = write_scenario(tiny(4))
    code, out, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 0, err
    run_dir = next((tmp_path / "runs" / "tiny").iterdir())
    summary = json.loads((run_dir / "summary.json").read_text())
    for key in (
        "trials",
        "top1",
        "top3",
        "median_shrink",
        "null_correct",
        "out_of_library_unexplained",
        "per_effect",
        "median_param_error",
    ):
        assert key in summary
    assert summary["trials"] == 4 and summary["by_kind"] == {"single": 1, "pair": 1, "null": 1, "withheld": 1}
    assert (run_dir / "report.html").exists() and (run_dir / "figures" / "gap_benchmark.png").exists()
    assert len((run_dir / "results.jsonl").read_text().splitlines()) == 4
    names = sorted(p.name for p in (run_dir / "targets" / "trial_000").iterdir())
    assert names[:3] == ["answers.json", "calibration.json", "diagnosis.json"] and len(names) == 4
    assert names[3] in ("target.npz", "target.wav")
    assert "top-1" in out
    # what each trial's diagnosis cost, in its log line, and in all (issue 41: no total anywhere)
    assert summary["evaluations"] == {"total": 3 * 23 + 22, "trials": 4, "median": 23.0}
    assert re.search(r"trial 003 \(withheld\): .*; 22 score evaluations, \d+ s", out + err), out + err
    assert "score evaluations of the diagnoses: 91 over 4 trials (median 23 a trial)" in out
    # table.md: per effect, the median of the evaluations its trials' records hold; the 'all' row, the median
    records = [json.loads(line) for line in (run_dir / "results.jsonl").read_text().splitlines()]
    table = (run_dir / "table.md").read_text().split("\n\n")[0]
    head, _, *rows = [[c.strip() for c in line[1:-1].split("|")] for line in table.splitlines()]
    assert head[-1] == "median evaluations" and len(rows) == 4
    for row in rows[:-1]:
        hidden_in = [r for r in records if r["kind"] in bench.EFFECT_KINDS and row[0] in [h[0] for h in r["hidden"]]]
        mine = [r["evaluations"] for r in hidden_in]
        assert row[-1] == (f"{np.median(mine):.0f}" if mine else ""), (row, records)
    assert rows[-1][0].startswith("**all**") and rows[-1][-1] == "23" and any(r[-1] == "23" for r in rows[:-1])
    if chromium():  # the report as a reader gets it (issue 41: a browser test covers every kind)
        check_report(run_dir / "report.html", tmp_path / "browser")
    # resume: nothing left to do, nothing recomputed
    monkeypatch.setattr(bench, "_diagnose", lambda *a: pytest.fail("a finished trial was diagnosed again"))
    code, out, err = cli("run", "--resume", run_dir)
    assert code == 0, err


@pytest.mark.parametrize(
    "text,where",
    [
        (tiny(0), "[benchmark] key 'trials'"),
        (tiny(library='["sensor_noize", "tooth_friction"]'), "[benchmark] key 'library'"),
        (tiny(library='["tooth_friction"]'), "[benchmark] key 'library'"),
        (tiny(library='["tooth_friction", "tooth_friction"]'), "[benchmark] key 'library'"),
        (tiny().replace("target_revolutions = 12", "target_revolutions = 3"), "[benchmark] key 'target_revolutions'"),
        (tiny(extra='\n[source]\nfile = "x.npz"\n'), "[source] key 'file'"),
        (tiny(extra='\n[source]\npreset = "B-7"\n'), "[source]"),
        (tiny(extra='\n[source]\neffects = [{name = "sensor_noise", snr_db = 900}]\n'), "[source] key 'effects'"),
        (tiny().replace("budget = 1", "budget = 0"), "[search] key 'budget'"),
    ],
)
def test_bad_input_exits_2_naming_file_table_key(cli, write_scenario, text, where):
    path = write_scenario(text)
    code, out, err = cli("validate", path)
    assert code == 2
    assert str(path) in err and where in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_quick_benchmark_with_the_real_diagnosis(cli, tmp_path):
    """The shipped scenario, --quick: 4 trials through the real diagnosis (a few minutes on 2 cores)."""
    from conftest import ROOT

    code, out, err = cli("run", ROOT / "scenarios" / "gap_benchmark.toml", "--quick", "--out", tmp_path / "runs")
    assert code == 0, err
    summary = json.loads(next((tmp_path / "runs" / "gap_benchmark").iterdir()).joinpath("summary.json").read_text())
    assert summary["trials"] == 4


# --- targets too weak to show a gap ------------------------------------------------------------------


def test_a_target_too_weak_to_show_a_gap_is_scored_by_the_oracle():
    """An effect trial the diagnosis saw no gap in: when fresh realisations of its target show none
    either (oracle under ORACLE_SEEN), "no significant gap" is the right answer and top-1 does not
    apply; when they do, it is a miss."""
    weak = answers("single", [("shaft_eccentricity", {"e": 1.5e-4, "phase": 0.3})])
    quiet = fake_result(significant=False, gap_before=1.0, gap_after=1.0)
    r = bench.score_trial(weak, quiet, oracle=0.2)
    assert r["too_weak"] and r["right_answer"] and r["top1"] is None and r["oracle_seen"] == 0.2
    seen = bench.score_trial(weak, quiet, oracle=0.8)
    assert not seen["too_weak"] and not seen["right_answer"] and seen["top1"] is False
    assert bench.score_trial(weak, quiet)["top1"] is False  # no oracle: a miss as before
    named = bench.score_trial(weak, fake_result(["sensor_noise"], significant=False), oracle=0.0)
    assert named["too_weak"] and not named["right_answer"]  # something named where no gap was seen
    hit = bench.score_trial(weak, fake_result(["shaft_eccentricity"]))
    s = bench.summarise([r, seen, hit], LIBRARY)
    assert s["too_weak"] == 1 and s["top1"] == pytest.approx(0.5) and s["right_answer"] == pytest.approx(2 / 3)


def test_a_gap_seen_within_the_noise_width_with_nothing_named_stays_a_miss_and_is_counted():
    """The diagnosis's below_noise_width (a gap seen, its RMS effect within the noise width): with
    nothing named the trial is flagged, and it is still a miss of right_answer (the effect shows)."""
    weak = answers("single", [("shaft_eccentricity", {"e": 1.6e-4, "phase": 0.3})])
    flagged = bench.score_trial(weak, {**fake_result(unexplained=True), "below_noise_width": True})
    assert flagged["below_noise_width"] and flagged["top1"] is False and not flagged["right_answer"]
    named = bench.score_trial(weak, {**fake_result(["shaft_eccentricity"]), "below_noise_width": True})
    assert not named["below_noise_width"] and named["right_answer"]
    assert not bench.score_trial(weak, fake_result(unexplained=True))["below_noise_width"]
    s = bench.summarise([flagged, named], LIBRARY)
    assert s["below_noise_width"] == 1 and s["right_answer"] == pytest.approx(0.5)


def test_the_oracle_sees_a_strong_effect_and_not_a_negligible_one(tmp_path):
    """oracle_seen writes fresh realisations of the trial's target as measured files and judges the
    plain source against each as the diagnosis's "before" report does."""
    acquisition = bench.Acquisition(0.45, 1.0, "npz")
    registry = get_registry()
    settings = {**SETTINGS, "bootstrap": 0, "permutations": 100}

    def trial(name, params):
        return bench.Trial(0, "single", (registry.get("effect", name).spec(params),), None, LIBRARY, 5, acquisition)

    assert bench.oracle_seen(trial("sensor_noise", {"snr_db": 0.0}), SOURCE, settings, 30, tmp_path) == 1.0
    assert bench.oracle_seen(trial("shaft_eccentricity", {"e": 1e-7}), SOURCE, settings, 30, tmp_path) <= 0.2
    assert not list(tmp_path.iterdir())  # the realisations are not kept


def test_kinds_runs_only_some_trials_of_the_same_draw(write_scenario):
    """[benchmark] kinds: the trials are drawn as for a full run and only those kinds run."""
    from gearlab.engine import load_scenario

    head = '[scenario]\nname = "b"\nkind = "gap_benchmark"\n[benchmark]\ntrials = 50\nseed = 0\n'
    full = load_scenario(write_scenario(head, "full.toml"))
    held = load_scenario(write_scenario(head + 'kinds = ["withheld"]\n', "held.toml"))
    assert len(held.spec.trials) == 10
    assert held.spec.trials == [t for t in full.spec.trials if t.kind == "withheld"]


def test_suborder_trials_hide_a_tone_between_the_first_orders_and_are_drawn_only_when_named(write_scenario):
    from gearlab.data.builder import operating_point
    from gearlab.engine import load_scenario
    from gearlab.errors import GearlabInputError

    library = ("sensor_noise", "interference_tone", "tooth_friction")
    trials = bench.draw_suborder_trials(6, 3, library, SOURCE, first=10)
    assert trials == bench.draw_suborder_trials(6, 3, library, SOURCE, first=10)
    speed, _ = operating_point(SOURCE)
    for k, trial in enumerate(trials):
        assert trial.index == 10 + k and trial.kind == "suborder" and trial.candidates == library
        ((name, params),) = trial.hidden
        order = dict(params)["frequency"] / speed
        assert name == "interference_tone" and bench.SUBORDER_ORDERS[0] <= order <= bench.SUBORDER_ORDERS[1]
        assert abs(order - round(order)) >= bench.SUBORDER_CLEAR
    with pytest.raises(GearlabInputError, match="interference_tone"):
        bench.draw_suborder_trials(2, 3, ("sensor_noise", "tooth_friction"), SOURCE)
    # the mix never holds one; kinds = ["suborder"] runs `trials` of them alone, kinds = ["null",
    # "suborder"] the mix's nulls and as many sub-order trials as `trials`
    assert all(t.kind in bench.KINDS for t in bench.draw_trials(20, 3, library, SOURCE))
    head = '[scenario]\nname = "b"\nkind = "gap_benchmark"\n[benchmark]\ntrials = 20\nseed = 0\n'
    alone = load_scenario(write_scenario(head + 'kinds = ["suborder"]\n', "sub.toml")).spec.trials
    assert [t.kind for t in alone] == ["suborder"] * 20
    both = load_scenario(write_scenario(head + 'kinds = ["null", "suborder"]\n', "both.toml")).spec.trials
    assert [t.kind for t in both] == ["null"] * 3 + ["suborder"] * 20
    assert len({t.index for t in both}) == len(both)
    # scored as an effect trial
    truth = dict(trials[0].hidden[0][1])
    answers = {"kind": "suborder", "hidden": [["interference_tone", truth]]}
    record = bench.score_trial(answers, fake_result(["interference_tone"], params={"interference_tone": truth}))
    assert record["top1"] and record["param_error_median"] == pytest.approx(0.0)
