"""Which of a file's vibration channels carries the gear mesh (`gearlab inspect`): a triaxial sensor's axial axis, or
an accelerometer on another bearing, holds the mesh lines far weaker than the axis across the mesh, and read alone it
still 'matches' the description. Each other channel's mesh is read at the same input angle, as the one read."""

from __future__ import annotations

import math

import numpy as np

from .data.recordings import Recording, read_contents
from .errors import GearlabInputError
from .gearbox import Gearbox, order_table
from .signals import resample_revolutions, spectrum

# A channel whose strongest mesh line stands this much further over its floor than the read one's is named
STRONGER_DB = 10.0
# Bins either side of a line whose median is its floor (a few orders at a take's resolution)
_FLOOR_BINS = 40
# A channel at two values most of the time is a pulse train or a counter (a tacho not given, a take's number): its
# lines sit on every order, the mesh's too
_TWO_LEVELS = 0.9


def mesh_db(signal: np.ndarray, angle: np.ndarray, per_rev: float, mesh_orders: list[float]) -> float:
    """The strongest of *mesh_orders*' lines over the median of the order spectrum around it (dB)."""
    points = int(min(1 << 14, max(64, 2 ** math.ceil(math.log2(per_rev)))))
    orders, amp = spectrum(resample_revolutions(signal, angle, points=points).reshape(-1), points)
    best = -math.inf
    for m in mesh_orders:
        if m > 0.45 * min(points, per_rev):  # over the take's band
            continue
        k = int(np.argmin(np.abs(orders - m)))
        floor = np.median(amp[max(k - _FLOOR_BINS, 1) : k + _FLOOR_BINS])
        best = max(best, 20 * math.log10(max(amp[max(k - 1, 0) : k + 2].max(), 1e-300) / max(floor, 1e-300)))
    return best


def _two_levels(x: np.ndarray) -> bool:
    _, counts = np.unique(x, return_counts=True)
    return np.sort(counts)[-2:].sum() >= _TWO_LEVELS * x.size


def stronger_axis(rec: Recording, angle: np.ndarray, speed_hz: float, box: Gearbox) -> dict | None:
    """The file's other channels whose mesh stands STRONGER_DB further over its floor than the read one's (strongest
    first), or None."""
    others = [c for c in rec.channels if c not in (rec.vibration, rec.tacho_name)]
    if not others:
        return None
    try:
        contents, _ = read_contents(rec.path, others)
    except GearlabInputError:  # an unreadable neighbour is no reason to fail the inspection of the one asked
        return None
    meshes = [float(h * s.mesh) for s in order_table(box).stages for h in (1, 2)]
    per_rev = rec.fs / speed_hz
    read_db = mesh_db(rec.signal, angle, per_rev, meshes)
    found = {}
    for name in others:
        x = np.asarray(contents.found.get(name, ()))
        if x.dtype.kind not in "biuf" or x.shape != rec.signal.shape or not np.all(np.isfinite(x)) or _two_levels(x):
            continue
        found[name] = mesh_db(x.astype(float) - np.mean(x), angle, per_rev, meshes)
    stronger = {c: db for c, db in sorted(found.items(), key=lambda kv: -kv[1]) if db >= read_db + STRONGER_DB}
    if not stronger:
        return None
    named = ", ".join(f"{c!r} (+{db - read_db:.0f} dB)" for c, db in stronger.items())
    line = f"channel{'s' * (len(stronger) > 1)} {named} show{'s' * (len(stronger) == 1)} the mesh further over "
    line += f"the floor than {rec.vibration!r}, the one read: an axis across the gear mesh? "
    line += f"(--vibration {next(iter(stronger))})"
    return {"channels": stronger, "read_db_over_floor": read_db, "line": line}
