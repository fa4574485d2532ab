"""benchmarks/experiments.py counts the CPU seconds of a run's whole process tree (issue 42): a
pool's workers burn most of a run's CPU and are not children that `time` counts."""

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import experiments  # noqa: E402


def test_a_runs_cpu_counts_its_workers():
    burn = "import time\nt = time.process_time()\nwhile time.process_time() - t < 1.0: pass"
    parent = f"import subprocess, sys; subprocess.run([sys.executable, '-c', {burn!r}], check=True)"
    seconds, peak, code, cpu = experiments.measured([sys.executable, "-c", parent], dict(os.environ))
    assert code == 0 and peak > 0
    assert 1.0 <= cpu <= seconds + 0.5  # the grandchild's second is in it
