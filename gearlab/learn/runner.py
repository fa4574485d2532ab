"""One repetition's split of a dataset and one unit's run: the core of both protocols, the
chapter-5 transfer protocol (gearlab.learn.protocol) and the chapter-4 noise study
(gearlab.learn.noise_study), which say only what they cut, fit and score.

**The split.** Repetition r of a protocol seeded s draws from ``default_rng([s, r, *stream])``
(:func:`generator`; a stream keeps two draws of one repetition apart). Each class's rows come
in a random order, the classes drawn in the order given (:func:`orders`); a split cuts every
class's order at its counts, part j holding the j-th stretch of every class and the last part
the rest (:func:`cut`). Parts are sorted and disjoint. A class of one label (all rows) is a
plain random split.

**The unit** (:func:`run_unit`): the model is made from the split's training parts alone (the
test part is not in what *fit* is given); only then, with the model fixed, does *score* read
the test part, once.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol, TypeVar

import numpy as np

# torch is imported inside run_unit (start-up time): checking a scenario loads none of it.


class HeldOut(Protocol):
    """What run_unit needs of a protocol's split: the same split without its test part, and the
    test part."""

    @property
    def test(self) -> np.ndarray | None: ...

    def training(self) -> HeldOut: ...


S = TypeVar("S", bound=HeldOut)


def generator(seed: int, rep: int, *stream: int) -> np.random.Generator:
    """The generator of repetition *rep* of a protocol seeded *seed* (*stream*: which of its draws)."""
    return np.random.default_rng([seed, rep, *stream])


def orders(label: np.ndarray, classes: Sequence[int], rng: np.random.Generator) -> dict[int, np.ndarray]:
    """Each class's rows (indices where *label* is it) in a random order, drawn class by class
    in the order of *classes*."""
    label = np.asarray(label)
    return {int(c): rng.permutation(np.flatnonzero(label == c)) for c in classes}


def put_first(order: np.ndarray, rows: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """*order* with *rows* (some of its entries) first, in an order drawn from *rng*, the others after
    them as they were."""
    return np.concatenate([rng.permutation(rows), order[~np.isin(order, rows)]])


def cut(orders: dict[int, np.ndarray], counts: dict[int, Sequence[int]]) -> tuple[np.ndarray, ...]:
    """The parts of a split: class c's order cut after counts[c][0], counts[c][0] + counts[c][1],
    ... rows; part j is every class's j-th stretch, sorted; the last part holds the rest. Every
    class names as many counts."""
    parts: list[list[np.ndarray]] = [[] for _ in range(1 + len(next(iter(counts.values()))))]
    for c, order in orders.items():
        if len(counts[c]) + 1 != len(parts):
            raise ValueError(f"cut: class {c} has {len(counts[c])} counts, another {len(parts) - 1}")
        for j, stretch in enumerate(np.split(order, np.cumsum(counts[c]))):
            parts[j].append(stretch)
    return tuple(np.sort(np.concatenate(p)) for p in parts)


def run_unit(
    split: S, fit: Callable[[S, Any], Any], score: Callable[[Any, np.ndarray, Any], dict], device: str = "auto"
) -> dict:
    """One unit of a protocol: *fit*(the split without its test part, device) makes the model (and
    whatever the record needs of its training); then *score*(what fit made, the test part,
    device) scores the fixed model on the test rows and returns the unit's record."""
    from .training import pick_device  # start-up time

    device = pick_device(device)
    fitted = fit(split.training(), device)
    # Only now, with the model fixed, does the test part come in.
    return score(fitted, split.test, device)
