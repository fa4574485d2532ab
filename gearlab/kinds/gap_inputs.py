"""What the gap kind checks and reads of its target before any diagnosis (gearlab.kinds.gap):
measured history records of one operating condition (with a tacho, or without one a declared
speed or the description's mesh orders, as the detection kind reads them), enough healthy
revolutions, a rate that resolves the mesh harmonics, and what is said when their units are unknown."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from ..data.importers import MeasuredSpec
from ..data.spec import DatasetSpec
from ..errors import GearlabInputError
from ..events import Event
from ..parts.measured import Target, target_spec
from .common import FITS, SPEED_GROUP, TRAINS, DatasetEntry, dataset_spec, gearbox_name, measured, unconfirmed_speed

# The gap statistics need at least this many healthy revolutions per side (gearlab.gap.stats).
MIN_HEALTHY = 10
# Mesh sidebands the order bands resolve beside each mesh harmonic (gearlab.gap.views.BandPlan):
# a revolution must be sampled finely enough for the first mesh order plus these.
SIDEBANDS = 3


@dataclass(frozen=True, kw_only=True)
class TargetEntry(DatasetEntry):
    """[target]: a dataset entry, or measured records in the detection kind's shape ('files', read
    with the same measured-data keys); the diagnosis reads their history files."""

    files: list = measured("files")


@dataclass(frozen=True)
class Records:
    """Measured records as the gap's target: the [target] of the detection kind (files with roles);
    the diagnosis reads the history files (healthy data of one operating condition)."""

    name: str
    target: Target
    # a sensitivity was given, or the vibration channel's name says its unit (else the values are
    # taken as m/s², with a warning: units_warning)
    units_known: bool = True
    where: str = "[target]"  # the scenario file and table, for the messages of reading the records

    @property
    def history(self):
        return tuple(f for f in self.target.files if f.role == "history")


def target_of(entry: dict, where: str, base, box=None) -> DatasetSpec | MeasuredSpec | Records:
    """The [target]: measured records ('files'; *box*: their tacho's shafts), or a dataset entry (a preset, 'file')."""
    if not entry["files"]:
        if entry["pulses_per_rev"] not in (None, 1):
            raise GearlabInputError(f"{where} key 'pulses_per_rev': belongs to measured records ('files')")
        for key in ("vibration", "tacho"):
            if not isinstance(entry[key], str):
                raise GearlabInputError(
                    f"{where} key '{key}': a column index belongs to measured records "
                    f"('files'); a 'file' names its channel as text (a WAV's channels are named "
                    f'"0", "1", ...): expected e.g. {key} = "{entry[key]}"'
                )
        return dataset_spec(entry, where, base)
    for key in ("preset", "file"):
        if entry[key]:
            raise GearlabInputError(f"{where}: give either 'files' (measured records) or '{key}', not both")
    # without a tacho, a declared 'speed' or the 'gearbox' description's mesh orders give each record's
    # speed (parts.measured.target_spec refuses none of the three; the description resolved and loaded now)
    if entry["gearbox"]:
        entry = {**entry, "gearbox": gearbox_name(entry["gearbox"], f"{where} key 'gearbox'", base)}
    target = target_spec({**entry, "positive": "fault"}, where, base, need=("history",), box=box)
    return Records(entry["name"] or "measured records", target, units_declared(target), where)


def read_history(
    records: Records, on_event, described: tuple = (None, None)
) -> tuple[np.ndarray, float, list[str], float, bool, tuple[int, ...]]:
    """The history records' revolutions in m/s² (n, POINTS), their mean speed, notes, their sampling
    rate (a file's 'fs', else the [target]'s, else the record's own), whether the speed was found from the
    description's mesh lines alone (no tacho, no declared speed: data.chain.Chain.speed_from_mesh),
    and each record's count of revolutions (Chain.takes). *described*: the source's speed and pinion teeth,
    for what the note says of a speed found from the mesh lines (mesh_speed_note).
    Records of different speeds are different operating conditions: refused. Every record is turned
    into register with the first (parts.measured.aligned, as the detection kind does): with a tacho
    by m/N of a turn (one of its N marks, or on another shaft the N input angles they may find:
    Target.marks), without one by any whole sample of the revolution (each record's angle is zero at
    its first sample), so the set has one synchronous average; the record shifted as one signal
    (signals.angle.continued), so that what is not periodic in the input turn stays continuous."""
    from ..parts.measured import aligned

    t = records.target
    rows, speeds, found, notes = [], {}, {}, []
    files = records.history
    on_event(Event("stage", stage="records", total=len(files), message="measured history records"))
    for i, f in enumerate(files):
        rec = t.read(f)
        revs = rec.revolutions
        if rows:
            _, revs = aligned(rows[0].mean(axis=0), revs, t.tacho, t.marks, continuous=True)
        rows.append(revs)
        speeds[f.path], found[f.path] = rec.speed_hz, rec.angle_source
        notes += [f"{f.path}: {w}" for w in rec.warnings]  # clipped, a dropout, a baseline taken out
        on_event(Event("advance", stage="records", done=i + 1, total=len(files)))
    unconfirmed = unconfirmed_speed(found, speeds)
    if unconfirmed:
        # the description's mesh lines are nowhere near the declared speed: read at it, the records' lines
        # are smeared and fitted effects, 'unexplained' (a 19/58 + 25/67 fan described with 18 teeth)
        path, words = unconfirmed
        raise GearlabInputError(
            f"{records.where} key 'speed': {words}; expected the records' speed and tooth counts: gearlab "
            f"inspect {path} --gearbox ... says what differs"
        )
    low, high = min(speeds.values()), max(speeds.values())
    # one condition: the speeds a detection run groups as one (a 30 Hz and a 40 Hz record are two; a motor's slip at
    # 29.5, 30 and 30.6 Hz is one, as the same history is in a detection run)
    if high > low * (1 + SPEED_GROUP):
        shown = ", ".join(f"{p} {s:.2f} Hz" for p, s in speeds.items())
        mesh = all("mesh lines" in how for how in found.values())  # no tacho: the speeds the description's lines show
        raise GearlabInputError(
            f"{records.where} key 'files': the history records run at different speeds ({shown}); "
            f"the gap is diagnosed for one operating condition: give one speed's records (within {SPEED_GROUP:.0%})"
            + (
                f" (or, read off the description's mesh lines, a tooth count differs: gearlab inspect "
                f"{next(iter(speeds))} --gearbox ... says what)"
                if mesh
                else ""
            )
        )
    skipped = len(t.files) - len(files)
    if skipped:
        notes.append(f"{skipped} test file(s) of the [target] are not used: the gap is measured on the history")
    X = np.concatenate(rows).astype(np.float64)
    speed = float(np.average(list(speeds.values()), weights=[len(r) for r in rows]))
    # how the speed was found: the tacho, a declared speed, or the description's mesh lines (each its own), a text
    # of several records said once with their count (3 records' line listed 2 speeds where two texts were alike)
    counts = Counter(found.values())
    how = "; ".join(f"{n} record{'s' * (n > 1)}: {h}" if len(files) > 1 else h for h, n in counts.items())
    from_mesh = t.tacho is None and bool(t.gearbox) and t.speed_hz is None and all(f.speed_hz is None for f in files)
    said = mesh_speed_note(speed, *described) if from_mesh else "the source simulates that speed"
    notes.append(f"target: {len(X)} revolutions of {len(files)} history record(s) at {speed:.3f} Hz ({how}); {said}")
    return X, speed, notes, t.keys_of(f)["fs"] or rec.fs, from_mesh, tuple(len(r) for r in rows)


def mesh_speed_note(target_speed: float, described: float | None, z1: int | None) -> str:
    """What the gap's note says of the speed the source is run at, *target_speed* read off the description's
    mesh lines (no tacho, no declared speed): speed x teeth only, so a speed a whole tooth's share off the
    *described* one is as well another count of a *z1*-tooth pinion, as the structure check's verdict says
    (gap.structure.speed_line; box Q at 41 Hz described at 28 Hz: the note said 'the source simulates that
    speed', the verdict 'or a 40-tooth pinion at 27.67 Hz'). The count is the verdict's to name."""
    from ..gap.structure import SPEED_TOL, _beyond_slip, traded_teeth

    teeth = None
    if described and z1 and abs(target_speed / described - 1.0) > SPEED_TOL:
        teeth = traded_teeth(target_speed, described, z1) or _beyond_slip(target_speed, described, z1)
    if teeth is None:
        return "the source simulates that speed"
    return (
        f"the source simulates that speed, right if the pinion has the described {z1} teeth: without a tacho the "
        f"mesh lines give speed x teeth only, and another pinion at the described {described:.4g} Hz meshes there "
        "too: declare the records' speed ([target] speed) to tell"
    )


def units_warning(channel, X: np.ndarray) -> str:
    """What is said of measured values whose units are unknown (no sensitivity, and a vibration
    *channel* whose name says no unit: recordings.channel_scale), *X* the rows taken as m/s²: what
    fits values in volts and what fits values in m/s² already, and how a file says the latter (a
    channel name ending in the unit: recordings.name_unit; a file whose channels have no names: the
    'unit' key)."""
    return (
        f"WARNING: units unknown: no sensitivity given and vibration channel '{channel}' names no unit; "
        f"the values are taken as m/s² (RMS {float(np.sqrt(np.mean(np.square(X)))):.3g}). Values in volts "
        "need the sensor's sensitivity (e.g. sensitivity = '10 mV/g'; integer counts a gain too); values "
        "already in m/s² need none: a channel name ending in its unit (e.g. 'acc_ms2', 'acc [m/s^2]' or "
        "'acc [g]') says so, or in a file whose channels have no names unit = 'g' (or 'm/s^2'), and this "
        "warning goes"
    )


def units_declared(target: Target) -> bool:
    """A sensitivity or a 'unit' is given, or the vibration channel's name (or the unit the file
    states for it) in the first history file's header says the values are an acceleration already
    (recordings.name_unit: m/s², g; volts without a sensitivity are refused before:
    recordings.channel_scale)."""
    from ..data.recordings import channel_key, name_unit, named, read_header

    first = next(f for f in target.files if f.role == "history")
    keys = target.keys_of(first)  # its own keys, else the [target]'s
    if keys["sensitivity"] is not None or keys["unit"] is not None:
        return True
    header = read_header(first.resolved)
    name = channel_key(keys["vibration"])
    name = named(name, header.channels) if header.indexed else header.resolve(name)  # HDF5 'acc': 'rec/acc'
    said = name_unit(name) or (name_unit(f"[{header.units[name]}]") if name in header.units else None)
    return said is not None and said[0] == "acceleration"


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


def short_history(target, source: DatasetSpec, pair, where: str) -> None:
    """Warn (gearlab validate, a run's start) where the history's records are too short together for the report to
    resolve the orders of stage 1's wheel shaft: MIN_REVOLUTIONS blocks of Z2/gcd(Z1, Z2) consecutive input
    revolutions a set (gap.stats._output_shaft; the source's set is [diagnosis] healthy's), as long as every header
    gives its record's length (a WAV, an HDF5, npz or MAT array with its rate), at its declared speed, else the
    description's. The diagnosis runs without that view, said in a note (a 23/59 stage: 590 revolutions)."""
    import math
    import warnings

    from ..data.recordings import read_header
    from ..gap.stats import MIN_REVOLUTIONS
    from ..gap.structure_later import wheel_shaft
    from ..gearbox.simulation import gearbox_of

    if not isinstance(target, Records):
        return
    per_block = pair.Z2 // math.gcd(pair.Z1, pair.Z2)
    need, t, box = MIN_REVOLUTIONS * per_block, target.target, gearbox_of(source)
    turns, nominal = 0.0, source.speed_hz or (box.speed_hz if box is not None else None)
    for f in target.history:
        keys = t.keys_of(f)
        speed = (f.speed_hz or t.speed_hz if keys.get("tacho") is None else None) or nominal
        seconds = read_header(f.resolved).seconds(str(keys["vibration"]), keys["fs"])
        if seconds is None or not speed:
            return  # a text file's length: the run's note says it
        turns += seconds * speed
    if turns < need:
        warnings.warn(
            f"{where}: the report's orders of the {wheel_shaft(pair)} need {need} consecutive input revolutions a "
            f"set ({MIN_REVOLUTIONS} blocks of Z2/gcd(Z1, Z2) = {per_block}; the source's set: [diagnosis] healthy); "
            f"the history's {len(target.history)} record(s) hold ~{int(turns)} (their headers' lengths at "
            f"{speed:.4g} Hz: {math.ceil(10 * need / speed) / 10:g} s in all needed): the report leaves those orders "
            "out",
            stacklevel=2,
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


def unit_modules(scenario) -> tuple[str, ...]:
    """The gap kind's (ScenarioKind.unit_modules): the fits', and the accuracy's trainings where it runs (a
    measured history has no faults to score: the run skips it)."""
    return FITS + (TRAINS if scenario.spec.accuracy and not isinstance(scenario.spec.target, Records) else ())
