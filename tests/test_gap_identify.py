"""The profile behind "determined" (gearlab/gap/identify.py): a parameter is determined only when no
distant value fits as well, and the report says what the data do pin where one is not."""

import math
import warnings

import numpy as np
import pytest

from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.effects import effect_spec
from gearlab.gap import diagnose as d
from gearlab.gap import scoring
from gearlab.gap import search as gap_search
from gearlab.gap.diagnose import profile_effect
from gearlab.gap.identify import FIT_SIGMAS, profile


class _ResonanceLike:
    """A space like a casing's: mass and stiffness (log scale), and a parameter that does nothing."""

    def space(self):
        return [
            {"name": "m", "low": 0.1, "high": 1000.0, "default": 18.0, "integer": False, "log": True},
            {"name": "k", "low": 1e5, "high": 1e11, "default": 2e8, "integer": False, "log": True},
            {"name": "idle", "low": 0.0, "high": 1.0, "default": 0.5, "integer": False, "log": False},
        ]


def _fit(score, params, noise=1.0):
    return profile(d.Space(_ResonanceLike()), score, lambda p: noise, params, 0, {})


def test_a_resonance_whose_frequency_alone_is_seen_pins_only_the_ratio():
    # the data see only sqrt(k/m): every (m, k) with the true ratio scores 0; the search's own
    # neighbourhood (each parameter moved alone) is steep, so its bracket read "determined"
    def score(p):
        return 1e4 * (0.5 * math.log(p["k"] / p["m"]) - 0.5 * math.log(1e7)) ** 2

    out = _fit(score, {"m": 40.0, "k": 4e8, "idle": 0.5})
    marks = out["determined"]
    assert not marks["m"]["determined"] and not marks["k"]["determined"]
    assert marks["m"]["reason"] == "profile"
    pair = next(c for c in out["combinations"] if set(c["params"]) == {"m", "k"})
    assert sum(pair["exponents"].values()) == pytest.approx(0.0, abs=0.05)  # k/m (or m/k): the ratio
    assert pair["value"] == pytest.approx(1e7 if pair["exponents"]["k"] > 0 else 1e-7, rel=0.05)
    # a parameter the score ignores moved alone: nothing about it is determined
    idle = next(c for c in out["combinations"] if c["params"] == ["idle"])
    assert idle["determined"] is None and not marks["idle"]["determined"]


def test_parameters_that_act_each_on_their_own_are_determined():
    def score(p):
        return 1e4 * (math.log(p["m"] / 40.0) ** 2 + math.log(p["k"] / 4e8) ** 2 + (p["idle"] - 0.3) ** 2)

    out = _fit(score, {"m": 40.0, "k": 4e8, "idle": 0.3})
    assert all(mark["determined"] for mark in out["determined"].values()), out["determined"]
    assert out["combinations"] == []
    assert out["intervals"]["m"][0] < 40.0 < out["intervals"]["m"][1]


def test_a_fit_in_a_wrong_basin_is_left_for_a_distant_start():
    # the search stopped at m = 300 on a plateau (a load inertia far above the gear's, which a
    # coupling hides); the truth, m = 2, scores 0 in a basin the search's local steps never reach
    def score(p):
        well = 50.0 * math.log(p["m"] / 2.0) ** 2
        return min(well, 200.0 + math.log(p["m"] / 300.0) ** 2) + 1e3 * math.log(p["k"] / 4e8) ** 2

    out = _fit(score, {"m": 300.0, "k": 4e8, "idle": 0.5})
    assert out["score_fit"] > 199.0 and out["score"] < FIT_SIGMAS
    assert out["params"]["m"] == pytest.approx(2.0, rel=0.05) and out["determined"]["m"]["determined"]


def test_the_fit_that_leaves_a_gap_marks_nothing_determined():
    def score(p):
        return 50.0 + 1e4 * (math.log(p["m"] / 40.0) ** 2 + math.log(p["k"] / 4e8) ** 2 + (p["idle"] - 0.3) ** 2)

    out = _fit(score, {"m": 40.0, "k": 4e8, "idle": 0.3}, noise=2.0)
    assert out["gap_left"] and not any(mark["determined"] for mark in out["determined"].values())


@pytest.mark.slow
def test_a_motor_inertia_behind_a_prescribed_speed_is_not_identifiable():
    """drive_inertias on six_dof: the motor's speed is prescribed, so its inertia I11 acts on nothing
    (the score is bit-identical over its range), while the load inertia and the coupling act."""
    b6 = dataset_preset("B-6-ch5").with_(faults=(), healthy=24, noise=NoiseSpec("gaussian", 30.0, 0))
    true = effect_spec("drive_inertias", I11=0.0122, I22=0.00332, k_c=55209.0)
    target = scoring.source_rows(b6.with_(effects=(true,), seed=77, noise=NoiseSpec("gaussian", 30.0, 77), healthy=48))
    settings = d.Settings(candidates=("drive_inertias",))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        out = profile_effect((b6.with_(seed=5), (true,), 0, target, settings, 0, d.Rows(), {}))
    marks = out["determined"]
    assert not marks["I11"]["determined"] and marks["I11"]["reason"] == "profile"
    assert marks["I22"]["determined"] and marks["k_c"]["determined"]
    assert any(c["params"] == ["I11"] for c in out["combinations"])
    assert np.isfinite(out["score"]) and out["score"] <= out["score_fit"]


def test_the_alias_period_of_a_ripple_on_a_gear_of_z1_teeth():
    from gearlab.gap.identify import pitch_alias_period

    assert pitch_alias_period(2, 25) == (pytest.approx(2 * math.pi / 25), 25)  # order 2 visits every pitch
    assert pitch_alias_period(5, 25) == (pytest.approx(2 * math.pi / 5), 5)  # order 5: five aliases
    assert pitch_alias_period(25, 25) == (pytest.approx(2 * math.pi), 1)  # a mesh-order ripple: none


@pytest.mark.parametrize("shift_deg", [0.0, 2.0])
def test_a_ripple_phase_left_at_a_wrong_tooth_pitch_alias_comes_back_to_the_truth(shift_deg):
    """The score of a ripple's phase as measured on Dataset B (a 3 % order-2 speed ripple): a valley
    about a degree wide at the truth (5 there, 125-145 at +-1 deg), every other tooth-pitch alias
    (2 pi / 25 apart) 35-430 at its own best, and the amplitude as sharp. A fit 57 deg off at a 3 %
    amplitude error comes back within 0.1 deg and 0.5 %; the search's own phase from any alias does,
    also where the wrong aliases' valleys lie *shift_deg* from the true one's (so that a scan on the
    fit's alias points next to the truth's valley: every alias gets its own short search)."""
    from gearlab.gap.identify import ALIAS_BRENT, ALIAS_EVALS, ALIAS_FITS, alias_refit

    class Ripple:
        def space(self):
            return [
                {"name": "amplitude", "low": 0.0, "high": 0.1, "default": 0.01, "integer": False, "log": False},
                {"name": "order", "low": 1, "high": 32, "default": 1, "integer": True, "log": False},
                {"name": "phase", "low": 0.0, "high": 2 * math.pi, "default": 0.0, "integer": False, "log": False},
            ]

    truth, period = 1.0, 2 * math.pi / 25
    calls = []

    def score(p):
        calls.append(p)
        d_phase = (p["phase"] - truth + math.pi) % (2 * math.pi) - math.pi
        within = (d_phase + period / 2) % period - period / 2
        alias = round((d_phase - within) / period) % 25
        if alias:
            within -= math.radians(shift_deg)
        penalty = 0.0 if alias == 0 else 35.0 + 20.0 * (alias % 7)
        return 4e5 * within**2 + penalty + 1e6 * (p["amplitude"] - 0.03) ** 2

    for start in (truth + math.radians(57.3), truth - 3.3, truth + 0.5 * period):
        out = alias_refit(
            d.Space(Ripple()),
            score,
            {"amplitude": 0.0309, "order": 2, "phase": start % (2 * math.pi)},
            "phase",
            "order",
            25,
        )
        err = (out["params"]["phase"] - truth + math.pi) % (2 * math.pi) - math.pi
        assert abs(math.degrees(err)) < 0.1 and abs(out["params"]["amplitude"] / 0.03 - 1) < 0.005
        assert out["params"]["order"] == 2 and out["score"] < 1.0
    # per start: the fit, one scan, a short Brent search per alias, three local fits
    assert len(calls) <= 3 * (1 + 29 + 25 * (ALIAS_BRENT + 2) + ALIAS_FITS * ALIAS_EVALS)


@pytest.mark.slow
def test_a_speed_ripples_phase_is_found_from_a_measured_record(tmp_path):
    """A 3 % order-2 speed ripple at 57 deg written as a measured record (npz, 0.5 x 4096 samples per
    revolution, tacho offset 74 deg), diagnosed from the file: the search ends at another tooth-pitch
    alias (57 deg off, score 205); the round's alias step (diagnose.realiased) brings the phase back
    within a degree before the check, and the profile calls it determined (1-2 min on 2 shared cores)."""
    from gearlab.effects import EffectChain, default_candidates
    from gearlab.kinds.gap_benchmark import trials as bench
    from gearlab.registry import get_registry

    hidden = effect_spec("speed_fluctuation", amplitude=0.03, order=2, phase=1.0)
    source = dataset_preset("B-6-ch5").with_(noise=bench.BASE_NOISE, healthy=40)
    trial = bench.Trial(
        0,
        "single",
        EffectChain.load((hidden,)).specs(),
        None,
        tuple(default_candidates(get_registry())),
        77,
        bench.Acquisition(0.5, math.radians(74.48), "npz"),
    )
    path = bench.write_target(trial, source, tmp_path / "t", 80)
    settings = {"budget": 16, "max_effects": 1, "healthy": 40, "bootstrap": 50, "permutations": 99, "seed": 5}
    result = bench.diagnose_file(path, source, ("speed_fluctuation",), settings)
    (fit,) = result["effects"]
    err = (fit["params"]["phase"] - 1.0 + math.pi) % (2 * math.pi) - math.pi
    assert abs(math.degrees(err)) < 1.0 and abs(fit["params"]["amplitude"] / 0.03 - 1) < 0.01
    (step,) = result["rounds"][0]["aliases"]
    assert step["score"] < 0.2 * step["score_before"]
    assert fit["determined"]["phase"]["determined"] and result["verdict"] == "explained"


class _HeldNoise:
    """A stand-in for diagnose._NoiseNuisance: the noise fitted at each point, and a re-fit."""

    def __init__(self, level: float):
        self.effect = type("E", (), {"spec": staticmethod(lambda p: ("sensor_noise", tuple(sorted(p.items()))))})()
        self.at, self.tails_at, self.level, self.fits = {}, {}, level, []

    def fit(self, params):
        self.fits.append(dict(params))
        self.at[d._key(params)] = {"snr_db": self.level + 1.0, "kind": "gaussian"}
        self.tails_at[d._key(params)] = {"gaussian": 0.0}
        return _two_basins(params) - 0.5  # the noise fitted again there fits a little better


def _two_basins(p) -> float:
    # a coarse search stopped at m = 300 on a plateau; the truth, m = 2, scores 0 in a basin its local
    # steps never reach (as a drive train's load inertia, or a casing's mass and mounting)
    well = 50.0 * math.log(p["m"] / 2.0) ** 2
    return min(well, 200.0 + math.log(p["m"] / 300.0) ** 2) + 1e3 * math.log(p["k"] / 4e8) ** 2 + p["idle"]


@pytest.mark.parametrize("with_noise", [False, True])
def test_the_fine_stage_takes_a_coarse_search_out_of_its_wrong_basin(with_noise):
    space = d.Space(_ResonanceLike())
    coarse = {"m": 300.0, "k": 4e8, "idle": 0.5}
    u, choice = space.point_of(coarse)
    history = [{"u": u, "choice": choice, "params": space.params(u, choice), "score": _two_basins(coarse)}]
    noise, held_with = None, []
    if with_noise:
        noise = _HeldNoise(20.0)
        noise.at[d._key(history[0]["params"])] = {"snr_db": 20.0, "kind": "gaussian"}
        noise.tails_at[d._key(history[0]["params"])] = {"gaussian": 0.1}

    def held(params, extra):
        held_with.append(extra)
        return _two_basins(params)

    out = gap_search._fine_stage(space, history, held, lambda params, extra: 1.0, noise, 3)
    best = min(out, key=lambda h: h["score"])
    assert out[0] is history[0] and len(out) > 1
    assert best["params"]["m"] == pytest.approx(2.0, rel=0.05) and best["score"] < 1.0
    if with_noise:
        # the noise is held, and fitted again (then held at that) only where a point beats the best so far
        first, refitted = (noise.effect.spec({"snr_db": level, "kind": "gaussian"}) for level in (20.0, 21.0))
        assert held_with[0] == (first,) and set(held_with) == {(first,), (refitted,)}
        assert noise.fits and best["params"] in noise.fits and noise.at[d._key(best["params"])]["snr_db"] == 21.0
        assert best["score"] == pytest.approx(_two_basins(best["params"]) - 0.5)
    else:
        assert held_with and all(extra == () for extra in held_with)


def test_the_fine_stage_runs_for_the_rounds_first_fits_whose_effect_takes_it(monkeypatch):
    """fine_fits: casing_path and drive_inertias (model level, more than MODEL_DIMS parameters) ranked
    within FINE_RANKS get the fine stage from their coarse fit; a fit it lowers is ranked again; one
    ranked lower, or an effect of few parameters, is left as its round fitted it."""
    from types import SimpleNamespace

    from gearlab.executors import LocalExecutor

    calls = []

    def fake_fit(task):
        calls.append(task)
        return {"name": task[1], "score": 1.0, "params": {"fine": True}, "evaluations": 100, "seconds": 2.0}

    monkeypatch.setattr(d, "fit_effect", fake_fit)
    run = SimpleNamespace(settings=d.Settings(), executor=LocalExecutor(1), on_event=lambda event: None)
    names = ["sensor_bandwidth", "casing_path", "bearing_stiffness", "drive_inertias"]
    fits = [
        {"name": name, "score": score, "params": {"coarse": name}, "evaluations": 40, "seconds": 1.0}
        for name, score in zip(names, (10.0, 20.0, 30.0, 40.0))
    ]
    tasks = [("search", name, (), "target", run.settings, 7, True, "rows") for name in names]
    out = d.fine_fits(run, 1, fits, tasks)
    assert [task[1] for task in calls] == ["casing_path"]  # drive_inertias ranked 4th; bearing_stiffness has 2
    assert calls[0] == tasks[1] + ({"coarse": "casing_path"},)  # the round's own task, from its coarse fit
    assert [f["name"] for f in out] == ["casing_path", "sensor_bandwidth", "bearing_stiffness", "drive_inertias"]
    assert out[0]["coarse_score"] == 20.0 and out[0]["evaluations"] == 140 and out[0]["seconds"] == 3.0
    # --quick (a budget below the default): the coarse search alone
    calls.clear()
    run.settings = d.Settings(budget=4)
    assert d.fine_fits(run, 1, fits, tasks) == fits and not calls
