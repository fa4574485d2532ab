"""Outside-user check of issue 39, round 15: recordings as other tools export them, read as
docs/your_gearbox.md says (small files written here, not simulated by gearlab)."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.data.recordings import read_header, read_recording


def _table(n=2000, fs=25600.0):
    t = np.arange(n) / fs
    acc = np.sin(2 * np.pi * 450.0 * t)
    tacho = 5.0 * (np.mod(t * 23.4, 1.0) < 0.5)
    return t, acc, tacho


@pytest.mark.parametrize(
    "preamble, fs",
    [
        ("Device: NI-9234\nSample rate: 25600 Hz\nDate: 2026-11-30 10:12\n\n", 25600.0),
        ("Measurement export\nSampling Rate (kHz): 25.6\nOperator = J. Smith\n", 25600.0),
        ("Sample interval: 39.0625 us\n", 25600.0),
    ],
)
def test_a_csv_after_a_loggers_preamble_is_read_with_its_rate(tmp_path, preamble, fs):
    # a DAQ's export: lines of 'key: value' (and a title) above the table, no '#'. The file was refused with
    # 'line 2 has 4 fields but the header has 2' (the preamble's first line taken as the header)
    t, acc, tacho = _table()
    rows = "\n".join(f"{a:.6f},{k:.3f}" for a, k in zip(acc, tacho))
    path = tmp_path / "export.csv"
    path.write_text(preamble + "acc_ms2,tacho_V\n" + rows + "\n")
    header = read_header(path)
    assert {"acc_ms2", "tacho_V"} <= set(header.channels) and header.rate
    assert header.stated is not None and header.stated[0] == pytest.approx(fs)
    rec = read_recording(path, "acc_ms2", "tacho_V")
    assert rec.fs == pytest.approx(fs)
    assert np.allclose(rec.signal, np.round(acc, 6)) and rec.tacho.size == acc.size


def test_score_reads_a_file_with_the_keys_of_the_run_file_of_its_format_whose_channels_it_has(tmp_path):
    # D's run: CSV takes of two kinds, a logger's (header 'Beschleunigung', the [target]'s keys) and headerless ones
    # (their own vibration = "1", fs, unit). gearlab score of a headerless take said 'the run's channel keys are not in
    # it: tried vibration 'Beschleunigung', tacho 'Drehzahlgeber'': a format's keys were kept only where all its files
    # agreed
    from types import SimpleNamespace

    from gearlab.kinds.detection_scoring import file_keys, remembered

    own = {"vibration": "1", "tacho": "2", "fs": "25.6 kHz", "unit": "m/s^2"}
    files = [
        SimpleNamespace(path="rec/h1.csv", role="history", keys=own),
        SimpleNamespace(path="rec/h2.csv", role="history", keys={}),
        SimpleNamespace(path="rec/t1.csv", role="test", keys={}),
        SimpleNamespace(path="rec/t2.csv", role="test", keys=own),
    ]
    meta = {"target": {"vibration": "Beschleunigung", "tacho": "Drehzahlgeber"}, "file_keys": file_keys(files)}
    t, acc, tacho = _table()
    headerless = tmp_path / "next.csv"
    headerless.write_text("\n".join(f"{a:.7f},{b:.6f},{k:.3f}" for a, b, k in zip(t, acc, tacho)) + "\n")
    logger = tmp_path / "next_logger.csv"
    logger.write_text(
        "Zeit;Beschleunigung;Drehzahlgeber\n"
        + "\n".join(f"{a:.7f};{b:.6f};{k:.3f}" for a, b, k in zip(t, acc, tacho)).replace(".", ",")
        + "\n"
    )
    assert remembered(meta, str(headerless))[0] == own
    assert remembered(meta, str(logger))[0] == {}


@pytest.mark.parametrize("fmt", ["mat", "npz", "h5"])
def test_a_sample_interval_dt_gives_the_rate(tmp_path, fmt):
    # a logger that stores the sample interval, not the rate (MATLAB's dt, an HDF5 group's 'dt' attribute): 'no
    # sampling rate: the file has no 'fs'/time and none was given'
    import h5py
    import scipy.io

    t, acc, tacho = _table()
    path = tmp_path / f"take.{fmt}"
    if fmt == "mat":
        scipy.io.savemat(path, {"dt": 1 / 25600.0, "acc": acc, "tacho": tacho})
    elif fmt == "npz":
        np.savez(path, dt=np.float64(1 / 25600.0), acc=acc, tacho=tacho)
    else:
        with h5py.File(path, "w") as f:
            g = f.create_group("daq")
            g.attrs["dt"] = 1 / 25600.0
            g["acc"], g["tacho"] = acc, tacho
    assert read_header(path).rate
    rec = read_recording(path, "acc", "tacho", unit="m/s^2")
    assert rec.fs == pytest.approx(25600.0) and "dt" in rec.fs_source
    assert "dt" not in rec.channels


def test_a_time_column_of_iso_timestamps_gives_the_rate(tmp_path):
    # a logger's clock times ('2026-11-30T10:00:00.000039'): 'time 'timestamp' must hold numbers (seconds), got
    # dtype <U26'
    import datetime

    t, acc, tacho = _table()
    t0 = datetime.datetime(2026, 11, 30, 10, 0, 0)
    stamps = [(t0 + datetime.timedelta(seconds=float(s))).isoformat(timespec="microseconds") for s in t]
    path = tmp_path / "clock.csv"
    path.write_text(
        "timestamp,acc_ms2,tacho_V\n" + "\n".join(f"{s},{a:.6f},{k:.3f}" for s, a, k in zip(stamps, acc, tacho))
    )
    rec = read_recording(path, "acc_ms2", "tacho_V")
    assert rec.fs == pytest.approx(25600.0, rel=1e-3)


def test_a_record_with_dropped_samples_says_where_and_what_to_do(tmp_path):
    # a logger that lost 50 ms: the line named the step only; it now says how many samples are missing and what to do
    t, acc, tacho = _table(4000)
    keep = np.ones(t.size, bool)
    keep[2000:2128] = False
    path = tmp_path / "gap.csv"
    path.write_text("time_s,acc_ms2\n" + "\n".join(f"{a:.7f},{b:.6f}" for a, b in zip(t[keep], acc[keep])))
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError) as err:
        read_recording(path, "acc_ms2")
    text = str(err.value)
    assert "\n" not in text and "about 128 samples missing" in text and "split the record" in text, text


@pytest.mark.parametrize("fmt", ["mat", "npz", "h5"])
def test_a_column_of_a_matrix_of_channels_is_a_channel(tmp_path, fmt):
    # a logger's one matrix of channels (MATLAB 'data', N x 2, beside 'fs'): 'vibration channel 'data' has shape
    # (2000, 2); expected one channel over time', with no way to name a column; now 'data[0]', 'data[1]'
    import h5py
    import scipy.io

    from gearlab.data.recordings import check_recording

    t, acc, tacho = _table()
    data = np.column_stack([acc, tacho])
    path = tmp_path / f"take.{fmt}"
    if fmt == "mat":
        scipy.io.savemat(path, {"data": data, "fs": 25600.0})
    elif fmt == "npz":
        np.savez(path, data=data.T, fs=25600.0)  # channels first: the shorter axis is the channels'
    else:
        with h5py.File(path, "w") as f:
            f["data"] = data
            f["data"].attrs["fs"] = 25600.0
    check_recording(path, "[target]", {"vibration": "data[0]", "tacho": "data[1]"}, unit="m/s^2")
    rec = read_recording(path, "data[0]", "data[1]", unit="m/s^2")
    assert rec.fs == pytest.approx(25600.0)
    assert np.allclose(rec.signal, acc) and np.allclose(rec.tacho, tacho)
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError, match=r"data\[2\]"):
        read_recording(path, "data[2]", unit="m/s^2")


def test_a_speed_channel_given_as_the_tacho_is_named_as_such(tmp_path):
    # a logger's speed channel in rpm ('speed_rpm', 1400 rpm rising 5 %) given as --tacho: 'pulse train has 1 rising
    # edge(s) ... at least 2 once-per-revolution pulses are needed', as though the pulses were too few
    from gearlab.data.recordings import shaft_angle
    from gearlab.errors import GearlabInputError

    t, acc, _ = _table(25600)
    rpm = 1400 * (1 + 0.05 * t / t[-1]) + np.random.default_rng(1).normal(0, 2, t.size)
    path = tmp_path / "speed.csv"
    path.write_text(
        "time_s,acc_ms2,speed_rpm\n" + "\n".join(f"{a:.7f},{b:.6f},{c:.2f}" for a, b, c in zip(t, acc, rpm))
    )
    rec = read_recording(path, "acc_ms2", "speed_rpm")
    with pytest.raises(GearlabInputError) as err:
        shaft_angle(rec)
    text = str(err.value)
    assert "a speed channel?" in text and "'1435 rpm'" in text and "\n" not in text, text


def test_a_text_export_after_a_loggers_preamble_is_read_with_its_rate(tmp_path):
    # the same preamble above a tab-separated .txt (the streamed text reader): 'its first data row (line 2) holds no
    # number'
    t, acc, tacho = _table()
    path = tmp_path / "export.txt"
    rows = "\n".join(f"{a:.7f}\t{b:.6f}\t{k:.3f}" for a, b, k in zip(t, acc, tacho))
    path.write_text("Device: NI-9234\nSample rate: 25600 Hz\n\ntime_s\tacc_ms2\ttacho_V\n" + rows + "\n")
    header = read_header(path)
    assert {"acc_ms2", "tacho_V"} <= set(header.channels) and header.stated[0] == pytest.approx(25600.0)
    rec = read_recording(path, "acc_ms2", "tacho_V")
    assert rec.fs == pytest.approx(25600.0) and np.allclose(rec.signal, np.round(acc, 6))


def test_a_trailing_separator_makes_no_channel(tmp_path):
    # a spreadsheet's export ends every line with ',': the channels read 'acc_ms2, tacho_V, ' (an empty name)
    t, acc, tacho = _table()
    path = tmp_path / "trailing.csv"
    path.write_text(
        "time_s,acc_ms2,tacho_V,\n" + "\n".join(f"{a:.7f},{b:.6f},{k:.3f}," for a, b, k in zip(t, acc, tacho))
    )
    assert read_header(path).channels == ["time_s", "acc_ms2", "tacho_V"]
    rec = read_recording(path, "acc_ms2", "tacho_V")
    assert rec.channels == ["acc_ms2", "tacho_V"] and rec.fs == pytest.approx(25600.0)
