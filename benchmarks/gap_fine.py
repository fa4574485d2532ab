"""The gap search's fine stage (gearlab.gap.diagnose._fine_stage), old and new side by side.

    python benchmarks/gap_fine.py [--effect casing_path] [--seed 1005] [--folder DIR]

Writes one development target the way `gearlab gap benchmark` does (gearlab.gap.benchmark.write_target:
*effect* with parameters drawn from the benchmark's ranges by *seed*, a measured record of 80
revolutions) and fits *effect* on it as a diagnosis's first round does (fit_effect, the noise
nuisance beside it, the default budget): the coarse search alone (old), then the fine stage from
its fit, as the round runs it for its first fits (new: both together). Prints the truth's score,
each fit's score, evaluations and seconds, and the ratios new / old. Use development seeds, never
a benchmark trial's.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from gearlab.data.spec import dataset_preset
from gearlab.effects import default_candidates
from gearlab.gap import benchmark as bench
from gearlab.gap import diagnose as d
from gearlab.registry import get_registry


def fits(name: str, prepared: tuple) -> dict:
    """The coarse fit (old) and the fine stage from it (new: both together, as a round runs them)."""
    search, target, settings, rows = prepared
    task = (search, name, (), target, settings, settings.seed + 1000, True, rows)
    started = time.perf_counter()
    old = d.fit_effect(task)
    old["wall"] = time.perf_counter() - started
    fine = d.fit_effect(task + (old["params"],))
    new = fine if fine["score"] < old["score"] else dict(old)
    new.update(evaluations=old["evaluations"] + fine["evaluations"], wall=time.perf_counter() - started)
    return {"old": old, "new": new}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--effect", default="casing_path")
    parser.add_argument("--seed", type=int, default=1005)
    parser.add_argument("--folder", type=Path, default=None, help="where the record goes (default: a temporary folder)")
    args = parser.parse_args()
    warnings.simplefilter("ignore", UserWarning)
    registry = get_registry()
    source = dataset_preset("B-6-ch5").with_(noise=bench.BASE_NOISE, healthy=40)
    rng = np.random.default_rng(args.seed)
    effect = registry.get("effect", args.effect)
    params = bench.draw_params(effect, rng)
    trial = bench.Trial(
        args.seed,
        "single",
        (effect.spec(params),),
        None,
        tuple(default_candidates(registry)),
        args.seed,
        bench.Acquisition.draw(rng),
    )
    folder = args.folder or Path(tempfile.mkdtemp(prefix="gap_fine_"))
    path = bench.write_target(trial, source, folder, 80)
    rows_t, chain, max_order = bench.import_target(path)
    settings = d.Settings(candidates=(args.effect,), seed=5, max_order=max_order)
    target, chain, rows, settings, _, search, _ = d._prepared(source, rows_t, settings, chain)
    scorer = d._scorer(target, search, settings, rows)
    truth = scorer.score(rows(search.with_(effects=d._by_level(search.effects + (effect.spec(params),)))))
    print(json.dumps({"effect": args.effect, "seed": args.seed, "truth": params, "truth_score": truth}))
    fitted = fits(args.effect, (search, target, settings, rows))
    print(f"{'':6s} {'score':>12s} {'evaluations':>12s} {'seconds':>9s}  parameters")
    for label, out in fitted.items():
        shown = {k: float(f"{v:.4g}") if isinstance(v, float) else v for k, v in out["params"].items()}
        print(f"{label:6s} {out['score']:12.4g} {out['evaluations']:12d} {out['wall']:9.1f}  {shown}")
    old, new = fitted["old"], fitted["new"]
    print(
        f"ratio new / old: score {new['score'] / old['score']:.3g}, evaluations "
        f"{new['evaluations'] / old['evaluations']:.2f}x, seconds {new['wall'] / old['wall']:.2f}x; "
        f"truth scores {truth:.4g}"
    )


if __name__ == "__main__":
    main()
