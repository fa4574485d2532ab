"""A [target] 'files' entry may give its own acquisition keys (vibration, tacho, pulses_per_rev,
sensitivity, gain, unit, fs): a history in CSV (column 'acc') and test files in HDF5 (dataset 'vib')
or WAV (channel 0) in one detection scenario (issue 39 item 2: the same keys everywhere)."""

from __future__ import annotations

import dataclasses

import h5py
import numpy as np
import pytest
from scipy.io import wavfile

from gearlab.errors import GearlabInputError
from gearlab.parts.measured import target_spec

FS, SPEED = 6400.0, 25.0
BOX = (
    '[gearbox]\nname = "b"\n[operation]\nspeed = "25 Hz"\nload = "40 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    'pinion = { z = 21, bore = "20 mm" }\nwheel = { z = 53, bore = "30 mm" }\n'
)


def _signal(seconds: float = 2.0) -> np.ndarray:
    t = np.arange(int(FS * seconds)) / FS
    return 3.0 * np.sin(2 * np.pi * 21 * SPEED * t) + 0.5 * np.sin(2 * np.pi * SPEED * t)


def _takes(folder):
    x = _signal()
    # the history: a CSV whose column 'acc' is in g (no unit in its name), its rate in a '# fs' line
    (folder / "h.csv").write_text(f"# fs = {FS:g}\nacc\n" + "".join(f"{v / 9.80665:.7f}\n" for v in x))
    # a test file: HDF5, dataset 'vib' in m/s², 0.5 V per file unit read at 50 mV/(m/s^2) (scale 10)
    with h5py.File(folder / "t.h5", "w") as f:
        f.create_dataset("vib", data=x / 10.0).attrs["fs"] = FS
    # another: a mono float WAV in m/s², channel 0, rate from its header
    wavfile.write(folder / "t.wav", int(FS), x.astype(np.float32))
    (folder / "box.toml").write_text(BOX)


FILES = (
    '{ file = "h.csv", role = "history", label = "healthy" }, '
    '{ file = "t.h5", role = "test", label = "fault", vibration = "vib", unit = "", gain = "0.5 V", '
    'sensitivity = "50 mV/(m/s^2)" }, '
    '{ file = "t.wav", role = "test", label = "healthy", vibration = 0, unit = "m/s^2"%s }'
)


def _scenario(folder, extra: str = "") -> str:
    text = (
        '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
        '[target]\nvibration = "acc"\nunit = "g"\nspeed = "25 Hz"\nfiles = [' + FILES % extra + "]\n"
    )
    (folder / "d.toml").write_text(text)
    return folder / "d.toml"


def _target(folder, **changes):
    files = [
        {"file": "h.csv", "role": "history", "label": "healthy"},
        {
            "file": "t.h5",
            "role": "test",
            "label": "fault",
            "vibration": "vib",
            "unit": "",
            "gain": "0.5 V",
            "sensitivity": "50 mV/(m/s^2)",
        },
        {"file": "t.wav", "role": "test", "label": "healthy", "vibration": 0, "unit": "m/s^2", **changes},
    ]
    return target_spec(_target_table(files), "d.toml: [target]", folder)


def _target_table(files, fs=None) -> dict:
    """A [target] table as the scenario reader leaves it: acc in g at a declared 25 Hz, no tacho."""
    return {
        "vibration": "acc",
        "tacho": "",
        "tacho_shaft": "",
        "pulses_per_rev": None,
        "fs": fs,
        "speed": "25 Hz",
        "gearbox": "",
        "sensitivity": None,
        "gain": None,
        "unit": "g",
        "transient": "none",
        "positive": "fault",
        "files": files,
    }


def test_validate_accepts_per_file_channels_and_units(tmp_path, cli):
    _takes(tmp_path)
    got, out, err = cli("validate", _scenario(tmp_path))
    assert got == 0, (out, err)


def test_each_file_is_read_with_its_own_keys(tmp_path):
    _takes(tmp_path)
    target = _target(tmp_path)
    revs = [target.read(f).revolutions for f in target.files]
    reference = revs[0].mean(axis=0)
    rms = float(np.sqrt(np.mean(reference**2)))
    assert rms > 2.0  # 3 m/s² and 0.5 m/s² lines: the CSV's g read as m/s²
    for r in revs[1:]:  # the HDF5 scaled by gain / sensitivity, the WAV in m/s²: the same record
        assert np.sqrt(np.mean((r.mean(axis=0) - reference) ** 2)) < 0.01 * rms


@pytest.mark.parametrize(
    "extra, key",
    [
        (', fs = "-3 Hz"', "fs"),
        (', unit = "furlong"', "unit"),
        (', gain = "-1 V"', "gain"),
        (", pulses_per_rev = 0", "pulses_per_rev"),
        (', sensitivity = "fast"', "sensitivity"),
        (", vibration = -1", "vibration"),
        (', tacho = "tach"', "tacho"),
        (', colour = "red"', "colour"),
    ],
)
def test_a_bad_per_file_key_is_one_line_naming_the_entry_and_key(tmp_path, cli, extra, key):
    _takes(tmp_path)
    text = _scenario(tmp_path, extra).read_text()
    if key == "vibration":  # the WAV entry's own channel replaced by a bad one
        text = text.replace("vibration = 0, unit", "unit")
    if key == "unit":  # the WAV entry's own unit replaced by a bad one
        text = text.replace(', unit = "m/s^2", unit', ", unit")
    (tmp_path / "d.toml").write_text(text)
    got, out, err = cli("validate", tmp_path / "d.toml")
    assert got == 2, (out, err)
    line = err.strip()
    assert len(line.splitlines()) == 1, line
    assert "[target] key 'files' entry 3" in line and f"'{key}'" in line, line


def test_per_file_values_are_part_of_the_records_identity(tmp_path):
    _takes(tmp_path)
    one, two = _target(tmp_path), _target(tmp_path, unit="g")
    assert one != two and hash(one) != hash(two)
    assert dataclasses.asdict(one) != dataclasses.asdict(two)
    assert dataclasses.asdict(one)["files"][2]["keys"] != dataclasses.asdict(two)["files"][2]["keys"]
    with pytest.raises(GearlabInputError, match="entry 3 key 'unit'"):  # read with the file's own keys
        _target(tmp_path, gain="2 V")


def test_score_reads_new_files_with_their_own_keys():
    """gearlab score --key vibration=vib ...: a new file's own channel keys over the run's [target] keys
    (detection_scoring.reading_keys), as a 'files' entry gives them; a bad one is one line."""
    from gearlab.kinds.detection_scoring import reading_keys

    target = {"vibration": "acc", "tacho": "tach", "pulses_per_rev": 1, "fs": None, "sensitivity": 0.0102, "gain": None}
    meta = {"target": target, "unit": None, "conditions": {"25 Hz": {"speed_hz": 25.0}}}
    given = {"vibration": "vib", "tacho": "pulses", "fs": "25.6 kHz", "sensitivity": "100 mV/g", "unit": "V"}
    keys = reading_keys(meta, None, given)
    assert (keys["vibration"], keys["tacho"], keys["fs"], keys["unit"]) == ("vib", "pulses", 25600.0, "V")
    assert keys["sensitivity"] == pytest.approx(0.1 / 9.80665)
    assert reading_keys(meta, None, {"vibration": "0"})["vibration"] == "0"  # a WAV's or headerless column
    assert reading_keys(meta, None)["vibration"] == "acc"
    for bad, match in (
        ({"vib": "x"}, r"^--key vib=x: expected KEY=VALUE, .*did you mean 'vibration'"),
        ({"fs": "fast"}, r"^--key fs"),
        ({"unit": "furlong"}, r"^--key unit: 'furlong' is a displacement; expected an acceleration"),
    ):
        with pytest.raises(GearlabInputError, match=match):
            reading_keys(meta, None, bad)
    with pytest.raises(GearlabInputError, match=r"^--key tacho: the run read its records without a tacho"):
        reading_keys({**meta, "target": {**target, "tacho": None, "speed_hz": 25.0}}, None, {"tacho": "t"})


def test_the_gap_reads_a_history_at_its_file_s_own_rate(tmp_path):
    """A gap's history read at the rate its 'files' entry gives (the [target]'s 'fs' for the others):
    read_history's rate is the file's, not the [target]'s."""
    from gearlab.kinds.gap_inputs import Records, read_history

    _takes(tmp_path)
    x = _signal()
    (tmp_path / "bare.csv").write_text("acc\n" + "".join(f"{v / 9.80665:.7f}\n" for v in x))  # no rate in it
    t = _target_table([{"file": "bare.csv", "role": "history", "label": "healthy", "fs": "6.4 kHz"}], fs="1 kHz")
    target = target_spec(t, "g.toml: [target]", tmp_path, need=("history",))
    X, speed, _, fs, *_ = read_history(Records("g", target), lambda e: None)
    assert fs == FS and speed == pytest.approx(SPEED)


def test_score_reads_a_file_of_a_new_format_with_the_keys_whose_channels_it_has(tmp_path):
    """Outside round 12 (issue 39): a run of a CSV history (the [target]'s 'accel', 'probe') and WAV tests
    (channels '0', '1', gain 2 V) scored a .mat file with the WAV tests' keys: "no vibration channel '0'",
    no word of --key. A file of a format the run had none of is read with the first remembered keys whose
    channels its header holds (its values at no other file's gain), else one line says what was tried."""
    from scipy.io import savemat

    from gearlab.kinds.detection_scoring import reading_keys

    target = {"vibration": "accel", "tacho": "probe", "pulses_per_rev": 44, "fs": None, "sensitivity": 0.0102}
    target |= {"gain": None, "unit": None}
    wav = {"vibration": "0", "tacho": "1", "gain": 2.0}
    meta = {"target": target, "unit": None, "conditions": {"25 Hz": {"speed_hz": 25.0}}, "tacho_records": "all"}
    meta["file_keys"] = {"formats": {".csv": {}, ".wav": wav, ".zip": {}}, "tests": wav}
    x = _signal()
    wavfile.write(tmp_path / "t.wav", int(FS), np.stack([x, x], axis=1).astype(np.float32))
    savemat(tmp_path / "same.mat", {"accel": x, "probe": x, "fs": FS})
    keys = reading_keys(meta, None, None, str(tmp_path / "same.mat"))
    assert (keys["vibration"], keys["tacho"], keys["gain"]) == ("accel", "probe", None)
    assert reading_keys(meta, None, None, str(tmp_path / "t.wav"))["vibration"] == "0"  # its format's own
    savemat(tmp_path / "other.mat", {"accel_V": x, "probe_V": x, "fs": FS})
    with pytest.raises(GearlabInputError) as err:
        reading_keys(meta, None, None, str(tmp_path / "other.mat"))
    said = str(err.value)
    assert "\n" not in said and said.startswith(f"{tmp_path / 'other.mat'}: ")
    # the WAVs' own keys are not tried on a format the run read none of: named as not applied (test_outside_v)
    for part in (".wav files'", "'accel'", "'probe'", "accel_V", "probe_V", "--key vibration=NAME --key tacho=NAME"):
        assert part in said, said
    given = {"vibration": "accel_V", "tacho": "probe_V"}
    keys = reading_keys(meta, None, given, str(tmp_path / "other.mat"))
    assert (keys["vibration"], keys["tacho"], keys["gain"]) == ("accel_V", "probe_V", None)  # not the WAVs' gain


def test_the_gap_s_target_line_says_how_each_record_s_speed_was_found_with_a_count(tmp_path):
    """Three history records, two of one declared speed: the target line listed two speeds for three records (two
    texts alike, said once); each text now says how many records it stands for."""
    from gearlab.kinds.gap_inputs import Records, read_history

    _takes(tmp_path)
    for i in (2, 3):
        (tmp_path / f"h{i}.csv").write_text((tmp_path / "h.csv").read_text())
    speeds = {"h.csv": "25 Hz", "h2.csv": "25.1 Hz", "h3.csv": "25 Hz"}
    files = [{"file": f, "role": "history", "label": "healthy", "speed": s} for f, s in speeds.items()]
    target = target_spec(_target_table(files), "g.toml: [target]", tmp_path, need=("history",))
    _, _, notes, *_ = read_history(Records("g", target), lambda e: None)
    line = next(n for n in notes if n.startswith("target: "))
    assert "of 3 history record(s) at 25.033 Hz (2 records: nominal speed 25 Hz; 1 record: nominal speed 25.1 Hz)" in (
        line
    )
