"""The PEM TVMS engine (thesis 2.1, 2.2.5): quadrature convergence, periodicity, term switches, tooth shifts."""

import math

import numpy as np
import pytest

from gearlab.physics.stiffness import MeshStiffnessModel, StiffnessOptions, mesh_stiffness

PRESETS = ["luo2019", "meng2020"]


@pytest.fixture(scope="module")
def fine_models(pairs):
    return {name: MeshStiffnessModel(pair, StiffnessOptions(nodes=8192)) for name, pair in pairs.items()}


def _faults(registry, pair, which):
    if which == "healthy":
        return []
    kind, step = which
    fault = registry.get("fault", kind)
    return [fault.place(5, fault.at_step(pair, step), pair)]


CASES = ["healthy", ("crack", 12), ("spall", 15)]


@pytest.mark.parametrize("refined", ["section nodes", "angle grid"])
@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("case", CASES, ids=lambda c: c if isinstance(c, str) else f"{c[0]}{c[1]}")
def test_refining_the_quadrature_changes_the_mean_by_less_than_0_1_percent(
    registry, pairs, models, fine_models, preset, case, refined
):
    """8192 section nodes, or 16384 angles instead of 4096."""
    faults = _faults(registry, pairs[preset], case)
    coarse = models[preset].mesh_stiffness(faults, points=4096).mean
    model, points = (fine_models[preset], 4096) if refined == "section nodes" else (models[preset], 16384)
    assert abs(model.mesh_stiffness(faults, points=points).mean / coarse - 1) < 1e-3


@pytest.mark.parametrize("preset", PRESETS)
def test_faults_lower_the_mean_visibly_compared_with_the_quadrature_error(registry, pairs, models, preset):
    """The convergence tolerance is meaningful: a mid crack moves the mean by more than 0.1 %."""
    pair, model = pairs[preset], models[preset]
    healthy = model.mesh_stiffness(points=4096).mean
    cracked = model.mesh_stiffness(_faults(registry, pair, ("crack", 12)), points=4096).mean
    assert cracked < healthy * (1 - 1e-2)


@pytest.mark.parametrize("preset", PRESETS)
def test_healthy_tvms_repeats_every_pitch(pairs, models, preset):
    pair = pairs[preset]
    per_pitch = {"luo2019": 512, "meng2020": 200}[preset]
    points = pair.Z1 * per_pitch
    ms = models[preset].mesh_stiffness(points=points)
    assert ms.theta[1] == pytest.approx(2 * math.pi / points)
    assert np.ptp(ms.k) > 0.1 * ms.mean  # not trivially periodic: it alternates single/double contact
    for shift in (1, 2, pair.Z1 - 1):
        np.testing.assert_allclose(np.roll(ms.k, shift * per_pitch), ms.k, rtol=1e-9, atol=0)


@pytest.mark.parametrize("preset", PRESETS)
def test_healthy_tvms_has_single_and_double_contact_levels(pairs, models, preset):
    """Over one pitch (local angle of tooth 1 in [0, 2pi/Z1)) double contact lasts theta_d, single theta_s."""
    pair = pairs[preset]
    points = 16384
    ms = models[preset].mesh_stiffness(points=points)
    pitch = 2 * math.pi / pair.Z1
    one = ms.theta < pitch
    theta, k = ms.theta[one], ms.k[one]
    # Avoid samples within one grid step of a tooth entry/exit.
    step = 2 * math.pi / points
    double = (theta > step) & (theta < pair.theta_d - step)
    single = (theta > pair.theta_d + step) & (theta < pitch - step)
    assert k[double].min() > k[single].max()
    # Contact-pair counting: the jump at the end of double contact is a whole tooth pair's stiffness.
    jump = k[double][-1] - k[single][0]
    assert 0.2 * ms.mean < jump < ms.mean


@pytest.mark.parametrize("preset", PRESETS)
def test_term_switches_stiffen_the_mesh(pairs, models, preset):
    pair = pairs[preset]
    default = models[preset].mesh_stiffness(points=4096).mean
    no_fillet = mesh_stiffness(pair, points=4096, options=StiffnessOptions(fillet=False)).mean
    no_root = mesh_stiffness(pair, points=4096, options=StiffnessOptions(root_region=False)).mean
    neither = mesh_stiffness(pair, points=4096, options=StiffnessOptions(fillet=False, root_region=False)).mean
    assert no_fillet > default * 1.5  # the fillet foundation is a large compliance (docs/physics.md table)
    assert no_root > default * 1.05
    assert neither > max(no_fillet, no_root)


@pytest.mark.parametrize(
    "preset, mean, lo, hi",
    [("luo2019", 1.891e8, 1.241e8, 2.299e8), ("meng2020", 3.718e8, 2.521e8, 4.456e8)],
)
def test_healthy_stiffness_magnitude(models, preset, mean, lo, hi):
    ms = models[preset].mesh_stiffness(points=4096)
    assert 1e8 <= ms.mean <= 1e9
    assert np.all(ms.k > 0)
    # The values documented in docs/physics.md, to 0.1 %.
    assert ms.mean == pytest.approx(mean, rel=1e-3)
    assert ms.k.min() == pytest.approx(lo, rel=1e-3)
    assert ms.k.max() == pytest.approx(hi, rel=1e-3)


def test_model_is_not_changed_by_a_faulted_call(registry, pairs, models):
    """The healthy cache must not be overwritten by a faulted evaluation."""
    pair, model = pairs["luo2019"], models["luo2019"]
    before = model.mesh_stiffness(points=4096).k.copy()
    model.mesh_stiffness(_faults(registry, pair, ("crack", 20)), points=4096)
    np.testing.assert_array_equal(model.mesh_stiffness(points=4096).k, before)


def test_models_of_one_pair_share_its_healthy_tvms_and_no_call_changes_it(registry, pairs):
    """Computed once per pair, options and grid (a gap search makes a simulator per point it tries);
    read-only, so no caller can change what the next model of the pair gets."""
    pair = pairs["meng2020"]
    a, b = MeshStiffnessModel(pair), MeshStiffnessModel(pair)
    assert a._healthy(1024)[1] is b._healthy(1024)[1]
    assert MeshStiffnessModel(pair, StiffnessOptions(fillet=False))._healthy(1024)[1] is not a._healthy(1024)[1]
    healthy = a.mesh_stiffness(points=1024)
    with pytest.raises(ValueError):
        healthy.theta[0] = 1.0
    crack = registry.get("fault", "crack")
    faulted = b.mesh_stiffness([crack.place(2, crack.at_step(pair, 15), pair)], points=1024).k
    faulted[:] = 0.0  # a faulted TVMS is the caller's own copy
    assert np.array_equal(MeshStiffnessModel(pair).mesh_stiffness(points=1024).k, healthy.k) and healthy.k.any()


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("kind, step", [("crack", 15), ("chip", 20), ("spall", 20), ("pit", 20)])
def test_fault_on_tooth_n_is_the_tooth_1_tvms_shifted(registry, pairs, models, preset, kind, step):
    pair, model = pairs[preset], models[preset]
    per_pitch = 256
    points = pair.Z1 * per_pitch
    fault = registry.get("fault", kind)
    params = fault.at_step(pair, step)
    healthy = model.mesh_stiffness(points=points).k
    k1 = model.mesh_stiffness([fault.place(1, params, pair)], points=points).k
    assert np.max(np.abs(k1 - healthy)) > 1e-6 * healthy.mean()  # the fault does something
    for n in (3, 9):
        kn = model.mesh_stiffness([fault.place(n, params, pair)], points=points).k
        np.testing.assert_allclose(kn, np.roll(k1, (n - 1) * per_pitch), rtol=1e-9, atol=0)
        # and not trivially: a shift by one pitch less does not match
        assert not np.allclose(kn, np.roll(k1, (n - 2) * per_pitch), rtol=1e-9, atol=0)
