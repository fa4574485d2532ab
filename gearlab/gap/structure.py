"""Structure before effects (docs/gap.md, "Structure"): what no effect can change is checked before
any effect is searched, and a difference ends the diagnosis with one line that says what differs.

* **Tooth count.** The target's order spectrum (its revolutions one after another, as `gearlab inspect` reads a
  record: gearlab.signals.spectrum, lines by gearlab.gearbox.speed.find_lines and the description's mesh order tested
  by gearlab.gearbox.match.check_description) against the source's gear pair: mesh harmonics h Z1 with their sidebands
  (j <= SIDEBANDS, either shaft). The strongest lines of a gear record are often high mesh harmonics (B-6-ch5: order
  250, ten times its mesh order), so the line at Z1 alone decides nothing: the target differs when most of the power
  of its strongest lines lies off the source's comb (OFF_COMB); its own mesh order is then the comb that holds them
  (the largest, so not a divisor of it). A multi-stage source's later meshes are its comb too; a comb that holds the
  lines through its sidebands alone (ON_MESH) is another pinion's too. A later stage's mesh order is read off the
  target and off the source alike (later_stages).
* **Speed.** A measured target's speed (its tacho, or the speed it was cut at) against the source's: beyond SPEED_TOL
  the source simulates another operating point.
* **Level.** A pure scale factor (the target is the source x c: a record without its sensitivity or gain) is no
  effect: when the source scaled by the factor of their synchronous averages closes the gap as the verdict would judge
  an effect's fit, the diagnosis says the level or the units differ, and by how much.
"""

from __future__ import annotations

import math
from dataclasses import replace
from fractions import Fraction

import numpy as np

from ..gearbox.described_comb import SIDEBANDS, on_comb
from ..gearbox.match import MIN_TEETH, OFF_COMB, ON_MESH, STRONGEST, tacho_elsewhere, tacho_shaft_words
from ..gearbox.speed import TEETH_AGREE
from ..inspect_tacho import marks_words
from .structure_later import Spectra, _inspected, _lines, _PairDescription, later_stages, wheel_line
from .structure_later import _outshone as _outshone  # where tests/test_outside_user reads it

# A target whose strongest lines (STRONGEST, above order MIN_TEETH) hold at least this share of their
# power off the source's comb of mesh harmonics and sidebands may be another gearbox (then those lines
# hold a comb of their own, FAMILY): a 20-tooth record against B-6-ch5's 25 teeth holds 58 % there
# (its 200 and 300 lie on both combs), a 26- or 24-tooth one 100 %, a right one 0-5 % (a 0.5-ratio
# interference tone beside it: 4-5 %); or when less than ON_MESH of that power lies on the source's
# mesh harmonics themselves (the rest on their sidebands): a right record's mesh harmonics hold most
# of it (B-6-ch5, the PHM 2009 records against phm09; see mesh_check). The shares and counts are
# gearlab.gearbox.match's (a pinion of fewer than MIN_TEETH teeth is no gear: inspect's bound too).
FAMILY = 3  # lines of a foreign comb (module doc: a tone is one line)
# The source simulates another speed when a measured target's differs by more than this (one rig at
# one setting drifts by well under 1 %; a history's takes span up to kinds.common.SPEED_GROUP).
SPEED_TOL = 0.02
# A scale factor within this of 1 is a calibration's tolerance, left to the effects.
LEVEL_TOL = 0.1
IN_TARGET = "[target]"  # the table of the gap's records: their acquisition keys (a run has no inspect options)


def _comb_distance(x: np.ndarray, z: float, offsets: list[float]) -> np.ndarray:
    """Each order of *x*'s distance to the nearest h z + offset (h >= 1)."""
    off = np.asarray(offsets, dtype=np.float64)
    h = np.maximum(1, np.round((x[:, None] - off[None, :]) / z))
    return np.abs(x[:, None] - h * z - off[None, :]).min(axis=1)


def mesh_check(
    target: np.ndarray,
    z1: int,
    z2: int,
    max_order: int = 0,
    later: tuple = (),
    tacho=None,
    on_input: bool = True,
    spectra: Spectra | None = None,
) -> dict:
    """The target's mesh order against the source's Z1 (module doc): {'expected', 'measured' (the
    target's mesh order, or None when its lines do not show one), 'off_comb' (share of the strongest
    lines' power off the source's comb), 'lines', 'inspect' (check_description's stage), 'differs'}.
    *later*: the later stages of a multi-stage source, (mesh order, (its shafts' orders)) each, whose
    combs are the source's too (a second mesh as strong as the first is no other pinion). *tacho*:
    (the source's order table, the shaft the target's tacho was read as, the target's speed over the
    described): a tacho on another shaft (match.tacho_elsewhere) is told first. *on_input*: the
    revolutions are the input shaft's turns (its order is 1, not read off its sidebands: a tacho there,
    or a simulation); a tacho on another shaft makes them its turns times the described ratio. *spectra*: the
    structure check's readings (structure_later.Spectra), or None."""
    from ..gearbox.match import tol_mesh

    spectra = spectra or Spectra()
    n = target.shape[0]
    orders, amp = spectra.spectrum(target)
    lines = spectra.lines(target, max_order)
    # the later stages' lines are no sidebands of the first (their shafts but the first wheel's)
    beyond = tuple((mesh, shafts[1:] if i == 0 else shafts) for i, (mesh, shafts) in enumerate(later))
    read_on = None if tacho is None else tacho[1]
    check = spectra.check(target, max_order, _PairDescription.of(z1, z2), on_input, read_on, beyond)
    # ranked by the spectrum at the line's bin: the parabola's height overshoots where a noise-free
    # record's neighbouring bins are rounding (a line at order 1808 ranked above the mesh harmonics)
    x = lines.at[lines.at >= MIN_TEETH - 0.5]
    power = amp[np.clip(np.round(x / (orders[1] - orders[0])).astype(int), 0, amp.size - 1)] ** 2
    keep = np.argsort(-power, kind="stable")[:STRONGEST]
    x, power = x[keep], power[keep]
    below = lines.at[lines.at < MIN_TEETH - 0.5]  # for a tacho on a faster shaft (tacho_elsewhere's low)
    low_power = amp[np.clip(np.round(below / (orders[1] - orders[0])).astype(int), 0, amp.size - 1)] ** 2
    ranked = np.argsort(-low_power, kind="stable")
    low = (below[ranked], low_power[ranked], np.array([tol_mesh(v, 1.0 / n) for v in below[ranked]]))
    out = {
        "expected": float(z1),
        "measured": None,
        "off_comb": None,
        "lines": [float(v) for v in x],
        "inspect": check["stages"][0],
        "differs": False,
        # tooth counts its sidebands cannot tell from the next one over these revolutions (inspect's 'not checked')
        "unresolved": check["unresolved"],
    }
    tol = np.array([tol_mesh(v, 1.0 / n) for v in x], dtype=np.float64)
    # a tacho on another shaft read as this one: every order f times its own (a 16/48 output tacho
    # read as the input: the mesh at 48, all on the comb, 'partly explained' by sensor noise). Asked
    # before the lines over MIN_TEETH are counted: a faster shaft's meshes may all lie under it (a
    # 19/62 + 23/87 input tacho read as the output: every order 1/12.34 of its own, the first mesh
    # at 1.54 and 3.08, none over 5.5), and tacho_elsewhere reads those from *low* as inspect does
    # (the count let the gap name it on 48 kHz takes only through stray lines near order 60)
    elsewhere = None if tacho is None else tacho_elsewhere(x, power, tol, *tacho, low)
    if elsewhere is not None:
        table, read, _ = tacho
        out.update(measured=elsewhere[1] * z1, differs=True, shaft=elsewhere[0], factor=elsewhere[1])
        out["read_as"] = str(table.shafts[read])
        return out
    if x.size < 2:  # one line is a comb of itself: nothing to tell
        return out
    on = on_comb(x, z1, (1.0, z1 / z2), tol)
    for mesh, shaft_orders in later:
        on |= on_comb(x, mesh, shaft_orders, tol)
    out["off_comb"] = float(power[~on].sum() / power.sum())
    # the source's mesh harmonics themselves (no sideband): a pinion one tooth off puts its harmonics
    # h (z1 - 1), h <= SIDEBANDS, on the comb's sidebands, so a comb holding the lines through its
    # sidebands alone is another pinion's (a 24-tooth record against 25: 24, 48, 72 on 25 - 1, 50 - 2,
    # 75 - 3); a gear's mesh harmonics outweigh their sidebands
    on_mesh = on_comb(x, z1, (), tol)
    for mesh, _ in later:
        on_mesh |= on_comb(x, mesh, (), tol)
    out["on_mesh"] = float(power[on_mesh].sum() / power.sum())
    # a tacho of k marks a turn read as one scales every order by 1 / k: the strongest line, off the
    # comb, at Z1 / k with its harmonics (a 29/86 mixer's 2-pulse keyphasor read as one: 14.5, 29 on
    # the comb, 43.5; too few off it for another gear's family, so the fits ran: 'unexplained')
    first = int(np.argmax(power))
    # ... or q marks read as p of them, q / p not whole (a 3-mark output tacho described with 2: every order at 2/3)
    for k in (2, 3, 4, *map(float, sorted({Fraction(q, p) for p in (2, 3, 4) for q in range(p + 1, 4 * p) if q % p}))):
        hit = on_comb(x, z1 / k, (), tol)
        if not on[first] and abs(x[first] - z1 / k) <= tol[first] and hit.sum() >= 2:
            out.update(measured=z1 / k, differs=True, marks=k)
            return out
    # read with k times the marks a turn it gives, a revolution is k turns and every order k times
    # its own: the mesh's lines sit on the comb's multiples of k alone, all on the source's comb (a
    # 29/86 mixer's 1-pulse tacho read as 2: 58, 116, 174, nothing at 29 or 87; 'unexplained'). The
    # strongest line at k Z1 and no mesh harmonic h Z1 of another h tell it; a record showing its
    # mesh's fundamental, or its input-shaft sidebands at other than k apart, is read as it is (a
    # resonance can raise the mesh's kth harmonic over the first; it leaves the +-1 sidebands)
    bare = on_comb(x, z1, (), tol)
    for k in (2, 3, 4):
        hit = on_comb(x, k * z1, (), tol)
        # a line nearer a sideband j (not a multiple of k) than to one the k-turn reading also has
        d_odd = _comb_distance(x, k * z1, [s * j for j in range(1, SIDEBANDS + 1) if j % k for s in (-1, 1)])
        d_even = _comb_distance(
            x, k * z1, [0.0] + [s * j * o for o in (k, k * z1 / z2) for j in (1, 2, 3) for s in (-1, 1)]
        )
        odd = (d_odd <= tol) & (d_odd < d_even)
        # ... nor a line on the source's comb off the k-turn reading's (16/48 read right, its mesh at 48
        # and 96 alone: its wheel's sidebands 1/3 apart; the input's 1 apart are the k-turn wheel's)
        read_k = on_comb(x, k * z1, (k, k * z1 / z2), tol)
        for mesh, shaft_orders in later:
            read_k |= on_comb(x, k * mesh, tuple(k * o for o in shaft_orders), tol)
        odd |= on & ~read_k
        # ... nor later meshes' harmonics, two at least, that the k-turn reading holds as sidebands alone: a later
        # stage's lines are read k times too (a 135/405 last stage described 15/45: its 15, 30, 45 under stage 2's
        # 66 and 78, 11 and 13 x 6, which the 2-turn reading's 12 lacks; 'pulses_per_rev?' blamed the tacho)
        later_bare = np.zeros(x.size, dtype=bool)
        read_bare = on_comb(x, k * z1, (), tol)
        for mesh, _ in later:
            later_bare |= on_comb(x, mesh, (), tol)
            read_bare |= on_comb(x, k * mesh, (), tol)
        odd |= (later_bare & ~read_bare) if np.sum(later_bare & ~read_bare) >= 2 else False
        if abs(x[first] - k * z1) <= tol[first] and hit.sum() >= 2 and not (bare & ~hit).any() and not odd.any():
            out.update(measured=k * z1, differs=True, marks=1 / k)
            return out
    pools = ([~on] if out["off_comb"] >= OFF_COMB else []) + ([~on_mesh] if out["on_mesh"] < ON_MESH else [])
    if not pools:
        out["measured"] = float(z1)
        return out
    # Another gear is a family: its mesh harmonics. A tone (an interference line) is one line, so
    # the lines off the source's comb must hold a comb of their own, of at least FAMILY lines: every
    # such line / h is a candidate mesh order, harmonics only (sidebands would let a small one hold
    # anything); the one holding most of their power, the largest among near-equals (not a divisor).
    for pool in pools:
        found = _family(x[pool], power[pool], tol[pool])
        if found is not None:
            out.update(measured=found, differs=True)
            # a second mesh among the lines off the source's (the other pool's too): a train of more
            # stages reads as its strongest mesh alone, a 26/73 + 33/59 record against 25 teeth as
            # 'mesh order 11.8 measured ... cut at a speed 53 % off', the 26 unsaid
            rest = np.zeros(x.size, bool)
            for other in pools:
                rest |= other
            rest &= ~on_comb(x, found, (), tol)
            second = _family(x[rest], power[rest], tol[rest], fundamental=True)
            if second is not None and not _related(second, found):
                out["also"] = [second]
            return out
    return out


def _family(x: np.ndarray, power: np.ndarray, tol: np.ndarray, fundamental: bool = False) -> float | None:
    """The mesh order whose harmonics hold most of the power of lines *x* (at least FAMILY of them; the
    largest among near-equals, so not a divisor of it), or None. *fundamental*: its first harmonic
    must be one of the lines (a second mesh of a train shows its own)."""
    held = []
    for c in {float(v / h) for v in x for h in range(1, 41) if v / h >= MIN_TEETH - 0.5}:
        hit = on_comb(x, c, (), tol)
        if hit.sum() >= FAMILY and (not fundamental or np.any(np.abs(x - c) <= tol)):
            held.append((float(power[hit].sum() / power.sum()), c))
    if not held:
        return None
    best = max(share for share, _ in held)
    return max(c for share, c in held if share >= best - 0.05)


def _related(a: float, b: float) -> bool:
    """Whether one order is a whole multiple of the other (a harmonic, not another mesh)."""
    big, small = max(a, b), min(a, b)
    return abs(big / small - round(big / small)) * small <= 0.05


def later_combs(pair) -> tuple:
    """(mesh order, (pinion and wheel shaft orders)) of each stage after the first of *pair*'s train."""
    from ..gearbox import order_table

    stages = order_table(_PairDescription.train(pair)).stages[1:]
    return tuple((float(s.mesh), (float(s.pinion_shaft_order), float(s.wheel_shaft_order))) for s in stages)


def mesh_line(check: dict, z1: int, ppr: int | None = None) -> str:
    """The one line of a tooth-count difference. *ppr*: the marks a turn the tacho was read with (None: not known):
    a tacho on its shaft read with another whole count is told in inspect's words (inspect_tacho.marks_words), the
    count it gives and the key; no whole count, the teeth the record shows; else as a share of those read."""
    m = check["measured"]
    whole = abs(m - round(m)) <= 0.05
    if check.get("also"):
        orders = sorted([m, *check["also"]], reverse=True)
        teeth = [round(o) for o in orders if abs(o - round(o)) <= 0.05]
        shown = " and ".join(f"{o:.4g}" for o in orders)
        return (
            f"mesh orders {shown} measured, {z1} expected: the source simulates a {z1}-tooth pinion (the target "
            f"shows {len(orders)} meshes: another gear train"
            + (f"; {teeth[0]} teeth on the shaft its revolutions follow" if teeth else "")
            + ")"
        )
    line = f"mesh order {m:.1f} measured, {z1} expected: the source simulates a {z1}-tooth pinion"
    if check.get("shaft"):
        words = tacho_shaft_words(check["shaft"], check["factor"], check["read_as"])
        return line + f" ({words} give [target] tacho_shaft = '{check['shaft']}')"
    k = Fraction(check.get("marks") or 1).limit_denominator(4)  # marks given over read: 2 read as 1: 2; 1 as 3: 1/3
    # a tacho gives a whole count a turn: of one read, 7/4 x is none, and a mesh there is another gear's (a 16/37 +
    # 28/71 box described as 28/71 + 16/37: 'the tacho gives 7/4 x the pulses per revolution it was read with?'); a
    # share under 1 may be a slower shaft's tacho
    if check.get("marks") and (ppr is None or (ppr * k).denominator == 1 or k < 1):
        if k > 1:
            at = f"1/{k}" if k.denominator == 1 else f"{float(1 / k):.3g}"
            seen, share = f"at {at} of its order, with its harmonics", f"{k} x"
        else:
            n, nth = k.denominator, {2: "2nd", 3: "3rd"}.get(k.denominator, f"{k.denominator}th")
            seen, share = f"at {n} x its order, its lines on every {nth} harmonic alone", f"1/{n} of"
        if ppr is not None and (ppr * k).denominator == 1:  # the count read known, the one given whole: inspect's
            return line + f" (the target's mesh {seen}: {marks_words(int(ppr * k), ppr, IN_TARGET)})"
        return line + (
            f" (the target's mesh {seen}: the tacho gives {share} the pulses per revolution it was read with? "
            "[target] pulses_per_rev)"
        )
    if whole:
        return line + f" (the target's shows {round(m)} teeth)"
    return line + (
        f" (not a whole number of teeth: the target's revolutions were cut at a speed {100 * abs(m / z1 - 1):.1f} % "
        "off its shaft's, or another gear meshes)"
    )


def speed_line(target_speed: float, source_speed: float, z1: int | None = None, teeth: int | None = None) -> str | None:
    """The one line of a speed difference, or None within SPEED_TOL. *z1*: the source's pinion teeth
    when the target's speed was found from the mesh lines (no tacho): the record then measures only
    speed x teeth, and another tooth count (*teeth*, else traded_teeth's) at the source's speed may
    explain it as well."""
    if abs(target_speed / source_speed - 1.0) <= SPEED_TOL:
        return None
    if z1 is not None:
        teeth = teeth or traded_teeth(target_speed, source_speed, z1)
        if teeth is not None:
            mesh = z1 * target_speed
            # what the user does about it: the input shaft's own lines told neither reading (_traded_line)
            return (
                f"speed {target_speed:.4g} Hz found from the mesh lines (no tacho), {source_speed:.4g} Hz expected: "
                f"the record's mesh at {mesh:.4g} Hz is a {z1}-tooth pinion's at {target_speed:.4g} Hz "
                f"or a {teeth}-tooth pinion's at {mesh / teeth:.4g} Hz: ambiguous (the input shaft's own lines "
                "tell neither): declare the records' speed ([target] speed) or give a tacho, and the diagnosis names "
                "what differs"
            )
    return (
        f"speed {target_speed:.4g} Hz {'found from the mesh lines (no tacho)' if z1 else 'measured'}, "
        f"{source_speed:.4g} Hz expected: the source simulates {source_speed:.4g} Hz (set its speed_hz to the record's)"
    )


def traded_teeth(target_speed: float, source_speed: float, z1: int) -> int | None:
    """The other whole tooth count whose pinion at *source_speed* meshes where a *z1*-tooth one does at
    *target_speed* (beyond SPEED_TOL), or None."""
    teeth = z1 * target_speed / source_speed
    whole = round(teeth)
    if abs(target_speed / source_speed - 1.0) <= SPEED_TOL or abs(teeth - whole) > 0.05 or whole < MIN_TEETH:
        return None
    return whole


def _beyond_slip(target_speed: float, described_speed: float, z1: int) -> int | None:
    """The whole pinion count whose speed, at the mesh the target's speed puts a *z1*-tooth pinion's, lies within a
    motor's slip or a drive's setting of the *described_speed* (speed.NOMINAL_RANGE; of two, the nearer), where
    the target's speed lies beyond it; else None. A nominal speed is no exact one: traded_teeth's whole count
    missed a 13/39 + 19/42 box described with 14 teeth at 37.9 Hz (it runs at 37.48): its mesh lines read 34.8
    Hz, 14 x 34.8 / 37.9 = 12.85 teeth; within 6 % of 37.9 Hz only 13 teeth mesh there."""
    from ..gearbox.pinion_count import allowed_counts
    from ..gearbox.speed import NOMINAL_RANGE

    if abs(target_speed / described_speed - 1.0) <= NOMINAL_RANGE:
        return None
    mesh = z1 * target_speed
    counts = [z for z in allowed_counts(mesh, described_speed) if z != z1 and z >= MIN_TEETH]
    return min(counts, key=lambda z: abs(mesh / z / described_speed - 1.0), default=None)


def level_factor(target: np.ndarray, source: np.ndarray) -> float:
    """The scale c with target ~ c x source, from the magnitudes of their synchronous averages'
    orders (a rotation -- a tacho's zero elsewhere on the shaft -- leaves them): least squares
    sum |T||S| / sum |S|^2, weighted to the source's strong lines, where the target's noise counts
    least."""
    T = np.abs(np.fft.rfft(np.mean(target, axis=0)))[1:]
    S = np.abs(np.fft.rfft(np.mean(source, axis=0)))[1:]
    denominator = float(np.sum(S * S))
    return float(np.sum(T * S) / denominator) if denominator > 0 else 1.0


def scaled_rows(rows, spec, c: float) -> np.ndarray:
    """The source's rows x c, through the target's chain as a source at level c would go: its
    quantisation step (in the target's units) is c times the source's."""
    if rows.chain is not None and rows.chain.step > 0:
        rows = replace(rows, chain=replace(rows.chain, step=rows.chain.step / c))
    return rows(spec) * c


def level_line(c: float) -> str:
    factor = c if c >= 1 else 1.0 / c
    shown = f"{factor:.2g}" if factor < 10 else f"{factor:.3g}" if factor < 1000 else f"{round(factor, -2):.0f}"
    how = f"x {shown}" if c >= 1 else f"/ {shown}"
    return (
        f"level/units differ by a factor of ~{shown}: give sensitivity and gain (the target is the source {how} "
        "within its noise; no effect is fitted to a scale)"
    )


def level_differs(c: float) -> bool:
    return math.isfinite(c) and c > 0 and abs(math.log(c)) > math.log1p(LEVEL_TOL)


def stopped(result: dict, before: dict | None, verdict: str, line: str) -> dict:
    """*result* ended before any effect search: nothing fitted, the gap as it was, the verdict and
    its one line (``difference``). *before*: None where the structure differs: the source, another
    gearbox, was not simulated, and no gap is measured (before, after and their numbers None)."""
    from .conclusion import rms_effect

    result.update(
        after=before,
        gap_after=result["gap_before"],
        significant_after=result["significant_before"],
        shrink=None if before is None else 0.0,
        effects=[],
        unexplained=True,
        verdict=verdict,
        difference=line,
        explained_share=None,
        rms_effect_before=None if before is None else rms_effect(before),
        rms_effect_after=None if before is None else rms_effect(before),
        within_noise=False,
        corrected_effects=[],
    )
    result["notes"].append(f"{verdict}: {line}; no effect was searched")
    return result


def _tacho_read(chain, pair) -> tuple | None:
    """mesh_check's *tacho* of a measured target read at a tacho (Chain.tacho_shaft), else None."""
    if chain is None or not chain.tacho_shaft:
        return None
    from ..gearbox import order_table

    box = _PairDescription.train(pair)
    if chain.tacho_shaft not in box.shafts:
        return None
    ratio = chain.speed / chain.described_speed if chain.described_speed else None
    return order_table(box), box.shafts.index(chain.tacho_shaft), ratio


def structure_line(
    target,
    pair,
    max_order: int,
    chain,
    plain,
    record: dict,
    pulses_per_rev: int | None = None,
    spectra: Spectra | None = None,
) -> str | None:
    """The one line of the first tooth-count difference between *pair*'s train and the target's
    revolutions (*target*, input-shaft revolutions at uniform angle, read up to *max_order*), or None;
    what was measured goes into *record* (a count too few turns tell: its 'unchecked'). After a speed
    found from the mesh lines that a whole tooth explains as well, in turn: the first stage's mesh
    (mesh_check: its tacho's shaft and marks too), its wheel, the later stages (against *plain*'s
    reading of itself, the source's healthy rows, or a callable that makes them, called only when a later
    stage is read; None: against the description's orders). The gap
    diagnosis's structure check (first_difference) and the detection kind's check of its history
    records (gearlab.kinds.detection_records.check_structure). *pulses_per_rev*: the marks a turn the tacho was
    read with (None: not known; a misread count is then told as a share of them). *spectra*: the check's readings
    of the revolutions (structure_later.Spectra: each history's spectrum taken once), or None for its own."""
    spectra = spectra or Spectra()
    # records whose speed the description's mesh lines gave, the source set to it: revolutions cut
    # at that speed show the described mesh order whatever the teeth (a 14-tooth pinion at 45 Hz
    # described with 15 read at 42 Hz, 'unexplained'); a speed off the described one by a whole
    # tooth's share is told, a motor's slip (no whole tooth) is not
    if chain is not None and chain.speed_from_mesh and chain.described_speed:
        record.setdefault("speed_hz", {"target": chain.speed})["described"] = chain.described_speed
        # ... or, within a motor's slip and off by no whole tooth's share (the described speed is nominal: a 29-tooth
        # pinion at 35.18 Hz described with 28 at 35.8 Hz reads 36.44 Hz, 28.5 teeth at 35.8 Hz), another count the
        # input shaft's own lines show at the speed found, as inspect reads them (wheel_line's reading of the input's
        # comb said 'the pinion shows 39.5 teeth')
        # the count those lines show before the one nearest the nominal speed (25 teeth at 33.09 Hz described with 24
        # at 32.4 Hz: 34.47 Hz read, 6.4 % off; 26 teeth at 31.82 Hz lie nearer 32.4 Hz than 25 at 33.09 Hz)
        shown = _input_count(_longest(target, chain), pair, max_order, chain, chain.described_speed, spectra)[1]
        teeth = shown if shown not in (None, pair.Z1) else traded_teeth(chain.speed, chain.described_speed, pair.Z1)
        teeth = teeth or _beyond_slip(chain.speed, chain.described_speed, pair.Z1)
        if teeth is not None:
            return _traded_line(target, pair, max_order, chain, teeth, record, shown, spectra)
    # a tacho on another shaft than the input, or a speed found from the mesh lines: the input's order is
    # read off its sidebands, as inspect reads it (a 23/61 fan's output tacho, described 24/61: the mesh
    # at 24 by the described ratio, the input's sidebands 24/23 apart; inspect said '23.0 teeth', detection
    # ran; a 17/44 + 21/53 reducer without a tacho described with 18 teeth: the speed found 17/18 of its own)
    input_shaft = _PairDescription.train(pair).shafts[0]
    on_input = chain is None or (chain.tacho_shaft or (None if chain.speed_from_mesh else input_shaft)) == input_shaft
    tacho = _tacho_read(chain, pair)
    takes = _takes(target, chain)
    whole = mesh_check(target, pair.Z1, pair.Z2, max_order, later_combs(pair), tacho, on_input, spectra)
    # record['mesh'] is the reading the line (or the pass) was decided on, 'read_on' says which
    laid = {"read_on": "records laid end to end" if takes else "all revolutions", "revolutions": len(target)}
    record["mesh"] = whole | laid
    if whole.get("shaft") or whole.get("marks"):  # the tacho itself read wrong: no shaft's speed is known
        return mesh_line(whole, pair.Z1, pulses_per_rev)
    # a tacho on another shaft with another count of marks: every order reads their product times its own, which
    # mesh_check's shaft alone and marks alone miss (a 19/47 + 29/71 reducer's 1-mark output tacho read as the
    # input's 2: 12.11 x, 'stage 1 pinion: 230 teeth fit the recording'); read as inspect reads it,
    # on all revolutions as mesh_check's shaft alone, before the gears
    if tacho is not None and (line := _misread_line(target, pair, max_order, tacho, pulses_per_rev, record, spectra)):
        return line
    # a slower shaft's sidebands within one record (the longest): records laid end to end are in register
    # on the input shaft only (a 13/81 fan's three takes of 228 turns: 'the wheel shows 80.3 ± 0.6 teeth')
    one = _longest(target, chain)
    mesh = mesh_check(one, pair.Z1, pair.Z2, max_order, later_combs(pair), tacho, on_input, spectra) if takes else whole
    if takes:  # summary.json showed the records laid end to end (89.4 ± 0.7) where the line read 89.0 ± 1.8
        record["mesh"] = mesh | {"read_on": f"the longest of {len(takes)} records", "revolutions": len(one)}
    # any tacho's shaft, the input's too (a 38/89 + 48/95 described for 49/95 read 'stage 2: mesh order 20.92
    # measured ... or a wheel upstream, differs' with an input tacho, 'stage 2 pinion: 49 teeth fit' with an output one)
    if tacho is not None and (line := outward_line(one, pair, max_order, tacho[1], record, spectra)):
        return line
    # no tacho, the input's mesh where described: the stages as inspect reads such a record (its shaft's order
    # not 1 by fiat), outward from the input; a later gear one tooth off is that gear, not another mesh order
    # (68/103 + 82/99 described 68/104: 'mesh order 54.1 measured, 68 expected ... 20.4 % off', inspect named
    # the 103-tooth wheel)
    no_tacho = chain is not None and not chain.tacho_shaft  # a declared speed's too: refined on the mesh lines
    if no_tacho and (line := _no_tacho_line(one, pair, max_order, record, spectra)):
        return line
    if whole["differs"]:  # the input's mesh: records laid end to end are in register on its shaft
        record["mesh"] = whole | laid
        return mesh_line(whole, pair.Z1, pulses_per_rev)
    target = one
    # the wheel: its shaft's sidebands of the mesh, as inspect reads them (a 29/86 mixer described
    # with an 85-tooth wheel: inspect said '86.0 ± 0.2 teeth', the gap fitted effects, 'unexplained')
    line = (None if on_input else wheel_line(mesh, pair.Z1, "pinion")) or wheel_line(mesh, pair.Z2)
    if line:
        return line
    later = later_stages(target, plain() if callable(plain) else plain, pair, max_order, spectra)
    if later["stages"]:
        record["later_stages"] = later["stages"]
    if later["line"]:
        return later["line"]
    # what passed unchecked, as inspect says it (gearbox.match.unchecked on check_description read as inspect
    # reads the record): a tooth count its sidebands cannot tell from the next one over these revolutions (D,
    # 43/89 described with 88 teeth, three records of ~52 turns: inspect 'not checked ... need 103', the gap
    # 'unexplained', the wheel unsaid), a shaft whose order no sideband shows (its wheel checked only through a
    # later mesh: inspect said so, the gap's verdict did not)
    if unresolved := _inspect_unchecked(target, pair, max_order, on_input, tacho, spectra):
        record["unchecked"] = unchecked_record(unresolved, takes)
    return None


def _takes(target, chain) -> tuple:
    """The revolutions of each record laid end to end in *target* (chain.takes), or () for one record."""
    return chain.takes if chain is not None and len(chain.takes) > 1 and sum(chain.takes) == len(target) else ()


def _longest(target, chain):
    """The longest record's revolutions of *target*: a shaft other than the one the revolutions were cut on is
    in register within one record only."""
    takes = _takes(target, chain)
    return target[sum(takes[: (k := int(np.argmax(takes)))]) : sum(takes[: k + 1])] if takes else target


def _input_count(target, pair, max_order: int, chain, declared: float, spectra: Spectra | None = None) -> tuple:
    """gearbox.pinion_count.pinion_evidence of *target*'s revolutions read at the speed found from the mesh lines
    (*chain*.speed), as inspect reads a record without a tacho: (the first mesh's line in Hz, the pinion count the
    input shaft's own lines show or None, [(z, Hz)] of the other counts the line allows near *declared*)."""
    from ..gearbox import order_table
    from ..gearbox.pinion_count import pinion_evidence

    table = order_table(_PairDescription.train(pair))
    return pinion_evidence(
        _lines(target, max_order, spectra), chain.speed, target.shape[0], table, int(pair.Z1), declared
    )


def _traded_line(
    target, pair, max_order: int, chain, teeth: int, record: dict, shown: int | None = None, spectra=None
) -> str:
    """The line of a speed found from the mesh lines a whole tooth's share off the described one: the input
    pinion's sidebands decide between the described count at the speed found and *teeth* at the described
    speed, as inspect decides it (their spacing is the input shaft's turn, whatever the speed read); where
    they show neither, speed_line's either-or. A 17/53 + 22/67 + 29/83 box described with 18 teeth, no tacho:
    every stage's mesh where 18 puts it at 33.06 Hz, the input's sidebands 17 teeth apart at 35 Hz. *shown*:
    the count the input shaft's lines show read as inspect reads them (_input_count), where the comb of
    mesh_check's reading shows none or another."""
    mesh = mesh_check(target, pair.Z1, pair.Z2, max_order, later_combs(pair), None, False, spectra)["inspect"]
    seen, spread = mesh.get("z1_seen"), mesh.get("z1_resolution") or 0.0
    if seen is None or abs(seen - teeth) > max(TEETH_AGREE, spread):
        if shown != teeth:
            return speed_line(chain.speed, chain.described_speed, pair.Z1, teeth)
        seen, spread = float(teeth), 0.0
    record["outward"] = {"stage": 1, "gear": "pinion", "seen": float(seen), "described": int(pair.Z1)}
    shows = f"pinion's sidebands show {seen:.1f} ± {spread:.1f}" if spread else f"shaft's own lines show {teeth}"
    return (
        f"mesh order {teeth} measured, {pair.Z1} expected (stage 1): the input {shows} teeth, the input at "
        f"{pair.Z1 * chain.speed / teeth:.4g} Hz (no tacho: the mesh lines read {chain.speed:.4g} Hz for a "
        f"{pair.Z1}-tooth pinion); every later mesh follows from it"
    )


def _inspect_unchecked(target, pair, max_order: int, on_input: bool, tacho, spectra=None) -> list[str]:
    """gearbox.match.unchecked of *target*'s revolutions read against *pair*'s train as inspect reads a record
    (the input's order 1 where *on_input*, a tacho's shaft index from *tacho*: _tacho_read), no speed found."""
    from ..gearbox.match import unchecked

    box = _PairDescription.train(pair)
    return unchecked(_inspected(target, max_order, box, on_input, tacho and tacho[1], spectra), box, None)


def unchecked_record(unresolved: list[str], takes: tuple = ()) -> dict:
    """{'items': inspect's 'not checked' reasons, 'line': the structure's one line}: the structure passed,
    but not every tooth count was told from the next one. *takes*: the records' revolutions laid end to
    end (a slower shaft is read within the longest alone)."""
    line = "structure not fully checked: " + "; ".join(unresolved)
    if takes:
        line += (
            f", read within one record (the longest of {len(takes)}: records laid end to end are in register "
            "on the input shaft only)"
        )
    return {"items": list(unresolved), "line": line}


def _misread_line(
    target, pair, max_order: int, tacho: tuple, ppr: int | None, record: dict, spectra=None
) -> str | None:
    """The one line of a tacho read on another shaft with another count of marks a turn than it gives
    (inspect_tacho.misread on the stages as inspect reads them: check_description with the tacho's shaft), or
    None. *tacho*: _tacho_read's; *ppr*: the marks a turn read (None: not known)."""
    from ..inspect_tacho import misread, misread_line

    box = _PairDescription.train(pair)
    _, read, ratio = tacho
    n = target.shape[0]
    spectra = spectra or Spectra()
    lines = _lines(target, max_order, spectra)
    check = _inspected(target, max_order, box, read == 0, read, spectra)
    found = misread(check, box, box.shafts[read], ppr, ratio, 1.0 / n, lines)
    if found is None:
        return None
    record["tacho"] = {"shaft": found[0], "marks_read_over_given": float(found[1]), "factor": found[2]}
    return misread_line(found, check, box.shafts[read], ppr, IN_TARGET)


def outward_line(target, pair, max_order: int, tacho: int, record: dict, spectra=None) -> str | None:
    """The one line of the first gear, read outward from the tacho's shaft (index *tacho*; 0, the input,
    alike), whose tooth count the target's revolutions contradict, or None. The stages are read as inspect
    reads them (gearbox.match.check_description with the tacho's shaft); a stage's mesh, in orders of
    its shaft nearer the tacho, is that gear's count while every gear between is as described, and the
    far gear's count is its shaft's sidebands of the mesh. A wrong gear puts every stage beyond it off
    (Q, 38/89 + 49/95 with an output tacho, described with a 48-tooth later pinion: the input read 2 %
    slow, stage 1's mesh at 37.2, 'mesh order 37.2 measured, 38 expected', the pinion unnamed); the
    nearest stage first, the input's side after the output's at one distance."""
    from ..gearbox.leading import inspect_first, outward

    box = _PairDescription.train(pair)
    stages = _inspected(target, max_order, box, tacho == 0, tacho, spectra)["stages"]
    found = inspect_first(stages) or outward(stages, box, tacho)
    if found is None:
        return None
    record["outward"], line = found
    return line


def _no_tacho_line(target, pair, max_order: int, record: dict, spectra=None) -> str | None:
    """outward_line of a multi-stage train's record without a tacho, read as inspect reads one (no shaft's
    order given), from the input shaft, when inspect finds the first mesh where described; else None."""
    from ..gearbox.leading import inspect_first, outward

    box = _PairDescription.train(pair)
    stages = _inspected(target, max_order, box, False, None, spectra)["stages"]
    if len(stages) < 2 or not stages[0].get("matched"):
        return None
    origin = "the input shaft (no tacho: its speed from the mesh lines)"
    found = inspect_first(stages) or outward(stages, box, 0, origin)
    if found is None:
        return None
    record["outward"], line = found
    return line


def count_ambiguity(
    target, pair, max_order: int, chain, declared: float | None = None, spectra: Spectra | None = None
) -> dict | None:
    """Where the target's speed came from the description's mesh lines (no tacho, no speed given) and no
    line of the input shaft tells the pinion's count, the other counts the mesh line allows at speeds
    within the nominal range, as inspect decides it (gearbox.pinion_count.pinion_evidence: inspect's
    check.ambiguous): {'speed_hz', 'others': [(teeth, Hz)], 'line'}, else None. A structure that passes
    then holds only if the input turns at the speed read (a 37-tooth pinion at 24.53 Hz meshes where the
    described 36 at 25.22 Hz do). *declared*: the description's speed where the chain holds none (a measured
    dataset's chain, data.chain.chain_of). *spectra*: structure_line's readings, or None."""
    declared = (chain and chain.described_speed) or declared
    if chain is None or not chain.speed_from_mesh or not declared:
        return None
    from ..gearbox import order_table
    from ..gearbox.pinion_count import alternatives_words
    from ..signals.checks import fmt_hz

    _, seen, others = _input_count(target, pair, max_order, chain, declared, spectra)
    if seen is not None or not others:
        return None
    why = order_table(_PairDescription.train(pair))  # a later shaft's whole turn hides the input's lines: say so
    line = (
        f"the input pinion's tooth count is ambiguous: the description holds if the input turns at "
        f"{fmt_hz(chain.speed)}; {alternatives_words(others, '[target] speed', why)}"
    )
    return {"speed_hz": chain.speed, "others": [[int(z), float(hz)] for z, hz in others], "line": line}


def first_difference(source, target, pair, settings, rows, fresh, plain, before, chain) -> tuple:
    """(verdict, its one line, what was measured) of the first thing no effect changes that differs
    between the *source* and the *target* -- its speed (a measured target's chain), its tooth count,
    a pure scale factor -- or (None, None, what was measured). *plain*(): the plain source's rows on
    the reports' seeds (*fresh*), *before*(): their report against the target, each made when first
    asked (the speed and a first stage's teeth are read off the target and the description alone);
    *rows*: how the source's rows are made."""
    from ..data.builder import operating_point
    from .conclusion import gap_seen, verdict_of, within_noise
    from .scoring import _report

    record: dict = {}
    if chain is not None:
        record["speed_hz"] = {"target": chain.speed, "source": operating_point(source)[0]}
        line = speed_line(chain.speed, record["speed_hz"]["source"], pair.Z1 if chain.speed_from_mesh else None)
        if line:
            return "structure differs", line, record
    spectra = Spectra()  # the structure check's and the ambiguity's one reading of each history
    ppr = chain and chain.pulses_per_rev
    line = structure_line(target, pair, settings.max_order, chain, plain, record, ppr, spectra)
    if line:
        return "structure differs", line, record
    declared = record.get("speed_hz", {}).get("source")  # a measured dataset's chain holds no described speed
    if ambiguous := count_ambiguity(target, pair, settings.max_order, chain, declared, spectra):
        record["ambiguous"] = ambiguous  # the diagnosis goes on; its verdict says it (conclusion.verdict_text)
    before = before()
    if not gap_seen(before):
        return None, None, record
    c = level_factor(target, plain())
    record["level"] = {"factor": c}
    if not level_differs(c):
        return None, None, record
    after = _report(scaled_rows(rows, fresh, c), target, pair, settings)
    gap0, gap1 = float(before["total"]["gap"]), float(after["total"]["gap"])
    share = 1.0 - gap1 / gap0 if gap0 > 0 else 0.0
    closed = verdict_of(True, True, gap_seen(after), float(after["auc"]), share, within=within_noise(before, after))
    record["level"].update(gap_scaled=gap1, p_scaled=float(after["p_value"]), closes=closed == "explained")
    return ("level differs", level_line(c), record) if closed == "explained" else (None, None, record)
