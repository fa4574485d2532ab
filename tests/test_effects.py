"""Unmodelled effects (gearlab.effects, plugins/effects; docs/gap.md, docs/plugins.md): the plugin
contract, each built-in effect's signature on a short simulation or signal, zero strength,
the tooth-shift symmetry, datasets and scenarios with effects, and bad input.

Simulations are single steady revolutions in time samples at the builder's whole-steps rate,
so shaft orders fall exactly on spectrum bins (an effect-free revolution has no energy off
the mesh harmonics to 1e-13). Every dataset is tiny and builds in its own cache
(GEARLAB_CACHE = tmp_path)."""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
import json
import math
import sys
import types
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from gearlab import PHYSICS_VERSION
from gearlab.data.builder import (
    SimTask,
    _configured_simulator,
    _simulator,
    build_dataset,
    simulate_unit,
    steady_response,
    steady_revolution,
    whole_steps_rate,
)
from gearlab.data.spec import DATASET_PRESETS, POINTS, NoiseSpec, dataset_preset
from gearlab.dynamics.excitation import Excitation
from gearlab.effect_contract import HOOKS, Effect, SignalContext
from gearlab.effects import EffectChain, config_of, effect_spec, effects_from_tables, model_of
from gearlab.errors import GearlabInputError, UnknownPluginError
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry, hookimpl, load_registry
from gearlab.settings import declared, setting
from gearlab.signals import NOISE_KINDS, order_spectrum
from gearlab_plugins.effects.sensor_bandwidth import frequency_response
from gearlab_plugins.effects.tooth_friction import friction_pattern

REG = get_registry()

# name: (level, breaks the tooth-shift symmetry)
EFFECTS = {
    "casing_path": ("model", False),
    "drive_inertias": ("model", False),
    "bearing_stiffness": ("model", False),
    "mesh_damping": ("model", False),
    "speed_fluctuation": ("excitation", True),
    "load_fluctuation": ("excitation", True),
    "shaft_eccentricity": ("excitation", True),
    "tooth_friction": ("excitation", False),
    "fillet_correction": ("excitation", False),
    "sensor_noise": ("signal", False),
    "sensor_bandwidth": ("signal", False),
    "sensor_lowpass": ("signal", False),
    "interference_tone": ("signal", False),
    "load_level": ("excitation", False),
    "sensor_offset": ("signal", False),
}

# the thesis's operating points: Dataset B (Table 2.4) and Dataset A (Table 2.3)
B = dict(model="six_dof", preset="meng2020", speed=40.0, load=20.0, channel="pinion_y", Z1=25)
A = dict(model="ten_dof", preset="luo2019", speed=25.2, load=7.0, channel="pinion_x", Z1=16)


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    path = tmp_path / "cache"
    monkeypatch.setenv("GEARLAB_CACHE", str(path))
    return path


def fs_of(op) -> float:
    return whole_steps_rate(200e3, op["speed"], op["Z1"])


def configured(effects=(), op=B, **changes):
    """(simulator, configuration, chain) of *op* (with *changes*) under *effects* (canonical specs)."""
    op = {**op, **changes}
    chain = EffectChain.load(tuple(effects))
    config = chain.model_config(config_of(op["model"], op["preset"], op["channel"]))
    return _configured_simulator(config, fs_of(op)), config, chain


def revolution(effects=(), op=B, faults=(), **changes):
    """One steady revolution (time samples from a tacho zero) and its angle (None when nominal)."""
    op = {**op, **changes}
    sim, config, chain = configured(effects, op)
    placed = [place_fault(REG, sim.pair, name, tooth, step=step) for name, tooth, step in faults]
    return steady_response(sim, placed, op["speed"], op["load"], config.channel, chain.at("excitation"))


def rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def rel(a, b) -> float:
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)) / np.linalg.norm(b))


def sidebands(x, Z1: int, q: int = 1, harmonics=(1, 2, 3)) -> float:
    """RMS amplitude of the orders h Z1 +- q relative to the mesh harmonics h Z1 (h in harmonics)."""
    _, amp = order_spectrum(x)
    mesh = sum(amp[h * Z1] ** 2 for h in harmonics)
    side = sum(amp[h * Z1 + s * q] ** 2 for h in harmonics for s in (-1, 1))
    return math.sqrt(side / mesh)


# --- the contract and the registry ----------------------------------------------------------


def test_all_builtin_effects_are_registered_with_level_symmetry_and_a_physical_docstring():
    assert REG.problems == []
    assert REG.names("effect") == sorted(EFFECTS)
    rows = {row["name"]: row for row in REG.describe() if row["kind"] == "effect"}
    for name, (level, breaks) in EFFECTS.items():
        effect = REG.get("effect", name)
        assert REG.packages[("effect", name)] == "gearlab"
        assert (effect.level, effect.breaks_symmetry) == (level, breaks), name
        assert getattr(type(effect), HOOKS[level]) is not getattr(Effect, HOOKS[level]), name  # its level's hook
        schema = declared(effect.params)
        assert schema and all(p.low <= default <= p.high for p, default in schema.values())
        module = sys.modules[type(effect).__module__].__doc__
        assert "Physical mismatch" in module and "Bounds" in module, name  # what it models and why its bounds
        assert (rows[name]["level"], rows[name]["breaks_symmetry"]) == (level, breaks)  # gearlab plugins shows them
        assert rows[name]["params"] and rows[name]["doc"]
        assert effect.resolve({}) == dict(effect.spec()[1])  # defaults resolve, canonical = resolved
    assert rows["sensor_noise"]["options"] == {"kind": list(NOISE_KINDS)}


def test_search_space_has_bounds_scales_and_choices():
    space = {p["name"]: p for p in REG.get("effect", "drive_inertias").space()}
    assert space["k_c"] == {
        "name": "k_c",
        "unit": "N*m/rad",
        "low": 1.0,
        "high": 1e8,
        "default": 1e3,
        "integer": False,
        "log": True,
    }
    # a coupling's damping spans 0.01-1e4 N m s/rad (the load mode's damping ratio 0.1-2 over inertias and stiffnesses
    # of five decades): searched on a log scale as the stiffness is; a ratio of 0-0.15 stays linear
    assert space["c_c"]["log"] is True
    assert {p["name"]: p for p in REG.get("effect", "mesh_damping").space()}["zeta"]["log"] is False
    noise = {p["name"]: p for p in REG.get("effect", "sensor_noise").space()}
    assert noise["kind"] == {"name": "kind", "choices": list(NOISE_KINDS), "default": "gaussian"}
    assert REG.get("effect", "speed_fluctuation").space()[1]["integer"] is True


class _Dist:
    name = "thirdparty"


class _EntryPoint:
    def __init__(self, name, module):
        self.name, self.value, self.dist, self._module = name, f"thirdparty.{name}", _Dist(), module

    def load(self):
        return self._module


@dataclass(frozen=True)
class RatioParams:
    ratio: float = setting(float, 0.1, low=0.0, high=1.0, doc="level")


class Hum(Effect):
    name = "hum"
    doc = "mains hum"
    level = "signal"
    params = RatioParams

    def apply_signal(self, x, params, ctx):
        return x + params["ratio"] * ctx.reference_rms * np.sin(2 * np.pi * 50.0 * ctx.time(x.size).reshape(x.shape))


class NoHook(Hum):
    name = "nohook"
    level = "model"  # but implements only the signal hook


class BadLevel(Hum):
    name = "badlevel"
    level = "sensor"


class BadSymmetry(Hum):
    name = "badsymmetry"
    breaks_symmetry = "no"


class Hiss(Effect):  # names no level: the one hook it overrides is its level
    name = "hiss"
    params = RatioParams

    def apply_signal(self, x, params, ctx):
        return x + params["ratio"] * ctx.rng.standard_normal(x.shape)


class TwoHooks(Hiss):
    name = "twohooks"

    def apply_model(self, config, params):
        return config


def test_third_party_effect_loads_and_contract_breaches_are_reported():
    module = types.ModuleType("thirdparty")
    module.gearlab_effects = hookimpl(lambda: [Hum(), NoHook(), BadLevel(), BadSymmetry(), Hiss(), TwoHooks()])
    module.gearlab_effects.__name__ = "gearlab_effects"
    builtin = [ep for ep in importlib.metadata.entry_points(group="gearlab") if ep.dist.name == "gearlab"]
    registry = load_registry(builtin + [_EntryPoint("hum", module)])
    assert "hum" in registry.names("effect") and registry.packages[("effect", "hum")] == "thirdparty"
    problems = " | ".join(str(p) for p in registry.problems)
    assert "effect 'nohook' of level 'model' lacks apply_model" in problems
    assert "level must be one of model, excitation, signal, got 'sensor'" in problems
    assert "breaks_symmetry must be True or False" in problems
    assert "effect 'twohooks': override exactly one of apply_model, apply_excitation, apply_signal" in problems
    assert not {"nohook", "badlevel", "badsymmetry", "twohooks"} & set(registry.names("effect"))
    assert registry.get("effect", "hiss").level == "signal"
    # a third-party effect goes through the same chain as the built-in ones
    chain = EffectChain.load((("hum", (("ratio", 0.5),)),), registry=registry)
    x = np.zeros((2, 64))
    y = chain.apply_signal(x, fs=6400.0, speed_hz=100.0, reference_rms=2.0, seed=[0])
    assert 0.9 < np.abs(y).max() <= 1.0


# --- model level -----------------------------------------------------------------------------


# Table 2.4's drive (Chaari et al. 2012, Mohammed et al. 2015): Dataset B-8's values, given here, never
# the effect's defaults (a diagnosis starts at the defaults; it must not start at a target's answer)
TABLE_2_4_DRIVE = effect_spec("drive_inertias", I11=0.0043, I22=0.0045, k_c=1e4, c_c=10.0)
# Table 2.3's casing (Luo et al. 2019b): Dataset A-casing's values
TABLE_2_3_CASING = effect_spec("casing_path", mf=18.509, k_xf=1.9912e8, k_yf=2.036e8, c_xf=1995.56, c_yf=2005.80)


def test_no_model_effect_defaults_to_a_target_preset():
    """The defaults of the effects that add DOFs are none of the presets' values (Tables 2.3, 2.4):
    the corrected simulator must be found from the target's data, not start at the answer."""
    from gearlab.gap.diagnose import Space

    LUO2019, MENG2020 = REG.get("model", "ten_dof").preset("luo2019"), REG.get("model", "eight_dof").preset("meng2020")
    for name in ("drive_inertias", "casing_path"):
        for key, (_, default) in declared(REG.get("effect", name).params).items():
            assert all(default != preset["params"].get(key) for preset in (LUO2019, MENG2020)), (name, key)
    # a search starts from the source: a six_dof source has no drive (the defaults), a ten_dof source
    # has its own, which the search starts from
    drive = REG.get("effect", "drive_inertias")
    assert Space(drive, dataset_preset("B-6-ch5")).defaults == {k: d for k, (_, d) in declared(drive.params).items()}
    assert Space(drive, dataset_preset("A-pinion-ch5")).defaults == {
        k: LUO2019["params"][k] for k in ("I11", "I22", "k_c", "c_c")
    }


def test_the_gap_search_starts_from_the_source_it_is_given(monkeypatch):
    """A fit of drive_inertias on a ten_dof source (Dataset A's, whose model has its own drive)
    starts from the source's values, not the effect's defaults: the search the diagnosis runs
    (gearlab.gap.search.fit_effect) builds its space from the source, as Space does above."""
    from gearlab.gap import search

    LUO2019 = REG.get("model", "ten_dof").preset("luo2019")
    made = []

    class Started(Exception):
        pass

    class Recorded(search.Space):
        def __init__(self, effect, source=None):
            super().__init__(effect, source)
            made.append(self)
            raise Started  # the start is all this test reads: no simulation

    monkeypatch.setattr(search, "Space", Recorded)
    with pytest.raises(Started):
        search.fit_effect((dataset_preset("A-pinion-ch5"), "drive_inertias", (), None, None, 0, False, None))
    assert made[0].defaults == {k: LUO2019["params"][k] for k in ("I11", "I22", "k_c", "c_c")}


def test_no_mismatch_factor_defaults_a_source_value_onto_another_preset_s():
    """A mismatch factor at its default keeps the source's value (1) or lands it on no preset's value:
    load_level's factor times a preset's torques is none of the presets' loads (1.5 or 0.5 would move
    Dataset B's 20 N*m onto its 30 or 10), bearing_stiffness's factors times one preset's k_b, c_b none
    of the other's (k_factor 0.5 is a prior, supports softer than the bearing alone). Every parameter
    named *factor is listed here."""
    presets = (REG.get("model", "ten_dof").preset("luo2019"), REG.get("model", "eight_dof").preset("meng2020"))
    values = {
        ("load_level", "factor"): lambda p: p["loads_nm"],
        ("bearing_stiffness", "k_factor"): lambda p: (p["params"]["k_b"],),
        ("bearing_stiffness", "c_factor"): lambda p: (p["params"]["c_b"],),
    }
    named = {(n, k) for n in REG.names("effect") for k in declared(REG.get("effect", n).params) if k.endswith("factor")}
    assert named == set(values)
    for (name, key), of in values.items():
        factor = declared(REG.get("effect", name).params)[key][1]
        if factor == 1.0:
            continue
        moved = [v * factor for p in presets for v in of(p)]
        assert not any(math.isclose(m, v) for m in moved for p in presets for v in of(p)), (name, key, factor)


def test_drive_inertias_on_six_dof_is_the_eight_dof_model_of_dataset_b():
    sim, config, _ = configured([TABLE_2_4_DRIVE])
    assert model_of(config).name == "eight_dof" and sim.model is REG.get("model", "eight_dof")
    assert (config.input_dof, config.load_dof) == ("theta11", "theta22")  # the motor turns at fixed speed
    eight = _simulator("eight_dof", "meng2020", fs_of(B))
    for faults in ((), (("crack", 5, 20),)):
        placed = [place_fault(REG, eight.pair, n, t, step=s) for n, t, s in faults]
        want = steady_revolution(eight, placed, 40.0, 20.0, "pinion_y")
        got, angle = revolution([TABLE_2_4_DRIVE], faults=faults)
        assert angle is None and np.array_equal(got, want)
    # on a model that has them, it only sets their values
    _, ten, _ = configured([effect_spec("drive_inertias", I11="0.01 kg*m^2")], A)
    assert model_of(ten).name == "ten_dof" and ten.params["I11"] == 0.01 and ten.params["I22"] == 1e-3


def test_casing_path_moves_the_pinion_sensor_to_the_casing():
    # Experiment A: A-pinion (x1) with Table 2.3's casing path is A-casing (xf)
    got, _ = revolution([TABLE_2_3_CASING], A)
    want = steady_revolution(_simulator("ten_dof", "luo2019", fs_of(A)), [], 25.2, 7.0, "casing_x")
    assert np.array_equal(got, want)
    # on the six-DOF model it adds the casing (bearings no longer grounded) and the sensor follows
    _, config, _ = configured([effect_spec("casing_path")])
    assert model_of(config).name == "six_dof+xf+yf" and config.channel == "casing_y" and config.params["mf"] == 10.0
    casing, _ = revolution([effect_spec("casing_path")])
    pinion, _ = revolution()
    assert rms(casing) < 0.2 * rms(pinion)  # the path hides the gear vibration (Figure 2.28)


def test_bearing_stiffness_moves_the_bearing_modes_by_the_square_root_of_its_factor():
    bearing_mode = math.sqrt(6.56e8 / 0.4439) / (2 * math.pi)  # gear block on its bearings, x (Table 2.4)
    base, _, _ = configured()
    assert np.any(np.isclose(base.natural_frequencies(), bearing_mode, rtol=1e-6))
    for factor in (0.25, 4.0):
        sim, config, _ = configured([effect_spec("bearing_stiffness", k_factor=factor)])
        assert config.params["k_b"] == pytest.approx(6.56e8 * factor)
        assert np.any(np.isclose(sim.natural_frequencies(), bearing_mode * math.sqrt(factor), rtol=1e-6))
    same, _ = revolution([effect_spec("bearing_stiffness", k_factor=1.0, c_factor=1.0)])
    assert np.array_equal(same, revolution()[0])  # factor 1: the source model


def test_mesh_damping_ratio_and_model():
    source, _ = revolution()
    thesis, _ = revolution([effect_spec("mesh_damping", zeta=0.07, model="proportional")])
    assert np.array_equal(thesis, source)  # the thesis's own choice changes nothing
    for model in ("proportional", "constant"):
        levels = [rms(revolution([effect_spec("mesh_damping", zeta=z, model=model)])[0]) for z in (0.03, 0.07, 0.15)]
        assert levels[0] > levels[1] > levels[2], (model, levels)  # more damping, less resonant response
    constant, _ = revolution([effect_spec("mesh_damping")])
    assert rel(constant, source) > 1e-3  # c = c_m is not c = mu k(t)


# --- excitation level ------------------------------------------------------------------------


def test_fillet_correction_softens_double_contact_only():
    sim, _, chain = configured([effect_spec("fillet_correction")])
    k = sim.run([], 40.0, 20.0, duration=1 / 40, effects=chain.at("excitation")).tvms
    k0 = sim.run([], 40.0, 20.0, duration=1 / 40).tvms
    single = k == k0
    assert 0.2 < single.mean() < 0.5  # the single-contact share of a revolution (contact ratio 1.63)
    assert k0[single].max() < k0[~single].min()  # unchanged where one pair carries the load
    drop = 1 - k[~single] / k0[~single]
    assert 0.08 < drop.min() and drop.max() < 0.2  # about 12 % softer in double contact (docstring)
    assert np.array_equal(revolution([effect_spec("fillet_correction", lam=0.0)])[0], revolution()[0])


def test_tooth_friction_is_dissipative_linear_and_mostly_across_the_line_of_action():
    sim, _, _ = configured()
    t = np.arange(5000) / 200e3
    tvms = sim.stiffness.mesh_stiffness(points=5000)
    exc = Excitation(
        fs=200e3,
        speed_hz=40.0,
        load_nm=20.0,
        t=t,
        angle=2 * np.pi * 40.0 * t,
        tvms=tvms,
        load=np.full(5000, 20.0),
        dofs=sim.dofs,
        M=sim.M,
        P=sim.P,
        mu=sim.mu,
        c0=0.0,
        load_dof=sim.load_dof,
        stiffness=sim.stiffness,
    )
    force, t1, t2 = friction_pattern(exc, 0.05)
    power = t1 + t2 * sim.pair.pinion.R_b / sim.pair.gear.R_b  # on the rigid rotation, per rad/s
    assert power.max() <= 1e-9 and power.min() < -1e-3  # friction only dissipates
    assert np.any(force > 0) and np.any(force < 0)  # it reverses at the pitch point
    W = 20.0 / sim.pair.gear.R_b
    assert np.abs(force).max() <= 0.05 * W * (1 + 1e-12)
    # the response change is linear in mu_f and far larger across the line of action (x) than along it (y)
    x0, y0 = revolution(channel="pinion_x")[0], revolution()[0]
    dx = {mu: revolution([effect_spec("tooth_friction", mu_f=mu)], channel="pinion_x")[0] - x0 for mu in (0.05, 0.1)}
    dy = revolution([effect_spec("tooth_friction", mu_f=0.05)])[0] - y0
    assert np.abs(dx[0.1] - 2 * dx[0.05]).max() < 1e-9 * np.abs(dx[0.1]).max()
    assert rms(dx[0.05]) > 0.2 * rms(x0) and rms(dy) < 0.5 * rms(dx[0.05]) * rms(y0) / rms(x0)
    assert np.array_equal(revolution([effect_spec("tooth_friction", mu_f=0.0)])[0], y0)


@pytest.mark.parametrize("model", ["six_dof", "eight_dof"])
def test_shaft_eccentricity_adds_first_shaft_order_sidebands_around_the_mesh_harmonics(model):
    base, _ = revolution(model=model)
    assert sidebands(base, 25) < 1e-10  # fixed speed, healthy: only mesh harmonics
    small, _ = revolution([effect_spec("shaft_eccentricity", e="20 um")], model=model)
    large, _ = revolution([effect_spec("shaft_eccentricity", e="100 um")], model=model)
    assert sidebands(small, 25) > 1e-4
    assert sidebands(large, 25) / sidebands(small, 25) == pytest.approx(5.0, rel=0.01)  # linear in e
    assert np.array_equal(revolution([effect_spec("shaft_eccentricity", e=0.0)], model=model)[0], base)


def test_speed_fluctuation_modulates_the_mesh_at_its_order_and_moves_the_tacho():
    base, none = revolution()
    x, angle = revolution([effect_spec("speed_fluctuation", amplitude=0.01, order=3)])
    assert none is None and angle is not None
    assert angle[0] == pytest.approx(0.0, abs=1e-9) and angle[-1] < 2 * np.pi  # one revolution from the tacho zero
    speed = np.diff(angle) * fs_of(B) / (2 * np.pi)
    assert speed.max() == pytest.approx(40.4, rel=1e-3) and speed.min() == pytest.approx(39.6, rel=1e-3)
    assert sidebands(x, 25, q=3) > 0.05 > 1e-10 > sidebands(base, 25, q=3)
    assert sidebands(x, 25, q=3) > 100 * sidebands(x, 25, q=1)  # at its own order
    # the dataset row is resampled at the true angle (order tracking): mesh harmonics stay on their orders
    row = simulate_unit(
        SimTask(
            "six_dof",
            "meng2020",
            fs_of(B),
            40.0,
            20.0,
            "pinion_y",
            None,
            None,
            (1,),
            (effect_spec("speed_fluctuation", amplitude=0.01, order=3),),
            1,
        )
    )[0]
    orders, amp = order_spectrum(row)
    assert orders[np.argmax(amp[1:]) + 1] % 25 == 0
    assert np.array_equal(revolution([effect_spec("speed_fluctuation", amplitude=0.0)])[0], base)


def test_load_fluctuation_modulates_the_mesh_amplitude_linearly():
    base, _ = revolution()
    x1, angle = revolution([effect_spec("load_fluctuation", amplitude=0.1, order=2)])
    x2, _ = revolution([effect_spec("load_fluctuation", amplitude=0.2, order=2)])
    assert angle is None
    assert sidebands(x1, 25, q=2) > 0.02 and sidebands(base, 25, q=2) < 1e-10
    assert np.abs((x2 - base) - 2 * (x1 - base)).max() < 1e-8 * np.abs(x2 - base).max()  # a load, linear in eps
    assert np.array_equal(revolution([effect_spec("load_fluctuation", amplitude=0.0)])[0], base)


# --- the tooth-shift symmetry (docs/physics.md, Builder) --------------------------------------------------


@pytest.mark.parametrize("name", [n for n, (level, _) in EFFECTS.items() if level != "signal"])
def test_symmetry_breaking_effects_make_tooth_n_differ_from_the_shifted_tooth_1(name):
    effects = [effect_spec(name)]
    n = 7
    tooth1, _ = revolution(effects, faults=[("crack", 1, 12)])
    direct, _ = revolution(effects, faults=[("crack", n, 12)])
    shifted = np.roll(tooth1, (n - 1) * (len(tooth1) // 25))  # what the builder does without effects
    if EFFECTS[name][1]:
        assert rel(shifted, direct) > 1e-4, rel(shifted, direct)  # far above the 1e-10 of an exact shift
    else:
        assert rel(shifted, direct) < 1e-8, rel(shifted, direct)


def test_dataset_with_a_symmetry_breaking_effect_simulates_every_tooth():
    effects = (effect_spec("shaft_eccentricity", e="50 um"),)
    spec = dataset_preset("B-8-ch5").with_(teeth=(1, 9), faults=(("crack", (20,)),), healthy=1, effects=effects)
    ds = build_dataset(spec)
    assert ds.meta["simulations"] == 1 + 2  # healthy once, the crack on each tooth
    for tooth in (1, 9):
        want = simulate_unit(
            SimTask("eight_dof", "meng2020", fs_of(B), 40.0, 20.0, "pinion_y", "crack", 20, (tooth,), effects, tooth)
        )[0]
        row = ds.X[ds.tooth == tooth][0].astype(float) * ds.reference[1] + ds.reference[0]
        assert np.allclose(row, want, rtol=1e-5, atol=1e-4 * rms(want))
    symmetric = spec.with_(effects=(effect_spec("tooth_friction"),))
    assert build_dataset(symmetric).meta["simulations"] == 2  # healthy and the crack, shifted to tooth 9


# --- signal level ----------------------------------------------------------------------------


def context(seed=0, speed=40.0, reference_rms=1.0) -> SignalContext:
    return SignalContext(
        fs=POINTS * speed, speed_hz=speed, t0=123.4, rng=np.random.default_rng(seed), reference_rms=reference_rms
    )


@pytest.fixture(scope="module")
def healthy_row():
    return simulate_unit(SimTask("six_dof", "meng2020", 200e3, 40.0, 20.0, "pinion_y", None, None, (1,)))[0]


@pytest.mark.parametrize("kind", NOISE_KINDS)
def test_sensor_noise_reaches_its_snr_on_every_revolution(kind, healthy_row):
    record = np.broadcast_to(healthy_row, (4, POINTS))
    effect = REG.get("effect", "sensor_noise")
    for snr in (-5.0, 0.0, 20.0):
        noisy = effect.apply_signal(record, effect.resolve({"kind": kind, "snr_db": snr}), context())
        noise = noisy - record
        measured = 10 * np.log10(np.mean(record**2, axis=1) / np.mean(noise**2, axis=1))  # eq. 4.1, 4.2
        assert np.allclose(measured, snr, atol=1e-9)
        assert not np.allclose(noise[0], noise[1])  # fresh noise on every revolution


def test_sensor_bandwidth_is_a_second_order_response_that_attenuates_above_its_cutoff(healthy_row):
    effect = REG.get("effect", "sensor_bandwidth")
    orders, amp = order_spectrum(healthy_row)
    f = orders * 40.0
    present = amp > 1e-6 * amp.max()
    present[-1] = False  # the Nyquist bin of a real record keeps only the real part of H
    for f_n, zeta in ((5e3, 0.707), (3e3, 0.05)):
        out = effect.apply_signal(healthy_row[None, :], effect.resolve({"f_n": f_n, "zeta": zeta}), context())[0]
        _, filtered = order_spectrum(out)
        gain = np.abs(frequency_response(f, f_n, zeta))
        assert np.allclose(filtered[present], gain[present] * amp[present], rtol=1e-8, atol=1e-12 * amp.max())
    # Butterworth at 5 kHz: flat at the 1 kHz mesh frequency, -3 dB at f_n, 1/25 at 5 f_n
    gain = np.abs(frequency_response(np.array([1e3, 5e3, 25e3]), 5e3, 1 / math.sqrt(2)))
    assert gain == pytest.approx([0.9992, 1 / math.sqrt(2), 1 / math.sqrt(1 + 5**4)], rel=1e-3)
    out = effect.apply_signal(healthy_row[None, :], effect.resolve({"f_n": 5e3}), context())[0]
    _, filtered = order_spectrum(out)
    above, below = f >= 20e3, f <= 1e3
    assert np.sum(filtered[above] ** 2) < (1 / 15) ** 2 * np.sum(amp[above] ** 2)  # > 23 dB down from 4 f_n up
    assert np.sum(filtered[below] ** 2) == pytest.approx(np.sum(amp[below] ** 2), rel=0.01)  # the mesh band passes


def test_interference_tone_adds_a_non_synchronous_line_at_its_frequency(healthy_row):
    effect = REG.get("effect", "interference_tone")
    J, order = 8, 2.375  # 95 Hz on a 40 Hz shaft: 19 whole cycles in 8 revolutions
    record = np.broadcast_to(healthy_row, (J, POINTS))
    params = effect.resolve({"frequency": "95 Hz", "ratio": 0.5})
    out = effect.apply_signal(record, params, context(reference_rms=rms(healthy_row)))
    orders, before = order_spectrum(record.reshape(-1), per_revolution=POINTS)
    _, after = order_spectrum(out.reshape(-1), per_revolution=POINTS)
    line = np.argmin(np.abs(orders - order))
    assert after[line] == pytest.approx(math.sqrt(2) * 0.5 * rms(healthy_row), rel=1e-9)
    assert before[line] < 1e-9 * after[line]
    synchronous = orders % 1 == 0
    assert np.allclose(after[synchronous], before[synchronous], atol=1e-9 * after[line])  # left as it was
    later = dataclasses.replace(context(), t0=3.001, reference_rms=rms(healthy_row))
    other = effect.apply_signal(record, params, later)
    assert not np.allclose(other, out)  # another time, another phase
    assert np.array_equal(effect.apply_signal(record, {"frequency": 95.0, "ratio": 0.0}, context()), record)
    with pytest.raises(GearlabInputError, match="above the Nyquist frequency"):
        effect.apply_signal(record, {"frequency": 9e4, "ratio": 0.5}, context())


@pytest.mark.parametrize("frequency, ratio, noise", [(1234.0, 0.3, None), (333.0, 0.1, ("laplace", 0.0))])
def test_the_tone_is_read_off_a_target_for_the_diagnosis_to_start_from(frequency, ratio, noise):
    """The diagnosis's needle: a budgeted search over 1 Hz - 20 kHz misses a tone's line, so the
    effect reads its frequency and level off the target's revolutions (also under 0 dB noise)."""
    tone = (effect_spec("interference_tone", frequency=frequency, ratio=ratio),)
    spec = dataset_preset("B-6-ch5").with_(faults=(), healthy=16, effects=tone, seed=3)
    if noise:
        spec = spec.with_(noise=NoiseSpec(noise[0], noise[1], 7))
    ds = build_dataset(spec)
    revolutions = ds.X.astype(float) * ds.reference[1] + ds.reference[0]
    guesses = REG.get("effect", "interference_tone").guesses(revolutions, 40.0)
    guess = guesses[0]  # the one-revolution guess; the others read the rows as one record
    assert all(g["frequency"] == guesses[1]["frequency"] for g in guesses[1:])
    assert guess["frequency"] == pytest.approx(frequency, rel=0.01)
    assert guess["ratio"] == pytest.approx(ratio, rel=0.4)
    assert REG.get("effect", "tooth_friction").guesses(revolutions, 40.0) == []  # the default: none


def test_tsa_averages_the_non_synchronous_tone_away_in_a_dataset():
    tone = (effect_spec("interference_tone", frequency="33.3 Hz", ratio=1.0),)
    spec = dataset_preset("B-6-ch5").with_(teeth=(1,), faults=(), healthy=3, effects=tone)
    clean = build_dataset(spec.with_(effects=()))
    noisy, averaged = build_dataset(spec), build_dataset(spec.with_(revolutions=32, tsa=True))

    def raw(ds):
        return ds.X.astype(float) * ds.reference[1] + ds.reference[0]

    residual = [rms(raw(ds) - raw(clean)) / rms(raw(clean)) for ds in (noisy, averaged)]
    assert residual[0] == pytest.approx(1.0, rel=0.05)  # the tone's RMS equals the healthy RMS
    assert residual[1] < 0.1  # ... and TSA over 32 revolutions takes it down
    assert not np.allclose(raw(noisy)[0], raw(noisy)[1])  # each sample at its own time
    assert np.array_equal(build_dataset(spec).X, noisy.X)  # deterministic


# --- datasets, cache keys, scenarios ---------------------------------------------------------------


def test_cache_keys_without_effects_are_unchanged_and_effects_are_part_of_the_key():
    for spec in DATASET_PRESETS.values():
        d = dataclasses.asdict(spec)
        for label in ("name", "domain", "effects", "healthy_twin", "unit_shaft"):
            d.pop(label)
        text = json.dumps({"spec": d, "physics": PHYSICS_VERSION}, sort_keys=True)
        assert (
            spec.key() == hashlib.sha256(text.encode()).hexdigest()[:24]
        )  # the key before effects, twins and shaft units
    spec = dataset_preset("B-6-ch5")
    noise = effect_spec("sensor_noise", kind="laplace", snr_db=0)
    with_noise = spec.with_(effects=(noise,))
    assert with_noise.key() != spec.key()
    assert spec.with_(effects=(effect_spec("sensor_noise", kind="laplace", snr_db="0"),)).key() == with_noise.key()
    assert noise == ("sensor_noise", (("kind", "laplace"), ("snr_db", 0.0)))
    # scenario lists are put in the order the effects act in: model, excitation, signal
    listed = effects_from_tables(
        [{"name": "sensor_noise"}, {"name": "drive_inertias"}, {"name": "tooth_friction"}], "here"
    )
    assert [name for name, _ in listed] == ["drive_inertias", "tooth_friction", "sensor_noise"]
    within = effects_from_tables([{"name": "sensor_noise"}, {"name": "sensor_bandwidth"}], "here")
    assert [name for name, _ in within] == ["sensor_noise", "sensor_bandwidth"]  # within a level: as given


SCENARIO = """[scenario]
name = "fx"
kind = "dataset"
description = "effects"

[execution]
workers = 1

[[datasets]]
preset = "B-6-ch5"
name = "B-6-fx"
teeth = [1, 2]
faults = {{ crack = [20] }}
healthy = 2
{effects}
"""


def test_dataset_scenario_with_effects_validates_and_runs(cli, write_scenario, tmp_path, cache, unrendered_figures):
    effects = (
        'effects = [{name = "sensor_noise", kind = "laplace", snr_db = 0}, {name = "drive_inertias"}, '
        '{name = "shaft_eccentricity", e = "10 um"}]'
    )
    path = write_scenario(SCENARIO.format(effects=effects))
    code, out, err = cli("validate", path)
    assert code == 0 and "B-6-fx" in out, err
    code, out, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 0, err
    run = Path(out.strip().splitlines()[-1].split("run directory: ", 1)[1])
    summary = json.loads((run / "summary.json").read_text())["datasets"]["B-6-fx"]
    assert summary["n"] == 4 and summary["counts"] == {"healthy": 2, "crack": 2}
    assert [e[0] for e in summary["spec"]["effects"]] == ["drive_inertias", "shaft_eccentricity", "sensor_noise"]
    assert summary["meta"]["model"] == "eight_dof" and summary["meta"]["simulations"] == 3
    assert (cache / f"{summary['key']}.npz").is_file()


@pytest.mark.parametrize(
    "effects,message",
    [
        ('effects = [{name = "sensor_nose"}]', "unknown effect 'sensor_nose' (did you mean 'sensor_noise'?); known"),
        (
            'effects = [{name = "sensor_noise", snr_db = 200}]',
            "(sensor_noise), parameter 'snr_db': 200 is outside [-20",
        ),
        ('effects = [{name = "shaft_eccentricity", e = "10 Hz"}]', "parameter 'e': '10 Hz' has the wrong dimension"),
        ('effects = [{name = "shaft_eccentricity", e = "1 mm"}]', "parameter 'e': 1000 um is outside [0 um, 200 um]"),
        ('effects = [{name = "sensor_noise", snr = 3}]', "unknown parameter 'snr' (did you mean 'snr_db'?)"),
        ('effects = [{name = "sensor_noise", kind = "pink"}]', "'pink' is not one of gaussian, laplace, student_t"),
        ("effects = [{snr_db = 3}]", "missing 'name'"),
        ('effects = ["sensor_noise"]', "expected a table"),
        ('effects = {name = "sensor_noise"}', "expected a list"),
        ('effects = [{name = "speed_fluctuation", order = 1.5}]', "parameter 'order': expected a whole number"),
    ],
)
def test_bad_effects_in_a_scenario_are_one_line_naming_file_table_and_key(
    cli, write_scenario, tmp_path, effects, message
):
    path = write_scenario(SCENARIO.format(effects=effects))
    for args in (("validate", path), ("run", path, "--out", tmp_path / "runs")):
        code, out, err = cli(*args)
        assert code == 2, (out, err)
        lines = [line for line in err.splitlines() if line.strip()]
        assert len(lines) == 1 and "Traceback" not in err, err
        assert message in lines[0] and str(path) in lines[0] and "[[datasets]] #1" in lines[0], lines[0]
        assert "key 'effects'" in lines[0], lines[0]
    assert not (tmp_path / "runs").exists()


def test_effects_on_a_measured_file_are_refused(cli, write_scenario, tmp_path):
    path = write_scenario(
        '[scenario]\nname = "m"\nkind = "dataset"\n\n[[datasets]]\nfile = "x.csv"\n'
        'vibration = "v"\nspeed = "40 Hz"\neffects = [{name = "sensor_noise"}]\n'
    )
    code, _, err = cli("validate", path)
    assert code == 2 and "key 'effects': effects act on simulations" in err


def test_bad_effects_in_python():
    with pytest.raises(UnknownPluginError, match="unknown effect 'casing'"):
        effect_spec("casing")
    with pytest.raises(GearlabInputError, match="parameter 'amplitude': 0.5 is outside"):
        effect_spec("speed_fluctuation", amplitude=0.5)
    with pytest.raises(GearlabInputError, match="is not \\(name, \\(\\(param, value\\), ...\\)\\)"):
        dataset_preset("B-6-ch5").with_(effects=(("sensor_noise",),)).check()
    with pytest.raises(GearlabInputError, match="dataset 'B-6-ch5': effects #1: unknown effect 'nope'"):
        dataset_preset("B-6-ch5").with_(effects=(("nope", ()),)).check_model()
    with pytest.raises(GearlabInputError, match="has no channel 'casing_y'"):  # the source's sensor is checked first
        dataset_preset("B-6-ch5").with_(channel="casing_y", effects=(effect_spec("casing_path"),)).check_model()
