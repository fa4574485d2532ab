"""The one import path of a measured recording (gearlab.data.recordings; issue 39, item 2): every
format and layout gives the same revolutions, units follow the sensitivity and the channel's name,
time columns under their common names, a record without a tacho, and `gearlab validate` refusing
a wrong column, a missing rate or a unit mistake from the file's header alone."""

import io
import json
import re
import zipfile
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
from gearboxes import description, stage
from scipy.io import wavfile

from gearlab.data.importers import MeasuredSpec, import_measured
from gearlab.data.recordings import check_recording, cut_recording, read_header, read_recording, time_scale
from gearlab.errors import GearlabInputError

FS = 10_000.0
SPEED = 25.0
TEETH = 20
REVS = 24
N = int(FS / SPEED * REVS)
SENSITIVITY = 0.1 / 9.80665  # 100 mV/g in V per m/s²


def signals(seed=0):
    """(time s, acceleration m/s², once-per-revolution tacho V) of a 20-tooth pinion at 25 Hz."""
    t = np.arange(N) / FS
    theta = 0.4 + 2 * np.pi * SPEED * t
    acc = 3.0 * np.sin(TEETH * theta) + 0.5 * np.sin(theta) + 0.2 * np.random.default_rng(seed).standard_normal(N)
    tacho = np.where(np.mod(theta, 2 * np.pi) < 0.4, 5.0, 0.0)
    return t, acc, tacho


def delimited(path: Path, columns: dict, sep: str, header: bool = True, decimal: str = ".") -> Path:
    names = list(columns)
    rows = np.column_stack([columns[n] for n in names])
    # each value '%.9g' (as f"{v:.9g}"), formatted in one operation rather than row by row (textrecords.text)
    body = ((sep.join(["%.9g"] * len(names)) + "\n") * len(rows)) % tuple(rows.ravel().tolist())
    path.write_text((sep.join(names) + "\n" if header else "") + body.replace(".", decimal))
    return path


@pytest.fixture(scope="module")
def reference():
    t, acc, tacho = signals()
    return cut_recording_of(acc, tacho)


def cut_recording_of(acc, tacho):
    """The revolutions of the signals through an NPZ with an 'fs' field (the reference layout)."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "ref.npz"
        np.savez(path, acc=acc, tacho=tacho, fs=FS)
        return cut_recording(path, vibration="acc", tacho="tacho").revolutions


def layouts(tmp_path: Path) -> dict[str, tuple[Path, dict]]:
    """The same recording in every format and layout: (file, the keys a scenario would give)."""
    t, acc, tacho = signals()
    volts = acc * SENSITIVITY
    out = {}
    for name, sep in (("comma", ","), ("semicolon", ";"), ("tab", "\t"), ("blanks", "  ")):
        cols = {"time_s": t, "acc_V": volts, "tacho_V": tacho}
        out[f"csv {name}"] = (
            delimited(tmp_path / f"{name}.csv", cols, sep, decimal="," if sep == ";" else "."),
            {"vibration": "acc_V", "tacho": "tacho_V", "sensitivity": SENSITIVITY},
        )
    out["csv no header"] = (
        delimited(tmp_path / "bare.csv", {"a": volts, "b": tacho}, ",", header=False),
        {"vibration": 0, "tacho": 1, "sensitivity": SENSITIVITY, "fs": FS},
    )
    out["csv Time [s], m/s^2"] = (
        delimited(tmp_path / "si.csv", {"Time [s]": t, "acc [m/s^2]": acc, "tacho": tacho}, ","),
        {"vibration": "acc [m/s^2]", "tacho": "tacho"},
    )
    out["csv t (ms), g"] = (
        delimited(tmp_path / "ms.csv", {"t (ms)": t * 1e3, "acc_g": acc / 9.80665, "tacho": tacho}, ","),
        {"vibration": "acc_g", "tacho": "tacho"},
    )
    text = io.StringIO()
    np.savetxt(text, np.column_stack([volts, tacho]), fmt="%.9g")
    with zipfile.ZipFile(tmp_path / "rec.zip", "w") as z:
        z.writestr("rec.txt", text.getvalue())
    out["zipped text"] = (tmp_path / "rec.zip", {"vibration": 0, "tacho": "1", "sensitivity": SENSITIVITY, "fs": FS})
    (tmp_path / "rec.txt").write_text("acc tacho\n" + text.getvalue())
    out["text with header"] = (
        tmp_path / "rec.txt",
        {"vibration": "acc", "tacho": "tacho", "sensitivity": SENSITIVITY, "fs": FS},
    )
    np.savez(tmp_path / "rec.npz", acc=volts, tacho=tacho, t=t)
    out["npz"] = (tmp_path / "rec.npz", {"vibration": "acc", "tacho": "tacho", "sensitivity": SENSITIVITY})
    with h5py.File(tmp_path / "rec.h5", "w") as f:
        g = f.create_group("run1")
        g.attrs["fs"] = FS
        g["acc"], g["tacho"] = acc, tacho
    out["h5"] = (tmp_path / "rec.h5", {"vibration": "run1/acc", "tacho": "run1/tacho"})
    scipy.io.savemat(tmp_path / "rec.mat", {"acc": volts, "tacho": tacho, "Fs": FS})
    out["mat"] = (tmp_path / "rec.mat", {"vibration": "acc", "tacho": "tacho", "sensitivity": SENSITIVITY})
    full_scale = 2.0  # V at full scale of the 16-bit PCM
    pcm = np.column_stack([volts / full_scale, tacho / 10.0])
    wavfile.write(tmp_path / "rec.wav", int(FS), np.round(pcm * 32767).astype(np.int16))
    out["wav"] = (
        tmp_path / "rec.wav",
        {"vibration": "0", "tacho": "1", "sensitivity": SENSITIVITY, "gain": full_scale * 32767 / 32768},
    )
    return out


def test_every_format_and_layout_gives_the_same_revolutions(tmp_path, reference):
    for name, (path, keys) in layouts(tmp_path).items():
        check_recording(path, name, {k: keys[k] for k in ("vibration", "tacho")}, **_units(keys))
        revs = cut_recording(path, **keys).revolutions
        assert revs.shape == reference.shape, name
        tol = 2e-3 if name == "wav" else 1e-5
        assert np.max(np.abs(revs - reference)) <= tol * np.max(np.abs(reference)), name


def _units(keys: dict) -> dict:
    return {k: keys[k] for k in ("fs", "sensitivity", "gain") if k in keys}


@pytest.mark.parametrize(
    "name,scale",
    [("t", 1.0), ("time", 1.0), ("time_s", 1.0), ("Time [s]", 1.0), ("t (ms)", 1e-3), ("Time_ms", 1e-3),
     ("timestamp", 1.0), ("time [us]", 1e-6), ("acc", None), ("tacho", None), ("theta", None)],
)  # fmt: skip
def test_time_columns_under_their_common_names(name, scale):
    assert time_scale(name) == scale


def test_header_checks_name_the_table_key_and_file(tmp_path):
    path, _ = layouts(tmp_path)["csv comma"]
    where = "s.toml: [[datasets]] #1"

    def refused(channels, key, *facts, **given):
        with pytest.raises(GearlabInputError) as info:
            check_recording(path, where, channels, **given)
        text = str(info.value)
        assert "\n" not in text and text.startswith(f"{where} key '{key}'") and str(path) in text or key != "vibration"
        for fact in facts:
            assert fact in text, text

    listed = "channels: acc_V, tacho_V (and the time 'time_s')"
    refused({"vibration": "acc_v", "tacho": "tacho_V"}, "vibration", "did you mean 'acc_V'", listed)
    refused({"vibration": "acc_V"}, "sensitivity", "in volts", "100 mV/g")
    with pytest.raises(GearlabInputError, match="key 'fs'.*no sampling rate"):
        check_recording(layouts(tmp_path)["csv no header"][0], where, {"vibration": 0}, sensitivity=1.0)
    si, _ = layouts(tmp_path)["csv Time [s], m/s^2"]
    with pytest.raises(GearlabInputError, match="key 'sensitivity'.*an acceleration already"):
        check_recording(si, where, {"vibration": "acc [m/s^2]"}, sensitivity=0.01)
    wav, _ = layouts(tmp_path)["wav"]
    with pytest.raises(GearlabInputError, match="key 'gain'.*integer counts"):
        check_recording(wav, where, {"vibration": "0"}, sensitivity=0.01)
    assert read_header(wav).rate and read_header(wav).channels == ["0", "1"]


@pytest.mark.parametrize(
    "written, said",
    [
        (100, "100 (100 V per m/s²)"),  # a bare number is V per m/s²: meant as 100 mV/g, 1000 times off
        ("100 V/g", "'100 V/g' (10.2 V per m/s²)"),
        ("0.001 mV/g", "'0.001 mV/g' (1.02e-07 V per m/s²)"),
    ],
)
def test_a_sensitivity_no_accelerometer_has_is_refused(written, said):
    from gearlab.data.textzip import parse_sensitivity

    with pytest.raises(GearlabInputError) as info:
        parse_sensitivity(written, "s.toml: [target] key 'sensitivity'")
    assert str(info.value) == (
        f"s.toml: [target] key 'sensitivity': {said} is no accelerometer's sensitivity (0.01 mV/g to 10 V/g); "
        "expected one with its unit, e.g. '100 mV/g'"
    )
    assert parse_sensitivity("10 V/g", "x") == pytest.approx(10 / 9.80665)
    assert parse_sensitivity(0.0102, "x") == 0.0102


def test_validate_refuses_bad_input_in_one_line_from_the_header(cli, tmp_path):
    layouts(tmp_path)
    scenario = tmp_path / "s.toml"
    base = '[scenario]\nname = "s"\nkind = "dataset"\n[[datasets]]\nfile = "comma.csv"\n'
    cases = [
        ('vibration = "acc_V"\ntacho = "tacho"\nsensitivity = "100 mV/g"\n', "key 'tacho'", "did you mean"),
        ('vibration = "acc_V"\ntacho = "tacho_V"\n', "key 'sensitivity'", "in volts"),
        ('vibration = "acc_V"\ntacho = "tacho_V"\nsensitivity = "100 mV/g"\nfile = "nope.csv"\n', "", "no such file"),
    ]
    for extra, key, fact in cases:
        text = base + extra
        if 'file = "nope.csv"' in extra:
            text = text.replace('file = "comma.csv"\n', "")
        scenario.write_text(text)
        code, _, err = cli("validate", scenario)
        assert code == 2 and len(err.strip().splitlines()) == 1 and key in err and fact in err, err
    scenario.write_text(base + 'vibration = "acc_V"\ntacho = "tacho_V"\nsensitivity = "100 mV/g"\n')
    code, out, err = cli("validate", scenario)
    assert code == 0, err


def rig(z1: int, **keys) -> str:
    """A description of one 2 mm z1/57 pair on 20/30 mm bores (*keys*: description()'s)."""
    return description(stage(z1, 57, bores=("20 mm", "30 mm")), **keys)


def test_no_tacho_the_speed_comes_from_the_gearbox_mesh_order(tmp_path, reference):
    _, acc, _ = signals()
    np.savez(tmp_path / "r.npz", acc=acc, fs=FS)
    gearbox = tmp_path / "rig20.toml"
    gearbox.write_text(rig(20, name="rig20", speed="1500 rpm", load="10 N*m"))
    from gearlab.gearbox import resolve_gearbox

    rec = read_recording(tmp_path / "r.npz", "acc")
    spec = MeasuredSpec(name="r", path=str(tmp_path / "r.npz"), vibration="acc", gearbox=str(gearbox))
    ds = import_measured(spec)
    assert ds.meta["speed_hz"] == pytest.approx(SPEED, rel=1e-4) and "mesh lines" in ds.meta["angle_source"]
    assert rec.tacho is None and resolve_gearbox(str(gearbox)).name == "rig20"


def test_an_edited_gearbox_description_is_not_served_from_the_cache(tmp_path, monkeypatch):
    """The speed of a record without a tacho comes from the description's tooth count: the cache
    key follows the description's content (not its name or place), so an edited one imports again."""
    from gearlab.data.cache import load_or_build

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    _, acc, _ = signals()
    np.savez(tmp_path / "r.npz", acc=acc, fs=FS)
    gearbox = tmp_path / "rig.toml"
    gearbox.write_text(rig(20, name="rig"))
    spec = MeasuredSpec(name="r", path=str(tmp_path / "r.npz"), vibration="acc", gearbox=str(gearbox))
    first, cached = load_or_build(spec)
    assert not cached and first.meta["speed_hz"] == pytest.approx(SPEED, rel=1e-4)
    elsewhere = tmp_path / "moved" / "other.toml"
    elsewhere.parent.mkdir()
    elsewhere.write_text(rig(20, name="rig"))
    assert MeasuredSpec(name="r", path=spec.path, vibration="acc", gearbox=str(elsewhere)).key() == spec.key()
    assert load_or_build(spec)[1]
    gearbox.write_text(rig(40, name="rig"))  # the same file, a 40-tooth pinion: the mesh line at 500 Hz is 12.5 Hz
    again, cached = load_or_build(spec)
    assert not cached and again.meta["speed_hz"] == pytest.approx(SPEED / 2, rel=1e-4)


def test_a_run_is_not_resumed_against_an_edited_gearbox_description(
    cli, run_scenario, tmp_path, monkeypatch, unrendered_figures
):
    """Its finished units were computed at the speed the old description gave: like a changed
    measured file, a changed description refuses the resume."""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    _, acc, _ = signals()
    np.savez(tmp_path / "r.npz", acc=acc, fs=FS)
    (tmp_path / "rig.toml").write_text(rig(20))
    run = run_scenario(
        '[scenario]\nname = "m"\nkind = "dataset"\n[[datasets]]\nfile = "r.npz"\nvibration = "acc"\n'
        'gearbox = "rig.toml"\ntransient = "none"\n'
    )
    assert str((tmp_path / "rig.toml").resolve()) in json.loads((run / "run.json").read_text())["inputs"]
    (run / "results.jsonl").unlink()  # as if killed before its unit finished
    (tmp_path / "rig.toml").write_text(rig(40))
    code, _, err = cli("run", "--resume", run)
    assert code == 2 and "rig.toml: has changed since the run" in err, err


def test_the_user_story_from_a_csv_to_a_detection_report(cli, write_scenario, run_scenario, tmp_path, monkeypatch):
    """Issue 39: CSVs in volts at 100 mV/g with time_s and tacho_V columns, a scenario of under 30
    lines, to a detection report."""
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    t, _, tacho = signals()
    for i, (name, chip) in enumerate((("h1", 0), ("h2", 0), ("t1", 0), ("t2", 6.0))):
        _, acc, _ = signals(seed=i)
        theta = 0.4 + 2 * np.pi * SPEED * t
        since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * SPEED)
        acc = acc + chip * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
        delimited(tmp_path / f"{name}.csv", {"time_s": t, "acc_V": acc * SENSITIVITY, "tacho_V": tacho}, ",")
    text = """[scenario]
name = "rig20"
kind = "detection"
[source]
preset = "B-6-ch5"
teeth = [1, 2]
faults = { chip = [20] }
healthy = 6
[target]
vibration = "acc_V"
tacho = "tacho_V"
sensitivity = "100 mV/g"
files = [
  { file = "h1.csv", role = "history", label = "healthy" },
  { file = "h2.csv", role = "history", label = "healthy" },
  { file = "t1.csv", role = "test", label = "healthy" },
  { file = "t2.csv", role = "test", label = "fault" },
]
[classical]
mesh_orders = [20]
[detection]
blocks = [5]
[[methods]]
adapter = "matched_filter"
[protocol]
batch = 4
"""
    assert len(text.splitlines()) < 30
    code, out, err = cli("validate", write_scenario(text, "rig20.toml"))
    assert code == 0, err
    run_dir = run_scenario(text, "rig20.toml")
    assert "fm4" in (run_dir / "report.html").read_text()
    rows = {(r["method"], r["unit"]): r for r in json.loads((run_dir / "summary.json").read_text())["rows"]}
    assert rows[("fm4", "record5")]["auc"] == 1.0  # the chipped record's every TSA above the healthy one's


def test_a_tacho_on_the_output_shaft_gives_the_input_shafts_revolutions(tmp_path):
    """A description whose [sensor] tacho reads the output shaft: its pulses (one per output turn,
    1/3 of the input's speed on a 16/48 stage) are turned into the input shaft's angle, so the cut
    revolutions are the input's (the mesh at order 16 of them, 3 times as many as output turns);
    without the description the same file is cut at the tacho's shaft (order 48)."""
    from gearlab.gearbox import load_gearbox

    text = (Path(__file__).parents[1] / "examples" / "your_gearbox" / "rig16.toml").read_text()
    text = text.replace('tacho = "input" ', 'tacho = "output"')
    assert 'tacho = "output"' in text
    (tmp_path / "rig16_out.toml").write_text(text)
    box = load_gearbox(tmp_path / "rig16_out.toml")
    fs, f_in = 20_000.0, 25.0
    t = np.arange(int(2.0 * fs)) / fs
    theta_in = 2 * np.pi * f_in * t + 0.3
    vibration = np.sin(16 * theta_in)
    theta_out = theta_in / 3
    tacho = (np.mod(theta_out, 2 * np.pi) < 0.2).astype(float) * 5.0
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.column_stack([t, vibration, tacho]), delimiter=",", header="time_s,acc,tacho", comments="")

    def mesh_order(cut):
        spectrum = np.abs(np.fft.rfft(cut.revolutions.mean(axis=0)))
        return int(np.argmax(spectrum))

    with_box = cut_recording(path, vibration="acc", tacho="tacho", gearbox=box, points=1024)
    plain = cut_recording(path, vibration="acc", tacho="tacho", points=1024)
    assert mesh_order(with_box) == 16 and with_box.speed_hz == pytest.approx(f_in, rel=1e-3)
    assert mesh_order(plain) == 48 and plain.speed_hz == pytest.approx(f_in / 3, rel=1e-3)
    assert "on the output shaft" in with_box.angle_source


@pytest.mark.parametrize("unit, scale", [("m/s^2", 1.0), ("g", 9.80665), ("V", None), ("mV", None)])
def test_an_hdf5_units_attribute_says_the_channels_unit(tmp_path, unit, scale):
    """A logger's HDF5 channel named plainly ('acc') with a 'units' attribute: in m/s² or g it
    is read as such with no sensitivity, and a sensitivity is refused (at validate, from the
    header alone, and on reading); in volts a sensitivity is required. The attribute's word is
    quoted in the error."""
    _, acc, _ = signals()
    path = tmp_path / "take.h5"
    with h5py.File(path, "w") as f:
        f.attrs["fs"] = FS
        f.create_dataset("acc", data=acc if scale is None else acc / scale).attrs["units"] = unit
    if scale is not None:
        rec = read_recording(path, "acc")
        assert np.allclose(rec.signal, acc) and "unknown" not in rec.units
        check_recording(path, "s.toml: [target]", {"vibration": "acc"})
        for call in (
            lambda: check_recording(path, "s.toml: [target]", {"vibration": "acc"}, sensitivity=SENSITIVITY),
            lambda: read_recording(path, "acc", sensitivity=SENSITIVITY, where="s.toml: [target]"),
        ):
            said = rf"^s.toml: \[target\] key 'sensitivity': .*file's unit '{re.escape(unit)}'"
            with pytest.raises(GearlabInputError, match=said):
                call()
    else:
        with pytest.raises(GearlabInputError, match=rf"key 'sensitivity': missing; .*in volts .*unit '{unit}'"):
            check_recording(path, "s.toml: [target]", {"vibration": "acc"})
        volts = 1e-3 if unit == "mV" else 1.0  # the stored values are the acceleration's digits in V or mV
        rec = read_recording(path, "acc", sensitivity=SENSITIVITY)
        assert np.allclose(rec.signal, acc * volts / SENSITIVITY)
