"""`gearlab score RUN_DIR FILE...` (issue 39, item 6): new recordings scored by a finished detection
run's trained methods at its thresholds, nothing trained again; the rows appended to the run's
scoring history, whose trend the report's charts show."""

import json

import numpy as np
import pytest
from detection_scenario import shared_run
from test_detection import FILES, run, scenario
from textrecords import record

import gearlab.learn.protocol as P
from gearlab.kinds import detection_scoring
from gearlab.parts import scoring
from gearlab.runs import RunDir


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))


def test_score_new_records_with_a_finished_run_without_training(cli, tmp_path, cache, monkeypatch, no_figures):
    files = [*FILES, ("h4", "history", "healthy", 0.0)]
    path = scenario(tmp_path, files=files, methods=("source_only", "matched_filter"), detection="seeds = 2\n")
    out = run(cli, path, tmp_path / "runs")
    assert json.loads((out / "scoring.json").read_text())["input_version"] == detection_scoring.INPUT_VERSION
    # two new records of the rig: a healthy one and a chipped one (not seen by the run)
    record(tmp_path / "new_ok.zip", revolutions=40, chip=0.0, seed=11, phase=0.3)
    record(tmp_path / "new_chip.zip", revolutions=40, chip=4.0, seed=12, phase=1.1)

    def no_training(*args, **kwargs):
        raise AssertionError("gearlab score trained a method")

    monkeypatch.setattr(P, "train_method", no_training)
    code, stdout, err = cli("score", out, tmp_path / "new_ok.zip", tmp_path / "new_chip.zip", "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    methods = {r["method"] for r in rows}
    assert methods == {"source_only", "matched_filter", "fm4", "na4"}
    assert {r["unit"] for r in rows} == {"revolution", "record5", "record10"}
    by = {(r["file"].rsplit("/", 1)[-1], r["method"], r["unit"]): r for r in rows}
    # the synthetic chip rings once a revolution: FM4 of the TSA calls the chipped record, not the healthy one
    assert by[("new_chip.zip", "fm4", "record10")]["decision"] == "fault"
    assert by[("new_ok.zip", "fm4", "record10")]["decision"] == "healthy"
    for r in rows:
        assert r["rule"] == "records" and 0 <= r["called"] <= r["units"] and np.isfinite(r["threshold"])
    # the run's own thresholds: a record already scored in the run scores alike
    summary = json.loads((out / "summary.json").read_text())
    fm4 = next(x for x in summary["rows"] if x["method"] == "fm4" and x["unit"] == "record10")
    assert by[("new_chip.zip", "fm4", "record10")]["threshold"] == pytest.approx(fm4["threshold"])
    # the history: appended, shown as a trend per method
    history = scoring.read_history(RunDir.open(out))
    assert len(history) == len(rows) and all("scored_at" in h for h in history)
    record(tmp_path / "week3.zip", revolutions=40, chip=4.0, seed=13, phase=0.5)
    code, _, err = cli("score", out, tmp_path / "week3.zip")
    assert code == 0, err
    assert len(scoring.read_history(RunDir.open(out))) == len(rows) + len(rows) // 2
    code, _, err = cli("score", out, tmp_path / "new_chip.zip")  # scored before: not a fourth take of the trend
    assert code == 0, err
    assert len(scoring.read_history(RunDir.open(out))) == len(rows) + len(rows) // 2
    from gearlab.kinds import SCENARIO_KINDS

    charts = SCENARIO_KINDS["detection"].charts(None, RunDir.open(out))
    (chart,) = [c for c in charts if "scored records" in c.title]  # beside the run's ROC per condition
    assert [c.title for c in charts if c is not chart] == ["16 Hz: ROC on the test's record10 units"]
    assert {c.label for c in chart.curves} == methods and all(len(c.x) == 3 for c in chart.curves)
    assert (out / "figures" / "score_trend.png").is_file() and "score_trend" in (out / "report.html").read_text()


def test_score_refuses_a_run_that_is_not_a_detection_run_and_a_record_of_no_condition(cli, tmp_path, cache, no_figures):
    path = scenario(tmp_path, methods=("matched_filter",))
    out = shared_run(path, tmp_path / "runs")
    fast = tmp_path / "fast.zip"
    record(fast, revolutions=40, seed=3, speed=40.0)
    code, _, err = cli("score", out, fast)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "more than 5%" in err, err
    code, _, err = cli("score", out, tmp_path / "missing.csv")
    assert code == 2 and "no such file" in err, err
    (out / "scoring.json").unlink()
    code, _, err = cli("score", out, tmp_path / "data" / "h1.zip")
    assert code == 2 and "scoring.json" in err, err


def test_a_model_file_naming_a_foreign_class_is_refused(tmp_path):
    import pickle

    from gearlab.confined import Confined
    from gearlab.errors import GearlabInputError

    folder = Confined(tmp_path, ("models",))

    class Evil:
        def __reduce__(self):
            return (print, ("ran",))

    import io
    import zipfile

    import torch

    buf = io.BytesIO()
    torch.save({"x": torch.zeros(1)}, buf)
    # a checkpoint whose pickle names builtins.print
    data = bytearray(buf.getvalue())
    with zipfile.ZipFile(io.BytesIO(bytes(data))) as z:
        members = {n: z.read(n) for n in z.namelist()}
    name = next(n for n in members if n.endswith("data.pkl"))
    members[name] = pickle.dumps(Evil(), protocol=2)
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as z:
        for n, v in members.items():
            z.writestr(n, v)
    (folder / f"{scoring.model_key('u')}.pt").write(out.getvalue())
    with pytest.raises(GearlabInputError, match="refused|damaged"):
        scoring.load_model(folder, "u")


def test_a_run_without_a_tacho_reads_a_new_record_as_it_read_its_own():
    """The keys a new record is cut with (detection_scoring.reading_keys): the run's tacho, or without
    one its declared speed and description; speeds declared per file only give a new record the
    speed of the condition it is scored in, one the run has alone or --condition names."""
    from gearlab.errors import GearlabInputError
    from gearlab.kinds.detection_scoring import reading_keys

    target = {"vibration": "acc", "tacho": None, "pulses_per_rev": 1, "speed_hz": None, "gearbox": None}
    one = {"target": target, "conditions": {"28 Hz": {"speed_hz": 28.04}}}
    assert reading_keys(one, None)["speed_hz"] == 28.04
    assert reading_keys({**one, "target": {**target, "speed_hz": 25.0}}, None)["speed_hz"] == 25.0
    assert reading_keys({**one, "target": {**target, "tacho": "tach"}}, None)["speed_hz"] is None
    two = {"target": target, "conditions": {"28 Hz": {"speed_hz": 28.04}, "40 Hz": {"speed_hz": 40.1}}}
    assert reading_keys(two, "40 Hz")["speed_hz"] == 40.1
    with pytest.raises(GearlabInputError, match=r"^--condition: missing; .* known: 28 Hz, 40 Hz$"):
        reading_keys(two, None)
    # a run from before the target could go without a tacho kept neither key
    old = {"target": {"vibration": 0, "tacho": "2", "pulses_per_rev": 10}, "conditions": one["conditions"]}
    assert "gearbox" not in reading_keys(old, None) and "speed_hz" not in reading_keys(old, None)


def test_a_run_whose_learned_methods_saw_another_input_is_refused(tmp_path, monkeypatch):
    """The outside-user check's gearbox E (18/67 + 29/71, its later mesh at 7.79 input orders): a run
    made before d9a4d9b changed that train's learned input, scored after it, called its healthy take
    a fault in 40 of 40 record10 units (likelihood_ratio; 0 of 40 with the run's own input). Such a
    run is refused in one line; a run from before the key of a train with no such mesh is scored."""
    from gearlab.errors import GearlabInputError
    from gearlab.kinds import detection_scoring as S

    class Passed(Exception):  # the check let the run through: scoring went on to read the records
        pass

    def passed(*args, **kwargs):
        raise Passed

    monkeypatch.setattr(S, "reading_keys", passed)
    run = RunDir(tmp_path)
    cases = [
        ({"later_orders": [18 * 29 / 67]}, "input_version 1 "),  # before the key: version 1
        ({"later_orders": [18 * 29 / 67], "input_version": 1}, "input_version 1 "),
        ({"later_orders": [], "input_version": S.INPUT_VERSION + 1}, f"input_version {S.INPUT_VERSION + 1} "),
        ({"later_orders": [18 * 29 / 67], "input_version": S.INPUT_VERSION}, None),
        ({"later_orders": []}, None),  # a whole-order train before the key: its input never changed
        ({}, None),  # a run from before the later orders were kept
    ]
    for meta, refused in cases:
        run.write_json(scoring.SCORING_FILE, {"conditions": {}, **meta})
        if refused is None:
            with pytest.raises(Passed):
                S.score(run, [])
            continue
        with pytest.raises(GearlabInputError) as found:
            S.score(run, [])
        line = str(found.value)
        assert refused in line and "run the scenario again" in line and "\n" not in line, line


def test_a_crossed_run_scores_a_record_as_it_scored_it_itself(cli, tmp_path, cache, no_figures):
    """history_fit = "crossed": score loads every fold's trained model (each from its own unit's
    file; the second fold's was looked for under the first's standardising models) and calls the
    units of a test record of the run as the run called them."""
    path = scenario(tmp_path, methods=("source_only",), detection='history_fit = "crossed"')
    out = run(cli, path, tmp_path / "runs")
    code, stdout, err = cli("score", out, tmp_path / "data" / "f1.zip", "--json")
    assert code == 0, err
    rows = {r["unit"]: r for r in json.loads(stdout) if r["method"] == "source_only"}
    assert set(rows) == {"revolution", "record5", "record10"}
    import csv

    with (out / "scores.csv").open() as f:
        own = [r for r in csv.DictReader(f) if r["method"] == "source_only" and r["file"].endswith("f1.zip")]
    for unit, r in rows.items():
        mine = [x for x in own if x["unit"] == unit]
        assert r["units"] == len(mine) and r["called"] == sum(x["decision"] == "1" for x in mine), (unit, r)


def test_the_scoring_state_is_stored_uncompressed_and_read_back_exactly_old_compressed_ones_too(tmp_path):
    """A condition's state (standardiser, reference, the whole history as float32) is written as a
    plain npz: deflate won ~8 % on its noisy floats for 0.16 s of CPU per 4 MB (issue 42). A run
    written before, compressed, is read as before."""
    import io
    import zipfile

    rng = np.random.default_rng(3)
    arrays = {
        "standardiser": np.array([0.1, 2.0]),
        "reference": rng.standard_normal(256),
        "history": rng.standard_normal((40, 256)).astype(np.float32),
    }
    run = RunDir(tmp_path)
    scoring.save_arrays(run.file("scoring", "condition0.npz"), **arrays)
    with zipfile.ZipFile(tmp_path / "scoring" / "condition0.npz") as z:
        assert {i.compress_type for i in z.infolist()} == {zipfile.ZIP_STORED}
    back = scoring.load_arrays(run.file("scoring", "condition0.npz"))
    assert set(back) == set(arrays) and all(
        back[k].dtype == v.dtype and np.array_equal(back[k], v) for k, v in arrays.items()
    )
    old = io.BytesIO()
    np.savez_compressed(old, **arrays)
    run.file("scoring", "condition1.npz").write(old.getvalue())
    back = scoring.load_arrays(run.file("scoring", "condition1.npz"))
    assert all(np.array_equal(back[k], v) for k, v in arrays.items())
