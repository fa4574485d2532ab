"""The measured-data key `unit` (issue 39 item 2): a headerless text column cannot say its unit, so
a scenario says it once (kinds.common.MEASURED) and every reader takes it where a file-stated unit
goes (recordings.channel_scale): a tab-separated file in g with unit = "g" gives the same m/s² as
the same data in m/s² with no unit, in the detection and gap [target], a [[datasets]] file,
`gearlab inspect --unit`, the notebook API and `gearlab score`; a unit that the channel's name or
the file contradicts, or "g" with a sensitivity, is one line naming the key (exit 2)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import h5py
import numpy as np
import pytest

import gearlab
from gearlab.data.importers import import_measured
from gearlab.data.recordings import STANDARD_GRAVITY, cut_recording
from gearlab.engine import load_scenario
from gearlab.errors import GearlabInputError

FS, SPEED, TEETH, REVS = 10_000.0, 25.0, 20, 16


def acceleration(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(m/s², once-per-revolution tacho in V) of a 20-tooth pinion at 25 Hz."""
    t = np.arange(int(FS / SPEED * REVS)) / FS
    theta = 0.4 + 2 * np.pi * SPEED * t
    acc = 3.0 * np.sin(TEETH * theta) + 0.2 * np.random.default_rng(seed).standard_normal(t.size)
    return acc, np.where(np.mod(theta, 2 * np.pi) < 0.4, 5.0, 0.0)


def headerless(path: Path, vibration: np.ndarray, tacho: np.ndarray) -> Path:
    """An outside user's file: tab-separated, no header, column 0 the vibration, column 1 the tacho."""
    assert len(vibration) == len(tacho)
    pairs = np.column_stack([vibration, tacho]).ravel().tolist()
    path.write_text("%.12g\t%g\n" * len(vibration) % tuple(pairs))  # in one operation, not line by line
    return path


@pytest.fixture
def files(tmp_path: Path) -> dict[str, list[Path]]:
    """Two records (history, test), each written in g and in m/s²."""
    out: dict[str, list[Path]] = {"g": [], "ms2": []}
    for i, role in enumerate(("history", "test")):
        acc, tacho = acceleration(i)
        out["g"].append(headerless(tmp_path / f"{role}_g.txt", acc / STANDARD_GRAVITY, tacho))
        out["ms2"].append(headerless(tmp_path / f"{role}_ms2.txt", acc, tacho))
    return out


def target(paths: list[Path], unit: str = "", extra: str = "") -> str:
    listed = ", ".join(
        f'{{ file = "{p.name}", role = "{role}", label = "healthy" }}'
        for p, role in zip(paths, ("history", "test"))  # noqa: B905 - a gap's target lists its history alone
    )
    said = f'unit = "{unit}"\n' if unit else ""
    return f'[target]\nvibration = 0\ntacho = 1\nfs = "{FS:g} Hz"\n{said}{extra}files = [{listed}]\n'


def detection(paths: list[Path], unit: str = "", extra: str = "") -> str:
    return (
        '[scenario]\nname = "u"\nkind = "detection"\n[source]\npreset = "B-6-ch5"\nteeth = [1, 2]\n'
        "faults = { chip = [20] }\nhealthy = 6\n"
        + target(paths, unit, extra)
        + "[classical]\nmesh_orders = [20]\n[detection]\nblocks = [4]\n"
        + '[[methods]]\nadapter = "matched_filter"\n[protocol]\nbatch = 4\n'
    )


def gap(paths: list[Path], unit: str = "", extra: str = "") -> str:
    return (
        '[scenario]\nname = "u"\nkind = "gap"\n[source]\npreset = "B-6-ch5"\n'
        + target(paths[:1], unit, extra)
        + "[accuracy]\nenabled = false\n"
    )


def write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_detection_target_reads_g_as_m_s2(files, tmp_path):
    g = load_scenario(write(tmp_path, detection(files["g"], "g"), "g.toml")).spec.target
    ms2 = load_scenario(write(tmp_path, detection(files["ms2"]), "ms2.toml")).spec.target
    assert g.unit == "g" and ms2.unit is None
    for fg, fm in zip(g.files, ms2.files, strict=True):
        np.testing.assert_allclose(g.read(fg).revolutions, ms2.read(fm).revolutions, rtol=1e-8, atol=1e-9)


def test_gap_target_reads_g_as_m_s2_and_knows_its_units(files, tmp_path):
    g = load_scenario(write(tmp_path, gap(files["g"], "g"), "g.toml")).spec.target
    ms2 = load_scenario(write(tmp_path, gap(files["ms2"]), "ms2.toml")).spec.target
    assert g.units_known and not ms2.units_known  # no "units unknown" warning for the file in g
    fg, fm = g.target.files[0], ms2.target.files[0]
    np.testing.assert_allclose(g.target.read(fg).revolutions, ms2.target.read(fm).revolutions, rtol=1e-8, atol=1e-9)


def test_a_datasets_file_and_the_api_read_g_as_m_s2(files, tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    entry = '[scenario]\nname = "d"\nkind = "dataset"\n[[datasets]]\nfile = "{}"\nvibration = 0\ntacho = 1\n'
    entry += f'fs = "{FS:g} Hz"\ntransient = "none"\n'
    g_spec = load_scenario(write(tmp_path, entry.format(files["g"][0].name) + 'unit = "g"\n', "g.toml")).spec[0]
    ms2_spec = load_scenario(write(tmp_path, entry.format(files["ms2"][0].name), "ms2.toml")).spec[0]
    assert g_spec.unit == "g" and g_spec.key() != replace(g_spec, unit=None).key()  # a cache entry of its own
    g, ms2 = import_measured(g_spec), import_measured(ms2_spec)
    np.testing.assert_allclose(g.X * g.reference[1] + g.reference[0], ms2.X * ms2.reference[1] + ms2.reference[0])
    assert not g.meta["units"].startswith("unknown") and ms2.meta["units"].startswith("unknown")
    # the notebook API: read_recording, and import_recording with the same keys as [[datasets]]
    rec = gearlab.read_recording(files["g"][0], 0, 1, fs=FS, unit="g")
    np.testing.assert_allclose(rec.signal, gearlab.read_recording(files["ms2"][0], 0, 1, fs=FS).signal, rtol=1e-9)
    api = gearlab.import_recording(files["g"][0], 0, tacho=1, fs=FS, transient="none", unit="g")
    np.testing.assert_allclose(api.reference, g.reference)
    with pytest.raises(GearlabInputError, match=r"unit: 'G' is not one of m/s\^2, m/s², g, V, mV"):
        gearlab.read_recording(files["g"][0], 0, 1, fs=FS, unit="G")


def test_inspect_unit(files, cli):
    common = ["--vibration", "0", "--tacho", "1", "--fs", f"{FS:g}", "--json"]
    code, out, err = cli("inspect", files["g"][0], *common, "--unit", "g")
    assert code == 0, err
    code, plain, err = cli("inspect", files["ms2"][0], *common)
    assert code == 0, err
    g, ms2 = json.loads(out), json.loads(plain)
    assert g["lines"][0]["order"] == pytest.approx(TEETH, abs=0.01)
    assert g["rms"] == pytest.approx(ms2["rms"], rel=1e-8) and ms2["rms"] > 2  # 3 m/s² peak, not 3 / 9.8
    assert g["lines"][0]["amplitude"] == pytest.approx(ms2["lines"][0]["amplitude"], rel=1e-6)
    api = gearlab.inspect_recording(files["g"][0], vibration="0", tacho="1", fs=FS, unit="g")
    assert api["lines"][0]["amplitude"] == pytest.approx(ms2["lines"][0]["amplitude"], rel=1e-6)
    # volts need a sensitivity, as a scenario's 'unit' does; a name that says otherwise is refused
    code, _, err = cli("inspect", files["g"][0], *common, "--unit", "V")
    assert code == 2 and "--sensitivity: missing" in err and "as --unit says" in err and len(err.splitlines()) == 1


def test_score_reads_with_the_runs_unit(files, tmp_path):
    """`gearlab score` reads new records with the keys the run kept (detection_scoring.store_scoring)."""
    from gearlab.kinds.detection_scoring import reading_keys, store_scoring

    class Run:  # the one call store_scoring makes without conditions
        def write_json(self, name, obj):
            self.meta = obj

    run = Run()
    store_scoring(run, load_scenario(write(tmp_path, detection(files["g"], "g"))).spec, {})
    assert run.meta["target"]["unit"] == "g"
    new = cut_recording(str(files["g"][1]), **reading_keys(run.meta, None)).revolutions
    ref = cut_recording(str(files["ms2"][1]), vibration=0, tacho=1, fs=FS).revolutions
    np.testing.assert_allclose(new, ref, rtol=1e-8, atol=1e-9)


def named_files(tmp_path: Path) -> dict[str, Path]:
    acc, tacho = acceleration(0)
    (tmp_path / "named.txt").write_text(
        "acc_V\ttacho\n" + "\n".join(f"{v:.9g}\t{p:g}" for v, p in zip(acc * 0.01, tacho, strict=True)) + "\n"
    )
    with h5py.File(tmp_path / "stated.h5", "w") as f:
        f.create_dataset("acc", data=acc).attrs["units"] = "m/s^2"
        f.create_dataset("tacho", data=tacho)
        f.attrs["fs"] = FS
    return {"named": tmp_path / "named.txt", "stated": tmp_path / "stated.h5"}


CONFLICTS = [
    # (file, vibration, keys, the key named, what the line says)
    ("g", 0, 'unit = "g"\nsensitivity = "100 mV/g"\n', "unit", "expected no sensitivity"),
    ("g", 0, 'unit = "g"\ngain = "1 mV"\n', "unit", "expected no gain"),
    ("g", 0, 'unit = "mV"\n', "sensitivity", "missing; channel '0' is in volts (mV, as key 'unit' says)"),
    ("named", "acc_V", 'unit = "g"\nsensitivity = "100 mV/g"\n', "unit", "which is in V (as its name says)"),
    ("stated", "acc", 'unit = "g"\n', "unit", "which is in m/s^2 (as the file's unit 'm/s^2' says)"),
    ("g", 0, 'unit = "G"\n', "unit", "'G' is not one of m/s^2, m/s², g, V, mV"),
]
IDS = ["g+sensitivity", "g+gain", "mV without sensitivity", "name says V", "file says m/s^2", "unknown unit"]


@pytest.mark.parametrize("make", ["detection", "gap", "dataset"])
@pytest.mark.parametrize(("which", "vibration", "keys", "key", "said"), CONFLICTS, ids=IDS)
def test_a_unit_conflict_is_one_line_naming_the_key(files, tmp_path, cli, make, which, vibration, keys, key, said):
    path = files["g"][0] if which == "g" else named_files(tmp_path)[which]
    tacho = 1 if which != "stated" else '"tacho"'
    vib = vibration if isinstance(vibration, int) else f'"{vibration}"'
    if make == "dataset":
        text = (
            f'[scenario]\nname = "d"\nkind = "dataset"\n[[datasets]]\nfile = "{path.name}"\nvibration = {vib}\n'
            f'tacho = {tacho}\nfs = "{FS:g} Hz"\n{keys}'
        )
        table = "[[datasets]] #1"
    else:
        listed = [path, files["ms2"][1]] if make == "detection" else [path]
        text = (detection if make == "detection" else gap)(listed, extra=keys)
        text = text.replace("vibration = 0", f"vibration = {vib}").replace("tacho = 1", f"tacho = {tacho}")
        table = "[target]"
    if which == "stated":
        text = text.replace(f'fs = "{FS:g} Hz"\n', "")
    code, out, err = cli("validate", write(tmp_path, text))
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, err
    assert f"{table} key '{key}'" in line and said in line, line
    assert "s.toml" in line


def test_a_unit_the_name_agrees_with_is_accepted(tmp_path):
    """'acc [g]' and unit = "g" say the same: no conflict, and the value is read once in g."""
    acc, tacho = acceleration(0)
    path = tmp_path / "acc.csv"
    path.write_text("acc [g],tacho\n" + "\n".join(f"{v:.12g},{p:g}" for v, p in zip(acc / STANDARD_GRAVITY, tacho)))
    rec = cut_recording(path, vibration="acc [g]", tacho="tacho", fs=FS, unit="g").revolutions
    ref = cut_recording(path, vibration="acc [g]", tacho="tacho", fs=FS).revolutions
    np.testing.assert_array_equal(rec, ref)


SHARED = [("fs", "-1", "expected a positive value"), ("transient", '"stat"', "'stat' is not one of stats, none")]
SHARED += [("vibration", "-1", "a column index is 0 or more"), ("gain", '"0 V"', "expected a positive voltage")]


@pytest.mark.parametrize("make", ["detection", "gap"])
@pytest.mark.parametrize(("key", "value", "said"), SHARED, ids=[k for k, _, _ in SHARED])
def test_the_target_keys_are_checked_once_by_their_declaration(files, tmp_path, cli, make, key, value, said):
    """parts.measured.target_spec no longer checks fs, gain, transient or a column itself: the shared
    declaration (kinds.common.MEASURED) refuses them first, in the same one line."""
    text = (detection if make == "detection" else gap)(files["ms2"], extra=f"{key} = {value}\n")
    text = text.replace(f'fs = "{FS:g} Hz"\n', "") if key == "fs" else text
    text = text.replace("vibration = 0\n", "") if key == "vibration" else text
    code, _, err = cli("validate", write(tmp_path, text))
    assert code == 2 and len(err.strip().splitlines()) == 1 and f"[target] key '{key}': " in err and said in err, err


@pytest.mark.parametrize("key", ["sensitivity", "gain"])
def test_a_key_an_acceleration_channel_needs_none_of_says_how_to_drop_it(key):
    # an outside user scoring an npz in m/s² with a run read in volts was told 'expected no sensitivity' and no more:
    # the run's key applies to every file, and only an empty one (an entry's key = "", score's --key KEY=) drops it
    from gearlab.data.channel_units import channel_scale
    from gearlab.errors import GearlabInputError

    given = {"sensitivity": 0.0102, "gain": None} if key == "sensitivity" else {"sensitivity": None, "gain": 2.0}
    with pytest.raises(GearlabInputError) as caught:
        channel_scale("acc_ms2", given["sensitivity"], given["gain"], "week1.npz")
    line = str(caught.value)
    assert line.startswith(f"week1.npz key '{key}': channel 'acc_ms2' is an acceleration already"), line
    assert f'{key} = "" in this file\'s entry; gearlab score: --key {key}=)' in line and "\n" not in line, line
