"""Revolutions of a record without a tacho, cut by the one reader every kind uses
(recordings.shaft_angle): with a gearbox description, at the speed followed on a mesh
harmonic's phase (gearbox.speed.follow_speed), not at a constant speed. A real motor's speed
swings a little; at a constant speed a 0.3 % swing smears each revolution's mesh over the
record and the synchronous average (TSA) loses most of its mesh harmonics."""

from __future__ import annotations

import numpy as np
import pytest
from test_inspect import described, synthesise

from gearlab.data.recordings import cut_recording, read_recording, shaft_angle, wrap
from gearlab.gearbox import speed
from gearlab.gearbox.speed import follow_speed
from gearlab.signals import cut_revolutions

SPEED = 24.0
SWING = 0.003  # a motor's slow speed swing, relative (synthesise: at 0.5 Hz)


def _record(tmp_path, stages):
    """The record, with its true shaft angle beside it (wrapped, as a tacho channel the test reads)."""
    x, _, fs = synthesise(stages, speed=SPEED, revs=150, swing=SWING)
    t = np.arange(x.size) / fs
    theta = 2 * np.pi * SPEED * t + SWING * SPEED / 0.5 * (1 - np.cos(2 * np.pi * 0.5 * t))  # as synthesise
    path = tmp_path / "swing.npz"
    np.savez(path, acc=x, angle=wrap(theta), fs=fs)
    return str(path)


def _mesh_amplitudes(revolutions: np.ndarray, z: int) -> np.ndarray:
    """Amplitudes of the TSA's mesh harmonics 1-3 (orders z, 2z, 3z)."""
    tsa = revolutions.mean(axis=0)
    return 2 * np.abs(np.fft.rfft(tsa))[[z, 2 * z, 3 * z]] / tsa.size


@pytest.mark.parametrize("stages", [((26, 37),), ((22, 29), (17, 51))], ids=["26-37", "22-29+17-51"])
def test_a_swinging_speed_is_followed_when_revolutions_are_cut(tmp_path, stages, monkeypatch):
    path, box, z = _record(tmp_path, stages), described(*stages), stages[0][0]
    true = _mesh_amplitudes(cut_recording(path, vibration="acc", tacho="angle").revolutions, z)

    rec = read_recording(path, "acc")
    source, angle, how = shaft_angle(rec, gearbox=box)
    assert how.startswith("speed followed on the mesh phase ("), how
    # the follower's unsettled ends (gearbox.speed.settling): localisation leaves them out, every revolution is cut
    assert rec.tacho is None and set(source) == {"tacho", "ends"} and 0 < source.pop("ends") < 0.2, source
    assert angle[0] == pytest.approx(0.0, abs=1e-9)  # revolutions start at the first sample, as at a constant speed
    followed = cut_revolutions(rec.signal, rec.fs, **source, transient="none")
    assert followed.speed_hz == pytest.approx(SPEED, rel=2e-4)  # the mean speed: conditions, the gap's note
    tracked = _mesh_amplitudes(followed.revolutions, z)
    assert np.allclose(tracked, true, rtol=0.03), (tracked, true)

    # follow_speed's fallback (no mesh harmonic stands clear): the constant speed of its first look,
    # which smears the TSA's mesh (the path every kind but inspect took before)
    def first_look(*args, **kwargs):
        return (None, *follow_speed(*args, **kwargs)[1:])

    monkeypatch.setattr(speed, "follow_speed", first_look)
    constant = cut_recording(path, vibration="acc", gearbox=box)
    assert constant.angle_source.startswith("constant speed from the mesh lines"), constant.angle_source
    assert constant.speed_hz == pytest.approx(SPEED, rel=2e-3)
    smeared = _mesh_amplitudes(constant.revolutions, z)
    assert smeared[0] < 0.7 * true[0], (smeared, true)
