"""A vibration channel given as the tacho (the two swapped) is said so in one line, not 'a run-up or coast-down?'.

A 19/62 + 23/87 box's WAV, channels 0 (vibration) and 1 (a once-a-turn TTL tacho), read with vibration = "1",
tacho = "0": the vibration's mid-level crossings, through its noise, made 66-206 Hz of a 30 Hz shaft; a detection
run stopped at 'a history take must run steady ... a run-up or coast-down?', inspect read '+317 %, the mean of a
run-up'. A real pulse train, a cosine tacho and a run-up's keep their angles.
"""

import numpy as np
import pytest

from gearlab.errors import GearlabInputError
from gearlab.signals.angle import angle_from_pulses

FS = 20000.0


def _vibration(seed=0, seconds=4.0, f=30.0):
    """Mesh lines of two stages modulated by their shafts, and noise: what a housing accelerometer holds."""
    t = np.arange(int(seconds * FS)) / FS
    theta = 2 * np.pi * f * t
    x = sum(
        (1 + 0.1 * np.cos(theta * r)) * np.cos(h * z * theta * r + h) / h
        for z, r in ((19, 1.0), (23, 19 / 62))
        for h in (1, 2, 3)
    )
    return x + np.random.default_rng(seed).normal(0, 0.5, t.size), theta


def test_a_vibration_read_as_a_tacho_is_refused_as_swapped():
    x, _ = _vibration()
    with pytest.raises(GearlabInputError, match=r"no pulses of a shaft's turn; a vibration channel\? \(vibration and "):
        angle_from_pulses(x, FS)


@pytest.mark.parametrize("kind", ["ttl", "cosine", "noisy ttl", "run-up"])
def test_tachos_keep_their_angle(kind):
    _, theta = _vibration()
    rng = np.random.default_rng(1)
    if kind == "run-up":  # 20 -> 40 Hz over the take
        t = np.arange(theta.size) / FS
        theta = 2 * np.pi * (20 * t + 2.5 * t**2)
    phase = np.mod(theta, 2 * np.pi)
    pulses = {
        "ttl": np.where(phase < 0.2, 5.0, 0.0),
        "cosine": np.cos(theta),
        "noisy ttl": np.where(phase < 0.2, 5.0, 0.0) + rng.normal(0, 0.3, theta.size),
        "run-up": np.where(phase < 0.2, 5.0, 0.0),
    }[kind]
    angle = angle_from_pulses(pulses, FS)
    turns = (angle[-1] - angle[0]) / (2 * np.pi)
    assert abs(turns - (theta[-1] - theta[0]) / (2 * np.pi)) < 1.5, turns
