"""A run's workers load what its kind's units load first before the first pool of the run starts
(gearlab.kinds.common.executor_for, ScenarioKind.unit_modules): the forkserver imports them once, and
each worker is forked with them loaded. Detection warmed only after reading its target, which a
multi-file target reads on the pool, so its workers were forked bare and each imported torch itself;
the gap and noise-study kinds warmed nothing."""

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from detection_scenario import scenario

from gearlab.engine import load_scenario

SCENARIOS = Path(__file__).parents[1] / "scenarios"

WARMED = """
import json, sys
from gearlab.engine import load_scenario
from gearlab.kinds.common import executor_for
from test_run_warm import forkserver_maps
scenario = load_scenario(sys.argv[1])
with executor_for(scenario) as executor:
    started = executor._pool is not None
    print(json.dumps([started, executor.map(forkserver_maps, ["libtorch", "libtorch"])]))
"""


def forkserver_maps(library: str) -> bool:
    """Whether this worker's parent, the forkserver, has *library* mapped: it imported the module itself."""
    return library in Path(f"/proc/{os.getppid()}/maps").read_text()


@pytest.mark.skipif(sys.platform != "linux", reason="reads the forkserver's memory map in /proc")
def test_a_detection_run_has_its_forkserver_load_torch_before_it_reads_its_target(tmp_path):
    """A fresh process, as `gearlab run` is: the run's executor starts no pool, and the first map (the
    records' read of a multi-file target) finds torch loaded once, by the forkserver, not by each worker."""
    path = scenario(tmp_path)
    path.write_text(path.read_text().replace("workers = 1", "workers = 2"))
    here = str(Path(__file__).parent)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([here, *filter(None, [os.environ.get("PYTHONPATH")])])}
    out = subprocess.run(
        [sys.executable, "-c", WARMED, str(path)], env=env, capture_output=True, text=True, check=True, cwd=tmp_path
    )
    started, mapped = json.loads(out.stdout)
    assert not started  # the warm alone starts no pool: a run that maps nothing loads nothing
    assert mapped == [True, True]
    assert "torch" in load_scenario(path).unit_modules


@pytest.mark.parametrize(
    "name",
    [
        "quick.toml",
        "gap_expA.toml",
        "ch4_noise.toml",
        "dataset_A.toml",
        "gap_benchmark.toml",
        "transfer_benchmark.toml",
    ],
)
def test_each_kinds_unit_modules_exist(name):
    """The forkserver skips a preload it cannot import, silently: a module renamed would leave the
    workers to load everything themselves again."""
    modules = load_scenario(SCENARIOS / name).unit_modules
    assert modules
    assert all(importlib.util.find_spec(module) is not None for module in modules), modules
