"""The target's load fitted beside every candidate of a gap diagnosis (gearlab/gap/level.py).

A target at another load than the source scales every mesh vibration: left unfitted, a stand-in that
changes the level (a softer fillet) was named for a drive (issue 37, development trial 904/10)."""

from dataclasses import asdict

import numpy as np
import pytest

from gearlab.data.builder import build_dataset
from gearlab.data.spec import dataset_preset
from gearlab.effects import effect_spec
from gearlab.gap import level
from gearlab.gap.diagnose import Settings, corrected_source, diagnose
from gearlab.gap.scoring import Rows, source_rows
from gearlab.gap.views import healthy_rows, offset_removed

B6 = dataset_preset("B-6-ch5").with_(faults=(), healthy=16)
NOISE = (effect_spec("sensor_noise", kind="gaussian", snr_db=20),)
SMALL = {"healthy": 16, "bootstrap": 20, "permutations": 99}  # a unit test's diagnosis: 16 rows, small statistics
# The bearing test's searches: 10 source simulations a fit, under the default 16, so without the drive's fine stage
# (search._fine; 55 evaluations against 257, 5.7 s less of CPU): the bearing still scores 30x under the drive, the load
# read within 0.1 %. The drive test keeps the default search, its fine stage scored with the load profiled out
BUDGET = 10


pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")  # the simulator's accuracy warnings on odd parameters


def test_the_load_is_a_scale_of_the_rows_and_its_factor_is_read_off_them():
    source = B6.with_(effects=NOISE)
    at = source.with_(load_nm=0.6 * source.load_nm)
    X, Y = offset_removed(source_rows(source)), offset_removed(source_rows(at))
    assert np.allclose(Y, 0.6 * X, rtol=0, atol=1e-3 * np.abs(X).max())  # the same noise seeds: a scale
    assert level.factor(level.leveling(Y), X) == pytest.approx(0.6, rel=1e-3)
    leveled = Rows(load=level.factor(level.leveling(Y), X))
    assert np.allclose(leveled(source), Y, rtol=0, atol=1e-3 * np.abs(Y).max())


def test_a_drive_at_another_load_is_named_with_the_load_factor():
    """eight_dof (six_dof + the thesis's drive) at 0.6 of the source's load: the drive is named, not a
    stand-in, and the corrected source carries the load (load_level)."""
    target = healthy_rows(
        build_dataset(dataset_preset("B-8-ch5").with_(faults=(), healthy=16, effects=NOISE, seed=21, load_nm=12.0))
    )
    source = B6.with_(effects=NOISE)
    candidates = ("drive_inertias", "bearing_stiffness", "fillet_correction")
    settings = Settings(candidates=candidates, max_effects=1, budget=16, seed=0, **SMALL)
    result = diagnose(source, target, settings)
    assert [e["name"] for e in result["effects"]] == ["drive_inertias"]
    assert result["load"]["factor"] == pytest.approx(0.6, rel=0.03)
    fixed = corrected_source(source, result)
    assert [name for name, _ in fixed.effects] == ["drive_inertias", "load_level", "sensor_noise"]


def test_a_bearing_at_another_load_is_not_explained_by_the_drive():
    """A softer bearing (k_factor 0.5, c_factor 0.6) at 1.4 x the source's load: the bearing is named, not
    the drive, which moves the level itself and was credited with the load where it alone read its own
    factor (development trial 1327/10: the drive named for a bearing, mmd 73.6 -> 52.1 on the corrected
    source); the load is profiled out of every candidate's score alike."""
    bearing = effect_spec("bearing_stiffness", k_factor=0.5, c_factor=0.6)
    source = B6.with_(effects=NOISE)
    target = healthy_rows(build_dataset(source.with_(effects=(bearing,) + NOISE, seed=21, load_nm=28.0)))
    candidates = ("drive_inertias", "bearing_stiffness", "fillet_correction")
    settings = Settings(candidates=candidates, max_effects=1, budget=BUDGET, seed=0, **SMALL)
    result = diagnose(source, target, settings)
    # main before: the drive won round 1 (49,210 against the bearing's 78,815), the load read 0.47; at BUDGET the
    # bearing 1,878 against the drive's 59,686, the load 1.400 (the load unread: the drive 64,971, the bearing 127,054)
    assert result["rounds"][0]["best"] == "bearing_stiffness"
    assert [e["name"] for e in result["effects"]] == ["bearing_stiffness"]
    assert result["load"]["factor"] == pytest.approx(1.4, rel=0.03)


def test_no_load_fit_where_the_scenario_names_load_level_or_the_target_is_measured():
    assert level.fitted_here(B6, ("drive_inertias",), None)
    assert not level.fitted_here(B6, ("drive_inertias", "load_level"), None)
    assert not level.fitted_here(B6.with_(effects=(effect_spec("load_level", factor=2.0),)), (), None)
    assert not level.fitted_here(B6, ("drive_inertias",), object())


def test_the_drive_search_covers_load_modes_and_damping_and_refuses_what_cannot_settle():
    """drive_inertias' guesses are a grid of load modes f_L and damping ratios; a searched model that
    settles on more than SETTLE_MOST revolutions is refused before it is simulated (a development fit,
    slowest mode 2.8 1/s, passed the search and failed the corrected source's crack records: issue 37)."""
    from gearlab.errors import GearlabInputError
    from gearlab.gap.search import settles
    from gearlab.registry import get_registry

    drive = get_registry().get("effect", "drive_inertias")
    guesses = drive.guesses(None, 30.0)
    modes = sorted({round(np.sqrt(g["k_c"] / g["I22"]) / (2 * np.pi)) for g in guesses})
    zetas = sorted({round(g["c_c"] / (2 * np.sqrt(g["k_c"] * g["I22"])), 3) for g in guesses})
    assert modes[0] == 30 and modes[-1] == 3000 and len(modes) >= 10 and zetas == [0.1, 0.5, 2.0]
    for g in guesses:
        settles(B6.with_(effects=(effect_spec("drive_inertias", **{**asdict(drive.params()), **g}),)))
    with pytest.raises(GearlabInputError, match="settles on"):
        settles(B6.with_(effects=(effect_spec("drive_inertias", I11=3.3, I22=0.055, k_c=1.74e5, c_c=1.25),)))


def test_on_a_pure_load_change_the_score_is_least_at_the_load():
    """The factor the effects settle beside (level.best_factor: where the search's score is least, the
    rows scaled) is the load itself on a target that is the source at 0.6 of its load, other noise
    seeds; the closed form (what a drive's sets are read at) agrees."""
    from gearlab.gap.diagnose import _prepared
    from gearlab.gap.scoring import Scorer

    source = B6.with_(effects=NOISE)
    target_X = healthy_rows(build_dataset(source.with_(load_nm=0.6 * source.load_nm, seed=21)))
    settings = Settings(candidates=("bearing_stiffness",), **SMALL)
    target, _, rows, settings, pair, search, _ = _prepared(source, target_X, settings, None)
    scorer = Scorer(target, pair, settings.max_order, rows.consecutive)
    X = rows(search)
    c = Scorer(target, pair, settings.max_order, rows.consecutive, level.bounds()).load_factor(X)
    assert c == pytest.approx(0.6, rel=0.01)
    assert scorer.score(c * X) < min(scorer.score(0.97 * c * X), scorer.score(1.03 * c * X))
    assert level.factor(level.leveling(target), X) == pytest.approx(c, rel=0.01)


def test_the_score_of_each_factor_is_read_off_the_rows_once():
    """Scorer.at_factor (the score of c times the rows, from their features read once: what the profile
    searches) is the score of the scaled rows; a free scorer scores the rows at their best factor."""
    from gearlab.gap.diagnose import _prepared
    from gearlab.gap.scoring import Scorer

    source = B6.with_(effects=NOISE)
    hidden = (effect_spec("bearing_stiffness", k_factor=0.58, c_factor=0.61),)
    target_X = healthy_rows(build_dataset(source.with_(effects=hidden + NOISE, load_nm=14.8, seed=21)))
    target, _, rows, settings, pair, search, _ = _prepared(source, target_X, Settings(**SMALL), None)
    scorer = Scorer(target, pair)
    X = rows(search)
    at = scorer.at_factor(X)
    for c in (0.3, 0.74, 1.0, 2.5):
        assert at(c) == pytest.approx(scorer.score(c * X), rel=1e-9)
    free = Scorer(target, pair, free_load=level.bounds())
    c = free.load_factor(X)
    assert free.score(X) == pytest.approx(scorer.score(c * X), rel=1e-12)
    assert free.score(X) <= min(at(0.97 * c), at(1.03 * c), at(0.74))


def test_a_bearing_keeps_its_damping_with_the_load_profiled_out():
    """A bearing target behind a 7.1 kHz sensor resonance at 0.74 of the source's load (as development
    trial 902/4 of the transfer benchmark), its effects re-fitted with the load profiled out of every
    score (level.free: each set at its own best factor): the bearing's damping stays where it is and
    the factor read beside them is the load. Read in closed form beside every point of the search, the
    factor moved with the bearing's parameters (902/4: c_factor 0.23 for 0.61)."""
    from gearlab.gap.diagnose import _as_tuple, _prepared
    from gearlab.gap.scoring import Scorer, _by_level
    from gearlab.gap.search import fit_effect

    hidden = (
        effect_spec("bearing_stiffness", k_factor=0.58, c_factor=0.61),
        effect_spec("sensor_bandwidth", f_n=7130.0, zeta=0.27),
    )
    source = B6.with_(effects=NOISE)
    # the target's noise before its resonance, as the source's noise comes before a fitted one: the truth
    # is then a point of the search (after it, the resonance stood in elsewhere: 11 kHz, zeta 1, factor 1.49)
    target_X = healthy_rows(build_dataset(source.with_(effects=_by_level(NOISE + hidden), load_nm=14.8, seed=21)))
    settings = Settings(candidates=("bearing_stiffness", "sensor_bandwidth"), healthy=16, budget=16, seed=0)
    target, _, rows, settings, pair, search, _ = _prepared(source, target_X, settings, None)
    rows = level.free(rows)
    fitted = _as_tuple(fit_effect((search, None, hidden, target, settings, 0, False, rows))["accepted"])
    scorer = Scorer(target, pair, settings.max_order, rows.consecutive, rows.free_load)
    c = scorer.load_factor(rows(search.with_(effects=_by_level(search.effects + fitted))))
    assert c == pytest.approx(0.74, rel=0.05)
    assert dict(fitted[0][1])["c_factor"] == pytest.approx(0.61, rel=0.05)


def test_the_report_says_the_load_the_correction_carries_and_the_one_its_figures_use():
    """The reports' rows are held at the factor read beside every fitted effect (read[0]); where an
    effect was taken back the corrected source carries the one read beside the kept effects (read[-1]).
    The note and the record name the carried factor, and the reports' beside it where they differ."""
    effects = [["drive_inertias", [["I11", 0.01], ["I22", 0.01], ["c_c", 5.0], ["k_c", 1e4]]]]
    two = level.carried({"notes": [], "corrected_effects": list(effects)}, [2.9, 3.12])
    assert two["load"] == {"factor": 3.12, "report": 2.9, "read": [2.9, 3.12]}
    assert two["corrected_effects"][-1] == ["load_level", [["factor", 3.12]]]  # what the corrected source runs at
    (note,) = two["notes"]
    assert "fitted with the effects: 3.12 x the source's" in note and "compare at 2.9 x" in note
    one = level.carried({"notes": [], "corrected_effects": list(effects)}, [0.62])
    assert one["load"]["factor"] == one["load"]["report"] == 0.62 and "compare at" not in one["notes"][0]
    # within LOAD_DIFFERS of the source's own load: 1 held, nothing carried
    own = level.carried({"notes": [], "corrected_effects": list(effects)}, [1.02, 0.6])
    assert own["load"]["report"] == 1.0 and own["corrected_effects"][-1] == ["load_level", [["factor", 0.6]]]
