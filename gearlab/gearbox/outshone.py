"""A described mesh read on a line far weaker than an order family beside it that the description does not
explain (gearlab.gearbox.match.check_description): a gearbox's strongest lines are its meshes, so a weak line
at the described order with such a family near it is no mesh of the description; the family is the mesh and
a tooth count differs. A 27/57 + 35/69 box described with a 56-tooth first wheel put stage 2 at 16.875: a
line 18 dB over the floor was read as that mesh, while the real one, 16.579 (harmonics 1-3 at 48, 63 and 68 dB),
0.3 orders off, was explained by nothing described and the verdict said 'matches'. Nor does a sideband of the weak
line explain a line OUTSHONE_DB over its mirror image (unpaired): a count a tooth off puts the real mesh's harmonics on
the described one's sidebands, on one side alone (38/69 + 22/51 described with a 23-tooth second pinion: the real
12.116's harmonics 1-3 on the described 12.667's sidebands -1 to -3 of its pinion's shaft, 38 dB over the line it was
read on; 32/66 + 26/62 described with 65: the real 12.606's on the output shaft's, 45 dB), while a modulation's stand
in pairs.
"""

from __future__ import annotations

import numpy as np

from .sideband_combs import tol_mesh
from .speed import MAX_HARMONIC, Lines

# A family this much stronger than the described mesh's strongest line (its own harmonics) outshines it: on the
# development boxes (seeds 5120-5191) the true descriptions put no family at a count's order at all, the PHM 2009
# rig's records (its mesh lines under input-shaft sidebands) one 6.5 dB over the stage-2 mesh at most; a 37/97 +
# 28/77 box described with 96 teeth put the real stage-2 mesh 22 dB over the described order's line, 27/57 + 35/69
# with 56 at 50 dB. A sideband of the described mesh this much over its mirror image is unpaired (unpaired)
OUTSHONE_DB = 12.0
COUNTS = (-3, -2, -1, 1, 2, 3)  # the counts tried: a gear this many teeth off


def family(lines: Lines, m: float, bin_: float, free: np.ndarray) -> tuple[float, float] | None:
    """(order refitted over the lines in *free* at harmonics 1-MAX_HARMONIC of *m*, the amplitude of the strongest
    of them at harmonics 1-3), or None where fewer than two of its first three harmonics hold one: a mesh shows
    its low harmonics, a bearing's or any line's h-th subharmonic does not, and a rich record's lines (the PHM
    2009 rig's) fall on some high harmonic of any order (its strongest such family 5 dB over its stage-2 mesh)."""
    h = np.maximum(1.0, np.round(lines.at / m))
    hit = free & (np.abs(lines.at - h * m) <= tol_mesh(lines.at, bin_)) & (h <= MAX_HARMONIC)
    low = hit & (h <= 3)
    if np.count_nonzero(low) < 2:
        return None
    w = lines.amp[hit] ** 2
    return float(np.sum(w * h[hit] * lines.at[hit]) / np.sum(w * h[hit] ** 2)), float(lines.amp[low].max())


def counts(table, k: int) -> list[tuple[float, str, dict]]:
    """(mesh order, the count that puts it there, that gear: {stage, gear, seen, described}) of stage *k* of *table*
    where its pinion, or a wheel of a stage before it, is a tooth or three off the described count (COUNTS): a
    wheel upstream moves the mesh by z / (z + j) of its order, no whole tooth of the pinion's shaft."""
    s, look = table.stages[k], float(table.stages[k].mesh)
    gears = [(s.pinion_teeth, "pinion", s.pinion_shaft, 1, k + 1)] + [
        (t.wheel_teeth, "wheel", t.wheel_shaft, -1, i + 1) for i, t in enumerate(table.stages[:k])
    ]
    out = []
    for z, role, shaft, way, n in gears:  # a pinion's count moves its mesh with it, a wheel's against it
        words = f"a {{}}-tooth {role} on the {shaft} shaft puts it there, {z} described"
        gear = {"stage": n, "gear": role, "described": int(z)}
        out += [(look * ((z + j) / z) ** way, words.format(z + j), gear | {"seen": float(z + j)}) for j in COUNTS]
    return out


def unpaired(lines: Lines, look: float, bin_: float, own: list[bool]) -> np.ndarray:
    """Which lines, explained only as sidebands of the mesh *look* (*own*), stand OUTSHONE_DB or more over the line
    at their mirror image across its harmonic (none counts as the floor): a mesh's modulation puts its sidebands in
    pairs, a count a tooth off puts the real mesh on one side alone (the PHM 2009 rig's input-shaft sidebands, over
    its stage-2 mesh lines, stand in pairs)."""
    out = np.zeros(lines.at.size, dtype=bool)
    for q in np.flatnonzero(own):
        x = float(lines.at[q])
        h = max(1.0, round(x / look))
        mirror = lines.near(2 * h * look - x, tol_mesh(x, bin_))
        out[q] = mirror is None or lines.amp[q] >= lines.amp[mirror] * 10 ** (OUTSHONE_DB / 20)
    return out


def outshone_line(lines: Lines, stages: list[dict], table, bin_: float, explained) -> str | None:
    """The line saying the first later stage read at its described mesh order (check_description's *stages*)
    is outshone: OUTSHONE_DB under a family of lines no described mesh, harmonic or sideband explains
    (*explained*(order, stage): whether an order is one, that stage's sidebands left out) at the order one count puts
    it (counts), or None. The first stage's mesh is left to check_description: a pinion count moves it a whole order
    of its shaft, which it reads."""
    for k, entry in enumerate(stages[1:], start=1):
        if not entry.get("matched") or not entry.get("amplitude"):
            continue
        look, best = float(entry["expected_order"]), None
        alone = np.array([not explained(float(x)) for x in lines.at], dtype=bool)
        free = alone | unpaired(lines, look, bin_, [not explained(float(x), k) for x in lines.at])
        if not free.any():
            continue
        for m, what, gear in counts(table, k):
            got = family(lines, m, bin_, free)
            if got is None or abs(got[0] - m) > tol_mesh(m, bin_) or abs(got[0] - look) <= tol_mesh(look, bin_):
                continue
            # the same lines may fit two counts (a 108-tooth first wheel and a 93-tooth second one of 39/109 +
            # 44/94 + 62/101, 0.015 apart): the count putting the mesh nearest the refitted order is named
            top, near = got[1], -abs(got[0] - m)
            if top >= entry["amplitude"] * 10 ** (OUTSHONE_DB / 20) and (best is None or (top, near) > best[1:3]):
                best = (got[0], top, near, what, family(lines, m, bin_, alone) is None, gear)
        if best is None:
            continue
        m, top, _, what, on_sidebands, gear = best
        db = 20 * np.log10(top / entry["amplitude"])
        but = " but as that line's sidebands, unpaired" if on_sidebands else ""
        line = (
            f"stage {k + 1}: the strongest lines near the described mesh order {look:.4g} stand at {m:.4g} (its "
            f"harmonics, {db:.0f} dB over the line the mesh was read on, explained by nothing described{but}): that "
            f"is the mesh: {what}"
        )
        entry["outshone"] = {"order": m, "db": float(db), "line": line, "gear": gear}  # the gap says it too
        return line
    return None


def unnamed(findings: list[dict]) -> bool:
    """Whether check_description's *findings* name no gear the outshone check would contradict: each is a later
    stage's sideband reading, a pinion as described on a shaft turning off, or one following from another stage
    (39/108 + 44/93 + 62/101, 109 real: stage 2 read on its own sideband, only stage 3's shaft said to turn 0.9 %
    off; or that stage's wheel count read off the weak line's sidebands, '94.1 +- 1.0 teeth', seeds 1 and 8)."""
    return all(
        f["kind"] == "pinion_as_described" or f["follows"] or (f["kind"] == "sidebands" and f["stage"] != 1)
        for f in findings
    )


def outshone_first(findings: list[dict], stages: list[dict], line: str) -> list[dict]:
    """*findings* led by the outshone stage's *line* (outshone_line set its entry's 'outshone'), less that stage's
    tooth counts read off the sidebands of the weak line its mesh was read on: the line explains them (39/109 +
    44/93 + 62/101 described with 108 also said 'stage 2: the wheel ... shows 94.1 +- 1.0 teeth')."""
    entry = next(e for e in stages if "outshone" in e)
    k = entry["stage"]
    lead = dict(kind="outshone", stage=k, gear=None, guess=None, follows=[], text=line, bare=line)
    lead["names"] = entry["outshone"]["gear"]
    return [lead] + [f for f in findings if not (f["kind"] == "sidebands" and f["stage"] == k)]
