"""Faults on both gears of one pair: the TVMS over the hunting-tooth period (lcm(Z1, Z2) meshes), mesh n
engaging pinion tooth n mod Z1 and wheel tooth n mod Z2, each pair with both its teeth's faulted sections."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearlab.dynamics.newmark import Simulator
from gearlab.errors import GearlabInputError
from gearlab.physics import stiffness
from gearlab.physics.faults import place_fault, place_fault_option
from gearlab.physics.geometry import GearPair
from gearlab.physics.presets import gear_pair
from gearlab.physics.stiffness import MeshStiffnessModel
from gearlab.registry import get_registry

PER_MESH = 32  # grid points per mesh period: cheap, and the same grid in every table compared


def _pair_20_25() -> GearPair:
    return GearPair(
        name="p20_25", Z1=20, Z2=25, module=2e-3, face_width=20e-3, hub_radius=9.76e-3,
        pressure_angle=math.radians(20), E=200e9, nu=0.3,
    )  # fmt: skip


def _singles(model: MeshStiffnessModel, fp, fw):
    """Healthy TVMS over the hunting period and each single fault's change, tiled over that period."""
    pair = model.pair
    L = math.lcm(pair.Z1, pair.Z2)
    hp, hw = model.healthy(pair.Z1 * PER_MESH), model.healthy(pair.Z2 * PER_MESH, "wheel")
    dp = np.tile(model.mesh_stiffness([fp], pair.Z1 * PER_MESH).k - hp, L // pair.Z1)
    dw = np.tile(model.mesh_stiffness([fw], pair.Z2 * PER_MESH).k - hw, L // pair.Z2)
    return model.healthy(L * PER_MESH, "both"), dp, dw


@pytest.mark.parametrize(
    "preset, pinion_tooth, wheel_tooth, shared",
    [
        ("luo2019", 3, 19, [18]),  # 16/48: pinion tooth 3 meets wheel tooth 19 at mesh 18 (0-based) only
        ("luo2019", 3, 5, []),  # 3 and 5 differ mod gcd = 16: they never meet
        ("meng2020", 3, 8, [127]),  # 25/30: 127 = 2 mod 25 = 7 mod 30
        ("meng2020", 3, 5, []),
    ],
)
def test_combined_tvms_is_the_singles_added_except_where_both_faulty_teeth_meet(
    preset, pinion_tooth, wheel_tooth, shared
):
    reg, pair = get_registry(), gear_pair(preset)
    model = MeshStiffnessModel(pair)
    L = math.lcm(pair.Z1, pair.Z2)
    fp = place_fault(reg, pair, "chip", pinion_tooth, step=18)
    fw = place_fault(reg, pair, "crack", wheel_tooth, step=18, gear="wheel")
    both = model.mesh_stiffness([fp, fw], L * PER_MESH)
    assert both.gear == "both" and both.turns == pytest.approx(pair.Z1 / L) and both.k.size == L * PER_MESH
    healthy, dp, dw = _singles(model, fp, fw)
    assert np.abs(healthy - np.tile(model.healthy(pair.Z1 * PER_MESH), L // pair.Z1)).max() < 1e-6 * healthy.max()
    # where the pair of mesh n (0-based) is in contact: n PER_MESH <= j < n PER_MESH + theta_t / pitch
    _, arcs = model._arc(L * PER_MESH, [n + 1 for n in shared], "both")
    meet = arcs.any(axis=0)
    err = np.abs(both.k - (healthy + dp + dw))
    assert err[~meet].max(initial=0.0) < 1e-6 * healthy.max()  # added where the faulty teeth do not meet
    if shared:
        assert err[meet].max() > 1e-3 * healthy.max()  # in series where they meet: not the sum
    # each single change lies on the arcs of the meshes that engage its tooth: pinion tooth i at meshes
    # n = i - 1 mod Z1, wheel tooth j at n = j - 1 mod Z2 (the numbering of each gear's own table)
    for d, tooth, Z in ((dp, pinion_tooth, pair.Z1), (dw, wheel_tooth, pair.Z2)):
        arcs = model._arc(L * PER_MESH, range(tooth, L + 1, Z), "both")[1].any(axis=0)
        assert not d[~arcs].any() and np.abs(d[arcs]).max() > 1e-3 * healthy.max()


@pytest.mark.parametrize(
    "pair, meshes, pinion_turns",
    [(gear_pair("luo2019"), 48, 3), (gear_pair("meng2020"), 150, 6), (_pair_20_25(), 100, 5)],
)
def test_the_period_is_the_hunting_tooth_period(pair, meshes, pinion_turns):
    """16/48: one wheel turn (48 meshes, 3 pinion turns); 20/25: lcm 100 meshes, 5 pinion turns."""
    reg = get_registry()
    faults = [place_fault(reg, pair, "pit", 2, step=15), place_fault(reg, pair, "pit", 4, step=15, gear="wheel")]
    table = MeshStiffnessModel(pair).mesh_stiffness(faults, meshes * 16)
    assert 1 / table.turns == pytest.approx(pinion_turns)
    assert round(pair.Z1 / table.turns) == meshes


def test_cli_syntax_and_the_old_refusal_is_gone():
    reg, pair = get_registry(), gear_pair("phm09_stage1")
    both = [place_fault_option(reg, pair, t, "--fault") for t in ("chip@3=20", "chip@wheel:3=20")]
    assert [f.label for f in both] == ["chip@3", "chip@wheel:3"] and [f.gear for f in both] == ["pinion", "wheel"]
    table = MeshStiffnessModel(pair).mesh_stiffness(both, 96 * 8)  # refused before ("both gears of one pair")
    assert table.gear == "both" and round(1 / table.turns) == 3
    with pytest.raises(GearlabInputError, match=r"wheel tooth number in 1\.\.96, got 97"):
        place_fault_option(reg, pair, "chip@wheel:97=20", "--fault")


def test_a_too_long_period_is_refused_in_one_line(monkeypatch):
    reg, pair = get_registry(), _pair_20_25()
    faults = [place_fault(reg, pair, "chip", 1, step=20), place_fault(reg, pair, "chip", 1, step=20, gear="wheel")]
    monkeypatch.setattr(stiffness, "MAX_HUNTING_TURNS", 4)
    with pytest.raises(GearlabInputError, match=r"^faults chip@1, chip@wheel:1: .* after 100 meshes = 5 pinion turns"):
        MeshStiffnessModel(pair).mesh_stiffness(faults, 100 * 16)
    from gearlab.notebook import simulator

    sim: Simulator = simulator("six_dof", "meng2020")  # 25/30: 6 input revolutions
    faults = [place_fault(reg, sim.pair, "chip", 1, step=20), place_fault(reg, sim.pair, "chip", 2, 20, gear="wheel")]
    monkeypatch.setattr(stiffness, "MAX_HUNTING_TURNS", 5)
    with pytest.raises(GearlabInputError, match=r"on both gears of stage 1 repeat only after 6 input revolutions") as e:
        sim.run(faults, duration=0.01)
    assert "\n" not in str(e.value)


def test_a_simulation_shows_a_pinion_rate_and_a_wheel_rate_train():
    """six_dof meng2020 (25/30 at 40 Hz): a pinion chip every 5000 steps (one pinion turn at 200 kHz) and a
    wheel chip every 6000 (one wheel turn), in the simulated TVMS and in the response."""
    from gearlab.notebook import simulator

    reg = get_registry()
    sim = simulator("six_dof", "meng2020")
    fp = place_fault(reg, sim.pair, "chip", 3, step=20)
    fw = place_fault(reg, sim.pair, "chip", 5, step=20, gear="wheel")  # never meets pinion tooth 3 (gcd 5)
    assert sim.period([fp, fw]) == 6
    runs = {
        key: sim.run(faults, duration=0.15) for key, faults in (("h", []), ("p", [fp]), ("w", [fw]), ("b", [fp, fw]))
    }
    dev = {key: runs[key].tvms - runs["h"].tvms for key in "pwb"}
    assert np.abs(dev["b"] - dev["p"] - dev["w"]).max() < 1e-6 * runs["h"].tvms.max()

    def starts(d: np.ndarray) -> np.ndarray:
        on = np.abs(d) > 1e-3 * runs["h"].tvms.max()
        return np.flatnonzero(on[1:] & ~on[:-1]) + 1

    sp, sw, sb = starts(dev["p"]), starts(dev["w"]), starts(dev["b"])
    assert set(np.diff(sp)) == {5000} and set(np.diff(sw)) == {6000}  # the two rates
    assert len(sp) >= 5 and len(sw) >= 4 and set(sb) == set(sp) | set(sw)  # both trains in one TVMS
    for ch in ("pinion_y", "gear_y"):  # the response differs from either single fault's
        b = runs["b"].channels[ch]
        assert min(np.abs(b - runs[k].channels[ch]).max() for k in "pw") > 1e-3 * np.abs(b).max()


# --- a dataset's class on both gears ---------------------------------------------------------------


def test_a_dataset_class_joins_a_pinion_and_a_wheel_fault():
    from gearlab.data.placement import canonical_faults, shaft_names

    shafts = shaft_names("phm09", 2)
    faults = {"chip@wheel+spall": [20], "chip@idler pinion+chip@output gear": [18]}
    assert canonical_faults(faults, shafts, "[[datasets]]") == (
        ("spall+chip@wheel", (20,)),  # the pinion's first
        ("chip@s2-pinion+chip@s2-wheel", (18,)),
    )
    for bad in ("chip+crack", "chip+chip@s2-wheel", "chip+chip@wheel+pit", "+chip@wheel"):
        with pytest.raises(GearlabInputError, match=r"'\+' joins a fault on a stage's pinion and one on its wheel"):
            canonical_faults({bad: [20]}, shafts, "[[datasets]]")


def test_a_two_gear_class_s_period_and_its_bound(monkeypatch):
    from gearlab.data import placement
    from gearlab.data.spec import dataset_preset

    spec = dataset_preset("phm09-30").with_(faults=(("chip@s2-pinion+chip@s2-wheel", (20,)),), teeth=(2,), healthy=1)
    (on,) = spec.fault_classes().values()
    assert (on.name, on.stage, on.gear, on.mates) == ("chip", 2, "pinion", (("chip", 2, "wheel"),))
    assert on.period == 15  # 48/80 at 1/3 input order: lcm 240 meshes = 5 idler-pinion turns = 15 input turns
    monkeypatch.setattr(placement, "MAX_PERIOD", 10)  # past it: a stretch of steady turns, not the period
    from gearlab.data.builder import stretch_of

    classes = spec.fault_classes()
    assert stretch_of(spec, placement.train_pairs(spec.check_model()[0], spec.preset), classes) == 128


def test_a_two_gear_sample_puts_pinion_tooth_n_with_the_wheel_tooth_n_it_meets(monkeypatch):
    """meng2020 (25/30): pinion tooth n and wheel tooth n (mesh n - 1), one simulation turned by whole
    pitches for tooth 4: the same rows as simulating tooth 4 itself."""
    from gearlab.data import builder
    from gearlab.data.spec import POINTS

    calls, steady = [], builder.steady_response

    def spy(sim, faults, *args, **kw):
        calls.append([f.label for f in faults])
        return steady(sim, faults, *args, **kw)

    monkeypatch.setattr(builder, "steady_response", spy)
    fs = builder.whole_steps_rate(200e3, 40.0, 25)
    task = builder.SimTask("six_dof", "meng2020", fs, 40.0, 20.0, "gear_y", "chip+chip@wheel", 20, (3, 4), (), 3)
    rows = builder.simulate_unit(tuple(task))
    assert calls == [["chip@3", "chip@wheel:3"]] and rows.shape == (2, 6 * POINTS)  # 6 input turns: 150 meshes
    direct = builder.simulate_unit(tuple(task._replace(teeth=(4,), tooth=4)))
    assert calls[-1] == ["chip@4", "chip@wheel:4"]
    assert np.abs(direct[0] - rows[1]).max() < 1e-9 * np.abs(rows[1]).max()


def test_a_simulated_record_with_both_gears_and_the_bound(monkeypatch):
    from gearlab.data import placement
    from gearlab.data.simulated import simulated_record

    both = [{"name": "chip", "tooth": 3, "step": 20}, {"name": "chip", "gear": "idler gear", "tooth": 5, "step": 20}]
    assert simulated_record(both, speed_hz=30.0, load_nm=20.0, revolutions=2, seed=1).period == 3  # 32/96
    stage2 = [{**f, "gear": g} for f, g in zip(both, ("idler pinion", "output gear"))]
    monkeypatch.setattr(placement, "MAX_PERIOD", 10)  # each gear alone: 3 and 5 turns; both: lcm 240 meshes, 15
    rec = simulated_record(stage2, speed_hz=30.0, load_nm=20.0, revolutions=2, seed=1)  # a stretch, not the period
    assert rec.period == 15 and np.isfinite(rec.vibration).all()
    monkeypatch.setattr(stiffness, "MAX_HUNTING_TURNS", 4)  # the bound: the table's own turns (240 meshes / 48)
    with pytest.raises(GearlabInputError, match=r"both gears of stage 2 repeat only after 5 turns of the stage 2 pin"):
        simulated_record(stage2, speed_hz=30.0, load_nm=20.0, revolutions=2, seed=1)


STIFFNESS_SCENARIO = """\
[scenario]
name = "st"
kind = "stiffness"

[stiffness]
pair = "luo2019"
points = 768

[[cases]]
name = "both"
faults = [{ kind = "chip", tooth = 3, step = 18 }, { kind = "crack", tooth = 19, step = 18, gear = "wheel" }]
"""


def test_a_stiffness_scenario_case_on_both_gears(run_scenario):
    """The stiffness kind's `gear` key: the case's table spans the hunting period (48 meshes of 16/48); each
    fault's RFA is its own gear's (the wheel's crack against the wheel tooth, as its ladder is)."""
    import json

    from gearlab.kinds.stiffness import read_csv

    run = run_scenario(STIFFNESS_SCENARIO)
    theta, k = read_csv(run / "cases" / "both.csv")
    reg, pair = get_registry(), gear_pair("luo2019")
    faults = [place_fault(reg, pair, "chip", 3, step=18), place_fault(reg, pair, "crack", 19, step=18, gear="wheel")]
    assert np.allclose(k, MeshStiffnessModel(pair).mesh_stiffness(faults, 768).k, rtol=1e-9)
    (record,) = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines() if '"both"' in line]
    crack = faults[1]
    assert record["faults"][1]["gear"] == "wheel" and "gear" not in record["faults"][0]
    assert record["faults"][1]["rfa"] == pytest.approx(crack.fault.rfa(crack.params, pair.seen_from("wheel")))
