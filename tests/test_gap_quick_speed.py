"""--quick's profile of the fitted parameters: a limited number of score evaluations (the profile
ran 488 simulations for a three-stage box's casing under --quick, 7 of a 10-minute run, where its fit
had taken 12), and no effect on a run at the default budget."""

from __future__ import annotations

import math
from dataclasses import replace

from gearlab.gap import search
from gearlab.gap.identify import profile
from gearlab.gap.scoring import Settings
from gearlab.settings import shrunk


class _Casing:
    """A space like casing_path's: five continuous parameters (log scales)."""

    def space(self):
        return [
            {"name": n, "low": 1e-2, "high": 1e4, "default": 1.0, "integer": False, "log": True}
            for n in ("m", "k_x", "k_y", "c_x", "c_y")
        ]


def _counted(calls: list):
    def score(p) -> float:  # a narrow valley in every parameter: each profile point needs its polish
        calls.append(p)
        return 1e4 * sum(math.log(v / 3.0) ** 2 for v in p.values())

    return score


def test_quick_limits_the_profile_and_the_default_budget_does_not():
    space = search.Space(_Casing())
    quick = shrunk(Settings())
    most = search.quick_profile_evaluations(space, quick)
    assert most == search.QUICK_PROFILE_EVALS * quick.budget * (space.dims + 1)
    assert search.quick_profile_evaluations(space, Settings()) is None
    assert search.quick_profile_evaluations(space, replace(Settings(), budget=32)) is None

    start = {n: 2.0 for n in ("m", "k_x", "k_y", "c_x", "c_y")}
    free: list = []
    unlimited = profile(space, _counted(free), lambda p: 1.0, dict(start), 0, {})
    assert unlimited["evaluations"] > most  # what the limit saves (distant starts, polish, passes)
    calls: list = []
    out = profile(space, _counted(calls), lambda p: 1.0, dict(start), 0, {}, distant=False, evaluations=most)
    assert len(calls) <= most and out["evaluations"] == len(calls)
    # what it returns is still a profile: the best point seen, intervals and marks for every parameter
    assert out["score"] <= out["score_fit"] and set(out["intervals"]) == set(start)
    assert set(out["determined"]) == set(start)


def test_a_limit_above_what_the_profile_takes_changes_nothing():
    space = search.Space(_Casing())
    start = {n: 2.0 for n in ("m", "k_x", "k_y", "c_x", "c_y")}
    free = profile(space, _counted([]), lambda p: 1.0, dict(start), 0, {})
    capped = profile(space, _counted([]), lambda p: 1.0, dict(start), 0, {}, evaluations=10**6)
    assert capped == free
