"""[operation] load_level: a factor on the output torque however given, what a gap diagnosis's
load_level fit writes into gearbox_corrected.toml (issue 39 item 1; gearlab.gap.corrected).

Every kind that simulates a description (dataset, gap, transfer, detection sources through
kinds.common.described_spec; simulated records; `gearlab simulate --gearbox`; the model's preset)
simulates the load times the level; the written description simulates as the source with the fit.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from tiny import rig_gap_run

from gearlab.data.simulated import simulated_record
from gearlab.errors import GearlabInputError
from gearlab.gap.corrected import FILE, corrected_description
from gearlab.gearbox import load_gearbox
from gearlab.gearbox.simulation import preset_of, reference, simulate_command
from gearlab.kinds.common import DATASET_TABLE, dataset_spec

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.filterwarnings("ignore:.*gives fewer than 10 steps")  # a coarse rate: both sides alike
RIG16 = ROOT / "examples" / "your_gearbox" / "rig16.toml"  # [operation] load = "7 N*m"
LOAD = ["load_level", [["factor", 1.5]]]
NOISE = ["sensor_noise", [["kind", "gaussian"], ["snr_db", 25.1]]]
BEARING = ["bearing_stiffness", [["c_factor", 2.0], ["k_factor", 0.41]]]


def copy(tmp_path: Path, level: str = "") -> Path:
    path = tmp_path / "rig16.toml"
    text = RIG16.read_text()
    if level:
        text = text.replace(
            'load = "7 N*m"             # output torque', f'load = "7 N*m"\nload_level = {level}  # mine'
        )
    path.write_text(text)
    return path


def source(path: Path, **given):
    entry = {k: key.default for k, key in DATASET_TABLE.keys.items()}
    return dataset_spec({**entry, "gearbox": str(path), **given}, "s.toml: [source]", path.parent)


def record(path: Path, **kw) -> np.ndarray:
    return simulated_record(gearbox=str(path), revolutions=2, fs=20e3, sim_fs=40e3, **kw).vibration


def test_every_way_of_simulating_a_description_takes_the_load_times_its_level(tmp_path):
    path = copy(tmp_path, "1.25")
    box = load_gearbox(path)
    assert (box.load_nm, box.load_level, box.torque(), box.torque(10.0)) == (7.0, 1.25, 8.75, 12.5)
    assert source(path).load_nm == 8.75
    assert source(path, load="10 N*m").load_nm == 12.5  # a scenario's load, times the level
    assert simulate_command(str(path), None, None, None, None)[3] == 8.75
    assert simulate_command(str(path), None, None, None, 10.0)[3] == 12.5
    assert preset_of(box, ("k_b",), 1)["load_nm"] == 8.75
    assert simulated_record(gearbox=str(path), revolutions=1, fs=20e3, sim_fs=40e3).load_nm == 8.75
    (tmp_path / "plain").mkdir()
    plain = copy(tmp_path / "plain")
    assert load_gearbox(plain).load_level == 1.0 and source(plain).load_nm == 7.0  # absent: as before
    assert source(path).preset != source(plain).preset  # the file's hash: the dataset cache key differs


@pytest.mark.parametrize("level, message", [("0", r"key 'load_level': 0 is outside \[0.01, 100\]"), ('"x"', "")])
def test_a_bad_load_level_is_one_line_naming_the_key(tmp_path, level, message):
    with pytest.raises(GearlabInputError, match=rf"rig16.toml: \[operation\] key 'load_level'{message and ': '}") as e:
        load_gearbox(copy(tmp_path, level))
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("level", ["", "1.25"])
def test_the_fitted_load_level_goes_into_operation_and_simulates_as_the_source_with_the_fit(tmp_path, level):
    path = copy(tmp_path, level)
    spec = source(path)
    text, said = corrected_description(spec, {"verdict": "explained", "corrected_effects": [LOAD, NOISE]}, "g/1")
    assert said == FILE
    written = tmp_path / FILE
    written.write_text(text)
    box = load_gearbox(written)
    old = float(level or 1)
    assert box.load_level == pytest.approx(1.5 * old, rel=1e-6) and box.load_nm == 7.0
    line = next(line for line in text.splitlines() if line.startswith("load_level"))
    x = "" if not level else " x 1.25"
    assert line.startswith(f"load_level = {1.5 * old:g}  # gap run g/1: load_level factor = 1.5{x}: ")
    assert f"{7 * old:g} -> {10.5 * old:g} N*m at the [operation] load" in line
    assert line.endswith("(was 1.25; mine)" if level else "N*m at the [operation] load")
    assert '#   { name = "sensor_noise", kind = "gaussian", snr_db = 25.1 }' in text  # left to [corrected] effects
    assert "load_level" not in text.split("not part of the gearbox")[1]
    # simulated: the written description alone = the source with the fitted load_level effect
    fitted = record(path, effects=[{"name": "load_level", "factor": 1.5}])
    alone = record(written)
    assert np.abs(fitted - alone).max() <= 1e-6 * np.abs(fitted).max()
    assert np.abs(fitted - record(path)).max() > 0.1 * np.abs(fitted).max()


def test_with_a_dynamics_fit_both_tables_are_written(tmp_path):
    path = copy(tmp_path)
    text, _ = corrected_description(source(path), {"verdict": "explained", "corrected_effects": [BEARING, LOAD]}, "g/1")
    (tmp_path / FILE).write_text(text)
    box = load_gearbox(tmp_path / FILE)
    assert box.load_level == 1.5 and box.dynamics["bearing_stiffness"] == pytest.approx(0.41e8)
    assert text.index("[operation]") < text.index("load_level = 1.5") < text.index("[[stages]]")


def test_a_gap_run_whose_load_is_off_writes_the_corrected_load(tmp_path, module_cache):
    # a stand-in diagnosis: the load found 1.5 x the source's
    run = rig_gap_run(tmp_path, module_cache, RIG16, 'load = "10.5 N*m"', "load_level", [LOAD, NOISE])
    assert json.loads((run / "summary.json").read_text())["corrected_description"] == FILE
    box = load_gearbox(run / FILE)
    assert (box.load_nm, box.load_level, box.torque()) == (7.0, 1.5, 10.5)  # the target's 10.5 N*m
    assert (
        f"load_level = 1.5  # gap run rig_gap/{run.name}: load_level factor = 1.5: 7 -> 10.5 N*m"
        in (run / FILE).read_text()
    )
    target = record(tmp_path / "rig.toml", load_nm=10.5)
    assert np.abs(record(run / FILE) - target).max() <= 1e-6 * np.abs(target).max()
    assert reference(str(run / FILE)) != reference(str(tmp_path / "rig.toml"))
