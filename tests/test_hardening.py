"""Hardening: no file written outside the run directory, one line and exit code 2
for hostile input, full disks and read-only caches handled, tampered cache entries rebuilt.

Each test names the hostile or careless use it stands for. The disk-full and read-only tests
mount small tmpfs file systems and run only as root (they are skipped otherwise).
"""

from __future__ import annotations

import io
import json
import os
import struct
import subprocess
import tomllib
import warnings
import zipfile
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
import tomli_w
from test_fuzz import run_cli
from test_importers import make_record, write_npz

import gearlab.kinds.dataset as dataset_kind
import gearlab.runs as runs
from gearlab.data import cache
from gearlab.data.importers import MeasuredSpec, import_measured
from gearlab.engine import load_scenario, scenario_of
from gearlab.errors import GearlabInputError
from gearlab.files import atomic_write, inside
from gearlab.runs import RunDir

ROOT = Path(__file__).resolve().parents[1]


# ----------------------------------------------------------------------------- helpers


def last_line(err: str) -> str:
    return err.strip().splitlines()[-1]


def listing(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


@pytest.fixture(scope="module")
def record_file(tmp_path_factory) -> Path:
    """A short measured record (4 revolutions at 25 Hz, 50 kHz) as an NPZ file."""
    rec = make_record(n=8000)
    folder = tmp_path_factory.mktemp("data")
    return write_npz(folder / "rec.npz", {"acc": rec.acc, "tacho": rec.tacho, "label": rec.label, "fs": 50_000.0})


@pytest.fixture
def cache_env(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("GEARLAB_CACHE", str(folder))
    return folder


def measured_scenario(folder: Path, file: str, name: str = "rig", scenario: str = "m") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{scenario}.toml"
    path.write_text(
        f'[scenario]\nname = "{scenario}"\nkind = "dataset"\n\n[[datasets]]\nname = {json.dumps(name)}\n'
        f'file = "{file}"\nvibration = "acc"\ntacho = "tacho"\nlabels = "label"\n'
    )
    return path


def mounted(tmp_path: Path, name: str, options: str) -> Path:
    """A tmpfs mounted for the test (root only), unmounted at the end by the finaliser."""
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    point = tmp_path / name
    point.mkdir()
    result = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(point)], capture_output=True)
    if result.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {result.stderr.decode().strip()}")
    return point


@pytest.fixture
def tmpfs(tmp_path):
    points = []

    def mount(name: str, options: str) -> Path:
        point = mounted(tmp_path, name, options)
        points.append(point)
        return point

    yield mount
    for point in points:
        subprocess.run(["umount", "-l", str(point)], capture_output=True)


# ----------------------------------------------------------------------------- 1. path traversal


@pytest.mark.parametrize(
    "name", ["../../../../tmp/x", "a/b", "..", ".hidden", "a\\b", "x\x00y", " lead", "tab\there", "/abs", "n" * 101]
)
def test_name_with_path_characters_is_refused(tmp_path, record_file, name):
    path = measured_scenario(tmp_path / "sc", str(record_file), name=name)
    with pytest.raises(GearlabInputError, match="key 'name': expected a plain name") as info:
        load_scenario(path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("name", ["B-8-ch5-laplace", "two faults", "naïve (2)", "rig_1.5+x@y=z"])
def test_plain_names_are_taken(tmp_path, record_file, name):
    assert load_scenario(measured_scenario(tmp_path / "sc", str(record_file), name=name)).spec[0].name == name


def test_traversing_dataset_name_writes_nothing_outside(tmp_path, record_file, cache_env):
    """The reproduction of a reported escape: the run wrote figures/signals_<name>.png outside its run directory."""
    victim = tmp_path / "victim"
    victim.mkdir()
    depth = len((tmp_path / "out").parts) + 4
    path = measured_scenario(tmp_path / "sc", str(record_file), name="../" * depth + str(victim / "escaped")[1:])
    before = listing(tmp_path)
    code, err = run_cli("run", path, "--out", tmp_path / "out")
    assert code == 2 and "plain name" in last_line(err)
    assert listing(tmp_path) == before


def test_the_helper_refuses_every_way_out(tmp_path):
    root = tmp_path / "run"
    root.mkdir()
    (root / "link").symlink_to(tmp_path)
    assert inside(root, "figures", "a.png") == root / "figures" / "a.png"
    for parts in (("..", "x"), ("/etc/passwd",), ("figures", "../../x"), ("link", "x"), ("a\x00b",), (".",)):
        with pytest.raises(GearlabInputError, match="not a file inside"):
            inside(root, *parts)
    run = RunDir(root)
    with pytest.raises(GearlabInputError):
        run.write_text("../outside.txt", "x")
    with pytest.raises(GearlabInputError):
        dataset_kind.figures(
            import_measured(
                MeasuredSpec(name="../../../../x", path=str(make_npz(tmp_path)), vibration="acc", speed_hz=25.0)
            ),
            run,
        )
    assert not (tmp_path / "outside.txt").exists() and not (tmp_path / "x.png").exists()


def make_npz(folder: Path) -> Path:
    rec = make_record(n=8000)
    return write_npz(folder / "r.npz", {"acc": rec.acc, "fs": 50_000.0})


# ----------------------------------------------------------------------------- 2. resume with relative files


def test_resume_finds_a_relative_file_and_refuses_a_changed_one(
    tmp_path, record_file, cache_env, monkeypatch, unrendered_figures
):
    data = tmp_path / "data"
    data.mkdir()
    (data / "rec.npz").write_bytes(record_file.read_bytes())
    path = measured_scenario(tmp_path / "sc", "../data/rec.npz")
    monkeypatch.chdir(tmp_path / "sc")
    code, err = run_cli("run", "m.toml", "--out", tmp_path / "runs")
    assert code == 0, err
    run = next((tmp_path / "runs" / "m").iterdir())
    stored = json.loads((run / "run.json").read_text())["inputs"]
    assert list(stored) == [str((data / "rec.npz").resolve())]
    monkeypatch.chdir(tmp_path)  # elsewhere: the copy in the run directory must still find the file
    (run / "results.jsonl").unlink()  # as if killed before its unit finished
    code, err = run_cli("run", "--resume", run)
    assert code == 0, err
    assert path.is_file()
    rec = dict(np.load(data / "rec.npz"))
    rec["acc"] = rec["acc"] * 2
    np.savez(data / "rec.npz", **rec)
    code, err = run_cli("run", "--resume", run)
    assert code == 2 and "rec.npz: has changed since the run" in last_line(err), err


# ----------------------------------------------------------------------------- 3. two runs, one timestamp


class _FrozenClock:
    """datetime.datetime, stopped: every run gets the same timestamp."""

    moment = runs._dt.datetime(2026, 1, 2, 3, 4, 5, 678901)

    @classmethod
    def now(cls):
        return cls.moment


def test_same_timestamp_gets_a_fresh_name_and_never_removes_the_other_run(tmp_path, record_file, monkeypatch):
    monkeypatch.setattr(runs._dt, "datetime", _FrozenClock)
    scenario = load_scenario(measured_scenario(tmp_path / "sc", str(record_file)))
    other = tmp_path / "runs" / "m" / "20260102-030405-678901"
    other.mkdir(parents=True)
    (other / "results.jsonl").write_text('{"unit": "theirs"}\n')
    first = RunDir.create(tmp_path / "runs", scenario)
    second = RunDir.create(tmp_path / "runs", scenario)
    assert first.path.name == "20260102-030405-678901-2" and second.path.name == "20260102-030405-678901-3"
    assert (other / "results.jsonl").read_text() == '{"unit": "theirs"}\n'


# ----------------------------------------------------------------------------- 4. full disks, read-only places


@pytest.mark.parametrize("size", ["4k", "40k", "200k"])
def test_full_disk_is_one_line_and_leaves_a_resumable_run_or_none(tmp_path, record_file, cache_env, tmpfs, size):
    small = tmpfs(f"small{size}", f"size={size}")
    path = measured_scenario(tmp_path / "sc", str(record_file))
    code, err = run_cli("run", path, "--out", small / "runs")
    assert code == 2, err
    line = last_line(err)
    assert line.startswith("error: ") and "no space left on the device" in line and "Traceback" not in err
    made = list((small / "runs" / "m").iterdir()) if (small / "runs" / "m").exists() else []
    assert len(made) <= 1
    if made:  # kept: it must resume once there is room
        assert f"resume with: gearlab run --resume {made[0]}" in line
        subprocess.run(["mount", "-o", "remount,size=4m", str(small)], check=True)
        code, err = run_cli("run", "--resume", made[0])
        assert code == 0, err
        assert (made[0] / "report.html").is_file()
    else:
        assert "no run directory is left" in line or not (small / "runs").exists() or not listing(small / "runs")
        assert not [p for p in small.rglob("*") if p.is_file()]


def test_read_only_cache_falls_back_with_a_warning(tmp_path, record_file, tmpfs, monkeypatch, unrendered_figures):
    ro = tmpfs("ro", "ro,size=64k")
    monkeypatch.setattr(cache, "_FALLBACK", [])
    monkeypatch.setenv("GEARLAB_CACHE", str(ro))
    path = measured_scenario(tmp_path / "sc", str(record_file))
    code, err = run_cli("run", path, "--out", tmp_path / "runs")
    assert code == 0, err
    assert "warning: dataset cache" in err and "read-only file system" in err
    monkeypatch.setenv("GEARLAB_CACHE", str(ro / "sub"))  # a cache folder that cannot even be made
    monkeypatch.setattr(cache, "_FALLBACK", [])
    code, err = run_cli("run", path, "--out", tmp_path / "runs")
    assert code == 0 and "read-only file system" in err, err


def test_report_and_results_follow_the_umask(tmp_path, record_file, cache_env):
    old = os.umask(0o022)
    try:
        atomic_write(tmp_path / "a.txt", "x")
        assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
        code, err = run_cli("run", measured_scenario(tmp_path / "sc", str(record_file)), "--out", tmp_path / "runs")
        assert code == 0, err
        run = next((tmp_path / "runs" / "m").iterdir())
        for name in ("report.html", "summary.json", "scenario.toml", "run.json", "table.md"):
            assert (run / name).stat().st_mode & 0o777 == 0o644, name
        os.umask(0o077)
        atomic_write(tmp_path / "b.txt", "x")
        assert (tmp_path / "b.txt").stat().st_mode & 0o777 == 0o600
    finally:
        os.umask(old)


# ----------------------------------------------------------------------------- 5. tampered cache entries


def _tamper_label(d):
    d["label"] = d["label"][:1]


def _tamper_dtype(d):
    d["X"] = d["X"].astype(np.float64)


def _tamper_scale(d):
    d["X"] = d["X"] * 100


def _tamper_nan(d):
    d["X"] = np.full_like(d["X"], np.nan)


def _tamper_digest(d):
    meta = json.loads(str(d["meta"]))
    del meta["sha256"]  # as an older gearlab wrote it
    d["meta"] = np.array(json.dumps(meta))


@pytest.mark.parametrize("tamper", [_tamper_label, _tamper_dtype, _tamper_scale, _tamper_nan, _tamper_digest])
def test_tampered_cache_entry_is_rebuilt(tmp_path, record_file, cache_env, tamper):
    spec = MeasuredSpec(name="rig", path=str(record_file), vibration="acc", tacho="tacho", labels="label")
    built, cached = cache.load_or_build(spec)
    assert not cached
    entry = cache.entry_path(spec)
    data = dict(np.load(entry, allow_pickle=False))
    tamper(data)
    np.savez(entry, **data)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        again, cached = cache.load_or_build(spec)
    assert not cached and any("unreadable or altered" in str(w.message) for w in caught)
    assert np.array_equal(again.X, built.X) and np.array_equal(again.label, built.label)
    assert cache.load(spec) is not None  # the rebuilt entry is whole


# ----------------------------------------------------------------------------- 6. deep nesting


def test_deeply_nested_scenario_is_one_line(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text(
        f'[scenario]\nname = "d"\nkind = "dataset"\n[[datasets]]\npreset = "A-pinion"\nteeth = {"[" * 500}{"]" * 500}\n'
    )
    code, err = run_cli("validate", path)
    assert (
        code == 2
        and last_line(err)
        == f"error: {path}: invalid TOML: nested too deeply (arrays or tables inside "
        "one another hundreds of levels deep)"
    )


# ----------------------------------------------------------------------------- 7. files that claim more than they hold


def _import(path: Path, **options):
    return import_measured(
        MeasuredSpec(name="rig", path=str(path), **{"vibration": "acc", "speed_hz": 25.0, "fs": 25e3, **options})
    )


def test_hdf5_dataset_declared_beyond_the_limit_is_refused_before_reading(tmp_path):
    path = tmp_path / "huge.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("acc", shape=(400_000_000,), dtype="f8")  # never written: a tiny file
    assert path.stat().st_size < 10_000
    with pytest.raises(
        GearlabInputError,
        match=r"dataset '/acc' would take 3,052 MB, more than the limit of 1,024 MB"
        r".*GEARLAB_MAX_RECORD_MB",
    ):
        _import(path)


def test_npz_member_that_inflates_beyond_the_limit_is_refused(tmp_path, monkeypatch):
    path = tmp_path / "bomb.npz"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as z:
        buf = io.BytesIO()
        np.save(buf, np.zeros(1_000_000))  # 8 MB of zeros: a few kB compressed
        z.writestr("acc.npy", buf.getvalue())
    monkeypatch.setenv("GEARLAB_MAX_RECORD_MB", "2")
    with pytest.raises(GearlabInputError, match=r"array 'acc' would take 8 MB, more than the limit of 2 MB"):
        _import(path)


def test_npz_header_that_claims_more_than_the_member_holds_is_refused(tmp_path):
    path = tmp_path / "liar.npz"
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (10**10,)})
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("acc.npy", header.getvalue() + bytes(80))
    with pytest.raises(GearlabInputError, match="array 'acc' would take 76,294 MB"):
        _import(path)


def test_compressed_matlab_variable_beyond_the_limit_is_refused(tmp_path, monkeypatch):
    path = tmp_path / "bomb.mat"
    scipy.io.savemat(path, {"acc": np.zeros(1_000_000)}, do_compression=True)
    monkeypatch.setenv("GEARLAB_MAX_RECORD_MB", "2")
    with pytest.raises(GearlabInputError, match="inflates to more than the limit of 2 MB"):
        _import(path)


def test_the_limit_applies_to_the_file_and_can_be_raised(tmp_path, record_file, monkeypatch):
    monkeypatch.setenv("GEARLAB_MAX_RECORD_MB", "0.01")
    with pytest.raises(GearlabInputError, match="the file would take 0 MB, more than the limit of 0 MB"):
        _import(record_file, tacho="tacho", speed_hz=None, fs=None)
    monkeypatch.setenv("GEARLAB_MAX_RECORD_MB", "lots")
    with pytest.raises(GearlabInputError, match="GEARLAB_MAX_RECORD_MB: expected a number of megabytes"):
        _import(record_file, tacho="tacho", speed_hz=None, fs=None)
    monkeypatch.setenv("GEARLAB_MAX_RECORD_MB", "5000")
    assert _import(record_file, tacho="tacho", speed_hz=None, fs=None).X.shape[0] == 3


def test_running_out_of_memory_while_importing_is_one_line(record_file, monkeypatch):
    import gearlab.data.importers as importers

    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(importers, "cut_revolutions", exhausted)
    with pytest.raises(GearlabInputError, match="not enough memory to import this record"):
        _import(record_file, tacho="tacho", speed_hz=None, fs=None)


# ----------------------------------------------------------------------------- should fix


@pytest.mark.parametrize("table,key", [("scenario", "kind"), ("execution", "executor"), ("execution", "device")])
def test_long_values_are_shortened_in_errors(tmp_path, table, key):
    doc = {"scenario": {"name": "n", "kind": "dataset"}, "datasets": [{"preset": "A-pinion"}]}
    doc.setdefault(table, {})[key] = "x" * 5000
    path = tmp_path / "long.toml"
    path.write_text(tomli_w.dumps(doc))
    with pytest.raises(GearlabInputError) as info:
        load_scenario(path)
    assert len(str(info.value)) < 400 and f"key '{key}'" in str(info.value)


def test_errors_never_quote_a_system_file_reached_through_a_link(tmp_path, cache_env):
    secret = tmp_path / "shadow"
    secret.write_text("root:$6$SECRETHASH:20228:0:99999:7:::\ndaemon:*:20228:0:99999:7:::\n")
    (tmp_path / "sc").mkdir()
    (tmp_path / "sc" / "x.csv").symlink_to(secret)
    path = tmp_path / "sc" / "s.toml"
    path.write_text(
        '[scenario]\nname = "s"\nkind = "dataset"\n[[datasets]]\nname = "rig"\nfile = "x.csv"\n'
        'vibration = "acc"\nspeed = 25.0\n'
    )
    code, err = run_cli("run", path, "--out", tmp_path / "runs")
    assert code == 2 and "holds no number" in last_line(err)
    assert "SECRETHASH" not in err and "daemon" not in err and "99999" not in err


@pytest.mark.parametrize(
    "where,value,fact",
    [
        (("protocol", "max_epochs"), 10**20, "key 'max_epochs': 100000000000000000000 is outside [1, 100000]"),
        (("target", "effects", 0, "seed"), 10**30, "seed must be a whole number in [0, 4294967295]"),
        (("source", "fs"), 1e300, "key 'fs': 1e+300 is outside (0 Hz, 10 MHz]"),
        (("source", "speed"), "1 MHz", "key 'speed': '1 MHz' is outside (0 Hz, 1 kHz]"),
    ],
)
def test_absurd_values_are_refused_with_the_range(tmp_path, where, value, fact):
    doc = tomllib.loads((ROOT / "scenarios" / "quick.toml").read_text())
    node = doc
    for key in where[:-1]:
        node = node[key]
    node[where[-1]] = value
    path = tmp_path / "q.toml"
    path.write_text(tomli_w.dumps(doc))
    with pytest.raises(GearlabInputError) as info:
        load_scenario(path)
    assert fact in str(info.value)


def test_boolean_vibration_channel_is_refused(tmp_path):
    rec = make_record(n=8000)
    path = write_npz(tmp_path / "b.npz", {"acc": rec.acc > 0, "fs": 50_000.0})
    with pytest.raises(GearlabInputError, match="vibration channel 'acc' holds true/false values"):
        _import(path, fs=None)


def test_wav_with_no_channels_is_refused(tmp_path):
    fmt = struct.pack("<HHIIHH", 1, 0, 25_000, 0, 0, 16)
    body = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt + b"data" + struct.pack("<I", 0)
    path = tmp_path / "zero.wav"
    path.write_bytes(b"RIFF" + struct.pack("<I", len(body)) + body)
    with pytest.raises(GearlabInputError, match="declares 0 channels"):
        _import(path, vibration="0", fs=None)


def test_ctrl_c_says_how_to_resume(tmp_path, record_file, cache_env, monkeypatch):
    def interrupted(scenario, run, on_event):
        raise KeyboardInterrupt

    monkeypatch.setattr(dataset_kind, "run", interrupted)
    code, err = run_cli("run", measured_scenario(tmp_path / "sc", str(record_file)), "--out", tmp_path / "runs")
    run = next((tmp_path / "runs" / "m").iterdir())
    assert code == 130 and last_line(err) == f"interrupted; resume with: gearlab run --resume {run}"
    assert "Traceback" not in err and (run / "scenario.toml").is_file()


def test_a_transfer_runs_copy_finds_its_relative_target_file(tmp_path, record_file, monkeypatch):
    """`gearlab run --resume` of a transfer (and gap) run loads the run's copy of the scenario:
    its measured target, given relative to the scenario file, must resolve as it did."""
    data = tmp_path / "data"
    data.mkdir()
    (data / "rec.npz").write_bytes(record_file.read_bytes())
    doc = tomllib.loads((ROOT / "scenarios" / "quick.toml").read_text())
    doc["target"] = {"file": "../data/rec.npz", "vibration": "acc", "tacho": "tacho", "labels": "label", "name": "rig"}
    (tmp_path / "sc").mkdir()
    (tmp_path / "sc" / "t.toml").write_text(tomli_w.dumps(doc))
    monkeypatch.chdir(tmp_path / "sc")
    run = RunDir.create(tmp_path / "runs", load_scenario("t.toml"))
    monkeypatch.chdir(tmp_path)
    target = scenario_of(run).spec.target
    assert Path(target.path).resolve() == (data / "rec.npz").resolve()


def test_records_listed_in_files_tables_are_recorded_for_resume():
    """The detection kind's target lists its records as files = [{path = ..., role = ...}]."""
    from gearlab.runs import input_paths

    scenario = ROOT / "scenarios" / "phm09_chip.toml"
    records = ROOT.parent / "shared" / "data" / "phm09"  # where the scenario's relative paths lead
    if not scenario.is_file() or not records.is_dir():
        pytest.skip(f"the PHM 2009 records ({records}) are not here")
    paths = input_paths(load_scenario(scenario))
    assert len(paths) == 24 and all(p.is_absolute() and p.is_file() for p in paths)
