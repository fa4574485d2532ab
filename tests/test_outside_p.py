"""Which gear on a two-gear shaft by the record's own sidebands (issue 39 item 5; helper P): where the history's
mesh lines differ from the simulator's, a local fault on a gear is read where it modulates its own mesh. An outside
generator's 25/52 + 16/81 box (helper H's), a chip on the intermediate shaft's 16T pinion made as a dip and a phase
step of its mesh plus a strike, was named the 52T wheel, or both, by the simulated events' phases (their kinds'
phases matched neither gear's: cos -0.3..0.25). Its take end to end: tests/test_box_b_takes.py
(with helper P's, AC's and AB's box B takes, which share box B's simulated events)."""

from __future__ import annotations

import numpy as np

from gearlab.signals import which_template as T
from gearlab.signals.localise import Gear

WHEEL, PINION = Gear("intermediate", 1, "wheel", 52), Gear("intermediate", 2, "pinion", 16)


def _orders(top=400):
    """The intermediate shaft's own orders (not a mesh harmonic nor its first sideband) and their numbers."""
    m = np.arange(1, top + 1)
    keep = np.ones(m.size, bool)
    for z in (16, 52):
        keep &= np.abs(m - z * np.round(m / z)) > 1
    return keep, m[keep]


def test_mesh_combs_name_the_gear_whose_mesh_the_excess_gathers_about():
    rng = np.random.default_rng(5)
    keep, m = _orders()
    d16 = np.abs(m - 16 * np.round(m / 16))
    z = np.zeros(keep.size)
    z[keep] = 200 * np.exp(-(d16**2) / 18) + rng.normal(0, 1, m.size)  # sidebands about the 16T's mesh harmonics
    combs = T.mesh_combs(z, (keep, m), [WHEEL, PINION])
    assert T.by_sidebands(combs, [WHEEL, PINION]) == PINION, combs
    # an excess the structure spreads (no mesh's comb): neither named, the phases decide
    z[keep] = 200 * np.exp(-((m - 216) ** 2) / 800) + rng.normal(0, 1, m.size)
    combs = T.mesh_combs(z, (keep, m), [WHEEL, PINION])
    assert T.by_sidebands(combs, [WHEEL, PINION]) is None and max(combs.values()) < T.COMB_Z, combs
    # no excess at all: not read
    assert T.mesh_combs(np.zeros(keep.size), (keep, m), [WHEEL, PINION]) == {}


def test_the_decoy_periods_stand_clear_of_either_count():
    decoys = T.decoy_periods([52, 16])
    assert decoys and min(decoys) >= T.COMB_SHORTEST and max(decoys) <= 1.5 * 52
    for p in decoys:
        assert all(abs(p - k * z) > T.COMB_CLEAR for z in (16, 52) for k in (1, 2, 3, 4)), p
        assert all(abs(p - z / k) > T.COMB_CLEAR for z in (16, 52) for k in (2, 3, 4)), p
