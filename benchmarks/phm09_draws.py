"""Issue 19, fifteenth round: the corrected source's noise draws — fixed, or turned round the revolution.

The corrected source holds D noise draws of every sample ([corrected] draws), and a training batch
row is one of its own sample's draws, picked at random (gearlab.learn.training._rows). The design
tried here: a row is its sample's mean over the draws plus one draw's deviation from that mean,
turned round the revolution by a random angle — another draw of the noise wherever the noise is
stationary over the revolution, so no batch row repeats one.

For one condition of a detection scenario this prints

* the premise: the variance of the corrected source's draw deviations (as the learned methods see
  them) in each sixteenth of the revolution, relative to its mean, and their correlation at lags
  1-3 per sixteenth (stationary noise: 1 and the same in every sixteenth);
* the source AUC (training data only: the held-out samples of the source, every draw) of each
  corrected training, seed by seed, with the rows as shipped and with turned deviations, beside the
  source's bound.

The kind is run twice on the condition's records (a run folder each, under OUT), one worker, with
the methods asked; no test label is read (only the trainings' source AUCs are printed).

    python benchmarks/phm09_draws.py scenarios/phm09_chip.toml OUT [--condition "30 Hz high load"]
        [--methods source_only dann coral mmd] [--seeds 2]

About 11 min for the four methods at 30 Hz high load on this machine (both sources are trained).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path
from unittest import mock

import numpy as np
import torch
from phm09_localised import run_detection

import gearlab.learn.training as training
from gearlab.data.cache import load_or_build
from gearlab.engine import load_scenario
from gearlab.executors import LocalExecutor
from gearlab.kinds import detection
from gearlab.learn.protocol import Method, each_draw

SHIPPED = training._rows


def turned_rows(X: torch.Tensor, index: torch.Tensor, draws) -> torch.Tensor:
    """A row: its sample's mean over the draws plus one draw's deviation, turned by a random angle."""
    if X.ndim == 2:
        return X[index]
    n, length = len(index), X.shape[-1]
    rows = X[index]
    mean = rows.mean(dim=1)
    pick = torch.as_tensor(draws.integers(X.shape[1], size=n))
    turn = torch.as_tensor(draws.integers(length, size=n))
    deviation = rows[torch.arange(n), pick] - mean
    angle = (torch.arange(length) - turn[:, None]) % length
    return mean + deviation.gather(1, angle)


def one_condition(path: Path, condition: str, methods: list[str], seeds: int):
    """The scenario cut to *condition*'s records, *methods*, *seeds*, one worker."""
    scenario = load_scenario(path, {"detection": {"seeds": seeds}, "execution": {"workers": 1}})
    spec = scenario.spec
    files = tuple(f for f in spec["target"].files if f.condition == condition)
    if not files:
        raise SystemExit(f"{path}: no record of condition '{condition}'")
    spec["target"] = dataclasses.replace(spec["target"], files=files)
    spec["protocol"] = dataclasses.replace(spec["protocol"], methods=tuple(Method(m, False) for m in methods))
    return scenario


def stationarity(scenario, condition: str, samples: int = 60) -> None:
    spec = scenario.spec
    cond = detection.read_target(spec["target"], spec["blocks"], lambda e: None)[condition]
    source = detection.source_for(spec["corrected"], cond, spec["source_speed"])
    data, _ = load_or_build(source, LocalExecutor(1), lambda e: None)
    draws = spec["corrected_draws"]
    X = data.X.reshape(-1, draws, data.X.shape[-1])[:samples]
    seen = each_draw(detection.learned_input(spec, cond["max_order"]), X)
    deviation = seen - seen.mean(axis=1, keepdims=True)
    by_sixteenth = deviation.reshape(*deviation.shape[:2], 16, -1)
    var = (by_sixteenth**2).mean(axis=(0, 1, 3))
    print(f"{condition}, corrected source ({len(X)} samples x {draws} draws), its draws' deviations:")
    print("  variance per sixteenth of the revolution / mean:", " ".join(f"{v:.3f}" for v in var / var.mean()))
    for lag in (1, 2, 3):
        product = deviation * np.roll(deviation, -lag, axis=-1)
        r = product.reshape(*product.shape[:2], 16, -1).mean(axis=(0, 1, 3)) / var
        print(f"  correlation at lag {lag} per sixteenth:", " ".join(f"{v:+.3f}" for v in r))


def source_aucs(scenario, out: Path, rows) -> tuple[dict, float | None]:
    with mock.patch.object(training, "_rows", rows):
        path = run_detection(scenario, out)
    records = [json.loads(line) for line in (path / "results.jsonl").read_text().splitlines() if line.strip()]
    aucs = {
        (r["method"], r["seed"]): r["source_auc"]
        for r in records
        if r.get("source") != "source" and r.get("seed") is not None and r.get("source_auc") is not None
    }
    (cond,) = json.loads((path / "conditions.json").read_text()).values()
    bound = next(v for k, v in cond["source_bound"].items() if k != "source")
    return aucs, bound


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--condition", default="30 Hz high load")
    parser.add_argument("--methods", nargs="+", default=["source_only", "dann", "coral", "mmd"])
    parser.add_argument("--seeds", type=int, default=2)
    args = parser.parse_args()
    torch.set_num_threads(1)  # as each worker of a run
    scenario = one_condition(args.scenario, args.condition, args.methods, args.seeds)
    stationarity(scenario, args.condition)
    shipped, bound = source_aucs(scenario, args.out / "shipped", SHIPPED)
    turned, _ = source_aucs(scenario, args.out / "turned", turned_rows)
    print(f"source AUC of the corrected trainings (bound {bound:.2f}):")
    print(f"  {'method':28s} {'seed':>4s} {'shipped':>8s} {'turned':>8s}")
    for key in sorted(shipped):
        print(f"  {key[0]:28s} {key[1]:4d} {shipped[key]:8.3f} {turned.get(key, float('nan')):8.3f}")
    gain = [turned[k] - shipped[k] for k in shipped if k in turned]
    print(f"  mean change {np.mean(gain):+.3f} over {len(gain)} trainings")


if __name__ == "__main__":
    main()
