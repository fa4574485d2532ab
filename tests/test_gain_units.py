"""Units of an acquisition chain's `sensitivity` and `gain` (issue 39 item 2): every dimensionally valid
form -- a sensitivity in V per g or per m/s², its inverse (g per V), a gain in volts per file unit with a
sensitivity, a gain in g or m/s² per volt, a gain in g or m/s² per file unit (a WAV's full scale) -- gives
the same acceleration in m/s²; a form of the wrong dimension, a gain in g beside a sensitivity, and a gain
in volts without one are each one line naming the file's table and key, exit 2 at `gearlab validate`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.io import wavfile

import gearlab

G = 9.80665
FS = 8000
ACC = 30.0 * np.sin(2 * np.pi * 400 * np.arange(FS) / FS)  # m/s², peaks of about 3 g


def _npz(path: Path, values: np.ndarray) -> Path:
    np.savez(path, acc=values, fs=float(FS))
    return path


VOLTS = ACC / G * 0.1  # a 100 mV/g accelerometer
# (file maker, keys) that must all read ACC
FORMS = [
    ("volts", {"sensitivity": "100 mV/g"}),
    ("volts", {"sensitivity": "10.1971621 mV/(m/s^2)"}),
    ("volts", {"sensitivity": "10 g/V"}),  # the inverse: g per volt
    ("volts", {"gain": "10 g/V"}),
    ("volts", {"gain": "98.0665 m/s^2/V"}),
    ("volts", {"gain": "2 V", "sensitivity": "200 mV/g"}),
    ("fifty_g_float_wav", {"gain": "50 g"}),  # a float WAV whose full scale (1.0) is 50 g
    ("fifty_g_float_wav", {"gain": "490.3325 m/s^2"}),
    ("fifty_g_float_wav", {"gain": "50 V", "sensitivity": "1 V/g"}),  # the guide's older way, still read
    ("fifty_g_int16_wav", {"gain": "50 g"}),  # int16 WAV read as +-1: 50 g at full scale
    ("milli_g_counts", {"gain": "0.001 g"}),  # integer counts of 1 mg each
]
IDS = [
    "mV/g",
    "mV/(m/s^2)",
    "sensitivity g/V",
    "gain g/V",
    "gain m/s^2/V",
    "gain V + sensitivity",
    "float wav 50 g",
    "float wav m/s^2",
    "float wav 50 V + 1 V/g",
    "int16 wav 50 g",
    "counts 0.001 g",
]


def _file(tmp_path: Path, kind: str) -> tuple[Path, float]:
    """The file and the tolerance its storage allows (m/s²)."""
    if kind == "volts":
        return _npz(tmp_path / "v.npz", VOLTS), 1e-6
    if kind == "fifty_g_float_wav":
        wavfile.write(tmp_path / "f.wav", FS, (ACC / G / 50.0).astype(np.float32))
        return tmp_path / "f.wav", 1e-5
    if kind == "fifty_g_int16_wav":
        wavfile.write(tmp_path / "i.wav", FS, np.round(ACC / G / 50.0 * 32768).astype(np.int16))
        return tmp_path / "i.wav", 50 * G / 32768
    counts = np.round(ACC / G * 1000).astype(np.int32)
    return _npz(tmp_path / "c.npz", counts), 0.5e-3 * G * 1.0001


@pytest.mark.parametrize(("kind", "keys"), FORMS, ids=IDS)
def test_every_valid_form_reads_the_same_acceleration(tmp_path, kind, keys):
    path, tol = _file(tmp_path, kind)
    vibration = "acc" if path.suffix == ".npz" else "0"
    got = gearlab.read_recording(path, vibration, **keys)
    assert np.max(np.abs(got.signal - ACC)) <= tol


def _scenario(tmp_path: Path, keys: str) -> Path:
    t = np.arange(FS * 2) / FS
    theta = 2 * np.pi * 25.0 * t
    np.savez(tmp_path / "r.npz", acc=0.1 * np.sin(20 * theta), tacho=np.where(theta % (2 * np.pi) < 0.4, 5.0, 0.0))
    path = tmp_path / "s.toml"
    path.write_text(
        '[scenario]\nname = "d"\nkind = "dataset"\n[[datasets]]\nfile = "r.npz"\nvibration = "acc"\n'
        f'tacho = "tacho"\nfs = "{FS} Hz"\n{keys}\n'
    )
    return path


WRONG = [
    ('gain = "2 m/s"', "gain", "'2 m/s'"),
    ('sensitivity = "100 mV/Hz"', "sensitivity", "'100 mV/Hz'"),
    ('gain = "50 g"\nsensitivity = "100 mV/g"', "gain", "expected no sensitivity"),
    ('gain = "2 g/V"\nsensitivity = "100 mV/g"', "gain", "expected no sensitivity"),
    ('gain = "2 V"', "gain", "expected a sensitivity"),
]


@pytest.mark.parametrize(("keys", "key", "said"), WRONG, ids=["gain m/s", "mV/Hz", "g + sens", "g/V + sens", "V alone"])
def test_a_wrong_form_is_one_line_at_validate(tmp_path, cli, keys, key, said):
    code, _, err = cli("validate", _scenario(tmp_path, keys))
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, err
    assert "s.toml" in line and f"[[datasets]] #1 key '{key}'" in line and said in line, line


def test_the_valid_forms_pass_validate(tmp_path, cli):
    for keys in ('gain = "10 g/V"', 'sensitivity = "10 g/V"', 'gain = "2 V"\nsensitivity = "200 mV/g"'):
        code, _, err = cli("validate", _scenario(tmp_path, keys))
        assert code == 0, (keys, err)


def test_inspect_takes_the_same_forms():
    from gearlab.notebook import inspect_options

    for gain in ("50 g", "490.3325 m/s^2"):
        opts = inspect_options(gain=gain)
        assert opts.gain / opts.sensitivity == pytest.approx(50 * G)
    opts = inspect_options(gain="10 g/V")
    assert opts.gain is None and 1 / opts.sensitivity == pytest.approx(10 * G)


@pytest.mark.parametrize(("keys", "said"), [({"gain": "50 g"}, "50 g a file unit"), ({"gain": "10 g/V"}, "100 mV/g")])
def test_the_line_saying_how_values_became_m_s2_speaks_in_g(tmp_path, keys, said):
    path, _ = _file(tmp_path, "fifty_g_float_wav")
    assert said in gearlab.read_recording(path, "0", **keys).units


def test_score_takes_a_gain_in_g_over_the_run_s_sensitivity():
    """`gearlab score --key gain=...` on a run read at 100 mV/g: a gain in g replaces the run's sensitivity (a
    file in g at a full scale), a gain in volts keeps it; a gain in g beside --key sensitivity is one line."""
    from gearlab.errors import GearlabInputError
    from gearlab.kinds.detection_scoring import reading_keys

    target = {"vibration": "acc", "tacho": "tach", "pulses_per_rev": 1, "sensitivity": 0.1 / G, "gain": None}
    run = {"target": target, "conditions": {"25 Hz": {"speed_hz": 25.0}}}
    full = reading_keys(run, None, {"gain": "50 g"})
    assert full["gain"] / full["sensitivity"] == pytest.approx(50 * G)
    volts = reading_keys(run, None, {"gain": "2 V"})
    assert volts["gain"] / volts["sensitivity"] == pytest.approx(20 * G)
    with pytest.raises(GearlabInputError, match=r"^--key gain: '50 g' is an acceleration per file unit"):
        reading_keys(run, None, {"gain": "50 g", "sensitivity": "100 mV/g"})


def test_inspect_names_the_gain_in_g_given_on_a_channel_in_g(tmp_path, cli):
    np.savez(tmp_path / "g.npz", acc_g=ACC / G, fs=float(FS))
    code, _, err = cli("inspect", tmp_path / "g.npz", "--vibration", "acc_g", "--speed", "25 Hz", "--gain", "50 g")
    assert code == 2 and "--gain: channel 'acc_g' is an acceleration (g: its name); expected no --gain" in err, err
