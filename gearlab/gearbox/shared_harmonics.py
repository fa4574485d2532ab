"""A later mesh described at a simple fraction of another stage's mesh (gearlab.gearbox.match.check_description reads
each stage with it): its 2nd or 3rd harmonic falls on the other mesh's lines, so those lines say nothing of it. A
16/52 + 25/61 box described with a 26-tooth stage-2 pinion puts stage 2 at 8.000 = 16 / 2: its 2nd, 4th, 6th harmonics
are stage 1's 16, 32, 48, the real mesh (7.692, one intermediate-shaft order lower) put its 26th harmonic on 200 = 25 x
8 and two sidebands of its 24th and 28th on 184 and 216, and the stage 'matched' (inspect and the gap).

The analyst's rule: such a mesh is evidenced only by its OWN harmonics, those on no other mesh's harmonic (for 16 / 2:
the odd ones, 8, 24, 40), and a mesh shows its low ones (gearbox.outshone.family asks two of the first three): where
its first OWN_LOW own harmonics show no line, the described order is borrowed, and the stage is read where a count a
tooth or three off puts it (its pinion, its wheel, a wheel upstream: match's count search), as where every line at its
harmonics is another mesh's (36/84 + 27/69 described with 28: M2 = 12 = 36 / 3).
"""

from __future__ import annotations

from .sideband_combs import tol_mesh
from .speed import MAX_HARMONIC, Lines

FRACTION = 3  # a mesh whose 2nd or 3rd harmonic is another's: a half, a third or two thirds of it
OWN_LOW = 3  # the own harmonics (first ones, off the other meshes' harmonics) a described mesh must show one line at


def borrowed(lines: Lines, m: float, bin_: float, shared) -> bool:
    """Whether nothing of its own says a mesh turns at the order *m*: every line at a harmonic of it sits on another
    stage's mesh harmonic (*shared*: (order, tolerance)), or, *m* a simple fraction of such a mesh (its harmonic 2 to
    FRACTION on one of *shared*), no line stands at its first OWN_LOW harmonics off *shared* (module doc)."""

    def theirs(x: float) -> bool:
        return any(abs(x - o) <= t for o, t in shared)

    on = [q for h in range(1, MAX_HARMONIC + 1) if (q := lines.near(h * m, tol_mesh(h * m, bin_))) is not None]
    if not on:
        return False
    if all(theirs(float(lines.at[q])) for q in on):
        return True
    if not any(theirs(h * m) for h in range(2, FRACTION + 1)):
        return False
    own = [h for h in range(1, MAX_HARMONIC + 1) if not theirs(h * m)][:OWN_LOW]
    seen = (lines.near(h * m, tol_mesh(h * m, bin_)) for h in own)
    return not any(q is not None and not theirs(float(lines.at[q])) for q in seen)
