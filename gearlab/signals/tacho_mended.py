"""What the edge reading of a pulse tacho mended (signals.angle): a pulse the tacho missed put back, a glitch's
extra pulse left out. Both are mended silently in the angle; a user wants them said (a loose sensor, a dirty
mark), in inspect's speed line, a run's table and `gearlab score`'s, as the logger's other flaws are."""

from __future__ import annotations

import numpy as np

from ..errors import GearlabInputError
from .angle import _glitches, _missed_marks, _rising_edges


def mended_words(pulses: np.ndarray | None, fs: float, marks: int) -> str:
    """'; 1 missed pulse put back (at 1.5 s)' and/or '; 1 glitch pulse left out (at 0.8 s)' of the pulse train
    *pulses* at *fs* with *marks* marks a turn, '' where it needed neither (or is no pulse train: the angle
    reading refuses it in its own words). Where a missing-mark wheel's gap is its turn's reference (a 60-2
    encoder's), its left-out marks are its design, not said."""
    if pulses is None or marks < 1:
        return ""
    try:
        _, edges, quantised = _rising_edges(pulses, fs)
        kept, kept_q = _glitches(edges, quantised)
        filled, _, shift = _missed_marks(kept, kept_q, marks)
    except GearlabInputError:
        return ""
    words = []
    if shift is None and filled.size > kept.size:
        put = np.setdiff1d(filled, kept)
        words.append(f"{put.size} missed pulse(s) put back (at {_times(put, fs)})")
    if kept.size < edges.size:
        extra = np.setdiff1d(edges, kept)
        words.append(f"{extra.size} glitch pulse(s) left out (at {_times(extra, fs)})")
    return "".join(f"; {w}" for w in words)


def _times(samples: np.ndarray, fs: float) -> str:
    shown = ", ".join(f"{s / fs:.3g} s" for s in samples[:3])
    return shown + (f" and {samples.size - 3} more" if samples.size > 3 else "")
