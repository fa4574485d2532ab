"""Which gear in the envelope on healthy takes at another level than the history's: a two-stage 23/71 + 29/83 box at
30 Hz whose second mesh (667/71 input orders, the strongest, the sensor beside it) falls between the bins of a 120-turn
take, its 71-turn period not held twice (signals.nonsync.read_turns cannot cut the record to whole periods of it).
The residual's bins about the mesh's harmonics are removed, the rest of each line stays at the record's ends (its
Gibbs remainder, at the mesh's level over the noise's); its squared envelope there beats the meshes' harmonics and
their shafts' modulations, and is read on the shafts' orders in the envelope. A history at one level, a healthy take
at 1.4 times it, or a shorter take (a run-down's, a slower one's turns): the remainder differs from the history's
(a 3.0 s take's output shaft in the envelope: z 10.7 over 9.06), and the envelope named a gear that carries no
change. The strong lines are fitted out at their exact orders and the envelope is read a turn of the slowest shaft
away from the record's ends (signals.envelope_sync, "The record's ends"): the 3.0 s take's largest z 0.9 over 4.0."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.data import which_gear as W
from gearlab.gearbox import order_table, resolve_gearbox
from gearlab.signals import POINTS, resample_revolutions

Z = ((23, 71), (29, 83))
BOX = (
    '[gearbox]\nname = "off71"\n[operation]\nspeed = "30 Hz"\nload = "20 N*m"\n'
    + "".join(
        f'[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\npinion = {{ z = {p}, bore = "25 mm" }}\n'
        f'wheel = {{ z = {w}, bore = "30 mm" }}\n'
        for p, w in Z
    )
    + '[sensor]\nnear = "output"\ntacho = "input"\n'
)
FS, SPEED, SECONDS = 10_000.0, 30.0, 4.0


def take(seed: int, level: float = 1.0, seconds: float = SECONDS, noise: float = 0.02) -> W.Take:
    """A healthy take of *seconds* from an input tacho mark: each stage's mesh harmonics at *level* (the second stage's
    strongest), modulated by both its shafts, the shafts' lines (not scaled by the load), noise *noise* of the
    first harmonic's amplitude at level 1."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    th = [2 * np.pi * SPEED * t + rng.uniform(0, 2 * np.pi)]
    for p, w in Z:
        th.append(th[-1] * p / w)
    x = sum(0.2 * np.cos(a + k) for k, a in enumerate(th))
    for s, ((p, _), gain) in enumerate(zip(Z, (0.4, 1.0))):
        am = 1 + 0.08 * np.cos(th[s]) + 0.06 * np.cos(th[s + 1] + 1.1)
        for h, a in ((1, 1.0), (2, 0.45), (3, 0.2)):
            x = x + level * gain * a * am * np.cos(h * p * th[s] + 0.7 * h * s)
    x = x + noise * rng.standard_normal(t.size)
    angle = th[0] - th[0][0] + 1e-9
    first = 0
    return W.Take(resample_revolutions(x, angle, points=POINTS), first, SPEED, FS)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    path = tmp_path_factory.mktemp("off71") / "box.toml"
    path.write_text(BOX)
    table = order_table(resolve_gearbox(str(path)))
    return table, W.history_of([take(seed) for seed in (1, 2, 3)], table)


@pytest.mark.parametrize(("level", "seconds"), [(1.0, 3.0), (1.0, 3.4), (1.4, SECONDS)])
def test_a_healthy_take_of_another_length_or_level_is_named_nothing_in_the_envelope(box, level, seconds):
    table, hist = box
    assert hist.envelope is not None
    found = W.which_gear(take(10, level, seconds), hist, table, None)
    assert found["named"] is None, found["summary"]
