"""The dynamics and dataset commands of the CLI: `modes`, `simulate`, `run` of a dataset
scenario; exit codes and one-line errors for bad input."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT

from gearlab.data.spec import dataset_preset

DATASET_B = ROOT / "scenarios" / "dataset_B.toml"


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    path = tmp_path / "cache"
    monkeypatch.setenv("GEARLAB_CACHE", str(path))
    return path


def one_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


# --- modes -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name,n", [("ten_dof", 10), ("eight_dof", 8), ("six_dof", 6)])
def test_modes_json(cli, name, n):
    code, out, err = cli("modes", "--model", name, "--json")
    assert code == 0, err
    data = json.loads(out)
    f = data["frequencies_hz"]
    assert len(f) == n and len(data["fixed_input_hz"]) == n - 1
    assert f[0] == pytest.approx(0.0, abs=1e-3)  # the free drive train turns rigidly
    assert all(b >= a for a, b in zip(f, f[1:])) and f[1] > 10.0
    assert 1e8 < data["mean_mesh_stiffness_N_per_m"] < 1e9
    assert data["model"] == name


def test_modes_table(cli):
    code, out, err = cli("modes", "--model", "ten_dof")
    assert code == 0, err
    assert "ten_dof (luo2019)" in out and "free model (Hz)" in out and "fixed input speed (Hz)" in out


# --- simulate --------------------------------------------------------------------------------


def test_simulate_six_dof_writes_npz_and_plot(cli, tmp_path):
    out, png = tmp_path / "f.npz", tmp_path / "f.png"
    code, stdout, err = cli(
        "simulate", "--model", "six_dof", "--preset", "meng2020", "--duration", "0.05", "--out", out, "--plot", png
    )
    assert code == 0, err
    assert "simulation wall time" in stdout and f"wrote {out}" in stdout
    with np.load(out, allow_pickle=False) as data:
        assert set(data.files) == {"t", "tacho", "tvms", "pinion_x", "pinion_y", "gear_x", "gear_y"}
        arrays = {k: data[k] for k in data.files}
    n = 10001  # 0.05 s at 200 kHz, both ends
    assert all(a.shape == (n,) for a in arrays.values())
    assert arrays["t"][-1] == pytest.approx(0.05) and np.all(np.diff(arrays["t"]) > 0)
    tacho = arrays["tacho"]
    assert tacho.min() >= -np.pi and tacho.max() < np.pi
    # the tacho is the input-shaft angle: 40 Hz, two revolutions in 0.05 s
    turns = (np.unwrap(tacho)[-1] - tacho[0]) / (2 * np.pi)
    assert turns == pytest.approx(2.0, rel=1e-6)
    assert 1e8 < arrays["tvms"].min() and arrays["tvms"].max() < 1e9
    assert np.all(np.isfinite(arrays["pinion_y"])) and np.abs(arrays["pinion_y"]).max() > 0
    assert png.exists() and png.stat().st_size > 10_000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("name,preset,speed", [("ten_dof", "luo2019", "25.2"), ("six_dof", "meng2020", "40")])
def test_simulate_channels_and_a_broken_tooth_drops_the_tvms(cli, tmp_path, name, preset, speed):
    out = tmp_path / "f.npz"
    code, stdout, err = cli(
        "simulate",
        "--model",
        name,
        "--preset",
        preset,
        "--duration",
        "0.05",
        "--speed",
        speed,
        "--fault",
        "crack@5=20",
        "--out",
        out,
    )
    assert code == 0, err
    assert "crack@5" in stdout
    casing = {"casing_x", "casing_y"} if name == "ten_dof" else set()
    with np.load(out, allow_pickle=False) as data:
        assert set(data.files) == {"t", "tacho", "tvms", "pinion_x", "pinion_y", "gear_x", "gear_y"} | casing
        tvms = data["tvms"]
    assert tvms.min() == 0.0  # a broken tooth carries nothing in single-tooth contact (Figure 2.33)
    assert tvms.max() > 1e8


def test_simulate_default_is_healthy_without_zero_stiffness(cli, tmp_path):
    out = tmp_path / "h.npz"
    code, _, err = cli("simulate", "--model", "eight_dof", "--duration", "0.02", "--out", out)
    assert code == 0, err
    with np.load(out) as data:
        assert data["tvms"].min() > 1e8 and "casing_x" not in data.files


# --- run a dataset scenario --------------------------------------------------------------


def test_run_dataset_b_quick_then_from_cache(cli, tmp_path, monkeypatch, cache):
    # One worker: a process pool costs ~3 s to start per dataset on 2 cores, more than the quick
    # builds themselves; the pool path is covered by test_datasets (LocalExecutor(2) determinism).
    import gearlab.executors
    import gearlab.kinds.common

    monkeypatch.setattr(
        gearlab.kinds.common,
        "make_executor",
        lambda name="local", workers=None, **_: gearlab.executors.make_executor(name, 1),
    )
    code, out, err = cli("run", DATASET_B, "--quick", "--out", tmp_path / "runs")
    assert code == 0, err
    lines = out.strip().splitlines()
    assert lines[-1].startswith("run directory: ")
    run = Path(lines[-1].split("run directory: ", 1)[1])
    assert run.is_dir() and run.parent.parent == tmp_path / "runs"
    names = ["B-6", "B-6-ch5", "B-8", "B-8-ch5-laplace"]  # the summary is sorted by name
    # the class table (a rich table at the end of the run): quick keeps two teeth, the top step
    # of each fault and 4 healthy samples
    rows = [
        [c for c in re.split(r"\s*[┃│]\s*", line.strip()) if c]
        for line in out.splitlines()
        if line.strip()[:1] in ("┃", "│")
    ]
    assert ["class", *names] in rows
    assert ["healthy", "4", "4", "4", "4"] in rows
    for fault in ("crack", "chip", "spall", "pit"):
        assert [fault, "2", "2", "2", "2"] in rows
    assert ["total", "12", "12", "12", "12"] in rows
    assert "from cache" not in out
    summary = json.loads((run / "summary.json").read_text())
    assert summary["kind"] == "dataset" and list(summary["datasets"]) == names
    for name, d in summary["datasets"].items():
        assert d["n"] == 12 and d["shape"] == [12, 4096]
        assert d["counts"] == {"healthy": 4, "crack": 2, "chip": 2, "spall": 2, "pit": 2}
        assert d["cached"] is False
        assert len(d["key"]) == 24 and (cache / f"{d['key']}.npz").is_file()
        assert f"{name}: 12 samples x 4096, cache key {d['key']}" in out
        png = run / "figures" / f"signals_{name}.png"
        assert png.is_file() and png.stat().st_size > 10_000
    # the keys are those of the (quick-reduced) specs; the renamed noisy B-8-ch5 is its own entry
    assert summary["datasets"]["B-8-ch5-laplace"]["spec"]["noise"] == {"kind": "laplace", "snr_db": 0.0, "seed": 1}
    assert len({d["key"] for d in summary["datasets"].values()}) == 4
    b6 = dataset_preset("B-6").with_(
        teeth=(1, 2), faults=tuple((f, s[-1:]) for f, s in dataset_preset("B-6").faults), healthy=4
    )
    assert summary["datasets"]["B-6"]["key"] == b6.key()
    report = (run / "report.html").read_text()
    assert report.lstrip().lower().startswith("<!doctype html") or "<html" in report.lower()
    assert (run / "results.jsonl").read_text().count("\n") == 4

    # again: everything comes from the cache (figures are redrawn; stub them, they were checked above)
    import gearlab.kinds.dataset_figures
    from gearlab.confined import write_file

    def stub(dataset, path):
        write_file(path, b"stub")  # a file of the run directory (a Confined), as plots.save writes it
        return path

    monkeypatch.setattr(gearlab.kinds.dataset_figures, "dataset_signals", stub)
    code, out2, err = cli("run", DATASET_B, "--quick", "--out", tmp_path / "runs")
    assert code == 0, err
    for name, d in summary["datasets"].items():
        assert f"{name}: 12 samples x 4096, cache key {d['key']} (from cache)" in out2
    run2 = Path(out2.strip().splitlines()[-1].split("run directory: ", 1)[1])
    assert run2 != run
    summary2 = json.loads((run2 / "summary.json").read_text())
    assert all(d["cached"] for d in summary2["datasets"].values())
    keys = {n: d["key"] for n, d in summary["datasets"].items()}
    assert {n: d["key"] for n, d in summary2["datasets"].items()} == keys
    assert len(list(cache.glob("*.npz"))) == 4


# --- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args,message",
    [
        (("modes", "--model", "sixdof"), "unknown model 'sixdof' (did you mean 'six_dof'?)"),
        (("modes", "--model", "six_dof", "--preset", "meng"), "unknown preset 'meng' (did you mean 'meng2020'?)"),
        (("simulate", "--model", "tendof", "--out", "{tmp}/f.npz"), "unknown model 'tendof' (did you mean 'ten_dof'?)"),
        (
            ("simulate", "--model", "ten_dof", "--preset", "luo2091", "--out", "{tmp}/f.npz"),
            "unknown preset 'luo2091' (did you mean 'luo2019'?)",
        ),
        (("simulate", "--model", "six_dof", "--out", "{tmp}/f.npy"), "expected a .npz file name"),
        (("simulate", "--model", "six_dof", "--out", "{tmp}/missing/f.npz"), "does not exist"),
        (
            ("simulate", "--model", "six_dof", "--out", "{tmp}/f.npz", "--fs", "5000"),
            "fs = 5000 Hz is too low for the mesh harmonics at 1000 Hz",
        ),
        (
            ("simulate", "--model", "six_dof", "--out", "{tmp}/f.npz", "--fault", "crak@5=20"),
            "unknown fault 'crak' (did you mean 'crack'?)",
        ),
        (("simulate", "--model", "six_dof", "--out", "{tmp}/f.npz", "--fault", "crack@26=20"), "1..25"),
        (("simulate", "--model", "six_dof", "--out", "{tmp}/f.npz", "--fault", "crack@5=21"), "1..20"),
        (("simulate", "--model", "six_dof", "--out", "{tmp}/f.npz", "--duration", "0"), "duration must be a positive"),
        (("simulate", "--model", "six_dof", "--out", "{tmp}/f.npz", "--speed", "-40"), "speed must be a positive"),
    ],
)
def test_bad_input_exit_2_one_line(cli, tmp_path, args, message):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the too-coarse-step warning of --fs 5000 (test_dynamics)
        code, out, err = cli(*args)
    assert code == 2, (out, err)
    line = one_line(err)
    assert line.startswith("error: ") and message in line, line
    assert not (tmp_path / "f.npz").exists()


def test_fs_too_low_is_one_line_in_a_real_process(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-c",
            "from gearlab.cli import main; main()",
            "simulate",
            "--model",
            "six_dof",
            "--out",
            str(tmp_path / "f.npz"),
            "--fs",
            "5000",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    one_line(proc.stderr)


def test_a_too_coarse_step_that_still_runs_is_one_warning_line(cli, tmp_path):
    code, out, err = cli(
        "simulate", "--model", "six_dof", "--out", tmp_path / "f.npz", "--fs", "20000", "--duration", "0.05"
    )
    assert code == 0, err
    line = one_line(err)
    assert line.startswith("warning: ") and "fewer than 10 steps per period" in line, line
    assert (tmp_path / "f.npz").exists()


SCENARIO = '[scenario]\nname = "d"\nkind = "dataset"\n\n[[datasets]]\n'


@pytest.mark.parametrize(
    "body,message",
    [
        ('preset = "B-6-ch4"\n', "unknown dataset preset 'B-6-ch4' (did you mean 'B-6-ch5'?)"),
        ('preset = "B-6-ch5"\nhealty = 3\n', "key 'healty': unknown key (did you mean 'healthy'?)"),
        (
            'preset = "B-6-ch5"\nnoise = { kind = "laplace" }\n',
            "key 'noise': a recording's noise is an effect: effects = [{ name = \"sensor_noise\"",
        ),
        (
            'preset = "B-6-ch5"\neffects = [{ name = "sensor_noise", snr_db = "loud", seed = 1 }]\n',
            "parameter 'snr_db'",
        ),
        (
            'preset = "B-6-ch5"\neffects = [{ name = "sensor_noise", kind = "gaussain", seed = 1 }]\n',
            "'gaussain' is not one of gaussian, laplace, student_t (did you mean 'gaussian'?)",
        ),
        ('preset = "B-6-ch5"\neffects = [{ name = "sensor_noise", seed = 1, colour = "pink" }]\n', "colour"),
        ('preset = "B-6-ch5"\neffects = "laplace"\n', "key 'effects': expected a list"),
        ('preset = "B-6-ch5"\nfaults = { crack = [21] }\n', "step 21 is outside 1..20"),
        ('preset = "B-6-ch5"\nfaults = { crack = "top" }\n', "'crack' must map to a list of ladder steps"),
        ('preset = "B-6-ch5"\ntsa = true\n', "TSA needs revolutions >= 2"),
        ('preset = "B-6-ch5"\nspeed = "-40 Hz"\n', "key 'speed': expected a positive value"),
    ],
)
def test_bad_dataset_scenario_exit_2_one_line_no_run_dir(cli, write_scenario, tmp_path, body, message):
    path = write_scenario(SCENARIO + body)
    code, out, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 2, (out, err)
    line = one_line(err)
    assert message in line and str(path) in line and "[[datasets]] #1" in line, line
    assert not (tmp_path / "runs").exists()  # refused before anything is written
    code, _, err = cli("validate", path)
    assert code == 2 and message in err


@pytest.mark.parametrize(
    "body,message",
    [
        ('model_preset = "meng2021"\n', "unknown preset 'meng2021' (did you mean 'meng2020'?)"),
        ('model = "six_dfo"\n', "unknown model 'six_dfo' (did you mean 'six_dof'?)"),
        ("faults = { crak = [20] }\n", "unknown fault 'crak' (did you mean 'crack'?)"),
        ("teeth = [26]\n", "tooth 26 is outside 1..25"),
        ('channel = "casing_x"\n', "has no channel 'casing_x'"),
    ],
)
def test_model_dependent_mistakes_in_a_dataset_scenario(cli, write_scenario, tmp_path, body, message):
    path = write_scenario(SCENARIO + 'preset = "B-6-ch5"\n' + body)
    code, out, err = cli("validate", path)
    assert code == 2, (out, err)
    code, out, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 2, (out, err)
    line = one_line(err)
    assert message in line and str(path) in line and "[[datasets]] #1" in line, line
    assert not (tmp_path / "runs").exists()


def test_internal_error_is_exit_1_with_one_line(cli, monkeypatch):
    import gearlab.notebook

    def broken(*args, **kwargs):
        raise RuntimeError("boom")

    monkeypatch.setattr(gearlab.notebook, "simulator", broken)
    code, _, err = cli("modes", "--model", "six_dof")
    assert code == 1
    assert "internal error: RuntimeError: boom" in err
