"""gearlab.signals.fft: a whole take's FFT split at a large prime factor of its length (R revolutions of 4096
points, R prime) gives numpy's and scipy's transforms to round-off, at every length kind: a power of two (numpy's
own), small factors, a prime alone, and a prime times 2^k, even and odd."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import hilbert

from gearlab.signals import fft

# the last: a prime above fft.MATMUL times small factors (its columns by numpy)
LENGTHS = [4096, 3 * 5 * 4096, 2399, 131 * 4096, 131 * 256 * 3, 67 * 101, 2 * 67 * 101, 599 * 64 * 3]


@pytest.mark.parametrize("n", LENGTHS)
def test_the_split_transforms_are_numpy_s_and_scipy_s_to_round_off(n):
    x = np.random.default_rng(n).standard_normal(n)
    X = np.fft.fft(x)
    assert np.max(np.abs(fft.fft(x) - X)) <= 1e-12 * np.max(np.abs(X))
    assert np.max(np.abs(fft.rfft(x) - np.fft.rfft(x))) <= 1e-12 * np.max(np.abs(X))
    assert np.max(np.abs(fft.ifft(X) - x)) <= 1e-12 * np.max(np.abs(x))
    z = hilbert(x)
    assert np.max(np.abs(fft.analytic(x) - z)) <= 1e-12 * np.max(np.abs(z))


def test_a_tone_between_bins_of_a_prime_count_of_revolutions_lands_where_numpy_puts_it():
    # 131 turns of 256 points, a line at order 8.31: the largest bin is the same, its value to round-off
    n = 131 * 256
    x = np.cos(2 * np.pi * 8.31 * np.arange(n) / 256)
    a, b = np.abs(fft.rfft(x)), np.abs(np.fft.rfft(x))
    assert int(np.argmax(a)) == int(np.argmax(b)) == round(8.31 * 131)
    assert a.max() == pytest.approx(b.max(), rel=1e-12)
