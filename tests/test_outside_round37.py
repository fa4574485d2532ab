"""An outside user's look (issue 39): four gearboxes no other test uses, their takes made here by plain numpy (each
mesh with 4 harmonics, amplitude- and phase-modulated by both of its shafts, shaft lines, a slow speed wander, noise;
no gearlab simulator), read as docs/your_gearbox.md says. A: two stages 23/59 + 19/71 at 1,750 rpm, no tacho, MATLAB
v5 in m/s^2. B: one stage 37/89 at 12 Hz, an int16 stereo WAV (vibration at 100 mV/g, full scale 5 V; a tacho of 2
marks a turn). C: two stages 29/53 + 21/88 at 45 Hz, HDF5 of two accelerometers in g and a tacho on the intermediate
shaft, one (N, 3) dataset whose attributes name its columns and units. D: one stage 41/43 at 30 Hz, a CSV in volts
at 10.2 mV/(m/s^2) whose time column is in ms. Beside them: a file's unit spelled out as NI's software writes it."""

from __future__ import annotations

import h5py
import numpy as np
import pytest


def _take(stages, speed, fs, seconds, seed, gains=None):
    """(acceleration in m/s^2, each shaft's angle, the mean input speed in Hz) of a train of (pinion, wheel) *stages*
    at about *speed* Hz: each mesh's harmonics modulated by both of its shafts, shaft lines, a 0.4 Hz speed wander of
    0.3 %, white noise; *gains*: each stage's level at the sensor."""
    rng = np.random.default_rng(seed)
    n = int(fs * seconds)
    t = np.arange(n) / fs
    hz = speed * (1 + 0.003 * np.sin(2 * np.pi * 0.4 * t + rng.uniform(0, 2 * np.pi)))
    th = 2 * np.pi * np.cumsum(hz) / fs + rng.uniform(0, 2 * np.pi)
    shafts = [th * np.prod([zp / zw for zp, zw in stages[:k]]) for k in range(len(stages) + 1)]
    a = sum(0.3 * np.cos(s + k) for k, s in enumerate(shafts))
    for i, (zp, _) in enumerate(stages):
        am = 1 + 0.25 * np.cos(shafts[i] + 0.3) + 0.2 * np.cos(shafts[i + 1] + 1.2)
        pm = 0.3 * np.sin(shafts[i] + 2.0) + 0.25 * np.sin(shafts[i + 1] + 0.7)
        level = (gains or [1.0 / (1 + 0.6 * j) for j in range(len(stages))])[i]
        for h, amp in ((1, 3.0), (2, 1.8), (3, 1.0), (4, 0.6)):
            a = a + level * amp * am * np.cos(h * (zp * shafts[i] + pm) + h)
    return a + rng.normal(0, 0.3, n), shafts, float(np.mean(hz))


def _pulses(angle, marks=1):
    return np.where(np.mod(angle * marks / (2 * np.pi), 1.0) < 0.15, 4.0, 0.0)


@pytest.mark.parametrize("unit, volts", [("Volts", 1.0), ("VOLT", 1.0), ("Millivolts", 1e-3)])
def test_a_file_unit_spelled_out_as_ni_writes_it_is_read_as_volts(tmp_path, cli, unit, volts):
    # a TDMS channel's unit_string in its HDF5 export, 'Volts' as NI's software writes it: 'values: unknown (the
    # file's unit 'Volts' is not read; no sensitivity or gain given: the values are taken as m/s²)', where 'V' and
    # 'volt' said the sensitivity was missing, and a 'unit' key of 'Volts' was read as volts
    from gearlab.data.recordings import read_recording
    from gearlab.errors import GearlabInputError

    a, _, _ = _take(((41, 43),), 30.0, 5000.0, 1.0, seed=5)
    with h5py.File(tmp_path / "ni.h5", "w") as f:
        f.create_dataset("acc", data=a * 0.0102).attrs["unit_string"] = unit
        f.attrs["fs"] = 5000.0
    with pytest.raises(GearlabInputError, match="key 'sensitivity': missing; channel 'acc' is in volts"):
        read_recording(tmp_path / "ni.h5", "acc")
    rec = read_recording(tmp_path / "ni.h5", "acc", sensitivity=0.0102)
    assert np.allclose(rec.signal, a * volts), np.std(rec.signal) / np.std(a)
    code, out, err = cli("inspect", tmp_path / "ni.h5", "--speed", "30 Hz")
    assert code == 0, err
    assert f"not m/s² (channel 'acc' is in volts ({unit}, as the file's unit '{unit}' says)" in out, out[:600]
