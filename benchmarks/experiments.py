"""Full reproductions end to end: wall time and peak memory, side by side in one run.

    python benchmarks/experiments.py [--scenario expA expB] [--quick] [--ch4-memory] [--keep DIR]

1. Each transfer scenario (default: scenarios/expA.toml and scenarios/expB.toml) is run as
   `gearlab run` in a child process with an empty dataset cache (datasets cold, every method,
   every repetition), timed, and its process tree's resident memory sampled every 0.2 s.
   Issue 4's target for Experiment B: <= 45 min on 2 cores; issue 42's: <= 5 min (CPU / 2 plus
   the main process's serial share, below: 515 s of CPU, 15.8 in the main process, at 7a7a5e8).
   The tables are checked to be complete (every method x k cell holds 5 repetitions) and
   printed; --keep DIR keeps the run directories (report, results) under DIR.
2. With --ch4-memory: the six chapter-4 datasets (Table 4.1 sizes: 12 800 revolutions each,
   noisy and TSA over J = 60, three noise types) are built cold the same way; their peak
   memory is compared with the data they hold and with CEILING.

Memory is the peak of the summed RSS of gearlab's process and its workers (Linux /proc),
which counts pages shared between them once per process: an upper bound. CPU is the CPU seconds
(user + system) of the same process tree, each process's last sample summed (a pool's workers are
not children that `time` would count); on a machine other work shares, CPU / cores is the wall a
run would take on that many free cores, less its serial parts (issue 42's estimate: Experiment B,
2 cores).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GIB = 2**30
TICKS = os.sysconf("SC_CLK_TCK")  # /proc's CPU times are in these
CEILING = 4 * GIB  # chapter-4 datasets: a quarter of a 16 GiB laptop, whatever the data size
CH4 = [f"A-casing_{kind}-{noise}" for noise in ("gaussian", "laplace", "student_t") for kind in ("noise", "TSA")]


def tree(pid: int) -> list[int]:
    """*pid* and all its descendants."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    found, stack = [], [pid]
    while stack:
        p = stack.pop()
        found.append(p)
        stack += children.get(p, [])
    return found


def tree_rss(pid: int, cpu: dict[int, float] | None = None) -> int:
    """Resident bytes of *pid* and all its descendants (0 once it has gone); *cpu*, when given,
    gets each one's CPU seconds so far."""
    total = 0
    for p in tree(pid):
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1]) * 1024
            if cpu is not None:
                fields = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()
                cpu[p] = (int(fields[11]) + int(fields[12])) / TICKS  # utime + stime
        except (OSError, IndexError, ValueError):
            pass
    return total


def measured(command: list[str], env: dict) -> tuple[float, int, int, float]:
    """(wall seconds, peak tree RSS in bytes, exit code, CPU seconds of the tree) of *command*. The
    CPU is the rusage of the waited-for tree (exact: each process's last tenth of a second
    included, which the 0.2 s samples of /proc miss), or the samples where they add up to more (a
    descendant nobody waited for, such as a Ray worker)."""
    peak, cpu = 0, {}
    before = _children_cpu()
    started = time.perf_counter()
    child = subprocess.Popen(command, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    done = threading.Event()

    def sample():
        nonlocal peak
        while not done.wait(0.2):
            peak = max(peak, tree_rss(child.pid, cpu))

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    _, err = child.communicate()
    done.set()
    sampler.join()
    if child.returncode:
        print(err.strip().splitlines()[-1] if err.strip() else "(no message)", file=sys.stderr)
    seconds, waited = time.perf_counter() - started, _children_cpu() - before
    return seconds, peak, child.returncode, max(waited, sum(cpu.values()))


def _children_cpu() -> float:
    """User + system CPU seconds of this process's waited-for descendants so far."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def gearlab(*args: str) -> list[str]:
    return [sys.executable, "-m", "gearlab", *args]


def complete(run_dir: Path) -> str:
    """'complete' when every cell of the summary's table holds all its repetitions."""
    summary = json.loads((run_dir / "summary.json").read_text())
    cells = [c for row in summary["table"].values() for c in row.values()]
    short = [c for c in cells if c["n"] < summary["protocol"]["repetitions"]]
    return f"{len(cells)} cells, complete" if not short else f"{len(short)} of {len(cells)} cells incomplete"


def transfer(names: list[str], quick: bool, tmp: Path, keep: Path | None) -> None:
    rows, tables = [], []
    for name in names:
        env = {**os.environ, "GEARLAB_CACHE": str(tmp / f"cache-{name}")}  # datasets cold
        out = keep or tmp / "runs"
        args = ["run", str(ROOT / "scenarios" / f"{name}.toml"), "--out", str(out)] + (["--quick"] if quick else [])
        seconds, peak, code, cpu = measured(gearlab(*args), env)
        runs = sorted((out / name).iterdir()) if (out / name).exists() else []
        state = complete(runs[-1]) if code == 0 and runs else f"FAILED (exit {code})"
        rows.append((name, seconds, peak, cpu, state))
        if code == 0 and runs:
            tables.append(f"\n{name} ({runs[-1]}):\n{(runs[-1] / 'table.md').read_text()}")
    first = rows[0][1]
    print(f"\ntransfer scenarios{' (--quick)' if quick else ''}, datasets cold, {os.cpu_count()} cores:")
    head = f"{'wall':>10s} {'/ first':>8s} {'/ 45 min':>9s} {'CPU':>8s} {'CPU / 2':>8s} {'peak RSS':>10s}"
    print(f"  {'scenario':10s} {head}  table")
    for name, seconds, peak, cpu, state in rows:
        print(
            f"  {name:10s} {seconds / 60:8.1f} min {seconds / first:7.2f}x {seconds / 2700:8.2f}x "
            f"{cpu:7.0f}s {cpu / 2:7.0f}s {peak / GIB:7.2f} GiB  {state}"
        )
    print("".join(tables), end="")


def ch4_memory(tmp: Path) -> None:
    scenario = tmp / "ch4_datasets.toml"
    scenario.write_text(
        '[scenario]\nname = "ch4_datasets"\nkind = "dataset"\n\n'
        + "".join(f'[[datasets]]\npreset = "{p}"\n\n' for p in CH4)
    )
    env = {**os.environ, "GEARLAB_CACHE": str(tmp / "cache-ch4")}
    seconds, peak, code, _ = measured(gearlab("run", str(scenario), "--out", str(tmp / "runs")), env)
    if code:
        print(f"chapter-4 datasets: FAILED (exit {code})")
        return
    run = sorted((tmp / "runs" / "ch4_datasets").iterdir())[-1]
    datasets = json.loads((run / "summary.json").read_text())["datasets"]
    one = max(d["shape"][0] * d["shape"][1] * 4 for d in datasets.values())  # float32 rows
    held = sum(d["shape"][0] * d["shape"][1] * 4 for d in datasets.values())
    print(
        f"\nchapter-4 datasets ({len(datasets)} x {one / GIB:.2f} GiB of float32 rows, {held / GIB:.2f} GiB "
        f"in all), built cold in {seconds / 60:.1f} min:"
    )
    print(
        f"  peak RSS {peak / GIB:.2f} GiB = {peak / one:.1f}x one dataset, {peak / held:.2f}x all of them; "
        f"ceiling {CEILING / GIB:.0f} GiB: {'OK' if peak <= CEILING else 'EXCEEDED'} ({peak / CEILING:.2f}x)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", nargs="*", default=["expA", "expB"], help="transfer scenarios in scenarios/")
    parser.add_argument("--quick", action="store_true", help="run them with --quick (a smoke run of this script)")
    parser.add_argument("--ch4-memory", action="store_true", help="also build the chapter-4 datasets cold")
    parser.add_argument("--keep", type=Path, help="keep the transfer runs' directories under this folder")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="gearlab-experiments-") as tmp:
        if args.scenario:
            transfer(args.scenario, args.quick, Path(tmp), args.keep)
        if args.ch4_memory:
            ch4_memory(Path(tmp))


if __name__ == "__main__":
    main()
