"""Gearbox descriptions (gearlab.gearbox, docs/gearbox.md): the built-in presets as descriptions,
the order table, the ISO 21771 geometry checks and the derived gear pairs."""

from __future__ import annotations

import math
from fractions import Fraction

import gearboxes
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from thesis_tables import TABLE_2_3, TABLE_2_4

from gearlab.errors import GearlabInputError
from gearlab.gearbox import (
    builtin_gearboxes,
    gear_pair,
    gear_pairs,
    order_table,
    parse_gearbox,
    resolve_gearbox,
    stage_geometry,
)
from gearlab.gearbox.derive import StagePair, lumped_params
from gearlab.gearbox.description import speed_hz
from gearlab.physics.presets import PAIR_PRESETS
from gearlab.physics.presets import gear_pair as preset_pair
from gearlab.physics.stiffness import MeshStiffnessModel
from gearlab.registry import get_registry

# The lumped parameters as published (thesis_tables: Tables 2.3 and 2.4) and the PHM 2009 rig
# simulator's choices (docs/real_data.md); the built-in descriptions, and so the models' presets,
# must say exactly these.
RIG = {
    "m1": 0.89, "m2": 6.07, "m3": 3.54, "I11": 0.0043, "I12": 2.6e-4, "I21": 0.0223, "I31": 0.0101,
    "I22": 0.0045, "k_b": 1e8, "c_b": 2e3, "k_c": 1e4, "c_c": 10.0, "mf": 10.0, "k_xf": 2e8, "k_yf": 2e8,
    "c_xf": 2e3, "c_yf": 2e3, "zeta": 0.07,
}  # fmt: skip


def stage(z1, z2, **extra):
    pinion = {"z": z1, "bore": "10 mm", **extra.pop("pinion", {})}
    wheel = {"z": z2, "bore": "10 mm", **extra.pop("wheel", {})}
    return {"module": "2 mm", "face_width": "20 mm", **extra, "pinion": pinion, "wheel": wheel}


def described(*stages, **tables):
    return parse_gearbox({"stages": list(stages), **tables}, "box.toml")


# --- the presets as descriptions ----------------------------------------------------------------


def test_the_builtin_descriptions_are_the_three_presets():
    assert set(builtin_gearboxes()) == {"luo2019", "meng2020", "phm09"}


@pytest.mark.parametrize("name", ["luo2019", "meng2020", "phm09"])
def test_a_preset_description_derives_the_presets_gear_pairs(name):
    pairs = gear_pairs(resolve_gearbox(name))
    expected = [n for n in PAIR_PRESETS if n == name or n.startswith(f"{name}_stage")]
    assert [p.name for p in pairs] == expected
    for pair in pairs:
        assert pair == preset_pair(pair.name)  # every field: Z, m, b, α, E, ν, hub, h_a*, c*, ρ


@pytest.mark.parametrize(
    "name, model, params",
    [("luo2019", "ten_dof", TABLE_2_3), ("meng2020", "ten_dof", TABLE_2_4), ("phm09", "two_stage", RIG)],
)
def test_a_preset_description_derives_the_models_lumped_parameters(name, model, params):
    derived_model, derived = lumped_params(resolve_gearbox(name))
    assert derived_model == model
    for key, value in params.items():
        assert derived[key] == value, key  # bit for bit: "1.272 kg" read by pint is the float 1.272


@pytest.mark.parametrize(
    "model, preset, params",
    [("ten_dof", "luo2019", TABLE_2_3), ("eight_dof", "meng2020", TABLE_2_4), ("six_dof", "meng2020", TABLE_2_4),
     ("two_stage", "phm09", RIG)],
)  # fmt: skip
def test_the_models_presets_are_the_descriptions(model, preset, params):
    """One path: a model's preset is read from the built-in description of its name."""
    plugin = get_registry().get("model", model)
    p = plugin.preset(preset)
    assert p["params"] == {k: v for k, v in params.items() if k in plugin.param_names()}
    pairs = gear_pairs(resolve_gearbox(preset))
    assert p["pair"] == pairs[0] or p["pair"].next_stage == pairs[1]
    assert plugin.resolve(preset)[0].Z1 == pairs[0].Z1


@pytest.mark.parametrize("name, speed, load", [("luo2019", 25.2, 7.0), ("meng2020", 40.0, 20.0), ("phm09", 30.0, 20.0)])
def test_a_preset_description_states_the_presets_operating_point(name, speed, load):
    box = resolve_gearbox(name)
    assert (box.speed_hz, box.load_nm) == (speed, load)


def test_the_description_gives_the_same_mesh_stiffness_as_the_preset():
    a = MeshStiffnessModel(gear_pair(resolve_gearbox("luo2019"), resolve_gearbox("luo2019").stages[0]))
    b = MeshStiffnessModel(preset_pair("luo2019"))
    assert np.array_equal(a.mesh_stiffness((), 512).k, b.mesh_stiffness((), 512).k)


def test_the_iso_contact_ratio_is_the_stiffness_models():
    for name in builtin_gearboxes():
        box = resolve_gearbox(name)
        for s, pair in zip(box.stages, gear_pairs(box)):
            assert stage_geometry(s).contact_ratio == pytest.approx(pair.contact_ratio, rel=1e-9)


# --- the order table ---------------------------------------------------------------------------


def test_order_table_of_the_phm09_rig():
    table = order_table(resolve_gearbox("phm09"))
    assert table.shafts == ("input", "idler", "output")
    assert table.shaft_orders == (1, Fraction(1, 3), Fraction(1, 5))
    assert [s.mesh for s in table.stages] == [32, 16]
    assert [s.assembly_phase for s in table.stages] == [32, 16]
    # 32/96: the same pair meets every 3 pinion (= input) turns; 48/80: every 5 idler turns = 15 input turns
    assert [s.hunting_input_turns for s in table.stages] == [3, 15]
    assert table.train_period == 15
    labels = dict(table.lines())
    assert labels["M1"] == 32 and labels["M2 - idler"] == pytest.approx(16 - 1 / 3)


def test_order_table_of_an_unusual_two_stage_train():
    box = described(stage(23, 41), stage(19, 67))
    table = order_table(box)
    assert table.stages[1].mesh == Fraction(23 * 19, 41)
    assert table.shaft_orders[-1] == Fraction(23 * 19, 41 * 67)
    assert table.train_period == 41 * 67
    info = table.describe(speed_hz=25.0)
    assert info["stages"][0]["mesh_hz"] == pytest.approx(575.0)
    assert info["stages"][1]["mesh_hz"] == pytest.approx(25 * 23 * 19 / 41)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(17, 60), st.integers(17, 120)), min_size=1, max_size=3))
def test_order_table_identities(teeth):
    table = order_table(
        type("Box", (), {"stages": [_Teeth(i, *t) for i, t in enumerate(teeth)], "shafts": _names(len(teeth))})()
    )
    for k, s in enumerate(table.stages):
        assert s.mesh == table.shaft_orders[k] * s.pinion_teeth == table.shaft_orders[k + 1] * s.wheel_teeth
        assert (s.hunting_input_turns * s.pinion_shaft_order * s.pinion_teeth) % s.wheel_teeth == 0
    for o in table.shaft_orders:
        assert (o * table.train_period).denominator == 1


class _Teeth:
    def __init__(self, i, z1, z2):
        self.index = i + 1
        self.pinion = type("G", (), {"z": z1})()
        self.wheel = type("G", (), {"z": z2})()


def _names(n):
    return tuple(f"shaft {i}" for i in range(n + 1))


# --- reading and units -------------------------------------------------------------------------


def test_a_description_in_units_of_its_own(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text(
        """
[gearbox]
name = "rig"
[operation]
speed = "1500 rpm"
load = "12 N*m"
[materials.bronze]
E = "110 GPa"
nu = 0.34
density = "8800 kg/m^3"
[[stages]]
module = "0.0787 in"
pressure_angle = "0.3490658504 rad"
face_width = "20 mm"
pinion = { z = 20, bore = "20 mm" }
wheel = { z = 57, bore = "30 mm", material = "bronze" }
"""
    )
    box = resolve_gearbox(str(path))
    assert box.speed_hz == pytest.approx(25.0)  # revolutions per second, not 157 rad/s
    assert box.stages[0].module == pytest.approx(1.99898e-3)
    assert box.stages[0].wheel.material.E == 110e9
    assert box.shafts == ("input", "output")
    (pair,) = gear_pairs(box)  # each gear its own material (tests/test_profile_shift.py)
    assert (pair.pinion.E, pair.gear.E, pair.gear.nu) == (200e9, 110e9, 0.34)


def test_a_different_bore_per_gear_reaches_each_gears_fillet():
    box = described(stage(20, 57, wheel={"bore": "40 mm"}))
    pair = gear_pairs(box)[0]
    assert isinstance(pair, StagePair)
    assert pair.pinion.hub_radius == pytest.approx(5e-3) and pair.gear.hub_radius == pytest.approx(20e-3)


@pytest.mark.parametrize(
    "value, hz",
    [
        ("25 Hz", 25.0),
        ("1500 rpm", 25.0),
        ("1500 revolution/min", 25.0),
        ("1500 1/min", 25.0),
        ("157.0796327 rad/s", 25.0),
        (25, 25.0),
    ],
)
def test_speeds_in_any_unit(value, hz):
    assert speed_hz(value, "x") == pytest.approx(hz)


# --- one-line errors naming file, table and key -------------------------------------------------

BAD = [
    (
        {"stages": [stage(12, 40)]},
        r"box.toml: \[\[stages\]\] #1.pinion key 'z': 12 teeth at x = 0 are undercut.*'x' ≥ 0.131",
    ),
    ({"stages": [stage(14, 200)]}, r"#1.pinion key 'z': the wheel's tip meets the pinion below its base circle"),
    (
        {"stages": [stage(20, 57, centre_distance="80 mm")]},
        r"#1 key 'centre_distance': 80 mm contradicts z1 = 20, z2 = 57, m = 2 mm.*a_w = 77 mm; expected z1 \+ z2 = 80",
    ),
    ({"stages": [stage(20, 57, addendum=0.5, dedendum=0.8)]}, r"\[\[stages\]\] #1: contact ratio ε_α = 0.895 below 1"),
    ({"stages": [stage(14, 40, pinion={"x": 1.2})]}, r"#1.pinion key 'x': the teeth are pointed"),
    ({"stages": [stage(20, 57, pinion={"bore": "40 mm"})]}, r"#1.pinion key 'bore': 40 mm reaches the root circle"),
    ({"stages": [stage(20, 57, pinion={"teeth": 20})]}, r"#1.pinion key 'teeth': unknown key; known keys: z, x"),
    ({"stages": [stage(20.5, 57)]}, r"#1.pinion key 'z': expected a whole number, got 20.5"),
    ({"stages": [stage(20, 57, module="2 kg")]}, r"#1 key 'module': '2 kg' has the wrong dimension"),
    (
        {"stages": [{"face_width": "20 mm", "pinion": {"z": 20, "bore": "1 cm"}, "wheel": {"z": 57, "bore": "1 cm"}}]},
        r"#1 key 'module': missing",
    ),
    (
        {"stages": [stage(20, 57, wheel={"material": "stel"})]},
        r"#1.wheel key 'material': unknown material 'stel' \(did you mean 'steel'\?\)",
    ),
    ({"stages": [stage(20, 57)] * 4}, r"\[\[stages\]\]: 4 stages; expected 1 to 3"),
    ({"stages": []}, r"\[\[stages\]\]: expected 1 to 3 stages"),
    ({"stage": [stage(20, 57)]}, r"unknown table \[stage\] \(did you mean 'stages'\?\)"),
    (
        {"stages": [stage(20, 57)], "sensor": {"near": "inptu"}},
        r"\[sensor\] key 'near': unknown shaft 'inptu' \(did you mean 'input'\?\)",
    ),
    (
        {"stages": [stage(20, 57)], "operation": {"speed": "-3 Hz"}},
        r"\[operation\] key 'speed': expected an input-shaft speed's size, e.g. '25 Hz', got '-3 Hz': a box turning "
        r"either direction is read alike \(its tacho's pulses, its orders\): write '3 Hz'$",
    ),
    (
        {"stages": [stage(20, 57)], "dynamics": {"bearing_stiffness": "1 N/m"}},
        r"\[dynamics\] key 'bearing_stiffness': '1 N/m' is outside",
    ),
    ({"stages": [stage(20, 57)], "shafts": [{"name": "a"}]}, r"\[\[shafts\]\]: expected 2 shafts for 1 stage"),
]


@pytest.mark.parametrize("data, message", BAD)
def test_bad_descriptions_are_one_line_naming_the_key(data, message):
    with pytest.raises(GearlabInputError, match=message) as info:
        parse_gearbox(data, "box.toml")
    assert "\n" not in str(info.value)


def test_a_profile_shift_is_described_and_its_gear_pair_derived():
    box = described(stage(12, 40, pinion={"x": 0.3}, wheel={"x": -0.3}))
    assert order_table(box).stages[0].mesh == 12
    assert stage_geometry(box.stages[0]).a_w == pytest.approx(52e-3)  # x1 + x2 = 0: a_w = a
    (pair,) = gear_pairs(box)
    assert (pair.x1, pair.x2, pair.centre_distance) == (0.3, -0.3, pytest.approx(52e-3))


def test_a_shifted_centre_distance_is_accepted_with_the_matching_shift_sum():
    g = stage_geometry(described(stage(20, 57, pinion={"x": 0.5})).stages[0])
    assert g.a_w > 77e-3
    box = described(stage(20, 57, pinion={"x": 0.5}, centre_distance=f"{g.a_w * 1e3:.4f} mm"))
    assert box.stages[0].centre_distance == pytest.approx(g.a_w, abs=1e-7)


def test_files_that_cannot_be_read(tmp_path):
    with pytest.raises(GearlabInputError, match="no such gearbox description"):
        resolve_gearbox(str(tmp_path / "none.toml"))
    bad = tmp_path / "bad.toml"
    bad.write_text("[[stages]\n")
    with pytest.raises(GearlabInputError, match=r"bad.toml: invalid TOML"):
        resolve_gearbox(str(bad))
    with pytest.raises(GearlabInputError, match=r"no built-in description \(did you mean 'luo2019'\?\)"):
        resolve_gearbox("luo2018")


# --- the stiffness command ---------------------------------------------------------------------


def test_stiffness_of_a_described_gear_pair(tmp_path, cli):
    # `gearlab stiffness` in this process (the cli fixture: exit code, stdout, stderr), not three `python -m
    # gearlab` child processes, each of which imported gearlab again (1 s of CPU): what is asked is the
    # command's output and its one-line errors, which the CLI's own process tests cover elsewhere
    path = tmp_path / "g.toml"
    path.write_text(gearboxes.description(gearboxes.stage(20, 57, bores=("20 mm", "30 mm"))))
    code, out, err = cli("stiffness", "--gearbox", str(path), "--points", "256")
    assert code == 0, err
    assert (
        "Z1=20, Z2=57" in out
        and f"contact ratio {stage_geometry(resolve_gearbox(str(path)).stages[0]).contact_ratio:.4f}" in out
    )
    path.write_text(path.read_text().replace('module = "2 mm"', 'module = "2 mm"\ncentre_distance = "80 mm"'))
    code, out, err = cli("stiffness", "--gearbox", str(path))
    assert code == 2
    assert err.count("\n") == 1 and "g.toml: [[stages]] #1 key 'centre_distance'" in err
    code, out, err = cli("stiffness", "--gearbox", "phm09", "--stage", "3")
    assert code == 2 and "--stage: " in err and math.isfinite(1.0)
