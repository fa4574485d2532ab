"""The harmonic family a stage's strongest lines hold (gearlab.gearbox.match.check_description reads a stage on it
where no line stands at its described mesh, or where another family holds more of the power): a mesh's power can sit
at harmonics 4-11 with its fundamental under the threshold."""

from __future__ import annotations

import numpy as np

from .sideband_combs import tol_mesh
from .speed import DRIFT, EVIDENCE, MAX_HARMONIC, Lines, carrier, hit_sums

FAMILY_MARGIN = 0.1  # another harmonic family than the described one must hold 10 % more of the lines' power


def mesh_family(
    lines: Lines, o_p: float, bin_: float, span: float, others, expected: float, o_w: float | None = None, lent=()
) -> tuple | None:
    """(mesh order, index of its strongest harmonic, the orders of its lines) of the harmonic family
    among a stage's lines, or None: a mesh's power can sit at harmonics 4-11 with its fundamental
    under the threshold (the B-6-ch5 source: orders 100, 175, 225, no line at 25). The lines: the
    strongest carriers off the other stages' mesh harmonics (*others*), by their share of power.
    The candidates: each line / h (h up to MAX_HARMONIC) of whole teeth (6-1000) on the pinion's
    shaft holding two lines or more, refitted over its harmonics (M = Σ p h L / Σ p h²), scored by
    their power less what so dense a comb holds by chance (2 tol / M): a subharmonic M / k holds
    what M holds and loses, so the best is the gcd. The description's order is the prior: another
    family must hold FAMILY_MARGIN more of the power (even harmonics dominating are no gear of
    twice the teeth). *o_w*: the wheel shaft's order where a tacho gives it: whole teeth on it count too
    (111/157 + 115/173 with an output tacho, described with a 172-tooth last wheel: the intermediate shaft
    read 0.6 % slow, stage 2's own family at 115.67 pinion teeth was refused and stage 1's, 158, taken). *lent*:
    (order, tolerance) of the other stages' mesh harmonics: a line there that *others* leaves in (the described
    comb has a harmonic there too) counts for the described family, for another only where a line of its own stands
    at its order (a 15/45 last stage described 16/48 over 20 turns: stage 1's 105, 126, 231, within a line's
    tolerance of 1.778 x 59, 71, 130, read as 5, 6, 11 x 21, 'a 189-tooth pinion'; a 16/48 one described 15/45,
    stage 2's 60 and stage 1's 105 as 4 and 7 x 15, 'a 135-tooth pinion'; a pinion really of 135 teeth shows its line
    at 15)."""
    top = [
        q
        for q in range(min(EVIDENCE, lines.at.size))
        if carrier(lines, q, span, others) == q and not any(abs(lines.at[q] - o) <= t for o, t in others)
    ]
    if not top:
        return None
    x, power = lines.at[top], lines.amp[top] ** 2
    power = power / power.sum()
    tol = 2 * bin_ + DRIFT * x

    def fit(m: float, slack: np.ndarray) -> tuple[float, np.ndarray]:
        h = np.maximum(1.0, np.round(x / m))
        hit = np.abs(x - h * m) <= slack
        if hit.any():
            m = float(np.sum(power[hit] * h[hit] * x[hit]) / np.sum(power[hit] * h[hit] ** 2))
        return m, np.abs(x - np.maximum(1.0, np.round(x / m)) * m) <= tol

    def scored(m: float, hit: np.ndarray) -> tuple:
        strongest = top[int(np.argmax(np.where(hit, lines.amp[top], -np.inf)))]
        return float(np.sum(power * (hit - 2 * tol / m))), m, strongest, x[hit]

    m, hit = fit(expected, tol)
    prior = scored(m, hit) if hit.any() else None
    fits = []
    refit, hits = _fits(x, power, tol)
    # scored for every candidate at once (each row's sum and argmax are those of its own 1-D array)
    held = np.sum(power * (hits - 2 * tol / np.array(refit, dtype=float)[:, None]), axis=1).tolist()
    strongest = np.argmax(np.where(hits, lines.amp[top], -np.inf), axis=1).tolist()

    lent_at, lent_tol = (np.array([pair[i] for pair in lent], dtype=float) for i in (0, 1))

    def theirs(a: np.ndarray) -> np.ndarray:  # which orders *a* lie on another stage's mesh harmonic
        return np.any(np.abs(a[:, None] - lent_at[None, :]) <= lent_tol[None, :], axis=1)

    # a line of its own (on no other stage's mesh harmonic) within a line's tolerance of each candidate
    mine = np.sort(lines.at[~theirs(lines.at)])
    at = np.array(refit, dtype=float)
    right = np.searchsorted(mine, at)
    gap = np.minimum(
        np.abs(at - mine[np.clip(right - 1, 0, None)]) if mine.size else np.inf,
        np.abs(mine[np.clip(right, None, mine.size - 1)] - at) if mine.size else np.inf,
    )
    shown = (gap <= tol_mesh(at, bin_)).tolist()
    mine_x = ~theirs(x)
    for m, hit, p, s, seen in zip(refit, hits, held, strongest, shown):
        whole = [
            o for o in (o_p, o_w) if o and 6 <= m / o <= 1000 and abs(m / o - round(m / o)) * o <= tol_mesh(m, bin_)
        ]
        if not seen and not np.all(hit <= mine_x):  # without a line at its order, its own lines alone
            hit = hit & mine_x
            p = float(np.sum(power * (hit - 2 * tol / m)))
            s = int(np.argmax(np.where(hit, lines.amp[top], -np.inf)))
        if np.sum(hit) >= 2 and (whole or m / o_p >= 6):
            fits.append(((p, m, top[s], x[hit]), hit, bool(whole)))
    # The strongest family, whole teeth or not: a family of whole teeth whose power is mostly that family's lines
    # and which is slower is its subharmonic or borrows them; it is no mesh of its own (a 21/65 + 34/91 box described
    # with a 64-tooth wheel, 57 turns: the intermediate shaft read at 0.3307, stage 2's 10.985 not whole on it and
    # its harmonics 1-3 taken as 3, 6, 9 of 3.662, 'a 11-tooth pinion'; without them, 21.968 and a sideband at 20.0
    # as 11 and 10 of 1.997)
    free = max(fits, key=lambda f: f[0][0], default=None)
    best = None
    for candidate, hit, whole in fits:
        if not whole:
            continue
        if free is not None and not free[2] and candidate[1] < 0.9 * free[0][1]:
            if np.sum(power[hit & free[1]]) >= 0.5 * np.sum(power[hit]):
                continue
        if best is None or candidate[0] > best[0]:
            best = candidate
    if best is None or (prior is not None and best[0] < prior[0] + FAMILY_MARGIN):
        return None if prior is None else prior[1:]
    return best[1:]


def _fits(x: np.ndarray, power: np.ndarray, tol: np.ndarray) -> tuple[list, np.ndarray]:
    """mesh_family's fit of every candidate x[i] / h (i outer, h = 1 … MAX_HARMONIC inner) at once, its slack
    tol + tol[i] x / x[i]: (the refitted orders, their hits, one row each). The same floats as one candidate at a
    time (fit): every product and comparison element by element, and each refit's two sums over the hit lines
    alone, in their order, as rows of the hit count (a row's sum is numpy's sum of that 1-D array). One at a time,
    640 candidates of a dozen numpy calls each, mesh_family took 10.6 ms of CPU a call (now 1.8 ms): half of a
    description check's (inspect, the gap's structure check, the detection kind's reading of a gearbox)."""
    rows = (x[:, None] / np.arange(1, MAX_HARMONIC + 1)).ravel()
    slack = np.repeat(tol[None, :] + tol[:, None] * x[None, :] / x[:, None], MAX_HARMONIC, axis=0)
    h = np.maximum(1.0, np.round(x[None, :] / rows[:, None]))
    hit = np.abs(x[None, :] - h * rows[:, None]) <= slack
    upper, lower = hit_sums(hit, power * h * x, power * h**2)
    refit = list(rows)  # a row without a hit keeps its candidate
    for r in np.flatnonzero(hit.any(axis=1)).tolist():
        refit[r] = float(upper[r] / lower[r])
    m = np.array(refit, dtype=float)
    return refit, np.abs(x[None, :] - np.maximum(1.0, np.round(x[None, :] / m[:, None])) * m[:, None]) <= tol[None, :]
