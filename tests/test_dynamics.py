"""Lumped gearbox dynamics (thesis 2.3, 2.4.1, 2.4.2; docs/physics.md): assembly, modes,
the thesis' claims about the simulated signals, and the engineering requirements on the
Newmark integrator (rank-one update, divergence, step checks, bad input).

Every simulation here is short (well under a second of simulated time); the builder's
whole-steps rate makes one input-shaft revolution a whole number of integration steps, so
revolutions can be cut by reshaping and spectra have the mesh harmonics on their bins.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import scipy.linalg
from thesis_tables import PAIR_2_3, PAIR_2_4, TABLE_2_3, TABLE_2_4

from gearlab.data.builder import (
    STEADY_RTOL,
    _simulator,
    angle_samples,
    simulate_unit,
    steady_revolution,
    whole_steps_rate,
)
from gearlab.dynamics.model import CHANNEL_DOFS, DOF_ORDER, lumped_assembly
from gearlab.dynamics.newmark import BETA1, BETA2, TVMS_POINTS, SimulationError, Simulator
from gearlab.errors import GearlabInputError
from gearlab.physics.faults import place_fault
from gearlab.physics.stiffness import MeshStiffness
from gearlab.registry import get_registry
from gearlab.signals import (
    cut_revolutions,
    order_spectrum,
    revolution_starts,
    spectrum,
    steady_start,
    unwrap_tacho,
)

REG = get_registry()
FS = 200e3

# The three models on their thesis operating points: Dataset A (Table 2.3; 25.2 Hz, 7 N*m,
# also 8.1 Hz in Figures 2.26, 2.28, 2.36) and Dataset B (Table 2.4; 40 Hz, 20 N*m).
MODELS = {
    "ten_dof": dict(preset="luo2019", speed=25.2, load=7.0, channel="casing_x", Z1=16),
    "eight_dof": dict(preset="meng2020", speed=40.0, load=20.0, channel="pinion_y", Z1=25),
    "six_dof": dict(preset="meng2020", speed=40.0, load=20.0, channel="pinion_y", Z1=25),
}


def model(name):
    return REG.get("model", name)


def sim_at(name: str, speed: float):
    """The builder's (cached) simulator of *name* at the whole-steps rate for *speed*."""
    m = MODELS[name]
    return _simulator(name, m["preset"], whole_steps_rate(FS, speed, m["Z1"]))


def rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def rel(a, b) -> float:
    """Relative difference ||a - b|| / ||b||."""
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)) / np.linalg.norm(b))


# --- the thesis' matrices, written out independently of the code (tables: thesis_tables.py) ---

ALPHA0 = math.radians(20.0)


def thesis_matrices(t: dict, dofs: tuple[str, ...]):
    """M (eq. 2.97), Kc (eq. 2.100), Cc (eq. 2.101) and P (eq. 2.104) of the 10-DOF model,
    written entry by entry, restricted to *dofs* (a DOF left out is held at zero)."""
    Rb1 = t["module"] * t["Z1"] * math.cos(ALPHA0) / 2
    Rb2 = t["module"] * t["Z2"] * math.cos(ALPHA0) / 2
    mf = t.get("mf", 0.0)
    M = np.diag([t["m1"], t["m1"], t["I11"], t["I12"], t["m2"], t["m2"], t["I21"], t["I22"], mf, mf])

    def constant(kb, kc, kxf, kyf):
        K = np.zeros((10, 10))
        # rows x1, y1, x2, y2 against the casing xf, yf (eq. 2.100 rows 1, 2, 5, 6, 9, 10)
        for a, f in ((0, 8), (1, 9), (4, 8), (5, 9)):
            K[a, a] = kb
            K[a, f] = K[f, a] = -kb
        K[8, 8] = kxf + 2 * kb
        K[9, 9] = kyf + 2 * kb
        # couplings motor-pinion (theta11-theta12) and gear-load (theta21-theta22)
        for a, b in ((2, 3), (6, 7)):
            K[a, a] = K[b, b] = kc
            K[a, b] = K[b, a] = -kc
        return K

    has_motor = "theta11" in dofs
    Kc = constant(t["k_b"], t["k_c"] if has_motor else 0.0, t.get("k_xf", 0.0), t.get("k_yf", 0.0))
    Cc = constant(t["c_b"], t["c_c"] if has_motor else 0.0, t.get("c_xf", 0.0), t.get("c_yf", 0.0))
    P = np.array(
        [math.sin(ALPHA0), math.cos(ALPHA0), 0.0, Rb1, -math.sin(ALPHA0), -math.cos(ALPHA0), -Rb2, 0.0, 0.0, 0.0]
    )
    keep = [DOF_ORDER.index(d) for d in dofs]
    sub = np.ix_(keep, keep)
    return M[sub], Kc[sub], Cc[sub], P[keep]


# the thesis tables with their gear pairs (zeta, the mesh damping, plays no part in these matrices)
TABLES = {
    "ten_dof": {**TABLE_2_3, **PAIR_2_3},
    "eight_dof": {**TABLE_2_4, **PAIR_2_4},
    "six_dof": {**TABLE_2_4, **PAIR_2_4},
}
EXPECTED_DOFS = {
    "ten_dof": DOF_ORDER,
    "eight_dof": DOF_ORDER[:8],
    "six_dof": ("x1", "y1", "theta12", "x2", "y2", "theta21"),
}


# --- assembly ------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(MODELS))
def test_assembly_matrices_properties_and_projection(name):
    m = model(name)
    pair, values = m.resolve(MODELS[name]["preset"])
    asm = m.assemble(pair, values)
    assert asm.dofs == EXPECTED_DOFS[name]
    M, Kc, Cc, P = asm.M, asm.Kc, asm.Cc, asm.P
    n = len(asm.dofs)
    assert M.shape == Kc.shape == Cc.shape == (n, n) and P.shape == (n,)
    # M symmetric positive definite; Kc, Cc symmetric positive semi-definite
    assert np.array_equal(M, M.T) and np.linalg.eigvalsh(M).min() > 0
    for A in (Kc, Cc):
        assert np.array_equal(A, A.T)
        ev = np.linalg.eigvalsh(A)
        assert ev.min() >= -1e-12 * ev.max()
    # M, Kc, Cc and P are exactly those of the thesis' tables and eq. 2.97/2.100/2.101/2.104
    tM, tK, tC, tP = thesis_matrices(TABLES[name], asm.dofs)
    np.testing.assert_allclose(M, tM, rtol=1e-12)
    np.testing.assert_allclose(Kc, tK, rtol=1e-12, atol=0)
    np.testing.assert_allclose(Cc, tC, rtol=1e-12, atol=0)
    np.testing.assert_allclose(P, tP, rtol=1e-12, atol=1e-15)
    # P in the DOF order of eq. 2.96: x1, y1, th11, th12, x2, y2, th21, th22, xf, yf
    full = dict(
        x1=math.sin(ALPHA0),
        y1=math.cos(ALPHA0),
        theta11=0.0,
        theta12=pair.pinion.R_b,
        x2=-math.sin(ALPHA0),
        y2=-math.cos(ALPHA0),
        theta21=-pair.gear.R_b,
        theta22=0.0,
        xf=0.0,
        yf=0.0,
    )
    assert P.tolist() == pytest.approx([full[d] for d in asm.dofs], rel=1e-15, abs=0)
    assert asm.input_dof == ("theta12" if name == "six_dof" else "theta11")
    assert asm.load_dof == ("theta21" if name == "six_dof" else "theta22")


@pytest.mark.parametrize("name", list(MODELS))
def test_rigid_rotation_gives_no_mesh_deflection(name):
    """Pinion and gear turning together (R_b1 theta12 = R_b2 theta21) do not compress the mesh."""
    m = model(name)
    pair, values = m.resolve(MODELS[name]["preset"])
    asm = m.assemble(pair, values)
    u = np.zeros(len(asm.dofs))
    for dof, angle in (
        ("theta11", 1 / pair.pinion.R_b),
        ("theta12", 1 / pair.pinion.R_b),
        ("theta21", 1 / pair.gear.R_b),
        ("theta22", 1 / pair.gear.R_b),
    ):
        if dof in asm.dofs:
            u[asm.index(dof)] = angle
    assert pair.pinion.R_b * u[asm.index("theta12")] == pytest.approx(pair.gear.R_b * u[asm.index("theta21")])
    assert abs(asm.P @ u) < 1e-12
    # ... and the whole model turning rigidly is a zero-stiffness, zero-damping motion
    k = 3e8
    for A in (asm.Kc + k * np.outer(asm.P, asm.P), asm.Cc):
        assert np.abs(A @ u).max() < 1e-12 * np.abs(A).max()
    # a pinion rotation alone does compress it, by R_b1 per radian
    v = np.zeros(len(asm.dofs))
    v[asm.index("theta12")] = 1.0
    assert asm.P @ v == pytest.approx(pair.pinion.R_b)


def test_removing_the_casing_grounds_the_bearings():
    ten, eight = model("ten_dof"), model("eight_dof")
    pair, values = ten.resolve("luo2019")
    full = ten.assemble(pair, values)
    i_x1, i_xf = full.index("x1"), full.index("xf")
    assert full.Kc[i_x1, i_xf] == -values["k_b"]
    assert full.Kc[i_xf, i_xf] == pytest.approx(values["k_xf"] + 2 * values["k_b"])
    # the same parameters without the casing: each bearing becomes a spring to ground
    no_casing = lumped_assembly(DOF_ORDER[:8], pair, values, "theta11", "theta22")
    np.testing.assert_array_equal(no_casing.Kc, full.Kc[:8, :8])
    np.testing.assert_array_equal(no_casing.Cc, full.Cc[:8, :8])
    # the eight-DOF plugin, Table 2.4: x1 sees k_b to ground and nothing else
    pair8, values8 = eight.resolve("meng2020")
    asm = eight.assemble(pair8, values8)
    i = asm.index("x1")
    assert asm.Kc[i, i] == values8["k_b"] == 6.56e8
    assert asm.Cc[i, i] == values8["c_b"] == 1.8e3
    assert np.count_nonzero(asm.Kc[i]) == 1
    assert "casing_x" not in eight.channels and "casing_x" in ten.channels


# --- natural frequencies -----------------------------------------------------------------


def independent_frequencies(name: str, k: float, fixed_input: bool) -> np.ndarray:
    dofs = EXPECTED_DOFS[name]
    M, Kc, _, P = thesis_matrices(TABLES[name], dofs)
    K = Kc + k * np.outer(P, P)
    if fixed_input:
        keep = [i for i, d in enumerate(dofs) if d != ("theta12" if name == "six_dof" else "theta11")]
        M, K = M[np.ix_(keep, keep)], K[np.ix_(keep, keep)]
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)
    assert np.all(np.isreal(lam))
    assert lam.min() >= -1e-9 * lam.max()  # K is positive semi-definite: no negative eigenvalue
    return np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)


@pytest.mark.parametrize("name", list(MODELS))
def test_natural_frequencies_match_an_independent_eigen_solve(name):
    sim = Simulator(model(name), MODELS[name]["preset"])
    assert 1e8 < sim.k_mean < 1e9
    for fixed in (False, True):
        got = sim.natural_frequencies(fixed_input=fixed)
        want = independent_frequencies(name, sim.k_mean, fixed)
        assert got.shape == want.shape == (len(EXPECTED_DOFS[name]) - fixed,)
        assert np.all(np.isfinite(got)) and np.all(got >= 0) and np.all(np.diff(got) >= 0)
        # the free model turns rigidly: exactly one ~0 Hz mode; the fixed-input model has none
        rigid = got < 1e-3
        assert rigid.sum() == (0 if fixed else 1), got
        np.testing.assert_allclose(got[~rigid], want[~rigid], rtol=1e-6)
        assert np.all(want[rigid] < 1e-3)
    # at another stiffness as well
    np.testing.assert_allclose(sim.natural_frequencies(k=2e8), independent_frequencies(name, 2e8, True), rtol=1e-6)


@pytest.mark.parametrize("name", list(MODELS))
def test_mesh_damping_follows_eq_2_107_to_2_109(name):
    sim = Simulator(model(name), MODELS[name]["preset"])
    t = TABLES[name]
    c_m = 2 * 0.07 * math.sqrt(sim.k_mean * t["m1"] * t["m2"] / (t["m1"] + t["m2"]))  # eq. 2.107, zeta = 0.07
    assert sim.mu == pytest.approx(c_m / sim.k_mean, rel=1e-12)  # eq. 2.109
    healthy = sim.stiffness.mesh_stiffness(points=TVMS_POINTS)
    assert sim.k_mean == pytest.approx(healthy.k.mean(), rel=1e-12)  # k_m: the mean over a meshing cycle


def test_free_ten_dof_has_one_rigid_body_mode():
    sim = Simulator(model("ten_dof"), "luo2019")
    f = sim.natural_frequencies(fixed_input=False)
    assert len(f) == 10
    assert f[0] < 1e-3 and f[1] > 10.0, f


# --- mesh frequency and spectra (Figures 2.36, 2.39) ------------------------------------

SPECTRUM_CASES = [
    ("ten_dof", 8.1, 7.0, "casing_x", 129.6),  # Dataset A, f_p1: n x 129.6 Hz
    ("ten_dof", 8.1, 7.0, "pinion_x", 129.6),
    ("six_dof", 40.0, 20.0, "pinion_y", 1000.0),  # Dataset B: n x 1000 Hz
    ("eight_dof", 40.0, 20.0, "pinion_y", 1000.0),
]


@pytest.mark.parametrize("name,speed,load,channel,mesh_hz", SPECTRUM_CASES)
def test_spectral_peaks_sit_on_mesh_harmonics(name, speed, load, channel, mesh_hz):
    sim = sim_at(name, speed)
    assert speed * sim.pair.Z1 == pytest.approx(mesh_hz, rel=1e-12)
    res = sim.run([], speed, load, duration=5 / speed, channels=[channel])
    x = res.channels[channel]
    cut = cut_revolutions(x, res.fs, tacho=res.tacho, rtol=STEADY_RTOL)  # transient detected, then dropped
    starts = revolution_starts(unwrap_tacho(res.tacho))
    first, last = starts[cut.first_steady], starts[cut.complete]
    assert first / res.fs < 0.25  # the transient dies out within the first quarter second
    steady = x[int(round(first)) : int(round(last))]  # whole steady revolutions
    freq, amp = spectrum(steady, res.fs)
    df = freq[1]
    peaks = np.flatnonzero((amp[1:-1] > amp[:-2]) & (amp[1:-1] >= amp[2:])) + 1
    top = peaks[np.argsort(amp[peaks])[::-1][:10]]
    harmonic = np.round(freq[top] / mesh_hz)
    assert np.all(harmonic >= 1), freq[top]
    assert np.all(np.abs(freq[top] - harmonic * mesh_hz) <= df * (1 + 1e-9)), (freq[top], mesh_hz)
    # and nothing off the harmonics (and their Hann main lobes, +-1 bin) comes near the strongest one
    on = np.abs(freq - np.round(freq / mesh_hz) * mesh_hz) <= 1.5 * df
    assert amp[~on & (freq > 0)].max() < 1e-3 * amp.max()


@pytest.mark.parametrize("name", list(MODELS))
def test_order_spectrum_of_a_steady_revolution_is_at_multiples_of_z1(name):
    m = MODELS[name]
    sim = sim_at(name, m["speed"])
    Z1 = sim.pair.Z1
    rev = steady_revolution(sim, [], m["speed"], m["load"], m["channel"])  # whole steps per tooth
    for samples, tol in ((rev, 1e-12), (angle_samples(rev), 1e-2)):  # time samples; resampled to 4096
        orders, amp = order_spectrum(samples)
        ac = orders > 0
        off = ac & (np.round(orders) % Z1 != 0)
        fraction = np.sum(amp[off] ** 2) / np.sum(amp[ac] ** 2)
        assert fraction < tol, (len(samples), fraction)
        assert orders[np.argmax(np.where(ac, amp, 0))] % Z1 == 0


# --- measurement location (Figure 2.28) and model fidelity (Figure 2.30) -----------------


@pytest.mark.parametrize("speed", [8.1, 25.2])
def test_casing_vibrates_much_less_than_the_pinion(speed):
    sim = sim_at("ten_dof", speed)
    pinion = steady_revolution(sim, [], speed, 7.0, "pinion_x")
    casing = steady_revolution(sim, [], speed, 7.0, "casing_x")
    assert rms(casing) < 0.2 * rms(pinion), (rms(casing), rms(pinion))


@pytest.mark.parametrize("load", [10.0, 20.0, 30.0])
def test_eight_dof_pinion_y_is_lower_than_six_dof(load):
    six = steady_revolution(sim_at("six_dof", 40.0), [], 40.0, load, "pinion_y")
    eight = steady_revolution(sim_at("eight_dof", 40.0), [], 40.0, load, "pinion_y")
    assert rms(eight) < rms(six), (rms(eight), rms(six))


def state_space(sim):
    """First-order matrix of the model as simulated (input shaft fixed) at the mean mesh
    stiffness and the mean mesh damping mu * k_mean (eq. 2.107-2.109)."""
    PP = np.outer(sim.P, sim.P)
    K = sim.Kc + sim.k_mean * PP
    C = sim.Cc + sim.mu * sim.k_mean * PP
    n = len(sim.dofs)
    Minv = np.linalg.inv(sim.M)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])


def impulse_settling_time(sim, dof: str = "y1", level: float = 0.01, dt: float = 5e-6, steps: int = 4000) -> float:
    """Time for the envelope of the free y1 response to a unit velocity impulse on y1 to
    fall below *level* of its peak, from the exact discrete propagator expm(A dt)."""
    A = state_space(sim)
    n = len(sim.dofs)
    E = scipy.linalg.expm(A * dt)
    x = np.zeros(2 * n)
    x[n + sim.dofs.index(dof)] = 1.0
    y = np.empty(steps)
    for i in range(steps):
        y[i] = x[sim.dofs.index(dof)]
        x = E @ x
    envelope = np.maximum.accumulate(np.abs(y)[::-1])[::-1]
    below = envelope < level * envelope.max()
    assert below.any(), "the free response did not decay within the window"
    return float(np.argmax(below) * dt)


def y1_mode_damping(sim) -> np.ndarray:
    """Damping ratios -Re(lambda)/|lambda| of the modes that the pinion y channel sees
    (kinetic-energy share of y1 in the mode shape above 5 %)."""
    lam, V = np.linalg.eig(state_space(sim))
    n = len(sim.dofs)
    iy = sim.dofs.index("y1")
    out = []
    for value, vec in zip(lam, V.T):
        if value.imag <= 0:
            continue
        shape = vec[:n]
        energy = np.abs(shape) ** 2 * np.diag(sim.M)
        if energy[iy] / energy.sum() > 0.05:
            out.append(-value.real / abs(value))
    return np.array(out)


def test_eight_dof_is_more_damped_than_six_dof():
    six, eight = sim_at("six_dof", 40.0), sim_at("eight_dof", 40.0)
    t6, t8 = impulse_settling_time(six), impulse_settling_time(eight)
    assert t8 < 0.7 * t6, (t8, t6)  # measured: 1.4 ms against 3.6 ms
    z6, z8 = y1_mode_damping(six), y1_mode_damping(eight)
    assert len(z6) and len(z8)
    assert z8.min() > z6.min(), (z8, z6)  # the least damped mode seen at y1
    assert np.all(z6 > 0) and np.all(z8 > 0)  # every such mode decays


# --- faults ------------------------------------------------------------------------------

CRACK_CASES = [
    ("ten_dof", 25.2, 7.0, "casing_x"),  # Dataset A-casing
    ("ten_dof", 25.2, 7.0, "pinion_x"),  # Dataset A-pinion
    ("six_dof", 40.0, 20.0, "pinion_y"),  # Dataset B-6
    ("eight_dof", 40.0, 20.0, "pinion_y"),  # Dataset B-8
]


@pytest.mark.parametrize("name,speed,load,channel", CRACK_CASES)
def test_crack_response_grows_with_intensity(name, speed, load, channel):
    sim = sim_at(name, speed)
    peaks, levels = [], []
    for step in (2, 8, 14, 20):
        crack = place_fault(REG, sim.pair, "crack", 5, step=step)
        rev = steady_revolution(sim, [crack], speed, load, channel)
        peaks.append(np.abs(rev).max())
        levels.append(rms(rev))
    assert np.all(np.diff(peaks) > 0), peaks
    assert np.all(np.diff(levels) > 0), levels
    healthy = steady_revolution(sim, [], speed, load, channel)
    assert peaks[-1] > 5 * np.abs(healthy).max()  # a broken tooth: "massive amplitudes" (2.4.4)


# --- tooth-shift symmetry against direct simulation (docs/physics.md, Builder) ---------------------


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("fault,step", [("crack", 12), ("pit", 20)])
def test_tooth_shift_symmetry_against_direct_simulation(name, fault, step):
    m = MODELS[name]
    sim = sim_at(name, m["speed"])
    fs = whole_steps_rate(FS, m["speed"], m["Z1"])
    assert sim is _simulator(name, m["preset"], fs) and sim.fs == fs
    teeth = (1, 7, m["Z1"])
    rows = simulate_unit((name, m["preset"], fs, m["speed"], m["load"], m["channel"], fault, step, teeth))
    assert rows.shape == (3, 4096)
    for row, n in zip(rows, teeth):
        placed = place_fault(REG, sim.pair, fault, n, step=step)
        direct = angle_samples(steady_revolution(sim, [placed], m["speed"], m["load"], m["channel"]))
        assert rel(row, direct) < 1e-8, (n, rel(row, direct))
    # the shift is real: the rows of different teeth differ
    assert rel(rows[1], rows[0]) > 1e-3


# --- steady state ------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(MODELS))
def test_steady_state_is_periodic(name):
    m = MODELS[name]
    sim = sim_at(name, m["speed"])
    per_rev = int(round(sim.fs / m["speed"]))
    R = 10
    res = sim.run([], m["speed"], m["load"], duration=R / m["speed"], channels=[m["channel"]])
    revs = res.channels[m["channel"]][: R * per_rev].reshape(R, per_rev)
    first = steady_start(revs, rtol=STEADY_RTOL)  # detected, not assumed
    assert first <= R - 3 and first / m["speed"] < 0.2, first  # thesis Figure 2.25: ~100 ms of transient
    for a, b in zip(revs[first:-1], revs[first + 1 :]):
        assert rel(b, a) < 1e-6
    # before the detected start it was not yet periodic
    if first > 0:
        assert rel(revs[first], revs[first - 1]) > 1e-6


def test_a_longer_run_continues_a_shorter_one_with_the_same_floats():
    """steady_response lengthens a run that has not settled: the longer run continues the shorter
    one (Simulator.run's *after*) and must equal a run from the start bit for bit; a shorter run of
    another call (another speed) is not continued."""
    m = MODELS["six_dof"]
    sim = sim_at("six_dof", m["speed"])
    fault = [place_fault(REG, sim.pair, "crack", 5, step=10)]
    args = (fault, m["speed"], m["load"])
    short = sim.run(*args, duration=2 / m["speed"], channels=[m["channel"]])
    whole = sim.run(*args, duration=5 / m["speed"], channels=[m["channel"]])
    went_on = sim.run(*args, duration=5 / m["speed"], channels=[m["channel"]], after=short)
    assert np.array_equal(went_on.channels[m["channel"]], whole.channels[m["channel"]])
    assert all(np.array_equal(a, b) for a, b in zip(went_on.state, whole.state))
    other = sim.run(fault, m["speed"] * 1.25, m["load"], duration=2 / m["speed"], channels=[m["channel"]])
    again = sim.run(*args, duration=5 / m["speed"], channels=[m["channel"]], after=other)
    assert np.array_equal(again.channels[m["channel"]], whole.channels[m["channel"]])


# --- the rank-one solver against a plain Newmark ------------------------------------------


def plain_newmark(M, Kc, Cc, P, mu, k, F, u0, fs, gamma, beta):
    """Textbook Newmark: K_hat = K(t) + a0 M + a1 C(t), solved with np.linalg.solve each step."""
    dt = 1.0 / fs
    a0, a1 = 1 / (beta * dt**2), gamma / (beta * dt)
    a2, a3 = 1 / (beta * dt), 1 / (2 * beta) - 1
    a4, a5 = gamma / beta - 1, dt / 2 * (gamma / beta - 2)
    PP = np.outer(P, P)
    u, v, a = u0.copy(), np.zeros_like(u0), np.zeros_like(u0)
    out = [a.copy()]
    for kk in k[1:]:
        K = Kc + kk * PP
        C = Cc + mu * kk * PP
        rhs = F + M @ (a0 * u + a2 * v + a3 * a) + C @ (a1 * u + a4 * v + a5 * a)
        u_new = np.linalg.solve(K + a0 * M + a1 * C, rhs)
        a_new = a0 * (u_new - u) - a2 * v - a3 * a
        v = v + dt * ((1 - gamma) * a + gamma * a_new)
        u, a = u_new, a_new
        out.append(a.copy())
    return np.array(out)


@pytest.mark.parametrize("name", ["six_dof", "ten_dof"])
def test_rank_one_solver_equals_plain_newmark(name):
    m = MODELS[name]
    sim = Simulator(model(name), m["preset"])  # 200 kHz
    assert (sim.gamma, sim.beta) == (BETA1, BETA2 / 2) == (0.5, 1.125)
    crack = place_fault(REG, sim.pair, "crack", 3, step=15)
    steps = 2000
    res = sim.run([crack], m["speed"], m["load"], duration=steps / sim.fs)
    assert len(res.t) == steps + 1
    # The same static initial state: equilibrium at the mean of the revolution's TVMS, which
    # is sampled on whole steps when a revolution is a whole number of steps (six_dof: 40 Hz
    # at 200 kHz) and otherwise on a pitch-aligned grid and interpolated (ten_dof: 25.2 Hz).
    per_rev = sim.fs / m["speed"]
    if abs(per_rev - round(per_rev)) < 1e-9 * per_rev:
        tvms = sim.stiffness.mesh_stiffness([crack], points=round(per_rev))
        np.testing.assert_array_equal(res.tvms, tvms.k[np.arange(steps + 1) % round(per_rev)])
    else:
        tvms = sim.stiffness.mesh_stiffness([crack], points=sim.pair.Z1 * math.ceil(TVMS_POINTS / sim.pair.Z1))
    assert res.tvms.min() < 0.5 * tvms.mean  # the cracked tooth is in mesh within these steps
    F = np.zeros(len(sim.dofs))
    F[sim.dofs.index(sim.model.load_dof)] = -m["load"]
    u0 = np.linalg.solve(sim.Kc + tvms.mean * np.outer(sim.P, sim.P), F)
    ref = plain_newmark(sim.M, sim.Kc, sim.Cc, sim.P, sim.mu, res.tvms, F, u0, sim.fs, 0.5, 1.125)
    for ch, x in res.channels.items():
        want = ref[:, sim.dofs.index(CHANNEL_DOFS[ch])]
        assert np.abs(want).max() > 0
        assert np.abs(x - want).max() <= 1e-9 * np.abs(want).max(), (ch, np.abs(x - want).max() / np.abs(want).max())


# --- divergence and step checks ------------------------------------------------------------


class _Poisoned(MeshStiffness):
    """A TVMS whose series turns bad after some sample but whose mean stays finite, so the
    static initial state is fine and the integration itself has to catch the failure."""

    @property
    def mean(self) -> float:
        return float(np.nanmean(self.k))


def test_nan_stiffness_is_a_simulation_error_naming_model_faults_and_time(monkeypatch):
    sim = Simulator(model("six_dof"), "meng2020")
    original = sim.stiffness.mesh_stiffness
    bad_from = 3000  # sample from which the TVMS is NaN (5000 samples per revolution at 40 Hz)

    def poisoned(faults=(), points=4096):
        ms = original(faults, points)
        k = ms.k.copy()
        k[bad_from:] = np.nan
        return _Poisoned(ms.theta, k, ms.pair, ms.faults)

    crack = place_fault(REG, sim.pair, "crack", 5, step=10)
    chip = place_fault(REG, sim.pair, "chip", 9, step=20)
    monkeypatch.setattr(sim.stiffness, "mesh_stiffness", poisoned)
    with pytest.raises(SimulationError) as info:
        sim.run([crack, chip], 40.0, 20.0, duration=0.03)
    msg = str(info.value)
    assert isinstance(info.value, GearlabInputError)
    for part in ("model 'six_dof'", "preset 'meng2020'", "crack@5", "chip@9", "40 Hz", "20 N*m", "diverged"):
        assert part in msg, (part, msg)
    # the time reported is where the divergence was caught: after it began, within one check interval
    t = float(msg.split("near t = ")[1].split(" s")[0])
    assert bad_from / sim.fs <= t <= (bad_from + 2048) / sim.fs, msg
    assert "\n" not in msg


@pytest.mark.parametrize("k", [-1e8, -3e7])
def test_negative_mesh_stiffness_overflows_into_a_simulation_error(monkeypatch, k):
    """A negative 'mesh stiffness' makes K(t) indefinite: the response grows until caught."""
    sim = Simulator(model("ten_dof"), "luo2019")
    original = sim.stiffness.mesh_stiffness

    def negative(faults=(), points=4096):
        ms = original(faults, points)
        return MeshStiffness(ms.theta, np.full_like(ms.k, k), ms.pair, ms.faults)

    monkeypatch.setattr(sim.stiffness, "mesh_stiffness", negative)
    with pytest.raises(SimulationError, match=r"model 'ten_dof'.*\(healthy, 25.2 Hz.*diverged.*near t = "):
        sim.run([], 25.2, 7.0, duration=0.1)


def test_too_coarse_step_warns_naming_the_highest_natural_frequency():
    m = model("ten_dof")
    sim = Simulator(m, "luo2019")
    top = sim.natural_frequencies(k=sim.stiffness.mesh_stiffness(points=8192).k.max()).max()
    assert 4000 < top < 6000  # the casing/bearing mode of Table 2.3, ~5 kHz
    with pytest.warns(UserWarning, match=rf"highest natural frequency \({top:.0f} Hz\)"):
        coarse = Simulator(m, "luo2019", fs=20e3)
    res = coarse.run([], 25.2, 7.0, duration=0.05)  # it still runs (mesh 403 Hz x 10 < 20 kHz)
    assert np.all(np.isfinite(res.channels["casing_x"]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Simulator(m, "luo2019", fs=10 * top + 1)  # fine enough: no warning


def test_sampling_rate_below_ten_mesh_frequencies_is_refused():
    with pytest.warns(UserWarning, match="highest natural frequency"):
        sim = Simulator(model("six_dof"), "meng2020", fs=9e3)  # mesh at 40 Hz: 1000 Hz
    with pytest.raises(GearlabInputError, match=r"six_dof.*fs = 9000 Hz is too low.*1000 Hz.*at least 10000 Hz"):
        sim.run([], speed_hz=40.0, duration=0.1)
    with pytest.raises(GearlabInputError, match="too low"):
        sim.run([], speed_hz=36.5, duration=0.1)  # mesh 912.5 Hz: 10 x is 9125 Hz > 9 kHz
    sim.run([], speed_hz=36.0, duration=0.05)  # exactly 10 x the mesh frequency is accepted


# --- bad input ------------------------------------------------------------------------------


def test_unknown_preset_suggests_the_close_one():
    with pytest.raises(GearlabInputError, match=r"unknown preset 'luo2091'.*did you mean 'luo2019'.*known: luo2019"):
        Simulator(model("ten_dof"), "luo2091")
    with pytest.raises(GearlabInputError, match="eight_dof"):
        Simulator(model("eight_dof"), "luo2019")


def test_unknown_model_suggests_the_close_one():
    with pytest.raises(GearlabInputError, match=r"unknown model 'six_dfo'.*did you mean 'six_dof'"):
        REG.get("model", "six_dfo")


def test_unknown_channel_lists_the_channels():
    sim = Simulator(model("eight_dof"), "meng2020")
    with pytest.raises(GearlabInputError) as info:
        sim.run([], duration=0.01, channels=["casing_x"])
    msg = str(info.value)
    assert "casing_x" in msg and "pinion_x, pinion_y, gear_x, gear_y" in msg and "eight_dof" in msg


@pytest.mark.parametrize(
    "kwargs,pattern",
    [
        (dict(speed_hz=-40.0), "speed must be a positive"),
        (dict(speed_hz=0.0), "speed must be a positive"),
        (dict(speed_hz=float("nan")), "speed must be a positive"),
        (dict(load_nm=-1.0), "load must be a torque >= 0"),
        (dict(duration=0.0), "duration must be a positive"),
        (dict(duration=-0.1), "duration must be a positive"),
        (dict(duration=float("inf")), "duration must be a positive"),
    ],
)
def test_bad_operating_point(kwargs, pattern):
    sim = Simulator(model("six_dof"), "meng2020")
    with pytest.raises(GearlabInputError, match=pattern):
        sim.run([], **{"duration": 0.01, **kwargs})


@pytest.mark.parametrize(
    "kwargs,pattern",
    [
        (dict(beta1=0.5, beta2=0.4), "beta2 >= beta1 >= 0.5"),
        (dict(beta1=0.4, beta2=2.25), "beta2 >= beta1 >= 0.5"),
        (dict(fs=0.0), "fs must be a positive"),
        (dict(fs=-200e3), "fs must be a positive"),
        (dict(overrides={"k_b": -1.0}), "k_b"),
        (dict(overrides={"k_bb": 1e8}), r"unknown parameter 'k_bb'.*did you mean 'k_b'"),
    ],
)
def test_bad_simulator_settings(kwargs, pattern):
    with pytest.raises(GearlabInputError, match=pattern):
        Simulator(model("six_dof"), "meng2020", **kwargs)


def test_overrides_change_the_model():
    base = Simulator(model("six_dof"), "meng2020")
    stiff = Simulator(model("six_dof"), "meng2020", overrides={"k_b": "1e9 N/m"})
    assert stiff.values["k_b"] == 1e9
    assert stiff.natural_frequencies().max() > base.natural_frequencies().max()
