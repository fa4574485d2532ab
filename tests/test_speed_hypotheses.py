"""gearbox.speed.not_outdone: a speed hypothesis that another explains on more stages with as much evidence
is no reading. Taken per stage count (the most evidence above it), not pair by pair: the same hypotheses
kept, in their order, as the pairwise rule keeps them."""

import math
import random

from gearlab.gearbox.speed import not_outdone


def pairwise(hypotheses: list) -> list:
    """The rule as first written: every hypothesis against every other."""
    return [h for h in hypotheses if not any(g[5] > h[5] and g[0] >= h[0] for g in hypotheses)]


def test_a_hypothesis_on_more_stages_with_as_much_evidence_outdoes_one():
    one = (5.0, 35.0, "one stage", 1, 400.0, 1)
    two = (5.0, 33.06, "two stages", 1, 380.0, 2)
    weaker = (4.0, 33.5, "one stage, less evidence", 2, 300.0, 1)
    assert not_outdone([one, two, weaker]) == [two]
    assert not_outdone([(6.0, *one[1:]), two]) == [(6.0, *one[1:]), two]  # more evidence: kept
    assert not_outdone([]) == []


def test_the_same_hypotheses_as_pair_by_pair_in_their_order():
    draw = random.Random(7)
    values = (0.0, 1.0, 2.0, math.nan, -math.inf, math.inf)
    for _ in range(3000):
        evidence = [draw.choice(values) if draw.random() < 0.3 else draw.random() for _ in range(draw.randint(0, 12))]
        hypotheses = [(e, draw.random(), "", 1, 1.0, draw.randint(0, 3)) for e in evidence]
        kept = not_outdone(hypotheses)
        assert len(kept) == len(pairwise(hypotheses)) and all(a is b for a, b in zip(kept, pairwise(hypotheses)))
