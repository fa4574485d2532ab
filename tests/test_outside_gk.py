"""An outside user's two-stage box (26/71 + 23/82): what the importer said of its files."""

import numpy as np
import pytest

from gearlab.data.recordings import check_recording, read_recording
from gearlab.errors import GearlabInputError


def _npz(path, n=2000, fs=25600.0):
    t = np.arange(n) / fs
    np.savez(path, Dev1_ai0=np.sin(2 * np.pi * 780 * t), Dev1_ai1=np.zeros(n), Time=t, fs=np.array("25.6 kHz"))
    return path


def test_a_wrong_channel_lists_the_channels_apart_from_the_rate_and_time(tmp_path):
    # the file's list said 'Dev1_ai0, Dev1_ai1, Time, fs': a rate and a time vector are no vibration channels
    path = _npz(tmp_path / "day1.npz")
    with pytest.raises(GearlabInputError) as caught:
        check_recording(path, "gap.toml: [target]", {"vibration": "Dev1_aiX"})
    line = str(caught.value)
    channels = line.split("the file has channels: ")[1]
    assert channels == "Dev1_ai0, Dev1_ai1 (and the time 'Time', the sampling rate 'fs')", line


def test_a_csv_column_list_says_which_is_the_time(tmp_path):
    path = tmp_path / "rec.csv"
    t = np.arange(400) / 20000.0
    np.savetxt(path, np.column_stack([t, np.sin(t), t * 0]), delimiter=",", header="time_s,acc_V,tacho_V", comments="")
    with pytest.raises(GearlabInputError) as caught:
        read_recording(path, "acc_X")
    line = str(caught.value)
    assert line.endswith("the file has channels: acc_V, tacho_V (and the time 'time_s')"), line


def test_a_time_in_milliseconds_that_goes_back_is_said_in_milliseconds(tmp_path):
    # 'time 'time_ms' (x 0.001 s) does not increase ... (0.10045 -> 0.1004 s); expected increasing times in seconds'
    path = tmp_path / "nonmono.csv"
    t = np.arange(4000) / 20.0  # ms at 20 kHz
    t[2001] = t[2000] - 0.05
    np.savetxt(path, np.column_stack([t, np.sin(t)]), delimiter=",", header="time_ms,acc_V", comments="", fmt="%.4f")
    with pytest.raises(GearlabInputError) as caught:
        read_recording(path, "acc_V", sensitivity=0.01)
    line = str(caught.value)
    assert "(100 -> 99.95 ms)" in line and line.endswith("expected increasing times in ms"), line
    assert " s)" not in line.split("does not increase")[1] and "in seconds" not in line, line
