"""signals.fixed_lines.clock_share: whether a line's phase follows the shaft or the clock."""

from __future__ import annotations

import warnings

import numpy as np

from gearlab.signals import fixed_lines

FS = 5000.0


def take(speed_hz: float, swing: float, clock_hz: float | None = None, seconds: float = 4.0):
    """A shaft whose speed swings by *swing* (relative, 0.5 Hz), its 3rd order; or a line at *clock_hz* (Hz)."""
    t = np.arange(int(seconds * FS)) / FS
    angle = 2 * np.pi * speed_hz * (t + swing * np.sin(2 * np.pi * 0.5 * t) / (2 * np.pi * 0.5))
    line = np.sin(3 * angle) if clock_hz is None else np.sin(2 * np.pi * clock_hz * t)
    noise = 0.05 * np.random.default_rng(0).normal(size=t.size)
    return line + noise, angle


def test_a_shaft_order_follows_the_shaft_and_a_fixed_line_the_clock():
    signal, angle = take(25.0, 0.02)
    slope, _ = fixed_lines.clock_share(signal, FS, angle, 3.0)
    assert abs(slope) < 0.1
    signal, angle = take(25.0, 0.02, clock_hz=75.0)
    slope, _ = fixed_lines.clock_share(signal, FS, angle, 3.0)
    assert abs(slope - 1.0) < 0.1


def test_a_variance_rounded_below_zero_is_no_reading_and_no_warning(monkeypatch):
    """Where the speed barely wanders, the fit's inverse can round its variance below zero: `gearlab score`'s
    other-gearbox check printed numpy's 'invalid value encountered in sqrt' under every take. No reading, silently."""
    signal, angle = take(25.0, 0.02)
    inverse = np.linalg.inv
    monkeypatch.setattr(fixed_lines.np.linalg, "inv", lambda a: -np.abs(inverse(a)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert fixed_lines.clock_share(signal, FS, angle, 3.0) is None
