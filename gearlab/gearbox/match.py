"""A gearbox description's orders tested against the spectral lines of a record (docs/gearbox.md):
every stage's mesh order (the carrier at M, or the fundamental of the harmonic family the lines hold)
and each shaft's order from the sidebands around the measured mesh (z = M / o). `gearlab inspect`
reads a record's lines with it, the gap diagnosis's structure check (gearlab.gap.structure) a
target's and a source's. The sideband combs and the tolerances of lines and spacings:
gearlab.gearbox.sideband_combs; the harmonic family of a stage's strongest lines: gearlab.gearbox.mesh_family.
"""

from __future__ import annotations

import math
import re

import numpy as np

from .described_comb import comb_reading, described_holds
from .description import Gearbox
from .mesh_family import mesh_family
from .modulated import centre
from .orders import order_table
from .outshone import counts, outshone_first, outshone_line, unnamed
from .shared_harmonics import borrowed
from .sideband_combs import (
    SEPARATED,
    SIDEBAND_BINS,
    families,
    lone,
    modulation,
    others_lines,
    tol_mesh,
    train_wide,
    whole,
)
from .speed import DRIFT, MAX_HARMONIC, SPAN, Lines

UNEXPLAINED_DB = -30.0  # unexplained lines listed down to this level below the strongest line
# ... and, whatever their level against it, where they are no shaft's harmonic and stand this far over the
# spectrum's floor (shaft_harmonic: a fixed frequency read at one speed, or a bearing's line): a steady
# take's 50 Hz hum (0.02 g on a 31/73 box, 36.7 dB over the floor) sat 31.8 dB under the 73rd order's mesh
# line and was not listed, while a run-up's (the mesh smeared over orders) was
UNEXPLAINED_FLOOR_DB = 30.0


def harmonic_comb(lines: Lines, candidates: list[float], bin_: float, theirs) -> tuple[int, float] | None:
    """(index of the strongest line, mesh order refitted over its harmonics) of the candidate mesh
    order the lines bear out, lines on another stage's harmonics (*theirs*) left out, or None. The
    first candidate is the description's M; another, M + j o (a tooth count off by j), is taken when
    its line is the stronger over the floor at each of the first three harmonics where either has
    one (two at least) and its harmonics hold more power: a real mesh's sidebands can outgrow its
    line at one harmonic (PHM 2009, 40 Hz, low load: 124 over 128) but not at its first ones. Of such
    counts, the one stronger at more of the first three harmonics than another."""
    keep = np.array([not any(abs(a - o) <= t for o, t in theirs) for a in lines.at], dtype=bool)
    harmonics = np.arange(1, MAX_HARMONIC + 1)

    def comb(c: float) -> tuple[np.ndarray, list, float]:
        # every harmonic's window at once: the products and comparisons of one harmonic at a time, element by
        # element (40 harmonics a candidate, a few candidates a stage: 3.5 ms of CPU a call, one at a time; 1.2 ms)
        inside = keep & (np.abs(lines.at - (harmonics * c)[:, None]) <= (2 * bin_ + DRIFT * harmonics * c)[:, None])
        rows = np.flatnonzero(inside.any(axis=1))
        db, found = np.full(3, -np.inf), []
        if rows.size:
            strongest = np.where(inside[rows], lines.db, -np.inf).argmax(axis=1)
            # a window of lines all at -inf dB: its first line, as argmax over the window's own lines takes
            strongest = np.where(inside[rows, strongest], strongest, inside[rows].argmax(axis=1))
            found = [(int(r) + 1, int(q)) for r, q in zip(rows, strongest)]
        for h, q in found[:3]:
            if h <= 3:
                db[h - 1] = lines.db[q]
        return db, found, float(sum(lines.amp[q] ** 2 for _, q in found))

    def margin(db: np.ndarray, other: np.ndarray) -> int:  # harmonics 1-3 *db* is the stronger at, less those it is not
        seen = np.isfinite(db) | np.isfinite(other)
        return int(np.sum(db[seen] > other[seen]) - np.sum(db[seen] <= other[seen]))

    described, found, held = comb(candidates[0])
    best, least = described, held
    for c in candidates[1:]:
        db, hits, power = comb(c)
        seen = np.isfinite(db) | np.isfinite(described)
        if seen.sum() < 2 or not np.all(db[seen] > described[seen]) or power <= least:
            continue
        # of two counts that both outgrow the described one, the one stronger at more of the first harmonics: a
        # 14-tooth pinion's 1st sideband (13, 41 dB) outgrew its mesh line (14, 36 dB), but not its 2nd and 3rd
        if best is described or margin(db, best) > 0 or (margin(db, best) == 0 and power > held):
            best, found, held = db, hits, power
    if not found:
        return None
    h, q = np.array([f[0] for f in found], dtype=float), np.array([f[1] for f in found])
    w = lines.amp[q] ** 2
    return int(q[np.argmax(w)]), float(np.sum(w * h * lines.at[q]) / np.sum(w * h * h))


def lead(table, q: int, moved: dict) -> float:
    """What the nearest stage before shaft or stage *q* whose mesh moved (*moved*: stage -> its measured
    order) moves the orders after it by: every later shaft turns at that measured mesh over the described
    wheels (a 15-tooth input pinion described 16 puts stage 2 of 19/58 at 6.064, not 6.468)."""
    p = max((i for i in moved if i < q), default=None)
    return 1.0 if p is None else moved[p] / float(table.stages[p].mesh)


def other_stages(table, k: int, moved: dict, measured_shaft: dict, leads: bool = True, ahead=None) -> list:
    """(mesh order, orders of its shafts stage *k* does not carry, those it does) of every other stage of
    *table*, as measured where it was (an earlier stage's moved mesh, a later one's located *ahead*, a shaft's
    sidebands or tacho), else as a moved mesh before it makes it (lead)."""

    def order(i: int) -> float:
        return measured_shaft.get(i, (float(table.shaft_orders[i]) * (lead(table, i, moved) if leads else 1.0),))[0]

    return [
        (
            moved.get(q, (ahead or {}).get(q, float(t.mesh) * (lead(table, q, moved) if leads else 1.0))),
            [order(i) for i in (q, q + 1) if i not in (k, k + 1)],
            [order(i) for i in (q, q + 1) if i in (k, k + 1)],
        )
        for q, t in enumerate(table.stages)
        if q != k
    ]


def harmonics(meshes: list[float], bin_: float) -> list[tuple[float, float]]:
    """(order, tolerance) of every harmonic (1-MAX_HARMONIC) of the mesh orders *meshes*."""
    return [(h * m, tol_mesh(h * m, bin_)) for m in meshes for h in range(1, MAX_HARMONIC + 1)]


def off_own(shared: list[tuple[float, float]], look: float) -> list[tuple[float, float]]:
    """Those of the other stages' harmonics *shared* not within their tolerance of a harmonic of the mesh *look*: a
    line there is both stages' (a wrong later description can put a harmonic on the first mesh: 14/53 + 17/59 +
    23/67 for 18 puts the last mesh's 8th at 14.0045, and the first mesh, left out of its own comb, let stage 2's
    3rd, 14.264, take it)."""
    return [(x, t) for x, t in shared if abs(x - max(1, round(x / look)) * look) > t]


def at_harmonics(lines: Lines, meshes, bin_: float) -> set[int]:
    """The lines at the harmonics (1-MAX_HARMONIC) of the mesh orders *meshes*."""
    got = (lines.near(h * m, tol_mesh(h * m, bin_)) for m in meshes for h in range(1, MAX_HARMONIC + 1))
    return {q for q in got if q is not None}


def ahead_family(lines: Lines, family: tuple, m: float, bin_: float, theirs) -> tuple:
    """*family* (mesh_family's), or the family of the mesh order *m* located_ahead found where all its lines are
    harmonics of *m*: they are that mesh's, no mesh of their own (37/97 + 28/77 described with a 96-tooth first wheel:
    the real 10.680's 4th and 8th harmonics, 42.72 and 85.44, taken as a 14.24 family of whole teeth, 'a 37-tooth
    pinion on the intermediate shaft')."""
    if not all(abs(x / m - round(x / m)) * m <= tol_mesh(x, bin_) for x in family[2]):
        return family
    on = [q for q in at_harmonics(lines, [m], bin_) if not any(abs(lines.at[q] - o) <= t for o, t in theirs)]
    return (m, max(on, key=lambda q: lines.amp[q]), lines.at[on]) if on else family


def located_ahead(lines: Lines, table, bin_: float, tacho_shaft: int | None) -> dict:
    """{stage: its mesh order} of a later stage whose mesh the lines put a whole tooth off the described order (M + j o,
    either shaft's o as described; harmonic_comb), and of the stages after it, before any stage is read: an earlier
    stage's combs leave a later stage's lines out where they are, not where a wrong description puts them (14/53 +
    18/59 + 23/67 described with 17 for 18: stage 2's 3rd harmonic, 14.264, sits on the first mesh's wheel sideband,
    and read as one with its load sidebands it gave the intermediate shaft 0.2917 and 'the wheel shows 48.0 teeth')."""
    for k, s in enumerate(table.stages):
        m = float(s.mesh)
        if tacho_shaft is not None and tacho_shaft > k:
            continue  # behind a tacho on a later shaft no count moves the mesh by a whole tooth (check_description)
        theirs = off_own(harmonics([float(t.mesh) for q, t in enumerate(table.stages) if q != k], bin_), m)
        offsets = [j * float(o) for o in (s.pinion_shaft_order, s.wheel_shaft_order) for j in (-3, -2, -1, 1, 2, 3)]
        # an earlier wheel a tooth or three off moves this mesh by z / (z + j), no whole tooth of its own (21/65 +
        # 34/91 described with 64, 57 turns: stage 2 at 10.985 left unplaced, its 2nd harmonic, M1 + 0.968, pulled
        # the input's comb off its true sideband: 'the pinion on the input shaft shows 21.7 teeth')
        offsets += [
            m * t.wheel_teeth / (t.wheel_teeth + j) - m for t in table.stages[:k] for j in (-3, -2, -1, 1, 2, 3)
        ]
        got = harmonic_comb(lines, [m] + [m + d for d in offsets], bin_, theirs)
        if got is not None and abs(got[1] - m) > tol_mesh(m, bin_):
            # the first such stage, after stages where described: a moved mesh moves every later one by no whole
            # tooth (a 22/69 + 25/74 described with 23 for 22, no tacho, read with a later line at M + j o as stage
            # 2's, was told 'a 24-tooth pinion on the intermediate shaft'); they turn at it over the described
            # wheels (lead), where the orders are the input's
            after = {q: float(t.mesh) * got[1] / m for q, t in enumerate(table.stages) if q > k}
            return ({k: got[1]} | (after if tacho_shaft in (None, 0) else {})) if k else {}
    return {}


def check_description(
    lines: Lines, box: Gearbox, revolutions: int, tacho_on_input: bool, tacho_shaft: int | None = None, beyond=()
) -> dict:
    """Every stage's mesh order and every shaft's order tested against the lines (module doc). A tacho
    on another shaft (*tacho_shaft*, its index) gives that shaft's order: the revolutions are its turns
    over the described ratio (a 23/61 fan's output tacho: its sidebands read 0.3812, 'the wheel shows
    60.3 ± 0.2 teeth, 61 described' of the right description).

    Stages are taken input first: a shaft's order measured at one stage (the wheel's sidebands)
    is the pinion shaft's order of the next, so a wrong tooth count upstream is not blamed on a
    later stage. *beyond*: stages of the train the description leaves out (a simulator's later stages
    where its first is read alone), as other_stages gives them: their lines are no sidebands of it."""
    table = order_table(box)
    bin_ = 1.0 / revolutions
    explained = table.lines()
    # a moved mesh moves the stages after it only where the orders are the input's (no tacho, or one on the
    # input): a tacho on a later shaft anchors the stages near it (a 46-for-47 first wheel read through an
    # output tacho put stage 3 at '144.4 teeth')
    leads = tacho_shaft is None or tacho_shaft == 0

    def is_explained(x: float, without: int | None = None) -> bool:
        """Whether a described order explains *x*; *without*: a stage whose sidebands are left out (outshone)."""
        own = re.compile(rf"\d*M{without + 1} [+-] ") if without is not None else None
        if any(abs(x - o) <= tol_mesh(o, bin_) for label, o in explained if not (own and own.match(label))):
            return True
        # any mesh harmonic (a mesh's power can sit at harmonics 4-11) and its sidebands j <= 3
        for q, t in enumerate(table.stages):
            m = float(t.mesh)
            for o in (0.0,) if q == without else (0.0, float(t.pinion_shaft_order), float(t.wheel_shaft_order)):
                for off in {0.0, o, -o, 2 * o, -2 * o, 3 * o, -3 * o}:
                    h = max(1.0, round((x - off) / m))
                    if abs(x - h * m - off) <= tol_mesh(h * m + off, bin_):
                        return True
        return False

    measured_shaft: dict[int, tuple[float, float, str]] = {}  # shaft -> (order, tolerance, source)
    if tacho_on_input:
        measured_shaft[0] = (1.0, 0.0, "tacho")
    elif tacho_shaft is not None and 0 < tacho_shaft < len(table.shafts):
        measured_shaft[tacho_shaft] = (float(table.shaft_orders[tacho_shaft]), 0.0, "tacho")
    stages, findings, shaft_notes, named_shafts = [], [], {}, set()

    def differ(kind: str, text: str, stage=None, gear=None, guess=None, follows=(), tail: str = "") -> None:
        """A difference, as gearbox.leading picks the verdict's first line by it: its *kind* (no_line, follows,
        pinion_as_described, mesh_moved, sidebands, shaft; outshone, outward: a leading line's), the *stage* and
        *gear* read, the gear a count is *guess*ed for, the stages it *follows* from; *tail*: what a reading beyond
        the gear that leads drops (a count guessed, a stage it follows from)."""
        follows = list(follows)
        findings.append(
            dict(kind=kind, stage=stage, gear=gear, guess=guess, follows=follows, text=text + tail, bare=text)
        )

    implied: dict[int, float] = {}  # shaft -> its order as the measured mesh before it and the wheel make it
    wrong: list[int] = []  # the stages whose own tooth counts differ
    unresolved = []  # tooth counts the sidebands cannot tell from the next one (too few revolutions)
    moved: dict[int, float] = {}  # stage -> its mesh order measured where it differs from the described one
    modulated: set[int] = set()  # shafts whose comb another modulation made (sideband_combs.modulation)
    ahead = located_ahead(lines, table, bin_, tacho_shaft)  # the later meshes where the lines put them
    for k, s in enumerate(table.stages):
        said = len(findings)
        expected = float(s.mesh)
        look = expected * (lead(table, k, moved) if leads else 1.0)  # looked for where a moved mesh before it puts it
        o_p = measured_shaft.get(k, (float(s.pinion_shaft_order),))[0]
        span = SPAN * float(max(s.pinion_shaft_order, s.wheel_shaft_order))
        # a tacho on a later shaft reads the pinion's shaft through the described gears after it: a pinion count
        # off leaves the mesh on M (its shaft read as fast), another count moves it by no whole tooth, so M + j o_p
        # is no count's (a 22/69 + 25/74 box, output tacho, described with 24 for 25: stage 1's load sideband at
        # 21.02, beside its mesh at 21.12, was read as a 21-tooth pinion's, and stage 2 told 'shows 18.7 teeth')
        behind = int(tacho_shaft is not None and tacho_shaft > k)
        # the other stages' mesh orders: an earlier one that differs where it was measured (a wrong
        # first pinion moved stage 1's lines off its described order, and stage 2 took them)
        meshes = [
            moved.get(q, ahead.get(q, float(t.mesh) * (lead(table, q, moved) if leads else 1.0)))
            for q, t in enumerate(table.stages)
            if q != k
        ]
        entry = {"stage": s.index, "expected_order": expected, "z1": s.pinion_teeth, "z2": s.wheel_teeth}
        # lines on the other stages' mesh harmonics are theirs, unless on this one's too (off_own)
        shared = harmonics(meshes, bin_)
        theirs = off_own(shared, look)
        o_tacho = measured_shaft[k + 1][0] if measured_shaft.get(k + 1, (0, 0, ""))[2] == "tacho" else None
        family = mesh_family(lines, o_p, bin_, span, theirs, look, o_tacho, shared)
        if family is not None and k in ahead:
            family = ahead_family(lines, family, ahead[k], bin_, theirs)
        i = rests = None
        if lines.near(look, tol_mesh(look, bin_)) is not None:
            # a line at M: M, or a sideband of the real mesh M + j o (a tooth count off by j)? o: the
            # pinion's shaft, or the wheel's (a tacho on the output read through a first wheel one tooth
            # off puts the mesh at M + M / z2, its wheel sideband on M: a 38/89 + 49/95 mixer 'matched')
            o_w = measured_shaft.get(k + 1, (float(s.wheel_shaft_order),))[0]
            offsets = [j * o for o in (o_p, o_w)[behind:] for j in (-3, -2, -1, 1, 2, 3)]
            found = harmonic_comb(lines, [look] + [look + d for d in offsets], bin_, theirs)
            if found is not None:
                i, measured = found
        if family is not None and (i is None or abs(measured - look) <= tol_mesh(look, bin_)):
            # no line at M, or one at M that is the 2nd or 3rd harmonic of a family holding more of
            # the power (a description of twice or three times the teeth): the family's order
            ratio = look / family[0]
            # ... with two lines of its own at least, off M's harmonics (one line at M / 2 is a tone)
            own = [x for x in family[2] if abs(x / look - round(x / look)) * look > tol_mesh(x, bin_)]
            divisor = round(ratio) in (2, 3) and abs(ratio - round(ratio)) * family[0] <= tol_mesh(look, bin_)
            # ... unless the described comb holds the lines nothing else explains (gearbox.described_comb)
            if i is None and abs(family[0] - look) > tol_mesh(look, bin_):
                o_w = measured_shaft.get(k + 1, (float(s.wheel_shaft_order),))[0]
                shown = [*beyond, *other_stages(table, k, moved, measured_shaft, leads, ahead)]
                if described_holds(lines, look, family[0], (o_p, o_w), shown, bin_):
                    i, measured = harmonic_comb(lines, [look], bin_, theirs) or (None, look)
            if i is None or (divisor and len(own) >= 2):
                measured, i, rests = family
        at_m = lines.near(look, tol_mesh(look, bin_)) is not None
        if i is not None and not at_m and abs(measured - look) <= tol_mesh(look, bin_):
            # read with no line at M: the lines nothing else explains may say another count (gearbox.described_comb)
            o_w = measured_shaft.get(k + 1, (float(s.wheel_shaft_order),))[0]
            shown = [*beyond, *other_stages(table, k, moved, measured_shaft, leads, ahead)]
            i, measured = comb_reading(lines, look, (o_p, o_w), shown, bin_, rests) or (i, measured)
        # a wheel upstream a tooth or three off moves M by no whole order of the pinion's shaft (outshone.counts)
        upstream = [c * look / expected for c, *_ in counts(table, k)] if leads else []
        if i is None and family is None and not behind:
            # no line at M, nor a family: a count off by j puts the mesh at M + j o (a 15-tooth input pinion
            # described 16, its shaft unmodulated: no sideband at 16 led the search there), a wheel upstream elsewhere
            # (21/92 + 30/63 described with 91: 'no line at mesh order 6.923', the real 6.848 unsaid)
            found = harmonic_comb(
                lines, [look] + [look + j * o_p for j in (-3, -2, -1, 1, 2, 3)] + upstream, bin_, theirs
            )
            if found is not None and abs(found[1] - look) > tol_mesh(look, bin_):
                i, measured = found
        above = harmonics([m for m in meshes if m > look], bin_)
        if i is not None and abs(measured - look) <= tol_mesh(look, bin_) and borrowed(lines, look, bin_, above):
            # M held only by the harmonics of a higher mesh (M a subharmonic of it, no line of its own) is no evidence
            # of this one: M + j o with lines of its own is (36/84 + 27/69 described with 28: M2 = 12 = M1 / 3, read on
            # 36, 72, 108 while 11.57 and its harmonics stood 58-66 dB over the floor: 'matches'), nor, M a half or a
            # third of it, one with no line at its first own harmonics (gearbox.shared_harmonics: 8 = 16 / 2)
            o_w = measured_shaft.get(k + 1, (float(s.wheel_shaft_order),))[0]
            offsets = [j * o for o in (o_p, o_w)[behind:] for j in (-3, -2, -1, 1, 2, 3)]
            # ... or a wheel upstream (16/52 + 34/40 described with 51: M2 = 10.667 = 2 M1 / 3, read on 32, 64, 96)
            found = harmonic_comb(lines, [look] + [look + d for d in offsets] + upstream, bin_, shared)
            if found is not None and abs(found[1] - look) > tol_mesh(look, bin_):
                i, measured = found
        if i is not None and (tacho_on_input or (tacho_shaft is not None and tacho_shaft <= k)):  # gearbox.modulated
            o_w = measured_shaft.get(k + 1, (float(s.wheel_shaft_order),))[0]
            hit = centre(lines, table, k, look, measured, (o_p, o_w), bin_, theirs, harmonic_comb)
            i, measured = hit or (i, measured)
        matched = i is not None and abs(measured - expected) <= tol_mesh(expected, bin_)
        entry["matched"] = bool(matched)
        if i is None:  # the gap's later_stages says it too where it has no source to weigh the mesh's level by
            missing = f"stage {s.index}: no line at mesh order {expected:.4g} (a {s.pinion_teeth}-tooth pinion)"
            entry["no_line"] = missing
            differ("no_line", missing, s.index, "pinion", guess="pinion")
            wrong.append(s.index)
            stages.append(entry)
            continue
        # the pinion shaft's order as measured (its sidebands, a tacho), else as the stage before's
        # measured mesh and described wheel make it: a later stage is judged against that, so a wrong
        # count upstream is named once, where it is, and the stages after it as its consequence
        o_ref = measured_shaft[k][0] if k in measured_shaft else implied.get(k, o_p)
        implied[k + 1] = measured / s.wheel_teeth
        if not matched:
            moved[k] = measured
        consequence = not matched and wrong and abs(measured / o_ref - s.pinion_teeth) <= 0.5
        if consequence:
            differ(
                "follows",
                f"stage {s.index}: mesh order {measured:.4g} measured, {expected:.4g} expected",
                s.index,
                follows=wrong,
                tail=f", as follows from {_following(wrong)} (the {s.pinion_teeth}-tooth pinion as described, on the "
                f"{s.pinion_shaft} shaft at order {o_ref:.4g})",
            )
        elif not matched and round(measured / o_ref) == s.pinion_teeth:
            # the pinion as described on a shaft the speed read makes slower or faster than it turns
            entry["pinion_as_described"] = True
            differ(
                "pinion_as_described",
                f"stage {s.index}: mesh order {measured:.4g} measured, {expected:.4g} expected: the "
                f"{s.pinion_teeth}-tooth pinion as described, its {s.pinion_shaft} shaft turning "
                f"{100 * (measured / expected - 1):+.1f} % off the speed read ("
                + _between(table, k, measured / expected, leads and not tacho_on_input, leads)
                + ")",
                s.index,
                "pinion",
            )
        elif not matched:  # no whole count of the pinion: a wheel upstream where a whole count of it does it
            guess = wheel_upstream(table, k, measured / expected, measured / o_ref)[2:] if leads else ""
            role = "wheel" if guess else "pinion"
            guess = (
                guess
                or f"a {measured / o_ref:.0f}-tooth pinion on the {s.pinion_shaft} shaft? described {s.pinion_teeth}"
            )
            said_mesh = f"stage {s.index}: mesh order {measured:.4g} measured, {expected:.4g} expected"
            differ("mesh_moved", said_mesh, s.index, guess=role, tail=f" ({guess})")
        i = own_line(lines, i, measured, bin_, shared)
        entry.update(measured_order=measured, error_orders=measured - expected, amplitude=float(lines.amp[i]))
        entry["db_over_floor"] = float(lines.db[i])
        own = tuple(
            measured_shaft.get(q, (float(o),))[0] for q, o in ((k, s.pinion_shaft_order), (k + 1, s.wheel_shaft_order))
        )
        others = [*beyond, *other_stages(table, k, moved, measured_shaft, leads, ahead)]
        theirs_lines = others_lines(lines, expected, others, bin_, (float(lines.at[i]), own))
        # the combs leave out the shared shaft's sidebands of other meshes too; the checks of a comb below count them
        combed = others_lines(lines, expected, others, bin_, (float(lines.at[i]), own), shared=True)
        combs = families(lines, i, own, bin_, (k in measured_shaft, k + 1 in measured_shaft), combed)
        for (key, role, shaft_k, described), found in zip(
            (("z1", "pinion", k, s.pinion_teeth), ("z2", "wheel", k + 1, s.wheel_teeth)), combs
        ):
            if shaft_k not in measured_shaft:
                if found is None:
                    continue
                z = measured / found[0]
                if abs(z - described) > max(0.5, z * found[1] / found[0]):
                    mesh_of = {q: measured if q == k else meshes[q - (q > k)] for q in range(len(table.stages))}
                    # ... and the train's later stages where its first is read alone (beyond: the gap's mesh_check)
                    mesh_of |= {len(table.stages) + q: float(m) for q, (m, *_) in enumerate(beyond)}
                    on = [mesh_of[q] for q in (shaft_k - 1, shaft_k) if q in mesh_of]  # the meshes on that shaft
                    skip = theirs_lines | at_harmonics(lines, mesh_of.values(), bin_)
                    orders = [
                        float(o) * (lead(table, q, moved) if leads else 1.0) for q, o in enumerate(table.shaft_orders)
                    ]
                    carriers = at_harmonics(lines, on, bin_)
                    other = modulation(lines, carriers, found, measured / described, orders, bin_, skip)
                    if other is not None:
                        note = (
                            f"the tooth count of the {role} on the {table.shafts[shaft_k]} shaft (sidebands "
                            f"{found[0]:.4g} apart around its meshes, {len(other[1])} lines, and {len(other[2])} at "
                            f"odd multiples of half that: a modulation {found[0] / 2:.4g} apart, not that shaft's "
                            f"order; the {described} teeth's sidebands, {measured / described:.4g} apart: "
                            f"{len(other[0])} lines)"
                        )
                        unresolved += [] if shaft_k in modulated else [note]
                        modulated.add(shaft_k)
                        continue
                    elsewhere = at_harmonics(lines, [m for q, m in mesh_of.items() if m not in on], bin_)
                    if train_wide(lines, carriers, elsewhere, found, measured / described, bin_, skip):
                        unresolved.append(
                            f"the tooth count of the {role} on the {table.shafts[shaft_k]} shaft (sidebands "
                            f"{found[0]:.4g} apart stand as strong around meshes it does not carry: a swing of the "
                            "train's speed or load, not that shaft's order)"
                        )
                        continue
                    if lone(lines, carriers, found, measured / described, bin_, skip) or not whole(found, z, bin_):
                        continue  # as where its lines stay under the threshold: no comb (sideband_combs.lone, whole)
                measured_shaft[shaft_k] = (found[0], found[1], f"{found[2]} sideband(s) of M{s.index}")
            o_seen, tol, _ = measured_shaft[shaft_k]
            z = measured / o_seen
            spread = z * tol / o_seen
            entry[f"{key}_seen"], entry[f"{key}_resolution"] = z, spread
            # a tooth more or less would pass too, or the reading lies nearer another count within its spread (a
            # 22/68 + 18/70 box's wheel read 70.04 ± 0.97 passed as 71)
            if abs(z - described) <= spread and (spread >= 1.0 or abs(z - described) >= 0.5):
                need = revolutions_needed(z, o_seen, tol, revolutions, 1.0 if spread >= 1.0 else 0.5)
                unresolved.append(
                    f"the tooth count of the {role} on the {table.shafts[shaft_k]} shaft ({z:.1f} ± {spread:.1f} "
                    f"from its sidebands, {described} described: {revolutions} input revolutions, "
                    + (
                        f"need {need} to tell a tooth more or less)"
                        if need
                        else "too many teeth to tell from its sidebands)"
                    )
                )
            if abs(z - described) > max(0.5, spread):
                named_shafts.add(shaft_k)
                if role == "pinion" and not matched and round(z) == round(measured / o_p):
                    continue  # the mesh message has said it
                differ(
                    "sidebands",
                    f"stage {s.index}: the {role} on the {table.shafts[shaft_k]} shaft shows {z:.1f} ± {spread:.1f} "
                    f"teeth (mesh order {measured:.4g} / shaft order {o_seen:.4g}), {described} described",
                    s.index,
                    role,
                )
        if len(findings) > said + bool(consequence):
            wrong.append(s.index)
        stages.append(entry)

    shafts = []
    for k, (name, o) in enumerate(zip(table.shafts, table.shaft_orders)):
        o = float(o)
        entry = {"shaft": name, "expected_order": o}
        if k in measured_shaft:
            seen, tol, source = measured_shaft[k]
            entry.update(measured_order=seen, tolerance=tol, source=source, matched=bool(abs(seen - o) <= tol))
            if not entry["matched"]:
                upstream = [q for q in wrong if q <= k]
                upstream = upstream if upstream and abs(seen - implied.get(k, -1.0)) <= tol + bin_ else []
                shaft_notes[k] = (
                    f"{name} shaft: order {seen:.4g} measured ({source}), {o:.4g} expected",
                    upstream,
                    f", as follows from {_following(upstream)}" if upstream else "",
                )
        else:
            entry.update(measured_order=None, source="not seen (no sidebands of this shaft)", matched=None)
        shafts.append(entry)
    for k, (text, upstream, tail) in shaft_notes.items():
        if k not in named_shafts:
            differ("shaft", text, follows=upstream, tail=tail)
    if tacho_shaft is not None and 0 < tacho_shaft < len(table.shafts) and 0 not in measured_shaft:  # no mesh tells it
        unresolved.append(
            f"the tooth count of the pinion on the input shaft (no sideband shows the input shaft's order, and "
            f"the tacho reads the {table.shafts[tacho_shaft]} shaft: every mesh order is read through the gears "
            "after it)"
        )
    unexplained = []
    for q in range(lines.at.size):
        x = float(lines.at[q])
        if is_explained(x):
            continue
        # an order line (a shaft's harmonic, e.g. a chip's 4th sidebands) only at the level of the strongest
        off = shaft_harmonic(table, x, bin_) is None and bool(lines.db[q] >= UNEXPLAINED_FLOOR_DB)
        if off or 20 * math.log10(lines.amp[q] / lines.amp[0]) >= UNEXPLAINED_DB:
            unexplained.append(
                {"order": x, "amplitude": float(lines.amp[q]), "db_over_floor": float(lines.db[q])}
                | {"not_an_order": off}
            )
    unexplained = unexplained[:8]
    # a weak line read as a described mesh beside a far stronger family (outshone); said first where the only other
    # differences are later stages whose shafts turn off, no count named: 39/108 + 44/93 + 62/101 (109 real) read
    # stage 2 on its own sideband and said only that stage 3's shaft turned 0.9 % off; or, read on that sideband, a
    # later stage's wheel count off the line's sidebands, stage 3 following from it ('94.1 +- 1.0 teeth', seeds 1, 8)
    if unnamed(findings) and (line := outshone_line(lines, stages, table, bin_, is_explained)):
        findings[:] = outshone_first(findings, stages, line)
    differences = [f["text"] for f in findings]
    out = {"stages": stages, "shafts": shafts, "unexplained": unexplained, "differences": differences}
    out["findings"] = findings
    return out | {"unresolved": unresolved}


def shaft_harmonic(table, x: float, bin_: float) -> str | None:
    """The shaft *x* (an order of the input) is a whole harmonic of, within a line's tolerance, or None: a line
    that is none is no order of the gearbox (a fixed frequency such as a mains hum, or a bearing's line)."""
    for name, o in zip(table.shafts, table.shaft_orders):
        h = round(x / float(o))
        if h >= 1 and abs(x - h * float(o)) <= tol_mesh(x, bin_):
            return name
    return None


def _between(table, k: int, ratio: float, no_tacho: bool, from_input: bool = False) -> str:
    """What puts stage *k*'s pinion shaft *ratio* off the speed read: without a tacho or with one on the input
    (*from_input*), the stage before's wheel where a whole count does it (21/65 + 34/91 described with 64 on 57 turns,
    its sidebands unresolved: stage 2 at 10.985 was 'a tooth count between it and the tacho's shaft, or the tacho')."""
    said = "the input shaft differs" if no_tacho else "the tacho's shaft, or the tacho, differs"
    return f"a tooth count between it and {said}" + (wheel_upstream(table, k, ratio) if no_tacho or from_input else "")


def wheel_upstream(table, k: int, ratio: float, pinion: float | None = None) -> str:
    """': a z-tooth wheel on the ... shaft puts it there' where the stage before *k*'s wheel a whole count off turns
    stage *k*'s pinion shaft *ratio* of its described speed, and the mesh is no whole count of that pinion's teeth
    (*pinion*: the count it shows, where known), else '' (the gap's later_stages says it too: 37/97 + 28/77 described
    with 96 put stage 2 at '27.7 such teeth', the wheel unnamed)."""
    z = table.stages[k - 1].wheel_teeth / ratio if k else 0.0
    wheel = table.stages[k - 1].wheel_teeth if k else 0
    if pinion is not None and abs(pinion - round(pinion)) < 0.25:
        return ""
    if k and round(z) != wheel and abs(z - round(z)) <= 0.1:
        return f": a {round(z)}-tooth wheel on the {table.shafts[k]} shaft ({z:.2f}) puts it there, {wheel} said"
    return ""


def _following(stages: list[int]) -> str:
    if len(stages) == 1:
        return f"stage {stages[0]}'s difference"
    return f"stages {', '.join(map(str, stages[:-1]))} and {stages[-1]}'s differences"


def own_line(lines: Lines, i: int, measured: float, bin_: float, shared) -> int:
    """The line a stage's sidebands are read around: *i*, the strongest of its mesh harmonics, unless
    another stage's mesh harmonic (*shared*: (order, tolerance)) holds it too, then the strongest
    harmonic of *measured* that is its own. A 27/88 + 22/65 train's stage-2 mesh 6.75 has its 4th
    harmonic on stage 1's mesh 27: read around 27, stage 1's sidebands, the output shaft's order was
    never seen and a 66-tooth output wheel passed."""

    def theirs(x: float) -> bool:
        return any(abs(x - o) <= t for o, t in shared)

    if not theirs(float(lines.at[i])):
        return i
    h = np.maximum(1.0, np.round(lines.at / measured))
    own = [
        q
        for q in np.flatnonzero(np.abs(lines.at - h * measured) <= 2 * bin_ + DRIFT * lines.at)
        if not theirs(float(lines.at[q]))
    ]
    return int(max(own, key=lambda q: lines.amp[q])) if own else i


def revolutions_needed(z: float, o: float, tol: float, revolutions: int, teeth: float = 1.0) -> int | None:
    """The input revolutions at which a shaft order *o* measured to ±*tol* over *revolutions* tells a
    *z*-tooth gear from one of z ± 1 (z within ± *teeth*: 1, or a half where z lies between two counts), or None:
    a comb's tolerance is b bins / its furthest sideband + DRIFT o (comb), b = SIDEBAND_BINS at SEPARATED bins
    apart or more, else 2."""
    room = teeth * o / z - DRIFT * o  # the tolerance *teeth* allow
    spent = (tol - DRIFT * o) * revolutions  # b / jmax, in orders x revolutions
    if room <= 0 or spent <= 0:
        return None
    b = SIDEBAND_BINS if o * revolutions >= SEPARATED else 2.0
    per_bin = spent / b  # 1 / jmax
    need = SIDEBAND_BINS * per_bin / room
    if need * o < SEPARATED:  # that few revolutions put the sidebands under SEPARATED bins apart
        need = min(2.0 * per_bin / room, SEPARATED / o)
    return math.ceil(need * 1.01)


def unchecked(check: dict, box: Gearbox, speed_found: float | None) -> list[str]:
    """What a match does not vouch for: the input pinion's tooth count without a speed
    (:func:`pinion_unconfirmed`), a shaft whose order no sideband shows (a healthy mesh need not
    modulate), a tooth count its sidebands cannot tell from the next over so few revolutions."""
    unseen = [s["shaft"] for s in check["shafts"] if s["measured_order"] is None and s["shaft"] != box.shafts[0]]
    pinion = pinion_unconfirmed(check, box, speed_found)
    out = ([pinion] if pinion else []) + check.get("unresolved", [])
    between = [s for s in unseen if s != box.shafts[-1]]  # a later stage's pinion on it: that mesh tells the wheel
    if between:
        out.append(
            f"no sideband shows the order of the {', '.join(between)} shaft{'s' if len(between) > 1 else ''}, so a "
            "wheel on it is checked only through a later stage's mesh order"
        )
    if box.shafts[-1] in unseen:  # the last wheel: nothing after it (a one-stage box's 48T wheel 'if any')
        out.append(
            f"no sideband shows the order of the {box.shafts[-1]} shaft, so the tooth count of its "
            f"{box.stages[-1].wheel.z}-tooth wheel is not checked"
        )
    return out


def pinion_unconfirmed(check: dict, box: Gearbox, speed_found: float | None) -> str | None:
    """Why the input pinion's tooth count cannot be confirmed, or None: with the speed found from the
    mesh lines the description predicts (*speed_found*, Hz; None: a tacho or a declared speed gave it)
    and no sideband showing the input shaft's order, any pinion count fits at some speed (a 20-tooth
    pinion at 25 Hz meshes at 500 Hz as a 25-tooth one at 20 Hz does), as the gap diagnosis says it
    (gearlab.gap.structure.speed_line)."""
    seen = next(s["measured_order"] for s in check["shafts"] if s["shaft"] == box.shafts[0])
    if not speed_found or seen is not None:
        return None
    z1 = box.stages[0].pinion.z
    mesh_hz = z1 * speed_found
    others = " or ".join(f"a {z}-tooth pinion's at {mesh_hz / z:.4g} Hz" for z in (z1 - 1, z1 + 1))
    return (
        f"the speed ({speed_found:.4g} Hz) was found from the mesh lines the description predicts and no "
        f"sideband shows the input shaft's order: the mesh at {mesh_hz:.4g} Hz is a {z1}-tooth pinion's at "
        f"{speed_found:.4g} Hz, or {others}; give a tacho or the speed (--speed, [operation] speed) to check "
        "the pinion's tooth count"
    )


# A record's strongest lines (STRONGEST, from order MIN_TEETH - 0.5) off a comb by this share of their
# power, or on its mesh harmonics by less than ON_MESH, do not show that comb (gearlab.gap.structure's
# tooth-count check reads them alike)
OFF_COMB, ON_MESH, STRONGEST, MIN_TEETH = 0.25, 0.25, 8, 6
# A tacho read as another shaft's reads the speed 1 / f of the true one: within this of the described
TACHO_SPEED_TOL = 0.05


def on_table(x: np.ndarray, table, f: float, tol: np.ndarray, sidebands: int = 3) -> np.ndarray:
    """Which orders *x* lie on a mesh harmonic of a stage of *table* x *f* (h >= 1) or one of its
    sidebands j <= *sidebands* of either shaft (x *f*): the description's comb as a record shows it
    when each of its orders reads *f* times its own."""
    hit = np.zeros(x.size, dtype=bool)
    for s in table.stages:
        m = f * float(s.mesh)
        shafts = (float(s.pinion_shaft_order), float(s.wheel_shaft_order))
        off = np.array([0.0] + [g * j * f * o for o in shafts for j in range(1, sidebands + 1) for g in (-1, 1)])
        h = np.maximum(1, np.round((x[:, None] - off[None, :]) / m))
        hit |= np.any(np.abs(x[:, None] - h * m - off[None, :]) <= tol[:, None], axis=1)
    return hit


def tacho_elsewhere(x, power, tol, table, read: int, ratio: float | None, low=None) -> tuple[str, float] | None:
    """(shaft, f) when a record's tacho reads another shaft of the description than shaft *read*, the
    one it was read as, else None. The tacho's turns are then that shaft's, not shaft *read*'s: every
    order reads f = o_read / o_shaft times its own (a 16/48 output tacho read as the input: mesh at
    48, the input at 3, the output at 1). *x*, *power*, *tol*: the record's strongest lines (orders,
    power, tolerance) from order MIN_TEETH - 0.5; *low*: the same of the lines under it, strongest
    first, or None: a faster shaft (f < 1) is judged on the strongest lines from (MIN_TEETH - 0.5) f, its
    meshes' lines as its orders read them (an input tacho read as a 17/44 + 21/53 train's output: mesh
    1 at 2.6, 5.2, 7.8; only 7.8 over order 5.5, and no word of the tacho). The shaft is named when
    its comb (the table's orders x f) holds the lines as
    a right record's holds them (OFF_COMB, ON_MESH, two mesh harmonics), no line lies on the
    description's comb and off that one (a 16-tooth pinion's 16, 32 or its wheel's sidebands 1/3
    apart: a right reading whose mesh shows only every third harmonic, with the input's sidebands
    one apart, which the output's make too), and the speed read is 1 / f of the described (*ratio*:
    read / described, within TACHO_SPEED_TOL); without a described speed, the description's comb must
    not hold the lines, or a line must lie on the shaft's comb alone, or the strongest line is its mesh."""
    o_read = float(table.shaft_orders[read])
    for name, o in zip(table.shafts, table.shaft_orders):
        f = o_read / float(o)
        if abs(f - 1.0) < 1e-9:
            continue
        xs, ps, ts = x, power, tol
        if f < 1 and low is not None:  # the strongest lines down to this shaft's reading of MIN_TEETH
            keep = low[0] >= (MIN_TEETH - 0.5) * f
            xs, ps, ts = (np.concatenate([a, b[keep]]) for a, b in zip((x, power, tol), low))
            top = np.argsort(-ps, kind="stable")[:STRONGEST]
            xs, ps, ts = xs[top], ps[top], ts[top]
        if xs.size < 2:
            continue
        total = float(ps.sum())
        right = on_table(xs, table, 1.0, ts)
        on, mesh = on_table(xs, table, f, ts), on_table(xs, table, f, ts, 0)
        if ps[~on].sum() / total >= OFF_COMB or ps[mesh].sum() / total < ON_MESH or mesh.sum() < 2:
            continue
        if (right & ~on).any():
            continue
        if ratio is not None:
            called = abs(ratio * f - 1.0) <= TACHO_SPEED_TOL
        else:
            fails = ps[~right].sum() / total >= OFF_COMB or ps[on_table(xs, table, 1.0, ts, 0)].sum() / total < ON_MESH
            first, m1 = int(np.argmax(ps)), f * float(table.stages[0].mesh)
            called = fails or bool((on & ~right).any()) or abs(xs[first] - m1) <= ts[first]
        if called:
            return str(name), f
    return None


def tacho_shaft_words(name: str, f: float, read: str) -> str:
    """What a tacho_elsewhere call says: the orders' factor, and the shaft to name."""
    shown = f"{f:.4g}" if f >= 1 else f"1/{1 / f:.4g}"
    return (
        f"every order reads {shown} x its own, as when a tacho on the {name} shaft is read as on the {read}: "
        f"the tacho reads the {name} shaft?"
    )
