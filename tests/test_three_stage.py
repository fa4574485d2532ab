"""The three-stage model (plugins/models/two_stage.py, three_stage) on gearbox descriptions of three
stages (issue 39): assembly and modes, statics, the three mesh orders in the casing spectrum (and
in `gearlab inspect`), a chip on the output gear in the output shaft's TSA, the dataset builder,
the gear names of a three-stage train and a detection scenario that validate accepts."""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest
import scipy.linalg
from gearboxes import TWO_HISTORIES_ONE_TEST, description, stage

from gearlab.data.builder import build_dataset
from gearlab.data.placement import parse_fault_key
from gearlab.data.spec import DatasetSpec
from gearlab.dynamics.newmark import Simulator
from gearlab.gearbox import resolve_gearbox
from gearlab.gearbox.simulation import channel, model_name, reference
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry

SPEED, LOAD = 30.0, 40.0
# 19/43 + 23/57 + 29/71: co-prime, the later meshes at 19 x 23/43 and 19 x 23 x 29/(43 x 57) orders
COPRIME = (
    stage(19, 43),
    stage(23, 57, "2.5 mm", "25 mm", ("25 mm", "30 mm")),
    stage(29, 71, "3 mm", "30 mm", ("30 mm", "40 mm")),
)
MESH_ORDERS = (19.0, 19 * 23 / 43, 19 * 23 * 29 / (43 * 57))
# 18/36 + 20/60 + 20/50: the output turns once in 15 input turns, the third mesh at 10/3 orders
WHOLE = (
    stage(18, 36),
    stage(20, 60, "2.5 mm", "25 mm", ("25 mm", "30 mm")),
    stage(20, 50, "3 mm", "30 mm", ("30 mm", "40 mm")),
)
OUTPUT_TURNS = 15
SECONDS = 20  # validate's takes: 40 output turns each, a two-take history's 8 record30 units of that shaft
# their rate: 66 samples an input turn, its tacho pulse 6 of them; what validate says of the takes is the same
# as at 20 kHz, where writing and reading the 1.2 M rows as CSV was 7 s of the test's CPU
TAKE_FS = 2e3


def _box(tmp_path_factory, name, stages, **sensor):
    path = tmp_path_factory.mktemp(name) / f"{name}.toml"
    path.write_text(description(*stages, name=name, speed=f"{SPEED:g} Hz", load=f"{LOAD:g} N*m", **sensor))
    return path


@pytest.fixture(scope="module")
def coprime(tmp_path_factory):
    return _box(tmp_path_factory, "coprime", COPRIME, near="output", direction="y")


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    return _box(tmp_path_factory, "whole", WHOLE, near="intermediate 2", direction="x")


@pytest.fixture(scope="module")
def sim(coprime):
    # 19 x 30 Hz x 280: whole steps per tooth pitch, over 10 per period of the highest mode (15.2 kHz)
    return Simulator(get_registry().get("model", "three_stage"), reference(str(coprime)), 19 * SPEED * 280)


def test_a_three_stage_description_runs_the_three_stage_model(coprime):
    box = resolve_gearbox(str(coprime))
    model = get_registry().get("model", model_name(box))
    assert model.name == "three_stage" and model.stages == 3
    assert model.dofs[7:13] == ("x4", "y4", "theta41", "x3", "y3", "theta31")  # shaft 3's block, then the output
    assert channel(box, model.name, model.channels) == "casing_y"  # the housing carries the sensor
    # without a housing (a model-level effect's subset), the block of the shaft it is near
    no_casing = tuple(c for c in model.channels if not c.startswith("casing"))
    assert channel(box, model.name, no_casing) == "output_y"
    inner = dataclasses.replace(box, sensor=dataclasses.replace(box.sensor, near=box.shafts[2]))
    assert channel(inner, model.name, no_casing) == "shaft3_y"


def test_rigid_rotation_strains_no_mesh_and_the_free_train_has_one_rigid_mode(sim):
    asm = sim.model.assemble(sim.pair, sim.values)
    r = np.array([asm.rigid.get(d, 0.0) for d in asm.dofs])
    assert asm.rigid["theta41"] == pytest.approx(19 * 23 / (43 * 57))
    assert asm.rigid["theta22"] == pytest.approx(19 * 23 * 29 / (43 * 57 * 71))
    assert len(asm.meshes) == 2 and [m.masses for m in asm.meshes] == [("m2", "m4"), ("m4", "m3")]
    for P in (asm.P, *(m.P for m in asm.meshes)):
        assert abs(P @ r) < 1e-15
    np.testing.assert_allclose(asm.Kc @ r, 0.0, atol=1e-9)
    K = asm.Kc + sum(np.outer(p, p) * 3e8 for p in (asm.P, *(m.P for m in asm.meshes)))
    lam = scipy.linalg.eigh(K, asm.M, eigvals_only=True)
    assert abs(lam[0]) < 1e-6 * lam[1] and (lam[1:] > 0).all()


def test_gearlab_modes_of_a_description(cli, coprime):
    code, out, err = cli("modes", "--gearbox", str(coprime), "--json")
    assert code == 0, err
    data = json.loads(out)
    free, fixed = np.array(data["frequencies_hz"]), np.array(data["fixed_input_hz"])
    assert data["model"] == "three_stage" and len(free) == 16 and len(fixed) == 15
    assert np.isfinite(free).all() and abs(free[0]) < 1e-3 and (free[1:] > 10).all() and (fixed > 10).all()
    code, out, err = cli("modes", "--model", "three_stage")
    assert code == 2 and "--model three_stage: no built-in preset; give --gearbox DESCRIPTION" in err


def test_static_mesh_forces_pass_the_load_torque_along_the_train(sim):
    """f1 R_b2 = f2 R_b3, f2 R_b4 = f3 R_b5, f3 R_b6 = T_l at the static equilibrium."""
    F = np.zeros(len(sim.dofs))
    F[sim.load_index] = -LOAD
    K = sim.Kc + sim.k_mean * np.outer(sim.P, sim.P)
    K = K + sum(km * np.outer(P, P) for km, P in zip(sim.mesh_means, sim.mesh_P))
    u = np.linalg.solve(K, F)
    f1 = sim.k_mean * sim.P @ u
    f2, f3 = (km * P @ u for km, P in zip(sim.mesh_means, sim.mesh_P))
    p2, p3 = (m.pair for m in sim.meshes)
    assert f3 * p3.gear.R_b == pytest.approx(LOAD, rel=1e-9)
    assert f2 * p2.gear.R_b == pytest.approx(f3 * p3.pinion.R_b, rel=1e-9)
    assert f1 * sim.pair.gear.R_b == pytest.approx(f2 * p2.pinion.R_b, rel=1e-9)
    # the simulation starts there
    np.testing.assert_allclose(sim._equilibrium(LOAD, sim.k_mean)[1][0], u, rtol=1e-12)


def _spectrum(sim):
    x = sim.run([], SPEED, LOAD, duration=3.0, channels=["casing_y"]).channels["casing_y"]
    x = x[int(sim.fs) :]  # the last 2 s: 60 revolutions, 1/60-order bins
    return np.fft.rfftfreq(len(x), 1 / sim.fs) / SPEED, np.abs(np.fft.rfft(x * np.hanning(len(x))))


def test_the_three_mesh_orders_are_in_the_casing_spectrum(sim, monkeypatch):
    orders, a = _spectrum(sim)
    peaks = []
    for mesh in MESH_ORDERS:
        near = (orders > mesh - 0.5) & (orders < mesh + 0.5)
        peaks.append(np.argmax(np.where(near, a, 0)))
        assert abs(orders[peaks[-1]] - mesh) < 0.05, mesh
        assert a[peaks[-1]] > 20 * np.median(a[near]), mesh
    # the third mesh's line is its stiffness's: held at its mean, the line goes, the first mesh's stays
    series = sim._mesh_series

    def held(i, shaft, per_rev, *faults, **start):
        return np.full(len(shaft), sim.mesh_means[1]) if i == 1 else series(i, shaft, per_rev, *faults, **start)

    monkeypatch.setattr(sim, "_mesh_series", held)
    _, flat = _spectrum(sim)
    assert flat[peaks[2]] < 0.01 * a[peaks[2]] and flat[peaks[0]] > 0.1 * a[peaks[0]]


def test_inspect_finds_the_three_mesh_orders(sim, coprime, tmp_path):
    from gearlab.inspect import InspectOptions, inspect_record

    result = sim.run([], SPEED, LOAD, duration=4.0, channels=["casing_y"])
    keep = result.t >= 1.0
    x = result.channels["casing_y"][keep]  # 90 revolutions with sensor noise at 25 dB (60: see docs/gearbox.md, Limits)
    np.savez(
        tmp_path / "rec.npz",
        acc=x + np.random.default_rng(1).normal(0, x.std() * 10 ** (-25 / 20), x.size),
        tacho=np.where(np.mod(result.tacho[keep], 2 * np.pi) < 0.5, 5.0, 0.0),
        fs=np.array(sim.fs),
    )
    box = resolve_gearbox(str(coprime))
    report = inspect_record(str(tmp_path / "rec.npz"), box, InspectOptions(vibration="acc", tacho="tacho"))
    stages = report["check"]["stages"]
    assert [s["expected_order"] for s in stages] == pytest.approx(list(MESH_ORDERS))
    for s in stages:
        assert s["matched"] and abs(s["measured_order"] - s["expected_order"]) < 0.05, s
    assert report["matches"], report["verdict"]


def test_a_chip_on_the_third_stages_gear_shows_in_the_output_shafts_tsa(whole):
    reg = get_registry()
    fs = 18 * SPEED * 320  # whole steps per input turn (so per output turn), 10 per period of the highest mode
    sim = Simulator(reg.get("model", "three_stage"), reference(str(whole)), fs)
    output = sim.meshes[1].pair  # stage 3: 20T pinion on shaft 3, 50T output gear
    per_output = round(fs / SPEED) * OUTPUT_TURNS

    def tsa(faults):  # the last 4 of 6 output revolutions, averaged in the output shaft's angle
        x = sim.run(faults, SPEED, LOAD, duration=6 * OUTPUT_TURNS / SPEED, channels=["casing_x"]).channels["casing_x"]
        return x[2 * per_output : 6 * per_output].reshape(4, per_output).mean(axis=0)

    healthy = tsa([])
    for tooth in (13, 40):
        diff = tsa([place_fault(reg, output, "chip", tooth, step=20, gear="wheel", stage=3)]) - healthy
        # 1.4 % of the casing's RMS (stages 1 and 2 dominate it), all of it where the chipped tooth
        # meshes: tooth n spans output pitches n - 1 .. n from the shaft's zero, its event ringing
        # down within a few pitches; nowhere else in the output revolution
        assert np.sqrt(np.mean(diff**2)) > 0.005 * np.sqrt(np.mean(healthy**2)), tooth
        sectors = (diff**2).reshape(50, -1).sum(axis=1)
        assert sectors.argmax() == tooth - 1 and sectors[tooth - 2 : tooth + 5].sum() > 0.99 * sectors.sum(), tooth


def test_the_builder_puts_faults_on_the_gears_of_a_three_stage_train(whole):
    ref = reference(str(whole))
    names = {
        "chip@output gear": (3, "wheel"),
        "chip@intermediate 2 pinion": (3, "pinion"),
        "chip@intermediate 2 gear": (2, "wheel"),
    }
    shafts = tuple(resolve_gearbox(str(whole)).shafts)
    assert shafts == ("input", "intermediate 1", "intermediate 2", "output")
    for key, (stage_, gear) in names.items():
        assert parse_fault_key(key, shafts, "here")[1:] == (stage_, gear)
    spec = DatasetSpec(
        name="whole", model="three_stage", preset=ref, channel="casing_x", speed_hz=SPEED, load_nm=LOAD, fs=50e3
    )
    spec = spec.with_(healthy=1, teeth=(2,), faults=(("chip", (20,)), ("chip@s3-wheel", (20,))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 50 kHz: coarse for the highest mode, fine for the test
        data = build_dataset(spec)
    assert data.X.shape == (3, 4096) and np.isfinite(data.X).all()
    assert len({row.tobytes() for row in data.X}) == 3


DETECTION = (
    """[scenario]
name = "three"
kind = "detection"
[source]
gearbox = "{box}"
faults = {{ "{fault}" = [16, 20] }}
healthy = 8
[target]
vibration = "acc_V"
tacho = "tacho_V"
sensitivity = "10 mV/g"
"""
    + TWO_HISTORIES_ONE_TEST
)


def test_validate_takes_a_three_stage_detection_scenario(cli, tmp_path, whole, coprime):
    # takes long enough for a history's units of the output shaft (validate reads their tachos, as the run counts
    # them): 0.1 s takes hold no output turn, which the run refuses
    t = np.arange(int(SECONDS * TAKE_FS)) / TAKE_FS
    for name in ("h1", "h2", "t1"):
        rows = np.column_stack([t, np.sin(2e3 * t), (np.mod(SPEED * t, 1) < 0.1) * 5.0])
        np.savetxt(tmp_path / f"{name}.csv", rows, delimiter=",", header="time_s,acc_V,tacho_V", comments="")
    (tmp_path / "det.toml").write_text(DETECTION.format(box=whole, fault="chip@output gear"))
    code, out, err = cli("validate", str(tmp_path / "det.toml"))
    assert code == 0, err
    assert "methods: matched_filter" in out
    # on the co-prime train the output gear repeats only after 2451 x 71 ... turns: a stretch of steady
    # turns is simulated (tests/test_long_period_trains.py), so it validates too
    (tmp_path / "long.toml").write_text(DETECTION.format(box=coprime, fault="chip@output gear"))
    code, out, err = cli("validate", str(tmp_path / "long.toml"))
    assert code == 0 and "methods: matched_filter" in out, err
