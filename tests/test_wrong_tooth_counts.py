"""Descriptions one tooth off, told apart by inspect (issue 39: any tooth-count mismatch between description and
recording is called out), and the words a user reads around them. The records are small stand-ins written by hand
after the outside round-14 boxes (22/69 + 25/74 with an output tacho, 14/53 + 18/59 + 23/67 without one), not
simulated by gearlab."""

from __future__ import annotations

import numpy as np
import scipy.io.wavfile


def test_a_wav_without_a_gain_is_told_its_full_scale_volts(tmp_path):
    # a WAV's gain is the volts at its full scale (read as ±1): 'e.g. gain = 0.3 mV' (a count's volts) was no value a
    # user of a WAV would write
    from gearlab.inspect import InspectOptions, inspect_record

    fs, f = 20000.0, 30.0
    t = np.arange(int(2 * fs)) / fs
    x = 0.3 * np.sin(2 * np.pi * 20 * f * t)
    scipy.io.wavfile.write(tmp_path / "take.wav", int(fs), np.round(x * 32767).astype(np.int16))
    units = inspect_record(str(tmp_path / "take.wav"), None, InspectOptions(speed_hz=f, sensitivity=0.01))["units"]
    assert "a WAV file's: the volts at its full scale, e.g. gain = '10 V'" in units, units
