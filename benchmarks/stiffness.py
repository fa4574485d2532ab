"""Speed of the TVMS engine, measured side by side with a plain per-angle quad implementation.

    python benchmarks/stiffness.py

Prints the time of a healthy and a single-fault TVMS (4096 points), a 2000-pit TVMS, the
whole 82-case verification scenario, and the ratio against the reference style of
published PEM code (scipy quad per contact angle, tests/pem_reference.py) on the same
angles in the same run. Targets: <= 50 ms, <= 200 ms, <= 10 s.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from pem_reference import tooth_pair_stiffness  # noqa: E402

from gearlab.engine import run_scenario  # noqa: E402
from gearlab.physics.presets import gear_pair  # noqa: E402
from gearlab.physics.stiffness import MeshStiffnessModel  # noqa: E402
from gearlab.registry import get_registry  # noqa: E402


def best_of(fn, repeat=5):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times), statistics.median(times)


def main() -> None:
    registry = get_registry()
    pair = gear_pair("luo2019")
    crack, pit = registry.get("fault", "crack"), registry.get("fault", "pit")
    cracked = [crack.place(5, crack.at_step(pair, 12), pair)]
    pitted = [pit.place(5, pit.at_step(pair, 20), pair)]

    # Cold: includes building the healthy sections (what `gearlab stiffness` pays).
    cold, _ = best_of(lambda: MeshStiffnessModel(pair).mesh_stiffness(points=4096))
    model = MeshStiffnessModel(pair)
    healthy, _ = best_of(lambda: model.mesh_stiffness(points=4096))
    single, _ = best_of(lambda: model.mesh_stiffness(cracked, points=4096))
    pits, _ = best_of(lambda: model.mesh_stiffness(pitted, points=4096))
    print(f"healthy TVMS, 4096 points, cold model : {cold * 1e3:7.1f} ms   (target <= 50 ms)")
    print(f"healthy TVMS, 4096 points              : {healthy * 1e3:7.1f} ms")
    print(f"crack on tooth 5, 4096 points          : {single * 1e3:7.1f} ms   (target <= 50 ms)")
    print(f"2000 pits on tooth 5, 4096 points      : {pits * 1e3:7.1f} ms   (target <= 200 ms)")

    # Side by side: the same tooth-pair angles through the reference quad implementation.
    phi = np.linspace(0, pair.theta_t, 200)[1:-1]
    ours, _ = best_of(lambda: model.tooth_pair_stiffness(phi), repeat=20)
    ref, _ = best_of(lambda: [tooth_pair_stiffness(pair, p) for p in phi], repeat=3)
    print(
        f"one tooth pair, {len(phi)} angles: engine {ours * 1e3:.2f} ms, per-angle quad {ref * 1e3:.0f} ms "
        f"-> ratio {ref / ours:.0f}x"
    )

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        run_scenario(ROOT / "scenarios" / "stiffness_verification.toml", out=tmp)
        whole = time.perf_counter() - start
    print(f"verification scenario (82 TVMS cases + CSVs + figures + report): {whole:.2f} s   (target <= 10 s)")


if __name__ == "__main__":
    main()
