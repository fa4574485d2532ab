"""Overhead of the Ray executor against the local process pool, measured side by side in one run.

    python benchmarks/executors.py [--scenario scenarios/quick.toml] [--quick] [--workers N] [--tasks N]

1. Per task: a trivial function mapped over --tasks items, local pool against Ray (the Ray
   session already open; its start-up is timed on its own).
2. A transfer scenario (default scenarios/quick.toml; --quick shrinks it as `gearlab run
   --quick` does): the wall time of its training units on one local worker, on the local pool
   and on Ray, with the datasets built beforehand into a shared temporary cache so that every
   executor runs the same work. Ray runs twice: right after start-up (its workers still cold)
   and again (warm). The records must be the same on every executor.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def nothing(x: int) -> int:
    return x


def per_task(workers: int, tasks: int) -> None:
    from gearlab import executors

    items = range(tasks)
    t = time.perf_counter()
    executors.LocalExecutor(workers).map(nothing, items)
    local = time.perf_counter() - t

    t = time.perf_counter()
    executors._open_session(None, workers)
    start = time.perf_counter() - t
    ray_executor = executors.RayExecutor(workers=workers)
    ray_executor.map(nothing, range(2 * workers))  # start the workers: not part of the per-task cost
    t = time.perf_counter()
    ray_executor.map(nothing, items)
    ray = time.perf_counter() - t

    print(f"ray session start (ray.init, {workers} CPUs): {start:.1f} s")
    print(f"trivial map over {tasks} items, {workers} workers (local includes its pool start-up):")
    print(f"  local {local:7.2f} s   {1e3 * local / tasks:6.2f} ms/task")
    print(f"  ray   {ray:7.2f} s   {1e3 * ray / tasks:6.2f} ms/task   ratio ray / local: {ray / local:.2f}x")


def scenario_text(path: Path, execution: str) -> str:
    text = path.read_text()
    if "[execution]" in text:
        raise SystemExit(f"{path}: has its own [execution] table; give a scenario without one")
    return text + f"\n[execution]\n{execution}\n"


def records(run: Path) -> dict[str, dict]:
    out = {}
    for line in (run / "results.jsonl").read_text().splitlines():
        r = json.loads(line)
        out[r["unit"]] = {k: v for k, v in r.items() if "seconds" not in k and "time" not in k}
    return out


def scenario_runs(path: Path, workers: int, quick: bool) -> None:
    from gearlab.data.cache import load_or_build
    from gearlab.engine import load_scenario, run_scenario
    from gearlab.executors import LocalExecutor
    from gearlab.kinds import SCENARIO_KINDS

    tmp = Path(tempfile.mkdtemp(prefix="gearlab-bench-"))
    os.environ["GEARLAB_CACHE"] = str(tmp / "cache")
    os.environ.pop("RAY_ADDRESS", None)
    scenario = load_scenario(path)
    if quick:
        SCENARIO_KINDS[scenario.kind].quick(scenario)
    t = time.perf_counter()
    for data in (scenario.spec.source, scenario.spec.target):
        load_or_build(data, LocalExecutor(workers))
    print(
        f"\n{path.name}{' --quick' if quick else ''}: datasets built in {time.perf_counter() - t:.1f} s "
        "(shared by all runs below)"
    )

    runs = [
        ("local, 1 worker", "workers = 1"),
        (f"local, {workers} workers", f"workers = {workers}"),
        (f"ray, {workers} CPUs (cold)", f'executor = "ray"\nworkers = {workers}'),
        (f"ray, {workers} CPUs (warm)", f'executor = "ray"\nworkers = {workers}'),
    ]
    times, results = {}, {}
    for i, (label, execution) in enumerate(runs):
        file = tmp / f"run{i}.toml"
        file.write_text(scenario_text(path, execution))
        t = time.perf_counter()
        run = run_scenario(file, out=tmp / f"runs{i}", quick=quick)
        times[label] = time.perf_counter() - t
        results[label] = records(run.path)
    local = times[runs[1][0]]
    print(f"training units ({len(results[runs[0][0]])}), wall time:")
    for label, seconds in times.items():
        print(f"  {label:24s} {seconds:7.1f} s   / local {workers} workers: {seconds / local:.2f}x")
    same = all(r == results[runs[0][0]] for r in results.values())
    print(f"  same records on every executor: {'yes' if same else 'NO'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", type=Path, default=ROOT / "scenarios" / "quick.toml")
    parser.add_argument("--quick", action="store_true", help="shrink the scenario as `gearlab run --quick` does")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--tasks", type=int, default=200)
    args = parser.parse_args()
    try:
        import ray  # noqa: F401
    except ImportError:
        raise SystemExit("Ray is not installed: pip install 'gearlab[ray]'") from None
    # Wall times mean little on a machine that other jobs keep busy: say how busy it was.
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start")
    per_task(args.workers, args.tasks)
    scenario_runs(args.scenario, args.workers, args.quick)
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":  # the local pool's workers import this module: run only as a script
    main()
