"""An outside user's leftovers (issue 39, "How it will be checked", round Z): box B, a 21/65 + 34/91 reducer
without a tacho, described with a 64-tooth first wheel on a short take; which gear on a shaft carrying two
gears at weak evidence; a healthy take over the non-synchronous threshold. The records are small stand-ins
written here with numpy, not simulated by gearlab."""

from __future__ import annotations

import numpy as np
from test_inspect import described

from gearlab.inspect import InspectOptions, inspect_record


def _lab(path, speed=29.3, fs=8192.0, revs=57, seed=0):
    """An outside lab's two-stage signal: each mesh's harmonics 1-3 amplitude-modulated by the first harmonic of
    both its shafts only, white noise."""
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * speed * np.arange(int(revs / speed * fs)) / fs
    shaft = [theta, theta * 21 / 65, theta * 21 / 65 * 34 / 91]
    x = rng.normal(0, 0.5, theta.size)
    for k, (z, level) in enumerate(((21, 5.0), (34, 4.0))):
        am = 1 + 0.15 * np.cos(shaft[k] + 0.3) + 0.1 * np.cos(shaft[k + 1] + 1.1)
        for h, a in enumerate((1.0, 0.45, 0.2), start=1):
            x += level * a * am * np.cos(h * z * shaft[k] + rng.uniform(0, 6))
    np.savez(path, acc=x, fs=fs)


def test_a_short_take_of_a_wrong_first_wheel_invents_no_pinion_count(tmp_path):
    # 57 turns: stage 2's 2nd harmonic (M1 + 0.968, where the 64-tooth wheel leaves stage 2 unexplained) merges with
    # the input's upper sideband and, weighted by its level, pulled the input's comb to 0.968: 'the pinion on the
    # input shaft shows 21.7 ± 0.2 teeth' beside 'stage 2: no line at mesh order 11.16'
    _lab(tmp_path / "lab.npz")
    box = described((21, 64), (34, 91), speed="29.3 Hz")
    wrong = inspect_record(str(tmp_path / "lab.npz"), box, InspectOptions("acc"))["verdict"]
    assert "pinion on the input shaft shows" not in wrong, wrong
    # the sidebands cannot tell 64 from 65 at 57 turns; stage 2's mesh, 1.5 % low, says which wheel moves it
    assert "a 65-tooth wheel on the intermediate shaft (65.0" in wrong, wrong
    assert "64 said" in wrong and "or the tacho" not in wrong, wrong
