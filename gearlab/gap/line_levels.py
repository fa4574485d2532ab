"""Why no sensor or path effect can be told on a box whose own mesh lines the simulator does not make
(docs/gap.md, "Assumptions and limits").

A sensor's low-pass, a resonance or a casing path shows in the records as the mesh harmonics' levels
changed relative to each other: a 2-pole low-pass at 3 kHz lowers the 8 harmonics of a 675 Hz mesh by 0-11 dB,
3.8 dB RMS around their mean. On a box that gearlab's simulator does not make (a 27/61 + 22/53 box whose
lines a plain numpy generator drew), the plain box's harmonics already differ from the simulator's by 7.7 dB
RMS harmonic to harmonic, up and down with no smooth shape: a candidate is then fitted against that mismatch
as much as against the effect. The plain box's best stand-in, a resonance at 4.6 kHz, removed 48-50 % of its
gap; behind the low-pass (3 kHz, 2 poles), the low-pass came back at 4.5 kHz with 5-8 poles on two of three
development sets and removed 2 % beyond the noise alone on fresh revolutions: no rule on the shares tells the
effect from the box, and none is named. The verdict says so with the numbers: the records' lines against the
plain simulator's, and beside the fit that matches them best (:func:`line_mismatch`)."""

from __future__ import annotations

import numpy as np

from ..errors import GearlabInputError
from .level import _lines
from .scoring import NUISANCE

# A harmonic counts where its line stands this many times over the noise of its synchronous average (the
# variance of the mean), in both sets: a line the box lacks (the simulator's harmonics 9-13 of the 27-tooth
# mesh, past the box's own 8) is a structure question, not a level, and its noise-level reading swamped the RMS
# (21.5 dB where the 8 lines both sets hold differ by 7.7).
LINE_OVER_NOISE = 10.0
ROUNDING = 1e-12  # a noise-free set's line under this share of its strongest is rounding, not a line
MIN_HARMONICS = 3  # fewer harmonics tell no shape across them
# The harmonic-to-harmonic mismatch left beside the fit that matches the lines best is said from this many dB
# RMS: a 2-pole low-pass at 3 kHz moves the 8 harmonics of a 675 Hz mesh by 3.8 dB RMS, so a box whose own
# lines stray more than that leaves such a filter untold. The simulator's own box behind a filter, the filter
# fitted, leaves under 0.1 dB (tests/test_gap_line_levels.py).
SAID_DB = 3.0


def relative_levels(target: np.ndarray, *sources: np.ndarray, z1: int, max_order: int) -> list[np.ndarray]:
    """The target's mesh harmonics k Z1 (up to *max_order*; 0: every order) over each of the *sources*', in dB
    with their mean taken out (a scale is the level check's: gearlab.gap.structure), at the harmonics every set
    holds (LINE_OVER_NOISE); empty arrays where fewer than MIN_HARMONICS are held by all."""
    t, held = _held(target)
    top = min(len(t), max_order or len(t))
    orders = np.arange(z1, top + 1, z1) - 1
    powers = [_held(X) for X in sources]
    here = held[orders] & np.logical_and.reduce([h[orders] for _, h in powers])
    if here.sum() < MIN_HARMONICS:
        return [np.empty(0) for _ in sources]
    out = []
    for s, _ in powers:
        d = 10.0 * np.log10(t[orders][here] / s[orders][here])
        out.append(d - d.mean())
    return out


def _held(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each order line's power in the rows' synchronous average (level._lines: its noise taken out) and
    whether it stands LINE_OVER_NOISE times over that noise (and, for noise-free rows, over rounding)."""
    F = np.fft.rfft(np.asarray(X, dtype=np.float64), axis=1)[:, 1:]
    noise = F.var(axis=0) / len(F) if len(F) > 1 else np.zeros(F.shape[1])
    lines = _lines(X)
    return lines, (lines > LINE_OVER_NOISE * noise) & (lines > ROUNDING * lines.max(initial=0.0))


def _rms(d: np.ndarray) -> float:
    return float(np.sqrt(np.mean(d**2))) if d.size else 0.0


def line_shaping(result: dict) -> list[dict]:
    """The fits whose lines are compared: each effect the diagnosis fitted, then did not name, at its final fit,
    and round 1's candidates as fitted there; the noise alone shapes no line."""
    fits = [*(result.get("dropped_effects") or []), *(result.get("ranking") or [])]
    return [f for f in fits if f["name"] != NUISANCE and f.get("params")]


def line_mismatch(target: np.ndarray, plain: np.ndarray, fits: dict, z1: int, max_order: int) -> dict | None:
    """The records' mesh lines against the plain source's (``plain_db``, the RMS harmonic to harmonic) and
    against the fit of *fits* ({name: rows}) that matches them best (``left_db``, ``name``); ``harmonics``:
    how many every set holds. None where fewer than MIN_HARMONICS are."""
    names = list(fits)
    before, *after = relative_levels(target, plain, *fits.values(), z1=z1, max_order=max_order)
    if before.size < MIN_HARMONICS:
        return None
    left = [_rms(d) for d in after]
    best = int(np.argmin(left)) if left else None
    return {
        "harmonics": int(before.size),
        "plain_db": _rms(before),
        "left_db": left[best] if best is not None else _rms(before),
        "name": names[best] if best is not None else None,
    }


def told(record: dict | None) -> bool:
    """Whether the mismatch *record* (:func:`line_mismatch`) is said: even the best fit leaves SAID_DB."""
    return bool(record) and record["name"] is not None and record["left_db"] >= SAID_DB


def told_text(record: dict) -> str:
    """The verdict's clause: why no effect can be told on this box."""
    return (
        f"the records' mesh lines differ from the simulator's by {record['plain_db']:.1f} dB RMS harmonic to "
        f"harmonic ({record['harmonics']} harmonics, their mean aside), and by {record['left_db']:.1f} dB beside "
        f"the fit that matches them best, {record['name']}: as much as a sensor's filter moves them (from "
        f"{SAID_DB:g} dB), so no sensor or path effect can be told on these records (records from before the "
        "change, or a description whose lines match, can tell one)"
    )


def mismatch_of(run, result: dict) -> dict | None:
    """conclusion's record for an unexplained measured target (a chain): the line-shaping fits
    (:func:`line_shaping`) against the plain source on the report's rows; None where not measured or none."""
    shaping = line_shaping(result) if result.get("chain") is not None else []
    fits, params = {}, {}
    for fit in shaping:
        label = fit["name"] if fit["name"] not in fits else f"{fit['name']} at round 1's fit"
        if label in fits:
            continue
        try:  # a fit the search scored; the simulator may still refuse it alone
            fits[label] = run.judged((run.spec(fit["name"], fit["params"]),))
        except GearlabInputError:
            continue
        params[label] = fit["params"]
    if not fits:
        return None
    record = line_mismatch(run.target, run.judged(()), fits, run.pair.Z1, run.settings.max_order)
    return None if record is None else {**record, "params": params[record["name"]]}
