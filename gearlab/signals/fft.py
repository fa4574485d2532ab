"""FFTs of a long take's whole length, to round-off, where that length has a large prime factor.

A take of R input revolutions of P = 4096 points is R x P samples long; numpy's (and scipy's) pocketfft pass over
a prime factor p of the length at O(N p) where p is under the square root of N (no Bluestein then): a 60 s take's
2399 x 4096 points took 8.4 s an rfft, 36 s a Hilbert transform, against 0.5 s for 2048 x 4096. Split as the
four-step FFT (N = p m, n = m n1 + n2, k = k1 + p k2):

    X[k1 + p k2] = Σ_n2 W_m^(n2 k2) W_N^(n2 k1) Σ_n1 x[m n1 + n2] W_p^(n1 k1),   W_L = exp(-2πi / L),

the length-p transforms of the columns made on their own (a product with the DFT matrix where p is small, MATMUL;
else numpy's, Bluestein's O(p log p) path), then the length-m ones of the rows; a real x's rows k1 > p / 2 follow from
the others (rfft), so that half of them are made.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

# A prime factor of the length at or above this is split off (numpy's own pass over a factor below it is cheap)
SPLIT = 64
# The length-p transforms of the columns as a product with the p x p DFT matrix up to this p, numpy's (Bluestein's)
# above: a matrix product is p^2 multiply-adds a column, but at BLAS's rate; per rfft of 1199 x 4096 points (p = 109)
# 0.17 s of CPU against 0.43 s for numpy's column transforms, equal at p = 599, slower at 2399 (1.9 s against 1.0 s)
MATMUL = 256


def largest_prime(n: int) -> int:
    largest, f = 1, 2
    while f * f <= n:
        while n % f == 0:
            largest, n = f, n // f
        f += 1
    return max(largest, n) if n > 1 else largest


@lru_cache(maxsize=8)
def _dft(p: int, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """(cos, sin) of 2π k1 n1 / p for k1 < *rows*, n1 < p: the first rows of the length-p DFT matrix, W_p^(k1 n1) =
    cos - i sin; the product k1 n1 reduced modulo p first, so that no angle is larger than 2π."""
    angle = (np.arange(rows)[:, None] * np.arange(p)[None, :] % p) * (2 * np.pi / p)
    return np.cos(angle), np.sin(angle)


# A take's transforms come in runs of one length (shaft_averages: a record's spectrum once per slower shaft, over
# the takes of a history): its twiddles are kept, half the rows (the other half from them, _twiddles), 40 MB for
# 1199 x 4096 points
@lru_cache(maxsize=2)
def _half_twiddles(p: int, m: int) -> np.ndarray:
    """W_N^(n2 k1) for k1 <= p / 2, n2 < m (N = p m), the product reduced modulo N first."""
    n = p * m
    table = np.exp((np.arange(p // 2 + 1)[:, None] * np.arange(m)[None, :] % n) * (-2j * np.pi / n))
    table.flags.writeable = False
    return table


def _twiddled(a: np.ndarray, p: int, m: int) -> np.ndarray:
    """*a* (rows k1 = 0 … len(a) - 1 of the column transforms) times W_N^(n2 k1), in place; rows past p / 2 from
    the kept half: W_N^(n2 k1) = W_m^n2 conj(W_N^(n2 (p - k1)))."""
    half = _half_twiddles(p, m)
    h = half.shape[0]
    a[:h] *= half[: len(a)]
    if len(a) > h:
        turn = np.exp(np.arange(m) * (-2j * np.pi / m))
        for k1 in range(h, len(a)):
            a[k1] *= turn * np.conj(half[p - k1])
    return a


def _columns(x: np.ndarray, p: int, m: int, rows: int) -> np.ndarray:
    """The length-p DFTs of the columns of *x* as (p, m), rows k1 < *rows* (MATMUL: by the DFT matrix or numpy's)."""
    cols = x.reshape(p, m)
    if p > MATMUL:
        full = np.fft.fft(cols, axis=0) if np.iscomplexobj(x) or rows > p // 2 + 1 else np.fft.rfft(cols, axis=0)
        return full[:rows]
    cos, sin = _dft(p, rows)
    if np.iscomplexobj(x):  # (C - iS)(u + iv) = Cu + Sv + i(Cv - Su)
        u, v = np.ascontiguousarray(cols.real), np.ascontiguousarray(cols.imag)
        a = np.empty((rows, m), complex)
        a.real = cos @ u
        a.real += sin @ v
        a.imag = cos @ v
        a.imag -= sin @ u
        return a
    a = np.empty((rows, m), complex)
    a.real = cos @ cols
    a.imag = sin @ cols
    a.imag *= -1.0
    return a


def _split(n: int) -> int:
    """The prime factor four-step splits a length *n* at; 1 where numpy's own transform is as fast."""
    p = largest_prime(n) if n > SPLIT else 1
    return 1 if p < SPLIT or p == n else p


def _four_step(x: np.ndarray, rows: int | None = None) -> np.ndarray:
    """The flat *x*'s DFT as rows B[k1, k2] = X[k1 + p k2] for k1 < *rows* (default p), p its length's largest prime
    factor, split off (_split; module doc)."""
    n = x.size
    p = _split(n)
    m = n // p
    a = _twiddled(_columns(x, p, m, p if rows is None else rows), p, m)
    return np.fft.fft(a, axis=1)


def fft(x: np.ndarray) -> np.ndarray:
    """np.fft.fft of the flat *x*, to round-off (module doc)."""
    x = np.asarray(x).reshape(-1)
    if _split(x.size) == 1:
        return np.fft.fft(x)
    return _four_step(x).T.reshape(-1)  # (k1, k2) to k1 + p k2


def ifft(X: np.ndarray) -> np.ndarray:
    """np.fft.ifft of the flat *X*, to round-off: the conjugate of fft of its conjugate, over its length."""
    X = np.asarray(X).reshape(-1)
    return np.conj(fft(np.conj(X))) / X.size


def rfft(x: np.ndarray) -> np.ndarray:
    """np.fft.rfft of the flat real *x*, to round-off. Only the rows k1 <= p / 2 are transformed: the real *x*'s
    X[N - k] = conj(X[k]) gives the others, B[k1, k2] = conj(B[p - k1, m - 1 - k2]) (p odd)."""
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    n = x.size
    p = _split(n)
    if p == 1:
        return np.fft.rfft(x)
    m, h = n // p, p // 2 + 1
    b = _four_step(x, h)
    top = m // 2 + 1  # k2 up to m / 2 holds k up to N / 2
    out = np.empty((top, p), complex)
    out[:, :h] = b[:, :top].T
    out[:, h:] = np.conj(b[p - h : 0 : -1][:, m - 1 - np.arange(top)]).T
    return out.reshape(-1)[: n // 2 + 1]


def analytic(x: np.ndarray) -> np.ndarray:
    """scipy.signal.hilbert of the flat real *x* (its analytic signal), to round-off: its weights are 0 at the
    negative frequencies, so the rfft's half of the spectrum is all it reads."""
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    n = x.size
    half = rfft(x)  # bins 0 … n // 2
    half[1 : (n + 1) // 2] *= 2.0  # the positive frequencies doubled; 0 (and n / 2 where n is even) kept
    spectrum = np.zeros(n, complex)
    spectrum[: half.size] = half
    return ifft(spectrum)
