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
