"""The two-stage model of the PHM 2009 rig (plugins/models/two_stage.py): assembly and modes,
statics, the second mesh at 16x input order, the rank-m Newmark step, and a chipped 32T tooth.

Simulations run at the rig's own rate (66 666.67 Hz rounded up to whole steps per tooth pitch),
so a steady input revolution is a whole number of steps and orders sit on spectral bins."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from gearlab.data.builder import build_dataset, steady_revolution, whole_steps_rate
from gearlab.data.spec import PHM09_FS, dataset_preset
from gearlab.dynamics.newmark import Simulator, _integrate, _integrate_meshes
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry

SPEED, LOAD = 30.0, 20.0


@pytest.fixture(scope="module")
def model():
    return get_registry().get("model", "two_stage")


@pytest.fixture(scope="module")
def sim(model):
    return Simulator(model, "phm09", whole_steps_rate(PHM09_FS, SPEED, 32))


@pytest.fixture(scope="module")
def healthy(sim):
    return steady_revolution(sim, [], SPEED, LOAD, "casing_x")


def amplitudes(rev):
    return np.abs(np.fft.rfft(rev)) * 2 / len(rev)


def test_rigid_rotation_strains_neither_mesh_nor_coupling(model):
    pair, values = model.resolve("phm09")
    asm = model.assemble(pair, values)
    r = np.array([asm.rigid.get(d, 0.0) for d in asm.dofs])
    assert asm.rigid["theta21"] == pytest.approx(1 / 3) and asm.rigid["theta22"] == pytest.approx(1 / 5)
    assert abs(asm.P @ r) < 1e-15 and abs(asm.meshes[0].P @ r) < 1e-15
    np.testing.assert_allclose(asm.Kc @ r, 0.0, atol=1e-9)
    # free input: exactly one rigid-body mode, every other frequency positive
    K = asm.Kc + sum(np.outer(p, p) * 1.6e8 for p in (asm.P, asm.meshes[0].P))
    lam = scipy.linalg.eigh(K, asm.M, eigvals_only=True)
    assert abs(lam[0]) < 1e-6 * lam[1] and (lam[1:] > 0).all()


def test_natural_frequencies_of_the_rig(sim):
    f = sim.natural_frequencies()
    assert len(f) == 12 and (f > 50).all()
    # the highest mode stays resolved at the records' rate (>= 10 steps per period)
    assert f.max() < sim.fs / 10
    # the second mesh stiffens the idler: removing it lowers (never raises) every frequency
    K = sim.Kc + sim.k_mean * np.outer(sim.P, sim.P)
    without = np.sqrt(np.clip(scipy.linalg.eigh(K, sim.M, eigvals_only=True), 0, None)) / (2 * np.pi)
    assert (without <= f * (1 + 1e-9)).all() and (without < f * 0.99).any()


def test_static_mesh_forces_balance_the_load_torque(sim):
    """At the static equilibrium the stage-2 force carries T_l at the output's base radius and the
    idler passes it on: f1 R_b2 = f2 R_b3, f2 R_b4 = T_l."""
    F = np.zeros(len(sim.dofs))
    F[sim.load_index] = -LOAD
    K = sim.Kc + sim.k_mean * np.outer(sim.P, sim.P) + sim.mesh_means[0] * np.outer(sim.mesh_P[0], sim.mesh_P[0])
    u = np.linalg.solve(K, F)
    f1, f2 = sim.k_mean * sim.P @ u, sim.mesh_means[0] * sim.mesh_P[0] @ u
    pair2 = sim.meshes[0].pair
    assert f2 * pair2.gear.R_b == pytest.approx(LOAD, rel=1e-9)
    assert f1 * sim.pair.gear.R_b == pytest.approx(f2 * pair2.pinion.R_b, rel=1e-9)


def test_both_mesh_orders_are_in_the_casing_spectrum(healthy):
    a = amplitudes(healthy)
    floor = np.median(a[1:200])
    for order in (16, 32, 48, 64):
        assert a[order] > 100 * floor, order
    assert a[16] > 10 * max(a[15], a[17]) and a[32] > 10 * max(a[31], a[33])


def test_the_16x_order_comes_from_the_second_mesh(sim, healthy, monkeypatch):
    """With a constant stage-2 stiffness (its mean) the odd multiples of 16 vanish; the 32T mesh stays."""
    monkeypatch.setattr(sim, "_mesh_series", lambda i, shaft, per_rev, start=0: np.full(len(shaft), sim.mesh_means[i]))
    flat = amplitudes(steady_revolution(sim, [], SPEED, LOAD, "casing_x"))
    a = amplitudes(healthy)
    assert flat[16] < 1e-6 * a[16] and flat[48] < 1e-6 * a[48]
    assert flat[32] > 0.1 * a[32]


def test_rank_m_step_reduces_to_the_single_mesh_step():
    """The Woodbury step with one mesh is the Sherman-Morrison step of the one-pair models."""
    one = Simulator(get_registry().get("model", "ten_dof"), "luo2019", 200e3)
    n, steps = len(one.dofs), 3000
    k = one.stiffness.mesh_stiffness(points=steps).k
    F = np.zeros(n)
    F[one.load_index] = -7.0
    idx = np.arange(n, dtype=np.int64)
    outs = []
    for multi in (False, True):
        u, v, a = np.linalg.solve(one.Kc + one.k_mean * np.outer(one.P, one.P), F), np.zeros(n), np.zeros(n)
        out = np.empty((steps + 1, n))
        # the load without a time-varying part, then the Newmark constants, step, state and output
        loaded = (one.GMC, one.G @ F, np.zeros((n, 0)), np.zeros((steps, 0)))
        state = (one.c, 1 / one.fs, one.gamma, u, v, a, idx, out)
        if multi:
            W = one.G @ one.P[:, None]
            _integrate_meshes(
                *loaded, W, one.P[None, :], one.P[None, :] @ W, k[:, None].copy(), np.array([one.mu]), *state
            )
        else:
            _integrate(*loaded, one.w, one.P, one.pw, k, one.mu, *state)
        outs.append(out)
    np.testing.assert_allclose(outs[1], outs[0], rtol=1e-9, atol=1e-9 * np.abs(outs[0]).max())


def test_a_chip_changes_the_response_once_per_revolution_at_its_tooth(sim, healthy):
    chip = place_fault(get_registry(), sim.pair, "chip", 1, step=20)
    chipped = steady_revolution(sim, [chip], SPEED, LOAD, "casing_x")
    diff = chipped - healthy
    assert np.sqrt(np.mean(diff**2)) > 0.01 * np.sqrt(np.mean(healthy**2))
    # the change is where tooth 1 meshes (its arc: the first 1.76 pitches of the revolution),
    # ringing down within a few pitches, and nowhere else in the revolution
    sectors = (diff**2).reshape(32, -1).sum(axis=1)
    assert sectors.argmax() <= 2 and sectors[:6].sum() > 0.9 * sectors.sum()


def test_rig_dataset_presets():
    for speed in (30, 40):
        spec = dataset_preset(f"phm09-{speed}")
        model, pair, teeth = spec.check_model()
        assert (model.name, pair.Z1, pair.Z2, spec.channel, spec.speed_hz) == ("two_stage", 32, 96, "casing_x", speed)
        assert len(teeth) == 32 and spec.faults[0][0] == "chip"


@pytest.mark.parametrize("speed", [35.0, 45.0, 50.0])
def test_the_rig_builds_at_the_other_speeds_of_the_records(speed):
    """The PHM 2009 rig ran at 30-50 Hz; at 35 Hz a revolution is 1920 steps, where 2 pi n / n
    once rounded below a whole turn and the resampling found no complete revolution."""
    spec = dataset_preset("phm09-30").with_(speed_hz=speed, teeth=(1,), faults=(("chip", (20,)),), healthy=1)
    data = build_dataset(spec)
    assert data.X.shape == (2, 4096) and np.isfinite(data.X).all()
