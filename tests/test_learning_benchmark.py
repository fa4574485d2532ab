"""benchmarks/learning.py: its shapes comparison runs at HEAD (it broke silently when
matched_start began to require the history's noise law) and prints both timings and their ratio."""

import importlib.util

from conftest import ROOT


def test_shapes_comparison_runs_and_prints_its_ratio(capsys):
    spec = importlib.util.spec_from_file_location("learning_benchmark", ROOT / "benchmarks" / "learning.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    bench.shapes_local(1)
    out = capsys.readouterr().out
    assert "local (an eighth of the revolution)" in out and "whole revolution" in out
    assert "ratio whole revolution / local" in out
