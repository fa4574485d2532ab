"""The transfer path between two domains' healthy references (gearlab.learn.path)."""

import numpy as np
import pytest

from gearlab.learn.path import IDENTITY, fit_path

N, TEETH = 2048, 16
rng = np.random.default_rng(0)
n = np.arange(N)
# a healthy mesh signal: harmonics of the tooth order with their shaft-order sidebands
HEALTHY = sum(
    a * np.cos(2 * np.pi * (h * TEETH + s) * n / N + p)
    for h in range(1, 24)
    for s, a, p in zip((-1, 0, 1), rng.uniform(0.2, 1.0, 3) / h**0.5, rng.uniform(0, 2 * np.pi, 3))
)


def burst(start: int, size: float = 1.0) -> np.ndarray:
    x = np.zeros(N)
    x[start : start + 40] = size * np.exp(-np.arange(40) / 8.0) * np.sin(np.arange(40) / 1.7)
    return x


def resonance(x: np.ndarray, order: float = 150.0, damping: float = 0.08) -> np.ndarray:
    """*x* through a lightly damped resonance at *order* (a casing path), circularly."""
    k = np.arange(N // 2 + 1) / order
    return np.fft.irfft(np.fft.rfft(x) * 0.7 / (1 - k**2 + 2j * damping * k), n=N)


def domain(through, n_healthy: int, noise: float, seed: int):
    g = np.random.default_rng(seed)
    X = np.array([through(HEALTHY)] * n_healthy) + g.laplace(scale=noise, size=(n_healthy, N))
    return X


def relative_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_a_resonant_path_read_off_the_healthy_references_carries_over_to_a_fault_burst():
    faults = np.array([HEALTHY + burst(s) for s in (100, 900, 1700)])
    Xs, ys = np.vstack([[HEALTHY] * 20, faults]), np.r_[np.zeros(20), np.ones(3)]
    history = domain(resonance, 120, 0.3, seed=1)
    truth = resonance(faults - HEALTHY)  # what the target would see of the same faults
    h_s, h_t, fir = fit_path(Xs, ys, history, "fir")
    _, _, gain = fit_path(Xs, ys, history, "gain")
    assert np.allclose(h_s, HEALTHY) and relative_error(h_t, resonance(HEALTHY)) < 0.05
    assert len(fir.taps) > 1 and len(gain.taps) == 1
    assert relative_error(fir(faults - h_s), truth) < 0.3
    assert relative_error(gain(faults - h_s), truth) > 0.6  # one number cannot turn a burst into a ringing one


def test_a_path_that_only_scales_is_found_as_a_gain():
    Xs, ys = np.vstack([[HEALTHY] * 20, [HEALTHY + burst(300)]]), np.r_[np.zeros(20), 1]
    history = domain(lambda x: 0.5 * x, 120, 0.3, seed=2)
    _, _, fir = fit_path(Xs, ys, history, "fir")
    assert relative_error(fir(burst(300)), 0.5 * burst(300)) < 0.05


def test_a_reference_without_energy_gives_the_identity():
    """A difference signal is zero on a healthy simulated revolution: there is no path to read."""
    Xs = np.vstack([np.zeros((20, N)), [burst(300)]])
    ys = np.r_[np.zeros(20), 1]
    for kind in ("gain", "fir"):
        assert fit_path(Xs, ys, domain(resonance, 50, 0.3, seed=3), kind)[2] is IDENTITY


def test_an_unknown_kind_is_refused():
    with pytest.raises(ValueError, match="path must be one of"):
        fit_path(np.vstack([[HEALTHY] * 3]), np.zeros(3), domain(resonance, 5, 0.3, seed=4), "spline")


def test_references_whose_lines_do_not_predict_each_other_fall_back_to_the_gain():
    """The same lines with amplitudes and phases drawn at random: no smooth filter maps one
    reference onto the other, so the path is the ratio of their RMS, not a filter fitted to chance."""
    g = np.random.default_rng(5)
    S = np.fft.rfft(HEALTHY)
    scrambled = np.fft.irfft(S * g.uniform(0.2, 2.0, S.shape) * np.exp(2j * np.pi * g.uniform(size=S.shape)), n=N)
    Xs, ys = np.vstack([[HEALTHY] * 20, [HEALTHY + burst(300)]]), np.r_[np.zeros(20), 1]
    history = domain(lambda x: scrambled, 120, 0.3, seed=8)
    _, _, fir = fit_path(Xs, ys, history, "fir")
    _, _, gain = fit_path(Xs, ys, history, "gain")
    assert len(fir.taps) == 1 and fir.taps[0] == gain.taps[0]


def test_medians_of_noise_are_no_reference():
    """Difference signals averaged over revolutions (the PHM rig's corrected source): their
    medians are what is left of the noise, so there is no path to read: the identity."""
    g = np.random.default_rng(6)
    Xs, ys = g.normal(size=(60, N)), np.r_[np.zeros(50), np.ones(10)]
    for kind in ("gain", "fir"):
        assert fit_path(Xs, ys, domain(resonance, 120, 0.3, seed=7), kind)[2] is IDENTITY
        assert (
            fit_path(np.vstack([[HEALTHY] * 20, [burst(3)]]), np.r_[np.zeros(20), 1], g.normal(size=(60, N)), kind)[2]
            is IDENTITY
        )


def test_the_filter_is_fitted_on_one_blas_thread(monkeypatch, blas_threads_as_started):
    """The cross-validation's small solves run on one BLAS thread (numpy's default, a thread per
    core, made a fit 4-11 times slower on busy cores) and the threads are given back afterwards."""
    from threadpoolctl import threadpool_info

    import gearlab.learn.path as path

    def blas_threads() -> list[int]:
        return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]

    seen, fit = [], path._filter
    monkeypatch.setattr(path, "_filter", lambda *args: seen.append(blas_threads()) or fit(*args))
    before = blas_threads()
    Xs, ys = np.vstack([[HEALTHY] * 20, [HEALTHY + burst(300)]]), np.r_[np.zeros(20), 1]
    fit_path(Xs, ys, domain(resonance, 30, 0.3, seed=4), "fir")
    assert seen and all(threads == 1 for threads in seen[0]) and blas_threads() == before
