"""The target's load level, held beside the candidates of a gap diagnosis (docs/gap.md, "The load").

A simulated target may run at another load torque than the source (the transfer benchmark draws
10-30 N m against the source's 20), and in the lumped model every vibration the mesh excites grows
in proportion to the load (the static mesh deflection is T_l / (R_b k); friction follows the mesh
load; noise and a tone are set relative to the signal's RMS): a load factor c is a scale of the
source's rows, exact in the linear model. Left out, a candidate was credited with the scale: on a
development target at 0.61 of the source's load with motor and load inertias, the true effects
scored 1,387 and a fillet stand-in 220, the truth 0.45 at the true factor; the fillet was named.

So the diagnosis's rounds compare a source set with a drive (an effect that moves the level itself,
``moves_level``) at the factor that brings its synchronous-average order lines onto the target's
(least squares, closed form: no simulation, no search parameter; gearlab.gap.scoring.Rows), every
other set at the source's load; after the rounds the factor and the fitted effects settle in turn,
the factor held while the effects are re-fitted (:func:`settled`). The plain source's report (before)
and the structure check keep the source's own load. The corrected source carries the factor as the
``load_level`` effect. Not fitted for a measured target (there a scale is the sensor's sensitivity and
gain: gearlab.gap.structure's "level differs"), nor where the scenario names ``load_level`` itself (a
candidate then) or the source already carries it.
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


# The load is fitted where the plain source's factor is this far from 1 or more, and carried where the
# settled one is (:func:`settled`): at the source's own load
# (tests' targets made from the source: 0.98-1.02) a free scale beside every candidate absorbed what a
# candidate left (a fillet 3 % off read "explained") and reordered the ranking; the transfer benchmark's
# loads (10-30 N m against 20) mostly lie farther off.
LOAD_DIFFERS = 0.05


def level_differs(level: tuple, X: np.ndarray) -> bool:
    """Whether the plain source's rows *X* stand LOAD_DIFFERS or more off the target's level (*level*)."""
    return abs(math.log(factor(level, X))) >= math.log1p(LOAD_DIFFERS)


def moving() -> frozenset:
    """The registered effects that move the vibration's level themselves (``moves_level``: a drive)."""
    registry = get_registry()
    return frozenset(n for n in registry.names("effect") if getattr(registry.get("effect", n), "moves_level", False))


def level_rows(rows, level: tuple):
    """*rows* (a Rows) for the rounds: the source's load held (factor 1), the target's read beside each set
    with an effect that moves the level itself (:func:`moving`)."""
    return replace(rows, load=1.0, level=level, read_beside=moving())


def unleveled(rows):
    """*rows* (a Rows) making the source's rows at its own load."""
    return replace(rows, load=None, read_beside=frozenset())


# Why the factor is not read beside every candidate, and held while the effects settle. Read afresh at every
# point of a search (closed form), it trades against the parameters: a parameter that moves the level
# moves the factor with it, and the score sees the pair. On a development bearing target behind a 7.1 kHz
# sensor resonance at 0.74 of the source's load (transfer benchmark 902/4) the fit so read found the
# resonance at 6.4 kHz and the bearing at c_factor 0.23, k_factor 0.24 (true 7.1 kHz, 0.61, 0.58):
# 155 on the search's rows, where the truth scores 0.4 and reads the true factor, 0.738. Held at the
# plain source's factor instead, a model effect that moves the level is judged at the wrong one: a drive
# target at 0.6 of the load (the thesis's drive alone: 0.59 of the six-DOF lines' scale; plain factor
# 0.36) named no drive, and the close-fillet targets of tests/test_gap_diagnose.py (a fillet moving
# the level 19 % at the source's load) named nothing. Alternated with the closed form, factor and effects
# drifted apart (the closed form is not where the score is least: 0.54, 0.50, 0.36, 0.30 on a bearing
# target at 0.74); the factor where the score is least makes every step of the turns lower the score.
# At most SETTLE_ROUNDS turns, until the factor moves less than LOAD_SETTLES; none where the first lies
# within LOAD_DIFFERS of 1 (a 3 % off fillet at the source's load, the factor free, read "explained").
SETTLE_ROUNDS = 3
LOAD_SETTLES = 0.005


def best_factor(score, X: np.ndarray, bounds_: tuple[float, float]) -> float:
    """The factor c within *bounds_* at which *score*(c * X) is least (bounded search on log c): rows
    scaled, no simulation."""
    from scipy.optimize import minimize_scalar

    lo, hi = math.log(bounds_[0]), math.log(bounds_[1])
    found = minimize_scalar(
        lambda u: score(X * math.exp(u)), bounds=(lo, hi), method="bounded", options={"xatol": 1e-4}
    )
    return float(math.exp(found.x))


def settled(run, fitted: tuple, refit, plain) -> tuple[tuple, list[float], float]:
    """The accepted effects *fitted* and the held load factor (in *run*.rows), in turn: the factor at
    which the search's score is least with the effects held (*plain*(fitted): their search rows at the
    source's load), then held while the effects are re-fitted (*refit*(run, fitted) -> fitted),
    :data:`SETTLE_ROUNDS` times at most: each step lowers the score. Where the effects have one that
    moves the level, the factor read beside them is the load. Returns (the effects, each factor found,
    the load factor)."""
    if any(name in run.rows.read_beside for name, _ in fitted):
        c = factor(run.rows.level, plain(fitted))
        return fitted, [c], c
    read = []
    for _ in range(SETTLE_ROUNDS):
        c = best_factor(run.scorer.score, plain(fitted), run.rows.level[1:])
        read.append(c)
        if len(read) == 1 and abs(math.log(c)) < math.log1p(LOAD_DIFFERS):
            return fitted, read, 1.0  # the source's load (LOAD_DIFFERS)
        moved = abs(math.log(c / run.rows.load)) > math.log1p(LOAD_SETTLES)
        run.rows = replace(run.rows, load=c)
        if not moved:
            break
        fitted = refit(run, fitted)
    return fitted, read, run.rows.load


def load_entry(c: float, read: list[float]) -> tuple[tuple, dict]:
    """The load_level effect (canonical) the corrected source carries for the factor *c*, and the
    diagnosis's record of it (*read*: the factors :func:`settled` read)."""
    return get_registry().get("effect", LOAD).spec({"factor": c}), {"factor": c, "read": read}


def load_note(c: float) -> str:
    return (
        f"the target's load fitted with the effects: {c:.3g} x the source's (the vibration scales "
        "with it); the corrected source carries it as load_level"
    )


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


# Within this of 1 the fitted factor is the source's own load: a target at the source's load, with its
# model, read 0.9986-0.9992 (16 revolutions at 20 dB SNR, two noise seeds).
LOAD_STANDS = 0.005


def carried(result: dict, c: float, read: list[float]) -> dict:
    """*result* (a diagnosis's conclusion) with the load factor *c* its effects were fitted beside:
    ``load`` (*read*: what :func:`settled` read), a note, and ``load_level`` in the corrected source
    where it has effects and the factor is not 1 (LOAD_STANDS)."""
    effect, result["load"] = load_entry(c, read)
    result["notes"].append(load_note(c))
    if result.get("corrected_effects") and abs(math.log(c)) > math.log1p(LOAD_STANDS):
        result["corrected_effects"] = [*result["corrected_effects"], [effect[0], [list(kv) for kv in effect[1]]]]
    return result
