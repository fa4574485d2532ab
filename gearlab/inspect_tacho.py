"""A pulse tacho read wrong: on another shaft than the one it is read as (elsewhere_line, on
gearbox.match.tacho_elsewhere), with another count of marks a turn (marks_line), or both (misread,
shaft_and_marks): both together scale every order by their product, which neither alone tries: a 19/47 + 29/71
reducer's 1-mark output tacho read as the input's 2 reads every order 12.11 x its own (6.056 x 2), and inspect said
'a 230-tooth pinion on the input shaft? described 19'. `gearlab inspect --gearbox` and the gap's structure check,
which the detection kind's check of its history records is (gap.structure.structure_line), read it here.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from fractions import Fraction

import numpy as np

from .data.recordings import speed_channel_note
from .errors import GearlabInputError
from .gearbox import Gearbox, order_table
from .gearbox.match import MIN_TEETH, STRONGEST, TACHO_SPEED_TOL, tacho_elsewhere, tacho_shaft_words, tol_mesh
from .signals import resample_revolutions
from .signals.checks import reversal, reversal_words, speed_varies, turn_times
from .signals.tacho_mended import mended_words


@contextmanager
def speed_channel(tacho: np.ndarray):
    """Re-raise a tacho's refusal as a speed channel's (data.recordings.speed_channel_note) where its level says so,
    as a run does: inspect said a 30 Hz speed channel given as --tacho had 'pulse train has 1 rising edge(s)'."""
    try:
        yield
    except GearlabInputError as exc:
        raise GearlabInputError(speed_channel_note(tacho) or str(exc)) from None


MARKS = range(1, 9)  # the counts of marks a turn tried, as marks_line tries them


def reversal_notes(signal: np.ndarray, fs: float, theta: np.ndarray) -> list[str]:
    """inspect's note of a take whose shaft reverses (signals.checks.reversal), its input angle *theta* read off its
    tacho: inspect reads a take whole, both ways in its spectrum and averages, where a detection run and `gearlab
    score` keep one side (detection_in_band). [] where its speed is steady or it turns one way."""
    if not speed_varies(theta, fs):
        return []
    found = reversal(resample_revolutions(signal, theta), turn_times(theta, fs))
    if found is None:
        return []
    return [
        f"{reversal_words(found)} (its turns after match those before mirrored or off the tacho's mark, which "
        "counts turns either way): read whole here, both ways in its spectrum and averages; a detection run and "
        "gearlab score keep the side of its longest run at a history's speed"
    ]


def _ratios(ppr: int | None) -> list[Fraction]:
    """The marks read a turn over the tacho's own: *ppr* / k for k in MARKS, or, the count read unknown (a
    structure check given no pulses_per_rev), every p / k of two counts in MARKS."""
    if ppr is not None:
        return [Fraction(ppr, k) for k in MARKS]
    return sorted({Fraction(p, k) for p in MARKS for k in MARKS}, key=lambda r: (r.denominator, r.numerator))


def misread(check: dict, box, read: str, ppr: int | None, ratio: float | None, bin_: float, lines=None) -> tuple | None:
    """(shaft, r, f) of a tacho on shaft s with r times fewer marks a turn than read, read as *ppr* (None: not
    known) on shaft *read*: every order reads f = (o_read / o_s) r times its own. Found where the speed read is
    1 / f of the described (*ratio*: read / described, within TACHO_SPEED_TOL) and every stage's mesh line lies at
    f times its order (among check_description's measured orders; where a stage did not match, its unexplained
    lines and the STRONGEST of *lines*, the Lines it read; *bin_*: the order resolution); else None. Without a
    described speed nothing is found: the lines alone fit any shaft and count whose product is f. *box*: a Gearbox,
    or anything order_table reads (the gap's _PairDescription)."""
    stages = check["stages"]
    if ratio is None or not stages:
        return None
    table = order_table(box)
    o_read = float(table.shaft_orders[list(table.shafts).index(read)])
    described = [s["expected_order"] for s in stages]
    seen = [s["measured_order"] for s in stages if s.get("measured_order") is not None]
    if not all(s["matched"] for s in stages):
        # a stage given no line, or another, may have its mesh among the lines no described order explains: a 21/59
        # box's 2-mark output tacho read as a 1-mark input's put the mesh at 29.5, and stage 1 was given no line
        seen += [u["order"] for u in check["unexplained"]]
        # ... or among the strongest, explained as another's: a 19/47 + 29/71 reducer's 2-mark output tacho put stage
        # 2's mesh at 35.5, read as its 3rd harmonic's sideband (35.17 + 0.40), and gave it the line at 4.43
        seen += [] if lines is None else [float(x) for x in lines.at[:STRONGEST]]
    for name, o in zip(table.shafts, table.shaft_orders):
        for r in _ratios(ppr):
            f = o_read / float(o) * float(r)
            # one alone is the others' to tell; a product near 1 (2 marks on a shaft turning half as fast, read as 1)
            # reads as the right one
            alone = float(o) == o_read or r == 1 or abs(f - 1.0) <= TACHO_SPEED_TOL
            if alone or abs(ratio * f - 1.0) > TACHO_SPEED_TOL:
                continue
            # each stage's mesh among the lines read, whichever stage check_description gave it to (19 turns of the
            # reducer above gave stage 1 the line at 142, stage 2's mesh 11.72 x 12.11, and stage 2 the line at 230)
            if all(any(abs(x - f * m) <= tol_mesh(f * m, bin_) for x in seen) for m in described):
                return str(name), r, f
    return None


def misread_line(found: tuple, check: dict, read: str, ppr: int | None, table: str | None = None) -> str:
    """The one line of misread's *found*: the first stage's mesh as read, the tacho's shaft and marks, and how to
    read it (inspect's options and a scenario's keys, or with *table* the keys of the scenario table that holds the
    records, where a run that has no such options says it; without *ppr*, the marks as a share of those read)."""
    name, r, f = found
    m = check["stages"][0]["expected_order"]
    line = f"stage 1: mesh order {f * m:.4g} measured, {m:.4g} expected ({tacho_shaft_words(name, f, read)} "
    if ppr is not None:
        k = Fraction(ppr) / r  # a whole count: _ratios' ppr / k
        how = (
            f"{table} tacho_shaft = '{name}', pulses_per_rev = {k}"
            if table
            else f"--tacho-shaft {name} --pulses-per-rev {k}, keys 'tacho_shaft' and 'pulses_per_rev' in a scenario"
        )
        return line + f"with {k} pulse(s) per revolution, not {ppr}? ({how})"
    return line + (
        f"with {1 / r} x the pulses per revolution it was read with? ([target] tacho_shaft = '{name}', "
        f"pulses_per_rev x {1 / r})"
    )


def shaft_and_marks(
    check: dict, box: Gearbox, read: str, ppr: int, ratio: float | None, bin_: float, lines=None
) -> list[str]:
    """inspect's verdict line for misread's tacho (module doc), or []."""
    found = misread(check, box, read, ppr, ratio, bin_, lines)
    return [] if found is None else [misread_line(found, check, read, ppr)]


def elsewhere_line(lines, box: Gearbox, read: str, speed, revolutions: int) -> str | None:
    """A tacho on another shaft of the description than the one it was read as (match.tacho_elsewhere
    on the strongest lines, as the gap's structure check reads them), in one line, or None."""
    keep = lines.at >= MIN_TEETH - 0.5
    x, amp = lines.at[keep][:STRONGEST], lines.amp[keep][:STRONGEST]
    tol = np.array([tol_mesh(v, 1.0 / revolutions) for v in x])
    ratio = speed.mean_hz / box.speed_hz if box.speed_hz else None
    table = order_table(box)
    below = lines.at[~keep]  # for a faster shaft than the one read (its meshes read at low orders)
    low = (below, lines.amp[~keep] ** 2, np.array([tol_mesh(v, 1.0 / revolutions) for v in below]))
    found = tacho_elsewhere(x, amp**2, tol, table, box.shaft_index(read, "--tacho-shaft"), ratio, low)
    if found is None:
        return None
    name, f = found
    m = float(table.stages[0].mesh)
    return (
        f"stage 1: mesh order {f * m:.4g} measured, {m:.4g} expected ({tacho_shaft_words(name, f, read)} "
        f"--tacho-shaft {name}, key 'tacho_shaft' in a scenario)"
    )


def marks_words(marks: int, ppr: int, table: str | None = None) -> str:
    """A tacho on the shaft it is read as, giving *marks* a turn where *ppr* were read, and how to read it: inspect's
    option and a scenario's key, or with *table* (the gap's structure check, run on a scenario, which has no such
    option) that table's key. inspect's marks_line and the gap's mesh_line both use it: one sentence for one fault."""
    how = f"--pulses-per-rev {marks}, key 'pulses_per_rev' in a scenario"
    how = f"{table} pulses_per_rev = {marks}" if table else how
    return f"the tacho gives {marks} pulse(s) per revolution, not {ppr}? ({how})"


def implied_marks(ppr: int, ratio: float | None) -> set[int]:
    """The whole count of marks a turn, other than *ppr* and over 8 (marks_line tries those), that would bring the
    speed read (*ratio* x the described) to the described one: {ppr x ratio} where that is within 5 % of a whole
    count, else {}. An encoder's count typed a factor off (6 for 60, 360 for 36) lies beyond 8."""
    if ratio is None or ratio <= 0:
        return set()
    marks = _whole_count(ppr, ratio)
    return {marks} if marks > 8 and marks != ppr and abs(ppr * ratio / marks - 1) < 0.05 else set()


def _whole_count(ppr: int, ratio: float) -> int:
    """The whole count of marks nearest *ppr* x *ratio*, a whole multiple or divisor of *ppr* first where one lies
    within 5 %: a count typed a factor off (6 for 60) read on a shaft 1 % off its described speed is 60.6 x, and 61
    marks a turn is no encoder's count."""
    k = round(ratio) if ratio >= 1 else round(1 / ratio)
    typed = ppr * k if ratio >= 1 else (ppr // k if k and ppr % k == 0 else 0)
    return typed if typed and abs(ppr * ratio / typed - 1) < 0.05 else round(ppr * ratio)


SHAFT_RATIO_TOL = 0.01  # a speed read a shaft ratio off within this: the tacho's shaft, not its count of marks


def shaft_ratios(box: Gearbox) -> tuple[float, ...]:
    """Every ratio of two different shafts' turns of the description *box* (speed_marks_line's *ratios*)."""
    turns = [float(o) for o in order_table(box).shaft_orders]
    return tuple(a / b for a in turns for b in turns if abs(a / b - 1) > SHAFT_RATIO_TOL)


def speed_marks_line(
    speed: float, described: float | None, ppr: int | None, where: str, table: str = "[target]", ratios=()
) -> str | None:
    """The one line of a tacho whose *speed* read is a whole count of marks off the *described* speed (a 60-mark
    encoder typed as 6: 600 Hz read for 60). *where*: the location of the pulses_per_rev read, in *table* (a
    scenario's [target], a 'files' entry, the description's [sensor]). None where no count fits, the speed is
    within 25 % of the described (slip, another load), or nearer one of *ratios* (shaft_ratios: a tacho on another
    shaft than the one it is read as, which the structure check names; 19/62 x 23/87 is 12.34, not 12 marks, while a
    60-mark encoder typed 6 reads 10.00 x beside a box turning 1 : 10.02)."""
    if not described or not ppr or 0.8 <= speed / described <= 1.25:
        return None
    marks = _whole_count(ppr, speed / described)
    off = abs(ppr * speed / described / marks - 1) if marks >= 1 else math.inf
    if marks < 1 or marks == ppr or off >= 0.05:
        return None
    if any(abs(speed / described / q - 1) < min(SHAFT_RATIO_TOL, off) for q in ratios):
        return None
    return (
        f"{where}: the tacho reads the shaft at {speed:.4g} Hz, {speed / described:.3g} x the described "
        f"{described:.4g} Hz: {marks_words(marks, ppr, table)}"
    )


def marks_line(check: dict, lines, ppr: int, bin_: float, ratio: float | None) -> list[str]:
    """A tacho read with the wrong marks per turn scales every order by f: the first mesh shows at f M and the input
    shaft's line at f, f = 1 / k when k marks a turn are read as one (a 29/86 mixer's 2-pulse keyphasor read as 1: mesh
    at 14.5, and its 2nd harmonic at 29 passed as the mesh) or k (fewer: mesh at 58, its harmonics all on M's,
    'matches'). The line at f M stronger than at M tells it, with the shaft's line at f stronger than at 1 or a
    speed 1 / f times the described (*ratio*): a mesh whose power sits at its harmonics (no line at M) keeps its
    shaft at 1."""

    def amp(x: float) -> float:
        i = lines.near(x, tol_mesh(x, bin_))
        return 0.0 if i is None else float(lines.amp[i])

    first = check["stages"][0]
    m = first["expected_order"]
    unexplained = [u["order"] for u in check["unexplained"] if "shaft_harmonic" not in u]  # a clock's line: no mesh
    # any count of marks up to 8 (a 3-mark output tacho described with 2: every order at 2/3 of its own, 'the wheel
    # on the output shaft shows 10.9 teeth'), the nearest the described count first; and the count the speed read
    # implies, whatever its size (a 60-mark encoder typed as 6 read 10 x the described speed, every mesh at a tenth)
    tried = {q for q in range(1, 9) if q != ppr} | implied_marks(ppr, ratio)
    for marks in sorted(tried, key=lambda q: (abs(math.log(q / ppr)), q)):
        for f in (ppr / marks,):
            at_mesh, at_shaft = amp(f * m), amp(f)
            described = ratio is not None and abs(ratio * f - 1) < 0.05
            if at_mesh <= amp(m) or (at_shaft <= amp(1.0) and not described):
                continue
            if f < 1 and not any(abs(u - f * m) <= tol_mesh(f * m, bin_) for u in unexplained):
                continue  # another stage's mesh
            return [
                f"stage 1: the {first['z1']}-tooth pinion's mesh shows at order {f * m:.4g}, not {m:.4g}"
                + (f", the input shaft at {f:.3g}" if at_shaft > amp(1.0) else "")
                + (f", the speed {1 / f:.3g} x the described" if described else "")
                + f": {marks_words(int(marks), ppr)}"
            ]
    return []


def pulses_how(rec, ppr: int, shaft: str) -> str:
    """How inspect read the speed from a pulse tacho of *ppr* marks a turn on *shaft*, with what its edges mended
    (a missed pulse put back, a glitch's left out: signals.tacho_mended)."""
    mended = mended_words(rec.tacho, rec.fs, ppr)
    return f"tacho '{rec.tacho_name}' ({ppr} pulse(s) per revolution{mended}) on the {shaft} shaft"
