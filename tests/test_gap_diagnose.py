"""The gap diagnosis (gearlab/gap/diagnose.py): which effect, with which parameters, turns the
source simulator into the target — checked on targets whose effect we know.

Kept fast: few healthy revolutions, small budgets, short candidate lists, fits in this process.
"""

import inspect
import json
import warnings

import numpy as np
import pytest

from gearlab.data.builder import build_dataset
from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.effects import effect_spec, model_of
from gearlab.errors import GearlabInputError
from gearlab.executors import LocalExecutor
from gearlab.gap.diagnose import SMALL_AUC, Scorer, Settings, corrected_source, diagnose, source_rows, verdict_of
from gearlab.gap.stats import gap_report
from gearlab.gap.views import healthy_rows

B6 = dataset_preset("B-6-ch5").with_(faults=(), healthy=16)
FAST = dict(healthy=16, bootstrap=20, permutations=99, budget=4, seed=0)


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the simulator's accuracy warnings on odd parameters
        yield


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


def test_drive_inertias_turn_six_dof_into_eight_dof():
    # Both sides carry the same sensor noise (other seeds): the only difference is the drive.
    # (Noise-free, identical sets still show a rounding-level TSA residual in gap_report.)
    noise = (effect_spec("sensor_noise", kind="gaussian", snr_db=20),)
    source = B6.with_(effects=noise)
    target = target_rows(dataset_preset("B-8-ch5").with_(faults=(), healthy=16, effects=noise, seed=21))
    settings = Settings(candidates=("drive_inertias", "bearing_stiffness", "fillet_correction"), max_effects=1, **FAST)
    result = diagnose(source, target, settings)
    assert result["significant_before"]
    assert names(result) == ["drive_inertias"]
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


def test_a_parameter_whose_interval_spans_its_range_is_not_identifiable():
    """Per parameter, the diagnosis says whether the data determine it: an interval of a tenth of the
    range (on the search's scale: log for a frequency) is determined, one over most of it is not."""
    from gearlab.gap.diagnose import Space, determined
    from gearlab.gap.identify import DETERMINED_WIDTH
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
