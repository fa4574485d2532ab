"""Whether the envelope's flag is a strike's or the train's: products of shafts' synchronous modulations.

The envelope (signals.envelope_sync) is read on the record less every shaft's synchronous average: each shaft's
orders are taken out, every other line stays. A mesh whose amplitude follows two shafts at once, as an eccentric
pinion's mesh with a gear whose own run-out also modulates it, carries the products of the two shafts' lines: at
orders of neither shaft (the rig's second mesh: 16 ± 1/3 ± j/5 input orders), which only the train's period repeats
(15 input turns: the idler's 5, the output's 3). They stay in the residual, and its squared envelope holds their
differences: the idler's once-a-turn eccentricity beats only at 2/3 of an input order with itself, the output
gear's modulation at each of its harmonics' differences, so the envelope reads the output shaft over its threshold
(the ring's phase never wandered: every shaft's synchronous average reads this change at its own orders, and does
not name it, or names the eccentric shaft where it is over its threshold).

A strike whose ring's phase wanders is not repeated by the train's period either: its residual is spread over
every order. So the record less its train's synchronous average (every order the train repeats) keeps a strike's
envelope and loses the products: the envelope's flag is kept where the shaft is still flagged so; else it is the
train's, and the envelope names no gear. Where the record holds fewer than MIN_PERIODS of the train's periods, the
train's average keeps too much of everything else (a strike's share 1 / periods) to be told apart: the flag stands.
"""

from __future__ import annotations

import numpy as np

from . import envelope_sync as E
from . import localise as L

MIN_PERIODS = L.MIN_PERIODS  # train periods a record must hold for the train's average (as signals.localise reads)
SET_ASIDE = "the envelope's flag set aside: gone from the record less the train's synchronous average"


def less_train(revolutions: np.ndarray, table) -> np.ndarray | None:
    """The record *revolutions* (R, points: consecutive input revolutions) less its train's synchronous average, over
    its whole train periods (table.train_period input turns each); None where it holds fewer than MIN_PERIODS."""
    revs = np.asarray(revolutions, dtype=np.float64)
    period = int(table.train_period)
    count = len(revs) // period
    if count < MIN_PERIODS:
        return None
    whole = revs[: count * period].reshape(count, period, -1)
    return (whole - whole.mean(axis=0)).reshape(count * period, -1)


def of_the_train(revolutions: np.ndarray, seen: L.Localisation, hist: L.History, table, first: int) -> str | None:
    """Why the envelope's flag *seen* (envelope_sync.localise of *revolutions* against the envelope's history *hist*,
    its first revolution *first*) is the train's (module doc), in words; None where it stands."""
    rest = less_train(revolutions, table)
    if rest is None or seen.named_shaft is None:
        return None
    again = E.localise(rest, hist, table, first)
    kept = next(e for e in again.ranking if e.shaft == seen.named_shaft)
    if kept.flagged:
        return None
    was = next(e for e in seen.ranking if e.shaft == seen.named_shaft)
    return (
        f"{SET_ASIDE} ({seen.named_shaft} z {was.z:.2f} -> {kept.z:.2f}, threshold {kept.threshold:.2f}: products of "
        f"shafts' synchronous modulations, repeated every {int(table.train_period)} input turns)"
    )
