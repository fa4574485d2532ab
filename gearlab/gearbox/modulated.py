"""A mesh whose sidebands outgrow its line (gearbox.match reads each stage with it): under load, or with a fault or
an eccentric gear, the sidebands of a shaft the stage's gears sit on can stand at or above the mesh line itself
(PHM 2009 at high load: the strongest idler sideband within 2/3 order of the 32nd stood 0.3-4.8 dB over the mesh line
in five records of 48), and a reading of the strongest comb takes a sideband for the mesh: 'mesh order 31.33
measured, 32 expected (a 31-tooth pinion?)' of a true description.

The analyst's rule: amplitude modulation by a shaft puts sidebands at +-j times its order about the mesh, a family
symmetric about its centre. A measured order j such spacings (j = 1-3) from the described M, with a line at M (the
family's centre) and one at its mirror (M - d), is the described mesh, not another tooth count (centre), unless the
count search over whole counts of the pinion's shaft alone reads another count (then that count's mesh, not the
sideband, is the reading). A tooth count never explains itself away so: a pinion a tooth off moves its mesh by a
whole order of the pinion's shaft (with a tacho on the input, by whole orders: a 33-tooth pinion's mesh at 33 has its
input sideband at 32), a wheel upstream by z / (z + j) of its order; such offsets are left to the count search
(gearbox.outshone.counts), whatever sideband they also equal (the 32/96 stage's 3rd idler sideband is one input
order). Read only where a tacho gives the pinion shaft's order before this stage (no speed fitted to the lines that
could move instead).
"""

from __future__ import annotations

from .outshone import COUNTS, counts
from .sideband_combs import tol_mesh
from .speed import Lines

SIDEBANDS = (1, 2, 3)  # the sideband orders j a measured mesh is tried as


def _offset_of(d: float, shafts: tuple[float, ...], tol: float) -> bool:
    """Whether the offset *d* is j times the order of one of *shafts* (j in SIDEBANDS)."""
    return any(abs(abs(d) - j * o) <= tol for o in shafts if o > 0 for j in SIDEBANDS)


def centre(
    lines: Lines, table, k: int, look: float, measured: float, shafts: tuple[float, float], bin_: float, theirs, comb
) -> tuple[int, float] | None:
    """(index of a line, the mesh order) of stage *k* where its reading *measured* is a sideband of a mesh (module
    doc): the described *look* where no whole count of the pinion's shaft beats it, else that count's (the count
    search over whole counts only: *comb*, gearbox.match.harmonic_comb, with *theirs*, the other stages' lines); None
    where the rule says nothing. *shafts*: the orders of the pinion's and the wheel's shaft."""
    tol, o_p, d = tol_mesh(look, bin_), shafts[0], measured - look
    if o_p <= 0:
        return None
    # a whole count of the pinion, or a wheel upstream a tooth or three off, puts the mesh there: no sideband's
    if abs(d) <= tol or abs(d / o_p - round(d / o_p)) * o_p <= tol:
        return None
    if any(abs(measured - c * look / float(table.stages[k].mesh)) <= tol for c, *_ in counts(table, k)):
        return None
    # no count puts a mesh there, the pinion's shaft turning as the tacho reads it: a count's own mesh is the reading
    found = comb(lines, [look] + [look + j * o_p for j in COUNTS], bin_, theirs)
    if found is not None and abs(found[1] - look) > tol:
        return found
    if not _offset_of(d, shafts, tol):
        return None
    i, mirror = lines.near(look, tol), lines.near(look - d, tol_mesh(look - d, bin_))
    return None if i is None or mirror is None else (i, float(lines.at[i]))
