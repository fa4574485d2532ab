"""Follow-ups of issue 39 found running gearlab as an outside user: `gearlab score` calls a take
whose damage lies on another gear what the detection run calls it (other damage: <gear>, with the
evidence) and prints a table that fits 80 columns with each record's speed and how it was found;
the gap kind reads history records without a tacho (a declared speed, or a description's mesh
orders) aligned as the detection kind aligns them; and its unknown-units warning says what fits
values in volts and values already in m/s²."""

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest
from detection_scenario import shared_run
from gearboxes import description, stage
from test_detection import scenario
from textrecords import FS, record, signals

from gearlab.errors import GearlabInputError
from gearlab.kinds import detection_scoring
from gearlab.kinds.detection_which_gear import NOT_LOCALISED, OTHER, WATCHED, decision_of, is_other
from gearlab.parts import scoring
from gearlab.runs import RunDir

WHEEL = "output gear 71T (stage 1)"


def test_a_record_called_on_another_gear_is_other_damage_not_a_fault():
    """The rule the detection run's which-gear table counts flags with (calls_by_label)."""
    assert decision_of(True, f"{OTHER}: {WHEEL}") == f"{OTHER}: {WHEEL}"
    assert decision_of(True, f"{WATCHED}: input pinion 23T (stage 1)") == "fault"
    assert decision_of(True, NOT_LOCALISED) == "fault"  # no evidence of where: the watched gear
    assert decision_of(True, None) == "fault"  # a run that does not localise
    assert decision_of(False, f"{OTHER}: {WHEEL}") == "healthy"
    assert is_other(f"{OTHER}: {WHEEL}") and not is_other(NOT_LOCALISED) and not is_other(None)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))


def test_score_says_other_damage_with_its_evidence_in_80_columns(cli, tmp_path, cache, monkeypatch, no_figures):
    out = shared_run(scenario(tmp_path, methods=("matched_filter",)), tmp_path / "runs")
    record(tmp_path / "new_ok.zip", revolutions=40, chip=0.0, seed=11, phase=0.3)
    record(tmp_path / "wheel.zip", revolutions=40, chip=4.0, seed=12, phase=1.1)
    evidence = "output z 850.5/2.6, input z -5.2/2.6; tooth 20 of 71"

    def localised(run_dir, records, turned=None):
        """The localisation of a take whose damage lies on the output gear (that localisation itself
        is signals.localise's; here what score makes of it)."""
        out = {}
        for recs in records.values():
            for path, *_ in recs:
                other = path.endswith("wheel.zip")
                out[path] = {
                    "named": WHEEL if other else None,
                    "summary": "",
                    "call": f"{OTHER}: {WHEEL}" if other else NOT_LOCALISED,
                    "evidence": evidence if other else "input z 1.0/2.6",
                }
        return out

    monkeypatch.setattr(detection_scoring, "localise_scored", localised)
    code, stdout, err = cli("score", out, tmp_path / "new_ok.zip", tmp_path / "wheel.zip", "--json")
    assert code == 0, err
    rows = {(Path(r["file"]).name, r["method"], r["unit"]): r for r in json.loads(stdout)}
    wheel = rows[("wheel.zip", "fm4", "record10")]
    assert wheel["called"] > wheel["units"] / 2  # FM4 flags the ringing take ...
    assert wheel["decision"] == f"{OTHER}: {WHEEL}" and wheel["evidence"] == evidence  # ... on another gear
    assert rows[("new_ok.zip", "fm4", "record10")]["decision"] == "healthy"
    assert wheel["speed_hz"] == pytest.approx(16.0, rel=1e-3) and wheel["speed_from"].startswith("tacho")
    history = scoring.read_history(RunDir.open(out))
    assert any(h["decision"] == f"{OTHER}: {WHEEL}" and h["evidence"] == evidence for h in history)
    # the trend the report and the TUI draw names the record called other damage (the second scored)
    (trend,) = [c for c in detection_scoring.score_trends(RunDir.open(out))]
    assert f"record 2: {OTHER}: {WHEEL}" in trend.title

    # the table: per file its speed and how it was found, which gear with the evidence; 80 columns
    code, stdout, err = cli("score", out, tmp_path / "wheel.zip")
    assert code == 0, err
    table = [line for line in stdout.splitlines() if line[:1] in "┏┃┡│└"]
    assert table and max(len(line) for line in table) <= 80, stdout
    cells = " ".join(" ".join(c.strip() for c in line.split("│")) for line in table if line.startswith("│"))
    assert f"{OTHER}: {WHEEL}" in " ".join(cells.split())  # a cell may wrap; no word is cut
    assert "16.000 Hz, from tacho" in stdout and f"which gear: {WHEEL} ({evidence})" in " ".join(stdout.split())


def _records(folder: Path, header: str) -> list[dict]:
    """Two healthy CSV records (time, vibration in m/s²) of the test rig, starting at different
    angles; no tacho."""
    files = []
    for i, phase in enumerate((0.0, 2.1)):
        vib, _ = signals(revolutions=30, seed=i, phase=phase)
        t = np.arange(vib.size) / FS
        name = f"{header}{i}.csv"
        np.savetxt(folder / name, np.c_[t, vib], delimiter=",", header=f"time_s,{header}", comments="")
        files.append({"file": name, "role": "history", "label": "healthy"})
    return files


BOX = description(stage(32, 71, bores=("25 mm", "35 mm")), name="box32", speed="16 Hz", load="40 N*m", near="input")


@pytest.mark.parametrize("keys", [{"speed": "16 Hz"}, {"gearbox": "box.toml"}])
def test_gap_history_records_without_a_tacho(tmp_path, keys):
    from gearlab.kinds.gap import target_of
    from gearlab.kinds.gap_inputs import TargetEntry, read_history

    (tmp_path / "box.toml").write_text(BOX)
    entry = {**asdict(TargetEntry()), "vibration": "acc_ms2", "files": _records(tmp_path, "acc_ms2"), **keys}
    records = target_of(entry, "s.toml: [target]", tmp_path)
    X, speed, notes, fs, from_mesh, _ = read_history(records, lambda e: None)
    # 29 + 28 revolutions: the second record, shifted into register as one signal, gives up its last
    assert speed == pytest.approx(16.0, rel=1e-3) and fs == FS and X.shape == (57, 4096)
    # the description's [operation] speed is the prior, as inspect takes it (gearbox.speed.follow_speed)
    mesh = "speed followed on the mesh phase (from the mesh lines (512 Hz as 1×M1), declared 16 Hz; box32), mean 16 Hz"
    how = "nominal speed 16 Hz" if "speed" in keys else mesh
    assert how in notes[-1] and "(tacho)" not in notes[-1] and from_mesh == ("gearbox" in keys)
    # the second record, started 2.1 rad later, is turned into register with the first at a whole
    # sample (parts.measured.aligned): one synchronous average (unturned, the mesh tone's means
    # correlate at cos(32 x 2.1) = -0.33)
    assert np.corrcoef(X[:29].mean(axis=0), X[29:].mean(axis=0))[0, 1] > 0.95


def test_gap_records_with_no_tacho_speed_or_gearbox_are_refused_in_one_line(tmp_path):
    from gearlab.kinds.gap import target_of
    from gearlab.kinds.gap_inputs import TargetEntry

    entry = {**asdict(TargetEntry()), "vibration": "acc_ms2", "files": _records(tmp_path, "acc_ms2")}
    with pytest.raises(GearlabInputError, match=r"^s.toml: \[target\] key 'tacho': missing; .*'speed'.*'gearbox'"):
        target_of(entry, "s.toml: [target]", tmp_path)


@pytest.mark.parametrize("channel, warned", [("acc", True), ("acc_ms2", False)])
def test_the_unknown_units_warning_says_what_fits_volts_and_m_s2(tmp_path, channel, warned):
    from gearlab.kinds.gap import target_of
    from gearlab.kinds.gap_inputs import TargetEntry, units_warning

    entry = {**asdict(TargetEntry()), "vibration": channel, "speed": "16 Hz", "files": _records(tmp_path, channel)}
    records = target_of(entry, "s.toml: [target]", tmp_path)
    assert records.units_known is not warned  # a name ending in m/s² says the unit
    line = units_warning(channel, np.ones((2, 8)))
    assert "\n" not in line and f"channel '{channel}' names no unit" in line
    assert "Values in volts need the sensor's sensitivity (e.g. sensitivity = '10 mV/g'" in line
    assert "already in m/s² need none" in line and "'acc_ms2'" in line
