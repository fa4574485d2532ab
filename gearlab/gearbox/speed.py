"""The input-shaft speed of a record without a tacho, from a gearbox description's mesh lines
(docs/gearbox.md): the spectral lines of the record, each tried as a mesh harmonic of each stage.
Used by the importer (gearlab.data.recordings) and by `gearlab inspect`."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..errors import GearlabInputError
from ..signals import spectrum, upsampled
from ..signals.checks import SPEED_VARIES, UNSEEN_WORDS, fmt_hz, speed_shape, speed_varies, stopped
from ..signals.pipeline import Upsampled
from .description import Gearbox
from .orders import order_table
from .speed_course import FLOOR_BINS, SHIFT_MIN, speed_course, speed_shift

THRESHOLD_DB = 15.0  # a line stands this far over the running median of the spectrum
PEAK_BINS = 7  # a line is the largest value within ±3 bins (Hann sidelobes are not lines)
DECLARED_RANGE = 0.01  # a declared speed is trusted to ±1 %
# A declared speed is nominal: a motor under load runs below it (an induction motor's slip, up to some 6 %:
# a 4-pole motor's 1500 rpm is 1476 rpm at its rated load), a drive's setting above it. A speed further
# than DECLARED_RANGE but within NOMINAL_RANGE is taken from the mesh lines only where the shaft sidebands
# confirm it (sidebands_confirm): a mesh line alone cannot tell a slipping motor from another tooth count.
NOMINAL_RANGE = 0.06
AMBIGUOUS = 0.9  # a second speed hypothesis explaining ≥ 90 % of the best one's power is ambiguous
SPEED_AGREE = 0.005  # two hypotheses within 0.5 % are the same speed
DRIFT = 1e-3  # relative smear of an order by speed drift
# A mesh line is tried as harmonic 1-40 of each stage: a simulated mesh can hold its power at
# harmonics 4-11 with its fundamental under the threshold (B-6-ch5: orders 100, 175, 225 of 25).
MAX_HARMONIC = 40
EVIDENCE = 16  # hypotheses are scored on the strongest lines
AMBIGUOUS_TRIES = 8  # an ambiguous speed: the best hypotheses followed on their mesh phase


@dataclass
class Lines:
    """Spectral lines: position (orders or Hz), amplitude, dB over the running median."""

    at: np.ndarray
    amp: np.ndarray
    db: np.ndarray

    def near(self, x: float, tol: float) -> int | None:
        """Index of the strongest line within ±tol of x, or None."""
        inside = np.flatnonzero(np.abs(self.at - x) <= tol)
        return None if inside.size == 0 else int(inside[np.argmax(self.amp[inside])])

    def closest(self, x: float, half: float, exclude=()) -> int | None:
        inside = [i for i in np.flatnonzero(np.abs(self.at - x) <= half) if i not in exclude]
        return None if not inside else int(min(inside, key=lambda i: abs(self.at[i] - x)))


def find_lines(axis: np.ndarray, amp: np.ndarray, threshold_db: float, low: float, high: float) -> Lines:
    """Peaks of a spectrum standing *threshold_db* over its running median, refined to a fraction
    of a bin (parabola through the log amplitude of the peak bin and its neighbours)."""
    from scipy import ndimage  # here: checking a scenario imports this module, and no scipy.ndimage

    floor = ndimage.median_filter(amp, size=min(FLOOR_BINS, amp.size | 1), mode="nearest")
    floor = np.maximum(floor, 1e-300)
    peak = (ndimage.maximum_filter(amp, size=PEAK_BINS, mode="nearest") == amp) & (
        amp > floor * 10 ** (threshold_db / 20)
    )
    peak[[0, -1]] = False
    idx = np.flatnonzero(peak & (axis >= low) & (axis <= high))
    step = axis[1] - axis[0]
    with np.errstate(divide="ignore"):
        l, c, r = (np.log(np.maximum(amp[idx + k], 1e-300)) for k in (-1, 0, 1))
    denom = l - 2 * c + r
    delta = np.where(denom < 0, 0.5 * (l - r) / np.where(denom < 0, denom, -1), 0.0)
    delta = np.clip(delta, -0.5, 0.5)
    at = axis[idx] + delta * step
    height = np.exp(c - 0.25 * (l - r) * delta)
    order = np.argsort(-height)
    return Lines(at[order], height[order], 20 * np.log10(height[order] / floor[idx][order]))


SPAN = 3.5  # a mesh carrier is the strongest line within ±3.5 shaft orders (its sidebands j ≤ 3)


def carrier(lines: Lines, i: int, span: float, others=()) -> int:
    """The strongest line within ±span of line *i*, unless it sits on another stage's mesh
    harmonic (*others*: (order, tolerance)): the line at a described mesh order may be a sideband
    of the real carrier (z off by j teeth puts M on the j-th sideband of the pinion's shaft)."""
    near = np.flatnonzero(np.abs(lines.at - lines.at[i]) <= span)
    near = [q for q in near if not any(abs(lines.at[q] - o) <= t for o, t in others)]
    return int(max(near, key=lambda q: lines.amp[q])) if near else i


class AmbiguousSpeed(GearlabInputError):
    """Two speeds explain the mesh lines about equally; *speeds*: every hypothesis, best first."""

    def __init__(self, message: str, speeds: list[float], head: str | None = None):
        super().__init__(message)
        self.speeds, self.head = speeds, head or message  # head: the message without its hint

    def __reduce__(self):  # raised in a worker (a run's record pool): pickled whole, not a BrokenProcessPool
        return type(self), (str(self), self.speeds, self.head)


def hit_sums(hit: np.ndarray, *values: np.ndarray) -> list[np.ndarray]:
    """Per row r of *hit* (rows, n), the sum of each of *values* (rows, n) over the row's hits: numpy's sum of the
    1-D array values[r][hit[r]], the same float (a row's sum is that of its own array: the rows of one hit count
    are summed together); NaN where a row has none. One sum of a few elements at a time was most of the CPU of
    speed_from_mesh's refits (some 1,000 a record) and mesh_family's (640 a call)."""
    count = hit.sum(axis=1)
    first = np.argsort(~hit, axis=1, kind="stable")  # each row's hits first, in their order
    sums = [np.full(hit.shape[0], np.nan) for _ in values]
    for n in np.unique(count[count > 0]).tolist():
        at = np.flatnonzero(count == n)
        take = first[at, :n]
        for total, v in zip(sums, values):
            total[at] = np.take_along_axis(v[at], take, axis=1).sum(axis=1)
    return sums


def speed_from_mesh(
    signal: np.ndarray, fs: float, box: Gearbox, declared: float | None, where: str, threshold_db: float = THRESHOLD_DB
) -> tuple[float, str, str | None]:
    """(input speed in Hz, how it was found, a note or None) of a record without a tacho, from the
    description's mesh lines: each strong line tried as a mesh harmonic (1-MAX_HARMONIC) of each
    stage; a hypothesis must put a mesh harmonic on a carrier, and is scored by the stages it finds
    and the lines it explains; of those explaining as much (TIE) the fastest, the harmonic family's
    fundamental. A *declared* speed is nominal: the search is limited to ±1 % of it, or to ±6 % where
    the input pinion's sidebands confirm the speed (NOMINAL_RANGE; the declared speed is kept, with a
    note, when no line fits); with none, two hypotheses at speeds that are not multiples of each other
    and explain nearly as much are refused as ambiguous. *where*: the file and channel, for the messages."""
    n = signal.size
    table = order_table(box)
    freq, amp = spectrum(signal, fs)
    lines = find_lines(freq, amp, threshold_db, 2 * freq[1], 0.45 * fs)
    if lines.at.size == 0:
        if declared is not None:
            return declared, "declared", "no spectral line to check the declared speed against"
        raise GearlabInputError(f"{where}: shows no spectral line; cannot find the speed")
    df = fs / n
    # the strongest lines are the evidence; each counts by its height over the floor (capped), so
    # the speed that explains the sidebands too beats one that only puts a harmonic on a carrier
    x, weight = lines.at[:EVIDENCE], np.minimum(lines.db[:EVIDENCE], 40.0)
    tol = np.maximum(2.5 * df, DRIFT * x)
    slowest = float(min(table.shaft_orders))
    # explain() reads every (line, stage, harmonic) tried at once, some 1,000 a record, twice: what does
    # not depend on the speed is worked out once here (the sums and comparisons stay the same ones)
    combs = []
    for s in table.stages:
        m = float(s.mesh)
        shafts = (float(s.pinion_shaft_order), float(s.wheel_shaft_order))
        offsets = np.unique(np.round([0.0] + [k * j * o for o in shafts for j in (1, 2, 3) for k in (-1, 1)], 12))
        combs.append((m, offsets, int(np.flatnonzero(offsets == 0.0)[0]), np.diff(offsets), SPAN * max(shafts)))
    # carrier(lines, q, span) == q, asked of each line q on a mesh harmonic, holds unless a line within
    # span would be chosen over q (the first of the strongest): a stronger line, or an as strong one
    # before q. So it holds when span < the distance to the nearest such line (inf: none)
    dist = np.abs(lines.at[:, None] - lines.at[None, : x.size])  # [j, q] = |at[j] - at[q]| as carrier has it
    a, b = lines.amp[:, None], lines.amp[None, : x.size]
    before = np.arange(lines.at.size)[:, None] < np.arange(x.size)[None, :]
    beats = (a > b) | ((a == b) & before)
    rival = np.where(beats, dist, np.inf).min(axis=0, initial=np.inf)

    def explain(f: np.ndarray, slack: np.ndarray, mesh_only: bool = False) -> tuple:
        """At each input speed f[k] (one row k a hypothesis, all at once: the same sums and comparisons
        as one at a time): (the evidence of each line, whether it lies on a mesh harmonic, that
        harmonic's order h M, the stages with a carrier on a mesh harmonic). A line is explained by
        a mesh harmonic h M (h up to MAX_HARMONIC: a simulated mesh can hold its power at harmonics
        4-11 with no line at M), by a sideband h M ± j o (j ≤ 3, either shaft of the stage) or by a
        harmonic of a shaft; its evidence is log(1 / c), c the share of the axis around it that
        the explaining comb covers (2 slack / spacing, the sidebands' windows counted once): a
        comb dense enough to hold any line is no evidence, and a speed f / k, which explains
        every line f does with k times the coverage, has less. *mesh_only*: (whether on a mesh
        harmonic, its order) alone, the same ones (the refit reads nothing else). *slack*: per
        line, or per hypothesis and line."""
        f = f[:, None]
        slack = np.broadcast_to(slack, (f.shape[0], x.size))
        evidence = np.zeros(slack.shape)
        on_mesh, hm = np.zeros(slack.shape, bool), np.zeros(slack.shape)
        stages = np.zeros(f.shape[0], int)

        def credit(near: np.ndarray, cover: np.ndarray) -> None:
            np.maximum(evidence, np.where(near, np.log(1.0 / np.maximum(cover, 1e-12)), 0.0), out=evidence)

        per_f = x / f
        for m, offsets, zero, diffs, span in combs:
            inside = x <= (MAX_HARMONIC + 0.5) * m * f  # beyond, no harmonic of this mesh is read
            # every offset (axis 1) at once: the nearest harmonic h M + off of each line (axis 2)
            offs = offsets[zero : zero + 1] if mesh_only else offsets
            h = np.maximum(1.0, np.round((per_f[:, None, :] - offs[:, None]) / m))
            near = (np.abs(x - (h * m + offs[:, None]) * f[:, :, None]) <= slack[:, None, :]) & inside[:, None, :]
            row = 0 if mesh_only else zero
            on = near[:, row]  # the mesh harmonics themselves (offset 0)
            hm = np.where(on & ~on_mesh, h[:, row] * m, hm)
            on_mesh |= on
            if mesh_only:
                continue
            credit(on, 2 * slack / (m * f))
            stages += np.any(on & (span * f < rival), axis=1)
            gaps = diffs * f
            sidebands = np.minimum(gaps[:, None, :], 2 * slack[:, :, None]).sum(axis=2)
            credit(near.any(axis=1), (2 * slack + sidebands) / (m * f))
        if mesh_only:
            return on_mesh, hm
        for o in table.shaft_orders:
            spacing = float(o) * f
            near = np.abs(x - np.maximum(1.0, np.round(x / spacing)) * spacing) <= slack
            credit(near, 2 * slack / spacing)
        return evidence, on_mesh, hm, stages

    tried = []  # (line, stage, harmonic, speed) of each hypothesis
    for i in range(min(12, x.size)):
        for s in table.stages:
            for h in range(1, MAX_HARMONIC + 1):
                f = x[i] / (h * float(s.mesh))
                if f * slowest < 2 * df:  # a shaft line the record cannot resolve: higher h only lower f
                    break
                tried.append((i, s, h, f))
    hypotheses = []
    if tried:
        # the hypothesis's own error grows with the harmonic: explained within it, refitted by least
        # squares over the mesh harmonics (f = Σ w L hM / Σ w (hM)²), explained again
        at = np.array([i for i, _, _, _ in tried])
        speeds = [f for _, _, _, f in tried]
        on_mesh, hm = explain(np.array(speeds), tol + tol[at][:, None] * x / x[at][:, None], mesh_only=True)
        upper, lower = hit_sums(on_mesh, weight * x * hm, weight * hm**2)
        for k in np.flatnonzero(on_mesh.any(axis=1)).tolist():
            speeds[k] = float(upper[k] / lower[k])
        evidence, _, _, stages = explain(np.array(speeds), tol)
        # every hypothesis's evidence at once (a row's sum is numpy's sum of that 1-D row), each line's frequency
        # in words once, not some 1,000 sums and formattings a record one at a time (a call 22 -> 20 ms of CPU)
        held, heard = np.sum(weight * evidence, axis=1).tolist(), [fmt_hz(v) for v in x[: min(12, x.size)]]
        for k, (i, s, h, _) in enumerate(tried):
            if not stages[k]:
                continue  # a hypothesis must put a mesh harmonic on a carrier (not on sidebands only)
            # (evidence, speed, words, the stage, its mesh fundamental in Hz, the stages with a carrier on a mesh)
            said = f"{heard[i]} as {h}×M{s.index}"
            hypotheses.append((held[k], speeds[k], said, s.index, x[i] / h, int(stages[k])))

    if declared is not None:
        # the declared speed, refined by the best hypothesis near it, unless the lines fit another speed
        # much better: a few weak lines always fit within ±1 % as some harmonic, and a wrong tooth count
        # is then read at the declared speed (inspect: "mesh order 23 measured, 24 expected")
        # every stage's mesh at once: a speed whose lines another speed explains on more stages, with as much
        # evidence, is no reading (a 17/53 + 22/67 + 29/83 box described with 18 teeth at a declared 35 Hz:
        # 2x M1, 1.19 kHz, read as 11x M3 at 33.45 Hz, its sidebands spuriously 17.9 teeth; at 33.06 Hz every
        # stage's mesh is on a line, as the 18-tooth description puts it for a 17-tooth pinion at 35 Hz)
        kept = not_outdone(hypotheses)
        near = [h for h in kept if abs(h[1] / declared - 1) <= DECLARED_RANGE]
        slipped = [h for h in kept if DECLARED_RANGE < abs(h[1] / declared - 1) <= NOMINAL_RANGE]
        # the input pinion's sidebands, whichever stage's mesh gave the speed: a later stage's mesh and
        # pinion shaft both scale with the input's speed times stage 1's described ratio, and agree at a
        # speed a wrong input pinion's count makes (19/58 + 25/67 described 18/58: 36.95 Hz, not 35)
        # the best few speeds (each looks at every carrier), one hypothesis a speed: a later stage's harmonics
        # all read one speed where its count is off (68/103 + 82/99 described 68/104 at +1.6 %: four at 12.31
        # Hz hid stage 1's, 12.19 Hz, which its pinion's sidebands confirm)
        distinct: list = []
        for h in sorted(slipped, key=lambda h: -h[0]):
            if len(distinct) < 4 and all(abs(h[1] / d[1] - 1) > SPEED_AGREE for d in distinct):
                distinct.append(h)
        confirmed = [h for h in distinct if sidebands_confirm(lines, h[1], table.stages[0], df)]
        near += confirmed
        overall = max(hypotheses, key=lambda h: h[0]) if hypotheses else None
        if not near:
            return (
                declared,
                "declared",
                f"no line within ±{DECLARED_RANGE:.0%} of a mesh frequency at this speed"
                + (
                    f" (the lines fit {fmt_hz(overall[1])} ({overall[2]})"
                    f"{teeth_said(overall, declared, box, lines, table, df)})"
                    if overall
                    else ""
                ),
            )
        best = max(near, key=lambda h: h[0])
        swapped = False
        if (
            best not in confirmed
            and len(table.stages) > 1
            and not sidebands_confirm(lines, best[1], table.stages[0], df)
        ):
            # within ±1 % too: a later stage whose described count is off by one reads a speed 0.9 % away
            # (111/157 + 115/173 at +1.2 %, described with a 116-tooth second pinion: stage 2's lines read
            # 40.13 Hz, which leaves stage 1's mesh unexplained; the input pinion's sidebands confirm 40.48)
            sure = [h for h in confirmed if h is not best] or [
                h
                for h in sorted(near, key=lambda h: -h[0])[:4]
                if abs(h[1] / best[1] - 1) > SPEED_AGREE and sidebands_confirm(lines, h[1], table.stages[0], df)
            ]
            if sure:
                best, swapped = max(sure, key=lambda h: h[0]), overall not in sure
        # a speed the input pinion's sidebands confirm outweighs a better fit they do not, beyond ±1 %
        unconfirmed = overall not in confirmed and abs(overall[1] / declared - 1) > DECLARED_RANGE
        if best[0] < AMBIGUOUS * overall[0] and not (best in confirmed and unconfirmed) and not swapped:
            return (
                declared,
                "declared",
                f"the mesh lines fit {fmt_hz(overall[1])} ({overall[2]}) better than the declared speed"
                f"{at_declared(overall, declared, box, ' (')}: the speed or a tooth count differs",
            )
        return best[1], f"from the mesh lines ({best[2]}), declared {fmt_hz(declared)}", None
    if not hypotheses:
        raise GearlabInputError(
            f"{where}: no tacho, and no line of the spectrum fits a mesh order of {box.source} at any "
            "speed; expected a tacho channel or a declared speed (e.g. '25 Hz')"
        )
    best = max(hypotheses, key=lambda h: h[0])

    def rivals(best: tuple) -> list:
        """The hypotheses at another speed, no multiple of *best*'s (that is its family), explaining about as much."""
        ratio = [max(best[1] / h[1], h[1] / best[1]) for h in hypotheses]
        return [
            h for h, r in zip(hypotheses, ratio) if h[0] >= AMBIGUOUS * best[0] and abs(r - round(r)) > SPEED_AGREE * r
        ]

    if contested := rivals(best):
        # of such speeds, the one alone whose input pinion's sidebands show the described count to a tenth of a bin of
        # their spacing (EXACT_BINS; their spacing is the input's turn whatever stage gave the speed): a later gear a
        # tooth off reads its stages at another speed than the first mesh's (a 14/34 + 17/42 + 26/97 box described
        # with an 18-tooth second pinion: 21.11 Hz from stage 2's 2nd harmonic, its stage-1 'sidebands' 13.83 teeth,
        # against 22.35 Hz from stage 1's mesh, 14.0005, was refused as ambiguous)
        stage, z = table.stages[0], table.stages[0].pinion_teeth

        def exact(h: tuple) -> bool:
            seen = sideband_teeth(lines, h[1], stage, df)
            return seen is not None and abs(seen - z) <= z * EXACT_BINS * df / h[1]

        sure = [h for h in [best, *contested] if exact(h)]
        top = max(sure, key=lambda h: h[0]) if sure else None
        if top is not None and not any(exact(h) for h in rivals(top)):
            return top[1], f"from the mesh lines ({top[2]}; the input pinion's sidebands confirm it)", None
        # two stages' meshes reading two speeds: a tooth count between them may be wrong (a 19/71 +
        # 28/47 reducer described with a 70-tooth wheel was told only to declare its speed)
        other = contested[0]
        stages = best[3] != other[3]
        head = (
            f"{where}: the speed is ambiguous without a tacho: {fmt_hz(best[1])} ({best[2]}) or "
            f"{fmt_hz(other[1])} ({other[2]}) explain the spectrum about equally; expected a declared "
            "speed (e.g. '25 Hz') or a tacho channel"
        )
        raise AmbiguousSpeed(
            head
            + (
                f" (or the description's tooth counts of stages {min(best[3], other[3])} to "
                f"{max(best[3], other[3])} differ from the gearbox's: gearlab inspect at the speed names them)"
                if stages
                else ""
            ),
            [h[1] for h in sorted(hypotheses, key=lambda h: -h[0])],
            head,
        )
    return best[1], f"from the mesh lines ({best[2]})", None


SIDEBANDS_SHOW = "its sidebands show"
EXACT_BINS = 0.1  # a refined line lies within a small share of a bin of its frequency (sidebands 30-45 dB up)
SIDEBAND_WINDOW = 0.15  # a pinion shaft's sideband is looked for within ±15 % of its spacing at the speed tried
TEETH_AGREE = 0.3  # the sidebands confirm a speed where they put the pinion's teeth within ±0.3 of its count


def not_outdone(hypotheses: list) -> list:
    """The speed hypotheses (evidence, ..., stages on a mesh) that no other explains on more stages
    (h[5]) with as much evidence (h[0]): each against the most evidence of those on more stages, once
    per stage count, not against every other (~700,000 pairs where a record's lines make ~840
    hypotheses: 0.1 s a read). The same as the pairwise rule, NaN evidence included (it outdoes none)."""
    most = {}
    for n in {h[5] for h in hypotheses}:
        most[n] = max((g[0] for g in hypotheses if g[5] > n and g[0] == g[0]), default=None)
    return [h for h in hypotheses if most[h[5]] is None or not most[h[5]] >= h[0]]


def sidebands_confirm(lines: Lines, f: float, stage, df: float) -> bool:
    """Whether the sidebands of *stage*'s mesh at input speed *f* put its pinion's teeth within
    TEETH_AGREE of the described count (sideband_teeth)."""
    seen = sideband_teeth(lines, f, stage, df)
    return seen is not None and abs(seen - stage.pinion_teeth) <= TEETH_AGREE


def sideband_teeth(lines: Lines, f: float, stage, df: float) -> float | None:
    """The teeth of *stage*'s pinion (gearbox.orders.StageOrders) that its sidebands show at the input
    speed *f* (Hz), or None (no sideband): around each mesh harmonic h M f on a line (the carrier, at
    c Hz), the strongest line within ±SIDEBAND_WINDOW of c ± the pinion shaft's frequency is its
    sideband, d Hz from c; the pinion's teeth are c / (h d) whatever the speed (their median). A
    34-tooth pinion at 24.6 Hz and a 33-tooth one at 25.36 Hz mesh at the same 836.4 Hz; only the
    sidebands, 24.6 or 25.36 Hz apart, tell them apart."""
    shaft = float(stage.pinion_shaft_order) * f
    mesh = float(stage.mesh) * f
    top = float(lines.at.max(initial=0.0))
    seen = []
    for h in range(1, MAX_HARMONIC + 1):
        if h * mesh + (1 + SIDEBAND_WINDOW) * shaft > top:
            break
        c = lines.near(h * mesh, max(2.5 * df, DRIFT * h * mesh))
        if c is None:
            continue
        carrier = float(lines.at[c])
        if lines.near(carrier, 0.5 * shaft) != c:
            # a stronger line within half the spacing: c is a slower shaft's sideband, no carrier (M1 less the
            # intermediate shaft of a 21/65 + 34/91 box, read at a speed 1.5 % slow, 'confirmed' 21 teeth)
            continue
        for sign in (-1.0, 1.0):
            inside = np.flatnonzero(np.abs(lines.at - (carrier + sign * shaft)) <= SIDEBAND_WINDOW * shaft)
            if inside.size:
                q = inside[np.argmax(lines.amp[inside])]
                seen.append(carrier / (h * abs(float(lines.at[q]) - carrier)))
    return float(np.median(seen)) if seen else None


def by_sidebands(hypothesis: tuple, lines: Lines, table, df: float, box: Gearbox) -> str:
    """A first-stage mesh line that fits another speed than the declared one, whose sidebands put the
    pinion at a whole count of teeth other than the described: ': its sidebands show a 33-tooth pinion
    (at 25.35 Hz)? described 34' (a 33-tooth pinion at 25.35 Hz meshes where a 34-tooth one at 24.6 Hz
    does: a slip of the described speed's motor, unless the sidebands say otherwise); else ''."""
    if hypothesis[3] != 1:
        return ""
    seen = sideband_teeth(lines, hypothesis[1], table.stages[0], df)
    said = box.stages[0].pinion.z
    if seen is None or abs(seen - round(seen)) > TEETH_AGREE or round(seen) in (said, 0):
        return ""
    z = round(seen)
    return (
        f": {SIDEBANDS_SHOW} a {z}-tooth pinion on the {box.shafts[0]} shaft (at {fmt_hz(hypothesis[4] / z)})? "
        f"described {said}"
    )


def teeth_said(hypothesis: tuple, declared: float, box: Gearbox, lines: Lines, table, df: float) -> str:
    """The pinion's tooth count a first-stage mesh line off the declared speed suggests: at_declared's
    (its order at the declared speed) unless the sidebands show another count (by_sidebands): the declared
    speed is nominal (a 33-tooth pinion at 1455 rpm, described 34 at 1500 rpm, was told 'a 32-tooth
    pinion' by its order at 1500 rpm; its sidebands show 33)."""
    at = at_declared(hypothesis, declared, box)
    seen = by_sidebands(hypothesis, lines, table, df, box)
    teeth = [re.search(r"a (\d+)-tooth pinion", t) for t in (at, seen)]
    if seen and (not at or teeth[0].group(1) != teeth[1].group(1)):
        return seen
    return at


def nominal_line(measured: float, nominal: float, said: str, per_revolution=()) -> str:
    """The measured speed against a description's (or a --speed's) nominal one, *said* where it was
    given: information, never a mismatch (a tooth count, a tacho's shaft or its marks are what differ).
    *per_revolution* (Hz, each revolution's): a take whose speed, each the mean over 5 turns (as
    signals.checks.speed_varies reads a run's), spans over SPEED_VARIES of its mean is a run-up, coast-down or drift
    (speed_shape), whose mean is no operating point (a take starting with 1 s of run-up, then steady at the nominal
    23.7 Hz, read 1.6 % slow: 'slip under load'); one revolution's jitter (a speed followed on a mesh line) is none."""
    d = measured / nominal - 1.0
    s = np.asarray(per_revolution, dtype=float)
    s = np.convolve(s, np.full(5, 0.2), "valid") if s.size >= 5 else np.full(1, measured)
    low, high = float(s.min()), float(s.max())
    if high - low > SPEED_VARIES * measured:
        stop = stopped(1.0 / np.asarray(per_revolution, dtype=float))  # the turns' seconds, from the first mark
        span = f"{fmt_hz(low)} .. {fmt_hz(high)}{stop and '; ' + stop}"
        how = f"the mean of {speed_shape(s, bool(stop))} ({span}), not a steady speed"
    elif abs(d) <= 0.002:
        how = "as described"
    elif -NOMINAL_RANGE <= d < 0:
        how = "slip under load"
    elif 0 < d <= NOMINAL_RANGE:
        how = "a light load or the drive's setting"
    else:
        how = "another operating point than the description's: a run simulates the measured speed"
    shown = f"{100 * d:+.0f}" if abs(d) >= 0.1 else f"{100 * d:+.2g}"
    rpm = f"speed {measured * 60:.0f} rpm ({fmt_hz(measured)}) measured, {nominal * 60:.0f} rpm nominal ({said})"
    return f"{rpm}: {shown} %, {how}"


def at_declared(hypothesis: tuple, declared: float, box: Gearbox, lead: str = ": ") -> str:
    """What a first-stage mesh line that fits another speed means at the *declared* one: its order
    there, the pinion's tooth count when that order is the one whole number within the declared
    speed's ±1 % (an 18-tooth pinion described for a 19-tooth one, read at a declared 35 Hz: 'no line
    within ±1 %' and the pinion unsaid, its smeared mesh line among 'lines the description does not
    explain'); '' for a later stage's line (its order also holds the wheels' counts)."""
    if hypothesis[3] != 1:
        return ""
    order = hypothesis[4] / declared
    z = round(order)
    said = box.stages[0].pinion.z
    if z == said or abs(order - z) > DECLARED_RANGE * order or DECLARED_RANGE * order >= 0.5:
        return ""
    close = ")" if lead == " (" else ""
    return (
        f"{lead}at {fmt_hz(declared)}, {fmt_hz(hypothesis[4])} is mesh order {order:.4g}: a {z}-tooth pinion on the "
        f"{box.shafts[0]} shaft? described {said}{close}"
    )


TRACK_SHARE = 0.01  # the harmonic followed holds at least this share of the strongest first-stage harmonic's power
TRACK_CUTOFF = 0.45  # the angle's deviation is kept below this share (to 1.5 x) of the slowest shaft's frequency


def follow_speed(
    signal: np.ndarray,
    fs: float,
    box: Gearbox,
    declared: float | None,
    where: str,
    threshold_db: float = THRESHOLD_DB,
    file: str | None = None,
) -> tuple[np.ndarray | None, float, str, str | None]:
    """(input angle per sample or None, mean input speed in Hz, how it was found, a note or None)
    of a record without a tacho: the speed from the mesh lines (speed_from_mesh), followed through
    the record on the phase of a first-stage mesh harmonic (mesh_angle), and found again on the
    record read at that uniform angle, where a swinging speed no longer smears the lines (a 0.3 %
    swing at 15 Hz made the sidebands of a 40-tooth mesh fit a third of the declared speed). Kept
    when the two agree within SPEED_AGREE and, with a declared speed, the lines confirm it (else
    None: the constant speed of the first look, as before). *file*: a record read against a run's
    description (not inspect's own), whose ambiguity says the tooth counts may differ and how to see."""
    if declared is None and getattr(box, "speed_hz", None):
        # the description's [operation] speed is the prior, as in inspect: the speed the lines show near it
        # (a 68/103 + 82/99 box at +1.6 %, described 68/104: 12.31 Hz from stage 2's lines, or refused as
        # 1.94 Hz (15xM1) or 12.19 Hz; inspect read 12.19 Hz, its pinion's sidebands confirm it); none
        # there (the lines do not confirm it): found from the mesh lines alone, as without one
        got = _follow_speed(signal, fs, box, box.speed_hz, where, threshold_db)
        # on a take whose speed moves, a reading near the prior whose phase is not followed is none (98/113 + 112/135
        # stepping 17.5 -> 18.03 Hz: stage 2's mesh at 17.92 Hz on a sideband of stage 1's, 0.9 % high)
        if got[2] != "declared" and (got[0] is not None or not passes(signal, fs)):
            return got
    elif declared is not None and ((ramp := speed_shift(signal, fs) is not None) or passes(signal, fs)):
        # a take whose spectra show its speed move (a run-up or coast-down; a step or swing wider than a declared
        # speed's trust): the declared speed is the nominal one it passes, not its mean, which the lines do not
        # confirm (14 -> 19 Hz over 12 s declared 16 Hz: its mean 16.5 Hz, unconfirmed without sidebands, was read at
        # a constant 16 Hz, 191 'revolutions' all in band; a 4 % step declared at its first plateau: 1.9 % low).
        # None near it: the speed the mesh lines show along the take's course, kept where its phase is followed (a
        # step's or swing's only where the take passes the declared speed: else the declared speed is wrong)
        got = _follow_speed(signal, fs, box, declared, where, threshold_db, file)
        if got[2] == "declared" or (got[0] is None and not ramp):  # as a prior's unfollowed reading, above
            try:
                found = _follow_speed(signal, fs, box, None, where, threshold_db, file)
            except GearlabInputError:
                return got
            return found if found[0] is not None and (ramp or passes(signal, fs, found[0], declared)) else got
        return got
    return _follow_speed(signal, fs, box, declared, where, threshold_db, file)


def passes(signal: np.ndarray, fs: float, angle: np.ndarray | None = None, declared: float = 0.0) -> bool:
    """Whether a record without a tacho moves its speed over more than DECLARED_RANGE (its speed_course), where a
    declared speed may be one it passes and not its mean; with its input *angle* (rad per sample): whether the
    speeds of its revolutions come within DECLARED_RANGE of the *declared* speed (Hz)."""
    course = speed_course(signal, fs)
    if course is None or float(np.ptp(course)) <= DECLARED_RANGE:
        return False
    if angle is None:
        return True
    starts = np.flatnonzero(np.diff(np.floor((angle - angle[0]) / (2 * np.pi))))
    if starts.size < 2:
        return False
    speeds = fs / np.diff(starts)  # per revolution
    low, high = float(np.min(speeds)), float(np.max(speeds))
    return low * (1 - DECLARED_RANGE) <= declared <= high * (1 + DECLARED_RANGE)


def _follow_speed(signal, fs, box, declared, where, threshold_db, file=None) -> tuple:
    """follow_speed at the *declared* speed (or none) as given: no prior tried."""
    fine = upsampled(signal)  # read at uniform angle 8 times denser: no false lines
    # a speed ramp smears every line over its sweep: the first look is at the record read along the speed's
    # course from its own spectra (speed_course), where the lines stand narrow at the mean speed
    first = signal
    if (course := speed_course(signal, fs)) is not None:
        u = np.cumsum(course) - course[0]
        first = np.interp(np.linspace(u[0], u[-1], signal.size), fine.at(u), fine.signal)
    try:
        f, how, note = speed_from_mesh(first, fs, box, declared, where, threshold_db)
    except AmbiguousSpeed as exc:
        # smeared lines can fit several speeds: the one whose mesh phase, followed, leaves lines that
        # fit that speed and no other is the speed (several such: still ambiguous)
        # (a smeared line read as harmonic h of a mesh: the speed can be k times faster, the line its h / k)
        tries: list[float] = []
        for f in (k * g for g in exc.speeds[:AMBIGUOUS_TRIES] for k in (1, 2, 3, 4)):
            if not any(abs(f / g - 1) <= SPEED_AGREE for g in tries):
                tries.append(f)
        found: list[tuple] = []
        for f in tries:
            got = _followed(signal, fine, course, fs, box, declared, where, threshold_db, f, "")
            if got[0] is not None and not any(abs(got[1] / g[1] - 1) <= SPEED_AGREE for g in found):
                found.append(got)
        if len(found) > 1:
            found = gathered(signal, fs, fine, found, box, threshold_db)
        if len(found) != 1:
            if file is None:  # inspect's own record (a 29/73 box described 28/73: 8.4 or 12.6 Hz, the count unsaid)
                tell = f"(or a tooth count differs from {box.name}'s: at its nominal speed, --speed, inspect names it)"
                raise AmbiguousSpeed(f"{exc.head} {tell}", exc.speeds, exc.head) from None
            # a record of another gearbox reads so too: `gearlab score` stopped at 'the speed is ambiguous',
            # the tooth counts unsaid (issue 39)
            raise AmbiguousSpeed(
                f"{exc.head} (or the record's tooth counts differ from {box.name}'s, another gearbox's: "
                f"gearlab inspect {file} --gearbox {box.source.removeprefix('built-in ')} names them)",
                exc.speeds,
            ) from None
        return found[0]
    return _followed(signal, fine, course, fs, box, declared, where, threshold_db, f, how, note)


GATHERED_DB = 6.0  # a followed phase whose strongest line stands this far over every other's is the speed's


def gathered(signal, fs: float, fine: Upsampled, found: list[tuple], box: Gearbox, threshold_db: float) -> list[tuple]:
    """Of speeds of one family whose mesh phase, followed, gave a speed (_followed's), the one whose angle gathers
    the mesh's power (its top line within GATHERED_DB of the highest: a speed k times too slow follows no swing above
    its shafts' rates, its FM sidebands stay) and reads its own speed again (one followed on 2 M reads half); else
    *found*. A 39/110 + 38/101 box at 41.70 Hz swinging at ~1 Hz: 41.70 (71.7 dB) or 8.340 Hz (54.7 dB) (issue 39)."""
    # one family: every speed a whole multiple of the slowest (17.67, 35.34 and 53.01 Hz are; the fastest over each,
    # 53.01 / 35.34 = 1.5, is not)
    slowest = min(g[1] for g in found)
    if any(abs(g[1] / slowest - round(g[1] / slowest)) > SPEED_AGREE * g[1] / slowest for g in found):
        return found  # two families: another tooth count, not a swing, can read so
    heights, evens = [], []
    for g in found:
        evens.append(np.interp(np.linspace(g[0][0], g[0][-1], signal.size), fine.at(g[0]), fine.signal))
        freq, amp = spectrum(evens[-1], fs)
        lines = find_lines(freq, amp, threshold_db, 2 * freq[1], 0.45 * fs)
        heights.append(float(lines.db[0]) if lines.at.size else -np.inf)
    kept = [k for k, h in enumerate(heights) if h > max(heights) - GATHERED_DB]
    if len(kept) > 1:
        own, read = [], []
        for k in kept:
            try:
                f = speed_from_mesh(evens[k], fs, box, None, "", threshold_db)[0]
            except GearlabInputError:
                continue
            read.append(f)
            if abs(f / found[k][1] - 1) <= SPEED_AGREE:
                own.append(k)
        if read and not own:
            # every angle kept reads one speed of the family, itself followed less cleanly: that speed (98/113 +
            # 112/135 at 17.67 Hz: its angles followed at 35.34 and 53.01 Hz, 6.3 dB over its own, both read 17.67)
            own = [j for j, g in enumerate(found) if all(abs(f / g[1] - 1) <= SPEED_AGREE for f in read)]
        kept = own
    return [found[kept[0]]] if len(kept) == 1 else found


def _followed(signal, fine: Upsampled, course, fs, box, declared, where, threshold_db, f, how, note=None) -> tuple:
    """follow_speed from a first speed *f* (its *how*, *note*; *course*: speed_course of *signal*): (angle or
    None, speed, how, note)."""
    n = signal.size
    for _ in range(3):  # a first look at a wrong multiple of the speed is corrected on the second
        theta = mesh_angle(signal, fs, box, f, course)
        if theta is None:
            break
        mean = (theta[-1] - theta[0]) * fs / (2 * np.pi * (n - 1))
        if declared is not None and abs(mean / declared - 1) > NOMINAL_RANGE:
            break  # the phase followed another line than the declared speed's mesh
        even = np.interp(np.linspace(theta[0], theta[-1], n), fine.at(theta), fine.signal)
        try:
            f2, how2, note2 = speed_from_mesh(even, fs, box, declared, where, threshold_db)
        except GearlabInputError:  # ambiguous, or no line fits: the phase followed was no mesh's
            break
        if how2 != "declared" and abs(f2 / mean - 1) <= SPEED_AGREE:
            return theta, mean, how2 + ", followed on a mesh harmonic's phase", note2
        k = round(mean / f2)
        if (
            how2 != "declared"
            and k >= 2
            and abs(mean / (k * f2) - 1) <= SPEED_AGREE
            and abs(f / mean - 1) <= SPEED_AGREE
        ):
            # read along the angle followed, the lines fit a whole fraction of its speed, one harmonic family: its
            # fundamental, the speed followed, is the speed (speed_from_mesh's rule among a family's speeds). A run-up's
            # angle leaves weak sidebands that a comb at half the speed explains too, and the reading swung between
            # the two (a 32-tooth mesh, 8 -> 16 Hz in 1 s then 2 s steady: read at a constant 7.33 Hz, 21 revolutions)
            # -- unless the strongest line, read there, is a mesh harmonic of the fraction and of no mesh at the speed
            # followed: the phase of h M was followed as (h / k) M, in a band k times wider, which followed a swing
            # below the slowest shaft's rate that a band at the speed did not (a 45/119 + 28/123 conveyor at
            # 0.7425 Hz swinging 0.2 % at 0.05 Hz: its mesh at 33.41 Hz, order 22.5 at 1.485 Hz, was cut at 1.485 Hz)
            freq, amp = spectrum(even, fs)
            top = find_lines(freq, amp, threshold_db, 2 * freq[1], 0.45 * fs).at[:1]
            if not top.size or _on_mesh(top[0], mean, box, freq[1]) or not _on_mesh(top[0], f2, box, freq[1]):
                return theta, mean, how + ", followed on a mesh harmonic's phase", note
            return theta / k, mean / k, how2 + ", followed on a mesh harmonic's phase", note2
        if how2 == "declared":
            if note2 and SIDEBANDS_SHOW in note2 and SIDEBANDS_SHOW not in (note or ""):
                note = note2  # at uniform angle a speed's swing no longer splits the sidebands (a 0.1 % swing did)
            break
        f = f2
    return None, f, how, note


def _on_mesh(line: float, f: float, box: Gearbox, df: float) -> bool:
    """Whether a spectral *line* (Hz; *df* the bin) lies on a harmonic of a mesh of *box* at input speed *f*."""
    tol, meshes = max(2.5 * df, DRIFT * line), [float(s.mesh) * f for s in order_table(box).stages]
    return any(abs(line - max(1.0, round(line / m)) * m) <= tol for m in meshes)


def settling(box: Gearbox, f: float) -> float:
    """Seconds at each end of a record where mesh_angle's angle (input speed *f*, Hz) has not settled: half a period
    of its low-pass's cutoff (TRACK_CUTOFF of the slowest shaft's frequency), past the main lobe of its kernel (flat
    to the cutoff, a cosine to 1.5 x: first zero at 0.4 / cutoff), which near an end reads the phase mirrored there,
    not the take's. A 31/97 box at 8 Hz (10 takes): 26-56e-5 turns rms in the first and last 0.375 s, 8-23e-5 to
    1 s, 1-5e-5 beyond. Localisation reads a take's revolutions clear of them (signals.settled, CutRecording.settled):
    the error there, shared by every order of the take, put healthy takes over their thresholds; a whole period cut
    (0.87 s there) called the same 6 of 360 healthy takes, its faults' z 10-15 % lower (six 3-take histories,
    development seeds). A detection run's units keep every revolution: a 20/30 + 20/50 box's chip, its four or five
    record10 units a take, read AUC 0.75-0.94 cut, 0.96 whole (one set of takes; 1.00 both on another)."""
    return 0.5 / (TRACK_CUTOFF * float(min(order_table(box).shaft_orders)) * f)


RECENTRE = 0.002  # a followed mean this far off the band's centre is followed again about itself (mesh_angle)
RECENTRE_TRIES = 2


def mesh_angle(
    signal: np.ndarray, fs: float, box: Gearbox, f: float, course: np.ndarray | None, recentred: int = 0
) -> np.ndarray | None:
    """The input-shaft angle per sample (rad) of a record without a tacho, tracked on the phase of
    the strongest harmonic h M of the first stage's mesh (tacho-less order tracking; M of the first
    stage is its pinion's count, which a declared speed checks), or None when no harmonic stands
    clear of its neighbours. A motor's speed swinging by 0.3 % moves harmonic 3 of a 40-tooth mesh
    by 0.36 orders: read at a constant speed, every line of it smears over the sidebands that tell
    the shafts apart (a 25-tooth pinion read as 32). The harmonic's analytic signal is taken in a
    band half-way to the nearest other mesh harmonic (of any stage), wide enough for the swing, and
    its phase low-passed below TRACK_CUTOFF of the slowest shaft's frequency: a shaft's sidebands
    (its amplitude and phase modulation) leave the angle alone, a slower speed change is followed.
    *course*: the record's speed_course (None: steady), found once by the caller (0.5 s on 10 s at 25.6 kHz);
    *recentred*: how often it was followed again about its own mean (RECENTRE)."""
    table = order_table(box)
    n = signal.size
    spec = np.fft.fft(signal)
    freq = np.fft.fftfreq(n, 1 / fs)
    cutoff = TRACK_CUTOFF * float(min(table.shaft_orders)) * f
    every = np.array([h * float(s.mesh) * f for s in table.stages for h in range(1, MAX_HARMONIC + 1)])
    best, strongest = None, None
    for h in range(1, MAX_HARMONIC + 1):
        c = h * float(table.stages[0].mesh) * f
        if c + 2 * cutoff >= fs / 2:
            break
        # the bins within the cutoff of c, found among the few about it (c > cutoff: positive frequencies alone), not
        # over the whole record for each of up to MAX_HARMONIC harmonics: the same bins in the same order, the same sum
        near = slice(max(math.floor((c - cutoff) * n / fs) - 2, 0), min(math.ceil((c + cutoff) * n / fs) + 3, n))
        power = float(np.sum(np.abs(spec[near][np.abs(freq[near] - c) <= cutoff]) ** 2))
        order = h * float(table.stages[0].mesh)
        if strongest is None or power > strongest[0]:
            strongest = (power, c, 2 * cutoff, order)
        others = np.abs(every - c)
        half = 0.5 * float(others[others > 1e-9 * c].min(initial=c))
        if c + half >= fs / 2 or half < 2 * cutoff:
            continue
        if best is None or power > best[0]:
            best = (power, c, half, order)
    if best is None:
        return None
    # a harmonic far weaker than the mesh's strongest is the record's noise: followed, it wobbles the angle
    # (a description's third stage 0.07 orders off put its 4th harmonic beside M1 and the next 4: the 8th,
    # 10^-5 of M1's power, was followed and split every line in three); the strongest is followed then, in
    # the narrowest band the swing allows
    if best[0] < TRACK_SHARE * strongest[0]:
        best = strongest
    _, c, half, order = best
    t = np.arange(n) / fs
    # a speed ramp moves the line further than the band (2 % at 1.9 kHz is 38 Hz; a band of ±2.6 Hz followed a
    # sixth of it): the record's own spectra over time give the speed's course (speed_course), and the line is
    # followed on the record with that course taken out, which leaves it narrow at c. So too where the band holds
    # the sweep but the low-pass does not: a line swept further than the cutoff leaves a parabola in the phase, whose
    # mirrored kinks ring through the low-pass (a 20 -> 14 Hz coast-down over 3 s, 32 teeth: 190 Hz in a ±272 Hz
    # band, the angle 0.6 rad off at the start, ±2.6 Hz sidebands read at half the speed). That only where the
    # course spans a run-up or coast-down (SHIFT_MIN, as speed_shift reads one from the record's ends): the quadratic
    # course of a smaller swing, a step between two plateaus, is not its shape, and taken out inside the band it moved
    # the line (a 0.6 % step at 49 Hz, a 15-tooth pinion read 14.99)
    chirp = np.zeros(n)
    spread = 0.0 if course is None else float(np.ptp(course))
    if c * spread > half or (c * spread > cutoff and spread > SHIFT_MIN):
        chirp = 2 * np.pi * c * np.cumsum(course - 1.0) / fs
        spec = np.fft.fft(np.fft.ifft(np.where(freq > 0, 2 * spec, 0)) * np.exp(-1j * chirp))
    analytic = np.fft.ifft(np.where(np.abs(freq - c) <= half, 2 * spec, 0))
    phase = np.unwrap(np.angle(analytic * np.exp(-2j * np.pi * c * t)))  # slow: the deviation from c (and chirp)
    line = np.polyval(np.polyfit(t, phase, 1), t)
    wiggle = np.concatenate([phase - line, (phase - line)[::-1]])  # mirrored: no jump where the FFT wraps
    # flat to the cutoff, a cosine down to 1.5 times it (a sharp edge rings: lines at ± the cutoff)
    edge = np.clip((np.abs(np.fft.fftfreq(wiggle.size, 1 / fs)) - cutoff) / (0.5 * cutoff), 0.0, 1.0)
    smooth = np.fft.ifft(np.fft.fft(wiggle) * 0.5 * (1 + np.cos(np.pi * edge))).real[:n]
    # the course's phase is added after the smoothing: a mirrored parabola's kinks would ring through the low-pass
    theta = (2 * np.pi * c * t + line + smooth + chirp) / order
    # the band is centred on f: where the take's mean lies off it (a declared speed 2 % under it), the far side of a
    # step leaves the band and cycles slip (a 4 % step at 50 Hz, 100/116 + 108/114: 48.2 Hz read for 0.1 s on the
    # way 50 -> 52, the mean 50.75 Hz for 50.97, a wheel's count read 114.6 for 114): followed again about the mean
    mean = (theta[-1] - theta[0]) * fs / (2 * np.pi * (n - 1))
    if recentred < RECENTRE_TRIES and abs(mean / f - 1) > RECENTRE:
        return mesh_angle(signal, fs, box, mean, course, recentred + 1)
    return theta


def varies_words(angle: np.ndarray, rec) -> str:
    """What signals.checks.speed_varies says of a record *rec* (data.recordings.Recording) read at the shaft *angle*;
    where that is nothing and *rec* has no tacho, "; its spectrum's lines move +36 % from its first sixteenth to its
    last (a run-up or coast-down?): read whole ..." where its spectra show its speed vary (speed_shift, as inspect
    says a run-up); else "". A detection run and `gearlab score` cut a run-up to its revolutions at the history's
    speed where its angle gives each revolution's speed (a tacho's, or the mesh phase followed); a declared or
    constant found speed gives none: such a take was scored whole, unsaid."""
    said = speed_varies(angle, rec.fs)
    if said or rec.tacho is not None:
        return said
    shift = speed_shift(np.asarray(rec.signal, dtype=float), rec.fs)
    if shift is None:
        return ""
    return (
        f"; its spectrum's lines move {100 * (shift - 1):+.0f} % from its first sixteenth to its last (a run-up or "
        f"coast-down?): {UNSEEN_WORDS}"
    )
