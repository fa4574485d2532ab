"""signals.shaft.shaft_averages reads each shaft's average at the record's samples once per average (and
per mask of the orders a slower shaft shares with a faster one), not once per shaft subtracting it, and
no turns twice: the readings (an inverse FFT several times the record's length and an interpolation at
every sample) were most of a localisation's time. A record of one line per shaft, at each shaft's own
3rd order, read back at its amplitude."""

from __future__ import annotations

import hashlib
from fractions import Fraction
from types import SimpleNamespace

import numpy as np
import pytest

from gearlab.signals import shaft

POINTS = 256
ORDERS = (Fraction(1), Fraction(2, 5), Fraction(4, 25))  # the input, intermediate and output shafts' speeds
AMPLITUDE = (1.0, 0.7, 0.4)  # each shaft's line at its own 3rd order


def record(R: int = 50) -> tuple[np.ndarray, SimpleNamespace]:
    """R input revolutions of one line per shaft plus noise (flat), and the Layout reading them."""
    u = np.arange(R * POINTS) / POINTS  # input turns
    rng = np.random.default_rng(3)
    y = sum(a * np.cos(2 * np.pi * 3 * float(o) * u + 0.3) for a, o in zip(AMPLITUDE, ORDERS))
    lay = SimpleNamespace(
        shafts=("input", "intermediate", "output"),
        shaft_orders=ORDERS,
        points=POINTS,
        orders=np.array([3 * float(o) for o in ORDERS]),
        source=np.arange(3),
        index=np.full(3, 3),
    )
    return y + 0.05 * rng.standard_normal(y.size), lay


@pytest.mark.parametrize("sweeps", [1, 2])
def test_no_reading_is_made_twice_and_each_line_is_read_at_its_amplitude(monkeypatch, sweeps):
    y, lay = record()
    seen = []
    read = shaft.read_at

    def counted(spectrum, n, at, *args, **kwargs):
        digest = hashlib.sha1(np.ascontiguousarray(spectrum).tobytes() + np.ascontiguousarray(at).tobytes())
        seen.append(digest.hexdigest() + f"{n}{args}{kwargs}")
        return read(spectrum, n, at, *args, **kwargs)

    monkeypatch.setattr(shaft, "read_at", counted)
    mean, noise, periods = shaft.shaft_averages(y, lay, 0, 50, sweeps)
    assert len(seen) == len(set(seen)), f"{len(seen) - len(set(seen))} of {len(seen)} readings repeated"
    assert periods == 8  # 50 input turns hold 8 complete output-shaft turns
    np.testing.assert_allclose(np.abs(mean), AMPLITUDE, rtol=0.02)
    assert np.all(noise > 0) and np.all(np.sqrt(noise) < 0.05 * np.array(AMPLITUDE))
