"""A gap run's corrected gearbox description (gearlab.gap.corrected, docs/your_gearbox.md step 4):
the user's description with the [dynamics] values the kept structural effects fitted, which loads
back and simulates as the source with those effects; the gap kind writes it and says so; a detection
scenario's [corrected] gearbox takes it. Stand-in diagnosis results: no search runs here."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from tiny import rig_gap_run

from gearlab.data.builder import _configured_simulator, steady_revolution
from gearlab.data.spec import DatasetSpec
from gearlab.effects import EffectChain, config_of
from gearlab.gap.corrected import FILE, corrected_description, write_corrected
from gearlab.gearbox import load_gearbox
from gearlab.gearbox.simulation import channel, model_name, reference
from gearlab.registry import get_registry
from gearlab.settings import declared

ROOT = Path(__file__).resolve().parents[1]
RIG16 = ROOT / "examples" / "your_gearbox" / "rig16.toml"
MENG = ROOT / "gearlab" / "gearbox" / "presets" / "meng2020.toml"
NOISE = ["sensor_noise", [["kind", "gaussian"], ["snr_db", 25.1]]]
BEARING = ["bearing_stiffness", [["c_factor", 2.0], ["k_factor", 0.41]]]
CASING = ["casing_path", [["c_xf", 300.0], ["c_yf", 400.0], ["k_xf", 3e7], ["k_yf", 5e7], ["mf", 18.5]]]
DRIVE = ["drive_inertias", [["I11", 0.002], ["I22", 0.003], ["c_c", 2.0], ["k_c", 500.0]]]
DAMPING = ["mesh_damping", [["model", "proportional"], ["zeta", 0.05]]]


def source_of(path: Path) -> DatasetSpec:
    """The [source] a gap scenario's `gearbox = PATH` makes: the description's model and sensor channel."""
    box = load_gearbox(path)
    model = model_name(box)
    return DatasetSpec(
        box.name, model, reference(str(path)), channel(box, model, get_registry().get("model", model).channels)
    )


def result(*effects, verdict="explained") -> dict:
    return {"verdict": verdict, "corrected_effects": [list(e) for e in effects]}


def revolution(model: str, preset: str, chan: str, effects=()) -> np.ndarray:
    """One steady healthy revolution (a coarse rate: the two sides only have to agree)."""
    config = EffectChain.load(effects).model_config(config_of(model, preset, chan))
    sim = _configured_simulator(config, 20e3)
    box = load_gearbox(Path(preset.removeprefix("gearbox:").rpartition("#")[0]))
    return steady_revolution(sim, (), box.speed_hz, box.load_nm, config.channel)


@pytest.mark.filterwarnings("ignore:.*gives fewer than 10 steps")  # a coarse rate: both sides alike
@pytest.mark.parametrize(
    ("original", "effects"),
    [
        (RIG16, (BEARING, CASING, DRIVE, DAMPING, NOISE)),  # every structural effect at once
        (RIG16, (DRIVE,)),  # the drive alone: the housing is stated so that the model keeps it
        (MENG, (CASING, BEARING)),  # an eight-DOF description gets its housing (ten_dof)
    ],
)
def test_the_fitted_values_go_into_the_description_and_it_simulates_as_the_source_with_them(
    tmp_path, original, effects
):
    path = tmp_path / original.name
    shutil.copy(original, path)
    source = source_of(path)
    text, said = corrected_description(source, result(*effects), "rig_gap/20261202-120000")
    assert said == FILE
    lines = text.splitlines()
    before = path.read_text().splitlines()
    kept = [line for line in lines if line in before and line]
    assert kept == [line for line in before if line in lines and line]  # the user's lines, in their order
    changed = [line for line in before if line not in lines]
    assert all(line.split("=")[0].strip() in DYNAMICS_KEYS for line in changed), changed
    written = tmp_path / FILE
    written.write_text(text)
    box = load_gearbox(written)  # loads back, geometry checked
    if BEARING in effects:
        k_b = load_gearbox(path).dynamics["bearing_stiffness"]
        assert box.dynamics["bearing_stiffness"] == pytest.approx(0.41 * k_b, rel=1e-6)
        assert "bearing_stiffness k_factor = 0.41 x" in text and "gap run rig_gap/20261202-120000" in text
    if CASING in effects:
        assert box.dynamics["casing_mass"] == 18.5 and box.dynamics["mounting_stiffness_y"] == 5e7
        assert 'casing_mass = "18.5 kg"  # gap run rig_gap/20261202-120000: casing_path mf = 18.5' in lines
    if DRIVE in effects:
        assert box.dynamics["coupling_stiffness"] == 500.0 and box.dynamics["motor_inertia"] == 0.002
    if NOISE in effects:
        assert "# not part of the gearbox: give them in [corrected] effects" in text
        assert '#   { name = "sensor_noise", kind = "gaussian", snr_db = 25.1 }' in lines
    # simulated: the written description alone = the source with the structural effects
    new = source_of(written)
    structural = tuple(
        get_registry().get("effect", name).spec(dict(params)) for name, params in effects if name != "sensor_noise"
    )
    assert new.model == ("ten_dof" if original == MENG else source.model)
    a = revolution(source.model, source.preset, source.channel, structural)
    b = revolution(new.model, new.preset, new.channel)
    assert a.shape == b.shape and np.abs(a - b).max() <= 1e-4 * np.abs(a).max()
    assert np.abs(a - revolution(source.model, source.preset, source.channel)).max() > 1e-2 * np.abs(a).max()


DYNAMICS_KEYS = {
    "motor_inertia",
    "load_inertia",
    "coupling_stiffness",
    "coupling_damping",
    "bearing_stiffness",
    "bearing_damping",
    "casing_mass",
    "mounting_stiffness_x",
    "mounting_stiffness_y",
    "mounting_damping_x",
    "mounting_damping_y",
    "mesh_damping_ratio",
}


def test_the_users_units_and_what_stays_in_the_corrected_effects(tmp_path):
    """A key written in the user's unit keeps it; a constant-damping fit (no description key) and
    signal-level effects stay in the list at the end; nothing structural kept: no file."""
    path = tmp_path / "rig.toml"
    path.write_text(RIG16.read_text() + '\n[dynamics]\nbearing_stiffness = "2e5 kN/m"   # catalogue\n')
    source = source_of(path)
    constant = ["mesh_damping", [["model", "constant"], ["zeta", 0.05]]]
    text, said = corrected_description(source, result(BEARING, constant, NOISE), "r/1")
    assert said == FILE
    assert (
        'bearing_stiffness = "82000 kN/m"  # gap run r/1: bearing_stiffness k_factor = 0.41 x 2e8 N/m '
        '(was "2e5 kN/m"; catalogue)'
    ) in text.splitlines()
    assert "mesh_damping_ratio" not in text and "'constant' damping model has no description key" in text
    assert text.splitlines().count("[dynamics]") == 1
    for effects in ((NOISE,), (constant, NOISE), ()):
        assert corrected_description(source, result(*effects), "r/1") == (None, None)
    # a [source] model without the motor and load (six_dof): the drive's fit cannot go into its description
    meng = DatasetSpec("m", "six_dof", reference(str(MENG)), "pinion_y")
    text, said = corrected_description(meng, result(DRIVE), "r/1")
    assert text is None and said.startswith("not written: model 'six_dof'") and "theta11" in said
    # a preset source (no description) writes nothing
    assert corrected_description(DatasetSpec("B", "six_dof", "meng2020", "pinion_y"), result(BEARING), "r/1") == (
        None,
        None,
    )


def test_write_corrected_writes_into_the_run_directory_only_when_there_is_something(tmp_path):
    path = tmp_path / "rig.toml"
    shutil.copy(RIG16, path)
    written = {}
    run = SimpleNamespace(path=tmp_path / "runs" / "rig_gap" / "20261202", write_text=written.__setitem__)
    assert write_corrected(source_of(path), result(NOISE), run) is None and not written
    assert write_corrected(source_of(path), result(BEARING, NOISE), run) == FILE
    assert set(written) == {FILE} and "gap run rig_gap/20261202: bearing_stiffness" in written[FILE]


# --- the gap kind writes it and says so -----------------------------------------------------------


@pytest.mark.filterwarnings("ignore:.*gives fewer than 10 steps")  # 40 kHz: a cheap target
def test_a_gap_run_of_a_description_writes_the_corrected_description(tmp_path, module_cache):
    bearing = 'effects = [{ name = "bearing_stiffness", k_factor = 0.5 }]'  # the target with the bearing fitted
    run = rig_gap_run(tmp_path, module_cache, RIG16, bearing, "bearing_stiffness", [BEARING, NOISE])
    summary = json.loads((run / "summary.json").read_text())
    assert summary["corrected_description"] == FILE
    box = load_gearbox(run / FILE)
    assert box.dynamics["bearing_stiffness"] == pytest.approx(0.41e8)
    assert f"gap run rig_gap/{run.name}" in (run / FILE).read_text()
    from gearlab.kinds.gap import summary_lines
    from gearlab.kinds.gap_verdict import gap_lines
    from gearlab.runs import RunDir

    assert f"corrected description: {FILE}" in summary_lines(RunDir(run))
    assert f"corrected description: {FILE}" in gap_lines(summary)


# --- a detection scenario's [corrected] gearbox ----------------------------------------------------


def detection(folder: Path, corrected: str) -> Path:
    from detection_scenario import scenario

    path = scenario(folder, methods=("matched_filter",), extra=corrected)
    text = path.read_text().replace('[source]\npreset = "B-6-ch5"', '[source]\ngearbox = "meng2020"')
    path.write_text(text)
    return path


def test_a_detection_scenario_takes_the_corrected_description(tmp_path, cli):
    from gearlab.engine import load_scenario

    fixed = tmp_path / "scenarios" / FILE
    fixed.parent.mkdir(parents=True)
    fixed.write_text(MENG.read_text().replace('bearing_stiffness = "6.56e8 N/m"', 'bearing_stiffness = "3e8 N/m"'))
    path = detection(
        tmp_path, f'[corrected]\ngearbox = "{FILE}"\neffects = [{{ name = "sensor_noise", snr_db = 20 }}]\n'
    )
    code, out, err = cli("validate", path)
    assert code == 0, err
    assert f"matched_filter (corrected: + {FILE}, sensor_noise)" in out
    spec = load_scenario(path).spec
    assert spec.corrected.preset == reference(str(fixed)) and spec.source.preset != spec.corrected.preset
    assert spec.corrected.model == spec.source.model and [n for n, _ in spec.corrected.effects] == ["sensor_noise"]
    assert spec.corrected.faults == spec.source.faults and spec.corrected.teeth == spec.source.teeth
    # the gearbox alone makes a corrected simulator too
    path.write_text(path.read_text().replace('effects = [{ name = "sensor_noise", snr_db = 20 }]\n', ""))
    assert load_scenario(path).spec.corrected.preset == reference(str(fixed))
    # other gears, a missing file, a [source] without a description: one line each, exit 2
    shutil.copy(RIG16, fixed)
    code, _, err = cli("validate", path)
    assert code == 2 and "[corrected] key 'gearbox'" in err and "tooth counts [(16, 48)]" in err
    assert len(err.strip().splitlines()) == 1
    fixed.unlink()
    code, _, err = cli("validate", path)
    assert code == 2 and "[corrected] key 'gearbox'" in err and FILE in err
    path.write_text(path.read_text().replace('gearbox = "meng2020"', 'preset = "B-6-ch5"'))
    shutil.copy(MENG, fixed)
    code, _, err = cli("validate", path)
    assert code == 2 and "[corrected] key 'gearbox'" in err and "no gearbox description" in err


def test_every_fitted_key_is_an_effect_parameter_or_a_factor_on_one():
    """description.FITTED (docs/settings.md: 'a gap run fits it'): each key's model value is a parameter of its
    effect, or bearing_stiffness's factor on it (gearlab.gap.corrected.FACTORS)."""
    from gearlab.gap.corrected import FACTORS
    from gearlab.gearbox.derive import DYNAMICS_NAMES
    from gearlab.gearbox.description import FITTED

    assert set(FITTED) == DYNAMICS_KEYS
    for key, name in FITTED.items():
        params = set(declared(get_registry().get("effect", name).params))
        assert DYNAMICS_NAMES[key] in params or FACTORS.get(DYNAMICS_NAMES[key]) in params, key
