"""A slower shaft's turns read from consecutive input revolutions (signals.shaft.shaft_averages, the which-gear
localiser's per-shaft TSAs): linear interpolation between the revolutions' own samples left an image of each line,
and where the shaft turns 1/q times per input turn every turn repeats the reading grid, so the image survives the
average (issue 39 item 2): the PHM 2009 rig's idler (1/3) read a 3rd mesh harmonic's image 43 dB below it. Read
band-limited 2 x denser, cubic (signals.shaft.read_at, shaft_revolutions' own reading), it falls below -100 dB;
the input shaft's turns, on the samples themselves, are read exactly as before."""

from __future__ import annotations

from fractions import Fraction
from types import SimpleNamespace

import numpy as np
import pytest

from gearlab.signals.shaft import shaft_averages

P = 4096


def _mean(y: np.ndarray, o: Fraction, index: list[int], R: int) -> np.ndarray:
    lay = SimpleNamespace(
        points=P,
        shafts=("input", "shaft"),
        shaft_orders=(Fraction(1), o),
        orders=np.array([float(i * o) for i in index]),
        source=np.ones(len(index), int) if o != 1 else np.zeros(len(index), int),
        index=np.array(index),
    )
    mean, _, _ = shaft_averages(y.reshape(-1), lay, 0, R, 0)
    return np.abs(mean)


@pytest.mark.parametrize(("q", "k", "image"), [(3, 288, 4960), (3, 96, 4384), (7, 63, 4537)])
def test_a_1_over_q_shaft_s_image_stays_far_below_its_line(q, k, image):
    # the image of input order k (shaft order q k) in the turns of a shaft at 1/q, cut into `size` points a turn
    # (the power of two at or above q P): shaft order size - q (P - k)
    R = 12 * q
    u = np.arange(R * P) / P
    y = np.cos(2 * np.pi * k * u + 0.3)
    line, ghost = _mean(y, Fraction(1, q), [q * k, image], R)
    assert 20 * np.log10(ghost / line) < -100


def test_the_input_shaft_is_read_on_its_samples():
    R = 8
    y = np.random.default_rng(0).standard_normal(R * P)
    mean = _mean(y, Fraction(1), [5, 17, 300], R)
    expected = np.abs((np.fft.rfft(y.reshape(R, P), axis=1)[:, :301] * (2.0 / P)).mean(axis=0)[[5, 17, 300]])
    np.testing.assert_array_equal(mean, expected)


@pytest.mark.parametrize(("top", "bound"), [(0.05, 1e-5), (0.15, 1e-3), (0.3, 6e-3)])
def test_a_reading_between_samples_is_the_band_limited_wave_s(top, bound):
    # read_at against the wave's own sum of cosines at positions anywhere, past both ends included (periodic in n):
    # the cubic step on a 2 x denser grid, 3e-6, 3e-4, 4e-3 of the wave's rms for lines up to *top* cycles a
    # sample; the linear step on a 4 x denser one was 2e-4, 2e-3, 9e-3
    from gearlab.signals.shaft import read_at

    rng = np.random.default_rng(0)
    n = 6000
    spectrum = np.fft.rfft(rng.standard_normal(n))
    spectrum[int(top * n) :] = 0.0
    at = rng.uniform(-n, 2 * n, 2000)
    k = np.arange(spectrum.size)
    weight = np.where((k == 0) | (k == n // 2), 1.0, 2.0) / n
    exact = np.real((spectrum * weight) * np.exp(2j * np.pi * np.outer(at, k) / n)).sum(axis=1)
    read = read_at(spectrum, n, at.reshape(40, 50)).reshape(-1)
    assert np.sqrt(np.mean((read - exact) ** 2)) < bound * np.sqrt(np.mean(exact**2))
    assert np.isnan(read_at(spectrum, n, np.array([np.nan, np.inf]))).all()  # never an index from either
