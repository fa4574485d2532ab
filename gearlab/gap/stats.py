"""Where the gap lies and how large it is: discrepancies between source and target healthy sets.

Per-feature effect size. For a feature f with source and target means μ_s, μ_t and
standard deviations s_s, s_t over the rows,

    d_f = (μ_t − μ_s) / s_f,        s_f = √((s_s² + s_t²) / 2)   (pooled, floored)

is the target's shift in units of the rows' own spread (Cohen's d): "the mesh 3x band is
4 dB higher, 6 standard deviations of its revolution-to-revolution scatter".

Per-view gap. A view's gap is the squared standardised distance between the two means,

    G_v = Σ_{f ∈ v} (d_f² − c),     c = 1/n_s + 1/n_t,   clipped at 0,

a diagonal Mahalanobis distance (features treated as independent). c removes the bias of
d_f²: with no shift, the sampling noise of the two means alone makes E[d_f²] ≈ c, so a view
of 300 features would otherwise collect a "gap" of 300·c from nothing. Why this measure and
not an energy distance or MMD per view:

* it decomposes exactly: the total G = Σ_v G_v, and each view's G_v is a sum over its
  features, so "share of the total" and "which band / sector / statistic" are the same
  numbers read at two levels — an MMD of a view has no per-feature breakdown, and MMDs
  of different views (different kernels, bandwidths and dimensions) do not add up;
* it is in interpretable units (standard deviations of the healthy scatter), free of each
  feature's unit (dB, m/s², kurtosis);
* its bootstrap is a few matrix products (means and second moments of resampled rows).

What it does not see: changes of spread or shape with equal means, and differences that
live only in the correlations between features. The two-sample tests below, on all
features at once, do see them; the per-feature spread ratio s_t/s_s is reported beside d.
Correlated features (25 tooth sectors all shifted by extra broadband noise) each count,
so a broad change weighs more than a narrow one — which is what "where" should say.

Shares and bootstrap. share_v = G_v / G. Intervals resample the rows of each set with
replacement (jointly for all views, so the views' covariance is kept), B times (default
200), seeded, as multinomial counts so every replicate is a matrix product. Replicates'
d² are centred on the estimate (resampling adds its own c on top of the sampling bias,
so a replicate subtracts 2c); intervals are percentiles.

Two-sample tests on all features (each standardised by its pooled mean and spread, which
ignores the set labels so that permutations stay valid):

* classifier two-sample test: the cross-validated (stratified 5-fold) AUC of an
  L1-regularised logistic regression telling target rows from source rows — 0.5 when
  the sets cannot be told apart, 1.0 when every row can (an effect size; the decision is
  the MMD test's);
* MMD² (unbiased) with a Gaussian kernel exp(−‖x − y‖² / 2h²), h the median distance
  between rows (the median heuristic), and a permutation p-value (labels permuted P times,
  default 1000, seeded; all permutations in one matrix product with the kernel matrix).
  "significant" = p < alpha. The permutation test is exact when the rows of both sets are
  exchangeable under "no gap"; two features are computed with the source's help (the
  residual against the source's TSA, the latent PCA basis), which makes it approximate to
  O(1/n) (the tests check the false-positive rate).

Inputs: both sets (n, P) healthy revolutions, at least MIN_REVOLUTIONS rows each, the same
P, and P/2 above the first mesh order plus its sidebands. Everything is in
:func:`gap_report`, which returns a JSON-serialisable dict.
"""

from __future__ import annotations

import importlib
import math
import numbers
import sys
from collections.abc import Callable

import numpy as np

from ..errors import GearlabInputError
from .structure_later import wheel_shaft
from .views import (
    BandPlan,
    View,
    check_revolutions,
    gear_ratio,
    latent_views,
    output_shaft_view,
    row_views,
)

MIN_REVOLUTIONS = 10  # per set: below this a standard deviation, an AUC and a p-value mean little
SD_FLOOR = 1e-6  # relative: spreads below 1e-6 of a feature's magnitude count as "no spread"


# --- input checks --------------------------------------------------------------------------------


def _check_set(X, which: str) -> np.ndarray:
    arr = np.asarray(X)
    if arr.size == 0:  # e.g. (0, P): a dataset's healthy selection came back empty
        raise GearlabInputError(f"no healthy {which} data: the gap is measured between healthy revolutions (label 0)")
    arr = check_revolutions(arr, f"{which} revolutions")
    if len(arr) < MIN_REVOLUTIONS:
        raise GearlabInputError(
            f"too few healthy {which} revolutions for the gap statistics: {len(arr)}; "
            f"expected at least {MIN_REVOLUTIONS} per set"
        )
    return arr


def check_sets(source_X, target_X) -> tuple[np.ndarray, np.ndarray]:
    """Both sets as float64 (n, P): non-empty, finite, >= MIN_REVOLUTIONS rows, the same P."""
    xs, xt = _check_set(source_X, "source"), _check_set(target_X, "target")
    if xs.shape[1] != xt.shape[1]:
        raise GearlabInputError(
            f"sample length mismatch: source revolutions have {xs.shape[1]} samples, target revolutions "
            f"{xt.shape[1]}; expected the same points per revolution (resample both in the angle domain)"
        )
    return xs, xt


def _check_count(value, name: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise GearlabInputError(f"gap statistics: {name} must be a whole number >= {minimum}, got {value!r}")
    return int(value)


def _check_fraction(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0.0 < value < 1.0:
        raise GearlabInputError(f"gap statistics: {name} must lie strictly between 0 and 1, got {value!r}")
    return float(value)


# --- per-feature effect sizes and per-view gaps ------------------------------------------------


def effect_sizes(source: np.ndarray, target: np.ndarray) -> dict[str, np.ndarray]:
    """Per feature (columns): both means, both standard deviations (ddof 1), the pooled,
    floored spread and the signed effect size d = (μ_t − μ_s) / spread."""
    ms, mt = source.mean(axis=0), target.mean(axis=0)
    ss, st = source.std(axis=0, ddof=1), target.std(axis=0, ddof=1)
    spread = np.maximum(np.sqrt((ss**2 + st**2) / 2.0), _floor(ms, mt))
    return {
        "source_mean": ms,
        "target_mean": mt,
        "source_sd": ss,
        "target_sd": st,
        "spread": spread,
        "d": (mt - ms) / spread,
    }


def _floor(ms: np.ndarray, mt: np.ndarray) -> np.ndarray:
    # Two noise-free (identical-row) sets have no spread at all; differences are then
    # measured against a numerical floor, so they stay finite (and huge, as they should).
    return SD_FLOOR * np.maximum(1.0, np.maximum(np.abs(ms), np.abs(mt)))


def _membership(sizes: list[int]) -> np.ndarray:
    """A 0/1 matrix (features x views): one matrix product sums per-feature terms per view."""
    member = np.zeros((sum(sizes), len(sizes)))
    start = 0
    for v, size in enumerate(sizes):
        member[start : start + size, v] = 1.0
        start += size
    return member


def view_gaps(d: np.ndarray, sizes: list[int], n_source: int, n_target: int) -> np.ndarray:
    """G_v = max(0, Σ_{f ∈ v} (d_f² − c)) for the views of *sizes* consecutive columns; *d* may
    carry leading axes (bootstrap replicates)."""
    c = 1.0 / n_source + 1.0 / n_target
    return np.maximum((d * d - c) @ _membership(sizes), 0.0)


def resampled_moments(
    rows: np.ndarray, centre: np.ndarray, scale: np.ndarray, replicates: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Bootstrap replicates (replicates, features) of the mean and variance of *rows* centred on
    *centre* and divided by *scale*. Each replicate is a vector of counts (how often each row is
    drawn, multinomial), so all replicates are two matrix products; centring and scaling first
    keeps the moments from losing precision to large offsets (dB levels, m/s²)."""
    z = (rows - centre) / scale
    n = len(z)
    counts = rng.multinomial(n, np.full(n, 1.0 / n), size=replicates).astype(np.float64)
    mean = counts @ z / n
    var = np.maximum(counts @ (z * z) / n - mean * mean, 0.0) * (n / (n - 1))
    return mean, var


def bootstrap_gaps(
    source: np.ndarray, target: np.ndarray, sizes: list[int], replicates: int, rng: np.random.Generator
) -> np.ndarray:
    """(replicates, views) bootstrap replicates of the view gaps, rows of each set resampled
    (see resampled_moments); features centred on the source mean and scaled by their spread."""
    ns, nt = len(source), len(target)
    base = effect_sizes(source, target)
    centre, scale = base["source_mean"], base["spread"]
    floor = _floor(base["source_mean"], base["target_mean"]) / scale
    ms, vs = resampled_moments(source, centre, scale, replicates, rng)
    mt, vt = resampled_moments(target, centre, scale, replicates, rng)
    d = (mt - ms) / np.maximum(np.sqrt((vs + vt) / 2.0), floor)
    # A replicate's d² is inflated by the sampling noise c twice (the data's and the
    # resampling's); removing one more c centres the replicates on the estimate.
    c = 1.0 / ns + 1.0 / nt
    return np.maximum((d * d - 2.0 * c) @ _membership(sizes), 0.0)


# --- two-sample tests ---------------------------------------------------------------------------------


def _pooled_standardised(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Both sets stacked, each feature scaled by its mean and spread over all rows (label-free)."""
    Z = np.concatenate([source, target])
    sd = Z.std(axis=0)
    return (Z - Z.mean(axis=0)) / np.where(sd > 0, sd, 1.0)


def _sklearn_at_least(major: int, minor: int) -> bool:
    import sklearn

    parts = sklearn.__version__.split(".")
    return (int(parts[0]), int("".join(ch for ch in parts[1] if ch.isdigit()) or 0)) >= (major, minor)


CLASSIFIER_MODULES = (
    "sklearn.linear_model",
    "sklearn.metrics",
    "sklearn.model_selection",
    "sklearn.pipeline",
    "sklearn.preprocessing",
)


def classifier_loaded() -> bool:
    """Whether :func:`classifier_auc`'s scikit-learn is imported: its import takes 2.5-4.2 s on a busy
    machine, which a caller with a progress line does first under a line of its own (load_classifier)."""
    return all(name in sys.modules for name in CLASSIFIER_MODULES)


def load_classifier() -> None:
    for name in CLASSIFIER_MODULES:
        importlib.import_module(name)


def classifier_auc(source: np.ndarray, target: np.ndarray, seed: int = 0, folds: int = 5) -> float:
    """Classifier two-sample test: cross-validated ROC AUC of a logistic regression telling
    target rows (1) from source rows (0); 0.5 = indistinguishable.

    Stratified folds (shuffled, seeded) keep both sets' proportions in every training set:
    unbalanced folds would let the classifier learn the fold's class ratio and push the AUC
    of identical sets below 0.5. Features are standardised inside each fold. The penalty is
    L1 (lasso, C = 0.1): a gap usually sits in a few of the few hundred features (one band,
    a few sectors), and an L2 fit spreads its weight over all the others' noise — on 40 + 40
    rows a tone 27 dB down in one band reads AUC 0.87 with L2 and 1.00 with L1, while sets
    with no gap read ≈ 0.5 either way.
    """
    from sklearn.linear_model import LogisticRegression
    from sklearn.metrics import roc_auc_score
    from sklearn.model_selection import StratifiedKFold, cross_val_predict
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    X = np.concatenate([source, target])
    y = np.r_[np.zeros(len(source)), np.ones(len(target))]
    folds = min(folds, len(source), len(target))
    # liblinear: L1 at a few milliseconds per fit; it penalises the intercept too, which
    # moves no ranking. scikit-learn 1.8 replaced penalty="l1" by l1_ratio=1.
    lasso = {"l1_ratio": 1.0} if _sklearn_at_least(1, 8) else {"penalty": "l1"}
    model = make_pipeline(StandardScaler(), LogisticRegression(C=0.1, solver="liblinear", random_state=seed, **lasso))
    cv = StratifiedKFold(folds, shuffle=True, random_state=seed)
    scores = cross_val_predict(model, X, y, cv=cv, method="decision_function")
    return float(roc_auc_score(y, scores))


def mmd_test(source: np.ndarray, target: np.ndarray, permutations: int = 1000, seed: int = 0) -> dict[str, float]:
    """Unbiased MMD² with a Gaussian kernel (median heuristic) and its permutation p-value.

    With K the kernel matrix of all rows (zero diagonal: the unbiased estimate leaves out
    k(x, x)) and a 0/1 vector s marking the source rows, the within-source sum is sᵀKs, the
    cross sum sᵀK1 − sᵀKs and the within-target sum 1ᵀK1 − 2·cross − within-source. Stacking
    the observed s and every permuted s as the columns of S, one product K·S gives all of
    them. p = (1 + #{permuted ≥ observed}) / (1 + permutations).
    """
    Z = _pooled_standardised(source, target)
    ns, nt = len(source), len(target)
    sq = np.sum(Z * Z, axis=1)
    dist2 = np.maximum(sq[:, None] + sq[None, :] - 2.0 * Z @ Z.T, 0.0)
    off = dist2[np.triu_indices(len(Z), k=1)]
    h2 = float(np.median(off))
    if h2 <= 0.0:  # more than half the pairs identical: any positive bandwidth will do
        h2 = float(off.max()) if off.max() > 0 else 1.0
    K = np.exp(-dist2 / (2.0 * h2))
    np.fill_diagonal(K, 0.0)

    rng = np.random.default_rng(seed)
    labels = np.r_[np.ones(ns), np.zeros(nt)]
    S = np.column_stack([labels, rng.permuted(np.tile(labels, (permutations, 1)), axis=1).T])
    within_s = np.sum(S * (K @ S), axis=0)
    cross = S.T @ K.sum(axis=1) - within_s
    within_t = K.sum() - 2.0 * cross - within_s
    mmd2 = within_s / (ns * (ns - 1)) + within_t / (nt * (nt - 1)) - 2.0 * cross / (ns * nt)
    # Float rounding must not split a permutation that equals the observed labelling.
    tol = 1e-12 * max(1.0, float(np.abs(mmd2).max()))
    p = (1.0 + np.count_nonzero(mmd2[1:] >= mmd2[0] - tol)) / (1.0 + permutations)
    return {"mmd2": float(mmd2[0]), "p_value": float(p), "bandwidth": math.sqrt(h2)}


# --- the report -------------------------------------------------------------------------------------


def _interval(samples: np.ndarray, confidence: float) -> list[float] | None:
    samples = samples[np.isfinite(samples)]
    if samples.size == 0:
        return None
    tail = 50.0 * (1.0 - confidence)
    lo, hi = np.percentile(samples, [tail, 100.0 - tail])
    return [float(lo), float(hi)]


def _feature_rows(views: list[str], names: list[str], stats: dict, index) -> list[dict]:
    """The report's line for each feature in *index* (columns of the concatenated views)."""
    rows = []
    for i in index:
        sd = stats["source_sd"][i]
        rows.append(
            {
                "view": views[i],
                "feature": names[i],
                "source_mean": float(stats["source_mean"][i]),
                "target_mean": float(stats["target_mean"][i]),
                "delta": float(stats["target_mean"][i] - stats["source_mean"][i]),
                "effect": float(stats["d"][i]),
                "sd_ratio": float(stats["target_sd"][i] / sd) if sd > 0 else None,  # None: no source spread
            }
        )
    return rows


def compare_views(
    source: list[View], target: list[View], bootstrap: int = 200, seed: int = 0, confidence: float = 0.95, top: int = 5
) -> dict:
    """Per-view gap, RMS effect, share and bootstrap intervals, and the total, for matching
    lists of views of the source and target rows (see the module docstring)."""
    sizes = [v.size for v in source]
    Fs = np.concatenate([v.features for v in source], axis=1)
    Ft = np.concatenate([v.features for v in target], axis=1)
    owner = [v.name for v in source for _ in v.names]  # the view of every column
    names = [name for v in source for name in v.names]
    stats = effect_sizes(Fs, Ft)
    gaps = view_gaps(stats["d"], sizes, len(Fs), len(Ft))
    total = float(gaps.sum())
    shares = gaps / total if total > 0 else np.zeros_like(gaps)
    if bootstrap:
        reps = bootstrap_gaps(Fs, Ft, sizes, bootstrap, np.random.default_rng([seed, 1]))
        rep_total = reps.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            rep_shares = reps / rep_total[:, None]  # NaN where a replicate has no gap at all
    views = {}
    start = 0
    for v, view in enumerate(source):
        columns = np.arange(start, start + view.size)
        d = stats["d"][columns]
        views[view.name] = {
            "features": view.size,
            "unit": view.unit,
            "gap": float(gaps[v]),
            "rms_effect": math.sqrt(gaps[v] / view.size),
            "share": float(shares[v]),
            "gap_interval": _interval(reps[:, v], confidence) if bootstrap else None,
            "share_interval": _interval(rep_shares[:, v], confidence) if bootstrap else None,
            "top": _feature_rows(owner, names, stats, columns[np.argsort(-np.abs(d))[:top]]),
            "names": list(view.names),
            "effect": [float(x) for x in d],
        }
        start += view.size
    return {
        "views": views,
        "total": {
            "gap": total,
            "interval": _interval(rep_total, confidence) if bootstrap else None,
            "features": int(sum(sizes)),
        },
        "top_features": _feature_rows(owner, names, stats, np.argsort(-np.abs(stats["d"]))[: 2 * top]),
    }


REPORT_PARTS = 4  # gap_report's parts, each told by its on_part


def gap_report(
    source_X,
    target_X,
    pair,
    embed: Callable | None = None,
    seed: int = 0,
    bootstrap: int = 200,
    permutations: int = 1000,
    alpha: float = 0.05,
    confidence: float = 0.95,
    top: int = 5,
    consecutive: bool = False,
    max_order: int = 0,
    on_part: Callable[[], None] = lambda: None,
) -> dict:
    """Where source and target healthy revolutions differ, and how strongly: a JSON-serialisable dict.

    *source_X*, *target_X*: healthy revolutions (n, P), one input-shaft revolution per row,
    in the same units (see :func:`gearlab.gap.views.healthy_rows`). *pair*: the gear pair
    (GearPair, (Z1, Z2) or preset name). *embed*: optional ``embed(X) -> (n, d)``, the
    latent features of a network trained on the source. *consecutive*: the rows of each set
    are consecutive revolutions of one record, so the output-shaft orders can be resolved
    (reported beside the views, outside the shares: they have one row per block of
    revolutions). *max_order*: the highest shaft order the sets hold (a measured record's
    passband; 0: P/2): the order bands end there (gearlab.gap.views.BandPlan, ``highest``).
    *on_part*: called as each of its REPORT_PARTS parts ends (the views, the effect sizes and their
    bootstrap, the classifier AUC, the permutation test), for a progress bar.

    Returns ``views`` (per view: gap, rms_effect, share, their intervals, top features, every
    feature's effect), ``total``, ``top_features``, ``auc``, ``mmd2``, ``p_value``,
    ``significant`` (p < alpha), the band layout and ``notes``.
    """
    Xs, Xt = check_sets(source_X, target_X)
    bootstrap = _check_count(bootstrap, "bootstrap", 0)
    permutations = _check_count(permutations, "permutations", 1)
    top = _check_count(top, "top", 1)
    alpha = _check_fraction(alpha, "alpha")
    confidence = _check_fraction(confidence, "confidence")
    z1, z2 = gear_ratio(pair)
    plan = BandPlan.make(Xs.shape[1], (z1, z2), highest=max_order)
    notes = []

    # The target's residual is taken against the source's TSA: "how the target deviates from
    # the simulator's synchronous average"; the source's own against its leave-one-out mean.
    source_views = row_views(Xs, (z1, z2), plan)
    target_views = row_views(Xt, (z1, z2), plan, reference=Xs.mean(axis=0))
    if embed is not None:
        latent_s, latent_t = latent_views(Xs, Xt, embed, seed=seed)
        source_views.append(latent_s)
        target_views.append(latent_t)
    kept = [i for i, v in enumerate(source_views) if v.size > 0]
    source_views = [source_views[i] for i in kept]
    target_views = [target_views[i] for i in kept]

    on_part()
    report = {"n_source": len(Xs), "n_target": len(Xt), "bands": plan.describe()}
    report.update(compare_views(source_views, target_views, bootstrap, seed, confidence, top))
    on_part()

    Fs = np.concatenate([v.features for v in source_views], axis=1)
    Ft = np.concatenate([v.features for v in target_views], axis=1)
    report["auc"] = classifier_auc(Fs, Ft, seed)
    on_part()
    report.update(mmd_test(Fs, Ft, permutations, seed))
    on_part()
    report.update(
        alpha=alpha,
        significant=bool(report["p_value"] < alpha),
        bootstrap=bootstrap,
        permutations=permutations,
        confidence=confidence,
        seed=seed,
    )
    if permutations < math.ceil(1.0 / alpha) - 1:
        notes.append(f"{permutations} permutations cannot give p < {alpha}; use at least {math.ceil(1 / alpha) - 1}")

    shaft = wheel_shaft(pair)
    if consecutive:
        report["output_shaft"] = _output_shaft(Xs, Xt, (z1, z2), plan, bootstrap, seed, confidence, top, notes, shaft)
    else:
        notes.append(
            f"orders of the {shaft} are not resolved: each row is one input "
            "revolution, so their lines leak into the neighbouring integer orders (shaft and "
            "non-synchronous bands)"
        )
    report["constant_sets"] = [which for which, X in (("source", Xs), ("target", Xt)) if np.all(X == X[0])]
    for which, X in (("source", Xs), ("target", Xt)):
        if np.all(X == X[0]):
            notes.append(
                f"the {which} revolutions are all identical (no noise): effect sizes are measured "
                "against the other set's spread or a numerical floor; add the sensor noise the other "
                "set has for meaningful sizes"
            )
    if not report["significant"]:
        notes.append(f"no significant gap (p = {report['p_value']:.3g} >= {alpha}): the shares describe sampling noise")
    report["notes"] = notes
    return report


def _output_shaft(Xs, Xt, pair, plan, bootstrap, seed, confidence, top, notes, shaft: str) -> dict | None:
    """The output-shaft view's entry (*shaft*: wheel_shaft's words), or None with a note where too few blocks."""
    z1, z2 = pair
    per_block = z2 // math.gcd(z1, z2)
    blocks = min(len(Xs), len(Xt)) // per_block
    if blocks < MIN_REVOLUTIONS:
        notes.append(
            f"orders of the {shaft} need {MIN_REVOLUTIONS} blocks of {per_block} consecutive revolutions "
            f"per set ({MIN_REVOLUTIONS * per_block} revolutions); got {blocks} blocks (the source's {len(Xs)}: "
            f"[diagnosis] healthy; the target's {len(Xt)}: its records together)"
        )
        return None
    vs, vt = output_shaft_view(Xs, pair, plan), output_shaft_view(Xt, pair, plan)
    out = compare_views([vs], [vt], bootstrap, seed, confidence, top)
    entry = out["views"]["output_shaft"]
    entry.pop("share"), entry.pop("share_interval")  # its rows are blocks: it stays out of the shares
    entry["blocks"] = [len(vs.features), len(vt.features)]
    entry["revolutions_per_block"], entry["shaft"] = per_block, shaft
    return entry
