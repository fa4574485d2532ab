"""Bad measured files and rates, each one line and exit 2, at validate time where the header suffices:
an empty file of any format (the readers' own words said nothing of it: 'file signature not found',
'File is not a zip file'), a sampling rate written as a shaft speed ('6400 rpm' was read as pint's
670 Hz and passed), a data sheet's 'kS/s' (refused as siemens per second), a text cell in a CSV's data
column, an HDF5 dataset of the wrong rank."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from gearlab.notebook import read_recording

FS = 6400.0
BOX = (
    '[gearbox]\nname = "b"\n[operation]\nspeed = "25 Hz"\nload = "40 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    'pinion = { z = 21, bore = "20 mm" }\nwheel = { z = 53, bore = "30 mm" }\n'
)


def _signal(n=12800):
    t = np.arange(n) / FS
    return t, 3.0 * np.sin(2 * np.pi * 525 * t) + 0.5 * np.sin(2 * np.pi * 25 * t)


def _scenario(folder, history: str, extra: str = "") -> object:
    _, x = _signal()
    (folder / "test.csv").write_text("acc\n" + "".join(f"{v:.6f}\n" for v in x))
    (folder / "box.toml").write_text(BOX)
    path = folder / "d.toml"
    path.write_text(
        '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
        f'[target]\nvibration = "acc"\nunit = "m/s^2"\nspeed = "25 Hz"\n{extra}\n'
        f'files = [{{ file = "{history}", role = "history", label = "healthy" }}, '
        '{ file = "test.csv", role = "test", label = "fault" }]\n'
    )
    return path


def _one_line(cli, *args) -> str:
    got, out, err = cli(*args)
    lines = [line for line in err.splitlines() if line.strip()]
    assert got == 2 and len(lines) == 1, (got, out, err)
    return lines[0]


@pytest.mark.parametrize("name", ["h.csv", "h.txt", "h.h5", "h.npz", "h.wav", "h.mat", "h.zip"])
def test_an_empty_file_is_named_as_empty(tmp_path, cli, name):
    (tmp_path / name).write_bytes(b"")
    line = _one_line(cli, "validate", _scenario(tmp_path, name, 'fs = "6.4 kHz"'))
    assert f"key 'file': {tmp_path / name}: is empty (0 bytes); expected a measured record" in line, line
    assert "is empty (0 bytes)" in _one_line(cli, "inspect", tmp_path / name, "--fs", "6.4 kHz", "--speed", "25 Hz")


@pytest.mark.parametrize("rate", ["6400 rpm", "6400 rad/s", "366700 deg/s"])
def test_a_rate_written_as_a_shaft_speed_is_refused(tmp_path, cli, rate):
    _, x = _signal()
    (tmp_path / "h.csv").write_text("acc\n" + "".join(f"{v:.6f}\n" for v in x))
    line = _one_line(cli, "validate", _scenario(tmp_path, "h.csv", f'fs = "{rate}"'))
    assert "[target] key 'fs'" in line and "rotational speed, not a sampling rate" in line, line
    line = _one_line(cli, "inspect", tmp_path / "h.csv", "--fs", rate, "--speed", "25 Hz")
    assert "--fs" in line and "rotational speed" in line, line


@pytest.mark.parametrize("rate", ["6400 S/s", "6.4 kS/s", "6.4 kSa/s"])
def test_a_rate_in_samples_per_second_is_hertz(tmp_path, cli, rate):
    _, x = _signal()
    (tmp_path / "h.csv").write_text("acc\n" + "".join(f"{v:.6f}\n" for v in x))
    assert cli("validate", _scenario(tmp_path, "h.csv", f'fs = "{rate}"'))[0] == 0
    assert read_recording(tmp_path / "h.csv", "acc", fs=rate, unit="m/s^2").fs == pytest.approx(FS)


def test_a_text_cell_in_a_data_column_is_one_line(tmp_path, cli):
    t, x = _signal()
    rows = [f"{a:.7f},{b:.6f}" for a, b in zip(t, x)]
    rows[500] = f"{t[500]:.7f},overload"
    (tmp_path / "h.csv").write_text("time_s,acc\n" + "\n".join(rows) + "\n")
    line = _one_line(cli, "inspect", tmp_path / "h.csv", "--speed", "25 Hz")
    assert "'overload' at sample 500" in line and "expected numbers" in line, line


def test_an_hdf5_dataset_of_the_wrong_rank_is_refused_at_validate(tmp_path, cli):
    with h5py.File(tmp_path / "h.h5", "w") as f:
        f["acc"] = np.zeros((10, 20, 30))
        f["acc"].attrs["fs"] = FS
    line = _one_line(cli, "validate", _scenario(tmp_path, "h.h5"))
    assert "key 'vibration'" in line and "shape (10, 20, 30)" in line and "expected one channel over time" in line
