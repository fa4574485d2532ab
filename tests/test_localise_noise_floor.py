"""signals.evidence.order_z: a take's level -- a load or a sensor gain that scales its lines and its noise alike --
is read from its noise floor, and scales the history off its lines. Takes of a user's mixer (47/131 +
37/151 at 35 Hz, its history at two loads, as that user's box B) made in the input angle: both meshes' harmonics
modulated at each shaft's rate and by a slow process load at no shaft's order (0.0089 input orders, 5 %), white
noise at 6 % of the RMS. The load's sidebands lie at no whole order of the slow output shaft: they scatter its
turns far more than they stay in its mean, so its synchronous power |X̄|² − n reads negative within an order of
the meshes (the history's S_h / N_h -1.4 there), and more negative the louder the take."""

from __future__ import annotations

import numpy as np
import pytest
from which_gear_takes import two_stage_text

from gearlab.signals import localise as L

TEETH = (47, 131, 37, 151)
POINTS, REVOLUTIONS = 1024, 99
LEVELS = (2 / 3, 4 / 3, 2 / 3, 4 / 3)  # the history's power at loads 50 and 100 against a take's at 75


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    from gearlab.gearbox import order_table, resolve_gearbox

    path = tmp_path_factory.mktemp("mixer") / "mixer.toml"
    path.write_text(two_stage_text("mixer", "35 Hz", "75 N*m", TEETH))
    return order_table(resolve_gearbox(str(path)))


def take(seed: int, level: float) -> np.ndarray:
    """REVOLUTIONS input revolutions of a healthy take at *level* times the power of one at the nominal load."""
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * np.arange(REVOLUTIONS * POINTS) / POINTS
    process = 1 + 0.05 * np.sin(0.0089 * theta + rng.uniform(0, 2 * np.pi))
    turns = (1.0, TEETH[0] / TEETH[1], TEETH[0] / TEETH[1] * TEETH[2] / TEETH[3])
    x = sum(0.2 * np.cos(k * r * theta + 0.7 * k + i) for i, r in enumerate(turns) for k in (1, 2))
    for s, z in enumerate(TEETH[::2]):
        a, b = turns[s] * theta, turns[s + 1] * theta
        for h, amp in ((1, 3.0), (2, 1.2), (3, 0.4)):
            am = (1 + 0.06 * np.cos(a + 0.3 * h) + 0.04 * np.cos(b + 0.8 * h)) * process
            x = x + amp / (s + 1) * am * np.cos(h * z * a + 0.4 * h * s)
    x = x + rng.normal(0, 0.06 * np.std(x), x.size)
    return np.sqrt(level) * x.reshape(REVOLUTIONS, POINTS)


@pytest.fixture(scope="module")
def history(table):
    return L.history([take(seed, level) for seed, level in enumerate(LEVELS)], table)


def z_of(revolutions, history, table) -> dict[str, float]:
    return {e.shaft: e.z for e in L.localise(revolutions, history, table).ranking}


def test_a_take_s_level_moves_no_shaft(history, table):
    """One healthy take read as it is and at 2/3 of its power (a load of 50 against 75): the same evidence on every
    shaft. Before, the history was scaled off its lines only by a heavier load's line gain, and its null spread never
    below its own: at 2/3 the output moved from z -1.05 to -0.34 and the intermediate from 1.11 to -0.02."""
    x = take(99, 1.0)
    full, lower = z_of(x, history, table), z_of(np.sqrt(2 / 3) * x, history, table)
    assert all(abs(full[s] - lower[s]) < 0.3 for s in full), (full, lower)


def test_healthy_takes_at_a_lighter_load_read_as_healthy(history, table):
    """Six healthy takes drawn at 2/3 of the history's mean power (each its own noise and process load): every shaft's
    mean z within 0.6 of zero. Before: the intermediate shaft at -1.28, the output at +0.83 (the history's negative
    power about the meshes, taken off unscaled), as the user's takes at 50 N m read the output gear high."""
    shafts = history.layout.shafts
    z = np.array(
        [[found[s] for s in shafts] for found in (z_of(take(200 + i, 2 / 3), history, table) for i in range(6))]
    )
    assert np.all(np.abs(z.mean(axis=0)) < 0.6), z.round(2)
