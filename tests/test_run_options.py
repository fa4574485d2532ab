"""`gearlab run` options that set [execution] keys, and `gearlab gap` on the wrong inputs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

STIFFNESS = """\
[scenario]
name = "stiff"
kind = "stiffness"

[stiffness]
pair = "luo2019"
points = 256

[sweep]
faults = ["crack"]
steps = [1, 3]
"""


@pytest.fixture
def scenario(tmp_path) -> Path:
    path = tmp_path / "stiff.toml"
    path.write_text(STIFFNESS)
    return path


def refused(code, err, *parts):
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for part in parts:
        assert part in lines[0], lines[0]


@pytest.mark.parametrize("option, value, key", [("--executor", "slurm", "executor"), ("--device", "gpu", "device")])
def test_bad_execution_options_are_refused_like_bad_scenario_keys(cli, scenario, tmp_path, option, value, key):
    code, _, err = cli("run", scenario, option, value, "--out", tmp_path / "runs")
    refused(code, err, f"[execution] key '{key}'", f"'{value}'")
    assert not (tmp_path / "runs").exists()


def test_options_reach_the_resolved_scenario_and_a_resume_may_change_them(cli, scenario, tmp_path):
    code, out, err = cli("run", scenario, "--executor", "local", "--device", "cpu", "--out", tmp_path / "runs")
    assert code == 0, err
    run = Path(out.strip().splitlines()[-1].removeprefix("run directory: "))
    assert 'device = "cpu"' in (run / "scenario.toml").read_text()
    # where units run is not what they compute: resuming with another device is allowed
    code, out, err = cli("run", "--resume", run, "--device", "auto")
    assert code == 0, err
    assert json.loads((run / "summary.json").read_text())["kind"] == "stiffness"


def test_gap_refuses_a_scenario_of_another_kind(cli, scenario):
    code, _, err = cli("gap", scenario)
    refused(code, err, str(scenario), "[scenario] key 'kind'", '"gap"', "gearlab run")


def test_gap_scenario_refuses_benchmark_options(cli, scenario):
    code, _, err = cli("gap", scenario, "--trials", "3")
    refused(code, err, "--trials and --seed belong to `gearlab gap benchmark`")


def test_gap_benchmark_checks_its_overrides(cli, tmp_path, monkeypatch):
    monkeypatch.chdir(Path(__file__).resolve().parents[1])
    code, _, err = cli("gap", "benchmark", "--trials", "0", "--out", tmp_path / "runs")
    refused(code, err, "gap_benchmark.toml", "[benchmark] key 'trials'")
    assert not (tmp_path / "runs").exists()
