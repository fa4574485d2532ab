"""A gearbox description as the simulator of a [source] (issue 39: `gearbox = "rig.toml"`): the built-in
descriptions give their dataset presets' arrays bit for bit (one path, not two), a user's gearbox with tooth
counts no preset has simulates end to end (one and two stages, a dataset and a gap diagnosis run), and what
the simulator cannot take is refused in one line naming the file, table and key."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.data.builder import _simulator, build_dataset, mesh_cycle
from gearlab.data.spec import CH5_STEPS, dataset_preset
from gearlab.errors import GearlabInputError
from gearlab.gearbox import builtin_gearboxes
from gearlab.kinds.common import DATASET_TABLE, dataset_spec
from gearlab.signals import spectrum


def _rig(name, load, direction, *stages):
    """A description's text: 25 Hz, *load*, the sensor near the input in *direction*."""
    return description(*stages, name=name, speed="25 Hz", load=load, near="input", direction=direction)


RIG20 = _rig("rig20", "10 N*m", "y", stage(20, 47, bores=("20 mm", "25 mm")))
RIG2S = _rig(
    "rig2s",
    "30 N*m",
    "x",
    stage(21, 53, bores=("20 mm", "25 mm")),
    stage(29, 61, "2.5 mm", "25 mm", ("25 mm", "30 mm")),
)


def source(base: Path = Path("."), **given):
    entry = {k: key.default for k, key in DATASET_TABLE.keys.items()}
    return dataset_spec({**entry, **given}, "s.toml: [source]", base)


def small(spec, faults, teeth):
    return spec.with_(faults=faults, teeth=teeth, healthy=2)


def same_arrays(a, b) -> None:
    x, y = build_dataset(a), build_dataset(b)
    assert np.array_equal(x.X, y.X)  # bit for bit: the same floats through the same simulation
    for key in ("label", "intensity", "tooth"):
        assert np.array_equal(getattr(x, key), getattr(y, key))
    assert x.reference == y.reference and x.meta == y.meta


# --- one path: the built-in descriptions are the dataset presets -------------------------------------


def test_the_phm09_description_gives_the_phm09_30_preset_bit_for_bit(tmp_path):
    chip = (("chip", (20,)),)
    described = small(source(gearbox="phm09", faults={"chip": [20]}, fs="66666.67 Hz"), chip, (1, 2))
    preset = small(dataset_preset("phm09-30"), chip, (1, 2))
    assert described.preset.startswith("gearbox:phm09#") and preset.preset == "phm09"
    assert (described.model, described.channel, described.speed_hz, described.load_nm, described.fs) == (
        "two_stage",
        "casing_x",
        30.0,
        20.0,
        preset.fs,
    )
    same_arrays(described, preset)
    # the same description as a user's file next to the scenario: the file path, not the name, is simulated
    shutil.copy(builtin_gearboxes()["phm09"], tmp_path / "rig.toml")
    copied = small(source(tmp_path, gearbox="rig.toml", preset="phm09-30"), chip, (1, 2))
    assert copied.preset.startswith(f"gearbox:{tmp_path.resolve()}") and copied.name == "phm09_phm09-30"
    same_arrays(copied, preset)


@pytest.mark.parametrize(
    "given, preset, model, channel",
    [
        ({"gearbox": "luo2019"}, "A-casing-ch5", "ten_dof", "casing_x"),  # the housing: ten_dof, sensor x
        ({"gearbox": "meng2020"}, "B-8-ch5", "eight_dof", "pinion_y"),  # a drive and no housing: eight_dof
        ({"gearbox": "meng2020", "model": "six_dof"}, "B-6-ch5", "six_dof", "pinion_y"),
    ],
)
def test_the_thesis_descriptions_give_their_dataset_presets_bit_for_bit(given, preset, model, channel):
    faults = (("crack", (12,)), ("chip", (20,)))
    described = small(source(**given), faults, (2, 5))
    expected = small(dataset_preset(preset), faults, (2, 5))
    assert (described.model, described.channel) == (model, channel) == (expected.model, expected.channel)
    assert (described.speed_hz, described.load_nm) == (expected.speed_hz, expected.load_nm)
    same_arrays(described, expected)


def test_a_description_alone_gets_the_chapter_5_ladders_and_a_preset_only_its_faults_and_sizes():
    spec = source(gearbox="luo2019")
    assert spec.name == "luo2019" and spec.faults == tuple(CH5_STEPS.items()) and spec.healthy == 15 * 16
    mixed = source(gearbox="luo2019", preset="B-6-ch5", speed="8.1 Hz")
    b6 = dataset_preset("B-6-ch5")
    assert (mixed.faults, mixed.healthy) == (b6.faults, b6.healthy)
    assert (mixed.model, mixed.speed_hz, mixed.load_nm) == ("ten_dof", 8.1, 7.0)  # the description's, 'speed' given


# --- a user's gearbox: tooth counts no preset has ------------------------------------------------


def test_the_defaults_a_description_leaves_are_the_ones_its_model_uses():
    from gearlab.gearbox import resolve_gearbox
    from gearlab.gearbox.simulation import defaults
    from gearlab.registry import get_registry

    names = get_registry().get("model", "eight_dof").param_names()
    # its housing keys are unused by eight_dof; load_level ([operation], the gap's load_level effect) is
    assert defaults(resolve_gearbox("meng2020"), names) == ["load_level (fit: load_level)"]
    names = get_registry().get("model", "ten_dof").param_names()
    assert "casing_mass (fit: casing_path)" in defaults(resolve_gearbox("meng2020"), names)


def test_a_one_stage_description_simulates_its_own_mesh(tmp_path):
    (tmp_path / "rig20.toml").write_text(RIG20)
    spec = small(source(tmp_path, gearbox="rig20.toml"), (("chip", (20,)),), (1,))
    assert (spec.model, spec.channel, spec.speed_hz, spec.load_nm) == ("ten_dof", "casing_y", 25.0, 10.0)
    data = build_dataset(spec)
    assert data.meta["Z1"] == 20 and data.X.shape == (3, 4096) and np.isfinite(data.X).all()
    orders, amp = spectrum(data.X[0].astype(float), 4096)  # a revolution of 4096 points: orders
    assert orders[1 + np.argmax(amp[1:])] % 20 == 0  # the strongest line is a harmonic of the 20-tooth mesh


def test_a_two_stage_description_of_fractional_mesh_order_settles_over_its_cycle(tmp_path):
    (tmp_path / "rig2s.toml").write_text(RIG2S)
    spec = small(source(tmp_path, gearbox="rig2s.toml"), (("chip", (20,)),), (1,))
    assert (spec.model, spec.channel) == ("two_stage", "casing_x")
    # stage 2 meshes 21 x 29 / 53 = 609/53 times per input turn: the train repeats every 53 turns
    assert mesh_cycle(_simulator(spec.model, spec.preset, 200025.0)) == 53
    assert mesh_cycle(_simulator("two_stage", "phm09", 66666.67)) == 1  # 32 x 48 / 96 = 16
    data = build_dataset(spec)
    assert data.X.shape == (3, 4096) and np.isfinite(data.X).all()
    orders, amp = spectrum(data.X[0].astype(float), 4096)
    assert orders[1 + np.argmax(amp[1:])] % 21 == 0


def test_a_cycle_too_long_to_simulate_whole_is_a_stretch(tmp_path, monkeypatch):
    """A healthy train repeats only after its meshes' cycle (rig2s: 53 turns; a wheel of over MAX_PERIOD
    teeth would take hours): beyond the limit, a stretch of steady turns (tests/test_long_period_trains.py)."""
    from gearlab.data import placement

    (tmp_path / "rig2s.toml").write_text(RIG2S)
    monkeypatch.setattr(placement, "MAX_PERIOD", 50)
    source(tmp_path, gearbox="rig2s.toml", faults={"chip": [20]})  # a fault's: validates (data.placement)
    data = build_dataset(source(tmp_path, gearbox="rig2s.toml", faults={}, healthy=2))
    assert data.X.shape == (2, 4096) and np.isfinite(data.X).all()
    orders, amp = spectrum(data.X[0].astype(float), 4096)
    assert orders[1 + np.argmax(amp[1:])] % 21 == 0


def test_a_user_gearbox_runs_a_dataset_and_a_gap_diagnosis(cli, tmp_path, monkeypatch, unrendered_figures):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "rig20.toml").write_text(RIG20)
    (tmp_path / "rig2s.toml").write_text(RIG2S)
    (tmp_path / "data.toml").write_text(
        '[scenario]\nname = "own"\nkind = "dataset"\n'
        '[[datasets]]\ngearbox = "rig20.toml"\nfaults = { chip = [20] }\nteeth = [1]\nhealthy = 2\n'
        '[[datasets]]\ngearbox = "rig2s.toml"\nfaults = { pit = [20] }\nteeth = [3]\nhealthy = 2\n'
    )
    (tmp_path / "gap.toml").write_text(
        '[scenario]\nname = "own_gap"\nkind = "gap"\n'
        '[source]\ngearbox = "rig20.toml"\nfaults = {}\nhealthy = 24\n'
        '[target]\ngearbox = "rig20.toml"\nfaults = {}\nhealthy = 24\n'
        'effects = [{ name = "sensor_noise", kind = "gaussian", snr_db = 20, seed = 3 }]\n'
        '[diagnosis]\ncandidates = ["sensor_noise"]\nbudget = 4\nhealthy = 24\nbootstrap = 50\npermutations = 50\n'
        "[accuracy]\nenabled = false\n"
    )
    for name in ("data.toml", "gap.toml"):
        code, out, err = cli("validate", name)
        assert code == 0, err
    code, out, err = cli("run", "data.toml", "--quick")
    assert code == 0, err
    assert "rig20: " in out and "rig2s: " in out
    code, out, err = cli("run", "gap.toml", "--quick")
    assert code == 0, err
    flat = " ".join(out.split())
    assert "effects: sensor_noise" in flat and "verdict: explained" in flat
    # the run says which of the simulator's values are the defaults' guesses, and which the diagnosis may fit
    assert "the source's gearbox description leaves to defaults" in flat and "casing_mass (fit: casing_path)" in flat
    assert "the input, output shaft blocks (solid discs)" in flat


# --- what the simulator cannot take: one line naming file, table and key ---------------------------------


@pytest.mark.parametrize(
    "text, given, expected",
    [
        (
            RIG20 + stage(23, 41) + stage(19, 67),
            {"model": "two_stage"},
            r"\[\[stages\]\]: 3 stage\(s\), but model 'two_stage' simulates 2 \(the description's model: three_stage\)",
        ),
        (RIG2S, {"model": "ten_dof"}, r"\[\[stages\]\]: 2 stage\(s\), but model 'ten_dof' simulates 1"),
        (RIG20.replace('direction = "y"', 'direction = "axial"'), {}, r"\[sensor\] key 'direction': 'axial'"),
        (RIG20.replace('speed = "25 Hz"\n', ""), {}, r"\[operation\] key 'speed': missing"),
        (RIG20.replace('load = "10 N*m"\n', ""), {}, r"\[operation\] key 'load': missing"),
        (RIG20, {"model_preset": "luo2019"}, r"key 'model_preset': the 'gearbox' description gives"),
    ],
)
def test_what_the_simulator_cannot_take_is_one_line(tmp_path, text, given, expected):
    (tmp_path / "box.toml").write_text(text)
    with pytest.raises(GearlabInputError, match=expected) as info:
        spec = source(tmp_path, gearbox="box.toml", **given)
        build_dataset(small(spec, (("chip", (20,)),), (1,)))
    assert "\n" not in str(info.value) and str(info.value).startswith("s.toml: [source] key ")


def test_a_description_edited_after_the_spec_was_made_is_refused(tmp_path):
    from gearlab.dynamics.newmark import Simulator
    from gearlab.registry import get_registry

    (tmp_path / "rig20.toml").write_text(RIG20)
    spec = source(tmp_path, gearbox="rig20.toml")
    (tmp_path / "rig20.toml").write_text(RIG20.replace("25 Hz", "30 Hz"))
    stale = spec.preset.replace("#", "#0")[:-1]  # a spec made from the other content (another process's cache)
    with pytest.raises(GearlabInputError, match="the gearbox description changed since the dataset was specified"):
        Simulator(get_registry().get("model", "ten_dof"), stale)
