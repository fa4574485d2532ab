"""Every shipped scenario (scenarios/*.toml) through the CLI as a user runs it (issue 38):
`gearlab validate` for each in the normal suite, `gearlab run --quick` for each, marked slow
where it takes more than a few seconds.

QUICK_SECONDS: --quick wall times measured one scenario at a time with a cold dataset cache on 2
cores shared with other work (load average 0.4-4.8 during these runs; at a load of 8-15 the same
runs took 2-8 times as long). Only stiffness_verification fits a few seconds; each other kind
keeps an end-to-end run in the normal suite through other tests: dataset_B --quick
(test_dynamics_cli), and small scenarios of their own for transfer (test_protocol), noise_study
(test_noise_study), gap (test_gap_kind), gap_benchmark (test_gap_benchmark), detection
(test_detection), transfer_benchmark (test_transfer_benchmark).

The PHM 2009 scenarios (phm09_*) read records from ../shared/data/phm09 beside the clone: where
they are absent, their tests are skipped and say so.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest
from conftest import ROOT

SCENARIOS = sorted((ROOT / "scenarios").glob("*.toml"))
FEW_SECONDS = 10.0  # a --quick run this fast joins the normal suite
QUICK_SECONDS = {
    "stiffness_verification.toml": 4.4,
    "dataset_A.toml": 11.4,
    "dataset_B.toml": 12.3,
    "ch4_noise.toml": 15.6,
    "ch4_hybrid.toml": 18.5,
    "phm09_gap.toml": 54.7,
    "expA.toml": 61.3,
    "quick.toml": 63.7,
    "gap_expB.toml": 81.8,
    "expB_thesis.toml": 87.4,
    "gap_expA.toml": 92.2,
    "expB.toml": 96.2,
    "expA_thesis.toml": 113.8,
    "phm09_gap_40hz.toml": 121.3,
    "gap_suborder.toml": 200.4,
    "gap_benchmark.toml": 220.1,
    "phm09_chip.toml": 260.0,
    "transfer_benchmark.toml": 350.7,
    "gap_out_of_library.toml": 368.3,
}


def measured_files(path: Path) -> list[Path]:
    """The measured files a scenario names ('file' keys, and each of 'files'), resolved as the
    scenario resolves them: relative to its folder."""
    found: list[Path] = []

    def walk(node) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                names = [value] if key == "file" else value if key == "files" and isinstance(value, list) else []
                for name in names:
                    name = name.get("file") if isinstance(name, dict) else name
                    if isinstance(name, str) and name:
                        found.append((path.parent / name).resolve())
                walk(value)
        elif isinstance(node, list):
            for item in node:
                walk(item)

    walk(tomllib.loads(path.read_text()))
    return found


def skip_without_its_records(path: Path) -> None:
    missing = [p for p in measured_files(path) if not p.is_file()]
    if missing:
        pytest.skip(
            f"{path.name} reads records that are not here ({missing[0]}; the PHM 2009 records live in "
            "../shared/data/phm09 beside the clone)"
        )


def test_the_list_is_every_shipped_scenario():
    assert set(QUICK_SECONDS) == {p.name for p in SCENARIOS}, "time a new scenario's --quick run"


# What validate says of a scenario besides "OK": phm09_chip's takes as its file list gives them (validate reads
# every take's tacho, 8 s of CPU: one test of it)
SAID = {"phm09_chip.toml": "24 measured records (8 history, 16 test)"}


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_validate(cli, path):
    skip_without_its_records(path)
    code, out, err = cli("validate", path)
    assert code == 0, err
    assert "OK" in out and SAID.get(path.name, "") in out, out


def quick_params():
    for path in SCENARIOS:
        fast = QUICK_SECONDS.get(path.name, float("inf")) <= FEW_SECONDS
        yield pytest.param(path, id=path.stem, marks=() if fast else pytest.mark.slow)


@pytest.fixture(scope="module")
def shared_cache(tmp_path_factory):
    """One dataset cache for this module's runs (several scenarios share their datasets), not the user's."""
    return tmp_path_factory.mktemp("cache")


@pytest.mark.parametrize("path", quick_params())
def test_run_quick(cli, path, tmp_path, monkeypatch, shared_cache):
    skip_without_its_records(path)
    monkeypatch.setenv("GEARLAB_CACHE", str(shared_cache))
    code, out, err = cli("run", path, "--quick", "--out", tmp_path / "runs")
    assert code == 0, err
    last = out.strip().splitlines()[-1]
    assert last.startswith("run directory: "), out
    run = Path(last.split(": ", 1)[1])
    meta = json.loads((run / "run.json").read_text())
    assert meta["status"] == "finished" and meta["quick"] is True, meta
    assert json.loads((run / "summary.json").read_text())
    assert (run / "report.html").stat().st_size > 1000
