"""--quick's profile of the fitted parameters: a limited number of score evaluations (the profile
ran 488 simulations for a three-stage box's casing under --quick, 7 of a 10-minute run, where its fit
had taken 12), no effect on a run at the default budget, and a line whose ETA holds when the last fit
runs alone (it said 0:34 for 5 minutes)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from gearlab.gap import search, tally
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


def test_the_eta_holds_when_the_last_fit_runs_alone():
    # three fits on two workers: 4 evaluations/s while two run, then 1/s for the casing alone
    most, clock, n = 200, 0.0, 0
    left = tally.Left(most, clock)
    said = []
    while n < most:
        clock += 1.0
        n += 4 if clock <= 20 else 1
        said.append((clock, left.left(min(n, most), clock)))
    end = clock
    # after the rate dropped, within a window the ETA is that of the last fit's rate, within 10 %
    for t, eta in said:
        if t >= 20 + tally.RATE_WINDOW_S:
            assert eta == pytest.approx(end - t, rel=0.10, abs=2.0)
    # the line says the bound and the rate
    assert "of at most 200 evaluations" in left.line(most, end) and "ETA ≤" in left.line(most, end + 1)
    assert tally.Left(10, 0.0).line(0, 0.0) == "fitting: 0 of at most 10 evaluations"
