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


def test_a_later_pinion_one_tooth_short_behind_an_output_tacho_is_named(tmp_path):
    # 22/69 + 25/74, a once-a-turn tacho on the output, described with a 24-tooth second pinion: the input read 25/24
    # fast puts stage 1's mesh at 21.12, a whole tooth nowhere; its load sideband at 21.02 (36 dB over the floor, the
    # carrier 61) was read as a 21-tooth pinion's mesh, its neighbours as the intermediate's comb (0.409, the
    # intermediate's and the output's orders summed), and stage 2 was told 'the pinion shows 18.7 teeth'
    from test_outside_round13 import _inspect
    from test_outside_round14 import _steps

    teeth, fs, f0, seconds = ((22, 69), (25, 74)), 20000.0, 55.0, 6.0
    x = _steps(teeth, f0, fs, seconds, (1.0, 1.0), ((1, 0.5, 0.3), (1, 0.5, 0.3)), step=0.0)
    out = f0 * 22 / 69 * 25 / 74 * np.arange(x.size) / fs
    key = 5.0 * (np.mod(out, 1.0) < 0.05)
    report = _inspect(
        tmp_path, ((22, 69), (24, 74)), {"acc": x, "key": key, "fs": fs}, "55 Hz", sensor='[sensor]\ntacho = "output"\n'
    )
    assert report["matches"] is False, report["verdict"]
    assert "the pinion on the intermediate shaft shows 25.0" in report["verdict"], report["verdict"]
    assert "18.7" not in report["verdict"], report["verdict"]
