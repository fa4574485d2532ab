"""What an unlabelled healthy history tells about its domain: the law of its noise, and a
threshold on any score that lets a chosen share of healthy revolutions through.

Both are read off data that may hold a few unlabelled faults (k of the 120 target training
revolutions): the noise law from the kurtosis of the residuals pooled over the history, the
threshold from the quartiles of the history's scores, refitted without those it finds to be faults.
"""

from __future__ import annotations

import numpy as np

NOISE_LAWS = ("gaussian", "laplace", "student_t")  # the thesis's noise laws (4.1.1)
# Kurtosis (Pearson) between the laws' own: Gaussian 3 | Laplace 6 | Student-t(2) unbounded.
_KURTOSIS_SPLITS = (4.5, 12.0)


def gumbel_quantile(scores: np.ndarray, p: float) -> float:
    """The *p* quantile of the Gumbel law (of maxima) whose quartiles are those of *scores*:
    F(s) = exp(-exp(-(s - mu) / beta)), so the q quantile is mu - beta ln(-ln q)."""
    q1, q3 = np.quantile(scores, [0.25, 0.75])
    beta = (q3 - q1) / (np.log(np.log(4.0)) - np.log(np.log(4.0 / 3.0)))
    mu = q1 + beta * np.log(np.log(4.0))
    return float(mu - beta * np.log(-np.log(p)))


def history_threshold(scores: np.ndarray, p: float) -> float:
    """`gumbel_quantile` of a history's *scores*, refitted without the scores it finds to be
    faults: those above the threshold beyond the (1 - p) share of healthy ones expected there,
    the highest first, until that count stops growing. Why: the faults a history may hold
    unlabelled score above the healthy ones and widen the quartiles (Experiment B, k = 16 of
    120: `likelihood_ratio` 87.7 % plain, 88.6 % refitted, 5 repetitions); a healthy history has about the
    expected share above, so it keeps its threshold (k = 0: the same accuracy to the digit)."""
    s = np.sort(np.asarray(scores, dtype=np.float64))
    n, faults = len(s), 0
    threshold = gumbel_quantile(s, p)
    while n - faults >= 4:
        above = int(np.sum(s > threshold)) - (1.0 - p) * (n - faults)
        more = max(faults, int(np.floor(above)))
        if more == faults:
            break
        faults = more
        threshold = gumbel_quantile(s[: n - faults], p)
    return threshold


def noise_law(residuals: np.ndarray) -> str:
    """The noise law whose kurtosis is nearest that of the pooled history residuals."""
    return NOISE_LAWS[int(np.searchsorted(_KURTOSIS_SPLITS, kurtosis(residuals)))]


def kurtosis(x: np.ndarray) -> float:
    """Pearson's kurtosis m4 / m2^2 of all of *x* (biased central moments), NaN where the variance
    is lost in rounding: scipy.stats.kurtosis(x.ravel(), fisher=False)'s steps, without importing
    scipy.stats, which took 1.8 s of every worker process that calibrates a unit (issue 42)."""
    x = np.asarray(x, dtype=np.float64).ravel()
    mean = x.mean()
    squares = (x - mean) ** 2
    m2, m4 = squares.mean(), (squares**2).mean()
    with np.errstate(all="ignore"):
        return float("nan") if m2 <= (np.finfo(np.float64).eps * mean) ** 2 else float(m4 / m2**2.0)
