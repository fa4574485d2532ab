"""Why `likelihood_ratio` ranks the PHM 2009 chips badly on the plain simulator (issue 19).

Builds the detector exactly as the detection kind does (same source datasets, same
difference signals, the same 120 history revolutions) for every condition and source of a
detection scenario, and scores the test units (revolutions and 30-revolution TSAs) in four
ways, so the cause can be read off the AUCs (labels used here only to measure, as in the
kind's summary):

* ``detector``  the detector as it is: each unit's own noise scale (median absolute residual);
* ``history σ`` the same shapes and noise law, the noise scale fixed to the healthy history
  units' median scale (of the same unit kind), the same under both hypotheses;
* ``rev σ``     the same with the history *revolutions'* median scale for every unit kind (what a
  detector that sees only revolutions when it is built can fix);
* ``σ alone``   the unit's own noise scale as a score (what the detector divides by);
* ``|r|``       the norm of the unit's residual from the history's median (anything unusual).

It also prints what the detector's shapes are scaled by (the size between the domains) and the
noise law. Run from the repository root:

    python benchmarks/phm09_likelihood.py scenarios/phm09_chip.toml

Needs the shared PHM records and takes about a minute (no training).
"""

from __future__ import annotations

import math
import sys

import numpy as np
import torch

from gearlab.data.cache import load_or_build
from gearlab.engine import load_scenario
from gearlab.kinds.detection import (
    auc,
    history_training_rows,
    learned_input,
    read_target,
    source_for,
    source_split,
)
from gearlab.learn.bounds import noise_scale, shape_llr
from gearlab.learn.detectors import likelihood_detector

UNITS = ("revolution", "record30")


def scores(det, X: np.ndarray, scale: float | None = None) -> np.ndarray:
    """log Λ of the rows of *X*: the detector's own (scale None: each row's scale) or at a fixed scale."""
    X = torch.as_tensor(X, dtype=torch.float32)
    r = X - det.reference
    s = noise_scale(r, det.kind) if scale is None else torch.full((len(r),), float(scale))
    with torch.no_grad():
        return (torch.logsumexp(shape_llr(r, det.shapes, s, det.kind), 1) - math.log(len(det.shapes))).numpy()


def main(path: str) -> None:
    spec = load_scenario(path).spec
    conditions = read_target(spec["target"], spec["blocks"], lambda e: None)
    positive = {f.path: f.label == spec["target"].positive for f in spec["target"].files}
    sources = {"plain": spec["source"]}
    if spec.get("corrected") is not None:
        sources[spec["corrected_label"]] = spec["corrected"]
    print(
        "| condition | source | noise law | shapes' RMS / history residual RMS | unit "
        "| detector | history σ | rev σ | σ alone | |r| |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for c, cond in conditions.items():
        shown = learned_input(spec, cond["max_order"])
        for name, source in sources.items():
            dataset, _ = load_or_build(source_for(source, cond, spec["source_speed"]))
            Xs, ys, _, _ = source_split(dataset, spec["protocol"])
            Xt = shown(history_training_rows(cond, spec["protocol"], c))
            det = likelihood_detector(shown(Xs), ys, Xt, None, spec["false_alarm"])
            ref = det.reference.numpy()
            size = float(np.sqrt(np.mean(det.shapes.numpy() ** 2)) / np.sqrt(np.mean((Xt - ref) ** 2)))
            rev_sigma = float(noise_scale(torch.as_tensor(Xt) - det.reference, det.kind).median())
            for u in UNITS:
                hist = shown(cond["history_units"][u])
                sigma = float(noise_scale(torch.as_tensor(hist) - det.reference, det.kind).median())
                got = {k: ([], []) for k in ("detector", "history σ", "rev σ", "σ alone", "|r|")}
                for p, units in cond["test_units"].items():
                    X = shown(units[u])
                    r = torch.as_tensor(X) - det.reference
                    k = int(positive[p])
                    got["detector"][k].append(scores(det, X))
                    got["history σ"][k].append(scores(det, X, sigma))
                    got["rev σ"][k].append(scores(det, X, rev_sigma))
                    got["σ alone"][k].append(noise_scale(r, det.kind).numpy())
                    got["|r|"][k].append(r.norm(dim=1).numpy())
                cells = []
                for neg, pos in got.values():
                    a = auc(np.concatenate(neg), np.concatenate(pos))
                    cells.append("–" if a is None else f"{a:.2f}")
                print(f"| {c} | {name} | {det.kind} | {size:.3g} | {u} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "scenarios/phm09_chip.toml")
