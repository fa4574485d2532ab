"""The target's load level, profiled out of every score of a gap diagnosis (docs/gap.md, "The load").

A simulated target may run at another load torque than the source (the transfer benchmark draws
10-30 N m against the source's 20), and in the lumped model every vibration the mesh excites grows
in proportion to the load (the static mesh deflection is T_l / (R_b k); friction follows the mesh
load; noise and a tone are set relative to the signal's RMS): a load factor c is a scale of the
source's rows, exact in the linear model. Left out, a candidate was credited with the scale: on a
development target at 0.61 of the source's load with motor and load inertias, the true effects
scored 1,387 and a fillet stand-in 220, the truth 0.45 at the true factor; the fillet was named.

So where the target's level differs (:func:`level_differs`), the factor is a nuisance profiled out of
every score the diagnosis takes of a source set: the search's points, the baselines, the acceptance
tests, the profiles (gearlab.gap.scoring.Scorer.load_factor: the set scored at the factor within the
bounds where its score is least, the rows scaled, no simulation), so every candidate gets the same
freedom in level, a drive (which moves the level itself) no more than a bearing. The factor read
beside the accepted effects is the load; the reports after (conclusion) hold it, and the corrected
source carries it as the ``load_level`` effect. The plain source's report (before) and the structure
check keep the source's own load. Not fitted for a measured target (there a scale is the sensor's
sensitivity and gain: gearlab.gap.structure's "level differs"), nor where the scenario names
``load_level`` itself (a candidate then) or the source already carries it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..registry import get_registry

LOAD = "load_level"


def bounds() -> tuple[float, float]:
    """load_level's factor bounds: the range a fitted factor is held to."""
    entry = next(e for e in get_registry().get("effect", LOAD).space() if e["name"] == "factor")
    return float(entry["low"]), float(entry["high"])


def fitted_here(source, candidates, chain) -> bool:
    """Whether a diagnosis fits the target's load (module docstring)."""
    if chain is not None or LOAD in candidates or any(e[0] == LOAD for e in source.effects):
        return False
    return LOAD in get_registry().names("effect")


def _lines(X: np.ndarray) -> np.ndarray:
    """The power of each order line of the rows' synchronous average, its noise taken out: |mean|^2
    less the variance of the mean (unbiased; the magnitude of a noisy average reads high, and a
    factor 0.2 % high scored the true effects 3.1 against 0.45 on a development target at -3 dB)."""
    F = np.fft.rfft(np.asarray(X, dtype=np.float64), axis=1)[:, 1:]
    n = len(F)
    return np.abs(F.mean(axis=0)) ** 2 - (F.var(axis=0) / n if n > 1 else 0.0)


def leveling(target: np.ndarray) -> tuple:
    """The target's order lines (:func:`_lines`) and the factor's bounds: what :func:`factor` reads."""
    return (tuple(_lines(target).tolist()), *bounds())


def factor(level: tuple, X: np.ndarray) -> float:
    """The load factor c that brings rows *X* onto the target (*level*: :func:`leveling`), within
    bounds: least squares of the target's line powers on c^2 times the source's, which weighs the
    source's strong lines (the mesh harmonics, which the score resolves finest)."""
    lines, low, high = level
    S = _lines(X)
    denominator = float(np.sum(S * S))
    c2 = float(np.sum(np.asarray(lines) * S)) / denominator if denominator > 0 else 1.0
    return min(max(math.sqrt(c2), low), high) if math.isfinite(c2) and c2 > 0 else 1.0


# The load is profiled where the plain source's factor is this far from 1 or more, and held where the one
# read beside the accepted effects is (:func:`own_or`): at the source's own load
# (tests' targets made from the source: 0.98-1.02) a free scale beside every candidate absorbed what a
# candidate left (a fillet 3 % off read "explained") and reordered the ranking; the transfer benchmark's
# loads (10-30 N m against 20) mostly lie farther off.
LOAD_DIFFERS = 0.05


def level_differs(level: tuple, X: np.ndarray) -> bool:
    """Whether the plain source's rows *X* stand LOAD_DIFFERS or more off the target's level (*level*)."""
    return abs(math.log(factor(level, X))) >= math.log1p(LOAD_DIFFERS)


def own_or(c: float) -> float:
    """The load a diagnosis holds for the factor *c* read beside its effects: the source's own (1) where
    *c* lies within LOAD_DIFFERS of it (a fillet 3 % off at the source's load read "explained" beside
    its factor), else *c*."""
    return 1.0 if abs(math.log(c)) < math.log1p(LOAD_DIFFERS) else c


def free(rows):
    """*rows* (a gearlab.gap.scoring.Rows) for the rounds: made at the source's load, each set scored at
    its own best load factor within the bounds (module docstring)."""
    return replace(rows, load=None, free_load=bounds())


def held(rows, c: float):
    """*rows* at the load factor *c* read beside the accepted effects: what the reports after compare."""
    return replace(rows, load=c, free_load=None)


# Why a profile (the factor where each set's score is least), not the closed form (:func:`factor`, the
# least squares of the order lines) beside every set: the closed form is not where the score is least
# (0.54, 0.50, 0.36, 0.30 on a bearing target at 0.74), and read afresh at every point of a search it
# traded against the parameters (development trial 902/4, a bearing behind a 7.1 kHz resonance at 0.74 of
# the load: resonance at 6.4 kHz, bearing c_factor 0.23, k_factor 0.24 for 0.61, 0.58; 155 on the
# search's rows, the truth 0.4): profiled, every point is scored at the factor where its own score is least.
# Why every set, not only a drive's: a drive read at its own factor and the other candidates at the
# source's load favoured the drive wherever the load differs (1327/10: drive named for a bearing, mmd
# 52.1 on the corrected source against 73.6 on the plain); a factor fitted alone first and held took the
# model effect's own level too (read/true 2.31/1.41 on 1327/20) and searched every candidate at it.
# The grid (GRID_POINTS, log-spaced over the bounds) guards the bounded search against a local minimum.
GRID_POINTS = 25


def best_factor(score_at, bounds_: tuple[float, float]) -> float:
    """The factor c within *bounds_* at which *score_at*(c) is least: a log-spaced grid, then a bounded
    search on log c between the best grid point's neighbours."""
    from scipy.optimize import minimize_scalar

    grid = np.linspace(math.log(bounds_[0]), math.log(bounds_[1]), GRID_POINTS)
    values = [score_at(math.exp(u)) for u in grid]
    i = int(np.argmin(values))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, GRID_POINTS - 1)]
    found = minimize_scalar(lambda u: score_at(math.exp(u)), bounds=(lo, hi), method="bounded", options={"xatol": 1e-4})
    return float(math.exp(found.x)) if found.fun <= values[i] else float(math.exp(grid[i]))


def load_entry(c: float, report: float, read: list[float]) -> tuple[tuple, dict]:
    """The load_level effect (canonical) the corrected source carries for the factor *c*, and the
    diagnosis's record of it: ``factor`` (*c*), ``report`` (the factor the reports' figures compare at)
    and ``read`` (the factors read beside the accepted effects, then the kept ones)."""
    return get_registry().get("effect", LOAD).spec({"factor": c}), {"factor": c, "report": report, "read": read}


def load_note(c: float, report: float) -> str:
    """The report's line on the load: the factor the corrected source carries (*c*) and, where the
    reports' figures compare at another (*report*: read beside an effect since taken back), that one."""
    out = (
        f"the target's load fitted with the effects: {c:.3g} x the source's (the vibration scales "
        "with it); the corrected source carries it as load_level"
    )
    if report != c:
        out += f"; the report's gap and shares compare at {report:.3g} x, read beside every fitted effect"
    return out


# Another round while the search's score left by the round's fit stands this many of its noise widths
# (the bootstrap spread of the score there) over zero, though the report sees no gap beyond its noise
# width: on development targets with a drive and a sensor filter, round 1's drive left 62-270 on the
# search's rows (noise 3-8), the filter beside it 0.5-1; the report's width stopped the loop there.
# Set on development trials (seeds 900-904).
SCORE_WIDTHS = 5.0


def score_stands(fit: dict, room: bool) -> bool:
    """Whether the diagnosis goes on to another round for what the round's winner *fit* left on the
    search's rows (SCORE_WIDTHS); *room*: a round is left (max_effects)."""
    noise = fit.get("noise")
    return bool(room and noise and math.isfinite(fit["score"]) and fit["score"] > SCORE_WIDTHS * noise)


def carried(result: dict, read: list[float]) -> dict:
    """*result* (a diagnosis's conclusion) with the load its effects were fitted beside (*read*: the
    factors read beside every accepted effect, which hold the reports' rows, then beside the kept ones,
    where needed_effects took one back): ``load``, a note that says the factor the corrected source
    carries and, where it differs, the one the reports' figures compare at, and
    ``load_level`` in the corrected source where it has effects and the factor is not 1 (the source's
    own: :func:`own_or` holds 1 within LOAD_DIFFERS)."""
    c, report = own_or(read[-1]), own_or(read[0])
    effect, result["load"] = load_entry(c, report, read)
    result["notes"].append(load_note(c, report))
    if result.get("corrected_effects") and c != 1.0:
        result["corrected_effects"] = [*result["corrected_effects"], [effect[0], [list(kv) for kv in effect[1]]]]
    return result
