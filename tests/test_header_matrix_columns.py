"""A channel named as a column of a matrix of channels ('data[2]') is checked against the array's shape
in the file's header, at validate time: a column out of range, a matrix column of a one-column channel
(a CSV's), or of an array that is no N x k matrix, is one line naming the file, the table, the key and
what the array holds (issue 39: a MAT v5 'data' of 2 columns passed validate with 'data[2]')."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
import scipy.io

from gearlab.data.recordings import check_recording, read_recording
from gearlab.errors import GearlabInputError

FS = 25600.0


def _data(n=2000):
    t = np.arange(n) / FS
    return np.column_stack([np.sin(2 * np.pi * 450.0 * t), 5.0 * (np.mod(t * 23.4, 1.0) < 0.5)])


def _write(tmp_path, fmt):
    data = _data()
    path = tmp_path / f"take.{fmt}"
    if fmt == "mat":
        scipy.io.savemat(path, {"data": data, "fs": FS})
    elif fmt == "mat-struct":
        path = tmp_path / "take.mat"
        scipy.io.savemat(path, {"rec": {"data": data, "fs": FS}})
    elif fmt == "mat-compressed":
        path = tmp_path / "take.mat"
        scipy.io.savemat(path, {"data": data, "fs": FS}, do_compression=True)
    elif fmt == "mat4":  # MATLAB v4: its variables' 20-byte headers give the shapes too
        path = tmp_path / "take.mat"
        scipy.io.savemat(path, {"data": data, "fs": FS}, format="4")
    elif fmt == "npz":
        np.savez(path, data=data.T, fs=FS)
    else:
        with h5py.File(path, "w") as f:
            f["data"] = data
            f["data"].attrs["fs"] = FS
    return path


def _refusal(path, channel) -> str:
    with pytest.raises(GearlabInputError) as err:
        check_recording(path, "s.toml: [target]", {"vibration": channel}, unit="m/s^2")
    text = str(err.value)
    assert "\n" not in text and str(path) in text and "s.toml: [target] key 'vibration'" in text, text
    return text


@pytest.mark.parametrize("fmt", ["mat", "mat-struct", "mat-compressed", "mat4", "npz", "h5"])
def test_a_column_out_of_range_fails_at_validate_time(tmp_path, fmt):
    path = _write(tmp_path, fmt)
    check_recording(path, "s.toml: [target]", {"vibration": "data[0]", "tacho": "data[1]"}, unit="m/s^2")
    text = _refusal(path, "data[2]")
    assert "2 channels" in text and "'data[0]' … 'data[1]'" in text, text
    with pytest.raises(GearlabInputError):  # the run refuses it too
        read_recording(path, "data[2]", unit="m/s^2")


def test_a_mat_matrix_named_whole_fails_at_validate_time(tmp_path):
    # as an HDF5 (N, 2) dataset already did: 'holds an array of shape ...; expected one channel over time'
    text = _refusal(_write(tmp_path, "mat"), "data")
    assert "shape (2000, 2)" in text and "'data[0]'" in text, text


def test_a_mat4_file_lists_its_variables_and_a_cut_one_is_refused(tmp_path):
    # a v4 file's header listed nothing (every name passed validate; the run then refused it)
    path = _write(tmp_path, "mat4")
    check_recording(path, "s.toml: [target]", {"vibration": "data[0]"}, unit="m/s^2")
    text = _refusal(path, "acc")
    assert "no channel 'acc'" in text and "channels: data (and the sampling rate 'fs')" in text, text
    path.write_bytes(path.read_bytes()[:20_000])  # a copy stopped early: 'data' declares 64,000 bytes
    with pytest.raises(GearlabInputError, match=r"key 'file': cannot read .* past the end of the file"):
        check_recording(path, "s.toml: [target]", {"vibration": "data[0]"}, unit="m/s^2")


def test_a_column_of_a_csv_column_fails_at_validate_time(tmp_path):
    data = _data()
    path = tmp_path / "take.csv"
    path.write_text("time_s,acc,tacho\n" + "\n".join(f"{i / FS:.7f},{a:.6f},{b:.1f}" for i, (a, b) in enumerate(data)))
    text = _refusal(path, "acc[1]")
    assert "'acc' is one column" in text and "expected 'acc'" in text, text
    with pytest.raises(GearlabInputError):
        read_recording(path, "acc[1]", unit="m/s^2")


def test_a_column_of_an_array_of_three_axes_fails_naming_its_shape(tmp_path):
    path = tmp_path / "take.h5"
    with h5py.File(path, "w") as f:
        f["cube"] = np.zeros((100, 2, 2))
        f["cube"].attrs["fs"] = FS
    text = _refusal(path, "cube[0]")
    assert "shape (100, 2, 2)" in text and "not a matrix of channels" in text, text


def test_validate_names_the_column_out_of_range(tmp_path, cli):
    scipy.io.savemat(tmp_path / "take.mat", {"data": _data(), "fs": FS})
    scipy.io.savemat(tmp_path / "test.mat", {"data": _data(), "fs": FS})
    (tmp_path / "box.toml").write_text(
        '[gearbox]\nname = "b"\n[operation]\nspeed = "25 Hz"\nload = "40 N*m"\n'
        '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
        'pinion = { z = 21, bore = "20 mm" }\nwheel = { z = 53, bore = "30 mm" }\n'
    )
    (tmp_path / "d.toml").write_text(
        '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
        '[target]\nvibration = "data[2]"\nunit = "m/s^2"\nspeed = "25 Hz"\n'
        'files = [{ file = "take.mat", role = "history", label = "healthy" }, '
        '{ file = "test.mat", role = "test", label = "fault" }]\n'
    )
    got, out, err = cli("validate", tmp_path / "d.toml")
    assert got == 2, (out, err)
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "take.mat" in lines[0] and "'vibration'" in lines[0] and "data[1]" in lines[0], err


def test_a_matrix_whose_columns_are_named_is_no_channel_to_inspect_as_to_validate(tmp_path, cli):
    # issue 39: an HDF5 (N, 3) 'data' whose attribute names its columns: validate said "no channel 'data'; the
    # file has channels: acc_in, acc_out, tacho", inspect and the run a shape refusal with a 'data[0]' … hint
    path = tmp_path / "take.h5"
    with h5py.File(path, "w") as f:
        f["data"] = np.column_stack([_data(), _data()[:, 0]])[:, [0, 2, 1]]
        f["data"].attrs["fs"] = FS
        f["data"].attrs["channel_names"] = ["acc_in", "acc_out", "tacho"]
    listed = "no channel 'data' (a vibration channel: acc_in, acc_out?); the file has channels: acc_in, acc_out, tacho"
    assert listed in _refusal(path, "data")
    with pytest.raises(GearlabInputError) as err:
        read_recording(path, "data", unit="m/s^2")
    assert str(err.value) == f"{path}: {listed.replace('no channel', 'no vibration channel')}"
    got, out, err_text = cli("inspect", path, "--vibration", "data")
    lines = [line for line in err_text.splitlines() if line.strip()]
    assert got == 2 and len(lines) == 1 and listed.replace("no channel", "no vibration channel") in lines[0], err_text
    assert read_recording(path, "data[1]", "tacho", unit="m/s^2").signal.size == 2000  # its columns still read
