"""Guesses a diagnosis reads off the target: a line below one shaft order from consecutive revolutions."""

import numpy as np
import pytest

from gearlab.registry import get_registry

SPEED, N, ROWS = 40.0, 4096, 80


def test_a_sub_order_tone_is_placed_from_consecutive_revolutions():
    """A 37.3 Hz neighbour at a 40 Hz shaft: one revolution holds less than one of its periods, so
    the per-revolution spectrum places it within a whole order only; 80 consecutive revolutions of
    a measured record resolve 0.25 Hz, and the diagnosis tries that guess too."""
    tone = get_registry().get("effect", "interference_tone")
    t = np.arange(ROWS * N) / (N * SPEED)
    rng = np.random.default_rng(0)
    x = (
        np.sin(2 * np.pi * 25 * SPEED * t)
        + 0.3 * np.sin(2 * np.pi * 37.3 * t + 1.0)
        + 0.1 * rng.standard_normal(t.size)
    ).reshape(ROWS, N)
    frequencies = [g["frequency"] for g in tone.guesses(x, SPEED)]
    assert min(abs(f - 37.3) for f in frequencies) < 0.2
    assert abs(frequencies[0] - 37.3) > 1.0  # the one-revolution guess alone could not place it


def test_a_tone_above_one_order_keeps_one_guess():
    tone = get_registry().get("effect", "interference_tone")
    t = np.arange(ROWS * N) / (N * SPEED)
    x = (np.sin(2 * np.pi * 25 * SPEED * t) + 0.3 * np.sin(2 * np.pi * 1234.5 * t)).reshape(ROWS, N)
    guesses = tone.guesses(x, SPEED)
    assert len(guesses) == 1 and guesses[0]["frequency"] == pytest.approx(1234.5, abs=1.0)
