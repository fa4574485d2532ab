"""The gap kind on measured records (docs/real_data.md): a [target] of zipped text records with an
N-pulse tacho, the diagnosis on their history files, model updating of an unpublished quantity,
the noise reference, and the refusals. The records are made here by the rig simulator itself
(a known load, known noise), so what the diagnosis must find is known; the real PHM 2009
records are used only when ../shared is there."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from textrecords import SENSITIVITY, write_zip

from gearlab.data.builder import _simulator, steady_revolution, whole_steps_rate
from gearlab.data.spec import PHM09_FS
from gearlab.engine import load_scenario, run_scenario
from gearlab.errors import GearlabInputError

SPEED, LOAD = 30.0, 20.0
PULSES = 10
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "phm09"


def rig_record(path: Path, load: float, seed: int, revolutions: int = 14, noise: float = 0.05) -> Path:
    """A record of the rig simulator at *load*: its steady casing revolution repeated, white noise of
    *noise* x its RMS, an output-side column, a 10-pulse tacho; volts at 10 mV/g, as the rig writes."""
    fs = whole_steps_rate(PHM09_FS, SPEED, 32)
    rev = steady_revolution(_simulator("two_stage", "phm09", fs), [], SPEED, load, "casing_x")
    rng = np.random.default_rng(seed)
    vib = np.tile(rev, revolutions) + noise * rev.std() * rng.standard_normal(revolutions * rev.size)
    theta = 2 * np.pi * np.arange(vib.size) / rev.size + 0.3
    # pulses with smooth edges (a real tacho's rise time): the sub-sample edge times, and with them the
    # order tracking, are then exact enough that the mesh tones do not leak into their neighbours
    tacho = 2.5 - 2.5 * np.cos(PULSES * theta)
    volts = vib * SENSITIVITY
    table = np.column_stack([volts, 0.5 * volts, tacho])
    lines = "%.7e  %.7e  %.7e\n" * len(table) % tuple(table.ravel().tolist())  # textrecords.text's one operation
    return write_zip(path, lines.encode())


def scenario(tmp_path: Path, files: list[tuple[str, str]], candidates: str, extra: str = "") -> Path:
    fs = whole_steps_rate(PHM09_FS, SPEED, 32)
    listed = ",\n".join(f'  {{ path = "{p}", role = "{role}", label = "healthy" }}' for p, role in files)
    text = f"""[scenario]
name = "records_gap"
kind = "gap"

[source]
preset = "phm09-30"

[target]
vibration = 0
tacho = 2
pulses_per_rev = {PULSES}
sensitivity = "10 mV/g"
fs = "{fs} Hz"
files = [
{listed}
]
{extra}
[diagnosis]
candidates = [{candidates}]
budget = 16
max_effects = 1
healthy = 12
bootstrap = 0
permutations = 50
reference = "noise"

[accuracy]
enabled = false
"""
    path = tmp_path / "records_gap.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def heavy(tmp_path_factory):
    """Two history records of the rig at twice the preset's load torque."""
    base = tmp_path_factory.mktemp("records")
    return [rig_record(base / f"rig_{i}.zip", 2 * LOAD, seed=i).name for i in range(2)], base


def diagnosed(heavy, tmp_path, monkeypatch, candidates: str) -> dict:
    """summary.json of the gap kind on the heavy records' history with these candidates."""
    names, base = heavy
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    run = run_scenario(scenario(base, [(n, "history") for n in names], candidates), out=tmp_path / "runs").path
    return json.loads((run / "summary.json").read_text())


def test_model_updating_finds_the_unpublished_load(heavy, tmp_path, monkeypatch, unrendered_figures):
    s = diagnosed(heavy, tmp_path, monkeypatch, '"load_level", "sensor_noise"')
    names_found = [e["name"] for e in s["effects"]]
    assert "load_level" in names_found
    factor = next(e for e in s["effects"] if e["name"] == "load_level")["params"]["factor"]
    assert factor == pytest.approx(2.0, rel=0.1)
    # beyond the noise fitted alone, the load removes most of what is left
    ref = s["reference"]
    assert ref["name"] == "sensor_noise" and s["gap_after"] < 0.7 * ref["gap"]
    assert any("history record(s) at 30.000 Hz" in n for n in s["notes"])


def test_a_wrong_mechanism_leaves_the_gap_unexplained(heavy, tmp_path, monkeypatch, unrendered_figures):
    """Only an effect that cannot scale the gear vibration is offered: the gap beyond the noise stays."""
    assert diagnosed(heavy, tmp_path, monkeypatch, '"interference_tone", "sensor_noise"')["unexplained"]


def test_records_of_two_speeds_are_refused(heavy, tmp_path, monkeypatch):
    names, base = heavy
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    fast = base / "fast.zip"
    vib = np.sin(32 * 2 * np.pi * 40.0 * np.arange(40000) / 67200.0)
    theta = 2 * np.pi * 40.0 * np.arange(vib.size) / 67200.0
    tacho = np.where(np.mod(theta * PULSES / (2 * np.pi), 1.0) < 0.3, 5.0, 0.05)
    rows = np.column_stack([vib * SENSITIVITY, vib * SENSITIVITY, tacho])
    write_zip(fast, ("%.7e  %.7e  %.7e\n" * len(rows) % tuple(rows.ravel().tolist())).encode())
    path = scenario(base, [(names[0], "history"), ("fast.zip", "history")], '"sensor_noise"')
    with pytest.raises(GearlabInputError, match="different speeds"):
        run_scenario(path, out=tmp_path / "runs")


@pytest.mark.parametrize(
    "extra, message",
    [
        ('preset = "phm09-30"\n', "either 'files'"),
    ],
)
def test_bad_record_targets(heavy, extra, message):
    names, base = heavy
    path = scenario(base, [(names[0], "history")], '"sensor_noise"')
    path.write_text(path.read_text().replace("[target]\n", "[target]\n" + extra))
    with pytest.raises(GearlabInputError, match=message):
        load_scenario(path)


def test_reference_noise_needs_the_noise_candidate(heavy):
    names, base = heavy
    path = scenario(base, [(names[0], "history")], '"load_level"')
    with pytest.raises(GearlabInputError, match="reference = 'noise' needs 'sensor_noise'"):
        load_scenario(path)


@pytest.mark.skipif(not SHARED.is_dir(), reason="the PHM 2009 records (../shared/data/phm09) are not here")
def test_shipped_rig_gap_scenarios_validate():
    root = Path(__file__).resolve().parents[1] / "scenarios"
    for name, speed in (("phm09_gap.toml", 30.0), ("phm09_gap_40hz.toml", 40.0)):
        s = load_scenario(root / name)
        assert s.spec.source.model == "two_stage" and s.spec.source.speed_hz == speed
        assert all(f.role == "history" for f in s.spec.target.target.files)
        assert s.spec.settings.reference == "noise"
