"""FFTs of a long take's whole length, to round-off, where that length has a large prime factor.

A take of R input revolutions of P = 4096 points is R x P samples long; numpy's (and scipy's) pocketfft pass over
a prime factor p of the length at O(N p) where p is under the square root of N (no Bluestein then): a 60 s take's
2399 x 4096 points took 8.4 s an rfft, 36 s a Hilbert transform, against 0.5 s for 2048 x 4096. Split as the
four-step FFT (N = p m, n = m n1 + n2, k = k1 + p k2):

    X[k1 + p k2] = Σ_n2 W_m^(n2 k2) W_N^(n2 k1) Σ_n1 x[m n1 + n2] W_p^(n1 k1),   W_L = exp(-2πi / L),

the length-p transforms are made on their own (Bluestein's O(p log p) path) and the length-m ones on the columns.
"""

from __future__ import annotations

import numpy as np

# A prime factor of the length at or above this is split off (numpy's own pass over a factor below it is cheap)
SPLIT = 64


def _largest_prime(n: int) -> int:
    largest, f = 1, 2
    while f * f <= n:
        while n % f == 0:
            largest, n = f, n // f
        f += 1
    return max(largest, n) if n > 1 else largest


def _four_step(x: np.ndarray) -> np.ndarray | None:
    """The flat *x*'s DFT as (p, m) rows B[k1, k2] = X[k1 + p k2], p its length's largest prime factor (module
    doc); None where p is under SPLIT or the length itself (numpy's own is as fast)."""
    n = x.size
    p = _largest_prime(n) if n > SPLIT else 1
    if p < SPLIT or p == n:
        return None
    m = n // p
    a = np.fft.fft(x.reshape(p, m), axis=0)  # (k1, n2)
    step = np.arange(m) / n
    for k1 in range(1, p):  # the twiddles W_N^(n2 k1), a row at a time: no (p, m) array of them
        a[k1] *= np.exp(-2j * np.pi * k1 * step)
    return np.fft.fft(a, axis=1)


def fft(x: np.ndarray) -> np.ndarray:
    """np.fft.fft of the flat *x*, to round-off (module doc)."""
    x = np.asarray(x).reshape(-1)
    b = _four_step(x)
    return np.fft.fft(x) if b is None else b.T.reshape(-1)  # (k1, k2) to k1 + p k2


def ifft(X: np.ndarray) -> np.ndarray:
    """np.fft.ifft of the flat *X*, to round-off: the conjugate of fft of its conjugate, over its length."""
    X = np.asarray(X).reshape(-1)
    return np.conj(fft(np.conj(X))) / X.size


def rfft(x: np.ndarray) -> np.ndarray:
    """np.fft.rfft of the flat real *x*, to round-off."""
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    b = _four_step(x)
    if b is None:
        return np.fft.rfft(x)
    return b[:, : b.shape[1] // 2 + 1].T.reshape(-1)[: x.size // 2 + 1]  # k2 to m / 2 hold k to N / 2


def analytic(x: np.ndarray) -> np.ndarray:
    """scipy.signal.hilbert of the flat real *x* (its analytic signal), to round-off."""
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    n = x.size
    h = np.zeros(n)
    h[0] = 1.0
    if n % 2 == 0:
        h[n // 2] = 1.0
        h[1 : n // 2] = 2.0
    else:
        h[1 : (n + 1) // 2] = 2.0
    return ifft(fft(x) * h)
