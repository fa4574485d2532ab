"""Outside-user check of issue 39 (helper CV): recordings made outside gearlab (numpy, here), read as
docs/your_gearbox.md says."""

from __future__ import annotations

import numpy as np
from test_inspect import described

from gearlab.inspect import InspectOptions, inspect_record


def _stepped(path, f0=21.4, step=1.06, fs=12800.0, seconds=6.0, seed=2):
    """A one-stage 106/127 box without a tacho, its input speed stepping by *step* over 0.2 s half-way: both
    shafts' lines and 2nd harmonics, mesh harmonics 1-3 with the shafts' AM/PM, noise at 20 dB (m/s^2)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    f = f0 * (1 + (step - 1) * np.clip((t - seconds / 2) / 0.2, 0, 1))
    a_in = 2 * np.pi * (np.cumsum(f) / fs + 0.3)
    a_out = 106 / 127 * a_in
    x = sum(0.06 * np.cos(h * a + 0.5 * h) for a in (a_in, a_out) for h in (1, 2))
    am = 1 + 0.1 * np.cos(a_in + 0.4) + 0.07 * np.cos(a_out + 1.3)
    pm = 0.12 * np.sin(a_in) + 0.08 * np.sin(a_out + 0.7)
    x = x + sum(am * np.cos(h * (106 * a_in + pm) + h) / h for h in (1, 2, 3))
    x = 5.0 * x / np.std(x)
    np.savez(path, acc=x + rng.normal(0, 0.5, t.size), fs=fs)
    return f


def test_a_stepped_take_declared_at_another_speed_is_not_told_a_speed_of_a_turn_a_record(tmp_path):
    # CV: a 106/127 box stepping 21.4 -> 22.7 Hz without a tacho, declared 20 Hz: its mesh smeared over 6 %, the
    # output shaft's line (18.4 Hz) and its 2nd harmonic were read as the 106-tooth mesh's at 0.172 Hz, and inspect
    # said 'the record runs at 0.172 Hz, not 20 Hz? (--speed '0.172 Hz')': a speed of one turn in the 6 s record
    _stepped(tmp_path / "a.npz")
    box = described((106, 127), speed="22 Hz")
    verdict = inspect_record(str(tmp_path / "a.npz"), box, InspectOptions("acc", speed_hz=20.0))["verdict"]
    assert "differs" in verdict, verdict
    if "every described mesh has its lines at " in verdict:
        said = float(verdict.split("every described mesh has its lines at ")[1].split(" Hz")[0])
        assert said * 6.0 >= 10, verdict  # the record holds at least 10 turns at the speed suggested
