"""A stage read on another harmonic family while the described one holds the lines of its own
(gearlab.gearbox.match.check_description). A slow last stage's mesh can stand under the floor at its first
harmonics and its lines under the faster stages': a 21/63 + 18/54 + 15/45 box at 30 Hz whose casing rings at
459 and 918 Hz (casing_path: mf 6 kg, k_xf 5e7, k_yf 2e8 N/m) showed stage 3's mesh (1.667 orders, 50 Hz) at
harmonics 6-35, 17-35 dB over the floor, none at 1-5; the strongest lines (mesh_family's evidence) held only lines
on stages 1 and 2's harmonics too (60, 105, 210), whose family, 15, was read: 'a 135-tooth pinion'.

The gear engineer's rule: the described count puts lines at every harmonic h M (and its shafts' sidebands), another
count at h M' alone. The lines that decide are those nothing else explains: off the other stages' mesh harmonics and
their sidebands, off the rival family's harmonics and sidebands. Where most of them (HELD) sit on the described comb,
at least OWN_LINES and CHANCE times what so dense a comb holds by chance, the description stands. A count really off
leaves only chance lines there: the real mesh's own lines and sidebands are the rival's.
"""

from __future__ import annotations

import numpy as np

from .sideband_combs import tol_mesh
from .speed import MAX_HARMONIC, Lines

SIDEBANDS = 3  # the sidebands j o of either shaft a mesh harmonic carries (the gap's combs too)
OWN_LINES = 3  # the described comb's unexplained lines a reading on it needs (one line is a tone)
HELD = 0.5  # the share of the unexplained lines the described comb must hold
CHANCE = 2.0  # ... and this many times what its windows (2 tol / M of the axis) hold by chance


def on_comb(x: np.ndarray, z: float, shaft_orders, tol: np.ndarray) -> np.ndarray:
    """Which orders *x* lie on a mesh harmonic h z (h >= 1) or one of its sidebands h z +- j o."""
    offsets = np.array([0.0] + [s * j * o for o in shaft_orders for j in range(1, SIDEBANDS + 1) for s in (-1, 1)])
    h = np.maximum(1, np.round((x[:, None] - offsets[None, :]) / z))
    return np.any(np.abs(x[:, None] - h * z - offsets[None, :]) <= tol[:, None], axis=1)


def described_holds(lines: Lines, m: float, rival: float, shafts, others, bin_: float) -> bool:
    """Whether the lines up to the described mesh *m*'s MAX_HARMONIC-th harmonic that neither the *others* ((mesh
    order, shaft orders ...): other_stages', a train's later stages') nor the *rival* family (with the stage's *shafts*'
    sidebands) explain sit on *m*'s harmonics (module doc)."""
    x = lines.at
    tol = tol_mesh(x, bin_)
    explained = on_comb(x, rival, shafts, tol)
    for mesh, *shafts_of in others:
        explained |= on_comb(x, mesh, [o for orders in shafts_of for o in orders], tol)
    free = ~explained & (x <= MAX_HARMONIC * m + tol)
    held = int(np.sum(free & on_comb(x, m, (), tol)))
    chance = float(np.sum(np.minimum(1.0, 2 * tol[free] / m)))
    return held >= OWN_LINES and held >= HELD * np.sum(free) and held >= CHANCE * chance
