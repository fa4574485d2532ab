"""A gap score's features of a source set (gap.scoring.Scorer.features), made hundreds of times a fit: the target's
TSA residual against the source's average is the target's mesh-free rows, made once, less the average's (the residual
is linear in both), where one inverse FFT of every target row was made at each call. The features are those of the
residual made whole each time, to 1e-9 relative."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.gap import views
from gearlab.gap.scoring import Scorer
from gearlab.gap.views import residual_view_of_spectrum

P, PAIR = 4096, (19, 53)


def rows(n: int, seed: int) -> np.ndarray:
    """Revolutions of a 19-tooth mesh with a shaft-order modulation and noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(P) / P
    mesh = sum(np.cos(2 * np.pi * 19 * k * t + k) / k for k in (1, 2, 3))
    shaft = 0.3 * np.cos(2 * np.pi * 3 * t) * np.cos(2 * np.pi * 19 * t)
    return mesh + shaft + 0.05 * rng.standard_normal((n, P)) + 0.02 * rng.standard_normal((n, 1))


@pytest.fixture
def inverse_rows(monkeypatch) -> list[int]:
    """The rows each inverse FFT of the residual views transforms, as they are asked for."""
    counted, irfft = [], np.fft.irfft

    def counting(a, *args, **kwargs):
        counted.append(int(np.prod(np.shape(a)[:-1])))
        return irfft(a, *args, **kwargs)

    monkeypatch.setattr(views.np.fft, "irfft", counting)
    return counted


def test_a_source_sets_features_take_one_row_of_the_targets_residual_not_all(inverse_rows):
    target, source = rows(60, 1), 1.1 * rows(40, 2)
    scorer = Scorer(target, PAIR)
    inverse_rows.clear()
    Fs, Ft, sizes = scorer.features(source)
    assert inverse_rows == [40, 1]  # the source's own residual, and its average's: none of the 60 target rows
    # the target's residual made whole, from its spectrum less the source's average's
    tsa = np.fft.rfft(source, axis=1).mean(axis=0)
    whole = residual_view_of_spectrum(scorer.target_fft - tsa, P, PAIR[0], scorer.target_power).features
    at = sum(sizes[:-2])  # the residual view's columns: after the order views, before the waveform's
    assert np.allclose(Ft[:, at : at + PAIR[0]], whole, rtol=1e-9, atol=0)
    assert Ft.shape == (60, sum(sizes)) and Fs.shape == (40, sum(sizes))
