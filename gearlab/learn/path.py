"""The transfer path between two domains, read off their healthy references (beyond the thesis).

A simulator and the gearbox it stands for differ, among other things, in how the mesh's
vibration reaches the sensor: a housing instead of the pinion (Dataset A's casing path), other
drive inertias (Experiment B). Where that difference is linear and time invariant it acts on a
fault's response exactly as on the healthy mesh signal: with ``s`` the source's healthy
revolution and ``t`` the target's, ``t = g ⊛ s`` and a source fault shape ``a`` reaches the
target as ``g ⊛ a`` (⊛: circular convolution; a revolution is periodic). In the order domain
(discrete Fourier transform over one revolution, bin k = order k)

    T(k) = G(k) · S(k),       G(k) = Σ_j g_j · exp(-2πi·k·j / N),   j = j0 … j0 + L - 1     (1)

The healthy references give G only at their *lines*, the orders that carry their energy (the
mesh harmonics and their sidebands); between the lines they say nothing. A short filter (L
taps) cannot change its response faster than about N / L orders, so it interpolates between the
lines smoothly; its length and a ridge weight λ are chosen by cross-validation over the lines
themselves: fit (1) by least squares on four fifths of the lines, predict the held-out fifth's
complex amplitudes, and keep the (L, j0, λ) that predicts best (j0: the lags centred on zero,
or mostly after it, for a path that rings on after the mesh's impulse). That rewards exactly what the fault
shapes need, the response between the lines, and uses nothing but the two healthy references
(the source's healthy training revolutions and the target's unlabelled history). L = 1 is a
scalar gain, so one number is among the candidates. (The cross-validation over revolutions
instead, fitting one half of the history's median and predicting the other's, prefers the
longest filter: it measures the lines, which a long filter fits, not the orders between them,
where it is then free to ring.) A reference whose energy is not in lines (they take over a
quarter of the orders), or a filter that predicts less than half the held-out lines' energy,
finds no common path (two references of noise, say): the path is then the gain.

Measured (docs/learning.md, decision 19; repetition 0, k = 0): the simulator's shapes through
the fitted path lift ``likelihood_ratio`` from 67 % (the gain) to 89 % on Experiment A, where
the target's own shapes give 88.5 %, and from 85 to 88.5 % on B.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

PATHS = ("gain", "fir")  # the ratio of the references' RMS (one number), or the filter (1)
LENGTHS = (1, 9, 17, 33, 65, 129, 257)  # candidate filter lengths L (taps)
LEADS = (0.5, 0.125)  # share of the taps before lag 0: centred, or mostly causal (a path that rings after)
RIDGES = (1e-4, 1e-3, 1e-2, 1e-1)  # candidate λ, relative to the mean diagonal of the normal equations
LINE_ENERGY = 0.999  # the lines: the fewest order bins holding this share of the source reference's energy
FOLDS = 5  # cross-validation folds over the lines (interleaved)
SIGNAL = 10.0  # a reference is a signal when its energy is this many times a noise median's (10 dB)
COHERENT = 0.5  # a filter must predict the held-out lines to within this share of their energy


@dataclass(frozen=True)
class Path:
    """A filter g on lags ``lags`` (samples), applied circularly along the last axis."""

    lags: np.ndarray
    taps: np.ndarray

    def __call__(self, X: np.ndarray) -> np.ndarray:
        X = np.asarray(X, dtype=np.float64)
        if len(self.taps) == 1 and self.lags[0] == 0:
            return self.taps[0] * X
        n = X.shape[-1]
        kernel = np.zeros(n)
        np.add.at(kernel, self.lags % n, self.taps)
        return np.fft.irfft(np.fft.rfft(X, axis=-1) * np.fft.rfft(kernel), n=n, axis=-1)


IDENTITY = Path(np.zeros(1, dtype=int), np.ones(1))  # lag 0, tap 1


def _lags(length: int, lead: float) -> np.ndarray:
    """*length* lags, the share *lead* of them before zero."""
    first = -int(round(lead * (length - 1)))
    return np.arange(first, first + length)


def _design(S: np.ndarray, bins: np.ndarray, n: int, lags: np.ndarray) -> np.ndarray:
    """The matrix of (1): G(k)·S(k) = Σ_j g_j · S(k) · exp(-2πi·k·j / N) on the order *bins*."""
    return np.exp(-2j * np.pi * np.outer(bins, lags) / n) * S[bins, None]


def _fit(S: np.ndarray, T: np.ndarray, bins: np.ndarray, n: int, lags: np.ndarray, ridge: float) -> np.ndarray:
    """Ridge least-squares taps of (1) on the order *bins* (real and imaginary parts stacked)."""
    A = _design(S, bins, n, lags)
    A = np.vstack([A.real, A.imag])
    b = np.concatenate([T[bins].real, T[bins].imag])
    G = A.T @ A
    return np.linalg.solve(G + ridge * np.trace(G) / len(lags) * np.eye(len(lags)), A.T @ b)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x, dtype=np.float64))))


def _is_signal(rows: np.ndarray, median: np.ndarray) -> bool:
    """Whether the median of *rows* holds a signal rather than what is left of their noise: its
    energy must stand SIGNAL times above the energy a median of pure noise keeps, about
    (π/2)·mean ||x - median||² / n for n rows (the sample median's variance, π/2 that of the mean).
    A median of difference signals (zero by construction, or averaged noise) is not a signal."""
    energy = float(np.sum(median**2))
    spread = float(np.mean(np.sum((rows - median) ** 2, axis=1)))
    return energy > 0.0 and energy > SIGNAL * (np.pi / 2) * spread / len(rows)


def fit_path(
    Xs: np.ndarray, ys: np.ndarray, target_healthy: np.ndarray, kind: str = "fir"
) -> tuple[np.ndarray, np.ndarray, Path]:
    """The two domains' healthy references (the medians of the source's healthy revolutions,
    rows of *Xs* where *ys* is 0, and of *target_healthy*, on the same angular grid) and the
    path between them:
    ``gain`` the ratio of their RMS (one number: a fault of the same relative size has the same
    size in both domains), ``fir`` the filter of (1) with its length and ridge chosen by
    cross-validation over the lines. A reference that is no signal (:func:`_is_signal`), e.g.
    of a difference signal, which removes the synchronous signal by construction, measures
    nothing: the path is then the identity rather than a ratio of two noises."""
    if kind not in PATHS:
        raise ValueError(f"path must be one of {PATHS}, got {kind!r}")
    Xs = np.asarray(Xs, dtype=np.float64)
    target_healthy = np.asarray(target_healthy, dtype=np.float64)
    source_healthy = Xs[np.asarray(ys) == 0]
    s, t = np.median(source_healthy, axis=0), np.median(target_healthy, axis=0)
    if not (_is_signal(source_healthy, s) and _is_signal(target_healthy, t)):
        return s, t, IDENTITY
    gain = Path(np.zeros(1, dtype=int), np.array([_rms(t) / _rms(s)]))
    if kind == "gain":
        return s, t, gain
    key = hashlib.blake2b(s.tobytes() + t.tobytes(), digest_size=16).digest()
    if key not in _FITTED:  # every method of a (repetition, k) asks for the same path
        if len(_FITTED) >= 64:
            _FITTED.pop(next(iter(_FITTED)))
        from threadpoolctl import threadpool_limits  # loaded by a fit only (start-up time)

        # ~600 small solves: on one BLAS thread, as the unit's torch; numpy's own default (a
        # thread per core, waiting on each other) made a fit 4-11 times slower on 2 busy cores
        # (1.97-4.71 s against 0.41-0.47 s, Experiment B's references), with the same taps
        with threadpool_limits(1, user_api="blas"):
            _FITTED[key] = _filter(s, t, gain)
    return s, t, _FITTED[key]


_FITTED: dict[bytes, Path] = {}


def _filter(s: np.ndarray, t: np.ndarray, gain: Path) -> Path:
    """The filter of (1) from reference *s* to *t*, cross-validated over the lines; *gain* where
    the lines do not give one."""
    n = len(s)
    S, T = np.fft.rfft(s), np.fft.rfft(t)
    power = np.abs(S) ** 2
    order = np.argsort(-power, kind="stable")
    lines = np.sort(order[: int(np.searchsorted(np.cumsum(power[order]) / power.sum(), LINE_ENERGY)) + 1])
    if len(lines) > len(S) // 4:  # a broadband reference (noise) has no lines to read a path off
        return gain
    folds = [lines[f::FOLDS] for f in range(FOLDS)]
    best, best_error = (_lags(1, 0.0), RIDGES[0]), np.inf
    for length in LENGTHS:
        if 2 * (len(lines) - len(folds[0])) < length:  # fewer equations than taps: not determined
            break
        for lags in dict.fromkeys(tuple(_lags(length, lead)) for lead in LEADS):  # L = 1: one
            for ridge in RIDGES:
                error = 0.0
                for held in folds:
                    taps = _fit(S, T, np.setdiff1d(lines, held), n, np.array(lags), ridge)
                    error += float(np.sum(np.abs(T[held] - _design(S, held, n, np.array(lags)) @ taps) ** 2))
                if error < best_error:
                    best, best_error = (np.array(lags), ridge), error
    if best_error > COHERENT * float(np.sum(np.abs(T[lines]) ** 2)):
        return gain  # the lines do not predict each other: no linear path links the references
    return Path(best[0], _fit(S, T, lines, n, *best))
