"""The Bayes bound (gearlab.learn.bounds), the calibration of calibrated methods
(gearlab.learn.calibration) and the `burst` network: behaviour and numbers on small
synthetic revolutions with known bursts in known noise."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import torch

from gearlab.engine import load_scenario
from gearlab.errors import GearlabInputError
from gearlab.learn.bounds import best_accuracy, detection_at, gain, likelihood_ratio
from gearlab.learn.calibration import (
    RECIPE,
    THESIS,
    Calibrated,
    Calibration,
    Inputs,
    calibrate,
    draw_noise,
    noise_law,
    prepare,
)
from gearlab.learn.networks import build_network
from gearlab.learn.path import IDENTITY
from gearlab.learn.training import _aligned

pytestmark = pytest.mark.usefixtures("one_torch_thread")

L = 512


def burst_shape(position: int, length: int = L, width: int = 24, cycles: float = 4.0) -> np.ndarray:
    """A decaying tone burst starting at *position* (a fault's response)."""
    t = np.arange(width)
    s = np.zeros(length)
    s[position : position + width] = np.exp(-t / (width / 3)) * np.sin(2 * np.pi * cycles * t / width)
    return s


def revolutions(n: int, faults: int, amplitude: float, law: str, seed: int, healthy_level: float = 1.0):
    """*n* revolutions (the first *faults* with a burst of *amplitude* at a random position) of
    a tone plus noise of *law* at unit scale (not rescaled row by row: that would make the
    residual's energy a give-away)."""
    rng = np.random.default_rng(seed)
    h = healthy_level * np.sin(2 * np.pi * 8 * np.arange(L) / L)
    gen = torch.Generator().manual_seed(seed)
    noise = draw_noise(law, (n, L), gen).double().numpy()
    X = h + noise
    positions = rng.integers(0, L - 30, faults)
    for i, p in enumerate(positions):
        X[i] += amplitude * burst_shape(p)
    y = (np.arange(n) < faults).astype(np.int64)
    return X.astype(np.float32), y, h, positions


# ----------------------------------------------------------------------------- bounds


def test_best_accuracy_and_detection_rate_by_hand():
    score = np.array([0.1, 0.2, 0.9, 0.3, 0.8, 0.7])
    y = np.array([0, 0, 1, 0, 1, 0])
    # threshold between 0.3 and 0.7 calls 0.7 wrongly: 5/6; between 0.7 and 0.8: all right
    assert best_accuracy(score, y) == pytest.approx(100.0)
    assert best_accuracy(np.array([0.5, 0.5, 0.5]), np.array([0, 1, 1])) == pytest.approx(100 * 2 / 3)
    assert detection_at(score, y, 0.01) == pytest.approx(
        100.0 * np.mean(score[y == 1] > np.quantile(score[y == 0], 0.99))
    )


AMPLITUDE = 3.0


@pytest.mark.parametrize("law", ["laplace", "gaussian", "student_t"])
def test_likelihood_ratio_beats_energy_and_knows_its_noise_law(law):
    """The likelihood ratio with the true shapes finds weak bursts better than the residual's
    energy, and the right noise law does at least as well as the wrong one."""
    # 200 revolutions, 100 with a burst (400 / 200: student_t's elementwise sums 3.0 s of CPU against 1.4): right
    # 70.0 / 76.5 / 85.5 %, energy 52.5 / 56.5 / 64.5, the wrong law 52.5 / 60.0 / 83.0 (student_t, laplace, gaussian)
    X, y, h, pos = revolutions(200, 100, amplitude=AMPLITUDE, law=law, seed=3)
    shapes = np.stack([burst_shape(p) * AMPLITUDE for p in range(0, L - 30)])
    right = best_accuracy(likelihood_ratio(X, h, shapes, law), y)
    energy = best_accuracy(((X - h) ** 2).sum(1), y)
    assert right > energy + 5
    wrong = "gaussian" if law != "gaussian" else "laplace"
    assert right >= best_accuracy(likelihood_ratio(X, h, shapes, wrong), y) - 1.0


@pytest.mark.parametrize("law", ["laplace", "gaussian", "student_t"])
def test_the_distance_forms_of_the_likelihood_ratio_are_the_elementwise_sums(law):
    """Laplace and Gaussian are computed as L1 distances and inner products; the same numbers
    as the sum over samples of log p(r - t) - log p(r)."""
    import torch

    from gearlab.learn.bounds import _log_density, noise_scale, shape_llr

    rng = np.random.default_rng(4)
    R, T = torch.as_tensor(rng.laplace(size=(7, 256))), torch.as_tensor(rng.normal(size=(5, 256)))
    s = noise_scale(R, law)
    direct = (
        _log_density(R[:, None] - T[None], s[:, None, None], law) - _log_density(R, s[:, None], law)[:, None]
    ).sum(-1)
    assert torch.allclose(shape_llr(R, T, s, law), direct, rtol=1e-10, atol=1e-9)


def test_likelihood_ratio_refuses_an_unknown_law_and_gain_recovers_a_scale():
    with pytest.raises(GearlabInputError, match="unknown noise kind 'cauchy'"):
        likelihood_ratio(np.zeros((2, 8)), np.zeros(8), np.ones((1, 8)), "cauchy")
    c = np.sin(np.arange(64) / 3.0)
    assert gain(0.7 * c, c) == pytest.approx(0.7)


# ----------------------------------------------------------------------------- calibration


@pytest.mark.parametrize("law", ["gaussian", "laplace", "student_t"])
def test_noise_law_is_read_off_the_history(law):
    X, _, h, _ = revolutions(60, 0, 0.0, law, seed=4)
    assert noise_law(X - np.median(X, axis=0)) == law


def test_draw_noise_has_the_laws_kurtosis():
    gen = torch.Generator().manual_seed(0)
    from scipy.stats import kurtosis

    assert kurtosis(draw_noise("gaussian", (200_000,), gen).numpy(), fisher=False) == pytest.approx(3.0, abs=0.1)
    assert kurtosis(draw_noise("laplace", (200_000,), gen).numpy(), fisher=False) == pytest.approx(6.0, abs=0.4)


def test_prepare_takes_references_gain_and_noise_level_from_the_training_arrays():
    Xs, ys, h_s, _ = revolutions(80, 40, 3.0, "gaussian", seed=5, healthy_level=2.0)
    Xs = (Xs - np.random.default_rng(0).normal(size=Xs.shape) * 0.0).astype(np.float32)
    Xt, _, h_t, _ = revolutions(60, 0, 0.0, "laplace", seed=6, healthy_level=1.0)
    inputs = prepare(Calibration(residual=True, source_noise="auto"), Xs, ys, Xt, None)
    assert inputs.noise_law == "laplace"
    assert inputs.noise_rms == pytest.approx(np.sqrt(2.0), rel=0.05)  # Laplace noise of unit scale
    # RMS of the references: source tone 2 (+ its noise averaged down), target 1
    assert len(inputs.path.taps) == 1 and inputs.path.taps[0] == pytest.approx(0.5, rel=0.1)
    assert np.allclose(inputs.target(Xt), Xt - inputs.target_reference)
    assert np.allclose(inputs.source(Xs), inputs.path.taps[0] * (Xs - inputs.source_reference), atol=1e-5)
    x = torch.zeros(4, L)
    noisy = inputs.augment(x, torch.Generator().manual_seed(1))
    assert noisy.pow(2).mean(1).sqrt().numpy() == pytest.approx(np.full(4, inputs.noise_rms), rel=1e-4)
    # the thesis's recipe changes nothing
    thesis = prepare(THESIS, Xs, ys, Xt, None)
    assert thesis.noise_law is None and np.array_equal(thesis.source(Xs), Xs) and np.array_equal(thesis.target(Xt), Xt)


def test_a_reference_of_zero_leaves_the_gain_at_one():
    """Inputs whose synchronous signal is already removed (a difference signal) have a zero
    healthy reference; the gain must not become the ratio of two round-off levels."""
    Xt, _, _, _ = revolutions(60, 0, 0.0, "laplace", seed=13, healthy_level=0.0)
    Xs, ys, _, _ = revolutions(80, 40, 3.0, "gaussian", seed=14, healthy_level=0.0)
    Xs -= np.median(Xs[ys == 0], axis=0)  # exactly zero reference
    Xs[ys == 0] = 0.0
    inputs = prepare(Calibration(residual=True, source_noise="auto"), Xs, ys, Xt, None)
    assert inputs.path.taps.tolist() == [1.0] and np.isfinite(inputs.source(Xs)).all()
    fir = prepare(Calibration(residual=True, path="fir"), Xs, ys, Xt, None)
    assert fir.path.taps.tolist() == [1.0] and np.array_equal(fir.source(Xs), inputs.source(Xs))


def test_a_few_unlabelled_faults_in_the_history_do_not_move_the_noise_level():
    Xt, yt, _, _ = revolutions(120, 16, 8.0, "laplace", seed=7)
    clean, _, _, _ = revolutions(120, 0, 0.0, "laplace", seed=7)
    a = prepare(Calibration(source_noise="laplace"), clean, np.r_[np.zeros(60), np.ones(60)], Xt, None)
    b = prepare(Calibration(source_noise="laplace"), clean, np.r_[np.zeros(60), np.ones(60)], clean, None)
    assert a.noise_rms == pytest.approx(b.noise_rms, rel=0.03)


def test_history_threshold_lets_the_asked_share_of_healthy_revolutions_through():
    """A fixed score (the residual's largest |value|) thresholded on a healthy history calls
    about 1 % of fresh healthy revolutions faulty, and the reference is subtracted."""

    class MaxAbs(torch.nn.Module):
        latent_dim = 1

        def embed(self, x):
            return x.abs().amax(1, keepdim=True)

        def forward(self, x):
            s = self.embed(x)[:, 0]
            return torch.stack([torch.zeros_like(s), s], 1)

    history, _, h, _ = revolutions(400, 0, 0.0, "laplace", seed=8, healthy_level=5.0)
    fresh, _, _, _ = revolutions(4000, 0, 0.0, "laplace", seed=9, healthy_level=5.0)
    inputs = prepare(
        Calibration(residual=True, threshold="history", false_alarm=0.01),
        history,
        np.r_[np.zeros(200), np.ones(200)],
        history,
        None,
    )
    model = calibrate(MaxAbs(), inputs, history, None, "cpu")
    called = model(torch.as_tensor(fresh)).argmax(1).numpy()
    assert 0.002 < called.mean() < 0.03
    assert isinstance(model, Calibrated) and model.reference.numel() == L


@pytest.mark.parametrize(
    "bad, match",
    [
        (dict(source_noise="pink"), "source_noise"),
        (dict(path="spline"), "path"),
        (dict(start="fault"), "start"),
        (dict(alignment="joint"), "alignment"),
        (dict(threshold="max"), "threshold"),
        (dict(false_alarm=0.7), "false_alarm"),
    ],
)
def test_calibration_settings_are_checked(bad, match):
    with pytest.raises(GearlabInputError, match=match):
        Calibration(**bad).check("s.toml")


def test_the_protocol_keys_of_calibration_are_its_fields_with_the_recipe_as_defaults(tmp_path):
    """Declared once: the transfer kind's [protocol] keys are Calibration's fields, defaults
    gearlab's recipe, and a bad value is refused there with the file, table and key."""
    from gearlab.learn.calibration import RECIPE
    from gearlab.parts.training import CALIBRATION

    assert {k: key.default for k, key in CALIBRATION.items()} == dataclasses.asdict(RECIPE)
    scenario = Path(__file__).resolve().parents[1] / "scenarios" / "quick.toml"
    bad = tmp_path / "bad.toml"
    bad.write_text(scenario.read_text().replace("[protocol]", '[protocol]\nsource_noise = "pinc"', 1))
    with pytest.raises(
        GearlabInputError,
        match=r"bad.toml.*protocol.*source_noise.*pinc",
    ):
        load_scenario(bad)


def test_healthy_alignment_compares_the_source_healthy_with_the_history():
    z_s, z_t = torch.arange(12.0).reshape(6, 2), torch.arange(100.0, 108.0).reshape(4, 2)
    y_s = torch.tensor([0, 1, 0, 1, 0, 1])
    assert len(_aligned(z_s, z_t, y_s, None, "marginal")) == 1
    ((a, b),) = _aligned(z_s, z_t, y_s, None, "healthy")
    assert torch.equal(a, z_s[[0, 2, 4]]) and torch.equal(b, z_t)
    y_t = torch.tensor([0, 0, 1, 1])
    pairs = _aligned(z_s, z_t, y_s, y_t, "healthy")  # supervised: class by class
    assert [len(a) for a, _ in pairs] == [3, 3] and torch.equal(pairs[1][1], z_t[2:])


# ----------------------------------------------------------------------------- burst network


def test_burst_network_is_gain_free_and_takes_any_length():
    net = build_network("burst", 2, seed=0).eval()
    x = torch.randn(3, 1000)
    with torch.no_grad():
        assert torch.allclose(net(x), net(37.0 * x), atol=1e-4)
        assert net(torch.randn(2, 4096)).shape == (2, 2)
    assert net.latent_dim == 32
    with pytest.raises(GearlabInputError, match="at least"):
        build_network("burst", 2, length=10)


def test_burst_network_finds_a_burst_anywhere_in_the_revolution():
    """Trained on bursts in the first half of the revolution, it finds those in the second half
    as well as unseen ones in the first (global max pooling over a circular bank)."""
    from gearlab.learn.training import fit_supervised

    torch.manual_seed(0)
    X, y, h, pos = revolutions(1200, 600, amplitude=10.0, law="laplace", seed=10)
    R = X - h.astype(np.float32)
    early = np.flatnonzero(pos < L // 2)
    train = np.r_[early[: len(early) // 2], np.arange(600, 800)]
    net = build_network("burst", 2, seed=0)
    fit_supervised(net, R[train], y[train], rng=np.random.default_rng(0), device="cpu", epochs=25, batch=40)
    with torch.no_grad():
        called = net.eval()(torch.as_tensor(R)).argmax(1).numpy()
    seen_half, other_half = called[early[len(early) // 2 :]].mean(), called[np.flatnonzero(pos >= L // 2)].mean()
    assert seen_half > 0.75 and other_half > seen_half - 0.05
    assert called[800:].mean() < 0.15  # healthy revolutions it never saw


# ----------------------------------------------------------------------------- matched_filter's limiter


def test_matched_filter_limiter_by_name_and_its_effect_in_impulsive_noise():
    from gearlab.learn.detectors import template_detector
    from gearlab.registry import get_registry

    adapter = get_registry().get("detector", "matched_filter")
    assert adapter.resolve({"limiter": "auto"})["limiter"] == 2
    with pytest.raises(GearlabInputError, match="parameter 'limiter': unknown value 'of'.*did you mean 'off'"):
        adapter.resolve({"limiter": "of"})
    # the same shapes in both domains, Student-t noise: the limiter finds more bursts (62.9
    # against 79.6 % with the best threshold; in Laplace noise it helps bursts weaker than the
    # noise, as in chapter 5, and costs strong ones: docs/learning.md)
    amplitude = 5.0
    X, y, h, pos = revolutions(600, 300, amplitude=amplitude, law="student_t", seed=11)
    bursts = np.stack([h + amplitude * burst_shape(p) for p in range(0, L - 30)])  # a noise-free source
    source = np.concatenate([bursts, np.tile(h, (len(bursts), 1))]).astype(np.float32)
    ys = np.r_[np.ones(len(bursts)), np.zeros(len(bursts))]
    history = X[300:420]
    test = np.r_[np.arange(0, 300), np.arange(420, 600)]
    scores = {}
    for limiter in ("off", "on"):
        d = template_detector(source, ys, history, None, false_alarm=0.01, limiter=limiter)
        with torch.no_grad():
            scores[limiter] = d.score(torch.as_tensor(X[test])).numpy()
    assert best_accuracy(scores["on"], y[test]) > best_accuracy(scores["off"], y[test]) + 10


@pytest.mark.parametrize("law", ["gaussian", "laplace", "student_t"])
def test_noise_drawn_in_place_is_the_formulas_to_the_bit(law):
    """draw_noise and augment work in place on the fresh draw (issue 42: a calibrated training draws
    a batch's noise every step): the same floats as the laws' formulas written out of place."""
    shape, rms = (6, 512), 0.37

    def reference(g: torch.Generator) -> torch.Tensor:
        if law == "gaussian":
            return torch.randn(shape, generator=g)
        u = torch.rand(shape, generator=g).clamp(1e-7, 1.0 - 1e-7)
        if law == "laplace":
            return -torch.sign(u - 0.5) * torch.log1p(-2.0 * (u - 0.5).abs())
        return torch.randn(shape, generator=g) / torch.sqrt(-torch.log(u))

    assert torch.equal(
        draw_noise(law, shape, torch.Generator().manual_seed(3)), reference(torch.Generator().manual_seed(3))
    )
    x = torch.randn(shape, generator=torch.Generator().manual_seed(9))
    n = reference(torch.Generator().manual_seed(5))
    expected = x + n * (rms / n.pow(2).mean(dim=-1, keepdim=True).sqrt().clamp_min(1e-12))
    inputs = Inputs(RECIPE, None, None, IDENTITY, noise_law=law, noise_rms=rms)
    before = x.clone()
    assert torch.equal(inputs.augment(x, torch.Generator().manual_seed(5)), expected)
    assert torch.equal(x, before)  # the batch itself is left as it was


def test_float32_laplace_likelihood_ratios_are_those_of_float64():
    """A detector's float32 Laplace ratios sum |r| - |r - t| over the samples (the compiled loop),
    not ||r||_1 - cdist: at Experiment B's size that form's cancellation put them 0.014 off the
    float64 figures (issue 42)."""
    from gearlab.learn.bounds import shape_llr

    rng = np.random.default_rng(0)
    R = torch.as_tensor(rng.normal(size=(64, 4096)), dtype=torch.float32)
    T = torch.as_tensor(0.3 * rng.normal(size=(40, 4096)), dtype=torch.float32)
    one = torch.ones(64)
    exact = shape_llr(R.double(), T.double(), one.double(), "laplace")
    assert (shape_llr(R, T, one, "laplace").double() - exact).abs().max() < 1e-3
    with torch.no_grad():  # float64 keeps its precision on the compiled path
        cdist = R.double().abs().sum(1, keepdim=True) - torch.cdist(R.double(), T.double(), p=1.0)
    assert torch.allclose(exact, cdist, rtol=0, atol=1e-9)


def test_a_process_calibrates_the_same_arrays_once():
    """Every calibrated method of a repetition and k asks for the same calibration: the second ask
    of equal arrays (not the same objects) gets the first's, read-only; other arrays their own."""
    Xs, ys, _, _ = revolutions(40, 20, 3.0, "gaussian", seed=5, healthy_level=2.0)
    Xt, _, _, _ = revolutions(30, 0, 0.0, "laplace", seed=6, healthy_level=1.0)
    settings = Calibration(residual=True, source_noise="auto")
    first = prepare(settings, Xs, ys, Xt, None)
    assert prepare(settings, Xs.copy(), ys.copy(), Xt.copy(), None) is first
    assert not first.target_reference.flags.writeable and not first.source_reference.flags.writeable
    other = prepare(settings, Xs, ys, Xt[:-1], None)
    assert other is not first and other.noise_law == first.noise_law
    assert prepare(replace_settings(settings), Xs, ys, Xt, None) is not first


def replace_settings(settings: Calibration) -> Calibration:
    return dataclasses.replace(settings, source_noise="laplace")
