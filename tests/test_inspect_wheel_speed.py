"""A first wheel described a tooth short, no tacho (issue 39 outside check, a 21/65 + 34/91 reducer at a
declared 29.3 Hz described with 64 teeth): the speed was read 1.5 % slow from stage 2's mesh, which the wrong
wheel moves, because the first mesh's lower wheel sideband (M1 less the intermediate shaft) was taken for
a carrier whose 'sidebands' confirmed a 21-tooth pinion at that speed; then, at the right speed, stage 2's 2nd
harmonic (one line, 0.969 above the first mesh) was taken for the input shaft's comb: 'the pinion shows 21.7 teeth'."""

from __future__ import annotations

import numpy as np
from test_inspect import described, synthesise

from gearlab.inspect import InspectOptions, inspect_record

TRAIN = ((21, 65), (34, 91))


def test_a_wrong_first_wheel_keeps_the_speed_and_is_named(tmp_path):
    x, _, fs = synthesise(TRAIN, speed=29.3, fs=8192.0, revs=300)
    path = tmp_path / "rec.npz"
    np.savez(path, acc=x, fs=fs)
    options = InspectOptions(vibration="acc")
    right = inspect_record(str(path), described(*TRAIN, speed="29.3 Hz"), options)
    assert right["matches"], right["verdict"]
    wrong = inspect_record(str(path), described((21, 64), (34, 91), speed="29.3 Hz"), options)
    assert abs(wrong["speed"]["mean_hz"] / 29.3 - 1) < 0.005, wrong["speed"]
    assert "the wheel on the intermediate shaft shows 65.0" in wrong["verdict"], wrong["verdict"]


def _lab(path, speed=29.3, fs=8192.0, revs=300, seed=0):
    """An outside lab's two-stage signal: each mesh's harmonics 1-3 amplitude-modulated by the first harmonic of
    both its shafts only (no products of the shafts), white noise."""
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * speed * np.arange(int(revs / speed * fs)) / fs
    shaft = [theta, theta * 21 / 65, theta * 21 / 65 * 34 / 91]
    x = rng.normal(0, 0.5, theta.size)
    for k, (z, level) in enumerate(((21, 5.0), (34, 4.0))):
        am = 1 + 0.15 * np.cos(shaft[k] + 0.3) + 0.1 * np.cos(shaft[k + 1] + 1.1)
        for h, a in enumerate((1.0, 0.45, 0.2), start=1):
            x += level * a * am * np.cos(h * z * shaft[k] + rng.uniform(0, 6))
    np.savez(path, acc=x, fs=fs)


def test_a_later_mesh_harmonic_the_wrong_wheel_moved_is_no_input_sideband(tmp_path):
    # stage 2's 2nd harmonic, M1 + 0.969 where the wrong wheel leaves it unexplained, four times the input's
    # true sidebands, was the input's comb of one line: 'the pinion on the input shaft shows 21.7 teeth'
    _lab(tmp_path / "lab.npz")
    wrong = inspect_record(
        str(tmp_path / "lab.npz"), described((21, 64), (34, 91), speed="29.3 Hz"), InspectOptions("acc")
    )
    assert wrong["verdict"].startswith(
        "the description 'box' differs: stage 1: the wheel on the intermediate shaft shows 65.0"
    ), wrong["verdict"]
    assert "the pinion on the input shaft shows" not in wrong["verdict"], wrong["verdict"]
