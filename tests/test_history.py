"""Thresholds from an unlabelled history (gearlab.learn.history): what a history's scores fix."""

import numpy as np
import pytest

from gearlab.learn.history import gumbel_quantile, history_threshold


def gumbel_scores(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).gumbel(loc=2.0, scale=0.5, size=n)


def test_a_healthy_history_keeps_its_threshold():
    """Removing a healthy history's top ~1 % leaves its quartiles, so the threshold barely moves."""
    for seed in range(5):
        s = gumbel_scores(120, seed)
        plain, refit = gumbel_quantile(s, 0.99), history_threshold(s, 0.99)
        assert refit <= plain
        assert refit == pytest.approx(plain, rel=0.03)


def test_unlabelled_faults_in_the_history_do_not_raise_the_threshold():
    """16 of 120 history scores from faults far above the healthy ones: the plain fit's quartiles
    widen and its threshold rises; the refit comes back to the healthy history's threshold."""
    healthy = gumbel_scores(104, 1)
    faults = np.random.default_rng(2).uniform(8.0, 20.0, size=16)
    mixed = np.concatenate([healthy, faults])
    alone = gumbel_quantile(gumbel_scores(120, 1), 0.99)
    assert gumbel_quantile(mixed, 0.99) > alone * 1.15
    assert history_threshold(mixed, 0.99) == pytest.approx(alone, rel=0.08)


def test_the_false_alarm_rate_asked_holds_on_new_healthy_scores():
    """Over many histories of 120 healthy scores, the share of new healthy scores above the
    refitted threshold is the one asked (1 %; 10 %)."""
    new = gumbel_scores(200_000, 99)
    for p in (0.99, 0.9):
        rates = [np.mean(new > history_threshold(gumbel_scores(120, seed), p)) for seed in range(200)]
        assert np.mean(rates) == pytest.approx(1 - p, rel=0.35)


def test_the_noise_law_is_read_without_scipy_stats():
    """A history's kurtosis is scipy.stats.kurtosis's figure to the bit, and reading it loads no
    scipy.stats (1.8 s of every worker that calibrated a unit; issue 42)."""
    import subprocess
    import sys

    from scipy.stats import kurtosis as scipy_kurtosis

    from gearlab.learn.history import kurtosis

    rng = np.random.default_rng(0)
    for x in (rng.normal(size=(40, 512)), 3.0 * rng.laplace(size=(9, 77)) + 2.0, rng.standard_t(2, size=999)):
        assert kurtosis(x) == float(scipy_kurtosis(x.ravel(), fisher=False))
    assert np.isnan(kurtosis(np.ones(10)))
    code = (
        "import sys, numpy as np; from gearlab.learn.history import noise_law; "
        "print(noise_law(np.random.default_rng(1).laplace(size=(20, 256))), 'scipy.stats' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["laplace", "False"]
