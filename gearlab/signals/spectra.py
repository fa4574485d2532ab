"""One-sided amplitude spectra in frequency (Hz) and in shaft orders (thesis Figures 2.36–2.39).

Amplitude scaling: a component A·cos(2π f t + φ) appears as a peak of height A. For a
window w[n] the DFT of that component peaks at A·Σw/2, hence

    amplitude[k] = 2 |X[k]| / Σ w[n],   except at DC and Nyquist, where it is |X[k]| / Σ w[n].

In time (:func:`spectrum`) a Hann window keeps leakage from the strong mesh harmonics off
their weak sidebands; a tone between bins then reads up to 15 % low (scalloping), exact
on a bin. In angle (:func:`order_spectrum`) the samples are whole revolutions, so shaft
orders fall exactly on bins and no window is needed.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .checks import check_array, check_int, check_positive
from .fft import largest_prime, rfft

# numpy takes the FFT of a length with a large prime factor r by a generic radix-r pass, some n r operations: a
# history of 4793 revolutions of 4096 points (19.6 M, 4793 prime; gap.structure's check of a three-stage box's
# takes) took 37-43 s on two busy cores, 2^24 points 4 s. A signal whose length has a prime factor of at least
# SPLIT_PRIME goes through gearlab.signals.fft's four-step rfft instead (1.9 s of CPU there), equal to rounding
# (1e-15 of the largest amplitude; the same lines found, gearbox.speed.find_lines); shorter factors keep numpy's
# own transform, bit for bit.
SPLIT_PRIME = 1000


def _rfft(x: np.ndarray) -> np.ndarray:
    """np.fft.rfft along the last axis; a 1-D signal whose length has a prime factor of SPLIT_PRIME or more by
    gearlab.signals.fft.rfft (not a prime length itself: numpy takes that by Bluestein's chirp)."""
    if x.ndim == 1 and x.size >= 2 * SPLIT_PRIME and SPLIT_PRIME <= largest_prime(x.size) < x.size:
        return rfft(x)
    return np.fft.rfft(x, axis=-1)


def _one_sided_amplitude(x: np.ndarray, window: np.ndarray) -> np.ndarray:
    n = x.shape[-1]
    amp = np.abs(_rfft(x * window)) * (2.0 / window.sum())
    amp[..., 0] /= 2.0  # DC has no negative-frequency twin
    if n % 2 == 0:
        amp[..., -1] /= 2.0  # neither has the Nyquist bin of an even length
    return amp


def spectrum(signal: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(freq_hz, amplitude): Hann-windowed one-sided amplitude spectrum along the last axis."""
    x = check_array(signal, "signal")
    fs = check_positive(fs, "sampling rate fs", "Hz")
    n = x.shape[-1]
    return np.fft.rfftfreq(n, d=1.0 / fs), _one_sided_amplitude(x, hann(n))


@lru_cache(maxsize=16)
def hann(n: int) -> np.ndarray:
    """The periodic ("DFT-even") Hann window of *n* samples, its coherent gain Σw/n exactly 1/2 (n > 1); made
    once a length (read-only): a record's spectra are taken again and again at its length (inspect, the
    speed's search, the gap's structure check), and its cosine cost as much as the spectrum's multiply."""
    window = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n) if n > 1 else np.ones(1)
    window.flags.writeable = False
    return window


def order_spectrum(revolution_samples: np.ndarray, per_revolution: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(orders, amplitude): one-sided amplitude spectrum of angle-domain samples, in shaft orders.

    An order is one cycle per input-shaft revolution: sin(25·θ) peaks at order 25, the
    pinion mesh of a Z1-tooth pinion at order Z1. By default the last axis is exactly one
    revolution (a resampled revolution or a TSA), giving integer orders 0 … P/2. Pass
    *per_revolution* = P for a last axis of several concatenated revolutions (e.g.
    ``revs.reshape(-1)``) to resolve orders in steps of 1/R (the output shaft's orders
    Z1/Z2·k are not integers of the input shaft).
    """
    x = check_array(revolution_samples, "angle-domain samples")
    n = x.shape[-1]
    per_rev = n if per_revolution is None else check_int(per_revolution, "points per revolution", minimum=1)
    orders = np.fft.rfftfreq(n, d=1.0 / per_rev)
    return orders, _one_sided_amplitude(x, np.ones(n))
