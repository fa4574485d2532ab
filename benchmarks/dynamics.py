"""Speed of the dynamics and the dataset factory, with side-by-side ratios in one run.

    python benchmarks/dynamics.py [--skip-ch4]

1. The rank-one numba Newmark against a plain NumPy Newmark loop that assembles and
   inverts the effective system matrix at every step (the public reference style),
   on the same 10-DOF model, steps and stiffness series: ratio (target >= 100x).
2. A 10-DOF, 0.4 s, 200 kHz simulation on one core (target <= 20 ms).
3. Both chapter-5 domains of Dataset B (B-6-ch5 and B-8-ch5 with Laplace noise) built cold
   with 2 workers (target <= 30 s) and loaded warm from the cache (target <= 1 s).
4. The chapter-4 Gaussian set, noisy and TSA (12 800 samples x 60 revolutions), built cold
   with 2 workers (target <= 5 min), with the peak memory of this process and its workers
   (target < 4 GiB).
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time

import numpy as np

from gearlab.data.cache import load_or_build
from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.dynamics.newmark import Simulator
from gearlab.executors import LocalExecutor
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry


def naive_newmark(sim: Simulator, k: np.ndarray, load: float) -> np.ndarray:
    """Textbook Newmark: assemble K(t), C(t), then invert K_hat at every step."""
    M, Kc, Cc, P = sim.M, sim.Kc, sim.Cc, sim.P
    PP = np.outer(P, P)
    a0, a1, a2, a3, a4, a5 = sim.c
    dt, gamma = 1.0 / sim.fs, sim.gamma
    F = np.zeros(len(sim.dofs))
    F[sim.load_index] = -load
    u = np.linalg.solve(Kc + k.mean() * PP, F)
    v = np.zeros_like(u)
    a = np.zeros_like(u)
    out = np.empty(len(k))
    for i, kk in enumerate(k):
        K = Kc + kk * PP
        C = Cc + sim.mu * kk * PP
        K_hat = K + a0 * M + a1 * C
        R = F + M @ (a0 * u + a2 * v + a3 * a) + C @ (a1 * u + a4 * v + a5 * a)
        u_new = np.linalg.inv(K_hat) @ R
        a_new = a0 * (u_new - u) - a2 * v - a3 * a
        v = v + dt * ((1 - gamma) * a + gamma * a_new)
        u, a = u_new, a_new
        out[i] = a[0]
    return out


def peak_memory_gib(workers: int) -> float:
    """An upper bound of the peak resident memory: this process plus *workers* times the largest
    worker (RUSAGE_CHILDREN reports the largest child, not the sum of those running at once)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    largest_child = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return (own + workers * largest_child) / 2**20  # ru_maxrss is in KiB on Linux


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--skip-ch4", action="store_true", help="skip the 5-minute chapter-4 build")
    args = parser.parse_args()
    registry = get_registry()
    sim = Simulator(registry.get("model", "ten_dof"), "luo2019")
    crack = [place_fault(registry, sim.pair, "crack", 5, step=12)]

    # 1, 2. the same 0.4 s simulation (80 000 steps, same stiffness series) both ways
    result = sim.run(crack, duration=0.4)
    ours = min(sim.run(crack, duration=0.4).wall_s for _ in range(5))
    start = time.perf_counter()
    naive_newmark(sim, result.tvms[1:], 7.0)
    naive = time.perf_counter() - start
    print(
        f"10-DOF, 0.4 s at 200 kHz, crack on tooth 5: gearlab {ours * 1e3:.1f} ms (TVMS + integration; "
        f"target <= 20 ms), plain NumPy Newmark inverting every step {naive:.2f} s -> {naive / ours:.0f}x "
        f"(target >= 100x)"
    )

    with tempfile.TemporaryDirectory() as cache:
        os.environ["GEARLAB_CACHE"] = cache
        workers = 2
        executor = LocalExecutor(workers)
        # 3. chapter-5 domains of Dataset B
        specs = [
            dataset_preset("B-6-ch5"),
            dataset_preset("B-8-ch5").with_(name="B-8-ch5-laplace", noise=NoiseSpec("laplace", 0.0, 1)),
        ]
        start = time.perf_counter()
        for spec in specs:
            load_or_build(spec, executor)
        cold = time.perf_counter() - start
        start = time.perf_counter()
        for spec in specs:
            _, cached = load_or_build(spec, executor)
            assert cached
        warm = time.perf_counter() - start
        print(
            f"Dataset B chapter-5 domains (675 + 675 samples): cold {cold:.1f} s (target <= 30 s), "
            f"warm {warm * 1e3:.0f} ms (target <= 1 s) -> {cold / warm:.0f}x"
        )

        # 4. chapter 4, Gaussian noise, noisy + TSA
        if not args.skip_ch4:
            start = time.perf_counter()
            for name in ("A-casing_noise-gaussian", "A-casing_TSA-gaussian"):
                dataset, _ = load_or_build(dataset_preset(name), executor)
                print(f"  {name}: {dataset.X.shape}, {time.perf_counter() - start:.0f} s so far", flush=True)
                del dataset
            total = time.perf_counter() - start
            print(
                f"chapter-4 Gaussian set (12 800 x 60 revolutions, noisy + TSA): cold {total:.0f} s "
                f"(target <= 300 s), peak memory <= {peak_memory_gib(workers):.2f} GiB (this process + {workers} x the "
                f"largest worker; target < 4 GiB)"
            )


if __name__ == "__main__":
    sys.exit(main())
