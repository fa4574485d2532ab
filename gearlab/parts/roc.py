"""The ROC of a detector's scores: the area under it (Mann-Whitney) from the scores of the
negative and positive units. Labels only score what was decided; nothing here fits anything."""

from __future__ import annotations

import numpy as np


def auc(negatives: np.ndarray, positives: np.ndarray) -> float | None:
    """ROC AUC = P(score of a positive > score of a negative), ties counted half (Mann-Whitney).
    None when a side is empty or holds a score that is not a finite number: a NaN compares
    false with everything, so it would read as AUC 0 — the chips ranked last — when the method
    in fact gave no ranking at all (a detector whose scores were NaN read so)."""
    if not len(negatives) or not len(positives):
        return None
    n, p = np.asarray(negatives, dtype=np.float64)[:, None], np.asarray(positives, dtype=np.float64)[None, :]
    if not (np.isfinite(n).all() and np.isfinite(p).all()):
        return None
    return float(np.mean((p > n) + 0.5 * (p == n)))


def roc_curve(negatives: np.ndarray, positives: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(false-alarm rates, detection rates) of calling every score above a threshold, the threshold
    lowered from above the highest score past each distinct score in turn: from (0, 0) to (1, 1).
    Units of equal score are passed together, a diagonal step, so the area under the curve (the
    trapezoid rule) is auc's, ties counted half. None where auc gives none."""
    if auc(negatives, positives) is None:
        return None
    neg, pos = np.asarray(negatives, dtype=np.float64), np.asarray(positives, dtype=np.float64)
    scores = np.concatenate([pos, neg])
    positive = np.concatenate([np.ones(len(pos)), np.zeros(len(neg))])
    order = np.argsort(-scores, kind="stable")
    scores, positive = scores[order], positive[order]
    last = np.r_[np.flatnonzero(np.diff(scores)), len(scores) - 1]  # the last unit of each distinct score
    found = np.cumsum(positive)[last]
    return np.r_[0.0, (last + 1 - found) / len(neg)], np.r_[0.0, found / len(pos)]
