"""Which gear, the evidence (signals.localise, "Evidence"): the healthy history's spread of synchronous
power per order, the null variance of a record's difference from it, and each shaft's level.

A record's Δ(q) = S(q) − S_h(q) is read in sds of its null spread (the record's noise, plus the
history's unit-to-unit spread of that order's power): a fault's event reaches the sensor through the
structure, so its excess is largest where the train's lines and resonances are, as is that spread, and
Δ weighted by 1 / the null variance read it at quiet orders it hardly reaches (a 67T fault of a
three-stage box placed on the slower 62T, a 24T pinion's chip on the input shaft). Two nuisances the
history's units do not show are taken out first. At the history's lines a take's load scales every line
alike, and two takes give that change with one degree of freedom (units cut from one take agree with
each other): the record is compared with the history times its lines' ratio of sums (healthy takes
15-19 % off two takes agreeing within 3-6 % named the intermediate shaft of three random trains at z
3.9-7.1, development seed 11), and the history's terms of the null variance scale with it, never below
the take's level (below; a 24/79 + 27/72 intermediate pinion's crack raised its shaft's lines 136 times and every
other shaft's 2.8-8 times: its gain of 37.5 read the input's one line at z -107, and the input was
flagged at 5.9). Off the lines the history's power is born of what the take's level scales: the other
shafts' lines' leaks into a shaft's average, and the estimate's own bias where content at no whole order
of a slow shaft (a load's sidebands about the meshes) scatters its turns more than it stays in its mean
(|X̄|² − n read -0.75 to -1.4 noise powers within an order of the meshes of a user's 47/131 + 37/151
mixer, its history at 50 and 100 N m). That level r -- a load, or a sensor's gain, that scales the lines
and the noise alike -- is read from the take's noise floor over the history's (per period averaged, the
median over the orders off the lines: level), which a localised fault hardly moves: it adds lines at
its shaft's orders, not scatter at every order. Off the lines the history is scaled by r, or by the
lines' gain where that is a heavier load's over r (up to LOAD_GAIN r: healthy 24/79 + 27/72 takes 3-6 %
over the history's load put the intermediate shaft at z 1.09 on average over four; 0.69 scaled); a
fault's gain is not: it moves the lines far more, or reads them low, and a gain under r taken off the
lines raises every order there (a random train's output gear fault read its intermediate lines at 0.61
of the history's, development seed 23, and the intermediate shaft was named at z 4.5; the soft 21/63 +
24/56 reducer's pinion chip at 0.89 raised its input shaft from z 3.27 to 4.42). The history's terms of
the null variance scale with the same gain, never below r: a take read at any level gives the same z on
every shaft (scaled off the lines by a heavier load's gain alone, the user's healthy takes at 50 N m
read the output gear at z 2.9-4.2, over its threshold of 2.71). Those leaks also scatter beyond a
slow shaft's noise model (z² 1.66 at the intermediate TSA's orders, 1.19 at the output's, seed 11):
the units' scatter over that model, pooled over neighbouring orders, scales it. A load scales the mesh's response
too, its harmonics and the sidebands about them alike, at every tooth: off the lines the history is scaled, at
least, by the power gain of the mesh harmonic nearest each order (mesh_gain), which a localised fault hardly moves
(its event spreads over many orders). Read at the noise level alone, a 38/103 reducer's healthy takes at 1.5 and 2 x
its one-load history's mesh level put the input pinion over its threshold of 2.58 in 1 and 3 of 10 (its second
sidebands by the input shaft, weak in the history, grew with the mesh), 0 of 10 so; weak chips on either gear are
named as before at the history's load (z 19 and 32) and at 1.5 x (14 and 23, against 20 and 32: the history's
terms of the null variance scale with the gain), development seeds 100-109. A noise floor's change is no line change: a
quieter or noisier sensor, or a faster rate (less noise an order), moves the noise alone. Where the lines are too few to
read their gain from, r stands for it only where the lines show it, else 1 (line_gain): a one-shaft take read on a 25/30
description whose meshes carry no line, its lines scaled by r, named the input shaft at z 36-38, 12-13 and 6.6-8.0
(threshold 2.58) at 0.5 and 0.7 times its history's noise and at twice its rate, and read it at -7 to -8 at 1.5 times
(a fault hidden); -0.6 to 0.5 so, development seeds 100-102.

Everything is numpy: no torch, nothing from the layers above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..errors import GearlabInputError
from .shaft import uniform_filter1d

if TYPE_CHECKING:  # localise imports this module
    from .localise import Content, Layout

WEIGHT_SMOOTH = 101  # orders over which noise powers and spreads are pooled (spread)
KAPPA = 8.0  # a history line: mean power this many noise sds of its mean over zero (see spread)
GAIN_LINES = 3  # lines a take's common line gain is read from (fewer: none removed)
LOAD_GAIN = 1.25  # the largest gain of the lines a heavier load gives (healthy takes 0.88-1.07, development)


@dataclass(frozen=True)
class Spread:
    """The history's per-order synchronous power and its record-to-record spread."""

    power: np.ndarray  # S_h: mean synchronous power of the units
    line: np.ndarray  # bool: S_h significant (KAPPA sd of its noise); elsewhere only noise
    between: np.ndarray  # variance of a line's power from unit to unit beyond its noise
    unit_noise: np.ndarray  # noise power of a unit's mean, smoothed over WEIGHT_SMOOTH orders
    units: int
    # off the lines, the units' scatter of power over its noise model, pooled over WEIGHT_SMOOTH orders of
    # one average (empty: a history saved before it was kept; the noise model alone)
    excess: np.ndarray = field(default_factory=lambda: np.zeros(0))
    periods: float = 0.0  # the periods behind a unit's noise (0: a history saved before it was kept; see level)


def _smooth(x: np.ndarray, source: np.ndarray | None = None, mask: np.ndarray | None = None) -> np.ndarray:
    """*x* smoothed over WEIGHT_SMOOTH orders of one average (*source*): a slow shaft's TSA, resampled
    by linear interpolation, holds a third of the input TSA's noise near the top order. *mask*: the mean
    of the orders it holds in each window."""
    out = np.empty_like(x)
    for s in np.unique(source) if source is not None else [None]:
        at = slice(None) if s is None else source == s
        if mask is None:
            out[at] = uniform_filter1d(x[at], size=WEIGHT_SMOOTH, mode="nearest")
            continue
        num = uniform_filter1d(np.where(mask[at], x[at], 0.0), size=WEIGHT_SMOOTH, mode="nearest")
        out[at] = num / np.maximum(uniform_filter1d(mask[at].astype(float), size=WEIGHT_SMOOTH, mode="nearest"), 1e-12)
    return out


def _estimate_var(power: np.ndarray, noise: np.ndarray, blocks: int = 1) -> np.ndarray:
    """Variance of Content.power about |μ|² = *power*: |X̄|² − n of complex Gaussian block means of noise
    power B n (n = *noise* of the whole mean), averaged over B = *blocks*."""
    return blocks * noise**2 + 2 * np.maximum(power, 0) * noise


def spread(units: list[Content], evidence: np.ndarray | None = None) -> Spread:
    """The units' mean power and, at the orders where it is a line, its spread beyond noise.

    The weights of the evidence (_null_var) never follow one order's own noisy estimate (a weight
    that rises where an order's power happened to come out low picks the orders where Δ comes out
    high, and biases every class mean up): the noise enters smoothed over many orders, an order's
    power and spread only where it is a line (KAPPA times the noise of its mean; at 4 the slow
    shafts' healthy z came out 0.3-0.6 high, at 8 within 0.15, development seeds), read from the
    take and the history pooled (_null_var); off the lines the units' scatter over its noise model,
    pooled over neighbouring orders.
    *evidence*: the orders read as evidence (not the mesh harmonics), whose lines give the common
    relative spread."""
    if len(units) < 2:
        raise GearlabInputError(f"the history holds {len(units)} unit; expected at least 2 to measure its spread")
    P = np.stack([u.power for u in units])
    mean = P.mean(axis=0)
    noise = np.mean([_smooth(u.noise, u.source) for u in units], axis=0)
    line = mean > KAPPA * noise / math.sqrt(len(units))
    nv = np.mean([_estimate_var(mean, u.noise) for u in units], axis=0)
    b = np.maximum(P.var(axis=0, ddof=1) - nv, 0.0)
    # two or three units give each order's spread with one or two degrees of freedom: a line
    # whose units happen to agree must still be allowed its share of the common relative spread
    strong = (mean > 10 * np.sqrt(nv)) & (True if evidence is None else evidence)
    alpha2 = float(np.median(b[strong] / mean[strong] ** 2)) if strong.sum() >= 5 else 0.0
    between = np.where(line, np.maximum(b, alpha2 * np.maximum(mean, 0) ** 2), 0.0)
    model = np.mean([_estimate_var(np.zeros_like(mean), _smooth(u.noise, u.source)) for u in units], axis=0)
    excess = _smooth(P.var(axis=0, ddof=1) / np.maximum(model, 1e-300), units[0].source, ~line)
    return Spread(mean, line, between, noise, len(units), excess, float(np.mean([u.periods for u in units])))


def _null_var(rec: Content, ref: Spread, evidence: np.ndarray, gain: float | np.ndarray = 1.0) -> np.ndarray:
    """Variance of Δ = S − *gain* S_h under the history, off the lines times the units' pooled excess scatter. Its
    powers, and what is a line, are read from the take (brought to the history's level by the gain) and the history
    pooled, B blocks and U units: for Gaussian powers X of B blocks and Y of U units, X − Y and B X + U Y are
    uncorrelated, so neither a weight nor the line decision follows Δ's sign. Read from the history alone, an order
    whose units happened to come out low was given a small variance, or left off the lines, where its Δ came out high
    (lines 10 noise powers over zero read z +0.054 on average; the 21/63 + 24/56 reducer's healthy input shaft
    0.61, healthy takes flagged 18 of 320, development seeds 48-49; pooled: 0.00, 0.20 and 6 of 320). A line's
    spread is the history's common relative spread (the median over its lines read as *evidence*, not the mesh
    harmonics) times the pooled power squared. The history's terms scale with the gain."""
    B, U = rec.blocks, ref.units
    noise = _smooth(rec.noise, rec.source)

    def model(lines: np.ndarray, between: np.ndarray, line: np.ndarray) -> np.ndarray:
        var = _estimate_var(gain * lines, noise, B) + gain**2 * (
            between * (1 + 1 / U) + _estimate_var(lines, ref.unit_noise) / U
        )
        if ref.excess.size != var.size:  # a history saved before the pooled scatter was kept
            return var
        return np.where(line, var, var * np.maximum(ref.excess, 1.0))

    # the take's share at most KAPPA sds (the history's alone) over the history's power, where a healthy take seldom
    # reaches: pooled whole, a fault's own power set its spread (box B's 16T chip: its own-mesh sidebands read z 0.5,
    # 7.1 from the history alone, 6.9 so)
    alone = model(np.where(ref.line, ref.power, 0.0), ref.between, ref.line)
    take = np.minimum(rec.power / gain, ref.power + KAPPA * np.sqrt(alone) / gain)
    pooled = (B * take + U * ref.power) / (B + U)
    line = pooled > KAPPA * ref.unit_noise / math.sqrt(B + U)
    lines = np.where(line, np.maximum(pooled, 0.0), 0.0)
    own = ref.line & evidence
    relative = float(np.median(ref.between[own] / ref.power[own] ** 2)) if own.sum() >= 5 else 0.0
    return model(lines, relative * lines**2, line)


def level(rec: Content, ref: Spread, lay: Layout) -> float:
    """The take's level r: its noise floor over the history's units' (the median over the orders off the lines and the
    mesh harmonics, smoothed as the null variance reads them), block for unit where the take is read in the units'
    blocks (its noise is their mean's), else per period averaged (a grand period's count is exact, a slow shaft's
    turns are not: a 21/63 + 24/56 record of 40 input turns holds 5 of the output, each half of it 2); 1 where the
    history kept no periods."""
    if not ref.periods:
        return 1.0
    off = ~ref.line & ~lay.carrier
    ratio = float(np.median(_smooth(rec.noise, rec.source)[off] / np.maximum(ref.unit_noise[off], 1e-300)))
    return ratio * rec.blocks if rec.blocks > 1 else ratio * rec.periods / ref.periods


def mesh_gain(rec: Content, ref: Spread, lay: Layout) -> np.ndarray:
    """Per order, the power gain over the history's of the mesh harmonic nearest it (1 where the history holds none
    as a line): what a load change scales the sidebands about that harmonic by."""
    at = np.flatnonzero(lay.carrier & ref.line & (ref.power > 0))
    if not at.size:
        return np.ones(lay.orders.size)
    gain = np.maximum(rec.power[at], 0.0) / ref.power[at]
    return gain[np.argmin(np.abs(lay.orders[:, None] - lay.orders[at][None, :]), axis=1)]


def line_gain(rec: Content, ref: Spread, lay: Layout, r: float) -> float:
    """The take's common gain of the history's lines: their ratio of sums off the mesh harmonics, where GAIN_LINES or
    more. Fewer cannot be read apart from a change of their own shaft, and the take's level r (its noise floor's) stands
    for their gain where the lines show it: a gain scales the lines and the noise alike, a quieter or noisier sensor
    the noise alone. Of 1 (the history's) and r, the one nearer the ratio of sums of every history line, the mesh
    harmonics' included (1 where r is 1: a change of the lines alone is read as before)."""
    lines = ref.line & ~lay.carrier
    if lines.sum() >= GAIN_LINES:
        return float(rec.power[lines].sum() / ref.power[lines].sum())
    every = ref.line & (ref.power > 0)
    if not every.any():
        return r
    shown = max(float(rec.power[every].sum() / ref.power[every].sum()), 1e-12)
    return r if abs(math.log(shown / r)) < abs(math.log(shown)) else 1.0


def order_z(rec: Content, ref: Spread, lay: Layout) -> np.ndarray:
    """Each order's Δ in sds of its null spread: from the history times the take's level (level), on the lines times
    their ratio of sums, off them times a heavier load's up to LOAD_GAIN times the level, or the nearest mesh
    harmonic's gain where larger (mesh_gain; the module's docstring)."""
    lines = ref.line & ~lay.carrier
    r = level(rec, ref, lay)
    # the take's common gain of the lines (its load); off the lines, where a shaft's average holds the
    # other shafts' lines' leaks, only a heavier load's: a fault moves the lines far more, and reads them
    # low as well, and a gain under the take's level taken off there raises every order (the module's docstring)
    # the ratio of the lines' sums, not the median of their ratios: a line's power over the history's is a ratio of
    # two noisy powers, skewed, and its median reads under the true gain (0.958 for lines 10 noise powers over zero),
    # so every line's Δ came out positive (the 21/63 + 24/56 reducer's healthy input shaft at z 0.92 on average,
    # 0.61 so, development seeds 48-50)
    gain = line_gain(rec, ref, lay, r)
    off = np.maximum(gain if r < gain <= LOAD_GAIN * r else r, mesh_gain(rec, ref, lay))
    g = np.where(lines, gain, off)
    # a gain under the take's level never narrows the history's spread: a slower gear's fault reads a faster shaft's
    # lines low (0.19-0.24 of the history's, random trains of development seed 23), and narrowed, they named it
    var = _null_var(rec, ref, ~lay.carrier, np.maximum(g, r))
    return (rec.power - g * ref.power) / np.sqrt(np.maximum(var, 1e-300))


def shaft_levels(rec: Content, ref: Spread, lay: Layout) -> tuple[np.ndarray, np.ndarray]:
    """(L_s, sd(L_s)) per shaft, L_s in null sds of Δ: each order's z (order_z), band by band least squares over the
    order classes (the module's docstring)."""
    z = order_z(rec, ref, lay)
    k = len(lay.shafts)
    code = lay.sync @ (1 << np.arange(k))
    num, info = np.zeros(k), np.zeros(k)
    edges = np.arange(lay.min_order, lay.max_order + lay.band, lay.band)
    for lo, hi in zip(edges[:-1], edges[1:]):
        inb = (lay.orders >= lo) & (lay.orders < hi) & ~lay.carrier
        classes = np.unique(code[inb])
        if classes.size < k:
            continue
        A, d, wc = [], [], []
        for c in classes:
            sel = inb & (code == c)
            A.append([(int(c) >> s) & 1 for s in range(k)])
            wc.append(float(sel.sum()))  # each order's z has unit variance: a class's mean has 1 / its count
            d.append(float(z[sel].mean()))
        A, d, wc = np.array(A, float), np.array(d), np.array(wc)
        F = A.T @ (A * wc[:, None])
        if np.linalg.matrix_rank(F) < k:
            continue
        cov = np.linalg.inv(F)
        L = cov @ (A.T @ (wc * d))
        var = np.diag(cov)
        num += L / var
        info += 1 / var
    if not info.any():
        raise GearlabInputError("no band of orders holds every shaft's class of orders: nothing to localise with")
    info = np.where(info > 0, info, np.nan)
    return num / info, 1 / np.sqrt(info)
