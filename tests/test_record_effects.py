"""The threshold for a new record's units: one-way random effects (record effect + within-record
spread) against the pooled quantile, on scores drawn from a known model."""

import numpy as np
import pytest
from scipy.stats import norm, t

from gearlab.kinds.record_effects import WithinLaw, fit, independent_units, law_quantile, moments, overlap_dof


def records(rng, n_records: int, n_units: int, record_sd: float, unit_sd: float, mean: float = 5.0) -> list:
    return [mean + record_sd * rng.standard_normal() + unit_sd * rng.standard_normal(n_units) for _ in range(n_records)]


def test_the_variance_components_are_recovered():
    rng = np.random.default_rng(1)
    m = fit(records(rng, 400, 50, record_sd=2.0, unit_sd=0.5), 0.99)
    assert m.record_sd == pytest.approx(2.0, rel=0.1)
    assert m.unit_sd == pytest.approx(0.5, rel=0.02)
    assert m.mean == pytest.approx(5.0, abs=0.3)
    assert m.records == 400
    # the threshold is the predictive quantile: mean + t sqrt(record² + unit² + se²), t of the
    # predictive variance's Satterthwaite degrees of freedom (here, many records: near the normal one)
    assert m.threshold == pytest.approx(m.mean + t.ppf(0.99, m.dof) * m.predictive_sd)
    assert 399 < m.dof < 600 and t.ppf(0.99, m.dof) == pytest.approx(norm.ppf(0.99), rel=0.01)
    assert m.predictive_sd == pytest.approx(np.hypot(2.0, 0.5), rel=0.1)


def test_a_new_records_false_alarms_are_as_asked_where_the_units_own_spread_is_not():
    """Histories of 8 records, each 100 units, whose record effect is twice the unit spread: a
    new record's healthy units exceed the random-effects threshold about as often as asked (5 %);
    a threshold from the units' spread about their record's mean (the record effect ignored, as
    when one take's units stand for every take) is exceeded several times as often."""
    rng = np.random.default_rng(7)
    ours, within = [], []
    for _ in range(300):
        history = records(rng, 8, 100, record_sd=1.0, unit_sd=0.5)
        new = records(rng, 1, 100, record_sd=1.0, unit_sd=0.5)[0]
        m = fit(history, 0.95)
        ours.append(np.mean(new > m.threshold))
        within.append(np.mean(new > m.mean + norm.ppf(0.95) * m.unit_sd))
    assert 0.03 < np.mean(ours) < 0.09
    assert np.mean(within) > 3 * np.mean(ours)


def test_three_records_false_alarms_are_as_asked_the_normal_quantile_let_through_half_as_many_again():
    """Issue 39: histories of three takes, whose take effect is twice the unit spread, estimate it on
    two degrees of freedom; the predictive quantile is Student-t's of the predictive variance's
    Satterthwaite degrees of freedom. A new take's healthy units exceed it about as often as asked
    (5 %); the normal quantile of the same variances let 9.1 % through (before the t quantile)."""
    rng = np.random.default_rng(11)
    fa, models = [], []
    for _ in range(2000):
        history = records(rng, 3, 40, record_sd=1.0, unit_sd=0.5)
        new = records(rng, 1, 40, record_sd=1.0, unit_sd=0.5)[0]
        models.append(fit(history, 0.95))
        fa.append(np.mean(new > models[-1].threshold))
    assert 0.04 < np.mean(fa) < 0.07, np.mean(fa)
    # the means' two degrees of freedom, and some of the within-record part's
    assert 2.0 <= np.median([m.dof for m in models]) < 4.0


def test_two_records_keep_the_normal_quantile_of_their_variances():
    """sigma_a^2 of two records rests on one degree of freedom, whose t quantile (31.8 at 99 %) would
    call nothing: the normal quantile of the same variances (a rough figure)."""
    m = fit([np.array([1.0, 1.2, 0.8]), np.array([3.0, 3.3, 2.7])], 0.99)
    assert m.dof == np.inf and m.threshold == pytest.approx(m.mean + norm.ppf(0.99) * m.predictive_sd)


def test_no_record_effect_gives_the_within_record_quantile():
    rng = np.random.default_rng(3)
    history = [rng.standard_normal(2000) for _ in range(5)]  # records differ only by chance
    m = fit(history, 0.99)
    assert m.record_sd == pytest.approx(0.0, abs=0.03)
    assert m.threshold == pytest.approx(norm.ppf(0.99), abs=0.1)


def test_one_record_cannot_tell_its_record_effect():
    rng = np.random.default_rng(4)
    g = rng.standard_normal(400)
    m = fit([g], 0.99)
    assert m.record_sd is None and m.records == 1
    sd = g.std(ddof=1)
    assert m.dof == 399  # the within-record variance's
    assert m.threshold == pytest.approx(g.mean() + t.ppf(0.99, 399) * sd * np.sqrt(1 + 1 / 400))


def test_overlapping_windows_count_as_fewer_independent_units():
    assert independent_units(110, block=10, stride=1) == pytest.approx(11.9)
    assert independent_units(30, block=30, stride=3) == pytest.approx(3.9)
    assert independent_units(119) == 119  # revolutions
    assert independent_units(4, block=10, stride=10) == 4
    # fewer independent units: more of the record means' spread is left to the within-record
    # noise, less to the record effect
    rng = np.random.default_rng(5)
    history = records(rng, 3, 50, record_sd=0.3, unit_sd=1.0)
    assert fit(history, 0.99, [5, 5, 5]).record_sd < fit(history, 0.99).record_sd


def test_standardised_scores_are_in_units_of_the_predictive_spread():
    m = fit([np.array([1.0, 2.0, 3.0]), np.array([3.0, 4.0, 5.0])], 0.99)
    assert m.standardised([m.mean, m.mean + m.predictive_sd]) == pytest.approx([0.0, 1.0])


def test_overlapping_windows_sum_of_squares_has_fewer_degrees_of_freedom():
    """Sliding TSA windows share revolutions, so their spread about their record's mean is narrower
    than a new record's unit varies: their sum of squares has overlap_dof degrees of freedom, not
    n − 1 (30 windows of 30 revolutions moved by 3, as a PHM record at 30 Hz gives: 21.1, not 29)."""
    assert overlap_dof(4, 10, 10) == 3.0 and overlap_dof(5) == 4.0  # no overlap: n − 1
    assert overlap_dof(30, 30, 3) == pytest.approx(21.1, abs=0.05)
    rng = np.random.default_rng(6)
    n, block, stride = 45, 30, 3
    ss = []
    for _ in range(4000):
        revs = rng.standard_normal(n)
        windows = np.array([revs[s : s + block].mean() for s in range(0, n - block + 1, stride)])
        ss.append(np.sum((windows - windows.mean()) ** 2))
    m = len(windows)
    # the variance of one window's mean of independent revolutions is 1/block
    assert np.mean(ss) / overlap_dof(m, block, stride) == pytest.approx(1 / block, rel=0.05)
    assert np.mean(ss) / (m - 1) < 0.3 / block  # n − 1 would call it less than a third of that


def test_a_size_whose_take_effect_is_a_factor_is_modelled_on_the_log_scale():
    """Issue 39: NA4's take effect is a factor (a take's gain and noise level multiply it), so its spread
    over takes is skewed. Histories of 8 takes of a size exp(a + e) (take effect twice the unit spread):
    the model on the raw scale let 5.2 % of a new take's units through where 1 % was asked, on
    log(score - floor) 1.3 %. Two takes keep the raw scale (the figures of before)."""
    rng = np.random.default_rng(5)
    raw, logged = [], []
    for _ in range(1000):
        history = [np.exp(x) for x in records(rng, 8, 40, record_sd=1.0, unit_sd=0.5, mean=0.0)]
        new = np.exp(records(rng, 1, 40, record_sd=1.0, unit_sd=0.5, mean=0.0)[0])
        raw.append(np.mean(new > fit(history, 0.99).threshold))
        logged.append(np.mean(new > fit(history, 0.99, floor=0.0).threshold))
    assert np.mean(raw) > 0.02, np.mean(raw)
    assert 0.005 < np.mean(logged) < 0.015, np.mean(logged)
    two = [np.exp(x) for x in records(rng, 2, 40, record_sd=1.0, unit_sd=0.5, mean=0.0)]
    assert fit(two, 0.99, floor=0.0) == fit(two, 0.99)
    m = fit([h + 3.0 for h in history], 0.99, floor=3.0)  # a floor other than 0: the same model, shifted
    assert m.floor == 3.0 and m.threshold == pytest.approx(3.0 + fit(history, 0.99, floor=0.0).threshold)
    assert m.standardised([m.threshold]) == pytest.approx([t.ppf(0.99, m.dof)])


def soft_maxima(rng, n: int) -> np.ndarray:
    """A log mean exp of 32 log-likelihood ratios d z - d^2 / 2 (d = 2.5) on noise: likelihood_ratio's score's
    form, skewed to the right (0.76; its 99 % quantile 2.93 sd above its mean, not 2.33)."""
    return np.log(np.mean(np.exp(2.5 * rng.standard_normal((n, 32)) - 2.5**2 / 2), axis=1))


def own_law(history, shape) -> WithinLaw:
    """*shape* (mean 0, sd 1) as the law of independent units' scores *history*: their own within-record variance."""
    _, within, _, _, dof = moments(history)
    return WithinLaw(shape, within, dof)


def test_a_skewed_within_record_law_holds_the_rate_asked_where_the_normal_quantile_does_not():
    """Issue 39: scores that are a soft maximum (likelihood_ratio's log-sum-exp over its shapes) are skewed to
    the right within a record; from two history records of them (a record effect besides), the normal quantile
    of their model let 2.2-2.3 % of a new record's units through where 1 % was asked, the quantile of their own
    within-record law (a sample of it, as detection_units.within_laws draws one) 1.0-1.2 %."""
    rng = np.random.default_rng(5)
    law = soft_maxima(rng, 4000)
    law = (law - law.mean()) / law.std()
    plain, skewed = [], []
    for _ in range(100):
        history = [0.2 * rng.standard_normal() + soft_maxima(rng, 400) for _ in range(2)]
        new = 0.2 * rng.standard_normal() + soft_maxima(rng, 2000)
        plain.append(np.mean(new > fit(history, 0.99).threshold))
        m = fit(history, 0.99, law=own_law(history, law))
        skewed.append(np.mean(new > m.threshold))
    assert np.mean(plain) > 0.018, np.mean(plain)
    assert 0.007 < np.mean(skewed) < 0.014, np.mean(skewed)
    assert m.tail > 1.1


def test_a_normal_within_record_law_gives_the_normal_quantile_back():
    rng = np.random.default_rng(6)
    law = rng.standard_normal(200_000)
    for share in (0.0, 0.3, 1.0):
        assert law_quantile(law, 0.99, share) == pytest.approx(norm.ppf(0.99), abs=0.03)
    history = [rng.standard_normal(300) for _ in range(2)]
    assert fit(history, 0.99, law=own_law(history, law)).threshold == pytest.approx(
        fit(history, 0.99).threshold, rel=0.02
    )


def soft_maximum(shapes: np.ndarray, X) -> np.ndarray:
    """log mean exp of *shapes*' log-likelihood ratios on units *X* (likelihood_ratio's form), noise sd 1 a
    revolution: 0.1 of a TSA of 10."""
    z = np.asarray(X, dtype=np.float64) @ shapes.T * 10
    return np.log(np.mean(np.exp(z - 0.5 * np.sum(shapes**2, axis=1) * 10), axis=1))


def test_units_drawn_again_from_a_records_revolutions_have_the_law_of_a_new_records_units():
    """detection_units.within_laws: TSAs of 10 revolutions drawn with replacement from each of two history records'
    45 revolutions, scored by a soft maximum over 32 shapes (likelihood_ratio's form), have the right-skewed law of
    TSAs of new noise: 99 % quantiles 2.88 and 2.93 sd above the mean, where the normal's is 2.33 (seeds 8-10:
    within 0.2 of each other), and their spread. A revolution's law is the history's own revolution scores, less
    each record's mean: none is scored again."""
    from gearlab.kinds.detection_units import Rule, within_laws

    rng = np.random.default_rng(9)
    shapes = rng.standard_normal((32, 256))
    shapes *= 0.9 / np.linalg.norm(shapes, axis=1, keepdims=True)
    scored = []

    def score(_, X):
        scored.append(len(X))
        return soft_maximum(shapes, X)

    fixed = 0.1 * rng.standard_normal((2, 256))  # each record's own revolution
    revolutions = np.concatenate([rng.standard_normal((45, 256)) + f for f in fixed])
    own = soft_maximum(shapes, revolutions) + np.repeat([0.0, 3.0], 45)  # a record effect: not in the law
    rule = Rule("records", 0.01, {"revolution": [(45, 45.0)] * 2, "record10": [(12, 4.5)] * 2})
    units = {"revolution": revolutions, "record10": np.zeros((24, 256))}
    laws = within_laws(score, rule, units, {"revolution": own, "record10": np.zeros(24)})
    law = laws["record10"]
    new = [soft_maximum(shapes, f + rng.standard_normal((10000, 10, 256)).mean(axis=1)) for f in fixed]
    # a little more spread than new TSAs': the drawn ones hold 45 revolutions' noise, whose projections on the 32
    # shapes spread more than the noise's own (1.16 times the variance here; on likelihood_ratio's 144 shapes and
    # the synthetic rig records 1.4-1.6), so the threshold errs high
    assert 1.0 < law.variance / np.mean([x.var() for x in new]) < 1.3 and law.dof == 88
    new = np.concatenate([(x - x.mean()) / x.std() for x in new])
    assert law.shape.mean() == pytest.approx(0.0, abs=1e-9) and law.shape.std() == pytest.approx(1.0)
    assert np.quantile(law.shape, 0.99) == pytest.approx(np.quantile(new, 0.99), abs=0.25)
    assert np.quantile(new, 0.99) > 2.7
    # the revolutions' own scores: only the TSAs drawn again (1000 a record) were scored
    assert scored == [1000, 1000]
    deviations = np.concatenate([own[:45] - own[:45].mean(), own[45:] - own[45:].mean()])
    assert laws["revolution"].shape == pytest.approx(deviations / deviations.std())
    assert laws["revolution"].variance == pytest.approx(moments([own[:45], own[45:]])[1])


def test_a_tsas_spread_from_every_revolution_holds_the_rate_where_the_historys_few_tsas_do_not():
    """Issue 39: two history records of 44 revolutions hold 4.4 independent TSAs of 10 each; the spread of their
    35 sliding TSAs, on so few, is far off in some histories, and the threshold on it let 2.4 % of a new record's
    TSAs through where 1 % was asked (a soft maximum's scores, 150 histories; 8.1 % in the worst tenth of them).
    The spread of TSAs drawn again from every revolution of the records (within_laws' variance): 0.4 %, 1.2 % in
    the worst tenth (below 1 %: that spread errs high, test_units_drawn_again_...)."""
    from gearlab.kinds.detection_units import Rule, within_laws

    rng = np.random.default_rng(11)
    shapes = rng.standard_normal((32, 64))
    shapes *= 0.9 / np.linalg.norm(shapes, axis=1, keepdims=True)
    n, b = 44, 10
    rule = Rule("records", 0.01, {"revolution": [(n, float(n))] * 2, "record10": [(n - b + 1, 4.4)] * 2})
    windows, redrawn = [], []
    for _ in range(150):
        revs = [rng.standard_normal((n, 64)) for _ in range(2)]
        tsas = np.concatenate([np.stack([r[i : i + b].mean(axis=0) for i in range(n - b + 1)]) for r in revs])
        hist = {"revolution": soft_maximum(shapes, np.concatenate(revs)), "record10": soft_maximum(shapes, tsas)}
        units = {"revolution": np.concatenate(revs), "record10": tsas}
        laws = within_laws(lambda _, X: soft_maximum(shapes, X), rule, units, hist)
        new = soft_maximum(shapes, rng.standard_normal((400, b, 64)).mean(axis=1))
        windows.append(np.mean(new > rule.model("record10", hist["record10"]).threshold))
        redrawn.append(np.mean(new > rule.model("record10", hist["record10"], law=laws["record10"]).threshold))
    windows, redrawn = np.sort(windows), np.sort(redrawn)
    assert np.mean(windows) > 0.018 and np.mean(windows[-15:]) > 0.05, windows
    assert 0.002 < np.mean(redrawn) < 0.01 and np.mean(redrawn[-15:]) < 0.02, redrawn
