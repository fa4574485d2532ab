"""What the gap kind checks and reads of its target before any diagnosis (gearlab.kinds.gap):
measured history records of one operating condition, enough healthy revolutions, a rate that
resolves the mesh harmonics."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.spec import DatasetSpec
from ..errors import GearlabInputError
from ..events import Event
from ..parts.measured import Target
from ..settings import setting
from .common import DatasetEntry

# History records of one condition: tacho speeds within this relative spread (a 30 Hz and a 40 Hz
# record are two conditions; one rig at one setting drifts by well under 1 %).
SPEED_SPREAD = 0.02
# The gap statistics need at least this many healthy revolutions per side (gearlab.gap.stats).
MIN_HEALTHY = 10
# Mesh sidebands the order bands resolve beside each mesh harmonic (gearlab.gap.views.BandPlan):
# a revolution must be sampled finely enough for the first mesh order plus these.
SIDEBANDS = 3


@dataclass(frozen=True, kw_only=True)
class TargetEntry(DatasetEntry):
    """[target]: a dataset entry, or measured records in the detection kind's shape (a list of files with
    a tacho of N pulses per revolution, docs/real_data.md); the diagnosis reads their history files."""

    vibration: int | str = setting(
        (int, str), "", doc="measured data: the vibration channel (records: 0-based column or name)"
    )
    tacho: int | str = setting((int, str), "", doc="measured data: the tacho channel (records: 0-based column or name)")
    pulses_per_rev: int = setting(int, 1, low=1, high=10_000, doc="records: tacho pulses per input-shaft revolution")
    sensitivity: float | str | None = setting(
        (int, float, str),
        None,
        doc="measured data: sensor sensitivity, e.g. '10 mV/g' (a number: V "
        "per m/s²); without it (or 'gain') the units are unknown",
    )
    files: list = setting(
        list,
        [],
        doc="measured records: [{path, role = 'history', label}, ...]; the diagnosis reads "
        "the history files (healthy, one operating condition)",
    )


@dataclass(frozen=True)
class Records:
    """Measured records as the gap's target: the [target] of the detection kind (files with roles);
    the diagnosis reads the history files (healthy data of one operating condition)."""

    name: str
    target: Target
    units_known: bool = True  # a sensitivity was given (else the values are taken as m/s², with a warning)

    @property
    def history(self):
        return tuple(f for f in self.target.files if f.role == "history")


def read_history(records: Records, on_event) -> tuple[np.ndarray, float, list[str], float]:
    """The history records' revolutions in m/s² (n, POINTS), their mean tacho speed, notes, and
    their sampling rate (the [target]'s fs, or the first record's own).
    Records of different speeds are different operating conditions: refused. Each record starts at
    one of the tacho's N marks: every record is turned by m/N of a turn into register with the first
    (textzip.align_to, as the detection kind does), so the set has one synchronous average."""
    from ..data.textzip import align_to

    t = records.target
    rows, speeds, notes = [], {}, []
    files = records.history
    on_event(Event("stage", stage="records", total=len(files), message="measured history records"))
    for i, f in enumerate(files):
        rec = t.read(f)
        revs = rec.revolutions
        if rows:
            _, revs = align_to(rows[0].mean(axis=0), revs, t.pulses_per_rev)
        rows.append(revs)
        speeds[f.path] = rec.speed_hz
        on_event(Event("advance", stage="records", done=i + 1, total=len(files)))
    low, high = min(speeds.values()), max(speeds.values())
    if high > low * (1 + SPEED_SPREAD):
        shown = ", ".join(f"{p} {s:.2f} Hz" for p, s in speeds.items())
        raise GearlabInputError(
            f"[target] key 'files': the history records run at different speeds ({shown}); "
            "the gap is diagnosed for one operating condition: give one speed's records"
        )
    skipped = len(t.files) - len(files)
    if skipped:
        notes.append(f"{skipped} test file(s) of the [target] are not used: the gap is measured on the history")
    X = np.concatenate(rows).astype(np.float64)
    speed = float(np.average(list(speeds.values()), weights=[len(r) for r in rows]))
    notes.append(
        f"target: {len(X)} revolutions of {len(files)} history record(s) at {speed:.3f} Hz "
        f"(tacho); the source simulates that speed"
    )
    return X, speed, notes, t.fs or rec.fs


def check_healthy(count: int, where: str) -> None:
    if count == 0:
        raise GearlabInputError(
            f"{where}: the target has no healthy data; the gap is measured on healthy "
            f"revolutions (expected at least {MIN_HEALTHY})"
        )
    if count < MIN_HEALTHY:
        raise GearlabInputError(
            f"{where}: too few healthy target revolutions for the gap statistics: {count}; "
            f"expected at least {MIN_HEALTHY}"
        )


def check_sampling(spec: DatasetSpec, z1: int, where: str) -> None:
    """The simulation rate must resolve the first mesh order and its sidebands in time: fs / speed
    samples per revolution, of which the highest order is half."""
    from ..data.builder import operating_point

    speed, _ = operating_point(spec)
    check_points(spec.fs / speed, z1, f"{where} key 'fs'", f"fs = {spec.fs:g} Hz at {speed:g} Hz")


def check_points(points: float, z1: int, where: str, what: str) -> None:
    need = 2 * (z1 + SIDEBANDS) + 1
    if points < need:
        raise GearlabInputError(
            f"{where}: sampling rate too low for the mesh harmonics: {what} gives "
            f"{points:.4g} samples per revolution, fewer than {need} needed to resolve mesh "
            f"order {z1} (a {z1}-tooth pinion) and its {SIDEBANDS} sidebands"
        )
