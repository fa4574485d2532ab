"""One band-limited upsampler (gearlab.signals.upsampled) for every reading of a record at uniform angle:
`gearlab inspect`'s order spectrum and the speed followed through a record without a tacho
(gearbox.speed.follow_speed) raised the rate 8 times each with their own code."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

import gearlab.signals.pipeline as pipeline
from gearlab.signals import upsampled

PACKAGE = Path(__file__).resolve().parent.parent / "gearlab"


def test_one_module_upsamples():
    users = sorted(
        str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py") if re.search(r"\bresample_poly\b", p.read_text())
    )
    assert users == ["signals/pipeline.py"]


def test_upsampled_interpolates_band_limited():
    n, nu = 4000, 0.37  # a line at 0.37 cycles per sample
    x = np.cos(2 * np.pi * nu * np.arange(n))
    fine = upsampled(x)
    assert fine.up == 8 and fine.signal.size == (n - 1) * 8 + 1  # nothing past the last sample
    exact = np.cos(2 * np.pi * nu * np.arange(fine.signal.size) / 8)
    middle = slice(800, -800)  # the filter's edges aside
    assert np.max(np.abs(fine.signal[middle] - exact[middle])) < 5e-3  # the filter's pass-band ripple
    np.testing.assert_allclose(fine.signal[::8][100:-100], x[100:-100], atol=5e-3)
    # linear interpolation between the record's own samples is off by about (ν / (1 - ν))² of the line
    linear = np.interp(np.arange(fine.signal.size) / 8, np.arange(n), x)
    assert np.max(np.abs(linear[middle] - exact[middle])) > 0.3


def test_angle_at_the_upsampled_samples():
    angle = np.cumsum(np.full(1001, 0.01)) + 0.02 * np.sin(np.arange(1001) / 50)
    fine = upsampled(np.sin(angle))
    at = fine.at(angle)
    assert at.size == fine.signal.size
    np.testing.assert_array_equal(at[::8], angle)
    np.testing.assert_allclose(at[4::8], 0.5 * (angle[:-1] + angle[1:]), rtol=0, atol=1e-15)


def test_a_long_record_is_raised_less(monkeypatch):
    monkeypatch.setattr(pipeline, "MAX_UPSAMPLED", 3000)
    x = np.random.default_rng(0).standard_normal(1000)
    assert upsampled(x).up == 3
    monkeypatch.setattr(pipeline, "MAX_UPSAMPLED", 1500)
    one = upsampled(x)
    assert one.up == 1 and one.signal is x
    angle = np.arange(1000.0)
    assert one.at(angle) is angle
