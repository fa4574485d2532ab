"""Speed of the networks and of the chapter-5 protocol, measured side by side in one run.

    python benchmarks/learning.py [--units]

1. One training step (forward, backward, SGD update) on a joint domain-adaptation batch of
   40 source + 40 target rotations of 4096 samples, `fast` against `cnn3`, alternating the
   two so that both see the same machine load. Target: fast >= 20x faster.
2. The same step of `burst` with its normalisation frozen (the joint phase), normalising only
   each filter's extremes (NormMaxAbs, shipped) against normalising the whole map.
3. The same step of `shapes` (a joint-phase batch, started on 256 fault bursts): each template
   on its own eighth of the revolution (shipped) against the same templates over the whole
   revolution (the likelihoods are the same; tests/test_networks.py).
4. With --units: the wall time of the protocol's units on Experiment B's datasets (priming,
   a baseline, one calibrated run at the full Table 5.3 schedule) and from them an estimate
   of the whole expB.toml table (6 k x 5 repetitions x every method). Target: <= 45 min.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import torch
from torch import nn

from gearlab.learn.networks import build_network

BATCH = 80  # 40 source + 40 target (Table 5.3)
LENGTH = 4096
STEPS = 3  # per timing


def step_time(net: nn.Module, x: torch.Tensor, y: torch.Tensor) -> float:
    opt = torch.optim.SGD(net.parameters(), lr=0.003)
    loss_fn = nn.CrossEntropyLoss()

    def step():
        opt.zero_grad()
        loss_fn(net(x), y).backward()
        opt.step()

    step()  # first call allocates
    t = time.perf_counter()
    for _ in range(STEPS):
        step()
    return (time.perf_counter() - t) / STEPS


def compare(rounds: int, title: str, variants: dict) -> None:
    """Print the median step time of each variant of a network (label -> a function that builds
    it) on one joint-phase batch, the variants alternated round by round so that all see
    the same machine load, and the second's time over the first's."""
    torch.manual_seed(0)
    x = torch.randn(BATCH, LENGTH)
    y = torch.randint(0, 2, (BATCH,))
    times: dict[str, list[float]] = {label: [] for label in variants}
    for _ in range(rounds):
        for label, build in variants.items():
            times[label].append(step_time(build(), x, y))
    median = {label: statistics.median(t) for label, t in times.items()}
    print(f"{title}, median of {rounds}:")
    for label, seconds in median.items():
        print(f"  {label:36s} {1e3 * seconds:8.1f} ms")
    first, second = median
    print(f"  ratio {second} / {first}: {median[second] / median[first]:.2f}x")


def networks(rounds: int) -> None:
    torch.manual_seed(0)
    x = torch.randn(BATCH, LENGTH)
    y = torch.randint(0, 2, (BATCH,))
    times: dict[str, list[float]] = {"fast": [], "cnn3": []}
    for _ in range(rounds):
        for name in times:
            times[name].append(step_time(build_network(name, 2, seed=0), x, y))
    fast, cnn3 = (statistics.median(times[n]) for n in ("fast", "cnn3"))
    print(f"training step, batch {BATCH} x {LENGTH}, {torch.get_num_threads()} threads (median of {rounds}):")
    print(f"  fast {1e3 * fast:8.1f} ms")
    print(f"  cnn3 {1e3 * cnn3:8.1f} ms")
    print(f"  ratio cnn3 / fast: {cnn3 / fast:.1f}x   (target >= 20x)")


class WholeMap(nn.Module):
    """BatchNorm1d over the whole filter-bank map, then |.| and the maximum over the revolution:
    what NormMaxAbs computes from the extremes alone."""

    def __init__(self, fused: nn.BatchNorm1d):
        super().__init__()
        self.norm = nn.BatchNorm1d(fused.num_features)
        self.norm.load_state_dict(fused.state_dict())

    def forward(self, y: torch.Tensor) -> torch.Tensor:
        return self.norm(y).abs().amax(dim=-1)


def burst_frozen(rounds: int) -> None:
    from gearlab.learn.training import train_mode

    def frozen(whole_map: bool) -> nn.Module:
        net = build_network("burst", 2, seed=0)
        if whole_map:
            net.features[-1] = WholeMap(net.features[-1])
        train_mode(net, freeze_norm=True)
        return net

    compare(
        rounds,
        "burst, joint-phase step (normalisation frozen)",
        {"extremes (NormMaxAbs)": lambda: frozen(False), "whole map": lambda: frozen(True)},
    )


def shapes_local(rounds: int) -> None:
    from gearlab.learn.networks import ShapeLikelihood, matched_start

    rng = np.random.default_rng(0)
    faults = np.zeros((256, LENGTH))
    for row in faults:  # decaying bursts of ~100 samples at random angles, as Experiment B's faults
        at = rng.integers(LENGTH)
        row[(at + np.arange(200)) % LENGTH] = rng.normal(size=200) * np.exp(-np.arange(200) / 40.0)

    def started(whole_revolution: bool) -> nn.Module:
        net = build_network("shapes", 2, seed=0)
        if whole_revolution:
            net.features[1] = ShapeLikelihood(len(net.features[1].weight), LENGTH)
        matched_start(net, faults, seed=0, law="gaussian")  # the bursts above are Gaussian
        return net

    compare(
        rounds,
        "shapes, joint-phase step (256 templates)",
        {"local (an eighth of the revolution)": lambda: started(False), "whole revolution": lambda: started(True)},
    )


def units() -> None:
    from gearlab.data.cache import load_or_build
    from gearlab.engine import load_scenario
    from gearlab.kinds.transfer import units as all_units
    from gearlab.learn.protocol import Method, Protocol, StateStore, run_unit

    scenario = load_scenario("scenarios/expB.toml")
    spec = scenario.spec
    source, _ = load_or_build(spec.source)
    target, _ = load_or_build(spec.target)
    full: Protocol = spec.protocol
    timed = {}
    states = StateStore(None)

    def time_unit(method: Method) -> float:
        t = time.perf_counter()
        run_unit(full, source, target, 0, 4, method, states)
        return time.perf_counter() - t

    timed["source_only"] = time_unit(Method("source_only", False))
    timed["priming + mmd"] = time_unit(Method("mmd", False))
    timed["mmd"] = time_unit(Method("mmd", False, shown=(("again", 1),)))  # priming now shared
    timed["dann"] = time_unit(Method("dann", False))
    timed["target_only"] = time_unit(Method("target_only", True))
    timed["finetune"] = time_unit(Method("finetune", True, (("variant", 0),)))
    print("protocol units on Experiment B (k = 4, repetition 0, one thread):")
    for name, seconds in timed.items():
        print(f"  {name:16s} {seconds:7.1f} s")
    prime = timed["priming + mmd"] - timed["mmd"]
    calibrated = 0.5 * (timed["mmd"] + timed["dann"])
    total = 0.0
    for _rep, k, m in all_units(full):
        if m.adapter == "source_only":
            total += timed["source_only"] if k == full.ks[0] else 0.0  # trained once per repetition
        elif m.adapter in ("target_only", "finetune"):
            total += timed[m.adapter]
        else:
            total += calibrated
    total += prime * full.repetitions  # one priming per repetition
    print(
        f"estimated full expB.toml table: {total / 60:.1f} min on one worker, {total / 120:.1f} min on two "
        f"({len(all_units(full))} units; target <= 45 min on 2 cores)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--units", action="store_true", help="also time the protocol's units on Experiment B")
    parser.add_argument(
        "--threads",
        type=int,
        default=1,
        help="torch threads (1, as each unit of a run uses; more threads than idle cores stall)",
    )
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    networks(args.rounds)
    burst_frozen(args.rounds)
    shapes_local(args.rounds)
    if args.units:
        units()


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    main()
