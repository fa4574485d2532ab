"""A threshold for a *new* record's units, from a history of a few records.

A detection threshold is applied to the units (revolutions, TSAs) of records that were not in
the history: another take, another day, another assembly of the gearbox. Its false-alarm rate
is therefore set by how much a new record's healthy units vary, and that is more than how
much the units of one history record vary among themselves: each record carries its own
offset (mounting, temperature, load setting, which tacho mark it started on). Pooling the
history's units and taking their quantile ignores that offset and calls too much, or — when
the history's records differ a lot and the pooled law is fitted by its quartiles — nothing.

The standard model for this is the one-way random-effects model (Searle, Casella & McCulloch
1992, ch. 3; the same as a gauge R&R's part-to-part and repeatability terms): the score of
unit j of record r is

    y_rj = mu + a_r + e_rj,    a_r ~ N(0, sigma_a^2) (record effect),  e_rj ~ N(0, sigma_e^2),

estimated by the method of moments (ANOVA): sigma_e^2 the pooled within-record variance,
sigma_a^2 the variance of the record means less what their within-record noise explains,
mu the mean of the record means. A new record's unit is y = mu + a_new + e_new, with mu known
only to within Var(mu_hat) = sum_r (sigma_a^2 + sigma_e^2 / m_r) / R^2, so the threshold that
lets a share alpha of healthy units of a new record through is the predictive quantile

    t = mu_hat + t_(nu, 1 - alpha) * sqrt(sigma_a^2 + sigma_e^2 + Var(mu_hat)),

a Student-t quantile, not the normal one, because the variances are estimated: with R records
sigma_a^2 rests on R - 1 degrees of freedom. The predictive variance is the linear combination
(1 + 1/R) S_b + (1 - mean 1/m_r) sigma_e^2 of the record means' variance S_b (R - 1 degrees of
freedom) and sigma_e^2 (the within-record ones), and nu its Satterthwaite degrees of freedom
(Satterthwaite 1946; Hahn & Meeker, *Statistical Intervals*, ch. 12 for the same interval). With
three records whose effect is twice the unit spread, the normal quantile let 9 % of a new record's
units through where 5 % was asked, the t quantile 6 % (`tests/test_record_effects.py`); with
many records the two agree.

m_r counts the record's *independent* units: sliding TSA windows of b revolutions moved by s
overlap, and only about (n - 1) s / b + 1 of n such windows are independent. For the same
reason their sum of squares about the record's mean has fewer degrees of freedom than n - 1
(``overlap_dof``); sigma_e^2 divides by those, so it is the variance of a unit of a new record.

With two records the record variance rests on one degree of freedom: its t quantile would call
nothing (31.8 at 99 %: on the PHM 2009 rig's history of two builds, an output-shaft tooth's image in
the input TSA went unlocalised), so there the normal quantile is kept — a rough figure, honest about
take-to-take variation where pooling ignores it, but no tolerance bound (give three takes). What a
threshold from two records needs first is history scores that are a new record's: scored against a
reference made with them, two synthetic rig records let 13-28 % of a new take's units through where 1 %
was asked, and the t quantile on those scores left record10's at 12-14 % (detection_classical). With a
single history record sigma_a^2 cannot be estimated and is taken as 0 (``record_sd`` None).
A score that is a *size* above a known floor (NA4, a fourth moment over a history's variance: a take's
mounting gain and noise level multiply it) has a record effect that is a factor, and its spread across
takes is skewed: the model on its own scale understates the upper tail whatever the number of takes.
With three records or more such a score is modelled on log(score − floor) and the threshold taken
back (development generator, 60 boxes, record30, 1 % asked, NA4 raw -> log: with 8 takes 3.1 -> 0.8 %
of a new take's units let through, with 3 takes 1.7 -> 0.8 %). Two records keep the raw scale (the
rough figure above, as before). matched_filter's correlation is a size too, but its level is divided
out by the history's (gearlab.learn.detectors): on the log scale it let 1.1 -> 0.8 % through and
found 22 -> 13 % of the chips, so it is not logged.
A score need not be normal within a record either: likelihood_ratio's log-sum-exp over many shapes (a soft
maximum) is right-skewed even on white noise (1.1-1.6 within a take), and the normal quantile let 1.7-4 % of a
new take's units through where 1 % was asked. Where the method gives its score's own within-record law (*law*,
`WithinLaw`: a detector's scores of TSAs made of a history record's own revolutions drawn again, and of its
revolutions, gearlab.kinds.detection_units.within_laws), sigma_e^2 is that law's variance, which rests on every
revolution of the records rather than on their few independent TSAs, and the quantile is that of sigma_e times
the law's shape plus the normal record and mean parts (`law_quantile`), in place of the normal one; the Student-t
widening is kept as the ratio of its quantile to the normal's. A symmetric law gives the normal quantile back.
(Synthetic rig records, 2 history takes, development seeds: likelihood_ratio's record10 3.5 -> 0.8 %, record30
1.7 -> 0.8 %; matched_filter's, nearly symmetric, 1.2 -> 0.6 % and 0.8 %; the chips found in every unit either way.)
Only the history's scores enter: nothing here sees a test record.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class RecordEffects:
    """The fitted model of a history's scores, and its threshold for a new record's units."""

    mean: float  # mu_hat
    record_sd: float | None  # sigma_a (None: one history record, not estimable)
    unit_sd: float  # sigma_e
    mean_se: float  # sqrt(Var(mu_hat))
    records: int
    threshold: float
    dof: float = float("inf")  # the predictive variance's degrees of freedom (Satterthwaite)
    floor: float | None = None  # a size's floor: the model is of log(score - floor) (module docstring)
    unit_dof: float = float("inf")  # sigma_e^2's degrees of freedom (overlap_dof's, summed over the records)
    tail: float = 1.0  # the within-record law's quantile over the normal one's (`law_quantile`; 1: normal)

    @property
    def predictive_sd(self) -> float:
        return float(np.sqrt((self.record_sd or 0.0) ** 2 + self.unit_sd**2 + self.mean_se**2))

    def standardised(self, scores) -> np.ndarray:
        """Scores in units of the predictive spread of a new healthy record's units, from its mean
        (what makes the scores of differently trained models comparable)."""
        return (logged(scores, self.floor) - self.mean) / max(self.predictive_sd, 1e-300)

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class WithinLaw:
    """A method's scores within a history record, from every revolution of the records (detection_units.within_laws):
    *shape*, a sample of their deviations from their record's mean in units of their sd (mean 0, sd 1); *variance*,
    the within-record variance of a unit's score it estimates, on *dof* degrees of freedom (the records' revolutions,
    less one a record)."""

    shape: np.ndarray
    variance: float
    dof: float


def independent_units(n_units: int, block: int = 1, stride: int = 1) -> float:
    """How many of *n_units* TSA windows of *block* revolutions, moved by *stride*, are
    independent (non-overlapping windows: all of them; a revolution: block = stride = 1)."""
    if n_units <= 0:
        return 0.0
    return min(float(n_units), (n_units - 1) * stride / block + 1.0)


def overlap_dof(n_units: int, block: int = 1, stride: int = 1) -> float:
    """The degrees of freedom of the sum of squares of *n_units* sliding TSA windows of *block*
    revolutions moved by *stride* about their own mean: its expectation in units of one window's
    variance, n − (1/n) Σ_ij ρ_ij with ρ_ij = max(0, 1 − |i − j|·stride/block), the correlation of
    two windows' means of independent revolutions (n − 1 for non-overlapping windows). Dividing
    that sum of squares by n − 1 instead underestimates a window's variance where they overlap:
    by a factor 0.73 for 30 windows of 30 revolutions moved by 3 (a PHM record at 30 Hz), 0.23
    for 6 of them."""
    if n_units <= 0:
        return 0.0
    lag = np.arange(-(n_units - 1), n_units)
    rho = np.maximum(0.0, 1.0 - np.abs(lag) * stride / block)
    pairs = n_units - np.abs(lag)  # how many (i, j) pairs lie at each lag
    return float(n_units - np.sum(rho * pairs) / n_units)


def moments(groups, independent=None, dofs=None) -> tuple[np.ndarray, float, np.ndarray, float | None, float]:
    """(record means, sigma_e^2, independent units per record, the unbiased method-of-moments
    estimate of sigma_a^2 — not truncated at 0; None for one record —, the degrees of freedom of
    sigma_e^2) of *groups*, as `fit` takes them (records without units left out)."""
    groups = [np.asarray(g, dtype=np.float64).ravel() for g in groups]
    keep = [i for i, g in enumerate(groups) if len(g)]
    if not keep:
        raise ValueError("record effects: no history scores")
    groups = [groups[i] for i in keep]
    m = np.asarray(independent if independent is not None else [len(g) for g in groups], dtype=np.float64)
    m = np.maximum(m[: len(groups)], 1.0)
    means = np.array([g.mean() for g in groups])
    dof = sum(len(g) - 1 for g in groups) if dofs is None else float(sum(dofs[i] for i in keep))
    within = sum(float(np.sum((g - g.mean()) ** 2)) for g in groups) / dof if dof > 0 else 0.0
    # E[var(record means)] = sigma_a^2 + mean(sigma_e^2 / m_r)
    record_var = float(means.var(ddof=1)) - float(np.mean(within / m)) if len(groups) >= 2 else None
    return means, within, m, record_var, float(dof)


SIZED_RECORDS = 3  # the fewest history records whose sizes are modelled on the log scale


def logged(scores, floor: float | None) -> np.ndarray:
    """*scores* as the model sees them: log(score - *floor*) for a size (floor not None), else as they are."""
    x = np.asarray(scores, dtype=np.float64)
    return x if floor is None else np.log(np.maximum(x - floor, 1e-300))


def law_quantile(law, p: float, share: float) -> float:
    """The *p* quantile of sqrt(*share*)·E + sqrt(1 − *share*)·Z, E drawn from *law* (a sample of the within-record
    law, mean 0, sd 1) and Z standard normal: a unit's score in units of its predictive sd, *share* of whose variance
    is within-record (the record effect and the mean's error normal, as the model has them)."""
    from scipy.optimize import brentq
    from scipy.stats import norm

    e = np.sqrt(share) * np.asarray(law, dtype=np.float64)
    rest = max(np.sqrt(max(1.0 - share, 0.0)), 1e-9)
    return float(brentq(lambda z: float(np.mean(norm.cdf((z - e) / rest))) - p, e.min() - 40.0, e.max() + 40.0))


def fit(groups, p: float, independent=None, dofs=None, floor: float | None = None, law=None) -> RecordEffects:
    """The model of *groups* (one array of unit scores per history record, in any order) and
    its *p* predictive quantile for a unit of a new record (Student-t, `predictive_dof`);
    *independent*: each record's number of independent units (default: its number of units);
    *dofs*: each record's degrees of freedom of its within-record sum of squares (default n − 1;
    sliding windows: overlap_dof); *floor*: the scores are sizes above it, modelled on the log scale
    with SIZED_RECORDS records or more; *law*: the scores' own within-record law (WithinLaw; not for sizes), whose
    variance is sigma_e^2 and whose shape sets the quantile (module docstring)."""
    if floor is not None and sum(1 for g in groups if np.size(g)) < SIZED_RECORDS:
        floor = None
    groups = [logged(g, floor) for g in groups]
    means, within, m, estimate, within_dof = moments(groups, independent, dofs)
    if law is not None:  # sigma_e^2 from every revolution of the records, not from their few independent TSAs
        within, within_dof = law.variance, law.dof
        estimate = None if estimate is None else float(means.var(ddof=1)) - float(np.mean(within / m))
    R = len(means)
    record_var = max(0.0, estimate) if estimate is not None else 0.0
    if estimate is not None and estimate <= 0.0 and R >= SIZED_RECORDS and within_dof < R - 1:
        # no take-to-take effect, and a take's units overlap so much that their own spread rests on fewer degrees of
        # freedom than the takes' means (three 35-turn takes of a 65T output shaft: 2 record30 windows each, 0.3 in
        # all; its t quantile put fm4's threshold at 43672 over a history at 3.0 +- 0.27, NA4's past exp's range):
        # with sigma_a = 0 each mean lies sigma_e / sqrt(m_r) about mu, so the means estimate sigma_e^2 too (the
        # one-way model's total sum of squares), on R - 1 more degrees of freedom
        between = float(np.sum(m * (means - means.mean()) ** 2))
        within, within_dof = (within * within_dof + between) / (within_dof + R - 1), within_dof + R - 1
    mean_var = float(np.sum(record_var + within / m)) / R**2
    sd = np.sqrt(record_var + within + mean_var)
    # two records: sigma_a^2 on one degree of freedom, whose t quantile (31.8 at 99 %, 13.6 times the
    # normal one) calls nothing: there the normal quantile is kept, a rough figure (module docstring)
    nu = predictive_dof(means, within, m, within_dof, record_var > 0) if R != 2 else float("inf")
    from scipy.stats import norm
    from scipy.stats import t as student  # here, not at the top: start-up time (scipy.stats takes ~1 s)

    share = (within / sd**2) if sd > 0 else 1.0
    tail = 1.0 if law is None or len(law.shape) < 2 else law_quantile(law.shape, p, float(share)) / float(norm.ppf(p))
    threshold = float(means.mean() + student.ppf(p, nu) * sd * tail)
    return RecordEffects(
        mean=float(means.mean()),
        record_sd=None if estimate is None else float(np.sqrt(record_var)),
        unit_sd=float(np.sqrt(within)),
        mean_se=float(np.sqrt(mean_var)),
        records=R,
        threshold=threshold if floor is None else floor + float(np.exp(threshold)),
        dof=nu,
        floor=floor,
        unit_dof=within_dof,
        tail=tail,
    )


def predictive_dof(means: np.ndarray, within: float, m: np.ndarray, within_dof: float, estimated: bool) -> float:
    """Satterthwaite's degrees of freedom of the predictive variance sigma_a^2 + sigma_e^2 + Var(mu_hat).
    With sigma_a^2 *estimated* (above 0) it is (1 + 1/R) S_b + (1 - mean 1/m_r) sigma_e^2, S_b the
    variance of the R record *means* (R - 1 degrees of freedom) and sigma_e^2 = *within* (*within_dof*);
    else sigma_e^2 (1 + mean(1/m_r) / R), of sigma_e^2's degrees of freedom (inf where none: the
    normal quantile)."""
    R = len(means)
    if estimated:
        parts = [
            ((1.0 + 1.0 / R) * float(means.var(ddof=1)), R - 1.0),
            (within * (1.0 - float(np.mean(1.0 / m))), within_dof),
        ]
    else:
        parts = [(within * (1.0 + float(np.mean(1.0 / m)) / R), within_dof)]
    total = sum(v for v, _ in parts)
    spread = sum(v**2 / d for v, d in parts if d > 0)
    return float(total**2 / spread) if spread > 0 else float("inf")
