"""benchmarks/training.py: its FLOP count of a network (the machine's limit it reports) against a
count by hand, and one tiny run that prints the table."""

import importlib.util
import sys

import pytest
import torch
from conftest import ROOT


def _benchmark():
    spec = importlib.util.spec_from_file_location("training_benchmark", ROOT / "benchmarks" / "training.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_fast_flops_per_sample_are_counted_by_hand():
    """`fast` at 2048 samples: each convolution and dense layer 2 FLOPs a multiply-add forward,
    as many for the weights' gradient, and as many for the input's gradient except the first
    layer's (its input, the signal, needs none)."""
    bench = _benchmark()
    net = bench.network("fast", 2048, torch.device("cpu"))
    counts = bench.flops_per_sample(net, 2048, torch.device("cpu"))
    conv1 = 16 * 128 * 64  # 16 kernels of 64 taps at 128 positions (stride 16, padding 24)
    conv2 = 32 * 32 * 16 * 3  # after the pool: 64 -> 32 positions
    conv3 = 64 * 16 * 32 * 3
    assert counts["conv"] == 2 * conv1 * 2 + 2 * (conv2 + conv3) * 3
    assert counts["matmul"] == 2 * (64 * 64 + 64 * 2) * 3


@pytest.mark.parametrize("case", ["fast", "fast+coral", "fast+mmd"])
def test_a_tiny_run_prints_the_ratios(monkeypatch, capsys, case):
    """A supervised and a joint step (the calibrated methods', most of phm09_chip's training)."""
    bench = _benchmark()
    threads = torch.get_num_threads()
    monkeypatch.setattr(sys, "argv", ["training.py", "--rounds", "1", "--steps", "1", "--networks", case])
    try:
        bench.main()
    finally:
        torch.set_num_threads(threads)
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith(f"{case} "))
    fields = row.split("(")[0].split()  # before "(the scenarios)"
    gearlab_per_plain, gearlab_per_limit = float(fields[-2]), float(fields[-1])
    assert 0 < gearlab_per_plain and 0 < gearlab_per_limit < 1  # no network beats the machine's limit
    assert "matmul" in out and "conv1d" in out
    ms_per_step, fixed_ms, speed = float(fields[-5]), float(fields[-4]), float(fields[-3])
    assert 0 < fixed_ms < ms_per_step and speed > 0  # a batch of 2 costs more than 1/20 and less than all of 40's


def test_a_step_splits_into_its_fixed_cost_and_a_cost_per_sample():
    """Steps of 2.0 + 0.1 * batch ms: 2.2 ms at batch 2 and 6.0 at 40 give back both terms."""
    bench = _benchmark()
    assert bench.SMALL == 2
    fixed, per_sample = bench.split(6.0e-3, 2.2e-3, 40, 2)
    assert abs(fixed - 2.0e-3) < 1e-12 and abs(per_sample - 0.1e-3) < 1e-12
