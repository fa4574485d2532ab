"""Null targets written as measured files: how often the gap diagnosis says "no significant gap".

    python benchmarks/gap_nulls.py [--trials 30] [--seed 7] [--folder DIR]

Each trial writes the plain source (B-6-ch5, the benchmark's base noise, its own noise seed) as a
measured record the way `gearlab gap benchmark` does (gearlab.gap.benchmark.Acquisition: 0.3-0.7 x
4096 samples per revolution, revolutions starting between samples, the tacho's zero uniform over
the turn, float npz / int16 npz / int16 PCM wav), and diagnoses it from the file alone
(diagnose_file, default reports: 200 bootstraps, 500 permutations). A null has no effect to
find: it costs one report unless the test calls it significant, so many trials take a minute.
Prints one JSON line per trial and the share per format.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from gearlab.data.spec import dataset_preset
from gearlab.gap import benchmark as bench


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--folder", type=Path, default=None, help="where the records go (default: a temporary folder)")
    args = parser.parse_args()
    folder = args.folder or Path(tempfile.mkdtemp(prefix="gap_nulls_"))
    source = dataset_preset("B-6-ch5").with_(healthy=40)
    source = source.with_(noise=bench.BASE_NOISE) if source.noise is None else source
    settings = {
        "budget": 1,
        "max_effects": 1,
        "healthy": 40,
        "bootstrap": 200,
        "permutations": 500,
        "alpha": 0.05,
        "seed": args.seed,
    }
    records = []
    for i in range(args.trials):
        acquisition = bench.Acquisition.draw(np.random.default_rng([args.seed, 2, i]))
        noise_seed = int(np.random.default_rng([args.seed, 1, i]).integers(1, 2**31 - 1))
        trial = bench.Trial(i, "null", (), None, ("sensor_noise",), noise_seed, acquisition)
        started = time.perf_counter()
        path = bench.write_target(trial, source, folder / f"s{args.seed}_{i:03d}", 80)
        result = bench.diagnose_file(path, source, ("sensor_noise",), settings)
        record = {
            "i": i,
            "format": acquisition.format,
            "rate_share": round(acquisition.rate_share, 3),
            "offset_deg": round(float(np.degrees(acquisition.offset)), 2),
            "offset_fit_deg": round(result["chain"]["offset_deg"], 2),
            "p": result["before"]["p_value"],
            "auc": round(result["before"]["auc"], 3),
            "significant": result["significant_before"],
            "verdict": result["verdict"],
            "seconds": round(time.perf_counter() - started, 1),
        }
        records.append(record)
        print(json.dumps(record), flush=True)
    print(f"no significant gap: {sum(not r['significant'] for r in records)} / {len(records)}")
    for fmt in bench.FORMATS:
        mine = [not r["significant"] for r in records if r["format"] == fmt]
        print(f"  {fmt}: {sum(mine)} / {len(mine)}")
    worst = max(abs((r["offset_fit_deg"] - r["offset_deg"] + 180) % 360 - 180) for r in records)
    print(f"largest tacho offset error: {worst:.3f} deg")


if __name__ == "__main__":
    main()
