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


def test_a_tone_above_one_order_gets_the_records_finer_guess_too():
    """Between higher orders the one-revolution peak lies within a hertz; the record read end to end
    places the line to a fraction of one, which a search against consecutive rows needs (their tone
    runs on: its line is one record bin wide)."""
    tone = get_registry().get("effect", "interference_tone")
    t = np.arange(ROWS * N) / (N * SPEED)
    x = (np.sin(2 * np.pi * 25 * SPEED * t) + 0.3 * np.sin(2 * np.pi * 1234.3 * t)).reshape(ROWS, N)
    guesses = tone.guesses(x, SPEED)
    assert guesses[0]["frequency"] == pytest.approx(1234.3, abs=1.0)
    assert guesses[1]["frequency"] == pytest.approx(1234.3, abs=0.15)
    # the record's frequency at the read level and at levels around it (other effects move the
    # healthy RMS the level is relative to)
    ladder = [g["ratio"] / guesses[1]["ratio"] for g in guesses[2:]]
    assert all(g["frequency"] == guesses[1]["frequency"] for g in guesses[2:])
    assert ladder == pytest.approx([0.5, 0.7, 1.4, 2.0])


def _meshing(ripple_order=None, index=0.0, rows=20):
    """Revolutions of a 25-tooth mesh (harmonics 1-8 at falling levels), amplitude-modulated at
    ripple_order shaft orders by *index*, with a little noise."""
    theta = 2 * np.pi * np.arange(N) / N
    x = sum(np.cos(25 * k * theta + 0.3 * k) / k for k in range(1, 9))
    if ripple_order:
        x = x * (1 + index * np.sin(ripple_order * theta + 0.7))
    rng = np.random.default_rng(1)
    return x + 1e-3 * rng.standard_normal((rows, N))


@pytest.mark.parametrize("q", [2, 3, 7])
def test_a_ripples_order_and_amplitude_are_read_off_the_mesh_sidebands(q):
    """A ripple at q shaft orders puts sidebands at L +- q around every mesh harmonic L: the load
    ripple's order and amplitude (the modulation index) and the speed ripple's order are guessed,
    at several phases (the record's tacho offset turns the sidebands' phases)."""
    registry = get_registry()
    load = registry.get("effect", "load_fluctuation").guesses(_meshing(q, 0.12), SPEED)
    assert len(load) == 4 and {g["order"] for g in load} == {q}
    assert load[0]["amplitude"] == pytest.approx(0.12, rel=0.05)
    assert len({g["phase"] for g in load}) == 4
    speed = registry.get("effect", "speed_fluctuation").guesses(_meshing(q, 0.05), SPEED)
    assert {g["order"] for g in speed} == {q}
    assert {g["amplitude"] for g in speed} == {0.003, 0.01, 0.03}  # eps is not read off: tried a decade around


def test_no_mesh_family_no_ripple_guess():
    noise = np.random.default_rng(2).standard_normal((20, N))
    assert get_registry().get("effect", "speed_fluctuation").guesses(noise, SPEED) == []


def test_a_line_below_one_order_is_read_to_a_fraction_of_a_record_bin_with_its_level():
    """A search against consecutive rows scores such a line by the record's own lines, a valley a few
    tenths of a percent of its frequency wide: the record's peak is zoomed to 1/100 of a bin (0.005 Hz
    here) and its level read by the whole record's least squares. Rows that are not consecutive (each
    its own tone phase) keep the one-revolution level: their record holds no coherent line."""
    tone = get_registry().get("effect", "interference_tone")
    t = np.arange(ROWS * N) / (N * SPEED)
    rng = np.random.default_rng(4)
    mesh = np.sin(2 * np.pi * 25 * SPEED * t)
    x = (mesh + 0.2 * np.sqrt(2) * np.sin(2 * np.pi * 7.29 * t + 2.0)).reshape(ROWS, N)
    x = x + 0.05 * rng.standard_normal(x.shape)
    guesses = tone.guesses(x, SPEED)
    assert guesses[1]["frequency"] == pytest.approx(7.29, rel=2e-3)  # a record bin is 0.5 Hz
    assert guesses[1]["ratio"] == pytest.approx(0.2 / np.sqrt(0.5 + 0.05**2), rel=0.01)  # against the rest RMS
    assert tone.guess_step < 0.01  # the search starts on that scale from such a reading
    phases = rng.uniform(0, 2 * np.pi, (ROWS, 1))
    rows = np.sin(2 * np.pi * 25 * SPEED * t[:N]) + 0.2 * np.sqrt(2) * np.sin(2 * np.pi * 167.3 * t[:N] + phases)
    independent = tone.guesses(rows, SPEED)
    assert independent[1]["ratio"] == pytest.approx(independent[0]["ratio"])  # the one-revolution level
