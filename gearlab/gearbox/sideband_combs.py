"""Sideband combs of a stage's shafts around its mesh line (gearbox.match reads each stage with them): the comb of
one shaft (comb: spacing, tolerance, lines), a stage's two combs sharing no line (families), and the lines another
stage's structure explains, no sideband of this one (others_lines, mixed); a comb reading no whole tooth count is
no shaft's (whole).

Tolerances: a line matches a mesh order M within 2 bins + 1e-3 M (tol_mesh: speed drift smears high orders); a
sideband spacing matches a shaft order o within 0.5 bin / j + 1e-3 o for the j-th sideband (2 bins / j under 16
bins apart), or within its lines' own readings of it (d / j) where they spread wider.
"""

from __future__ import annotations

import math

import numpy as np

from .speed import DRIFT, MAX_HARMONIC, Lines

# A sideband spacing's tolerance, bins over the furthest sideband j: sidebands SEPARATED bins apart or
# more are refined to a small part of a bin (outside records: z within 0.016 teeth; at 2 bins a 71-tooth
# wheel described as 70 passed); closer ones keep 2 bins (a 0.6 s simulation put a comb 0.1 order off).
SIDEBAND_BINS, SEPARATED = 0.5, 16
# A comb's line further than this off the spacing fitted through its lines is another's (dropped, the worst
# first, and the comb fitted again); half a bin dropped true lines of a 150-turn record, whose neighbours move them
CONSISTENT_BINS = 1.0
# A comb of one or two lines is no shaft's order where the described spacing's sidebands hold this many lines, their
# strongest this far over the comb's (lone): more than the lines that fall near any spacing by chance, and stronger
LONE_LINES, LONE_DB = 3, 6.0

# A comb around meshes its shaft does not carry, per carrier order this share of its own meshes' or more, is a swing
# of the train's speed or load (train_wide)
TRAIN_WIDE = 0.5


def tol_mesh(order: float, bin_: float) -> float:
    return 2 * bin_ + DRIFT * order


def mixed(d, o: float, rival: float | None, bin_: float):
    """Whether the offsets *d* (a float or an array) from a mesh line are the two shafts' intermodulation
    a rival +- b o (a, b = 1-3) and not a sideband j o: within CONSISTENT_BINS of such a product and further from
    every j o than from it. A mesh modulated by both its shafts carries o_p - o_w (a 22/68 + 18/70 box: 0.2403
    beside the output's 3rd, 0.2496, 2.2 bins apart at 235 turns), and the output's comb took it as its 3rd: 'the
    wheel shows 71.4 teeth'. *o* is the spacing a comb tries (comb), not the described order: with a count off the
    described order's products are no lines' (a 29/42 box described with 44 teeth: the output's true 1st sideband,
    0.6905, lay 1.1 bins from 2 - 2 x 29/44 and the comb lost it: 'the tooth count of its 44-tooth wheel is not
    checked')."""
    d = np.abs(np.asarray(d, dtype=float))
    if rival is None:
        return np.zeros(d.shape, dtype=bool) if d.ndim else False
    tol = CONSISTENT_BINS * bin_ + DRIFT * d
    pure = np.min([np.abs(d - j * o) for j in (1, 2, 3)], axis=0)
    products = [abs(a * rival + s * b * o) for a in (1, 2, 3) for b in (1, 2, 3) for s in (-1, 1)]
    mix = np.min([np.abs(d - p) for p in products], axis=0)
    out = (mix <= tol) & (pure > np.maximum(tol, mix))
    return out if d.ndim else bool(out)


def own_pair(hits: list, part: float) -> bool:
    """Whether a comb's *hits* ((j, line) each) spaced *part* (1/2 or 1/3; 0: any spacing) of the stage's other
    shaft's order hold a pair of its own lines: the sidebands +-j of a j no multiple of 1 / *part*. Every 2nd (3rd)
    line of such a comb lies on the other shaft's comb, which alone puts them there; the lines between are this
    shaft's only, and a shaft's modulation sets them either side of the carrier (a box of 32 and 64 teeth: the output
    at 0.5 beside the input's 1.0; of 40 and 119, 0.3361, 0.8 % from 1/3: each described a tooth or two off, 'not
    checked').
    One such line alone can be another mesh's tone (a three-stage train's 19/43 + 23/57 + 29/71: a comb at half the
    intermediate shaft's order read as the output's, '58.1 teeth, 71 described')."""
    if not part:
        return True
    n, js = round(1 / part), {j for j, _ in hits}
    return any(j % n and -j in js for j in js if j > 0)


def comb(
    lines: Lines, mesh: int, o: float, bin_: float, exclude=frozenset(), rival: float | None = None
) -> tuple | None:
    """(spacing, tolerance, count, {line: |j|}, score) of the sideband family of a shaft around the
    mesh line *mesh*.

    Every line within ±3.9 o of the carrier is an offset d; a candidate spacing c = |d| / j
    (j = 1, 2, 3, within ±30 % of the described o, and nearer o than the stage's other shaft's
    order *rival*: that spacing is the other shaft's evidence; nor 2-6 rival off o: the comb of the one
    seen in the other's every 2nd or 3rd line, or a harmonic of the other's: a cracked tooth on a 14/53
    wheel's shaft rings its 4th, 1.057, read as the input's: '13.2 teeth, 14 described'; 1/2 or 1/3 rival
    off o only with a pair of lines of its own, off the other's comb: own_pair)
    is scored by the amplitudes of
    the offsets at ±c, ±2c, ±3c; it must have a first sideband (±c), no product of the rival and c, and its
    others are no products of the rival and the order its first sidebands read (mixed): the lines' spacing, not the
    described o, which a count off moves (a 22/68 + 18/70 box's o_p - o_w, 0.2403, is 3 x 0.0801, and a product
    of 0.0831, the order 0.0801's first sidebands read). The best comb's spacing is the
    least-squares fit through its lines, so a 57- and a 58-tooth wheel are told apart once
    0.5 bin / 3 < o / 57 (sidebands 16 bins apart or more; else 2 bins)."""
    m = float(lines.at[mesh])
    near = np.flatnonzero((np.abs(lines.at - m) <= 3.9 * o) & (np.arange(lines.at.size) != mesh))
    near = np.array([q for q in near if q not in exclude], dtype=int)
    if near.size == 0:
        return None
    d, a, log = lines.at[near] - m, lines.amp[near], math.log

    def nth(c: float, ns) -> float:
        """The n of *ns* whose n x rival *c* lies at, off o by over 1 %, else 0."""
        # within 1 % of n x rival, or of the comb's own resolution where finer: a 54/107 stage's input comb
        # (0.981 of the input's order as a 53-tooth description reads it) sits 0.9 % from 2 x the output's
        near = min(0.01 * c, (SIDEBAND_BINS if c >= SEPARATED * bin_ else 2.0) * bin_ + DRIFT * c)
        if rival is None or abs(c - o) <= 0.01 * o:
            return 0
        return next((n for n in ns if abs(c - n * rival) <= near), 0)

    def allowed(c: float) -> bool:
        within = 0.7 * o <= c <= 1.3 * o and (rival is None or abs(log(c / o)) < abs(log(c / rival)))
        return within and not nth(c, (2, 3, 4, 5, 6))

    def fitted(hits: list) -> tuple[float, list]:
        """The spacing fitted through *hits* and the hits it keeps: a line further off the fitted comb than
        CONSISTENT_BINS (once separated) is another's and goes, the worst first (lines where two shafts'
        sidebands combine, 1 - 0.337 off a 28/83 mesh, took the intermediate's comb as its ±2nd, 0.5 % off).
        A line at |j| >= 2 is judged on the spacing the comb's other lines read, not on a fit it draws to itself
        (j^2 x its amplitude): a line 2.6 bins off M - 2 o, as strong as the first sidebands (both on o), took the
        fit 0.9 bin off o, where every line sat within a bin (a 34/58 + 22/84 box, synthetic: the first mesh's 5th
        harmonic folded about the rate and smeared by the speed's swing; 'intermediate shaft: order 0.5832
        measured (4 sideband(s) of M1), 0.5862 expected' of the right description)."""
        while True:
            js, ds, ws = (np.array(v, dtype=float) for v in zip(*((j, d[q], a[q]) for j, q in hits)))
            num, den = float(np.sum(ws * js * ds)), float(np.sum(ws * js * js))
            spacing, rest = num / den, den - ws * js * js
            judged = np.where(
                (np.abs(js) >= 2) & (rest > 0), (num - ws * js * ds) / np.where(rest > 0, rest, 1.0), spacing
            )
            bins = CONSISTENT_BINS if spacing >= SEPARATED * bin_ else 2.0
            off = np.abs(ds - js * judged) - (bins * bin_ + DRIFT * np.abs(js) * spacing)
            if off.max() <= 0 or len(hits) == 1:
                return spacing, hits
            hits = hits[: int(np.argmax(off))] + hits[int(np.argmax(off)) + 1 :]

    def on(own: np.ndarray, c: float, js: tuple) -> list:
        """(j, line) for the offsets *own* nearest j c (j in *js*), within 2 bins and the drift."""
        hits = []
        for j in js:
            q = int(np.argmin(np.abs(own - j * c)))
            if abs(own[q] - j * c) <= 2 * bin_ + DRIFT * abs(j) * c:
                hits.append((j, q))
        return hits

    candidates = []
    for c in {abs(v) / j for v in d for j in (1, 2, 3) if allowed(abs(v) / j)}:
        # a product of the rival and the shaft's order is no sideband of it (mixed): of c for the first sidebands,
        # of the order they read for the others; never of the described o (29/42 described with 44 teeth: 2 - 2 x
        # 29/44 lay 1.1 bins from the true first sideband, and no comb was left)
        own = np.where(mixed(d, c, rival, bin_), np.inf, d)
        hits = on(own, c, (-1, 1))
        if not hits:
            continue
        first = float(sum(a[q] * abs(d[q]) for _, q in hits) / sum(a[q] for _, q in hits))
        hits += on(np.where(mixed(d, first, rival, bin_), np.inf, own), c, (-3, -2, 2, 3))
        spacing, hits = fitted(hits)
        if any(abs(j) == 1 for j, _ in hits) and own_pair(hits, nth(c, (1 / 2, 1 / 3))):
            candidates.append((c, hits, spacing))
    # a comb of one line is that line's evidence alone: where another comb has a line on each side of the carrier,
    # it goes (a 21/65 + 34/91 box described with a 64-tooth first wheel: stage 2's 2nd harmonic, 0.969 above
    # the first mesh and 4 x its true sidebands, was 'the input's comb': 'the pinion shows 21.7 teeth')
    if any({-1, 1} <= {j for j, _ in hits} for _, hits, _ in candidates):
        candidates = [k for k in candidates if len(k[1]) > 1]
    best = None
    for c, hits, spacing in candidates:
        score = sum(a[q] for _, q in hits)
        if best is None or score > best[0] * 1.01 or (score >= best[0] * 0.99 and abs(c - o) < abs(best[1] - o)):
            best = (score, c, hits, spacing)
    if best is None:
        return None
    score, _, hits, spacing = best
    jmax = max(abs(j) for j, _ in hits)
    bins = SIDEBAND_BINS if spacing >= SEPARATED * bin_ else 2.0
    # the furthest sideband's resolution, and no tighter than the comb's lines agree: each reads the spacing d / j
    # alone, and a line fitted keeps (within CONSISTENT_BINS of the others' spacing) draws the fit off theirs: a line
    # 1.2 bins beside M - 2 o, as strong as the first sidebands, read 0.5875 where they read 0.5862 (34/58)
    read = max(abs(float(d[q]) / j - spacing) for j, q in hits)
    tolerance = max(bins * bin_ / jmax, read) + DRIFT * spacing
    return spacing, tolerance, len(hits), {int(near[q]): abs(j) for j, q in hits}, score


def families(
    lines: Lines, mesh: int, orders: tuple[float, float], bin_: float, known=(False, False), exclude=frozenset()
) -> list:
    """The combs of a stage's two shafts around its carrier. A line both combs claim (the third
    sideband of a slow wheel on the first of its pinion's shaft) goes to the comb it is the nearer
    sideband of (|j| the smaller: a first sideband is the likelier), on a tie to the comb of a
    shaft whose order is known already (the tacho's, or measured at the stage before), else to the
    stronger comb; a comb that lost lines is fitted again without them."""
    found = [comb(lines, mesh, o, bin_, exclude, rival) for o, rival in (orders, orders[::-1])]
    if all(found) and found[0][3].keys() & found[1][3].keys():
        rank = [(known[k], found[k][4]) for k in (0, 1)]
        lost: list[set] = [set(), set()]
        for q in found[0][3].keys() & found[1][3].keys():
            j0, j1 = found[0][3][q], found[1][3][q]
            keeper = 0 if (j0 < j1 or (j0 == j1 and rank[0] >= rank[1])) else 1
            lost[1 - keeper].add(q)
        for k in (0, 1):
            if lost[k]:
                found[k] = comb(lines, mesh, orders[k], bin_, exclude | lost[k], orders[1 - k])
    return found


def others_lines(lines: Lines, expected: float, others, bin_: float, own=None, shared: bool = False) -> frozenset:
    """The lines other stages' structure explains, no sidebands of a stage of mesh order *expected*: any harmonic of
    their meshes (off its own) and its sidebands j <= 3 of their shafts it does not carry (*others*: (mesh order,
    those shafts' orders[, the shared shaft's order]) each). A 22/63 last stage's 6th harmonic, 1.2 below a 15/47
    first mesh, and its sidebands read as the input shaft's comb: 'the pinion shows 12.5 teeth'. A shaft both carry
    modulates both: with *shared* (for the combs; a comb's checks, modulation and lone, count them as that shaft's
    evidence) its sidebands of their harmonics outside the stage's own comb of it (3.9 of its orders) are theirs
    only where no own sideband lies within a bin of the line or nearer it (23/77 + 34/49: 2 M2 - o2 = M1 - 2.9871,
    2.6 bins off the input's 3rd, made the input's comb 0.9968: 'input shaft: order 0.9968 measured, 1 expected').
    Its products with the other stage's own shaft, a o_shared +- b o (a, b = 1-3), are that stage's only (19/48 +
    25/94 + 17/48: stage 2's 2 M2 + o1 + o2 lies at M1 + 1.293 and the input's comb read 'the pinion shows 14.7
    teeth'), save a line on one of the stage's own sidebands (*own*: its mesh line, its shafts' orders), which the
    products, 36 a harmonic, pass near by chance (a 15/56 + 13/33 wheel read 33.0 teeth, 34 described, lost its
    comb)."""
    # kind: 0 a carrier, 1 a sideband, 2 a product of two shafts, 3 a sideband of the shaft both stages carry
    at, kind, step, js = [], [], [], (-3, -2, -1, 1, 2, 3)
    for m, shaft_orders, *both in others:
        offsets = [(0.0, 0, 0.0)] + [(j * o, 1, 0.0) for o in shaft_orders for j in js]
        offsets += [(j * o, 3, o) for o in (both[0] if both and shared else ()) for j in js]
        if both and len(both[0]) == 1 and len(shaft_orders) == 1:
            offsets += [(a * both[0][0] + b * shaft_orders[0], 2, 0.0) for a in js for b in js]
        for h in range(1, MAX_HARMONIC + 1):
            if abs(h * m / expected - round(h * m / expected)) > 1e-9:  # on the stage's own harmonic: both
                at += [h * m + off for off, _, _ in offsets]
                kind += [k for _, k, _ in offsets]
                step += [o for _, _, o in offsets]
    if not at:
        return frozenset()
    at, kind, step = np.array(at), np.array(kind), np.array(step)
    # a carrier within tol_mesh; a sideband within 2 bins and a tenth of the drift allowance: at DRIFT's 1e-3 of
    # order 14 a 15/47 input comb's own -1 line (14.000) fell within 0.019 of a later stage's sideband
    # (13.8004 + 0.2091), the comb lost it and another won
    tol = np.where(kind == 0, tol_mesh(at, bin_), 2 * bin_ + 0.1 * DRIFT * at)
    theirs = np.abs(lines.at[:, None] - at[None, :])
    near = theirs <= tol[None, :]
    if own is not None:
        sidebands = np.array([own[0] + j * o for o in own[1] for j in js])
        off = np.abs(lines.at[:, None] - sidebands[None, :])
        on_own = off <= 2 * bin_ + 0.1 * DRIFT * sidebands[None, :]
        near[:, kind == 2] &= ~on_own.any(axis=1)[:, None]
        # another stage's sideband that lies nearer an own one than its own place (a 19/48 + 25/94 + 17/48 box: 2 M2 +
        # 2 o_i2 = M1 + 1.0022, 0.7 bin from the input's first sideband, M1 + 1.0002; the input's comb lost it)
        closer = on_own.any(axis=1)[:, None] & (off.min(axis=1)[:, None] < theirs)
        near[:, kind == 1] &= ~closer[:, kind == 1]
        within = off.min(axis=1)[:, None] <= CONSISTENT_BINS * bin_ + 0.1 * DRIFT * at[None, :]
        near[:, kind == 3] &= ~(closer | within)[:, kind == 3]
        # within the stage's own comb of that shaft (3.9 of its orders, as comb looks) both meshes' sidebands of it
        # lie on one grid (M1 = z_w1 o, h M2 = h z_p2 o): the same lines (36/65 + 33/76: 2 M2 + o = M1 + 2 o)
        near[:, (kind == 3) & (np.abs(at - own[0]) <= 3.9 * step)] = False
    else:
        near[:, kind == 3] = False  # no own place to weigh the shared shaft's lines against: both stages'
    return frozenset(np.flatnonzero(near.any(axis=1)).tolist())


def sidebands_of(lines: Lines, carriers, spacing: float, rival: float, bin_: float, skip=frozenset()) -> list[int]:
    """The lines j *spacing* (j = ±1..3) off the lines *carriers* (indices), each nearer such a sideband than one of
    *rival* (a line both explain is the nearer's), none of them in *skip* (carriers, other stages' lines)."""
    out: set[int] = set()
    for c in carriers:
        for q in np.flatnonzero(np.abs(lines.at - lines.at[c]) <= 3.5 * max(spacing, rival)):
            d = abs(float(lines.at[q] - lines.at[c]))
            if q in skip or q == c or d == 0.0:
                continue
            j = min(3, max(1, round(d / spacing)))
            mine = abs(d - j * spacing)
            if mine <= 2 * bin_ + DRIFT * j * spacing and mine < min(abs(d - r * rival) for r in (1, 2, 3)):
                out.add(int(q))
    return sorted(out)


def modulation(lines: Lines, carriers, found: tuple, described: float, orders, bin_: float, skip=frozenset()):
    """(the described spacing's lines, the comb's, the half spacing's) where a shaft's comb *found* (comb's tuple),
    off its *described* spacing (the mesh over the described count), is the 2nd sideband of another modulation,
    not the shaft's order; else None. A shaft's modulation repeats once a turn: its sidebands lie at whole
    multiples of its order. Around the lines *carriers* (the harmonics of the meshes on that shaft), lines at odd
    multiples of half the comb's spacing, no shaft's order (*orders*), as many and as strong as the comb's own, make
    it a modulation repeating every other 'turn'; and the described spacing's sidebands (two lines at least) say the
    shaft turns as described. A tacho's timing error phase-modulates every line of order k by k phi: AF's tacho (a
    resampled angle ramp, 1.5-9 mrad at 5 and 10 Hz) put +-0.161 (5 Hz at 31 Hz) beside every line of a 23/59 +
    19/67 box and 0.322 beside its strongest, read as '71 teeth' where 14 lines carry the 59 teeth's 2 x 0.3898; a
    sampled TTL tacho at 33 Hz (edges +-0.5 sample, cycling at 0.2424 orders), 0.4848: 'the pinion shows 15.3
    teeth'. A count really off keeps its comb: no half-spacing lines (19/44 + 29/67 + 25/62 read with 66 teeth)."""
    spacing = found[0]
    # half the spacing a shaft's order, as described or as the comb would scale every shaft (a count off on this
    # shaft alone moves the next shaft with it: a 19/38 stage after it turns at half the comb): its 2nd sidebands
    if any(abs(spacing / 2 - o * f) <= 2 * bin_ + DRIFT * o for o in orders for f in (1.0, spacing / described)):
        return None
    ours = sidebands_of(lines, carriers, described, spacing, bin_, skip)
    theirs = sidebands_of(lines, carriers, spacing, described, bin_, skip)
    half = [q for q in sidebands_of(lines, carriers, spacing / 2, described, bin_, skip) if q not in theirs]
    power = [float(np.sum(lines.amp[q] ** 2)) if q else 0.0 for q in (half, theirs)]
    if len(ours) >= 2 and len(half) >= max(2, len(theirs)) and power[0] >= power[1]:
        return ours, theirs, half
    return None


def lone(lines: Lines, carriers, found: tuple, described: float, bin_: float, skip=frozenset()) -> bool:
    """Whether a shaft's comb *found* (comb's tuple) of one or two lines is outweighed by the *described* spacing's
    own sidebands around that shaft's meshes (*carriers*): LONE_LINES of them or more, the strongest LONE_DB over
    the comb's. A line or two near the threshold is no shaft's order: a 23/59 + 19/67 box at 43 Hz (171 turns)
    carries a line at order 29.333 (1261 Hz, 14.4-15.3 dB over the floor, THRESHOLD_DB 15) 0.2949 under stage 2's
    4th mesh harmonic; which 171 turns the mark starts put it over the threshold or not, and over it it alone read
    'the pinion on the intermediate shaft shows 25.1 teeth', where 9 lines (22-45 dB) lie 0.3898 (19 teeth) off the
    meshes. At 37 Hz a pair 15.0 Hz either side of the first mesh (0.4058, 17 dB; on no other mesh of that shaft)
    read 'the wheel shows 56.7 teeth', 8 lines (15-39 dB) 0.3898 off.

    A comb of up to three lines, one of them nearer the described spacing's sideband than its own (on_described),
    is outweighed too where the described spacing's sidebands hold LONE_LINES or more, more than the comb's
    spacing's, and their strongest is no weaker than its strongest."""
    if found[2] > 3:
        return False
    ours = sidebands_of(lines, carriers, described, found[0], bin_, skip)
    top = max(float(lines.amp[q]) for q in found[3])
    if len(ours) < LONE_LINES:
        return False
    strongest = float(np.max(lines.amp[ours]))
    return (found[2] <= 2 and strongest >= top * 10 ** (LONE_DB / 20)) or on_described(
        lines, carriers, found, described, ours, bin_, skip
    )


def on_described(lines: Lines, carriers, found: tuple, described: float, ours: list, bin_: float, skip) -> bool:
    """Whether a comb *found* of up to three lines reads its spacing from one line off the described comb: one of its
    own lines is the *described* spacing's sideband (in *ours*, the described spacing's sidebands around *carriers*)
    and on its own within CONSISTENT_BINS, and the comb's spacing holds fewer sidebands there, none stronger. A
    sideband's spacing is read from lines on the comb within the resolution: PHM 2009's spur3 at 40 Hz, high load
    (channel 1, 159 turns) carries the output shaft's first sideband at 16 - 0.1995 and a line 16 - 0.5856, 2.3 bins
    off its 3rd (a line 0.0811 off the mesh with the idler's sidebands); the fit weighting the 3rd sideband nine-fold
    read 0.1957: 'the wheel shows 81.8 teeth, 80 described', where 0.2's sidebands hold 3 lines about the meshes (16
    and 32), to 4-5 dB over the comb's, and 0.1957's one."""
    shared = set(found[3]) & set(ours)
    if found[2] > 3 or not shared:
        return False
    # the lines both spacings take sit on the comb's own too (as fitted keeps them): only its others tell them apart
    at = lines.at[sorted(carriers)]
    for q in shared:
        off = np.min(np.abs(np.abs(lines.at[q] - at) - found[3][q] * found[0]))
        if off > CONSISTENT_BINS * bin_ + DRIFT * found[3][q] * found[0]:
            return False
    theirs = sidebands_of(lines, carriers, found[0], described, bin_, skip)
    strongest = float(np.max(lines.amp[theirs])) if theirs else 0.0
    return len(ours) > len(theirs) and float(np.max(lines.amp[ours])) >= strongest


def whole(found: tuple, z: float, bin_: float) -> bool:
    """Whether a shaft's comb *found* (comb's tuple), reading *z* teeth (the mesh order over its spacing), fits a
    whole count: a shaft's sidebands lie at whole multiples of its order, and its mesh at z of them, so the spacing
    lies within CONSISTENT_BINS / its furthest sideband (as fitted keeps a comb's lines) of M / n for a whole n. A
    line that is no order of any shaft is no shaft's sideband: a 27/52 + 40/70 box at 38.03 Hz, simulated at
    200 kHz, carries stage 1's 194th mesh harmonic folded about that rate (200 kHz - 194 x 1026.7 Hz = 813.4 Hz,
    order 21.389), alone 0.6201 above stage 2's mesh (20 dB): 'the pinion on the intermediate shaft shows 33.5 ±
    0.2 teeth, 40 described' of the true description, 1.4 bins off M / 33 and M / 34."""
    spacing, jmax = found[0], max(found[3].values())
    mesh, bins = z * spacing, CONSISTENT_BINS if spacing >= SEPARATED * bin_ else 2.0
    off = min(abs(spacing - mesh / n) for n in {max(1, math.floor(z)), math.ceil(z)})
    return off <= bins * bin_ / jmax + DRIFT * spacing


def train_wide(lines: Lines, own, elsewhere, found: tuple, described: float, bin_: float, skip=frozenset()) -> bool:
    """Whether a shaft's comb *found* (comb's tuple), off its *described* spacing, stands around meshes its shaft does
    not carry (the lines *elsewhere*), on two lines or more, as a swing of the whole train's speed or load puts it:
    a swing modulates every mesh, a shaft's turn its own. Its strongest sideband over its carrier there is at least
    TRAIN_WIDE of that around the shaft's strongest mesh line (of *own*; none there: its strongest). A conveyor's
    45/119 + 28/123 reducer at 0.74 Hz, its speed swinging 0.2-0.4 % at 0.05 Hz (0.0673 input orders, its output
    turning at 0.0861), was read 'the wheel on the output shaft shows 158.3 ± 32.6 teeth' from the swing's sidebands,
    as strong as their carrier around the first mesh (order 45), 0.33 of it around the second, the output's."""
    if not elsewhere or not own:
        return False

    def over(carriers) -> tuple[int, float]:
        near = {c: sidebands_of(lines, [c], found[0], described, bin_, skip) for c in carriers}
        top = max((float(lines.amp[q] / lines.amp[c]) for c, qs in near.items() for q in qs), default=0.0)
        return sum(map(len, near.values())), top

    theirs, their_top = over(elsewhere)
    our_top = over([max(own, key=lambda c: lines.amp[c])])[1] or over(own)[1]
    return theirs >= 2 and their_top >= TRAIN_WIDE * our_top
