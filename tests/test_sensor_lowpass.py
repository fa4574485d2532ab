"""sensor_lowpass: a Butterworth anti-alias filter of order n (the gap diagnosis's richer sensor form)."""

import numpy as np
import pytest
from scipy.signal import butter, freqs

from gearlab.effects import EffectChain, effect_spec
from gearlab.registry import get_registry

FS, SPEED = 4096 * 40.0, 40.0


def response(order, f_c, f):
    module = __import__(type(get_registry().get("effect", "sensor_lowpass")).__module__, fromlist=["x"])
    return module.frequency_response(f, f_c, order)


@pytest.mark.parametrize("order", [1, 2, 4, 6, 8])
def test_the_response_is_scipys_analog_butterworth(order):
    f = np.array([0.0, 1e3, 5e3, 8e3, 2e4])
    b, a = butter(order, 2 * np.pi * 5e3, analog=True)
    _, h = freqs(b, a, worN=2 * np.pi * f)
    np.testing.assert_allclose(response(order, 5e3, f), h, rtol=1e-10, atol=1e-14)
    assert abs(response(order, 5e3, np.array([5e3]))[0]) == pytest.approx(2**-0.5)  # -3 dB at the corner


def test_a_tone_above_the_corner_falls_by_20n_db_per_decade():
    t = np.arange(4096 * 4) / FS
    x = np.sin(2 * np.pi * 20e3 * t).reshape(4, 4096)  # 20 kHz: a whole number of cycles per revolution
    for order in (2, 4):
        chain = EffectChain.load((effect_spec("sensor_lowpass", f_c=2e3, order=order),))
        y = chain.apply_signal(x, FS, SPEED, 1.0, [0])
        gain = np.sqrt(np.mean(y**2) / np.mean(x**2))
        assert 20 * np.log10(gain) == pytest.approx(-10 * np.log10(1 + 10.0 ** (2 * order)), abs=0.01)
