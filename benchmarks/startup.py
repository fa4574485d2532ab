"""Start-up times of the commands that do no work, measured side by side in one run.

    python benchmarks/startup.py [--repeat N]

Each command runs N times (default 5) in a fresh interpreter; the median wall time and the
median CPU time (user + system) are printed with their ratio to the issue-42 goal, beside the
interpreter alone and the import of the modules these commands no longer load (torch, numba,
scipy.stats, matplotlib.pyplot: what each command cost on top before). The TUI's first screen is
the app started headless (Textual's test pilot) until the scenario tree is filled.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

TUI = """
import asyncio
from gearlab.tui.app import GearlabApp

async def first_screen():
    app = GearlabApp("scenarios")
    async with app.run_test() as pilot:
        await pilot.pause()
        assert app.entries

asyncio.run(first_screen())
"""

# name, command, goal in seconds (None: a reference, no goal)
COMMANDS = [
    ("python alone", [sys.executable, "-c", "pass"], None),
    (
        "heavy modules (before: on top of each)",
        [sys.executable, "-c", "import torch, numba, scipy.stats, matplotlib.pyplot"],
        None,
    ),
    ("gearlab --help", [sys.executable, "-m", "gearlab", "--help"], 1.0),
    (
        "gearlab validate scenarios/quick.toml",
        [sys.executable, "-m", "gearlab", "validate", "scenarios/quick.toml"],
        1.0,
    ),
    ("TUI first screen (scenario tree)", [sys.executable, "-c", TUI], 2.0),
]


def timed(command: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds of one run of *command*."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, env={**os.environ, "NO_COLOR": "1"})
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise SystemExit(f"{' '.join(command)} failed:\n{done.stderr[-2000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}; median of {args.repeat} runs each")
    cached = (ROOT / "gearlab" / "__pycache__").is_dir()  # written before, they are read whatever the variable says
    if os.environ.get("PYTHONDONTWRITEBYTECODE") and not cached:  # every gearlab module is compiled at each start
        print("PYTHONDONTWRITEBYTECODE is set: no bytecode caches, 0.1-0.2 s more per command than a user's")
    rows = {name: [] for name, _, _ in COMMANDS}
    for _ in range(args.repeat):  # interleaved: a load that comes and goes hits every command alike
        for name, command, _ in COMMANDS:
            rows[name].append(timed(command))
    heavy = statistics.median(w for w, _ in rows[COMMANDS[1][0]])
    print(f"{'command':42s} {'wall s':>7s} {'CPU s':>7s} {'goal s':>7s} {'wall/goal':>9s} {'heavy/wall':>10s}")
    for name, _, goal in COMMANDS:
        wall = statistics.median(w for w, _ in rows[name])
        cpu = statistics.median(c for _, c in rows[name])
        ratio = f"{wall / goal:9.2f}" if goal else f"{'':9s}"
        print(f"{name:42s} {wall:7.2f} {cpu:7.2f} {goal or float('nan'):7.1f} {ratio} {heavy / wall:10.2f}")


if __name__ == "__main__":
    main()
