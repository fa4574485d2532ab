"""A unit a file states for the vibration channel (an HDF5 'units' attribute, a CSV row of units under the
names) or its name says ('acc_mg') is read as the quantity it names, prefix and number included (issue 39
item 2): milli-g, '50 g' (a full scale of 50 g per file unit), cm/s², µV with a sensitivity give the same
m/s² as the data written in m/s²; before, each was read as g (a factor 1000 or 50 off) or silently as
m/s². What the reader assumed is one line of inspect's output; a unit it cannot read is named there."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from gearlab.data.recordings import read_recording

G = 9.80665
FS = 2000.0
ACC = 20.0 * np.sin(2 * np.pi * 100 * np.arange(int(FS)) / FS)  # m/s²

STATED = [  # (unit, m/s² per file unit, keys)
    ("g", G, {}),
    ("mg", G / 1000, {}),
    ("milli-g", None, {}),  # not read: taken as stated nowhere, never as g
    ("50 g", 50 * G, {}),
    ("cm/s^2", 0.01, {}),
    ("m s-2", 1.0, {}),
    ("uV", 1e-6 / (0.1 / G), {"sensitivity": 0.1 / G}),
]


def _h5(path: Path, values: np.ndarray, unit: str) -> Path:
    path = path.with_suffix(".h5")
    with h5py.File(path, "w") as f:
        f.create_dataset("acc", data=values).attrs["units"] = unit
        f.attrs["fs"] = FS
    return path


def _csv(path: Path, values: np.ndarray, unit: str) -> Path:
    path = path.with_suffix(".csv")
    rows = "\n".join(f"{i / FS:.6f},{v:.12g}" for i, v in enumerate(values))
    path.write_text(f"time_s,acc\ns,{unit}\n{rows}\n")
    return path


@pytest.mark.parametrize("write", [_h5, _csv], ids=["h5 attribute", "csv units row"])
@pytest.mark.parametrize(("unit", "factor", "keys"), STATED, ids=[s[0] for s in STATED])
def test_a_stated_unit_is_read_with_its_prefix_and_number(tmp_path, write, unit, factor, keys):
    if factor is None:  # unreadable: the values are not scaled by a guess, and the line says what the file said
        got = read_recording(write(tmp_path / "r", ACC, unit), "acc")
        assert np.allclose(got.signal, ACC, rtol=1e-10, atol=1e-10) and f"'{unit}'" in got.units, got.units
        return
    got = read_recording(write(tmp_path / "r", ACC / factor, unit), "acc", **keys)
    assert np.max(np.abs(got.signal - ACC)) < 1e-8 * 20, got.units
    assert got.units.startswith("m/s² = value x") or factor == 1.0, got.units


@pytest.mark.parametrize(("name", "factor"), [("acc_mg", G / 1000), ("acc [mg]", G / 1000), ("acc_g", G)])
def test_a_name_s_unit_is_read_with_its_prefix(tmp_path, name, factor):
    np.savez(tmp_path / "n.npz", **{name: ACC / factor}, fs=FS)
    got = read_recording(tmp_path / "n.npz", name)
    assert np.max(np.abs(got.signal - ACC)) < 1e-8 * 20, got.units


def test_inspect_says_what_the_reader_assumed(tmp_path, cli):
    path = _h5(tmp_path / "r.h5", ACC / (50 * G), "50 g")
    code, out, err = cli("inspect", path, "--vibration", "acc", "--speed", "25 Hz")
    assert code == 0, err
    assert "value x 490.332 (channel 'acc' in 50 g: one file unit is 50 g)" in out, out


@pytest.mark.parametrize("write", [_h5, _csv], ids=["h5 attribute", "csv units row"])
@pytest.mark.parametrize(
    ("unit", "meant", "key", "keys"),
    [("G", "g", "unit", {"unit": "g"}), ("50 G", "50 g", "gain", None), ("MV", "mV", "unit", None)],
)
def test_a_stated_unit_in_another_case_is_refused_as_the_unit_key_is(tmp_path, write, unit, meant, key, keys):
    # a file's 'G' was read as g and a 'MV' as megavolts (10⁹ x a millivolt), while unit = "G" was refused with
    # "did you mean 'g'?": one rule now, the file's refusal naming the file and the key that reads it
    from gearlab.data.channel_units import declared_unit
    from gearlab.errors import GearlabInputError

    path = write(tmp_path / "r", ACC / G, unit)
    with pytest.raises(GearlabInputError) as file_said:
        read_recording(path, "acc", where="s.toml: [target]")
    line = str(file_said.value)
    assert "\n" not in line and line.startswith(f"s.toml: [target] key '{key}': missing;"), line
    assert f"{path} states its unit as '{unit}', not '{meant}'" in line and f"{key} = '{meant}'" in line, line
    with pytest.raises(GearlabInputError, match=f"did you mean '{meant}'|gain = '{meant}'"):  # the 'unit' key's
        declared_unit(unit, "s.toml: [target] key 'unit'")
    if keys is not None:  # the key the refusal names reads the file
        got = read_recording(path, "acc", **keys)
        assert np.max(np.abs(got.signal - ACC)) < 1e-8 * 20, got.units


def test_inspect_names_the_option_that_reads_a_stated_unit_in_another_case(tmp_path, cli):
    path = _h5(tmp_path / "r.h5", ACC / G, "G")
    code, out, err = cli("inspect", path, "--vibration", "acc", "--speed", "25 Hz", "--json")
    units = json.loads(out)["units"] if code == 0 else err  # any column is inspected: as stored, and why
    assert units.startswith("value x 1, not m/s² (") and "states its unit as 'G'" in units, units
    assert units.endswith("e.g. --unit 'g')"), units
    code, out, err = cli("inspect", path, "--vibration", "acc", "--speed", "25 Hz", "--unit", "g")
    assert code == 0 and "not m/s²" not in out and "in g" in out, (out, err)


def test_a_full_scale_given_as_the_unit_key_is_refused_naming_the_gain(tmp_path):
    # unit = "50 g" was read as g, its 50 dropped: the values 50 x too small, unsaid
    from gearlab.errors import GearlabInputError

    np.savez(tmp_path / "n.npz", acc=ACC / (50 * G), fs=FS)
    said = r"key 'unit': '50 g' is a full scale, not a unit; .*\(gain = '50 g'\)$"
    with pytest.raises(GearlabInputError, match=said):
        read_recording(tmp_path / "n.npz", "acc", unit="50 g", where="s.toml: [target]")
