"""Issue 19, thirteenth round: how long `phm09_chip.toml` must take on this machine at its protocol.

A finished run stores each training's time (`seconds`) and, for an adaptation, its epochs
(`history`). An adaptation cannot stop before the end of its lambda ramp (`min_epochs`, 500 in
Table 5.3): the stopping rule is read from epoch `min_epochs` on (gearlab.learn.training). So
the run's floor, with the same trainings and every adaptation stopped at the first epoch the rule
allows, is its training time less the epochs it ran beyond that, each at the epoch cost measured
here, side by side, on this machine: `fit_adaptation` itself on the run's shapes (`fast`, the
scenario's points per revolution and batch, target_train rows per domain, each method's own
domain loss) and random data.

    python benchmarks/phm09_runtime.py RUN [--wall SECONDS] [--epochs 40]

RUN is a finished run folder of phm09_chip.toml (or any detection run). The wall time is read
from the folder (its name is the start; summary.json is written last) unless given. Printed: the
trainings' time per method, the epochs beyond the floor and what they cost, and the run's wall
time scaled to the floor (the trainings fill both workers throughout: the wall time scales with
their total). No test label is read.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from collections import defaultdict
from datetime import datetime
from pathlib import Path

import numpy as np
import torch

from gearlab.engine import load_scenario
from gearlab.learn.networks import build_network
from gearlab.learn.training import fit_adaptation
from gearlab.registry import get_registry

SOURCE_VAL = 32  # the source's held-out share (10 % of 320 samples)


def wall_seconds(run: Path) -> float:
    """From the run folder's name (its start, YYYYmmdd-HHMMSS-micro) to summary.json's time."""
    started = datetime.strptime(run.name, "%Y%m%d-%H%M%S-%f").timestamp()
    return (run / "summary.json").stat().st_mtime - started


def epoch_seconds(protocol, points: int, adapters: list[str], epochs: int, rounds: int = 3) -> dict[str, float]:
    """Seconds per adaptation epoch of each adapter on random data of the run's shapes (*points*
    samples per revolution), the adapters alternated round by round so that all see the same
    machine load."""
    rng = np.random.default_rng(0)
    n = protocol.target_train
    Xs = rng.normal(size=(n, points)).astype(np.float32)
    ys = np.arange(n) % 2
    Xv, yv = rng.normal(size=(SOURCE_VAL, points)).astype(np.float32), np.arange(SOURCE_VAL) % 2
    Xt = rng.normal(size=(n, points)).astype(np.float32)
    times: dict[str, list[float]] = defaultdict(list)
    for _ in range(rounds):
        for name in adapters:
            adapter = get_registry().get("adapter", name)
            net = build_network(protocol.network, 2, dropout=protocol.dropout, length=points, seed=0)
            modules = adapter.extra_modules(net.latent_dim, {})
            started = time.perf_counter()
            fit_adaptation(
                net,
                adapter,
                modules,
                (Xs, ys),
                (Xv, yv),
                (Xt, None),
                rng=np.random.default_rng(1),
                device=torch.device("cpu"),
                batch=protocol.batch,
                lr=protocol.lr,
                min_epochs=epochs,  # the ramp ends with the timed epochs: the stopping rule never reads them
                max_epochs=epochs,
            )
            times[name].append((time.perf_counter() - started) / epochs)
    return {name: statistics.median(t) for name, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--wall", type=float, help="the run's wall time in seconds (default: from the folder)")
    parser.add_argument("--epochs", type=int, default=40, help="epochs timed per adapter and round")
    args = parser.parse_args()
    torch.set_num_threads(1)  # as each worker of a run
    run = args.run
    base = json.loads((run / "run.json").read_text())["base"]  # where the scenario's paths are resolved
    spec = load_scenario(run / "scenario.toml", base=base).spec
    protocol = spec["protocol"]
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines() if line.strip()]
    trainings = [r for r in records if "seconds" in r and "members" not in r]  # each training once
    floor = protocol.min_epochs + 1  # the first epoch the stopping rule may stop at
    adapters = sorted({r["adapter"] for r in trainings if r.get("history") and r["history"]["train_loss"]})
    cost = epoch_seconds(protocol, spec["points"], adapters, args.epochs)

    total = sum(r["seconds"] for r in trainings)
    # per method: seconds, trainings, epochs beyond the floor, their cost
    by_method: dict[str, list[float]] = defaultdict(lambda: [0.0, 0, 0, 0.0])
    for r in trainings:
        row = by_method[r["method"]]
        row[0] += r["seconds"]
        row[1] += 1
        history = r.get("history")
        if history and history["train_loss"]:
            extra = max(len(history["train_loss"]) - floor, 0)
            row[2] += extra
            row[3] += extra * cost[r["adapter"]]
    wall = args.wall if args.wall is not None else wall_seconds(run)
    saved = sum(row[3] for row in by_method.values())
    print(f"run {run}: wall {wall / 60:.1f} min; {len(trainings)} trainings, {total / 60:.1f} min of training time")
    print(
        f"adaptation epoch here (fit_adaptation, {protocol.network}, {spec['points']} points, "
        f"batch {protocol.batch} + {protocol.batch}):"
    )
    for name, seconds in cost.items():
        print(f"  {name:14s} {1e3 * seconds:6.1f} ms")
    print(f"{'method':30s} {'trainings':>9s} {'minutes':>8s} {'epochs > ' + str(floor - 1):>12s} {'their min':>9s}")
    for method, (seconds, n, extra, extra_cost) in sorted(by_method.items(), key=lambda kv: -kv[1][0]):
        print(f"{method:30s} {n:9d} {seconds / 60:8.1f} {extra:12d} {extra_cost / 60:9.1f}")
    floor_wall = wall * (total - saved) / total
    print(
        f"floor at the protocol (every adaptation stopped at epoch {floor}): training {(total - saved) / 60:.1f} min, "
        f"wall {floor_wall / 60:.1f} min (the run: {wall / 60:.1f} min; the issue's goal: 20 min)"
    )


if __name__ == "__main__":
    main()
