"""Which gear on a two-gear shaft by the record's own sidebands (issue 39 item 5; helper P): where the history's
mesh lines differ from the simulator's, a local fault on a gear is read where it modulates its own mesh. An outside
generator's 25/52 + 16/81 box (helper H's), a chip on the intermediate shaft's 16T pinion made as a dip and a phase
step of its mesh plus a strike, was named the 52T wheel, or both, by the simulated events' phases (their kinds'
phases matched neither gear's: cos -0.3..0.25). The recordings are made here, small, by plain numpy."""

from __future__ import annotations

import json

import numpy as np
from gearboxes import description, stage
from scipy.signal import lfilter

from gearlab.signals import which_template as T
from gearlab.signals.localise import Gear

BOX_B = description(
    stage(25, 52),
    stage(16, 81, module="3 mm", bores=("30 mm", "45 mm")),
    name="boxB",
    speed="25 Hz",
    load="40 N*m",
    near="intermediate",
    tacho="intermediate",
    marks=4,
)
WHEEL, PINION = Gear("intermediate", 1, "wheel", 52), Gear("intermediate", 2, "pinion", 16)


def _take(path, seed, chip=0.0, seconds=8.0, fs=10240.0):
    """A 25/52 + 16/81 take at 25 Hz (in g): both meshes' harmonics, amplitude and phase modulated at both shafts'
    rates (the gearbox's phases, not the take's); a chip on the 16T pinion: a dip (0.45) and a phase step (0.6 rad)
    of stage 2's mesh over ~1.2 of its pitches once per intermediate turn, and a strike ringing at 2.6 kHz; a 2.6 kHz
    resonance, noise; a tacho of 4 alike marks a turn on the intermediate shaft."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * seconds)) / fs
    th = 2 * np.pi * 25.0 * t * (1 + 0.0015 * np.sin(2 * np.pi * 0.37 * t)) + rng.uniform(0, 2 * np.pi)
    thm, tho = th * 25 / 52, th * 25 / 52 * 16 / 81
    window = np.exp(-0.5 * (((thm - 4.0 + np.pi) % (2 * np.pi) - np.pi) / (1.2 * np.pi / 16)) ** 2)

    def mesh(angle, z, a, b, dip=0.0, step=0.0):
        fixed = np.random.default_rng(z).uniform(0, 6, 7)  # the gearbox's own phases
        am = (1 + 0.15 * np.cos(a + fixed[0]) + 0.1 * np.cos(b + fixed[1])) * (1 - dip * window)
        pm = 0.05 * np.sin(a + fixed[2]) + 0.04 * np.sin(b + fixed[3]) + step * window
        return sum(c * am * np.cos(k * (z * angle + pm) + fixed[3 + k]) for k, c in enumerate((1.0, 0.45, 0.2), 1))

    x = 0.6 * mesh(th, 25, th, thm) + 0.9 * mesh(thm, 16, thm, tho, 0.45 * chip, 0.6 * chip)
    if chip:  # the strike: a 2.6 kHz ring decaying in 0.6 ms, once per intermediate turn at the chip
        ring = np.exp(-np.arange(31) / (0.0006 * fs)) * np.sin(2 * np.pi * 2600.0 * np.arange(31) / fs)
        turns = np.arange(np.ceil((thm[0] - 4.0) / (2 * np.pi)), np.floor((thm[-1] - 4.0) / (2 * np.pi)) + 1)
        at = np.searchsorted(thm, 4.0 + 2 * np.pi * turns)
        for i in at[at < t.size - 31]:
            x[i : i + 31] += 0.5 * chip * ring
    x = x + 0.05 * np.cos(th) + 0.06 * np.cos(thm + 2) + 0.05 * np.cos(tho + 1)
    r, w = np.exp(-0.04 * 2 * np.pi * 2600.0 / fs), 2 * np.pi * 2600.0 / fs  # the structure's resonance
    x = x + 0.8 * lfilter([1 - r], [1, -2 * r * np.cos(w), r * r], x) + rng.normal(0, 0.05, t.size)
    tacho = np.where((4 * thm / 2 / np.pi) % 1 < 0.1, 5.0, 0.0)
    np.savez(path, acc_top=x.astype("f4"), tacho=tacho.astype("f4"), fs=fs)
    return path


def _localised(cli, tmp_path, seed):
    (tmp_path / "boxB.toml").write_text(BOX_B)
    history = [_take(tmp_path / f"h{s}.npz", s) for s in (61, 62, 63)]
    take = _take(tmp_path / f"c{seed}.npz", seed, chip=1.0)
    args = ["inspect", take, "--gearbox", tmp_path / "boxB.toml", "--vibration", "acc_top", "--tacho", "tacho"]
    code, stdout, err = cli(*args, "--unit", "g", *[a for h in history for a in ("--history", h)], "--json")
    assert code == 0, err
    return json.loads(stdout)["localisation"]


def test_a_16t_chip_is_named_by_the_sidebands_about_its_own_mesh(cli, tmp_path, monkeypatch):
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
