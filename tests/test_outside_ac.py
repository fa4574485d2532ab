"""Which gear on a two-gear shaft by the contrast of each mesh's sidebands (issue 39 item 5, helper AC): an outside
generator's 25/52 + 16/81 box (helper H's), a crack on the intermediate shaft's 52T wheel made as a dip and a phase
step of stage 1's mesh. Its excess gathers about that mesh's first harmonic and fades by the 3rd, too few periods for
the own-mesh comb (2.2-3.2 against the decoy periods', under 6), so the simulated events' phases decided and named the
16T pinion, or both, in 9 of 40 development takes. Its take end to end: tests/test_box_b_takes.py
(with helper P's, AC's and AB's box B takes, which share box B's simulated events)."""

from __future__ import annotations

import numpy as np
from test_outside_p import _orders  # the intermediate shaft's own orders of box B

from gearlab.signals import which_template as T
from gearlab.signals.localise import Gear

WHEEL, PINION = Gear("intermediate", 1, "wheel", 52), Gear("intermediate", 2, "pinion", 16)


def test_a_mesh_whose_sidebands_alone_rise_is_named_and_not_where_both_rise():
    rng = np.random.default_rng(3)  # comb 2.7, under COMB_Z: as the crack's
    keep, m = _orders()
    # sidebands about the 52T's first three mesh harmonics, fading (1, 0.2, 0.05) as the outside generator's do
    k = np.round(m / 52).astype(int)
    fade = np.array([0, 1, 0.2, 0.05])[np.clip(k, 0, 3)] * (k <= 3)
    around52 = fade * np.exp(-(((m - 52 * k) / 8) ** 2))
    z = np.zeros(keep.size)
    z[keep] = 60 * around52 + np.abs(rng.normal(0, 1, m.size))
    combs, contrasts = T.mesh_combs(z, (keep, m), [WHEEL, PINION]), T.mesh_contrasts(z, (keep, m), [WHEEL, PINION])
    assert T.by_sidebands(combs, [WHEEL, PINION]) is None, combs  # the comb alone does not name it
    assert T.by_contrasts(contrasts, combs, [WHEEL, PINION]) == WHEEL, (combs, contrasts)
    # the 16T's sidebands risen as well: neither gear by the contrast (the comb may still name the 16T)
    d16 = np.abs(m - 16 * np.round(m / 16))
    z[keep] += 400 * np.exp(-(d16**2) / 8) * (m < 80)
    combs, contrasts = T.mesh_combs(z, (keep, m), [WHEEL, PINION]), T.mesh_contrasts(z, (keep, m), [WHEEL, PINION])
    assert T.by_contrasts(contrasts, combs, [WHEEL, PINION]) is None, contrasts
    assert min(contrasts[PINION.name]["each"]) >= T.CONTRAST_EACH, contrasts
    assert contrasts[WHEEL.name]["pooled"] >= T.CONTRAST_OTHER <= contrasts[PINION.name]["pooled"], contrasts
    # no excess at all: no contrast (the flanks' floor), nothing named
    quiet = T.mesh_contrasts(np.zeros(keep.size), (keep, m), [WHEEL, PINION])
    assert all(c["pooled"] == 0 for c in quiet.values()) and T.by_contrasts(quiet, {}, [WHEEL, PINION]) is None
