"""Outside-user check of issue 39 ("How it will be checked"): a one-stage 37/58 reducer (profile shifts +0.3/-0.3,
25 deg) logged as comma CSVs with a `time_ms` column, and a two-stage 26/71 + 23/82 box logged as one .npz a day of
several takes, described as docs/your_gearbox.md says; small recordings written here with numpy, not by gearlab."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.data.recordings import read_recording


def _mesh(fs=25600.0, seconds=0.5, f=30.0, z=26):
    t = np.arange(int(fs * seconds)) / fs
    acc = 0.1 * np.sin(2 * np.pi * z * f * t) + 0.01 * np.sin(2 * np.pi * f * t)
    tacho = np.where(np.mod(t * f, 1.0) < 0.05, 5.0, 0.0)
    return t, acc, tacho


@pytest.mark.parametrize("fs", ["25.6 kHz", "25600 Hz", "25.6 kS/s"])
def test_an_npz_s_rate_as_text_with_its_unit_is_read(tmp_path, fs):
    # a DAQ's export with its rate as text beside the channels: 'sampling rate field 'fs' must be one number in Hz,
    # got '25.6 kHz'', where a scenario's fs and a text file's 'Sample rate: 25.6 kHz' take the unit
    _, acc, tacho = _mesh()
    path = tmp_path / "day1.npz"
    np.savez(path, Dev1_ai0=acc, Dev1_ai1=tacho, fs=np.array(fs))
    rec = read_recording(path, "Dev1_ai0", "Dev1_ai1")
    assert rec.fs == pytest.approx(25600.0)


def test_an_npz_s_rate_as_a_speed_is_refused_in_one_line(tmp_path):
    _, acc, tacho = _mesh()
    path = tmp_path / "day1.npz"
    np.savez(path, Dev1_ai0=acc, Dev1_ai1=tacho, fs=np.array("1800 rpm"))
    with pytest.raises(Exception, match=r"day1.npz.*'fs'.*rotational speed"):
        read_recording(path, "Dev1_ai0", "Dev1_ai1")
