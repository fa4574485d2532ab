"""The Bayes bound of a simulated target: the reference row or column of the kinds that score
methods on a simulated target (transfer, gap, transfer_benchmark)."""

from __future__ import annotations

import numpy as np

from ..data.cache import load_or_build
from ..data.spec import DatasetSpec
from ..events import Event
from ..learn.bounds import bayes_scores, best_accuracy, detection_at, twin_problem
from ..learn.protocol import Protocol, split

BOUND = "Bayes bound (target's own shapes and noise law, best threshold)"


def bayes_bound(
    target_spec, source, target, protocol: Protocol, executor=None, on_event=lambda e: None, history=None
) -> dict | None:
    """The reference column of the table: the accuracy (%) of the Bayes detector
    (gearlab.learn.bounds) on each (repetition, k)'s target test set, with the best threshold,
    and the faults it finds at 1 % false alarms. None unless the target is simulated with noise
    (the detector needs its noise-free twin); it knows the test labels, so it is a bound, not a
    method. A target whose twin lies outside the detector's model (`twin_problem`) gets
    ``{"label", "unavailable": why}`` instead of a number that methods could beat."""
    if not isinstance(target_spec, DatasetSpec) or target_spec.noise is None:
        return None
    on_event(Event("log", message="the Bayes bound: the target's noise-free twin and its likelihood ratios"))
    clean, _ = load_or_build(target_spec.with_(noise=None), executor, on_event)
    problem = twin_problem(clean)
    if problem is not None:
        on_event(Event("log", message=f"the Bayes bound is unavailable: {problem}"))
        return {"label": BOUND, "unavailable": problem}
    healthy = target.X[target.fault == 0]
    scores = bayes_scores(target.X, healthy, clean, target_spec.noise.kind)
    cells: dict[str, dict[str, dict]] = {"accuracy": {}, "detection_at_1pct": {}}
    for k in protocol.ks:
        acc, det = [], []
        for rep in range(protocol.repetitions):
            test = split(protocol, source, target, rep, k, history).target_test
            y = target.fault[test]
            acc.append(best_accuracy(scores[test], y))
            det.append(detection_at(scores[test], y, 0.01))
        for name, values in (("accuracy", acc), ("detection_at_1pct", det)):
            cells[name][str(k)] = {
                "mean": float(np.mean(values)),
                "std": float(np.std(values, ddof=1)) if len(values) > 1 else 0.0,
                "n": len(values),
            }
    return {"label": BOUND, "noise": target_spec.noise.kind, **cells}
