"""The CLI of the foundation issue: plugins, stiffness, validate, run, report; exit codes."""

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT


def test_plugins_json_lists_builtin_faults_with_units(cli):
    code, out, err = cli("plugins", "--json")
    assert code == 0, err
    rows = json.loads(out)
    faults = {r["name"]: r for r in rows if r["kind"] == "fault"}
    assert set(faults) >= {"crack", "chip", "spall", "pit"}
    for row in faults.values():
        assert row["package"] == "gearlab"
        assert row["params"], row
        for p in row["params"]:
            assert {"name", "unit", "default", "low", "high"} <= set(p)
    q0 = next(p for p in faults["crack"]["params"] if p["name"] == "q0")
    assert q0["unit"] == "m" and q0["display_unit"] == "mm"


def test_plugins_table(cli):
    code, out, _ = cli("plugins")
    assert code == 0
    for name in ("crack", "chip", "spall", "pit"):
        assert name in out


@pytest.mark.parametrize("preset", ["luo2019", "meng2020"])
def test_stiffness_csv_healthy_and_faulted(cli, tmp_path, preset):
    healthy, faulted = tmp_path / "h.csv", tmp_path / "f.csv"
    assert cli("stiffness", "--preset", preset, "--csv", healthy)[0] == 0
    code, out, err = cli(
        "stiffness", "--preset", preset, "--fault", "crack@5=20", "--csv", faulted, "--plot", tmp_path / "f.png"
    )
    assert code == 0, err
    assert "RFA 1.0000" in out
    for path in (healthy, faulted):
        assert path.read_text().splitlines()[0] == "theta_rad,k_N_per_m"
    h = np.loadtxt(healthy, delimiter=",", skiprows=1)
    f = np.loadtxt(faulted, delimiter=",", skiprows=1)
    assert h.shape == (4096, 2) and np.allclose(h[:, 0], f[:, 0])
    assert 1e8 < h[:, 1].mean() < 1e9
    assert f[:, 1].min() == 0.0 and f[:, 1].mean() < h[:, 1].mean()
    assert (tmp_path / "f.png").stat().st_size > 10_000


def test_stiffness_explicit_parameters_with_units_match_ladder(cli, tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    # Step 20 of the luo2019 spall ladder is l_s = 1 mm, w_s = 15 mm, h_s = 1 mm, x_1 = 4 mm (Table 2.5).
    assert cli("stiffness", "--preset", "luo2019", "--fault", "spall@3=20", "--csv", a)[0] == 0
    code, _, err = cli(
        "stiffness", "--preset", "luo2019", "--fault", "spall@3:l_s=1 mm,w_s=1.5cm,h_s=1000um,x_1=0.004", "--csv", b
    )
    assert code == 0, err
    assert np.array_equal(np.loadtxt(a, delimiter=",", skiprows=1), np.loadtxt(b, delimiter=",", skiprows=1))


def test_stiffness_points_option(cli, tmp_path):
    path = tmp_path / "k.csv"
    assert cli("stiffness", "--preset", "meng2020", "--points", "1000", "--csv", path)[0] == 0
    assert len(path.read_text().splitlines()) == 1001


@pytest.mark.parametrize(
    "args, message",
    [
        (["--preset", "luo2018"], "did you mean 'luo2019'"),
        (["--preset", "luo2019", "--fault", "crak@3=2"], "did you mean 'crack'"),
        (["--preset", "luo2019", "--fault", "crack@17=3"], "1..16"),
        (["--preset", "luo2019", "--fault", "crack@0=3"], "1..16"),
        (["--preset", "luo2019", "--fault", "crack@3=0"], "1..20"),
        (["--preset", "luo2019", "--fault", "crack@3=21"], "1..20"),
        (["--preset", "luo2019", "--fault", "crack@3=x"], "STEP"),
        (["--preset", "luo2019", "--fault", "crack3"], "KIND@TOOTH"),
        (["--preset", "luo2019", "--fault", "crack@3:q0=6mm"], "deeper than the tooth is thick"),
        (["--preset", "luo2019", "--fault", "spall@3:x_1=7mm,l_s=1mm,w_s=3mm"], "past the tooth tip"),
        (["--preset", "luo2019", "--fault", "chip@3:c=-1mm"], "outside"),
        (["--preset", "luo2019", "--fault", "chip@3:c=1 s"], "wrong dimension"),
        (["--preset", "luo2019", "--fault", "chip@3:width=1mm"], "unknown parameter 'width'"),
        (["--preset", "luo2019", "--fault", "broken_tip@3:b=50mm,c=3mm"], "chip depth b = 50 mm reaches past"),
        (["--preset", "luo2019", "--fault", "broken_tip@3:b=1mm,c=30mm"], "exceeds the face width 16 mm"),
        (["--preset", "luo2019", "--points", "3"], "--points"),
    ],
)
def test_stiffness_bad_input_one_line_exit_2(cli, args, message):
    code, out, err = cli("stiffness", *args)
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "args, message",
    [
        (["stiffness"], "Missing option '--preset'"),
        (["stiffness", "--preset", "luo2019", "--points", "many"], "Invalid value for '--points'"),
        (["stiffness", "--preset", "luo2019", "--bogus"], "No such option: --bogus"),
        (["modes"], "give --model NAME (and --preset) or --gearbox DESCRIPTION"),
        (["stifness"], "No such command 'stifness'"),
    ],
)
def test_usage_errors_one_line_exit_2(cli, args, message):
    code, out, err = cli(*args)
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], err
    assert "Traceback" not in err


def test_stiffness_bad_csv_directory(cli, tmp_path):
    code, _, err = cli("stiffness", "--preset", "luo2019", "--csv", tmp_path / "missing" / "k.csv")
    assert code == 2 and "does not exist" in err


def test_validate_ok_and_bad(cli, write_scenario):
    code, out, _ = cli("validate", ROOT / "scenarios" / "stiffness_verification.toml")
    assert code == 0 and "OK" in out
    bad = write_scenario('[scenario]\nname = "x"\nkind = "stiffness"\n[stiffness]\npair = "luo2019"\npoint = 100\n')
    code, _, err = cli("validate", bad)
    assert code == 2
    assert "[stiffness] key 'point'" in err and "did you mean 'points'" in err and str(bad) in err


def test_run_stiffness_scenario_quick_and_resume(cli, tmp_path):
    code, out, err = cli("run", ROOT / "scenarios" / "stiffness_verification.toml", "--out", tmp_path, "--quick")
    assert code == 0, err
    last = out.strip().splitlines()[-1]
    assert last.startswith("run directory: ")
    run = Path(last.split(": ", 1)[1])
    summary = json.loads((run / "summary.json").read_text())
    assert set(summary["sweep"]) == {"crack", "chip", "spall", "pit"}
    assert summary["sweep"]["crack"]["20"]["rfa"] == pytest.approx(1.0)
    assert summary["sweep"]["crack"]["20"]["min"] == 0.0
    for name in ("tvms_ladders.png", "rfa.png", "tvms_cases.png"):
        assert (run / "figures" / name).stat().st_size > 10_000
    assert (run / "cases" / "crack_step10.csv").read_text().startswith("theta_rad,k_N_per_m\n")
    html = (run / "report.html").read_text()
    assert "data:image/png;base64," in html
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    # resume after a kill: drop the last record and a half-written line, rerun only that unit
    lines = (run / "results.jsonl").read_text().splitlines(keepends=True)
    (run / "results.jsonl").write_text("".join(lines[:-1]) + '{"unit": "half')
    code, out, err = cli("run", "--resume", run, "--quick")
    assert code == 0, err
    again = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    assert [r["unit"] for r in again] == [r["unit"] for r in records]
    assert again == records
    code, out, _ = cli("report", run)
    assert code == 0


def test_run_unwritable_output(cli, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    code, _, err = cli("run", ROOT / "scenarios" / "stiffness_verification.toml", "--out", blocker)
    assert code == 2 and "cannot write the run directory" in err


def test_resume_not_a_run_dir(cli, tmp_path):
    code, _, err = cli("run", "--resume", tmp_path)
    assert code == 2 and "not a gearlab run directory" in err


def test_a_file_without_a_rate_gets_it_from_the_scenario_not_from_run(cli, tmp_path):
    """A CSV without a time column: the rate is the measured entry's 'fs' (what a run computes lives
    in its scenario, which the run directory keeps; `run` options say only where it runs), and a
    run without it is refused at validate, naming the key, before any run directory is made."""
    fs, speed = 10_000.0, 25.0
    t = np.arange(int(fs)) / fs
    acc, tacho = np.sin(2 * np.pi * 20 * speed * t), np.where(np.mod(speed * t, 1.0) < 0.05, 5.0, 0.0)
    np.savetxt(tmp_path / "r.csv", np.c_[acc, tacho], delimiter=",", header="acc,tacho", comments="", fmt="%.6g")
    entry = '[scenario]\nname = "m"\nkind = "dataset"\n[[datasets]]\nfile = "r.csv"\n'
    entry += 'vibration = "acc"\ntacho = "tacho"\n'
    scenario = tmp_path / "m.toml"
    scenario.write_text(entry)
    code, _, err = cli("run", scenario, "--out", tmp_path / "runs")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "[[datasets]] #1 key 'fs': missing" in err and "carries no sampling rate" in err and "r.csv" in err, err
    assert not (tmp_path / "runs").exists()
    scenario.write_text(entry + 'fs = "10 kHz"\ntransient = "none"\n')
    code, out, err = cli("validate", scenario)
    assert code == 0 and "OK" in out, err


def test_gap_refuses_a_scenario_of_another_kind_naming_the_kinds_it_runs(cli):
    """`gearlab gap FILE` runs the kinds the registry gives it (kinds.GAP_COMMAND_KINDS: the diagnosis
    and its benchmark); another kind's file is one line, exit 2, naming each of them."""
    code, _, err = cli("gap", ROOT / "scenarios" / "quick.toml")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert 'key \'kind\': expected "gap" or "gap_benchmark" for `gearlab gap`, got "transfer"' in err, err
