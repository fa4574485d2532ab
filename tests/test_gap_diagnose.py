"""The gap diagnosis (gearlab/gap/diagnose.py): which effect, with which parameters, turns the
source simulator into the target — checked on targets whose effect we know.

Kept fast: few healthy revolutions, small budgets, short candidate lists, fits in this process.
"""

import inspect
import json

import numpy as np
import pytest

from gearlab.data.builder import build_dataset
from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.effects import default_candidates, effect_spec, model_of
from gearlab.errors import GearlabInputError
from gearlab.executors import LocalExecutor
from gearlab.gap.conclusion import (
    NAMED_SHARE,
    NOISE_WIDTH,
    SMALL_AUC,
    needed_effects,
    rms_effect,
    unneeded_note,
    verdict_of,
    within_noise,
)
from gearlab.gap.diagnose import Scorer, Settings, corrected_source, diagnose
from gearlab.gap.scoring import source_rows
from gearlab.gap.stats import gap_report
from gearlab.gap.views import healthy_rows

B6 = dataset_preset("B-6-ch5").with_(faults=(), healthy=16)
FAST = dict(healthy=16, bootstrap=20, permutations=99, budget=4, seed=0)


pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")  # the simulator's accuracy warnings on odd parameters


def target_rows(spec):
    """What the diagnosis may see of a target: its healthy revolutions in physical units."""
    return healthy_rows(build_dataset(spec))


def names(result):
    return [e["name"] for e in result["effects"]]


# --- the pieces ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "effects, noise",
    [
        ((), None),
        ((), NoiseSpec("laplace", 5.0, 2)),
        ((effect_spec("sensor_noise", kind="laplace", snr_db=5),), None),
        ((effect_spec("drive_inertias"), effect_spec("interference_tone", frequency=333.0, ratio=0.3)), None),
    ],
)
def test_source_rows_are_the_builders_healthy_rows_bit_for_bit(effects, noise):
    spec = B6.with_(healthy=12, effects=effects, noise=noise, seed=5)
    assert np.array_equal(source_rows(spec), target_rows(spec))


def test_the_search_score_is_the_reports_gap_total():
    source = source_rows(B6.with_(effects=(effect_spec("sensor_noise", snr_db=10),)))
    target = source_rows(B6.with_(effects=(effect_spec("sensor_noise", snr_db=3),), seed=4))
    want = gap_report(source, target, (25, 30), bootstrap=0, permutations=10)["total"]["gap"]
    assert Scorer(target, (25, 30)).report_gap(source) == pytest.approx(want, rel=1e-9)


def test_the_search_score_cannot_be_lowered_by_noise_the_target_lacks():
    # The search score is on the target's scale: adding noise to the source inflates no
    # spread, so against a quiet target more noise only makes the score worse.
    target = source_rows(B6.with_(effects=(effect_spec("sensor_noise", snr_db=30),), seed=4))
    scorer = Scorer(target, (25, 30))
    scores = [
        scorer.score(source_rows(B6.with_(effects=(effect_spec("sensor_noise", snr_db=snr),)))) for snr in (30, 10, 0)
    ]
    assert abs(scores[0]) < 0.05 * scores[1] and scores[0] < scores[1] < scores[2]


def test_a_source_far_noisier_than_the_target_cannot_score_below_a_right_one():
    """The source's sampling term is capped at the target's spread. Uncapped, the score of a source
    whose rows scatter 100x the target's is unbiased but as noisy as that scatter, and a search
    that minimises it finds the draws far below 0 -- better than the right model (a 3 Hz tone at
    10x the signal, the bound of its ratio, on consecutive revolutions: -1.8e5 against the right
    drive inertias' 0.3, and it won its round). Capped, the source's own scatter stays in the score."""
    rng = np.random.default_rng(0)
    Ft = rng.normal(0.0, 1.0, (80, 50))
    right = rng.normal(0.0, 1.0, (40, 50))
    wild = rng.normal(0.5, 100.0, (40, 50))  # its mean off by half a spread, its scatter 100x
    vs = wild.var(axis=0, ddof=1)
    uncapped = np.sum((Ft.mean(axis=0) - wild.mean(axis=0)) ** 2 - vs / 40 - Ft.var(axis=0, ddof=1) / 80)
    assert uncapped < -100.0 < Scorer.mismatch(right, Ft)  # uncapped, this draw beat the right model
    assert abs(Scorer.mismatch(right, Ft)) < 5.0  # a right model keeps its score near 0
    assert Scorer.mismatch(wild, Ft) > 1000.0 * abs(Scorer.mismatch(right, Ft))


def test_diagnose_gets_only_the_target_rows():
    # The diagnosis must not be able to learn the target's making: no spec, no dataset.
    assert list(inspect.signature(diagnose).parameters) == [
        "source",
        "target_X",
        "settings",
        "executor",
        "on_event",
        "chain",
    ]


# --- identification -------------------------------------------------------------------------------


def test_sensor_noise_is_named_with_its_snr():
    target = target_rows(B6.with_(effects=(effect_spec("sensor_noise", kind="laplace", snr_db=5),), seed=11))
    settings = Settings(candidates=("sensor_noise", "interference_tone", "mesh_damping"), max_effects=2, **FAST)
    result = diagnose(B6, target, settings)
    assert result["significant_before"]
    assert names(result)[0] == "sensor_noise"
    fit = result["effects"][0]
    assert abs(fit["params"]["snr_db"] - 5.0) < 1.5
    lo, hi = fit["intervals"]["snr_db"]
    assert lo <= fit["params"]["snr_db"] <= hi
    assert result["ranking"][0]["name"] == "sensor_noise" and len(result["ranking"]) == 3
    assert result["gap_after"] < 0.01 * result["gap_before"]
    assert not result["unexplained"]
    json.dumps(result)  # JSON-serialisable as it stands


def test_interference_tone_is_named():
    target = target_rows(B6.with_(effects=(effect_spec("interference_tone", frequency=1234.0, ratio=0.3),), seed=3))
    settings = Settings(candidates=("sensor_noise", "interference_tone", "tooth_friction"), max_effects=1, **FAST)
    result = diagnose(B6, target, settings)
    assert names(result) == ["interference_tone"]
    assert result["ranking"][0]["name"] == "interference_tone"


def test_same_simulator_other_noise_seed_has_no_gap_and_no_effects():
    source = B6.with_(effects=(effect_spec("sensor_noise", kind="gaussian", snr_db=10),))
    target = target_rows(source.with_(seed=99))
    result = diagnose(source, target, Settings(candidates=("sensor_noise", "tooth_friction"), **FAST))
    assert not result["significant_before"]
    assert result["effects"] == [] and result["corrected_effects"] == []
    assert result["unexplained"] is False
    assert corrected_source(source, result) == source


def test_drive_inertias_turn_six_dof_into_eight_dof(monkeypatch):
    # Both sides carry the same sensor noise (other seeds): the only difference is the drive.
    # (Noise-free, identical sets still show a rounding-level TSA residual in gap_report.)
    # The search's fit as it stands, without the profile (gearlab.gap.identify), a fifth of the diagnosis's
    # CPU: the profile leaves this fit's parameters and reports as they are (the same k_c, p after 0.28), and
    # test_gap_load's drive at another load profiles this effect on an eight_dof target.
    import gearlab.gap.diagnose as d

    monkeypatch.setattr(d, "profiled", lambda run, accepted, fitted: fitted)
    noise = (effect_spec("sensor_noise", kind="gaussian", snr_db=20),)
    source = B6.with_(effects=noise)
    target = target_rows(dataset_preset("B-8-ch5").with_(faults=(), healthy=16, effects=noise, seed=21))
    # The default budget (16): the search starts at the effect's generic defaults, not at Table 2.4's
    # drive (the target's); at budget 8 it does not reach the drive from there.
    settings = Settings(
        candidates=("drive_inertias", "bearing_stiffness", "fillet_correction"), max_effects=1, **{**FAST, "budget": 16}
    )
    result = diagnose(source, target, settings)
    assert result["significant_before"]
    assert names(result) == ["drive_inertias"]
    assert result["effects"][0]["params"]["k_c"] != 1e4  # found, not started at
    assert not result["significant_after"] and not result["unexplained"]
    fixed = corrected_source(source, result)
    assert [name for name, _ in fixed.effects] == ["drive_inertias", "sensor_noise"]  # in the order they act
    assert model_of(fixed.model_config()).name == "eight_dof"


def test_an_effect_outside_the_candidates_is_unexplained():
    noise = (effect_spec("sensor_noise", kind="gaussian", snr_db=20),)
    source = B6.with_(effects=noise)
    tone = effect_spec("interference_tone", frequency=1234.0, ratio=1.0)
    target = target_rows(B6.with_(effects=noise + (tone,), seed=8))
    result = diagnose(source, target, Settings(candidates=("tooth_friction", "fillet_correction"), **FAST))
    assert result["significant_before"]
    assert result["unexplained"] is True
    assert result["significant_after"] or result["effects"] == []


# --- bad input ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def some_target():
    return source_rows(B6.with_(healthy=12, effects=(effect_spec("sensor_noise", snr_db=10),)))


@pytest.mark.parametrize(
    "settings, match",
    [
        (Settings(candidates=("sensor_nose",)), "sensor_noise"),  # did you mean
        (Settings(budget=0), "budget"),
        (Settings(healthy=5), "healthy"),
        (Settings(alpha=1.5), "alpha"),
        (Settings(max_effects=0), "max_effects"),
        (Settings(candidates=("sensor_noise", "sensor_noise")), "repeat"),
    ],
)
def test_bad_settings_are_refused(settings, match, some_target):
    with pytest.raises(GearlabInputError, match=match):
        diagnose(B6, some_target, settings)


@pytest.mark.parametrize(
    "cut, match",
    [
        (lambda X: X[:5], "too few healthy target revolutions: 5"),
        (lambda X: X[:, :2048], "2048 samples"),
        (lambda X: X[0], "2-D"),
        (lambda X: np.where(X > 0, np.nan, X), "NaN"),
    ],
)
def test_bad_targets_are_refused(cut, match, some_target):
    with pytest.raises(GearlabInputError, match=match):
        diagnose(B6, cut(some_target), Settings(**FAST))


def test_a_bad_source_is_refused(some_target):
    with pytest.raises(GearlabInputError, match="channel"):
        diagnose(B6.with_(channel="nowhere"), some_target, Settings(**FAST))


# --- in parallel ------------------------------------------------------------------------------------


@pytest.mark.slow
def test_parallel_fits_give_the_serial_result():
    target = target_rows(B6.with_(effects=(effect_spec("sensor_noise", kind="laplace", snr_db=5),), seed=11))
    settings = Settings(candidates=("sensor_noise", "interference_tone", "mesh_damping"), max_effects=1, **FAST)
    serial = diagnose(B6, target, settings)
    parallel = diagnose(B6, target, settings, executor=LocalExecutor(2))
    assert serial["effects"] == parallel["effects"] and serial["ranking"] == parallel["ranking"]
    assert serial["evaluations"] == parallel["evaluations"] > 0  # the workers' counts summed (gearlab.gap.tally)


def test_no_extra_effect_is_credited_with_a_better_refit_of_the_first():
    """A short search fits tooth friction imperfectly. A later candidate is fitted next to a
    re-fitted friction, so it must beat the friction re-fitted alone (the round's baseline),
    not the first fit: measured against the first fit, sensor noise that the target lacks was
    accepted as removing 97 % of what was left."""
    source = B6.with_(noise=NoiseSpec("gaussian", 30.0, 0))
    hidden = effect_spec("tooth_friction", mu_f=0.1)
    target = target_rows(B6.with_(healthy=40, effects=(hidden,), noise=NoiseSpec("gaussian", 30.0, 7), seed=3))
    settings = Settings(candidates=("tooth_friction", "sensor_noise"), max_effects=2, **{**FAST, "budget": 6})
    result = diagnose(source, target, settings)
    assert names(result) == ["tooth_friction"]
    second = result["rounds"][1]
    assert second["baseline"] is not None and second["accepted"] is False
    assert abs(result["effects"][0]["params"]["mu_f"] - 0.1) < 0.02


def test_a_close_fit_that_still_tests_significant_is_partly_explained_with_its_share(monkeypatch):
    """On a quiet target (30 dB) the two-sample test flags a fillet factor 3 % off (p = 0.01,
    AUC 1.0); the gap left is under 1 % of the gap before. The verdict reads the test and its
    effect size: not "explained" while the sets are told apart perfectly, but partly
    explained, with the share removed. (The search's fit as it stands: the profile, which
    refines it to 0.02 % and "explained", is left out; the next test has it.)"""
    import gearlab.gap.diagnose as d

    monkeypatch.setattr(d, "profiled", lambda run, accepted, fitted: fitted)
    source = B6.with_(noise=NoiseSpec("gaussian", 30.0, 0))
    hidden = effect_spec("fillet_correction", lam=0.3)
    target = target_rows(B6.with_(healthy=40, effects=(hidden,), noise=NoiseSpec("gaussian", 30.0, 7), seed=3))
    result = diagnose(
        source, target, Settings(candidates=("fillet_correction",), max_effects=1, **{**FAST, "budget": 12})
    )
    assert names(result) == ["fillet_correction"]
    assert abs(result["effects"][0]["params"]["lam"] - 0.3) < 0.03
    assert result["significant_after"] and result["shrink"] >= 0.99
    assert result["shrink"] == pytest.approx(1 - result["gap_after"] / result["gap_before"])
    if result["after"]["auc"] > SMALL_AUC:
        assert result["verdict"] == "partly explained" and result["unexplained"]
        assert result["explained_share"] == pytest.approx(result["shrink"])
    else:
        assert result["verdict"] == "explained" and not result["unexplained"]


def test_the_profile_refines_a_close_fit_and_marks_it_determined():
    """The same target with the profile (gearlab.gap.identify): the fillet factor the search left
    3 % off comes back within 1 %, determined, and the corrected source is no longer told apart."""
    source = B6.with_(noise=NoiseSpec("gaussian", 30.0, 0))
    hidden = effect_spec("fillet_correction", lam=0.3)
    target = target_rows(B6.with_(healthy=40, effects=(hidden,), noise=NoiseSpec("gaussian", 30.0, 7), seed=3))
    result = diagnose(
        source, target, Settings(candidates=("fillet_correction",), max_effects=1, **{**FAST, "budget": 12})
    )
    effect = result["effects"][0]
    assert abs(effect["params"]["lam"] - 0.3) < 0.003
    assert effect["profile"]["score"] < effect["profile"]["score_fit"]
    assert effect["determined"]["lam"]["determined"] and effect["combinations"] == []
    assert result["verdict"] == "explained"


@pytest.mark.parametrize(
    "case, verdict",
    [
        ((False, False, False, 0.5, 0.0), "no significant gap"),
        ((True, False, True, 1.0, 0.3), "unexplained"),
        ((True, True, False, 0.9, 0.4), "explained"),  # the test no longer tells them apart
        ((True, True, True, 0.6, 0.995), "explained"),  # told apart, but by a small effect, < 1 % left
        ((True, True, True, 1.0, 0.995), "partly explained"),  # the 1 % rule alone no longer explains
        ((True, True, True, 0.6, 0.7), "unexplained"),  # stand-ins removed 4.5-94 %, right effects >= 99.8 %
        ((True, True, True, 0.9, 0.94), "unexplained"),
        ((True, True, True, 0.9, 0.998), "partly explained"),  # a pair's weak second effect missed
        ((True, True, True, 0.9, 0.045), "unexplained"),  # a stand-in removing 4.5 % names nothing
    ],
)
def test_the_verdict_reads_the_test_and_the_effect_size(case, verdict):
    assert verdict_of(*case) == verdict


@pytest.mark.parametrize(
    "case, verdict",
    [
        # a speed ripple fitted within 0.5 %: 97.7 % removed, RMS effect 0.41 left, AUC 0.98
        ((True, True, True, 0.98, 0.977, NAMED_SHARE, True), "explained"),
        # stand-ins for a withheld casing path: 97.5 % removed, RMS effect 50 left
        ((True, True, True, 1.0, 0.975, NAMED_SHARE, False), "unexplained"),
        # a right effect above the noise width but under 1 % of the gap left stays named
        ((True, True, True, 1.0, 0.9986, NAMED_SHARE, False), "partly explained"),
        # within the noise but no effect accepted: nothing explains it
        ((True, False, True, 0.98, 0.0, NAMED_SHARE, True), "unexplained"),
    ],
)
def test_what_is_left_within_the_noise_width_is_explained(case, verdict):
    assert verdict_of(*case) == verdict


def _report_of(gap: float, features: int) -> dict:
    return {"total": {"gap": gap, "features": features}}


def test_the_noise_width_is_the_rms_effect_of_the_gap_over_its_features():
    """sqrt(G / P): the mean revolution's RMS shift in units of the rows' own scatter. The rule
    needs what was removed above the width and what is left within it; a gap within the noise from
    the start is judged by the test alone."""
    assert rms_effect(_report_of(36.11, 214)) == pytest.approx(0.4108, abs=1e-4)
    assert rms_effect(_report_of(-1.0, 10)) == 0.0
    assert within_noise(_report_of(1581.0, 214), _report_of(36.11, 214))
    assert not within_noise(_report_of(1.496e7, 149), _report_of(3.717e5, 149))  # a stand-in: RMS 50 left
    assert not within_noise(_report_of(2.3, 154), _report_of(0.5, 154))  # within the noise before too
    assert within_noise(_report_of(4.0 * 214, 214), _report_of(NOISE_WIDTH**2 * 214, 214))  # the edge counts
    # a gap barely above the width: a stand-in removing a tenth brings it under, but what it
    # removed (RMS 0.33) is itself within the noise
    assert not within_noise(_report_of(1.1 * 214, 214), _report_of(0.99 * 214, 214))


def _seen_report(gap: float, features: int, seen: bool, auc: float) -> dict:
    """A report as gap_seen and rms_effect read it: the MMD test's verdict and the classifier AUC
    (40 source against 80 target revolutions)."""
    return {
        "total": {"gap": gap, "features": features},
        "significant": seen,
        "auc": auc,
        "n_source": 40,
        "n_target": 80,
        "alpha": 0.05,
    }


def test_a_gap_seen_within_the_noise_width_is_below_what_the_diagnosis_attributes():
    """A 160 um eccentricity: seen (AUC 0.74) with an RMS effect of 0.13 -- below the noise width;
    a speed ripple's RMS effect of 30 is not; nor is a gap the test does not see."""
    from gearlab.gap.conclusion import below_noise_width

    assert below_noise_width(_seen_report(0.13**2 * 300, 300, True, 0.74))
    assert not below_noise_width(_seen_report(30.0**2 * 300, 300, True, 1.0))
    assert not below_noise_width(_seen_report(0.13**2 * 300, 300, False, 0.5))


def _spec(name: str) -> tuple:
    return (name, (("x", 1.0),))


def _needed(reports: dict, names_rounds: list, before: dict) -> tuple:
    """needed_effects on canned reports keyed by the effects' names."""
    accepted = [{"name": n, "round": r, **({"nuisance_of": o} if o else {})} for n, r, o in names_rounds]
    fitted = tuple(_spec(n) for n, _, _ in names_rounds)
    calls = []

    def report_of(fx):
        calls.append(fx)
        return reports[tuple(name for name, _ in fx)]

    return needed_effects(before, accepted, fitted, report_of) + (calls,)


def test_an_effect_that_only_nibbles_at_a_remainder_within_the_noise_is_not_named():
    """Seed 53's trial 9 (a load ripple; sensor noise named beside it in round 1): without the noise
    the ripple leaves RMS 0.45 (G 28.1 over 139 features), within the noise width, and with it the
    test still sees the gap (AUC 0.886): the noise is taken back, with a note. A weak eccentricity
    next to a low-pass (seed 47's trial 20) makes the gap unseen: it stays."""
    before = _seen_report(2.214e4, 139, True, 1.0)
    reports = {
        ("load_fluctuation", "sensor_noise"): _seen_report(19.14, 139, True, 0.886),
        ("load_fluctuation",): _seen_report(28.07, 139, True, 0.999),
    }
    accepted, fitted, unneeded, _ = _needed(
        reports, [("load_fluctuation", 1, None), ("sensor_noise", 1, "load_fluctuation")], before
    )
    assert [e["name"] for e in accepted] == ["load_fluctuation"] and fitted == (_spec("load_fluctuation"),)
    assert [u["name"] for u in unneeded] == ["sensor_noise"]
    assert unneeded[0]["reason"] == "within noise without it"
    assert unneeded[0]["gap_without"] == 28.07 and unneeded[0]["rms_effect_without"] == pytest.approx(0.449, abs=1e-3)
    assert "sensor_noise (round 1) not named" in unneeded_note(unneeded[0]) and "0.45" in unneeded_note(unneeded[0])

    before = _seen_report(4.428e6, 214, True, 1.0)
    reports = {
        ("sensor_lowpass", "shaft_eccentricity"): _seen_report(0.0719, 214, False, 0.397),
        ("sensor_lowpass",): _seen_report(12.79, 214, True, 0.989),
    }
    accepted, _, unneeded, _ = _needed(reports, [("sensor_lowpass", 1, None), ("shaft_eccentricity", 2, None)], before)
    assert [e["name"] for e in accepted] == ["sensor_lowpass", "shaft_eccentricity"] and unneeded == []


def test_a_stand_in_the_final_fit_does_better_without_is_not_named_but_a_right_second_effect_is():
    """Seed 53's trial 14 (mesh damping and a load ripple): round 2 accepted a speed ripple for the
    load ripple, round 3 the load ripple too. Checked last-accepted first: the load ripple removes 80 %
    of what the others leave (kept); without the speed ripple the gap falls from 328 to 166 (taken
    back); then without the noise beside the mesh damping it falls to 148 (taken back). The first
    round's effect is never checked. (The stored fits' reports, current code.)"""
    before = _seen_report(5.958e5, 144, True, 1.0)
    reports = {
        ("mesh_damping", "sensor_noise", "speed_fluctuation", "load_fluctuation"): _seen_report(327.9, 144, True, 1.0),
        ("mesh_damping", "sensor_noise", "speed_fluctuation"): _seen_report(1643.0, 144, True, 1.0),
        ("mesh_damping", "sensor_noise", "load_fluctuation"): _seen_report(166.1, 144, True, 1.0),
        ("mesh_damping", "load_fluctuation"): _seen_report(148.1, 144, True, 1.0),
    }
    rounds = [
        ("mesh_damping", 1, None),
        ("sensor_noise", 1, "mesh_damping"),
        ("speed_fluctuation", 2, None),
        ("load_fluctuation", 3, None),
    ]
    accepted, fitted, unneeded, calls = _needed(reports, rounds, before)
    assert [e["name"] for e in accepted] == ["mesh_damping", "load_fluctuation"]
    assert [u["name"] for u in unneeded] == ["speed_fluctuation", "sensor_noise"]
    assert unneeded[0]["share_of_rest"] < 0 and "166.1 against 327.9" in unneeded_note(unneeded[0])
    assert unneeded[1]["share_of_rest"] < 0 and unneeded[1]["gap_without"] == 148.1
    assert all(fx[0] == _spec("mesh_damping") for fx in calls)  # never judged without the first


def test_a_parameter_whose_interval_spans_its_range_is_not_identifiable():
    """Per parameter, the diagnosis says whether the data determine it: an interval of a tenth of the
    range (on the search's scale: log for a frequency) is determined, one over most of it is not."""
    from gearlab.gap.diagnose import Space
    from gearlab.gap.identify import DETERMINED_WIDTH, determined
    from gearlab.registry import get_registry

    space = Space(get_registry().get("effect", "sensor_bandwidth"))
    f_n = next(e for e in space.numbers if e["name"] == "f_n")
    lo, hi = f_n["low"], f_n["high"]  # 0.1-100 kHz, searched on a log scale
    narrow = [lo * (hi / lo) ** 0.40, lo * (hi / lo) ** 0.50]
    marks = determined(space, {"f_n": narrow, "zeta": [0.01, 1.0]})
    assert marks["f_n"]["determined"] and marks["f_n"]["width"] == pytest.approx(0.1)
    assert not marks["zeta"]["determined"] and marks["zeta"]["width"] == pytest.approx(1.0)
    assert marks["zeta"]["width"] > DETERMINED_WIDTH >= marks["f_n"]["width"]


def test_a_small_search_says_it_may_miss_needle_like_parameters():
    """--quick's budget of 4 can miss a sharp resonance the default search finds: the result says so."""
    source = B6.with_(effects=(effect_spec("sensor_noise", kind="gaussian", snr_db=20),))
    target = target_rows(source.with_(seed=99))
    quick = diagnose(source, target, Settings(candidates=("sensor_noise",), **{**FAST, "budget": 4}))
    assert any("may be missed" in n for n in quick["notes"])
    full = diagnose(source, target, Settings(candidates=("sensor_noise",), **{**FAST, "budget": 16}))
    assert not any("may be missed" in n for n in full["notes"])


def test_consecutive_rows_add_the_output_shaft_orders_to_the_reports():
    """'consecutive' (auto: true for a measured target, which has a chain) resolves the output-shaft
    orders in the before/after reports; off, they are not reported."""
    source = B6.with_(effects=(effect_spec("sensor_noise", kind="gaussian", snr_db=20),))
    target = target_rows(source.with_(seed=99, healthy=60))
    base = dict(FAST, healthy=60)
    off = diagnose(source, target, Settings(candidates=("sensor_noise",), **base))
    on = diagnose(source, target, Settings(candidates=("sensor_noise",), consecutive=True, **base))
    assert off["settings"]["consecutive"] is False and "output_shaft" not in off["before"]
    assert on["settings"]["consecutive"] is True and on["before"]["output_shaft"]["blocks"] == [10, 10]
    with pytest.raises(GearlabInputError, match="consecutive"):
        diagnose(source, target, Settings(candidates=("sensor_noise",), consecutive="maybe", **base))


class _FakeSearch:
    effects: tuple = ()

    def with_(self, effects):
        return effects


def _joint_run(score_now: float):
    """A diagnosis's shared state with a score that reads the effects it is given: *score_now* unless
    the tone is at 179 Hz, then 1.0 where it acts before the sensor noise (as the fit scored it), 1,455
    where after it (912/11's kind: the noise's level is the RMS it is added to)."""
    from types import SimpleNamespace

    from gearlab.gap.diagnose import _by_level

    def score(effects):
        names = [n for n, _ in effects]
        if dict(dict(effects).get("interference_tone", ())).get("frequency") != 179.0:
            return score_now
        return 1.0 if names.index("interference_tone") < names.index("sensor_noise") else 1455.0

    return SimpleNamespace(
        scorer=SimpleNamespace(score=score),
        rows=lambda effects: _by_level(effects),
        search=_FakeSearch(),
        target=None,
        settings=Settings(seed=3),
        executor=LocalExecutor(1),
        on_event=lambda e: None,
        spec=lambda name, params: (name, tuple(sorted(params.items()))),
    )


@pytest.mark.parametrize("score_now, taken", [(50.0, True), (0.5, False)])
def test_the_round_s_effect_is_searched_again_next_to_the_backfitted_others(monkeypatch, score_now, taken):
    """joint_refit: the round's new effect gets a whole search next to the earlier effects (held,
    then backfitted by fit_effect), accepted sensor noise fitted at every point as the nuisance; the
    result replaces the round's fit only when it scores lower, every entry getting its parameters
    in the accepted order."""
    import gearlab.gap.diagnose as d

    seen = {}

    def fake_fit(task):
        seen["task"] = task
        return {
            "name": task[1],
            "score": 1.0,
            "params": {"frequency": 179.0, "ratio": 0.44},
            "accepted": [["sensor_bandwidth", [["f_n", 4921.0], ["zeta", 0.144]]]],
            "nuisance": {"name": "sensor_noise", "params": {"snr_db": 31.0}},
            "intervals": {"frequency": [178.0, 180.0]},
            "determined": {"frequency": {"determined": True}},
        }

    monkeypatch.setattr(d, "fit_effect", fake_fit)
    fitted = (
        ("sensor_bandwidth", (("f_n", 4930.0), ("zeta", 0.137))),
        ("interference_tone", (("frequency", 357.0), ("ratio", 0.19))),
        ("sensor_noise", (("snr_db", 30.0),)),
    )
    accepted = [
        {"name": "sensor_bandwidth", "round": 1, "params": {"f_n": 4930.0, "zeta": 0.137}},
        {"name": "interference_tone", "round": 2, "params": {"frequency": 357.0, "ratio": 0.19}},
        {"name": "sensor_noise", "round": 2, "params": {"snr_db": 30.0}, "nuisance_of": "interference_tone"},
    ]
    info = {}
    out = d.joint_refit(_joint_run(score_now), 2, accepted, fitted, info)
    name, others, nuisance = seen["task"][1], seen["task"][2], seen["task"][6]
    assert name == "interference_tone" and nuisance  # the accepted noise is fitted at every point
    assert [n for n, _ in others] == ["sensor_bandwidth"]
    assert info["joint_refit"]["score_before"] == score_now and info["joint_refit"]["score"] == 1.0
    if taken:
        assert [n for n, _ in out] == ["sensor_bandwidth", "interference_tone", "sensor_noise"]
        assert [e["params"] for e in accepted] == [
            {"f_n": 4921.0, "zeta": 0.144},
            {"frequency": 179.0, "ratio": 0.44},
            {"snr_db": 31.0},
        ]
        assert accepted[1]["determined"]["frequency"]["determined"]
    else:
        assert out == fitted and accepted[1]["params"] == {"frequency": 357.0, "ratio": 0.19}


def test_a_joint_refit_is_kept_only_where_it_scores_lower_in_the_order_it_is_kept(monkeypatch):
    """Sensor noise accepted in round 1 acts before round 2's tone where the effects are kept (acceptance
    order within a level); joint_refit fits the tone with the noise after it (the nuisance). Compared as
    fitted (1.0 against 8.26) it was taken, then every later step scored it in the kept order (912/11:
    1,455), the profiles moved from there and the tone was dropped: unexplained. Now it is scored as kept."""
    import gearlab.gap.diagnose as d

    monkeypatch.setattr(
        d,
        "fit_effect",
        lambda task: {
            "name": task[1],
            "score": 1.0,
            "params": {"frequency": 179.0, "ratio": 0.44},
            "nuisance": {"name": "sensor_noise", "params": {"snr_db": 31.0}},
            "intervals": {},
        },
    )
    fitted = (("sensor_noise", (("snr_db", 30.0),)), ("interference_tone", (("frequency", 357.0), ("ratio", 0.19))))
    accepted = [
        {"name": "sensor_noise", "round": 1, "params": {"snr_db": 30.0}},
        {"name": "interference_tone", "round": 2, "params": {"frequency": 357.0, "ratio": 0.19}},
    ]
    info = {}
    assert d.joint_refit(_joint_run(8.26), 2, accepted, fitted, info) == fitted
    assert info["joint_refit"]["score"] == 1455.0 and accepted[1]["params"] == {"frequency": 357.0, "ratio": 0.19}


def test_no_joint_refit_without_one_new_effect():
    import gearlab.gap.diagnose as d

    fitted = (("sensor_noise", (("snr_db", 30.0),)),)
    accepted = [{"name": "sensor_noise", "round": 1, "params": {"snr_db": 30.0}}]
    assert d.joint_refit(_joint_run(5.0), 2, accepted, fitted, {}) == fitted


@pytest.mark.slow
def test_a_tone_beside_a_resonance_is_fitted_at_its_frequency_not_at_twice_it(tmp_path):
    """The pair that the fourth round's benchmark missed (seed 31, trial 23 of 24: a 4.92 kHz sensor
    resonance, zeta 0.144, with a 179.1 Hz tone at ratio 0.44, written as a measured file): round 2 fitted
    the tone at 359 Hz next to round 1's misfitted resonance, and joint_refit moved it back. With the tone's
    line taken out while the others are searched (gearlab.gap.lines) the resonance is fitted first (4.92 kHz,
    zeta 0.144) and the tone, fitted last, lands within a few percent of 179.1 Hz at its first fit (176.9 Hz;
    2-9 min on 2 shared cores)."""
    from gearlab.kinds.gap_benchmark import trials as bench
    from gearlab.registry import get_registry

    source = dataset_preset("B-6-ch5").with_(faults=(), healthy=40, noise=bench.BASE_NOISE)
    library = tuple(default_candidates(get_registry()))
    trial = bench.draw_trials(24, 31, library, source)[23]
    assert [name for name, _ in trial.hidden] == ["sensor_bandwidth", "interference_tone"]
    settings = {"budget": 16, "max_effects": 3, "healthy": 40, "bootstrap": 200, "permutations": 500, "seed": 31}
    record = bench.trial_task(bench.TrialTask(trial, source, settings, str(tmp_path / "trial"), 80))
    result = json.loads((tmp_path / "trial" / "diagnosis.json").read_text())
    result = result.get("result", result)
    assert result["tone_line"] * source.speed_hz == pytest.approx(179.10857, rel=0.05)  # the line out: 4.48 orders
    tone = next(r for r in result["rounds"] if r.get("best") == "interference_tone")
    assert tone is result["rounds"][-1]  # fitted last
    assert abs(tone["fits"][0]["params"]["frequency"] / 179.10857 - 1) < 0.05  # its first fit: 176.9 Hz
    assert abs(tone["joint_refit"]["params"]["frequency"] / 179.10857 - 1) < 0.05
    assert record["accepted"][0] == "sensor_bandwidth" and record["top1"]


# --- the noise law -----------------------------------------------------------------------------------


def test_the_tail_shape_reads_each_noise_law():
    """The central 99 % range over the IQR: 3.82 (Gaussian), 6.64 (Laplace), 12.2 (Student-t, nu = 2)."""
    from gearlab.gap.scoring import tail_shape

    rng = np.random.default_rng(3)
    synchronous = np.sin(np.linspace(0.0, 40.0, 1024))  # the same in every row: the residual drops it
    draws = {
        "gaussian": rng.standard_normal,
        "laplace": lambda s: rng.laplace(0.0, 1.0, s),
        "student_t": lambda s: rng.standard_t(2.0, s),
    }
    for kind, wide in (("gaussian", 3.82), ("laplace", 6.64), ("student_t", 12.2)):
        shape = tail_shape(synchronous + draws[kind]((200, 1024)))
        assert abs(shape[1] - np.log(wide)) < 0.05, kind


@pytest.mark.parametrize("kind", ["gaussian", "laplace"])
def test_the_noise_law_is_the_one_the_residual_s_tails_show(kind):
    """Fitted alone and as another candidate's nuisance, the noise keeps the target's law, however
    the score ranks the laws within its own noise (Gaussian noise came out Laplace)."""
    from gearlab.gap import diagnose as d

    source = B6.with_(noise=NoiseSpec("gaussian", 30.0, 0))
    hidden = (effect_spec("sensor_noise", kind=kind, snr_db=12.0),)
    target_X = target_rows(source.with_(effects=hidden, seed=21, noise=NoiseSpec("gaussian", 30.0, 21)))
    settings = Settings(candidates=("sensor_noise", "mesh_damping"), **FAST)
    target, _, rows, s, _, search, _ = d._prepared(source, target_X, settings, None)
    alone = d.fit_effect((search, "sensor_noise", (), target, s, 5, False, rows))
    assert alone["params"]["kind"] == kind
    assert min(alone["tails"], key=alone["tails"].get) == kind
    assert abs(alone["params"]["snr_db"] - 12.0) < 1.5
    beside = d.fit_effect((search, "mesh_damping", (), target, s, 5, True, rows))
    assert beside["nuisance"]["params"]["kind"] == kind


# --- the casing path's search ----------------------------------------------------------------------


def test_the_casing_path_search_starts_from_mountings_over_its_natural_frequencies():
    """Ten isotropic mountings of the default mass, f_m = sqrt(k / m) / 2 pi log-spaced 30 Hz-10 kHz,
    tried before the design; all five parameters searched on a log scale, with budget x 3 simulations."""
    from gearlab.gap.diagnose import Space
    from gearlab.registry import get_registry

    effect = get_registry().get("effect", "casing_path")
    guesses = effect.guesses(np.zeros((4, 4096)), 40.0)
    mass = effect.params().mf
    f = [np.sqrt(g["k_yf"] / mass) / (2 * np.pi) for g in guesses]
    assert len(guesses) == 10 and all(g["k_xf"] == g["k_yf"] for g in guesses)
    assert f[0] == pytest.approx(30.0) and f[-1] == pytest.approx(1e4)
    assert np.allclose(np.diff(np.log(f)), np.log(1e4 / 30.0) / 9)
    space = Space(effect)
    assert all(e["log"] for e in space.numbers) and space.dims == 5


@pytest.mark.slow
def test_a_light_casing_path_beats_a_damped_sensor_resonance_in_its_round():
    """A 5 kg casing on 7.4e7 / 7.6e7 N/m mounts (development draw 1004): with the search's budget of
    16, casing_path searched from its design alone scored 1.16e6 and lost to a damped 1.6 kHz sensor
    (0.93e6); from the mountings, with three simulations per budget unit, it is far lower."""
    from gearlab.gap import diagnose as d

    source = B6.with_(noise=NoiseSpec("gaussian", 30.0, 0))
    casing = effect_spec("casing_path", mf=5.01, k_xf=7.38e7, k_yf=7.57e7)
    target_X = target_rows(source.with_(effects=(casing,), seed=31, noise=NoiseSpec("gaussian", 30.0, 31)))
    settings = Settings(candidates=("casing_path", "sensor_bandwidth"), **{**FAST, "budget": 16})
    target, _, rows, s, _, search, _ = d._prepared(source, target_X, settings, None)
    casing_fit = d.fit_effect((search, "casing_path", (), target, s, 1005, True, rows))
    sensor_fit = d.fit_effect((search, "sensor_bandwidth", (), target, s, 1005, True, rows))
    assert casing_fit["evaluations"] >= 3 * 16 - 1
    assert casing_fit["score"] < 0.1 * sensor_fit["score"]
    assert casing_fit["params"]["mf"] == pytest.approx(5.01, rel=0.3)  # above the mounts it is the mass


@pytest.mark.slow
def test_a_tone_s_noise_nuisance_takes_the_law_at_its_own_point():
    """Laplace noise beside a 180 Hz tone: the law is decided at every point of the tone's search, so
    at its fit, not at its defaults (24.75 Hz at half the signal's RMS, where Student-t came out)."""
    from gearlab.gap import diagnose as d

    source = B6.with_(noise=NoiseSpec("gaussian", 30.0, 0))
    hidden = (
        effect_spec("interference_tone", frequency=180.0, ratio=0.2),
        effect_spec("sensor_noise", kind="laplace", snr_db=10.0),
    )
    target_X = target_rows(source.with_(effects=hidden, seed=23, noise=NoiseSpec("gaussian", 30.0, 23)))
    settings = Settings(candidates=("interference_tone", "sensor_noise"), **{**FAST, "budget": 16})
    target, _, rows, s, _, search, _ = d._prepared(source, target_X, settings, None)
    fit = d.fit_effect((search, "interference_tone", (), target, s, 5, True, rows))
    assert fit["params"]["frequency"] == pytest.approx(180.0, rel=0.05)
    assert fit["nuisance"]["params"]["kind"] == "laplace"
    assert min(fit["nuisance"]["tails"], key=fit["nuisance"]["tails"].get) == "laplace"


def test_rounds_go_on_only_while_what_is_left_stands_above_the_noise_width():
    """another_round: a gap still seen after a round whose rest lies within the noise width (RMS 0.6
    of a removed RMS 40) ends the search; a rest above the width (RMS 3), or a gap seen from a start
    within the width (nothing removed above it), goes on; a gap no longer seen ends it."""
    from gearlab.gap.diagnose import another_round

    before = _seen_report(40.0**2 * 200, 200, True, 1.0)
    assert not another_round(before, _seen_report(0.6**2 * 200, 200, True, 0.9))
    assert another_round(before, _seen_report(3.0**2 * 200, 200, True, 1.0))
    assert not another_round(before, _seen_report(3.0**2 * 200, 200, False, 0.55))
    weak = _seen_report(0.9**2 * 200, 200, True, 0.8)
    assert another_round(weak, _seen_report(0.5**2 * 200, 200, True, 0.7))
