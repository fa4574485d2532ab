"""A stage read on another harmonic family while the described one holds the lines of its own
(gearlab.gearbox.match.check_description). A slow last stage's mesh can stand under the floor at its first
harmonics and its lines under the faster stages': a 21/63 + 18/54 + 15/45 box at 30 Hz whose casing rings at
459 and 918 Hz (casing_path: mf 6 kg, k_xf 5e7, k_yf 2e8 N/m) showed stage 3's mesh (1.667 orders, 50 Hz) at
harmonics 6-35, 17-35 dB over the floor, none at 1-5; the strongest lines (mesh_family's evidence) held only lines
on stages 1 and 2's harmonics too (60, 105, 210), whose family, 15, was read: 'a 135-tooth pinion'.

The gear engineer's rule: the described count puts lines at every harmonic h M (and its shafts' sidebands), another
count at h M' alone. The lines that decide are those nothing else explains: off the other stages' mesh harmonics and
their sidebands, off the rival family's harmonics and sidebands. Where most of them (HELD) sit on the described comb,
at least OWN_LINES and CHANCE times what so dense a comb holds by chance, the description stands. A count really off
leaves only chance lines there: the real mesh's own lines and sidebands are the rival's.

A stage read at M with no line there is checked against the same lines (comb_reading): M's comb seen only on
every n-th harmonic, the others empty where it is seen, is n times the teeth (a 45/135 last stage described 15/45:
lines at 1.667 k, k = 3, 6 ... 42, none at 4, 5, 7 ...); lines between M's harmonics on M / n's, none of another
stage's, are z / n teeth (15/45 described 30/90 or 45/135); and a reading on a family where M's comb holds few of
those lines is no evidence of M (a 16/48 description read on stage 1 and 2's 48, 96, 105, 231, within a line's
tolerance of 1.778 h). A count 1-3 off whose comb holds more of them says the count before the first two rules do:
a 15/45 stage's comb meets a 14/42 description's at every 15th of its harmonics (70, 140 ...), and with one stray
line (56, the 12th) the held harmonics were all multiples of 3: 'a 42-tooth pinion' (a 2-stage box, 60 turns),
while 5 x k held 22 of the 29 lines.
"""

from __future__ import annotations

import numpy as np

from .sideband_combs import tol_mesh
from .speed import MAX_HARMONIC, Lines

SIDEBANDS = 3  # the sidebands j o of either shaft a mesh harmonic carries (the gap's combs too)
OWN_LINES = 3  # the described comb's unexplained lines a reading on it needs (one line is a tone)
HELD = 0.5  # the share of the unexplained lines the described comb must hold
CHANCE = 2.0  # ... and this many times what its windows (2 tol / M of the axis) hold by chance
RELATED = range(2, 10)  # the multiples and divisors of a described count that comb_reading weighs
MIN_TEETH = 6  # no pinion has fewer


def on_comb(x: np.ndarray, z: float, shaft_orders, tol: np.ndarray) -> np.ndarray:
    """Which orders *x* lie on a mesh harmonic h z (h >= 1) or one of its sidebands h z +- j o."""
    offsets = np.array([0.0] + [s * j * o for o in shaft_orders for j in range(1, SIDEBANDS + 1) for s in (-1, 1)])
    h = np.maximum(1, np.round((x[:, None] - offsets[None, :]) / z))
    return np.any(np.abs(x[:, None] - h * z - offsets[None, :]) <= tol[:, None], axis=1)


def described_holds(lines: Lines, m: float, rival: float, shafts, others, bin_: float) -> bool:
    """Whether the lines up to the described mesh *m*'s MAX_HARMONIC-th harmonic that neither the *others* ((mesh
    order, shaft orders ...): other_stages', a train's later stages') nor the *rival* family (with the stage's *shafts*'
    sidebands) explain sit on *m*'s harmonics (module doc)."""
    x = lines.at
    tol = tol_mesh(x, bin_)
    explained = on_comb(x, rival, shafts, tol)
    for mesh, *shafts_of in others:
        explained |= on_comb(x, mesh, [o for orders in shafts_of for o in orders], tol)
    free = ~explained & (x <= MAX_HARMONIC * m + tol)
    held = int(np.sum(free & on_comb(x, m, (), tol)))
    chance = float(np.sum(np.minimum(1.0, 2 * tol[free] / m)))
    return held >= OWN_LINES and held >= HELD * np.sum(free) and held >= CHANCE * chance


def _explained(x: np.ndarray, others, tol: np.ndarray) -> np.ndarray:
    """Which orders *x* the *others* ((mesh order, shaft orders ...) each) explain: a harmonic or a sideband."""
    out = np.zeros(x.size, dtype=bool)
    for mesh, *shafts_of in others:
        out |= on_comb(x, mesh, [o for orders in shafts_of for o in orders], tol)
    return out


def comb_reading(lines: Lines, m: float, shafts, others, bin_: float, rests_on=None) -> tuple[int, float] | None:
    """(index of the strongest line, mesh order refitted over its harmonics) of the comb that says a stage read at its
    described mesh *m* with no line there (*shafts*: its pinion's and wheel's shaft orders; *others*: as
    described_holds's) is another count's, or None where the lines bear m out or say nothing (module doc). The lines
    that decide are those up to m's MAX_HARMONIC-th harmonic that no other stage explains:
    * m's harmonics holding them, OWN_LINES at least, are all multiples of n: m's other harmonics between the first
      and the last held stand empty (no line at all), OWN_LINES and HELD of them at least: n times the count;
    * a comb m / n (n | z) holds OWN_LINES of them off m's harmonics and sidebands, CHANCE times what its windows there
      hold by chance: the mesh shows lines between those the description puts, z / n teeth;
    * read on a family (*rests_on*: its lines; None where m's comb was weighed already) while m's comb holds fewer
      than OWN_LINES, CHANCE times chance or what a count 1-3 off holds (OWN_LINES, HELD, CHANCE times chance at
      least): that count, as it is before the first two where its comb holds more of them than theirs (module doc)."""
    x = lines.at
    tol = tol_mesh(x, bin_)
    free = ~_explained(x, others, tol) & (x <= MAX_HARMONIC * m + tol)
    if np.sum(free) < OWN_LINES:
        return None
    xf, tf, af, index = x[free], tol[free], lines.amp[free], np.flatnonzero(free)
    z = round(m / float(shafts[0]))

    def comb(c: float) -> tuple[np.ndarray, float]:
        return on_comb(xf, c, (), tf), float(np.sum(np.minimum(1.0, 2 * tf / c)))

    meshes = [float(c) for c, *_ in others]  # m's harmonics +- theirs (a train's meshes modulate each other)
    near = None  # (lines held, which, mesh order) of the count 1-3 off whose comb holds the most of them
    for j in (j for j in (-3, -2, -1, 1, 2, 3) if z + j >= MIN_TEETH):
        c = (z + j) * float(shafts[0])
        hit, chance = comb(c)
        if hit.any():  # refitted over its lines: the shaft's order as its sidebands read it is 0.1 % off or so
            c = _refit(xf, af, hit, c, index)[1]
            hit, chance = comb(c)
        # ... not counting its harmonics +- another mesh: where that mesh is a whole harmonic of it, every line
        # holds (a 45/135 last stage after meshes at 21 and 6 described 15/45: intermodulation at 26 = 21 + 5,
        # 32 = 27 + 5, 52, 56 ... on the 2-order comb of 18 teeth, 8 of the 12 lines, 5's holding 3)
        count = int(np.sum(hit & ~_beside(xf, c, meshes, tf)))
        if count >= max(OWN_LINES, HELD * xf.size, CHANCE * chance) and (near is None or count > near[0]):
            near = (count, hit, c)
    on_m = on_comb(xf, m, (), tf)
    held = np.round(xf[on_m] / m).astype(int)
    n = int(np.gcd.reduce(held)) if held.size >= OWN_LINES else 1
    if n >= 2:
        band = np.arange(held.min(), held.max() + 1)
        at = band[band % n != 0] * m
        empty = ~np.any(np.abs(x[None, :] - at[:, None]) <= tol_mesh(at, bin_)[:, None], axis=1)
        if np.sum(empty) >= OWN_LINES and np.sum(empty) >= HELD * at.size:
            return _refit(xf, af, *(near[1:] if near and near[0] > held.size else (on_m, n * m)), index)
    for n in sorted((n for n in RELATED if z % n == 0 and z // n >= MIN_TEETH), reverse=True):
        hit, chance = comb(m / n)
        extra = hit & ~on_comb(xf, m, (*shafts, *meshes), tf)
        if np.sum(extra) >= OWN_LINES and np.sum(extra) >= CHANCE * chance * (1 - 1 / n):
            return _refit(xf, af, *(near[1:] if near and near[0] > np.sum(hit) else (hit, m / n)), index)
    if rests_on is None:
        return None
    own, chance = comb(m)
    if near is None or (np.sum(own) >= max(OWN_LINES, CHANCE * chance) and np.sum(own) >= near[0]):
        return None
    return _refit(xf, af, *near[1:], index)


def _beside(x: np.ndarray, c: float, meshes, tol: np.ndarray) -> np.ndarray:
    """Which orders *x* lie at a harmonic of *c* +- j times another mesh (j = 1 ... SIDEBANDS): its intermodulation."""
    offsets = np.array([s * j * o for o in meshes for j in range(1, SIDEBANDS + 1) for s in (-1, 1)])
    if not offsets.size:
        return np.zeros(x.size, dtype=bool)
    h = np.maximum(1, np.round((x[:, None] - offsets[None, :]) / c))
    return np.any(np.abs(x[:, None] - h * c - offsets[None, :]) <= tol[:, None], axis=1)


def _refit(x: np.ndarray, amp: np.ndarray, hit: np.ndarray, c: float, index: np.ndarray) -> tuple[int, float]:
    """(index into the lines of the strongest line *hit*, the mesh order c refitted over its harmonics, by power)."""
    h, w = np.round(x[hit] / c), amp[hit] ** 2
    return int(index[hit][np.argmax(w)]), float(np.sum(w * h * x[hit]) / np.sum(w * h * h))
