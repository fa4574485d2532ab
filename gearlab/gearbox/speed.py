"""The input-shaft speed of a record without a tacho, from a gearbox description's mesh lines
(docs/gearbox.md): the spectral lines of the record, each tried as a mesh harmonic of each stage.
Used by the importer (gearlab.data.recordings) and by `gearlab inspect`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ..errors import GearlabInputError
from ..signals import spectrum
from ..signals.checks import fmt_hz
from .description import Gearbox
from .orders import order_table

THRESHOLD_DB = 15.0  # a line stands this far over the running median of the spectrum
FLOOR_BINS = 201  # width of the running median (bins)
PEAK_BINS = 7  # a line is the largest value within ±3 bins (Hann sidelobes are not lines)
DECLARED_RANGE = 0.01  # a declared speed is trusted to ±1 %
AMBIGUOUS = 0.9  # a second speed hypothesis explaining ≥ 90 % of the best one's power is ambiguous
SPEED_AGREE = 0.005  # two hypotheses within 0.5 % are the same speed
DRIFT = 1e-3  # relative smear of an order by speed drift


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


def speed_from_mesh(
    signal: np.ndarray, fs: float, box: Gearbox, declared: float | None, where: str, threshold_db: float = THRESHOLD_DB
) -> tuple[float, str, str | None]:
    """(input speed in Hz, how it was found, a note or None) of a record without a tacho, from the
    description's mesh lines: each strong line tried as a mesh harmonic (1-3) of each stage; a
    hypothesis must put a mesh fundamental on a carrier, and is scored by the lines it explains. A
    *declared* speed limits the search to ±1 % (and is kept, with a note, when no line fits); with
    none, two hypotheses at different speeds that explain nearly as much are refused as ambiguous.
    *where*: the file and channel, for the messages."""
    n = signal.size
    table = order_table(box)
    freq, amp = spectrum(signal, fs)
    lines = find_lines(freq, amp, threshold_db, 2 * freq[1], 0.45 * fs)
    if lines.at.size == 0:
        if declared is not None:
            return declared, "declared", "no spectral line to check the declared speed against"
        raise GearlabInputError(f"{where}: shows no spectral line; cannot find the speed")
    df = fs / n
    explained_orders = np.array([o for _, o in table.lines()])
    mesh_orders = np.array([h * float(t.mesh) for t in table.stages for h in (1, 2, 3)])
    weight = np.minimum(lines.db, 40.0)

    def tol(f):
        return max(2.5 * df, DRIFT * f)

    hypotheses = []
    for i in range(min(12, lines.at.size)):
        for s in table.stages:
            for h in (1, 2, 3):
                f = lines.at[i] / (h * float(s.mesh))
                if declared is not None and abs(f / declared - 1) > DECLARED_RANGE:
                    continue
                meshes, m_orders = [], []
                for t in table.stages:
                    q = lines.near(float(t.mesh) * f, tol(float(t.mesh) * f))
                    span = SPAN * float(max(t.pinion_shaft_order, t.wheel_shaft_order)) * f
                    if q is not None and carrier(lines, q, span) == q:
                        meshes.append(q)  # a mesh fundamental that is its neighbourhood's carrier
                        m_orders.append(float(t.mesh))
                if not meshes:
                    continue
                predicted = explained_orders * f
                hit = np.array([np.min(np.abs(predicted - x)) <= tol(x) for x in lines.at])
                harmonic = mesh_orders * f
                on_mesh = np.array([np.min(np.abs(harmonic - x)) <= tol(x) for x in lines.at])
                # least squares over the mesh fundamentals: f = Σ L M / Σ M²
                at, m_orders = lines.at[meshes], np.array(m_orders)
                refined = float(np.sum(at * m_orders) / np.sum(m_orders**2))
                # a carrier outweighs its sidebands: the mesh harmonics decide, the rest breaks ties
                # lines explained, each by its height over the floor (capped): a speed that explains
                # the sidebands too beats one that only puts a mesh harmonic on the carrier
                score = (len(meshes), float(weight[hit].sum() + weight[on_mesh].sum()))
                hypotheses.append((score, refined, f"{fmt_hz(lines.at[i])} as {h}×M{s.index}"))
    hypotheses.sort(key=lambda h: (-h[0][0], -h[0][1]))
    distinct = []
    for h in hypotheses:
        if all(abs(h[1] / d[1] - 1) > SPEED_AGREE for d in distinct):
            distinct.append(h)
    if not distinct:
        if declared is None:
            raise GearlabInputError(
                f"{where}: no tacho, and no line of the spectrum fits a mesh order of {box.source} at any "
                "speed; expected a tacho channel or a declared speed (e.g. '25 Hz')"
            )
        return declared, "declared", f"no line within ±{DECLARED_RANGE:.0%} of a mesh frequency at the declared speed"
    best = distinct[0]
    if (
        declared is None
        and len(distinct) > 1
        and distinct[1][0][0] == best[0][0]
        and distinct[1][0][1] >= AMBIGUOUS * best[0][1]
    ):
        other = distinct[1]
        raise GearlabInputError(
            f"{where}: the speed is ambiguous without a tacho: {fmt_hz(best[1])} ({best[2]}) or "
            f"{fmt_hz(other[1])} ({other[2]}) explain the spectrum about equally; expected a declared speed "
            "(e.g. '25 Hz') or a tacho channel"
        )
    how = f"from the mesh lines ({best[2]})" + (f", declared {fmt_hz(declared)}" if declared else "")
    return best[1], how, None
