"""The Bayes reference of a transfer table is a bound: with any effect in a simulated target, no
method beats it, or it is reported as unavailable (gearlab.learn.bounds.twin_problem).

Each target is Experiment B's eight-DOF domain cut down (one crack, a few healthy revolutions,
Laplace noise at 0 dB) with one registered effect at its defaults; the methods are the detectors,
which train in no time (their accuracy on the same test sets is what a bound must not be below)."""

import numpy as np
import pytest

from gearlab.data.builder import build_dataset
from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.effects import effect_spec
from gearlab.learn.bounds import twin_problem
from gearlab.learn.protocol import Protocol, StateStore, run_unit
from gearlab.parts.bound import bayes_bound
from gearlab.parts.training import method
from gearlab.registry import get_registry

# module_cache: the bound's twin datasets in the module's cache, not the user's (the one test file
# that wrote into ~/.cache/gearlab: 16 entries a run)
pytestmark = pytest.mark.usefixtures("one_torch_thread", "module_cache")

COMMON = dict(teeth=(1, 2, 3), faults=(("crack", (13,)),), healthy=30)
DETECTORS = tuple(
    method({"adapter": name, "supervised": False, "params": {}}, "test")
    for name in ("likelihood_ratio", "matched_filter")
)
PROTOCOL = Protocol(methods=DETECTORS, ks=(0,), repetitions=2, target_train=16, batch=4, device="cpu")


@pytest.fixture(scope="module")
def source():
    return build_dataset(dataset_preset("B-6-ch5").with_(**COMMON))


def target_with(*effects):
    return dataset_preset("B-8-ch5").with_(**COMMON, effects=effects, noise=NoiseSpec("laplace", 0.0, 1))


def bound_and_methods(source, spec):
    target = build_dataset(spec)
    bound = bayes_bound(spec, source, target, PROTOCOL)
    methods = {
        m.label: np.mean(
            [run_unit(PROTOCOL, source, target, rep, 0, m, StateStore(None))["accuracy"] for rep in (0, 1)]
        )
        for m in DETECTORS
    }
    return bound, methods


@pytest.mark.parametrize("name", sorted(get_registry().names("effect")))
def test_no_method_beats_the_reported_bound_whatever_effect_the_target_holds(source, name):
    bound, methods = bound_and_methods(source, target_with(effect_spec(name)))
    if "unavailable" in bound:
        assert bound["unavailable"] and "accuracy" not in bound
        return
    reported = bound["accuracy"]["0"]["mean"]
    assert all(acc <= reported for acc in methods.values()), (reported, methods)


def test_a_non_synchronous_tone_makes_the_bound_unavailable(source):
    """A tone at 333 Hz realised anew in each revolution: the detectors reach 97 % where the bound's
    model (one healthy revolution plus i.i.d. noise) gave 91 %; it is reported as unavailable."""
    spec = target_with(effect_spec("interference_tone", frequency=333.0, ratio=0.5))
    bound, methods = bound_and_methods(source, spec)
    assert "accuracy" not in bound and "tone" in bound["unavailable"]
    assert max(methods.values()) > 95.0  # what the wrong number would have been beaten by
    # a synchronous effect keeps the bound: its twin is still one healthy revolution
    assert twin_problem(build_dataset(target_with(effect_spec("speed_fluctuation")).with_(noise=None))) is None


def test_the_bound_at_the_methods_operating_point_thresholds_on_the_training_rows_alone(source):
    """`accuracy_at_rule`: the Bayes detector thresholded as the unsupervised methods are (the
    history rule at the scenario's false-alarm rate, on its scores of the target training rows), so
    a method's distance to the bound splits into the operating point's part and its model's. No
    higher than the best threshold; a test row's score moves nothing of it."""
    from dataclasses import replace

    from gearlab.learn.bounds import bayes_scores
    from gearlab.learn.history import history_threshold
    from gearlab.learn.protocol import split

    spec = target_with()
    target = build_dataset(spec)
    clean = build_dataset(spec.with_(noise=None))
    scores = bayes_scores(target.X, target.X[target.fault == 0], clean, "laplace")
    for rate in (0.01, 0.3):
        protocol = replace(PROTOCOL, calibration=replace(PROTOCOL.calibration, false_alarm=rate))
        bound = bayes_bound(spec, source, target, protocol)
        expected = []
        for rep in (0, 1):
            s = split(protocol, source, target, rep, 0)
            rule = history_threshold(scores[s.target_train], 1.0 - rate)
            y = target.fault[s.target_test]
            expected.append(100.0 * np.mean((scores[s.target_test] > rule) == (y == 1)))
        assert bound["accuracy_at_rule"]["0"]["mean"] == pytest.approx(np.mean(expected))
        assert bound["accuracy_at_rule"]["0"]["mean"] <= bound["accuracy"]["0"]["mean"]
