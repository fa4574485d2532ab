"""Standardisation against the healthy reference (thesis eq. 2.112 and 4.6).

    s_{n|i,j} = (s_{i,j} − s̄_r) / σ_{s_r}                                  (2.112)
    x_{n|i,j} = (x_{i,j} − x̄_r) / σ_{x_r}                                  (4.6)

s̄_r and σ_{s_r} are one scalar mean and one scalar standard deviation pooled over all
values of the reference signal, the healthy case of the same domain (thesis 3.2). Every
sample of that domain, healthy or faulty, is shifted and scaled by the same two numbers,
so fault-induced changes of level and energy survive standardisation.

The thesis leaves the estimator open; gearlab uses the population standard deviation
(divide by N, numpy's default), which for the millions of values of a reference differs
from the N−1 version by far less than float32 resolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import GearlabInputError
from .checks import as_real_array, check_array, check_finite


def _check_std(std: float, what: str) -> None:
    if not math.isfinite(std) or std <= 0.0:
        raise GearlabInputError(
            f"{what} has standard deviation {std:g}; expected a positive finite value to standardise against "
            "(eq. 2.112: the healthy reference must vary)"
        )


@dataclass(frozen=True)
class Standardiser:
    """x -> (x − mean) / std, with the mean and std of the healthy reference (eq. 2.112/4.6)."""

    mean: float
    std: float

    def __post_init__(self):
        if not math.isfinite(self.mean):
            raise GearlabInputError(f"standardiser mean is {self.mean}; expected a finite number")
        _check_std(self.std, "standardiser")

    @classmethod
    def fit(cls, reference: np.ndarray) -> Standardiser:
        """Scalar mean s̄_r and standard deviation σ_{s_r} pooled over all values of *reference*."""
        ref = check_array(reference, "reference")
        mean = float(np.mean(ref))
        std = float(np.std(ref))  # two-pass in float64: mean first, then squared deviations
        # Equal values can leave a rounding-level std (the mean is rounded); test equality itself.
        if ref.min() == ref.max():
            raise GearlabInputError(
                f"reference has zero variance (all {ref.size} values equal {mean:g}); "
                "cannot standardise against it (eq. 2.112)"
            )
        _check_std(std, "reference")
        return cls(mean, std)

    def apply(self, x: np.ndarray) -> np.ndarray:
        """(x − mean) / std, computed in float64 and returned as float32 (the dataset dtype)."""
        arr = as_real_array(x, "signal to standardise")
        check_finite(arr, "signal to standardise")
        return ((arr - self.mean) / self.std).astype(np.float32)


@dataclass
class StandardiserAccumulator:
    """Streaming fit: feed the reference block by block, get the same Standardiser as fit.

    Each block contributes its count n_b, mean μ_b and sum of squared deviations M2_b
    (two-pass within the block); blocks are merged with the parallel update of
    Chan, Golub & LeVeque (1979),

        δ = μ_b − μ_a,   n = n_a + n_b,   μ = μ_a + δ·n_b/n,   M2 = M2_a + M2_b + δ²·n_a·n_b/n,

    which, unlike accumulating Σx and Σx², does not lose the variance to cancellation when
    the mean is large compared with the spread. σ² = M2/n at the end.
    """

    n: int = 0
    mean: float = 0.0
    m2: float = 0.0
    low: float = math.inf
    high: float = -math.inf

    def add(self, block: np.ndarray) -> StandardiserAccumulator:
        """Merge the values of *block* (any shape); returns self so calls can be chained."""
        b = check_array(block, "reference block")
        n_b = b.size
        mean_b = float(np.mean(b))
        m2_b = float(np.sum((b - mean_b) ** 2))
        n = self.n + n_b
        delta = mean_b - self.mean
        self.mean += delta * n_b / n
        self.m2 += m2_b + delta * delta * self.n * n_b / n
        self.n = n
        self.low, self.high = min(self.low, float(b.min())), max(self.high, float(b.max()))
        return self

    def result(self) -> Standardiser:
        """The Standardiser of all values added so far."""
        if self.n == 0:
            raise GearlabInputError("no reference values were added; cannot standardise against nothing")
        std = math.sqrt(self.m2 / self.n)
        if self.low == self.high:
            raise GearlabInputError(
                f"reference has zero variance (all {self.n} values equal {self.mean:g}); "
                "cannot standardise against it (eq. 2.112)"
            )
        return Standardiser(self.mean, std)
