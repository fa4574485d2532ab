"""Faults on any gear: the wheel's tooth in the PEM pair (thesis 2.1, 2.2.5 with the roles of the
gears exchanged), its TVMS over one wheel revolution, and the simulator reading every mesh's table
at the angle of the gear that carries the fault (stage 2 of the PHM 2009 rig included)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearlab.data.builder import steady_response, whole_steps_rate
from gearlab.dynamics.newmark import Simulator
from gearlab.errors import GearlabInputError
from gearlab.physics.faults import place_fault
from gearlab.physics.geometry import GearPair
from gearlab.physics.presets import PAIR_PRESETS, gear_pair
from gearlab.physics.stiffness import MeshStiffnessModel, PlacedFault

PAIRS = ["luo2019", "meng2020", "phm09_stage1", "phm09_stage2"]
CASES = [("crack", 12), ("chip", 20), ("spall", 18), ("pit", 20), ("broken_tip", 16)]


@pytest.fixture(scope="module")
def tables():
    return {name: MeshStiffnessModel(gear_pair(name)) for name in PAIRS}


def swapped(name: str) -> GearPair:
    """The same mesh written with the wheel as gear 1, built from the preset's numbers (not from seen_from)."""
    values = dict(PAIR_PRESETS[name])
    values["Z1"], values["Z2"] = values["Z2"], values["Z1"]
    return GearPair(name=name, **values)


@pytest.mark.parametrize("name", PAIRS)
@pytest.mark.parametrize("kind, step", CASES)
def test_a_wheel_fault_is_the_pinion_fault_of_the_pair_with_the_roles_exchanged(registry, tables, name, kind, step):
    """A tooth pair's compliance is the sum of both teeth's (eq. 2.47, 2.48) at one contact point; which
    gear drives does not enter. Seen from the wheel, the contact that starts at pinion angle phi = 0 ends
    at wheel angle psi = theta_t' = theta_t Z1/Z2 (the path of contact is the same line segment, eq. 2.7,
    2.8), so k_wheel-fault(phi) = k'_pinion-fault(theta_t' - (Z1/Z2) phi) on the swapped pair."""
    pair, model = gear_pair(name), tables[name]
    other = swapped(name)
    assert other.theta_t == pytest.approx(pair.theta_t * pair.Z1 / pair.Z2, rel=1e-12)
    on_wheel = place_fault(registry, pair, kind, 5, step=step, gear="wheel")
    on_other = place_fault(registry, other, kind, 5, step=step)
    assert on_wheel.params == on_other.params  # ladder and checks on the wheel's geometry
    phi = np.linspace(0.0, pair.theta_t, 997, endpoint=False)
    k = model.tooth_pair_stiffness(phi, [on_wheel])
    k_other = MeshStiffnessModel(other).tooth_pair_stiffness(other.theta_t - pair.Z1 / pair.Z2 * phi, [on_other])
    healthy = model.tooth_pair_stiffness(phi)
    assert np.max(np.abs(k - healthy)) > 1e-4 * healthy.max()  # the fault does something
    np.testing.assert_allclose(k, k_other, rtol=1e-9, atol=1e-9 * healthy.max())


def test_the_crack_ladder_breaks_the_wheel_tooth_it_is_given(registry, tables):
    """Step 20 of the crack ladder cuts the whole tooth (2 max h_x): the wheel's, which is thicker than the
    32T pinion's, so the 96T tooth carries nothing over its whole contact."""
    pair, model = gear_pair("phm09_stage1"), tables["phm09_stage1"]
    on_wheel = place_fault(registry, pair, "crack", 7, step=20, gear="wheel")
    on_pinion = place_fault(registry, pair, "crack", 7, step=20)
    assert on_wheel.params["q0"] > on_pinion.params["q0"]
    phi = np.linspace(0.0, pair.theta_t, 301, endpoint=False)
    assert np.all(model.tooth_pair_stiffness(phi, [on_wheel]) == 0.0)
    # the pinion's depth on the wheel leaves the thicker wheel tooth carrying load over part of its contact
    weak = PlacedFault(on_pinion.fault, 7, on_pinion.params, gear="wheel")
    assert (model.tooth_pair_stiffness(phi, [weak]) > 0.0).mean() > 0.3


@pytest.mark.parametrize("name", ["luo2019", "meng2020", "phm09_stage2"])
def test_the_healthy_table_over_a_wheel_revolution_is_the_pinion_revolutions(tables, name):
    pair, model = gear_pair(name), tables[name]
    per_pitch = 64
    pinion = model.mesh_stiffness(points=pair.Z1 * per_pitch)
    wheel = model.mesh_stiffness(points=pair.Z2 * per_pitch)
    assert pinion.gear == wheel.gear == "pinion" and pinion.turns == 1.0
    # healthy: every mesh period alike, so Z2 periods are the Z1-period table's first pitch repeated
    period = pinion.k[:per_pitch]
    np.testing.assert_allclose(model._healthy(pair.Z2 * per_pitch, "wheel")[1], np.tile(period, pair.Z2), rtol=1e-12)
    np.testing.assert_allclose(pinion.k, np.tile(period, pair.Z1), rtol=1e-12)
    assert wheel.k.shape == (pair.Z2 * per_pitch,)


@pytest.mark.parametrize("name", ["luo2019", "phm09_stage1", "phm09_stage2"])
@pytest.mark.parametrize("kind, step", [("crack", 15), ("chip", 20), ("spall", 20)])
def test_a_fault_on_wheel_tooth_n_changes_the_table_only_where_that_tooth_meshes(registry, tables, name, kind, step):
    """Over one wheel revolution (Z2 mesh periods) wheel tooth n is in mesh for
    (n-1) 2 pi/Z2 <= theta_2 < (n-1) 2 pi/Z2 + theta_t Z1/Z2; tooth n's table is tooth 1's turned by n-1 pitches."""
    pair, model = gear_pair(name), tables[name]
    per_pitch = 128
    points = pair.Z2 * per_pitch
    healthy = model._healthy(points, "wheel")[1]
    k1 = model.mesh_stiffness([place_fault(registry, pair, kind, 1, step=step, gear="wheel")], points=points)
    assert k1.gear == "wheel" and k1.turns == pytest.approx(pair.Z1 / pair.Z2)
    for n in (1, 4, pair.Z2):
        kn = model.mesh_stiffness([place_fault(registry, pair, kind, n, step=step, gear="wheel")], points=points).k
        theta2 = 2 * np.pi * np.arange(points) / points
        local = np.mod(theta2 - (n - 1) * 2 * np.pi / pair.Z2, 2 * np.pi)
        inside = local < pair.theta_t * pair.Z1 / pair.Z2 * (1 - 1e-12)
        outside = local > pair.theta_t * pair.Z1 / pair.Z2 * (1 + 1e-12)
        changed = kn != healthy
        assert changed.any() and not changed[outside].any()  # bit for bit outside the tooth's arc
        arc = pair.theta_t * pair.Z1 / pair.Z2
        if kind == "chip":  # the wheel's tip meets the pinion's root first: a tip chip dips at the arc's start
            assert changed[inside & (local < 0.1 * arc)].all() and not changed[inside & (local > 0.5 * arc)].any()
        else:
            assert changed[inside].mean() > 0.5
        np.testing.assert_allclose(kn, np.roll(k1.k, (n - 1) * per_pitch), rtol=1e-9, atol=0)


def test_wrong_placements_are_one_line_input_errors(registry, tables):
    pair, model = gear_pair("phm09_stage1"), tables["phm09_stage1"]
    with pytest.raises(GearlabInputError, match=r"wheel tooth number in 1\.\.96, got 97"):
        place_fault(registry, pair, "chip", 97, step=20, gear="wheel")
    assert place_fault(registry, pair, "chip", 96, step=20, gear="wheel").tooth == 96
    with pytest.raises(GearlabInputError, match="gear must be one of pinion, wheel"):
        place_fault(registry, pair, "chip", 3, step=20, gear="rim")
    both = [place_fault(registry, pair, "chip", 3, step=20, gear=gear) for gear in ("pinion", "wheel")]
    assert model.mesh_stiffness(both).gear == "both"  # the hunting-tooth period: tests/test_both_gears.py
    assert [f.label for f in both] == ["chip@3", "chip@wheel:3"]


# --- the simulator ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def ten_dof(registry):
    return Simulator(registry.get("model", "ten_dof"), "luo2019", whole_steps_rate(200e3, 25.0, 16))


def test_the_wheel_table_is_read_at_the_wheels_angle(registry, ten_dof):
    """k(t) with a crack on wheel tooth n differs from the healthy k(t) exactly while that tooth meshes:
    wheel angle theta_2 = (Z1/Z2) 2 pi f t in its arc, once every Z2/Z1 = 3 input revolutions."""
    sim, speed = ten_dof, 25.0
    pair = sim.pair
    n = 10
    crack = place_fault(registry, pair, "crack", n, step=15, gear="wheel")
    assert sim.period([crack]) == 3 and sim.period([]) == 1
    duration = 6.5 / speed
    k = sim.run([crack], speed, 7.0, duration=duration, channels=["casing_x"]).tvms
    k0 = sim.run([], speed, 7.0, duration=duration, channels=["casing_x"]).tvms
    per_turn = round(sim.fs / speed * pair.Z2 / pair.Z1)  # steps per wheel revolution (whole here)
    local = 2 * np.pi * np.mod(np.arange(len(k)) - (n - 1) * per_turn // pair.Z2, per_turn) / per_turn
    arc = pair.theta_t * pair.Z1 / pair.Z2
    changed = np.abs(k - k0) > 1e-9 * k0.mean()  # the wheel table sums its Z2 rows: rounding apart, healthy
    assert not changed[local > arc * (1 + 1e-9)].any()
    assert changed[local < arc * (1 - 1e-9)].mean() > 0.5
    # off the nominal grid (the table interpolated at the wheel's angle) the same picture, to one grid step
    off = speed * 1.0137
    k_off = sim.run([crack], off, 7.0, duration=duration, channels=["casing_x"]).tvms
    k0_off = sim.run([], off, 7.0, duration=duration, channels=["casing_x"]).tvms
    t = np.arange(len(k)) / sim.fs
    local = np.mod(pair.Z1 / pair.Z2 * 2 * np.pi * off * t - (n - 1) * 2 * np.pi / pair.Z2, 2 * np.pi)
    step = 2 * np.pi / sim._grid(pair, [crack])
    changed = np.abs(k_off - k0_off) > 1e-9 * k0.mean()
    assert not changed[(local > arc + step) & (local < 2 * np.pi - step)].any()
    assert changed[local < arc - step].mean() > 0.5


def test_a_stage_the_model_lacks_is_refused(registry, ten_dof):
    chip = place_fault(registry, ten_dof.pair, "chip", 3, step=20, gear="wheel", stage=2)
    with pytest.raises(GearlabInputError, match=r"chip@s2-wheel:3 sits on stage 2; the model has stage\(s\) 1\.\.1"):
        ten_dof.run([chip], duration=0.01)


@pytest.fixture(scope="module")
def rig(registry):
    return Simulator(registry.get("model", "two_stage"), "phm09", whole_steps_rate(66666.67, 30.0, 32))


@pytest.mark.parametrize("stage, gear, period", [(1, "pinion", 1), (1, "wheel", 3), (2, "pinion", 3), (2, "wheel", 5)])
def test_each_gear_of_the_rig_repeats_its_damage_once_per_turn_of_its_shaft(registry, rig, stage, gear, period):
    """A chip on the 32T input pinion, the 96T idler gear, the 48T idler pinion or the 80T output gear:
    the steady response repeats after 1, 3, 3, 5 input revolutions, and what the chip adds to it sits on
    the comb of its shaft's order (1, 1/3, 1/3, 1/5), not on the input shaft's alone."""
    speed, load = 30.0, 20.0
    pair = rig.pair if stage == 1 else rig.meshes[0].pair
    chip = place_fault(registry, pair, "chip", 5, step=20, gear=gear, stage=stage)
    assert rig.period([chip]) == period
    per_rev = int(round(rig.fs / speed))
    x, _ = steady_response(rig, [chip], speed, load, "casing_x")
    assert len(x) == period * per_rev
    healthy, _ = steady_response(rig, [], speed, load, "casing_x")
    change = x - np.tile(healthy, period)
    assert np.sqrt(np.mean(change**2)) > 1e-3 * np.sqrt(np.mean(healthy**2))
    power = np.abs(np.fft.rfft(change)) ** 2  # bin b: order b / period
    off_shaft = power[np.arange(len(power)) % period != 0].sum() / power.sum()
    if period == 1:
        assert off_shaft == 0.0
    else:  # most of the change is on the sub-orders of the slower shaft
        assert off_shaft > 0.5


def test_a_stage_2_fault_leaves_stage_1_healthy(registry, rig):
    chip = place_fault(registry, rig.meshes[0].pair, "chip", 5, step=20, gear="wheel", stage=2)
    faulted = rig.run([chip], 30.0, 20.0, duration=0.05, channels=["casing_x"])
    healthy = rig.run([], 30.0, 20.0, duration=0.05, channels=["casing_x"])
    np.testing.assert_array_equal(faulted.tvms, healthy.tvms)  # stage 1's k(t)
    assert not np.array_equal(faulted.channels["casing_x"], healthy.channels["casing_x"])
    assert math.isclose(rig.gear_turns(2, "wheel"), 0.2, rel_tol=1e-12)
