"""Whether the data pin each fitted parameter: a profile along every one (docs/gap.md, "Identifiability").

The search's intervals bracket the points it happened to visit around the minimum it found. Where
two parameters trade off -- a resonance's mass and stiffness, whose ratio sets its frequency; a
load inertia far above the gear's, which a stiff coupling makes invisible -- every visited point
off the valley scores worse, so the bracket is narrow and the value reads "determined" although a
distant one fits as well (a casing mass found 5x off, a load inertia 650x off, both "determined").

A profile asks the question directly. With the other accepted effects held at their fitted values
and the score the search used (common random numbers, so a deterministic function of the
parameters), first a second fit from distant starts (a Latin hypercube, local fits from the best
distant points: the search's budget can stop in a wrong basin), then for each continuous
parameter x_j of the effect, around the best point seen:

1. the score's Hessian H by finite differences HESSIAN_STEP apart on the unit cube (1 + 2d +
   d(d - 1) points) gives the direction along which the other parameters follow x_j at least
   cost, v_o = -H_oo⁺ H_oj (the valley: for log-scaled mass and stiffness, a straight line in the
   search's coordinates);
2. x_j moved PROFILE_DISTANCES of its range to each side (the others started on that line, or
   held, whichever scores lower), then the others re-fitted locally (PROFILE_POLISH evaluations
   per coordinate);
3. a profile point whose score lies within the score's noise of the best (the bootstrap spread the
   search's intervals use) is a distant value that fits as well: it widens x_j's interval -- and
   those of the parameters that moved with it -- past DETERMINED_WIDTH, so x_j reads "not
   identifiable". The move itself says what the data do determine: x_k x_j^(-δ_k/δ_j) for a pair
   that moved together (δ the changes of ln x), e.g. k/m for a resonance whose frequency √(k/m) is
   pinned; a parameter that moved alone does not act on these revolutions at all.

A profile point that scores *lower* than the fit (the search stopped in a local minimum) is taken
as the fit, and profiled around again (PASSES). A fit that stays more than FIT_SIGMAS noise widths
above 0 -- what a right model scores, the score being bias-corrected -- leaves a gap: none of its
parameters is called determined ("fit leaves a gap"). Whole-number parameters keep the search's
intervals (a filter's order is already profiled value by value,
gearlab.gap.search._ordinal_profile); text options stay fixed.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable

import numpy as np

HESSIAN_STEP = 0.01  # unit-cube step of the quadratic model's stencil
# Where x_j is moved, in shares of its searched range (unit cube), each side: half the interval width
# that still reads "determined", then all of it (DETERMINED_WIDTH = 0.25).
PROFILE_DISTANCES = (0.125, 0.25)
PROFILE_POLISH = 3  # local re-fit evaluations per other coordinate at a profile point
DIRECTION_CAP = 4.0  # the valley's slope, capped: a near-flat H_oo must not throw the start across the cube
# The distant starts: design points per free coordinate, local fits from the best distant ones, and
# their evaluations per free coordinate.
STARTS_PER_COORDINATE, DISTANT_FITS, DISTANT_EVALS = 6, 2, 6
REFIT_EVALS = 10  # a local fit of every coordinate from a better point, evaluations per coordinate
# A parameter moved with x_j when its change of ln x is at least this share of the largest.
SIGNIFICANT_MOVE = 0.2
FIT_SIGMAS = 3.0  # a fit this many noise widths above 0 leaves a gap: no parameter of it is determined
PASSES = 3  # profiles around a better point found by the last one, at most
# A phase the record sees only up to whole tooth pitches (Effect.pitch_aliases, alias_refit): the
# scan's step within one alias period, the local fits from the best aliases, their evaluations, and
# their first simplex (the phase in radians; the other continuous parameters as a share of their value).
ALIAS_SCAN_STEP = math.radians(0.5)
ALIAS_FITS, ALIAS_EVALS = 3, 24
ALIAS_BRACKET, ALIAS_BRENT = math.radians(3.0), 8
ALIAS_SIMPLEX_PHASE, ALIAS_SIMPLEX_SHARE = math.radians(0.5), 0.02


# A parameter is "determined" when its interval spans at most this share of its searched range.
DETERMINED_WIDTH = 0.25
# A local fit (re-fits of accepted effects, an ordinal profile's, the profile's) starts from a simplex
# LOCAL_STEP wide (unit cube); one of a single coordinate is a bounded Brent search LOCAL_BRACKET either side.
LOCAL_STEP, LOCAL_BRACKET = 0.05, 0.1


# The reason a parameter is not determined where --quick's limited profile ended before reaching it.
CUT_SHORT = "not profiled (--quick)"


class _OutOfBudget(Exception):
    pass


def _local(space, evaluate, u0: np.ndarray, choice: tuple, free: list[int], evaluations: int) -> dict:
    """A short Nelder-Mead over the coordinates *free* from *u0*, the others held: the best point
    it saw (u0 included), as a history entry."""
    from scipy.optimize import minimize

    found = {"u": u0.copy(), "choice": choice, "score": math.inf}

    def at(v) -> float:
        u = u0.copy()
        u[free] = np.clip(v, 0.0, 1.0)
        value = evaluate(u, choice)
        if value < found["score"]:
            found.update(u=u, score=value)
        return value

    try:
        at(u0[free])
        if len(free) == 1 and evaluations > 1:
            # one coordinate: Brent's parabolas converge on a valley where a simplex crawls
            from scipy.optimize import minimize_scalar

            x = float(u0[free[0]])
            minimize_scalar(
                lambda v: at(np.array([v])),
                bounds=(max(0.0, x - LOCAL_BRACKET), min(1.0, x + LOCAL_BRACKET)),
                method="bounded",
                options={"maxiter": evaluations - 1, "xatol": 1e-5},
            )
        elif free and evaluations > 1:
            simplex = [u0[free]] + [
                u0[free]
                + np.where(np.arange(len(free)) == i, LOCAL_STEP if u0[j] + LOCAL_STEP <= 1 else -LOCAL_STEP, 0)
                for i, j in enumerate(free)
            ]
            minimize(
                at,
                u0[free],
                method="Nelder-Mead",
                bounds=[(0.0, 1.0)] * len(free),
                options={"maxfev": evaluations - 1, "initial_simplex": np.array(simplex), "xatol": 1e-4, "fatol": 0.0},
            )
    except _OutOfBudget:
        pass
    return {**found, "params": space.params(found["u"], choice)}


def _intervals(space, history: list[dict], best: dict, noise: float) -> dict:
    """Per numeric parameter: the bracket of every evaluated value within *noise* of the best
    score, out to the nearest evaluated value outside it on each side (or the bound; a refused
    point, scored inf, bounds nothing); a whole number's is the values within it."""
    out = {}
    threshold = best["score"] + noise
    for e in space.numbers:
        name = e["name"]
        inside = [h["params"][name] for h in history if h["score"] <= threshold]
        # a point scored inf was refused (the simulator cannot take it): no evidence either way
        outside = [h["params"][name] for h in history if threshold < h["score"] < math.inf]
        lo_in, hi_in = min(inside), max(inside)
        if e["integer"]:
            # Whole numbers: the values outside were evaluated and are worse; nothing lies between
            # (extended to them, a filter's order found exactly at 3 read [2, 4], "not identifiable").
            out[name] = [float(lo_in), float(hi_in)]
            continue
        below = [x for x in outside if x < lo_in]
        above = [x for x in outside if x > hi_in]
        out[name] = [float(max(below)) if below else float(e["low"]), float(min(above)) if above else float(e["high"])]
    return out


def determined(space, intervals: dict) -> dict:
    """Per numeric parameter: whether the data determine it -- its interval spans at most
    DETERMINED_WIDTH of the searched range (on the search's own scale: log where the effect says
    so). A wider one is "not identifiable" from these revolutions: an honest answer, and its
    fitted value should not be read as a measurement."""
    out = {}
    for e in space.numbers:
        lo, hi = intervals.get(e["name"], (e["low"], e["high"]))
        width = abs(space.unit(e, hi) - space.unit(e, lo)) if e["high"] > e["low"] else 0.0
        out[e["name"]] = {"width": float(width), "determined": bool(width <= DETERMINED_WIDTH)}
    return out


def _plain(params: dict) -> dict:
    return {
        k: (v if isinstance(v, str) else int(v) if isinstance(v, numbers.Integral) else float(v))
        for k, v in params.items()
    }


def profile(
    space,
    score: Callable[[dict], float],
    noise_of: Callable[[dict], float],
    params: dict,
    seed,
    prior,
    distant: bool = True,
    evaluations: int | None = None,
) -> dict:
    """Profile the parameters *params* of an effect's *space* under *score* (deterministic; lower is
    better) whose noise at a point is *noise_of*; *prior*: the search's intervals (kept for whole
    numbers). *distant*: start with the second fit from distant starts (False where the search's fine
    stage, :func:`refine`, has made it on the same score). *evaluations*: at most that many scores
    (None: no limit; --quick's, gearlab.gap.search.quick_profile_evaluations): the profile stops
    where they run out, and a parameter it did not reach keeps the interval its points give. Returns
    the best parameters seen (the fit, or a better point), their score, the fit's score, the noise,
    whether the fit leaves a gap, intervals, ``determined`` marks (with the reason where not) and
    ``combinations`` (what the data determine where a parameter is not)."""
    u0, choice = space.point_of(params)
    history: list[dict] = []
    seen: dict = {}

    def evaluate(u, choice=choice) -> float:
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        params = space.params(u, choice)
        key = tuple(sorted((k, v if isinstance(v, str) else float(v)) for k, v in params.items()))
        if key in seen:
            return seen[key]
        if evaluations is not None and len(history) >= evaluations:
            raise _OutOfBudget
        value = score(params)
        seen[key] = value
        history.append({"u": u.copy(), "choice": choice, "params": params, "score": value})
        return value

    score0 = evaluate(u0)
    free = [j for j, e in enumerate(space.numbers) if not e["integer"] and e["high"] > e["low"]]
    paths: dict[int, list[dict]] = {}
    reached: list[int] = []  # the coordinates the last pass profiled to both sides
    noise = noise_of(space.params(u0, choice))
    cut = False
    try:
        if free:
            start = _distant_starts(space, evaluate, history, u0, choice, free, seed) if distant else u0
            for _ in range(PASSES):  # around the best point; again if the profile found a lower one
                if not np.array_equal(start, u0):  # a new basin: a local fit of every coordinate first
                    u0 = _local(space, evaluate, start, choice, free, REFIT_EVALS * len(free))["u"].copy()
                noise = noise_of(space.params(u0, choice))
                paths, reached = {}, []
                _profile(space, evaluate, history, u0, choice, free, noise, paths, reached)
                best = min(history, key=lambda h: h["score"])
                if best["score"] >= evaluate(u0) - noise:
                    break
                start = best["u"].copy()
    except _OutOfBudget:  # --quick's evaluations ran out: what the points so far give
        cut = True
    params0 = space.params(u0, choice)

    best = min(history, key=lambda h: h["score"])
    intervals = _intervals(space, history, best, noise)
    for e in space.numbers:  # whole numbers: the search's own profile, widened to the value kept
        if e["integer"] or e["high"] == e["low"]:
            value = float(best["params"][e["name"]])
            lo, hi = prior.get(e["name"], (value, value))
            intervals[e["name"]] = [min(lo, value), max(hi, value)]
    marks = determined(space, intervals)
    # A right model scores 0 within its noise (the score is bias-corrected). A fit that stays FIT_SIGMAS
    # noise widths above it is a compromise of a model that does not match: its values are pinned only
    # given that model (a load inertia's plateau: 242 against a noise of 27 where the truth scores 1).
    gap_left = best["score"] > FIT_SIGMAS * noise
    for mark in marks.values():
        mark["reason"] = "fit leaves a gap" if gap_left else None if mark["determined"] else "profile"
        mark["determined"] = mark["determined"] and not gap_left
    for j in free if cut and not gap_left else ():
        if j not in reached:  # only the search's neighbourhood: it read a valley as steep (module doc)
            marks[space.numbers[j]["name"]].update(determined=False, reason=CUT_SHORT)
    return {
        "params": _plain(best["params"]),
        "score": best["score"],
        "score_fit": score0,
        "noise": noise,
        "gap_left": gap_left,
        "intervals": intervals,
        "determined": marks,
        "combinations": _combinations(space, params0, paths, marks, noise, best["score"]),
        "evaluations": len(history),
    }


def pitch_alias_period(order: int, teeth: int) -> tuple[float, int]:
    """The phase step between a shaft-order-*order* ripple's tooth-pitch aliases on a gear of *teeth*
    teeth, and how many distinct aliases there are: phi + 2 pi order j / teeth (j = 0 .. teeth - 1)
    are the multiples of 2 pi g / teeth, g = gcd(order, teeth), teeth / g of them."""
    g = math.gcd(int(order), int(teeth))
    return 2.0 * math.pi * g / teeth, teeth // g


def alias_refit(space, score: Callable[[dict], float], params: dict, phase: str, order: str | int, teeth: int) -> dict:
    """The best of a shaft-locked ripple's tooth-pitch aliases (Effect.pitch_aliases): a revolution
    turned by j tooth pitches is the same mesh, so the phase phi and phi + 2 pi q j / Z1 differ only
    by a few percent of the revolution once the tacho offset (a free rotation) is fitted, and the
    score's valley around the true phase is narrow (a 3 % order-2 speed ripple on Dataset B: 5 at the
    truth, 125-145 at +-1 deg, 35-430 at the other aliases; a 0.4 % order-4 ripple: 6 at +-5 deg).
    A budgeted search ends at some alias, a few degrees off. Three steps, *score* deterministic:

    1. the phase scanned over one alias period (2 pi gcd(q, Z1) / Z1) around the fit, ALIAS_SCAN_STEP
       apart, the rest held: the within-alias phase, to a few degrees;
    2. at every alias, a bounded Brent search of the phase ALIAS_BRACKET either side of that offset
       (ALIAS_BRENT evaluations): the fit's alias's valley need not lie where the true one's does;
    3. a local Nelder-Mead fit of the phase and the other continuous parameters (the amplitude) from
       each of the ALIAS_FITS best aliases, ALIAS_EVALS evaluations, a simplex ALIAS_SIMPLEX_PHASE and
       ALIAS_SIMPLEX_SHARE of each value wide (a 5 % amplitude error moves the score more than the
       alias does).

    Returns the best point seen (the fit included) as {"params", "score", "evaluations"}."""
    from scipy.optimize import minimize, minimize_scalar

    q = int(params[order]) if isinstance(order, str) else int(order)
    period, count = pitch_alias_period(q, teeth)
    seen: list[tuple[float, dict]] = []
    by_name = {e["name"]: e for e in space.numbers}
    others = [e["name"] for e in space.numbers if not e["integer"] and e["name"] != phase and e["high"] > e["low"]]

    def at(p: dict) -> float:
        p = {**p, phase: float(p[phase]) % (2.0 * math.pi)}
        for name in others:
            p[name] = float(np.clip(p[name], by_name[name]["low"], by_name[name]["high"]))
        value = score(p)
        seen.append((value, p))
        return value

    at(dict(params))
    base = float(params[phase])
    scan = [(at({**params, phase: base + o}), o) for o in np.arange(-period / 2, period / 2, ALIAS_SCAN_STEP)]
    base += min(scan, key=lambda s: s[0])[1]
    # The scan ran on the fit's alias, whose valley need not lie where the true alias's does: each
    # alias gets a bounded Brent search of the phase ALIAS_BRACKET either side (ALIAS_BRENT evaluations).
    ranked = []
    for j in range(count):
        res = minimize_scalar(
            lambda x: at({**params, phase: x}),
            bounds=(base + period * j - ALIAS_BRACKET, base + period * j + ALIAS_BRACKET),
            method="bounded",
            options={"maxiter": ALIAS_BRENT, "xatol": 1e-4},
        )
        ranked.append((float(res.fun), float(res.x)))
    ranked.sort()
    names = [phase] + others
    for _, start in ranked[:ALIAS_FITS]:
        x0 = np.array([start] + [float(params[n]) for n in others])
        steps = [ALIAS_SIMPLEX_PHASE] + [
            ALIAS_SIMPLEX_SHARE * (abs(x) if x != 0 else by_name[n]["high"] - by_name[n]["low"])
            for x, n in zip(x0[1:], others)
        ]
        simplex = np.array([x0] + [x0 + np.eye(len(x0))[k] * steps[k] for k in range(len(x0))])
        minimize(
            lambda x: at({**params, **dict(zip(names, x))}),
            x0,
            method="Nelder-Mead",
            options={"maxfev": ALIAS_EVALS, "initial_simplex": simplex, "xatol": 1e-9, "fatol": 0.0},
        )
    value, best = min(seen, key=lambda s: s[0])
    return {"params": best, "score": value, "evaluations": len(seen)}


def _profile(space, evaluate, history, u0, choice, free: list[int], noise: float, paths: dict, reached: list) -> None:
    """Per free coordinate j: the profile points, out to each side, that fit within the noise of the
    best score seen (the module docstring, steps 1-3), added to *paths* as they come, and j to
    *reached* once both sides are done (a profile that runs out of evaluations keeps what it made)."""
    H = _hessian(evaluate, u0, free)
    for a, j in enumerate(free):
        others = [k for k in free if k != j]
        slope = _valley(H, a)
        for side in (1.0, -1.0):
            previous = None
            for distance in PROFILE_DISTANCES:
                if not 0.0 <= u0[j] + side * distance <= 1.0:
                    break
                if previous is None:
                    start = u0.copy()
                    start[free] = u0[free] + side * distance * slope
                else:  # along the chord through the last point that fitted (a curved valley)
                    start = u0 + (previous["u"] - u0) * (distance / abs(previous["u"][j] - u0[j]))
                start[j] = u0[j] + side * distance
                start = np.clip(start, 0.0, 1.0)
                held = u0.copy()  # the others held: a parameter that acts alone, or not at all
                held[j] = start[j]
                threshold = min(h["score"] for h in history) + noise
                point = min(({"u": u, "score": evaluate(u)} for u in (start, held)), key=lambda p: p["score"])
                if point["score"] > threshold and others:
                    point = _local(space, evaluate, point["u"], choice, others, PROFILE_POLISH * len(others) + 1)
                if point["score"] > threshold:
                    break
                previous = point
                paths.setdefault(j, []).append(point)
        reached.append(j)


def _distant_starts(space, evaluate, history, u0, choice, free: list[int], seed) -> np.ndarray:
    """A second fit from distant starts: a Latin hypercube of STARTS_PER_COORDINATE points per
    coordinate over the free ones, then a local fit from each of the DISTANT_FITS best that lie at
    least DETERMINED_WIDTH from the fit in some coordinate. The search's budget (16 simulations for
    four or five parameters) can stop in a wrong basin: a load inertia at 2.6 kg m² (score 2.5e3)
    where the truth, 3.3e-3, scores 1.0. Returns the point to profile around: the fit, or a distant
    one that scores lower (the best point seen)."""
    from scipy.stats import qmc

    design = qmc.LatinHypercube(d=len(free), seed=np.random.default_rng([*np.atleast_1d(seed), 11])).random(
        STARTS_PER_COORDINATE * len(free)
    )
    points = []
    for row in design:
        u = u0.copy()
        u[free] = row
        points.append((evaluate(u, choice), u))
    distant = [p for p in sorted(points, key=lambda p: p[0]) if np.max(np.abs(p[1] - u0)) >= DETERMINED_WIDTH]
    for _, u in distant[:DISTANT_FITS]:
        _local(space, evaluate, u, choice, free, DISTANT_EVALS * len(free))
    return min(history, key=lambda h: h["score"])["u"].copy()


def _hessian(evaluate, u0: np.ndarray, free: list[int]) -> np.ndarray:
    """The score's Hessian (unit cube) at *u0* by finite differences HESSIAN_STEP wide: central ones
    along each coordinate, h(e_a ± e_b) for each pair (H_ab = [f(a+b) - f(a-b) - 2h g_b] / 2h², g_b
    central). A coordinate that would leave the cube is stepped the other way (a fit at a bound); the
    score is far from quadratic over a step at a sharp resonance, so H serves only to aim the profile's
    first step along a valley (:func:`_valley`), never as an interval."""
    d, h = len(free), HESSIAN_STEP
    side = np.where(u0[free] + h > 1.0, -1.0, 1.0)  # the step of each coordinate that stays inside

    def at(step: np.ndarray) -> float:
        u = u0.copy()
        u[free] = np.clip(u0[free] + step, 0.0, 1.0)
        value = evaluate(u)
        return value if math.isfinite(value) else 1e300

    f0 = at(np.zeros(d))
    plus = [at(side[a] * h * np.eye(d)[a]) for a in range(d)]
    minus = [at(-side[a] * h * np.eye(d)[a]) for a in range(d)]
    g = np.array([(p - m) / (2 * h) for p, m in zip(plus, minus)]) * side
    H = np.diag([(p + m - 2 * f0) / h**2 for p, m in zip(plus, minus)])
    for a in range(d):
        for b in range(a + 1, d):
            ea, eb = side[a] * h * np.eye(d)[a], side[b] * h * np.eye(d)[b]
            H[a, b] = H[b, a] = (at(ea + eb) - at(ea - eb) - 2 * h * side[b] * g[b]) / (2 * h**2) * side[a] * side[b]
    return H


def _valley(H: np.ndarray, a: int) -> np.ndarray:
    """The direction (per unit move of coordinate *a*) along which the others follow it at least
    cost in the quadratic model: 1 for *a*, -H_oo⁺ H_oa for the others (capped)."""
    d = len(H)
    v = np.zeros(d)
    v[a] = 1.0
    o = [b for b in range(d) if b != a]
    if o:
        v[o] = np.clip(-np.linalg.pinv(H[np.ix_(o, o)]) @ H[o, a], -DIRECTION_CAP, DIRECTION_CAP)
    return v


def _combinations(space, params0: dict, paths: dict, marks: dict, noise: float, best: float) -> list[dict]:
    """What the data determine where a parameter is not identifiable, read off its farthest profile
    point that fits within the noise: the factors every parameter moved by, and -- for two that
    moved together -- the product x_k x_j^c (c = -δ_k/δ_j, δ the changes of ln x) that stayed."""
    out, done = [], set()
    for j, points in paths.items():
        e = space.numbers[j]
        if marks[e["name"]]["determined"]:
            continue
        far = points[-1]
        moved = {}
        for other in space.numbers:
            x0, x1 = params0[other["name"]], space.params(far["u"], ())[other["name"]]
            if x0 > 0 and x1 > 0 and not other["integer"]:
                moved[other["name"]] = math.log(x1 / x0)
        largest = max(abs(v) for v in moved.values()) if moved else 0.0
        names = sorted((k for k, v in moved.items() if largest and abs(v) >= SIGNIFICANT_MOVE * largest), key=str)
        if not names or frozenset(names) in done:
            continue
        done.add(frozenset(names))
        entry = {
            "params": names,
            "factors": {k: float(math.exp(moved[k])) for k in names},
            "score": float(far["score"]),
            "within": float(far["score"] - best),
            "noise": noise,
        }
        if len(names) == 1:
            entry["determined"] = None  # it moved alone: these revolutions do not depend on it
        elif len(names) == 2:
            k, m = (e["name"], next(n for n in names if n != e["name"])) if e["name"] in names else names
            c = -moved[m] / moved[k]
            entry["determined"] = f"{m} * {k}^{c:.2f}"
            entry["exponents"] = {m: 1.0, k: float(c)}
            entry["value"] = float(params0[m] * params0[k] ** c)
        else:
            entry["determined"] = None  # several moved together: no single pair to name
        out.append(entry)
    return out
