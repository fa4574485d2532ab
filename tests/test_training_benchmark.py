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
    # this process's CPU seconds, the median of 3 rounds: on the wall clock a step timed while other
    # work held the core (the suite's other worker) made the batch-2 split's fixed cost negative
    monkeypatch.setattr(
        sys, "argv", ["training.py", "--rounds", "3", "--steps", "1", "--clock", "cpu", "--networks", case]
    )
    try:
        bench.main()
    finally:
        torch.set_num_threads(threads)
    out = capsys.readouterr().out
    lines = out.splitlines()
    header = next(line for line in lines if line.startswith("network ")).replace("step ms", "step_ms")
    names = header.split()[2:]  # after network and input, whose values hold spaces
    row = next(line for line in lines if line.startswith(f"{case} "))
    value = dict(zip(names, map(float, row.split("(")[0].split()[-len(names) :])))  # before "(the scenarios)"
    assert 0 < value["gearlab/plain"] and 0 < value["gearlab/limit"] < 1  # no network beats the machine's limit
    # the roof holds each layer to its bytes as well as its FLOPs: never above the FLOP limit, and lower
    # where the bytes move at the memory's bandwidth than at the cache's (to the noise of one round)
    assert value["roof/s"] <= value["limit/s"] * (1 + 1e-9) and value["dram/s"] <= value["roof/s"] * 1.5
    assert 0 < value["gearlab/roof"] < 1 and value["KB/sa"] > 0
    assert "matmul" in out and "conv1d" in out and "GB/s (memory)" in out
    # a batch of 2 costs more than 1/20 and less than all of 40's
    assert 0 < value["step_ms"] < value["ms/step"] and value["GF/s"] > 0
    assert any(line.startswith(f"  {case}: a step ") for line in lines)  # where the distance lies


def test_a_step_splits_into_its_fixed_cost_and_a_cost_per_sample():
    """Steps of 2.0 + 0.1 * batch ms: 2.2 ms at batch 2 and 6.0 at 40 give back both terms."""
    bench = _benchmark()
    assert bench.SMALL == 2
    fixed, per_sample = bench.split(6.0e-3, 2.2e-3, 40, 2)
    assert abs(fixed - 2.0e-3) < 1e-12 and abs(per_sample - 0.1e-3) < 1e-12


def test_the_roof_takes_each_layer_at_the_slower_of_its_flops_and_its_bytes():
    """2 GFLOP at 1 GFLOP/s moving 1 GB at 1 GB/s: 2 s; a layer of no counted FLOPs moving 2 GB: 2 s."""
    bench = _benchmark()
    assert bench.roofline([("conv", 2e9, 1e9), ("", 0.0, 2e9)], {"conv": 1e9, "matmul": 5e9}, 1e9) == 4.0


def test_fast_bytes_per_sample_are_counted_by_hand():
    """`fast`'s first convolution at batch 40: the signal (2048) and its map (16 x 128) forward, the
    map's gradient and the saved signal backward (the signal needs no gradient), its 16 x 64 weights
    read, read again and their gradient written once a step; AsChannels, a view, moves nothing."""
    bench = _benchmark()
    net = bench.network("fast", 2048, torch.device("cpu"))
    costs = bench.layer_costs(net, 2048, torch.device("cpu"), batch=40)
    assert costs[0] == ("", 0.0, 0.0)  # AsChannels
    kind, flops, moved = costs[1]
    assert kind == "conv" and flops == 2 * 16 * 128 * 64 * 2
    assert moved == 4.0 * (2 * (2048 + 16 * 128) + 3 * 16 * 64 / 40)


def _compiled_run(monkeypatch, capsys, compile_fn) -> str:
    """A tiny run of `fast` with --compile default, torch.compile replaced by *compile_fn*."""
    bench = _benchmark()
    monkeypatch.setattr(bench.torch, "compile", compile_fn)
    threads = torch.get_num_threads()
    argv = ["training.py", "--rounds", "1", "--steps", "1", "--networks", "fast", "--compile", "default"]
    monkeypatch.setattr(sys, "argv", argv)
    try:
        bench.main()
    finally:
        torch.set_num_threads(threads)
    return capsys.readouterr().out


def test_a_compiled_loop_is_timed_beside_gearlab(monkeypatch, capsys):
    """--compile adds the plain loop with the network's modules compiled (here a stand-in that
    returns them as they are), its compile seconds and the steps that repay them."""
    out = _compiled_run(monkeypatch, capsys, lambda model, mode, dynamic: model)
    lines = out.splitlines()
    header = next(line for line in lines if line.strip().startswith("network ") and "compiled/gearlab" in line)
    names = header.replace("compile s", "compile_s").replace("repaid after", "repaid_after").split()
    row = next(line for line in lines if line.split()[:2] == ["fast", "default"])
    value = dict(zip(names[2:-1], map(float, row.split()[2:8])))
    assert value["compile_s"] >= 0 and value["compiled/s"] > 0 and value["ms/step"] > 0
    assert value["compiled/gearlab"] > 0 and 0 < value["compiled/roof"] < 1
    assert row.endswith(" steps") or row.endswith("never")
    assert any(line.startswith("fast ") for line in lines)  # the main table as before


def test_a_compilation_that_fails_leaves_the_rest_of_the_run(monkeypatch, capsys):
    """Without a C++ compiler inductor fails at the first call: the row says why in one line and
    the benchmark goes on."""

    def compile_fn(model, mode, dynamic):
        def fails(x):
            raise RuntimeError("no C++ compiler found\nmore detail")

        return fails

    out = _compiled_run(monkeypatch, capsys, compile_fn)
    row = next(line for line in out.splitlines() if line.split()[:2] == ["fast", "default"])
    assert row.split(None, 2)[2] == "failed: RuntimeError: no C++ compiler found"
    assert any(line.startswith("fast ") and "(phm09_chip)" in line for line in out.splitlines())


def test_a_compilation_is_repaid_by_the_steps_it_saves():
    """10 s of compilation saving 1 ms a step: 10,000 steps; a compiled step no faster: never."""
    bench = _benchmark()
    assert bench.repaid_after(10.0, 3e-3, 2e-3) == pytest.approx(10_000)
    assert bench.repaid_after(10.0, 2e-3, 2e-3) == float("inf")


def test_shapes_is_measured_at_quick_toml_s_five_classes_too():
    """`shapes/5`: the network of scenarios/quick.toml's 5 classes, 256 templates a fault class
    (1,024), each of an eighth of the revolution: 6 FLOPs a sample and template element."""
    bench = _benchmark()
    assert "shapes/5" in [case[0] for case in bench.CASES] and bench.CLASSES["shapes/5"] == 5
    net = bench.network("shapes", 4096, torch.device("cpu"), classes=5)
    assert net.classifier.member.sum(0).tolist() == [1, 256, 256, 256, 256]
    counts = bench.flops_per_sample(net, 4096, torch.device("cpu"))
    assert counts == {"conv": 0.0, "matmul": 6.0 * 1024 * 512}
