"""The one realisation of simulated revolutions: what every simulated signal goes through after
the simulator -- the dataset builder's rows and healthy reference, the gap diagnosis's source rows
(angle domain or through a record's chain, gearlab.data.chain), the gap benchmark's target record
and a simulated record (gearlab.data.simulated) alike.

    noise-free rows x (J, L), consecutive stretches of one record: J revolutions in the angle
    domain (fs = POINTS x speed) or a record's samples in time (fs = its rate)
      ─► the signal-level effects, in the chain's order (by level, then as given: a sensor_noise
         listed before a sensor_lowpass is filtered by it), each from its own generator
      ─► the dataset's noise (a scenario's ``sensor_noise`` with a ``seed``), every row at the SNR
         of its own RMS (eq. 4.1-4.5), after every effect
      ─► the TSA of the J rows (eq. 4.7), when asked

A measured target's chain puts its sampling between the non-noise effects and the noise (a
sensor's noise is white in time): its callers realise twice, :func:`parts` of the chain apart.

**A train's cycle.** A later mesh of no whole input order (17/59 then 26/83: 442/59 orders) repeats
only after a cycle of input revolutions (builder.mesh_cycle: 59 here, 1 on every built-in train), at
another phase in each. The simulator's rows then hold the whole steady cycle, and a row's record is
J consecutive revolutions of it (:func:`record`) from a revolution drawn per row
(:func:`first_revolution`), as a recording's stretch starts anywhere: each raw revolution holds
the later mesh at its own phase, and their TSA averages it away as a recording's does. A cycle of
one period (every whole-order train) draws nothing: its rows are the same bits as before.

**Seeds** (:class:`Seeds`). Signal effect k (1-based, in the order of the chain given) draws from
``default_rng([*effects, k])`` and the record's time within the hour of recording from
``[*effects, 0]`` (EffectChain.apply_signal); the dataset's noise from ``default_rng(noise)``.
A realisation depends on its rows and these seeds only, never on the worker count or on the chunk
a row is made in. The callers' schemes, kept as they were (every figure made before stays):

* the builder's row i of a dataset: r = [dataset seed, noise seed, i] (:func:`row_seed`), then
  ``Seeds.of_row(r)`` = ([*r, EFFECT_STREAM], r); its healthy reference is row REFERENCE_ROW;
* the gap diagnosis through a record's chain: the same seeds per row, the non-noise effects and
  the noise ones each numbered from 1 (two chains); consecutive rows (one record): row 0's seeds;
* the gap benchmark's target record, trial seed t: the non-noise effects from [t, EFFECT_STREAM, 1],
  the noise effects from [t, EFFECT_STREAM], the dataset's noise from [t, 5];
* a simulated record, seed s: the effects from [s, 1], the noise from [s, 2].

A scenario declares a recording's noise one way, the ``sensor_noise`` effect, and it adds one noise
(gearlab.signals.add_noise). With a ``seed`` it is the dataset's noise (a NoiseSpec): last, after
every effect, from its own seed (what chapter 4's noise study sweeps and the Bayes bound assumes);
without one it stays an effect, at its place among the signal effects, from the effects' streams
(what the gap diagnosis fits). The two are kept apart so that every dataset keeps its draws.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from ..effects import EffectChain
from ..signals import add_noise, tsa

EFFECT_STREAM = 7  # seeds the signal effects' own generators apart from the dataset noise's
CYCLE_STREAM = 11  # seeds the revolution of the cycle a row's record starts at
REFERENCE_ROW = 2**32 - 1  # the row index that seeds a dataset's healthy reference (no sample's)


class Seeds(NamedTuple):
    """The seeds of one realisation: *effects* for the signal effects' streams, *noise* for the
    dataset's noise (module docstring)."""

    effects: Sequence[int]
    noise: Sequence[int]

    @classmethod
    def of_row(cls, row: Sequence[int]) -> Seeds:
        """The builder's seeds of a row seeded *row* (:func:`row_seed`)."""
        return cls([*row, EFFECT_STREAM], row)


def row_seed(spec, i: int) -> list[int]:
    """The seed of row *i* of dataset *spec* (a DatasetSpec): [seed, noise seed, i], the noise's
    own seed 0 when it has none."""
    return [spec.seed, spec.noise.seed if spec.noise else 0, i]


def first_revolution(seed: int, i: int, revolutions: int, period: int = 1) -> int:
    """The revolution of a steady cycle of *revolutions* at which record *i* of a dataset seeded *seed*
    starts (module docstring): a whole number of *period*s in (the period of its damaged gear, so its
    first revolution holds the damaged tooth, builder.period_turn), drawn from
    ``default_rng([seed, i, CYCLE_STREAM])``; 0, no draw, when the cycle is one period. Not seeded by
    the noise: a dataset and the same spec without noise cut the same revolutions (a twin of fewer
    samples, one per run of draws, detection_units.noise_free_twin, does not: its bound is then
    approximate on such a train)."""
    choices = revolutions // period
    if choices <= 1:
        return 0
    return period * int(np.random.default_rng([seed, i, CYCLE_STREAM]).integers(choices))


def record(revolutions: np.ndarray, count: int, start: int = 0) -> np.ndarray:
    """*count* consecutive revolutions (count, L) of the steady cycle *revolutions* (R, L) from
    revolution *start* on, the cycle repeating: one revolution is broadcast (not copied)."""
    if len(revolutions) == 1:
        return np.broadcast_to(revolutions[0], (count, revolutions.shape[1]))
    return revolutions[(start + np.arange(count)) % len(revolutions)]


def parts(chain: EffectChain) -> tuple[EffectChain, EffectChain]:
    """(shaping, noisy): the chain's signal-level effects that are not noise, and those that are,
    each in the chain's order."""
    signal = chain.at("signal")
    return (
        EffectChain(tuple(item for item in signal if not item[0].noise)),
        EffectChain(tuple(item for item in signal if item[0].noise)),
    )


def realise(
    rows: np.ndarray,
    effects: EffectChain,
    noise,
    seeds: Seeds | Sequence[Seeds],
    *,
    fs: float,
    speed_hz: float,
    reference_rms: float,
    average: bool = False,
) -> np.ndarray:
    """Noise-free *rows* (J, L) realised (module docstring): *effects*' signal-level effects at the
    rate *fs* and shaft speed *speed_hz* (their levels relative to *reference_rms*, the RMS of the
    domain's clean healthy signal), then the dataset's *noise* (anything with ``kind`` and
    ``snr_db``, a NoiseSpec; its own seed is the caller's to put into *seeds*; None: none).

    *seeds*: one :class:`Seeds` -- the rows are consecutive, one record; or one per row -- each row
    is a record of its own (a revolution made alone). *average*: the TSA of the realised rows (L,),
    else the rows (J, L). Unchanged rows come back as given (not copied)."""
    if not isinstance(seeds, Seeds):
        if len(seeds) != len(rows):
            raise ValueError(f"realise: {len(seeds)} seeds for {len(rows)} rows")
        out = np.stack(
            [
                realise(row[None], effects, noise, s, fs=fs, speed_hz=speed_hz, reference_rms=reference_rms)[0]
                for row, s in zip(rows, seeds)
            ]
        )
        return tsa(out) if average else out
    x = rows
    if effects:
        x = effects.apply_signal(x, fs, speed_hz, reference_rms, seeds.effects)
    if noise is not None:
        x = add_noise(x, noise.snr_db, noise.kind, np.random.default_rng(seeds.noise))
    return tsa(x) if average else x
