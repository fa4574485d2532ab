"""The Bayes bound of a simulated target: the reference row or column of the kinds that score
methods on a simulated target (transfer, gap, transfer_benchmark)."""

from __future__ import annotations

import numpy as np

from ..data.cache import load_or_build
from ..data.spec import DatasetSpec
from ..events import Event, standing
from ..learn.bounds import bayes_scores, best_accuracy, detection_at, twin_problem
from ..learn.history import history_threshold
from ..learn.protocol import Protocol, split

BOUND = "Bayes bound (target's own shapes and noise law, best threshold)"
PARTS = 10  # the target's revolutions are scored a tenth at a time: steps with counts and an ETA
STEPS = 2 + PARTS  # the noise-free twin, torch, then the tenths


def bayes_bound(
    target_spec,
    source,
    target,
    protocol: Protocol,
    executor=None,
    on_event=lambda e: None,
    history=None,
    on_step=lambda done: None,
) -> dict | None:
    """The reference column of the table: the accuracy (%) of the Bayes detector
    (gearlab.learn.bounds) on each (repetition, k)'s target test set, with the best threshold,
    the faults it finds at 1 % false alarms, and (``accuracy_at_rule``) its accuracy at the unsupervised
    methods' operating point: thresholded by the history rule at the scenario's false-alarm rate on
    its scores of the target training rows, as a detector's threshold is set (the best threshold
    needs the test labels; the part of a method's distance to the bound that is the operating
    point's, not its model's). None unless the target is simulated with noise
    (the detector needs its noise-free twin); it knows the test labels, so it is a bound, not a
    method. A target whose twin lies outside the detector's model (`twin_problem`) gets
    ``{"label", "unavailable": why}`` instead of a number that methods could beat. *on_step(done)*:
    each of its STEPS as it ends (a quick run's bound took 6-12 s at load 8-9 as one step: issue 41)."""
    if not isinstance(target_spec, DatasetSpec) or target_spec.noise is None:
        return None
    on_event(Event("log", message="the Bayes bound: the target's noise-free twin and its likelihood ratios"))
    clean, _ = load_or_build(target_spec.with_(noise=None), executor, on_event)
    on_step(1)
    problem = twin_problem(clean)
    if problem is not None:
        on_event(Event("log", message=f"the Bayes bound is unavailable: {problem}"))
        return {"label": BOUND, "unavailable": problem}
    with standing(on_event, "bound", "loading torch for the likelihood ratios"):
        import torch  # noqa: F401 (the first ratio would load it: 5 s of a quick run's first tenth at load 11)
    on_step(2)
    healthy = target.X[target.fault == 0]
    scores = []
    for i, rows in enumerate(np.array_split(np.arange(len(target.X)), PARTS), start=3):
        # each row's score is its own (its noise scale, its distances): the same numbers as at once
        scores.append(bayes_scores(target.X[rows], healthy, clean, target_spec.noise.kind))
        on_step(i)
    scores = np.concatenate(scores)
    cells: dict[str, dict[str, dict]] = {"accuracy": {}, "detection_at_1pct": {}, "accuracy_at_rule": {}}
    for k in protocol.ks:
        acc, det, at_rule = [], [], []
        for rep in range(protocol.repetitions):
            s = split(protocol, source, target, rep, k, history)
            y = target.fault[s.target_test]
            acc.append(best_accuracy(scores[s.target_test], y))
            det.append(detection_at(scores[s.target_test], y, 0.01))
            # the methods' operating point: a threshold from the training rows' scores alone (no label)
            rule = history_threshold(scores[s.target_train], 1.0 - protocol.calibration.false_alarm)
            at_rule.append(100.0 * float(np.mean((scores[s.target_test] > rule) == (y == 1))))
        for name, values in (("accuracy", acc), ("detection_at_1pct", det), ("accuracy_at_rule", at_rule)):
            cells[name][str(k)] = {
                "mean": float(np.mean(values)),
                "std": float(np.std(values, ddof=1)) if len(values) > 1 else 0.0,
                "n": len(values),
            }
    return {"label": BOUND, "noise": target_spec.noise.kind, **cells}
