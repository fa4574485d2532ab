"""Which gear on a two-gear shaft by the record's own sidebands (issue 39 item 5; helper P): where the history's
mesh lines differ from the simulator's, a local fault on a gear is read where it modulates its own mesh. An outside
generator's 25/52 + 16/81 box (helper H's), a chip on the intermediate shaft's 16T pinion made as a dip and a phase
step of its mesh plus a strike, was named the 52T wheel, or both, by the simulated events' phases (their kinds'
phases matched neither gear's: cos -0.3..0.25). The recordings are made here, small, by plain numpy."""

from __future__ import annotations

import json

import numpy as np
from which_gear_takes import box_b_description, box_b_take

from gearlab.signals import which_template as T
from gearlab.signals.localise import Gear

BOX_B = box_b_description(load="40 N*m")
WHEEL, PINION = Gear("intermediate", 1, "wheel", 52), Gear("intermediate", 2, "pinion", 16)


def _localised(cli, tmp_path, seed):
    (tmp_path / "boxB.toml").write_text(BOX_B)
    history = [box_b_take(tmp_path / f"h{s}.npz", s, seconds=8.0, ring=True) for s in (61, 62, 63)]
    take = box_b_take(tmp_path / f"c{seed}.npz", seed, seconds=8.0, chip=1.0, ring=True)
    args = ["inspect", take, "--gearbox", tmp_path / "boxB.toml", "--vibration", "acc_top", "--tacho", "tacho"]
    code, stdout, err = cli(*args, "--unit", "g", *[a for h in history for a in ("--history", h)], "--json")
    assert code == 0, err
    return json.loads(stdout)["localisation"]


def test_a_16t_chip_is_named_by_the_sidebands_about_its_own_mesh(cli, tmp_path, monkeypatch, synchronous_only):
    # red before: 'intermediate gear 52T (stage 1)' by the simulated events' phases (52T 0.30 / 16T 0.19, weak); seeds
    # 64-75 of this generator: the phases named the 52T in 9, both in 2, the 16T in 1; the sidebands the 16T in 12
    # (7.7-8.1)
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    found = _localised(cli, tmp_path, 64)
    shaft = found["shafts"][0]
    assert shaft["shaft"] == "intermediate" and shaft["flagged"], shaft
    assert found["named"] == PINION.name, found["summary"]
    ev = shaft["stage_evidence"]
    assert ev["rule"] == T.RULE_SIDEBANDS and ev["structure gap dB"] > T.SHAPE_DB, ev
    combs = ev["own-mesh sidebands"]
    assert combs[PINION.name] >= T.COMB_Z > combs[WHEEL.name], combs
    assert "sidebands about each gear's own mesh" in found["summary"] and "weak" not in found["summary"]


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
