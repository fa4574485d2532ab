"""inspect's 'the record runs at X, not the declared speed?' names the speed of the strongest lines.

A one-stage box's shaft line and its 2nd harmonic are a z-tooth mesh and its 2nd harmonic at 1/z of the shaft's
speed: a 29/73 box at 24.4 Hz inspected with its output's 584 rpm declared was told 'every described mesh has its
lines at 0.8402 Hz ...: the record runs at 0.8402 Hz, not 9.733 Hz? (--speed '0.8402 Hz')', the slowest of the
speeds whose lines every mesh has, where its mesh lines, 30 times stronger, say 24.4 Hz.
"""

import numpy as np
from test_inspect import described

from gearlab.inspect import InspectOptions, inspect_record


def _box(path, speed=24.4, fs=12800.0, seconds=6.0, seed=3):
    """A 29/73 box without a tacho: mesh harmonics 1-3 modulated by both shafts, the input shaft's line and its
    2nd harmonic, white noise (m/s^2)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    theta = 2 * np.pi * np.cumsum(speed * (1 + 0.002 * np.sin(2 * np.pi * 0.27 * t))) / fs
    h = np.arange(1, 4)[:, None]
    mod = 1 + 0.2 * np.cos(theta + 0.4) + 0.12 * np.cos(29 / 73 * theta + 2.0)
    mesh = 2.0 * mod * (np.cos(h * 29 * theta + 0.3 * h) / h).sum(0)
    shaft = 0.25 * np.cos(theta + 0.5) + 0.1 * np.cos(2 * theta + 1.3)
    np.savez(path, acc=mesh + shaft + rng.normal(0, 0.3, t.size), fs=fs)


def test_the_speed_suggested_is_the_mesh_lines_not_the_shaft_lines_read_as_a_mesh(tmp_path):
    _box(tmp_path / "a.npz")
    box = described((29, 73), speed="1480 rpm")
    verdict = inspect_record(str(tmp_path / "a.npz"), box, InspectOptions("acc", speed_hz=584 / 60))["verdict"]
    said = verdict.split("every described mesh has its lines at ")[1]
    assert abs(float(said.split(" Hz")[0]) / 24.4 - 1) < 0.005, verdict
    assert "(--speed '24." in said, verdict
