"""`gearlab inspect`: what a recording holds, and whether a gearbox description matches it.

    file ─► channels, sampling rate              the one import path (gearlab.data.recordings)
         ─► input-shaft angle θ(t)               tacho (angle or pulses, N per revolution, on any
                                                 shaft) | speed found from the mesh lines
         ─► order spectrum                        the record upsampled 8 times, resampled at uniform θ
                                                 over its R complete revolutions, Hann window: bins of 1/R order
         ─► lines                                 peaks 15 dB over the running median, refined by a
                                                 parabola through the log amplitudes
         ─► the description's orders tested       mesh order of every stage (the carrier at M, or the
                                                 fundamental of the harmonic family the lines hold);
                                                 each shaft's order from the sidebands around the
                                                 measured mesh (z = M / o)
         ─► TSA per shaft, verdict                "the description matches this recording" or what differs

The description's orders are tested in gearlab.gearbox.match (its tolerances there). Without a tacho the speed
comes from the mesh lines (gearbox.speed.speed_from_mesh).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np

from .charts import envelope
from .data.channel_series import same_length, series
from .data.recordings import (
    Recording,
    angle_tacho,
    channel_listing,
    channel_scale,
    is_rate_or_time,
    level_hint,
    name_unit,
    not_time,
    prefixed,
    pulses_without_tacho,
    read_contents,
    sampling_rate,
    tacho_kind,
)
from .errors import GearlabInputError
from .gap.stats import MIN_REVOLUTIONS
from .gearbox import Gearbox, order_table
from .gearbox.leading import outward_first
from .gearbox.match import check_description, pinion_unconfirmed, tol_mesh, unchecked
from .gearbox.orders import TachoShaft
from .gearbox.pinion_count import (
    EVERY_STAGE,
    SIDEBANDS,
    alternatives_words,
    every_stage_count,
    no_speed_line,
    pinion_evidence,
    shaft_line_count,
    sideband_counts,
)
from .gearbox.speed import (
    DECLARED_RANGE,
    NOMINAL_RANGE,
    SPEED_AGREE,
    TEETH_AGREE,
    THRESHOLD_DB,
    Lines,
    find_lines,
    follow_speed,
    mesh_angle,
    nominal_line,
    settling,
)
from .gearbox.speed_course import speed_course, speed_shift
from .inspect_axes import stronger_axis
from .inspect_tacho import elsewhere_line, marks_line, pulses_how, reversal_notes, shaft_and_marks, speed_channel
from .signals import angle_from_pulses, resample_revolutions, revolution_starts, spectrum, tsa, unwrap_tacho, upsampled
from .signals.checks import fmt_hz
from .signals.fixed_lines import fixed_on_orders, modulation_pairs, modulation_words, smear_merged
from .signals.nonsync import TURNS
from .signals.spikes import acquisition

TWO_PI = 2.0 * np.pi
MAX_TSA_POINTS = 1 << 15


@dataclass(frozen=True)
class InspectOptions:
    vibration: str | None = None
    tacho: str | None = None
    tacho_kind: str = "auto"
    pulses_per_rev: int | None = None  # default: the description's [sensor] pulses_per_rev, else 1
    tacho_shaft: str | None = None  # default: the description's [sensor] tacho, else the input
    speed_hz: float | None = None  # declared input-shaft speed (default: the description's)
    fs: float | None = None
    sensitivity: float | None = None  # V per m/s²
    gain: float | None = None  # V per file unit
    unit: str | None = None  # the vibration's unit where its name and file say none (recordings.UNITS)
    threshold_db: float = THRESHOLD_DB
    check_only: bool = False  # the description's check alone (gearlab score's): no TSA, no fixed-frequency search


# --- the record -------------------------------------------------------------------------------


def read_record(path: str, options: InspectOptions, history: bool = False) -> Recording:
    """The record as *options* name it, scaled by the unit its name or file says with the given gain / sensitivity
    or --unit, else as stored (any column can be inspected); a *history* file refuses the chain given it in one line."""
    if options.pulses_per_rev is not None and options.tacho is None:
        raise pulses_without_tacho(path, "--pulses-per-rev", lambda c: f"--tacho {c}", "--tacho")
    vibration = options.vibration
    if vibration is None:  # the file read to list its channels; a named one is read once (a 60 s take's CSV: 4 s)
        listing, _ = read_contents(path, [])
        channels = [c for c in listing.available if not is_rate_or_time(str(c))]
        left = [c for c in channels if c != options.tacho]
        if len(left) != 1:
            raise GearlabInputError(
                f"{path}: which channel is the vibration? the file has {channel_listing(channels)}; "
                f"expected --vibration {'INDEX (0-based: 0, 1)' if ''.join(map(str, channels)).isdigit() else 'NAME'}"
            )
        vibration = left[0]
    said = name_unit(str(vibration))
    if said is not None and said[0] == "acceleration" and options.sensitivity is not None:
        flag = "--gain" if options.gain is not None else "--sensitivity"  # a gain in g is read as both (calibration)
        raise GearlabInputError(  # the values would come out 1 / sensitivity too large, unsaid
            f"{path}: {flag}: channel '{vibration}' is an acceleration ({said[1]}: its name); expected no {flag}"
        )
    if options.tacho == vibration:  # as a scenario's [target] is refused (parts.measured.target_spec)
        raise GearlabInputError(f"{path}: --tacho: the same column as the vibration ({vibration!r}); expected another")
    roles = {vibration: "vibration", **({} if options.tacho is None else {options.tacho: "tacho"})}
    contents, fmt = read_contents(path, list(roles), roles)
    not_time((vibration, options.tacho), contents.available, path, f"{path}: --vibration/--tacho")
    scale = (options.gain or 1.0) / (options.sensitivity or 1.0)  # both positive when given
    units = f"value x {scale:g} (gain / sensitivity)"
    declared = {"unit": contents.units.get(vibration), "declared": options.unit, "flag": lambda key: f"--{key}"}
    integer = vibration in contents.steps or np.asarray(contents.found[vibration]).dtype.kind in "iu"
    try:  # the unit the name or file says, read as a scenario reads it: an HDF5 'vib_g' was shown in g, unsaid
        scale, units = channel_scale(str(vibration), options.sensitivity, options.gain, str(path), integer, **declared)
    except GearlabInputError as refused:  # any column can be inspected: as stored, and why not in m/s²
        if options.unit is not None or history and (options.sensitivity, options.gain) != (None, None):
            raise  # a history read another way than the take, unsaid, compared nothing (inspect_history)
        units = f"value x {scale:g}, not m/s² ({str(refused).split('; ', 1)[-1]})"
    vib = series(contents.found[vibration], vibration, "vibration", path) * scale
    units += level_hint(units, vib, "--unit {}")
    fs, fs_source = sampling_rate(contents, options.fs, vib.size, path)
    tacho = None
    if options.tacho is not None:
        tacho = series(contents.found[options.tacho], options.tacho, "tacho", path)
        same_length(tacho, options.tacho, "tacho", vib.size, vibration, path)
    channels, left_out = [c for c in contents.available if not is_rate_or_time(str(c))], tuple(contents.warnings)
    return Recording(
        str(path), fmt, channels, vibration, vib, fs, fs_source, options.tacho, tacho, units, warnings=left_out
    )


# --- speed ------------------------------------------------------------------------------------


@dataclass
class Speed:
    mean_hz: float
    source: str
    angle: np.ndarray  # continuous input-shaft angle per sample (rad)
    per_revolution_hz: np.ndarray  # speed of each complete revolution (or of each revolution-long stretch)
    declared_hz: float | None = None
    notes: list[str] = field(default_factory=list)
    settled: str = ""  # what replaced a declared speed the mesh lines do not confirm (the input pinion's sidebands)
    others: list = field(default_factory=list)  # [(z, Hz)]: other pinion counts the mesh line allows (no tacho)
    ends: float = 0.0  # s at either end a take's revolutions leave out: a followed angle's unsettled (settling)

    def describe(self) -> dict:
        s = self.per_revolution_hz
        return {
            "mean_hz": self.mean_hz,
            "min_hz": float(s.min()) if s.size else self.mean_hz,
            "max_hz": float(s.max()) if s.size else self.mean_hz,
            "variation_percent": float(100 * (s.max() - s.min()) / self.mean_hz) if s.size else 0.0,
            "std_percent": float(100 * s.std() / self.mean_hz) if s.size else 0.0,
            "source": self.source,
            "declared_hz": self.declared_hz,
            "notes": self.notes,
        }


def _tacho_speed(rec: Recording, box: Gearbox | None, options: InspectOptions) -> Speed:
    kind = tacho_kind(rec.tacho) if options.tacho_kind == "auto" else options.tacho_kind
    shaft = options.tacho_shaft or (box.sensor.tacho if box else "input")
    ratio = 1.0
    if box is not None:
        ratio = float(TachoShaft.of(box, shaft, "--tacho-shaft").turns)
    ppr = options.pulses_per_rev or (box.sensor.pulses_per_rev if box else 1)
    where = f"{rec.path}: tacho '{rec.tacho_name}'"
    if kind == "angle":
        with prefixed(f"{where} (read as the shaft angle in rad)"):
            theta = unwrap_tacho(angle_tacho(rec.tacho))
        how = f"tacho '{rec.tacho_name}' (shaft angle) on the {shaft} shaft"
    else:
        with prefixed(f"{where} (read as {ppr} pulse(s) per revolution)"), speed_channel(rec.tacho):
            theta = angle_from_pulses(rec.tacho, rec.fs, smooth=ratio < 1, marks=ppr) / ppr
        how = pulses_how(rec, ppr, shaft)
    theta = theta / ratio  # the input shaft's angle
    turns = (theta[-1] - theta[0]) / TWO_PI
    if turns <= 0:
        raise GearlabInputError(f"{where}: the shaft angle does not advance; expected a turning shaft")
    mean = turns * rec.fs / (theta.size - 1)
    with prefixed(where):
        starts = revolution_starts(theta) if turns >= 2 else np.zeros(0)
    per_rev = rec.fs / np.diff(starts) if starts.size >= 2 else np.zeros(0)
    return Speed(mean, how, theta, per_rev, notes=reversal_notes(rec.signal, rec.fs, theta))  # stops, turns back?


def _found_speed(rec: Recording, box: Gearbox | None, options: InspectOptions) -> Speed:
    """The input speed of a record without a tacho: declared, refined by the mesh lines; or found from the mesh
    lines alone; then followed through the record on the phase of a mesh harmonic (gearbox.speed.follow_speed)."""
    declared = options.speed_hz or (box.speed_hz if box else None)
    n = rec.signal.size
    if box is None:
        if declared is None:
            raise GearlabInputError(
                f"{rec.path}: no tacho and no speed: give --tacho NAME, --speed (e.g. '25 Hz'), or --gearbox "
                "to find the speed from its mesh orders"
            )
        theta = TWO_PI * declared * np.arange(n) / rec.fs
        return Speed(declared, "declared", theta, np.zeros(0), declared)
    theta, f, how, note = follow_speed(
        rec.signal, rec.fs, box, declared, f"{rec.path}: vibration '{rec.vibration}'", options.threshold_db
    )
    if theta is None:
        speed = Speed(f, how, *_along_course(rec, f), declared)
    else:
        starts = revolution_starts(theta - theta[0])
        speed = Speed(f, how, theta, rec.fs / np.diff(starts), declared, ends=settling(box, f))
    if note:
        speed.notes.append(note)
    if (shift := speed_shift(rec.signal, rec.fs)) is not None:  # a run-up smears every line at any one speed
        said = f"the spectrum's lines move {100 * (shift - 1):+.0f} % from the record's first sixteenth to its last: "
        said += "its speed varies (a run-up or coast-down?): give its tacho (--tacho) or inspect a steady take"
        speed.notes[:] = [said] if speed.source == "declared" else [*speed.notes, said]  # no line fits: the reason
    return speed


def _along_course(rec: Recording, f: float) -> tuple[np.ndarray, np.ndarray]:
    """(input angle per sample, speed per revolution) at the mean speed *f*, no mesh phase followed: along the speed's
    course (gearbox.speed_course), else constant (read constant, a 2 % ramp's input sidebands were lost)."""
    course = speed_course(rec.signal, rec.fs)
    if course is None:
        return TWO_PI * f * np.arange(rec.signal.size) / rec.fs, np.zeros(0)
    theta = TWO_PI * f * (np.cumsum(course) - course[0]) / rec.fs
    return theta, rec.fs / np.diff(revolution_starts(theta))


def measured_speed(rec: Recording, box: Gearbox | None, options: InspectOptions) -> Speed:
    """The input speed from the tacho, else declared or found from the mesh lines (_found_speed)."""
    return _tacho_speed(rec, box, options) if rec.tacho is not None else _found_speed(rec, box, options)


# --- the order spectrum and the description's orders ----------------------------------------------


def order_spectrum(rec: Recording, speed: Speed, fine: tuple | None = None):
    """(orders, amplitude, revolutions, points per revolution) of the record at uniform input angle
    (*fine*: the record and its angle upsampled, :func:`upsampled`)."""
    signal, angle = fine or (rec.signal, speed.angle)
    per_rev = rec.fs / speed.mean_hz
    points = int(min(1 << 14, max(64, 2 ** math.ceil(math.log2(per_rev)))))
    with prefixed(f"{rec.path}: vibration '{rec.vibration}'"):
        revs = resample_revolutions(signal, angle, points=points)
    orders, amp = spectrum(revs.reshape(-1), points)  # "Hz" per revolution: orders
    return orders, amp, revs.shape[0], points


def shaft_tsa(rec: Recording, speed: Speed, box: Gearbox | None, fine: tuple | None = None) -> list[dict]:
    """TSA of the record over each shaft's own revolutions: revolutions averaged, RMS, its strongest
    orders (*fine*: the record and its angle upsampled, :func:`upsampled`)."""
    signal, angle = fine or (rec.signal, speed.angle)
    if box is None:
        names, orders = ("input",), (1.0,)
    else:
        table = order_table(box)
        names, orders = table.shafts, tuple(float(o) for o in table.shaft_orders)
    out = []
    for name, o in zip(names, orders):
        per_rev = rec.fs / (speed.mean_hz * o)
        points = int(min(MAX_TSA_POINTS, max(64, 2 ** math.ceil(math.log2(per_rev)))))
        theta = angle * o
        count = int((theta[-1] - theta[0]) // TWO_PI) - 1
        if count < 2:
            out.append({"shaft": name, "revolutions": max(count, 0), "note": "fewer than 2 complete revolutions"})
            continue
        avg = tsa(resample_revolutions(signal, theta, points=points))
        amp = np.abs(np.fft.rfft(avg - avg.mean())) * 2 / points
        top = np.argsort(-amp)[:3]
        # over a few turns the other shafts' lines stay in the average (a 1 s take's output TSA of 2 turns: 'strongest
        # orders 378, 144, 58', the input's mesh first); as few as the which-gear check refuses (signals.nonsync.TURNS)
        few = {"note": f"{count} turns: too few to average out the other shafts ({TURNS} needed)"}
        out.append(
            {
                "shaft": name,
                "revolutions": count,
                "rms": float(np.sqrt(np.mean((avg - avg.mean()) ** 2))),
                "share_of_signal_rms": float(np.std(avg) / max(np.std(rec.signal), 1e-300)),
                "strongest_orders": [int(t) for t in top],
                "tsa": avg,
            }
            | (few if count < TURNS else {})
        )
    return out


@dataclass
class Reading:
    """The record read at uniform input angle at one speed: its order spectrum and the lines in it."""

    fine: tuple  # (signal, input angle) upsampled
    orders: np.ndarray
    amp: np.ndarray
    revolutions: int
    points: int
    top: float  # the highest order read (90 % of the Nyquist order)
    lines: Lines


def read_orders(rec: Recording, speed: Speed, threshold_db: float) -> Reading:
    up = upsampled(rec.signal)
    fine = (up.signal, up.at(speed.angle))
    orders, amp, revolutions, points = order_spectrum(rec, speed, fine)
    top = min(points / 2, rec.fs / (2 * speed.mean_hz)) * 0.9
    lines = find_lines(orders, amp, threshold_db, 1.5 / revolutions, top)
    return Reading(fine, orders, amp, revolutions, points, top, lines)


def unconfirmed(rec: Recording, box: Gearbox | None, speed: Speed) -> bool:
    """Whether *speed* is a declared one the mesh lines of a record without a tacho do not confirm."""
    return box is not None and rec.tacho is None and speed.source == "declared" and bool(speed.notes)


def settle_speed(
    rec: Recording, box: Gearbox | None, options: InspectOptions, speed: Speed | None = None
) -> tuple[Speed, Reading, str | None]:
    """(the speed inspect reads every order at, the record read at it, None; or, where no speed can be
    confirmed, the declared one, the record read at it and one line saying so). Without a tacho a declared
    speed the mesh lines do not confirm (gearbox.speed's note) is replaced by the speed the input pinion's
    sidebands show: their spacing is the input shaft's frequency whatever the speed read at, so the carrier
    over that spacing is the pinion's count z (gearbox.speed.sideband_teeth, within TEETH_AGREE of a whole
    number) and the speed is the mesh line's frequency / z, followed on the mesh's phase (a 33-tooth
    pinion at 1455 rpm, described 34 at 1500 rpm, was read at 1500 rpm in every row: 'mesh order 32
    measured, a 32-tooth pinion'), else the count every stage's lines show (every_stage_count), else not confirmed."""
    if speed is None:
        speed = measured_speed(rec, box, options)
    reading = read_orders(rec, speed, options.threshold_db)
    if not unconfirmed(rec, box, speed):
        return _by_input_lines(rec, box, options, speed, reading) + (None,)
    f0, lines, stage = speed.mean_hz, reading.lines, order_table(box).stages[0]
    in_hz = Lines(lines.at * f0, lines.amp, lines.db)  # read at a constant speed: order x speed is Hz
    mesh_hz, counts = sideband_counts(in_hz, stage, f0, f0 / reading.revolutions)
    said, df = box.stages[0].pinion.z, f0 / reading.revolutions
    if not counts and mesh_hz and (z := shaft_line_count(in_hz, mesh_hz, f0, df, order_table(box), said)):
        counts = [(mesh_hz, z)]  # no sideband, but a line at one allowed count's shaft frequency
    found = every_stage_count(lines, order_table(box), said, df / f0)  # at its line, or at the declared speed
    every = [(y * f0, z, EVERY_STAGE) for x, z in found for y in (x, z)]
    for line, count, *by in [*counts[:3], *every]:
        if (found := _read_at_count(rec, box, options, speed, line, count, *by)) is not None:
            if count == said:  # the described count, at a speed its shaft's line shows
                how = f"from the mesh line at {fmt_hz(line)} and the input shaft's line"
                found[0].source, found[0].settled, found[0].notes = how, "", []
            return found + (None,)
    return speed, reading, _elsewhere(in_hz, order_table(box), f0, df) or no_speed_line(mesh_hz, f0, bool(counts))


def _elsewhere(in_hz: Lines, table, declared: float, df: float) -> str | None:
    """Where every described mesh and its 2nd harmonic has a line at one speed far from the *declared*
    one (lines *in_hz*, bin *df*), that speed in one line: a 27/61 + 18/49 box at 41 Hz described at 28 Hz
    was told 'the mesh at 652.4 Hz is a 22-tooth pinion's at 29.65 Hz, ...' (its 2nd M2 near the declared
    M1), when the description is right and only the speed is not (outside check D). None: no such speed. A speed
    of which the record holds under MIN_REVOLUTIONS turns (1/*df* s long) is none: a stepped 106/127 take's mesh
    smeared, its output shaft's line and 2nd harmonic were a 106-tooth mesh's at 0.172 Hz, one turn a record."""
    meshes = [float(s.mesh) for s in table.stages]
    strong = in_hz.at[np.argsort(-in_hz.amp)[:8]]
    hm = np.array([h * m for m in meshes for h in (1, 2)])
    fits = []  # (the lines' amplitude, the speed) of each speed whose lines every mesh has
    for f in sorted({float(x / (h * m)) for x in strong for m in meshes for h in (1, 2)}):
        found = [in_hz.near(x * f, max(2.5 * df, 0.002 * f * max(meshes))) for x in hm]
        # one stage: a speed within the nominal range may be a pinion a few teeth off (the lines' own words)
        far = NOMINAL_RANGE if len(meshes) == 1 else 2 * DECLARED_RANGE
        if abs(f / declared - 1) > far and f >= MIN_REVOLUTIONS * df and None not in found:
            at = in_hz.at[np.array(found)]
            fits.append((float(np.sum(in_hz.amp[np.array(found)])), float(np.sum(at * hm) / np.sum(hm * hm))))
    if not fits:
        return None
    # the strongest: a 29/73 box's shaft line and its 2nd harmonic are a 29-tooth mesh's at 1/29 of its speed, the
    # first of the speeds tried (24.42 Hz, given 584 rpm, was told '0.8402 Hz'); its mesh lines are the strongest
    f = max(fits)[1]
    return (
        f"every described mesh has its lines at {fmt_hz(f)} (and its 2nd harmonic): the record runs "
        f"at {fmt_hz(f)}, not {fmt_hz(declared)}? (--speed '{fmt_hz(f)}'; a scenario's [target] speed)"
    )


def _by_input_lines(rec: Recording, box: Gearbox | None, options: InspectOptions, speed: Speed, reading: Reading):
    """(speed, reading) of a record without a tacho whose speed the mesh lines gave: where the input shaft's
    lines (sidebands, shaft line) show another pinion count, read at its speed (26 teeth at 24.09 Hz mesh
    where 25 at 25.06 Hz do: the search took the nominal speed's); where they show none, the other counts
    the mesh line allows within the nominal range are kept on the speed (speed.others): ambiguous."""
    if box is None or rec.tacho is not None:
        return speed, reading
    said, table = box.stages[0].pinion.z, order_table(box)
    # no speed declared: the counts within the nominal range of the speed found, only one the input shaft's lines show
    # acted on (17/53 + 22/67 + 29/83 described 18: read at 33.06 Hz, 'shows 17.0 teeth'; the input turns at 35 Hz)
    mesh_hz, seen, others = pinion_evidence(
        reading.lines, speed.mean_hz, reading.revolutions, table, said, speed.declared_hz or speed.mean_hz
    )
    if seen is None:
        speed.others = others if speed.declared_hz else []
    elif seen != said and (found := _read_at_count(rec, box, options, speed, mesh_hz, seen)) is not None:
        return found
    return speed, reading


def _read_at_count(rec, box: Gearbox, options, speed: Speed, mesh_hz: float, count: int, by: str = SIDEBANDS):
    """(the speed at which *mesh_hz* is a *count*-tooth input pinion's mesh, followed on its phase; the record
    read at it), or None where, read at it, the mesh is not at the count's whole order or the input
    shaft's sidebands not at order 1 (a line split by a swinging speed, read at the declared one, gave 29
    for a 28-tooth pinion: mesh order 28.97, the input at 1.034)."""
    described, f = box.stages[0].pinion.z, mesh_hz / count
    # the stage-1 mesh's phase, followed as the described pinion's at the speed that puts it on the line
    theta = mesh_angle(rec.signal, rec.fs, box, mesh_hz / described, speed_course(rec.signal, rec.fs))
    if theta is not None:
        theta = theta * described / count
        mean = (theta[-1] - theta[0]) * rec.fs / (TWO_PI * (theta.size - 1))
        theta = theta if abs(mean / f - 1) <= SPEED_AGREE else None
    if theta is None:
        theta, per_rev = _along_course(rec, f)
    else:
        f, per_rev = mean, rec.fs / np.diff(revolution_starts(theta - theta[0]))
    # the search's speed fitted the described count's mesh, not the shaft's lines
    why = f"not the {fmt_hz(speed.mean_hz)} a {described}-tooth pinion would turn at"
    if speed.source == "declared":
        why = f"the declared {fmt_hz(speed.declared_hz)} not confirmed by the mesh lines"
    how = f"from {by} (a {count}-tooth pinion meshing at {fmt_hz(mesh_hz)}), {why}"
    settled = Speed(f, how, theta, per_rev, speed.declared_hz, list(speed.notes), settled=by)
    at = read_orders(rec, settled, options.threshold_db)
    first = check_description(at.lines, box, at.revolutions, False)["stages"][0]
    off_mesh = abs(first.get("measured_order", -1.0) - count) > tol_mesh(count, 1.0 / at.revolutions)
    off_shaft = abs(first.get("z1_seen", float(count)) - count) > max(TEETH_AGREE, first.get("z1_resolution", 0.0))
    return None if off_mesh or off_shaft else (settled, at)


def inspect_record(path: str, box: Gearbox | None, options: InspectOptions, read: tuple = (), kept=None) -> dict:
    """Everything `gearlab inspect` shows, as plain numbers (the TSA curves as arrays). *read*: (the Recording, its
    flaws) as cut_recording read it, drift out (gearlab score: a 60 s CSV read once, not twice: 9 s of CPU). *kept*: a
    list given the record as read and the speed --history cuts its revolutions at (None where its drift taken out
    changed the signal): localisation reads and follows neither again (a take without a tacho: its speed's search)."""
    rec, flaws = read or (read_record(path, options), ())
    stored = rec.signal
    if not read:  # read as cut_recording reads it: a drift out, said
        with prefixed(f"{rec.path}: vibration '{rec.vibration}'"):
            rec.signal, flaws = acquisition(rec.signal, rec.fs)
    speed, reading, no_speed = settle_speed(rec, box, options, measured := measured_speed(rec, box, options))
    if kept is not None:  # input_revolutions' speed: the measured one, settled where the lines do not confirm it
        settled = rec.signal is stored and (speed if unconfirmed(rec, box, measured) else measured)
        kept[:] = replace(rec, signal=stored), settled or None
    fine, orders, amp, top = reading.fine, reading.orders, reading.amp, reading.top
    revolutions, lines = reading.revolutions, reading.lines
    report = {
        "file": rec.path,
        "format": rec.format,
        "channels": rec.channels,
        "vibration": rec.vibration,
        "tacho": rec.tacho_name,
        "fs_hz": rec.fs,
        "fs_source": rec.fs_source,
        "samples": int(rec.signal.size),
        "duration_s": rec.signal.size / rec.fs,
        "rms": float(np.std(rec.signal)),
        "units": rec.units,
        "speed": speed.describe(),
        "revolutions": revolutions,
        "order_resolution": 1.0 / revolutions,
        "max_order": top,
        "lines": [
            {"order": float(a), "hz": float(a * speed.mean_hz), "amplitude": float(v), "db_over_floor": float(d)}
            for a, v, d in zip(lines.at[:12], lines.amp[:12], lines.db[:12])
        ],
        "spectrum": (orders, amp),
        "tsa": [] if options.check_only else shaft_tsa(rec, speed, box, fine),
        # clipped at the logger's or the sensor's range (a knock over a WAV's full scale), a dropout, a drift
        "flaws": list(flaws),
        "left_out": list(rec.warnings),  # by the reader: a logger's footer under the rows
    }
    # a description's (or --speed's) speed is nominal: the measured one beside it, as information
    nominal, said = (options.speed_hz, "--speed") if options.speed_hz else (box and box.speed_hz, "[operation] speed")
    if nominal and speed.source != "declared":
        report["speed"]["nominal"] = {
            "hz": nominal,
            "given": said,
            "percent": 100 * (speed.mean_hz / nominal - 1),
            "line": nominal_line(speed.mean_hz, nominal, said, speed.per_revolution_hz),
        }
    if box is not None:
        tacho_shaft = options.tacho_shaft or box.sensor.tacho
        on_input = rec.tacho is not None and tacho_shaft == box.shafts[0]
        report["gearbox"] = box.name
        report["order_table"] = order_table(box).describe(speed.mean_hz)
        report["axis"] = None if options.check_only else stronger_axis(rec, speed.angle, speed.mean_hz, box)
        report["gears"] = gears(box)
        # the speed every row below is read at, and where it came from (a declared one the lines do not
        # confirm: said so, with the counts and speeds the mesh line allows, *no_speed*)
        at = {"speed_hz": speed.mean_hz, "speed_source": speed.source}
        if no_speed:
            at.update(speed_source=f"declared, not confirmed: {no_speed}", speed_confirmed=False)
        read_on = None if rec.tacho is None else box.shaft_index(tacho_shaft, "--tacho-shaft")
        report["check"] = check = at | check_description(lines, box, revolutions, on_input, read_on)
        # a fixed frequency on a shaft's order (box B's 50 Hz hum: its input's 2nd order at 25 Hz), or steady alike
        listed, take, bin_ = check["unexplained"], (rec.signal, rec.fs, speed.angle), 1.0 / revolutions
        if not options.check_only:  # lines no difference rests on: not for a check alone (40 s of a 60 s take's 68)
            listed += fixed_on_orders(listed, lines, order_table(box), take, speed.mean_hz, bin_)
        swing = report["speed"]["variation_percent"] / 100  # a line in a stronger one's smear is its skirt, not a line
        check["unexplained"] = modulation_pairs(smear_merged(listed, lines, swing, bin_), lines, bin_, order_table(box))
        differences = check["differences"]
        elsewhere = elsewhere_line(lines, box, tacho_shaft, speed, revolutions) if rec.tacho is not None else None
        misread = [elsewhere] if elsewhere else []
        pulses = rec.tacho is not None and (options.tacho_kind == "pulses" or tacho_kind(rec.tacho) == "pulses")
        if not elsewhere and pulses:
            # on any shaft: a wrong count of marks scales every order alike (a two-stage reducer's intermediate
            # tacho of 2 marks a turn read as 1 'matched': its mesh harmonics on every described order)
            ppr = options.pulses_per_rev or box.sensor.pulses_per_rev
            ratio = speed.mean_hz / box.speed_hz if box.speed_hz else None
            misread = marks_line(check, lines, ppr, 1.0 / revolutions, ratio)
            misread = misread or shaft_and_marks(check, box, tacho_shaft, ppr, ratio, 1.0 / revolutions, lines)
        if misread:
            # every order reads f x its own: the rows read at that speed follow from it, not from the gears (a
            # 19/47 + 29/71 reducer's output tacho read as the input's was also told 'a 115-tooth pinion on the
            # input shaft?', its 2-mark tacho read as 1 'the wheel on the output shaft shows 98.0 teeth')
            differences[:] = misread
            check["tacho_misread"] = True  # what differs is the tacho's reading, not the gears (score reads it so)
        if read_on and not misread:  # the tacho read as said: its shaft's gears first, then outward
            check["outward"] = outward_first(check, box, read_on)
        if read_on and differences and "nominal" in report["speed"]:
            # a later shaft's tacho gives the input's speed through the described gears: a wrong count moves it (a
            # 17/47 + 29/66 + 23/59 description of a 67-tooth wheel read 1.5 % slow, 'slip under load')
            said = report["speed"]["nominal"]["line"].split(" %, ")[0]
            words = f"read from the {tacho_shaft} tacho through the described gears and marks: what differs (below) "
            words += "moves it"
            report["speed"]["nominal"]["line"] = f"{said} %, {words}"
        # the speed the rows after the speed's line read at, where not the declared one (none declared: the speed found)
        if differences and ((speed.settled and speed.declared_hz) or no_speed):
            said = f"the speed {speed.settled} show" if speed.settled else "declared, not confirmed"
            differences[0] = f"at {fmt_hz(speed.mean_hz)} ({said}): {differences[0]}"
        if rec.tacho is None and (speed.source == "declared" or speed.settled):
            # a declared speed the mesh lines do not confirm (gearbox.speed's note: no mesh line within
            # ±1 %, or another speed fits them better): read at it, a weak line can pass as the described
            # mesh (a 29/102 record described with 27 teeth at 19.81 Hz 'matched'), and what else is read
            # there comes after it (a 19/58 + 25/67 fan described with 18 teeth was told 'stage 2: no
            # line at mesh order 7.759', the first stage's smeared mesh unsaid)
            differences[:0] = [_speed_line(speed.declared_hz, n, no_speed) for n in speed.notes]
        if differences:  # a line 'not a gear order' by the described orders may be one by the measured ones
            off_description(check, bin_)
        found = speed.mean_hz if rec.tacho is None and speed.declared_hz is None else None
        check["unchecked"] = unchecked(check, box, found)
        # no speed: the pinion's tooth count is not confirmed, 'matches' neither true nor false (None)
        pinion = None if differences else pinion_unconfirmed(check, box, found)
        report["matches"] = None if pinion else not differences
        # no tacho, no input-shaft line: other counts at other speeds in the nominal range give the same mesh
        check["ambiguous"] = [{"pinion_teeth": z, "speed_hz": hz} for z, hz in speed.others]
        name, rest = box.name, [u for u in check["unchecked"] if u != pinion]
        if pinion:
            head = f"the description {name!r} cannot be confirmed without a tacho or the speed: {pinion}"
        elif speed.others:
            head = f"the description {name!r} is consistent with this recording if the input turns at "
            head += f"{fmt_hz(speed.mean_hz)}: {alternatives_words(speed.others, table=order_table(box))}"
        else:
            head = f"the description {name!r} matches this recording"
        report["verdict"] = (
            f"the description {name!r} differs: " + "; ".join(differences)
            if differences
            else head + (f"; not checked: {'; '.join(rest)}" if rest else "")
        )
    return report


SPEED_OR_TEETH = ": the speed or a tooth count differs"


def off_description(check: dict, bin_: float) -> None:
    """Where the description differs, relabel *check*'s lines at no described shaft's harmonic (not those a clock's
    phase named fixed): a line at a measured mesh order's harmonic +- 0-3 x a measured shaft order gets 'measured_as'
    (a gear line, 'not_an_order' False), any other 'not_an_order' None: by the described orders alone a 21-tooth
    pinion described 22 had its wheel's sidebands 21 +- 21/71 called 'not a gear order (... mains ...)'."""
    meshes = [
        (f"stage {s['stage']}'s measured mesh", s["measured_order"]) for s in check["stages"] if s.get("measured_order")
    ]
    shafts = [(s["shaft"], s["measured_order"] or s["expected_order"]) for s in check["shafts"]]
    for line in check["unexplained"]:
        if not line.get("not_an_order") or "shaft_harmonic" in line:
            continue
        x, tol, said = line["order"], tol_mesh(line["order"], bin_), None
        for (mesh, m), (shaft, o), k in itertools.product([("", 0.0)] + meshes, shafts, (0, 1, -1, 2, -2, 3, -3)):
            h = max(0, round((x - k * o) / m)) if m else 0
            if said is None and (h or k > 0) and abs(x - h * m - k * o) <= tol:
                nth = f"{f'{h} x ' if h > 1 else ''}{mesh} order {m:.4g}" if h else ""
                side = f" {'+-'[k < 0]} {abs(k)} x" if h else f"{k} x"
                said = nth + (f"{side} the {shaft} shaft's measured order {o:.4g}" if k else "")
        line["not_an_order"], line["measured_as"] = (None, None) if said is None else (False, said)


def _speed_line(declared: float, note: str, no_speed: str | None) -> str:
    """The verdict's line for a declared speed the mesh lines do not confirm (*note*: the speed search's),
    with *no_speed* (no sideband confirms a speed: _no_speed_line) before its end."""
    body = note[: -len(SPEED_OR_TEETH)] if note.endswith(SPEED_OR_TEETH) else note
    end = "" if "differs" in body else SPEED_OR_TEETH
    return f"speed {fmt_hz(declared)} declared, but {body}" + (f"; {no_speed}" if no_speed else "") + end


def gears(box: Gearbox) -> list[dict]:
    """The description's gears by the names a scenario's 'faults' key takes ("chip@input pinion"), with
    their tip diameter d_a and the tip keys a gear gives itself ('tip': addendum, dedendum, tip_diameter)."""
    from .data.placement import gear_name
    from .gearbox.checks import gear_tip

    out = []
    for st in box.stages:
        for g in ("pinion", "wheel"):
            spec = getattr(st, g)
            own = {k: getattr(spec, k) for k in ("addendum", "dedendum") if getattr(spec, k) is not None}
            if spec.tip_diameter is not None:
                own["tip_diameter_mm"] = round(spec.tip_diameter * 1e3, 6)
            out.append(
                {
                    "name": gear_name(st.index, g, box.shafts),
                    "stage": st.index,
                    "gear": g,
                    "teeth": spec.z,
                    "tip_diameter_mm": gear_tip(st, spec) * 1e3,
                    "tip": own,
                }
            )
    return out


def _hunting_words(table: dict) -> str:
    """The order table's tooth-pair periods in one line: each stage's, and the whole train's."""
    stages = []
    for s in table["stages"]:
        g = s["assembly_phase_factor"]
        why = "a hunting tooth pair" if g == 1 else f"common factor {g}: {g} assembly phases"
        turns = s["hunting_tooth_input_revolutions"]
        stages.append(f"stage {s['stage']} ({s['z1']}/{s['z2']}) every {turns:.6g} input turns ({why})")
    period = table["train_period_input_revolutions"]
    return f"a tooth pair meets again: {'; '.join(stages)}; every shaft back in phase every {period} input turns"


def _tip_words(gear: dict) -> str:
    """'; h_a* = 0.8, d_a = 191.5 mm' for a gear with a tip of its own, else ''."""
    own = gear.get("tip") or {}
    words = [f"{sym} = {own[k]:g}" for k, sym in (("addendum", "h_a*"), ("dedendum", "h_f*")) if k in own]
    if own:
        words.append(f"d_a = {gear['tip_diameter_mm']:.4g} mm")
    return "; " + ", ".join(words) if words else ""


# --- the terminal ----------------------------------------------------------------------------------


def _unexplained_words(line: dict, f0: float) -> str:
    """A line the description does not explain, in Hz first where it is a strong line at no shaft's whole order (a
    fixed frequency such as a mains hum, or a bearing's; gearbox.match.shaft_harmonic), else as the order it is."""
    o, hz, db = line["order"], line["order"] * f0, line["db_over_floor"]
    shaft, h = line.get("shaft_harmonic") or ("", 0)
    if line.get("measured_as"):  # the description differs: a gear line by the measured orders
        said = f"{line['measured_as']} (a gear line at the measured orders"
        return f"input order {o:.4g} = {said}; {hz:.5g} Hz, {db:.0f} dB)"
    if line.get("modulation"):  # a pair about a stronger line (fixed_lines.modulation_pairs): its modulation
        (c, d), why = line["modulation"], modulation_words(line)
        return f"order {o:.4g} ({d:.3g} orders ({d * f0:.3g} Hz) off {c:.4g}, {why}; {db:.0f} dB)"
    if "measured_as" in line:  # ... or none of theirs either: what it is, the description as written cannot tell
        why = "no described shaft's harmonic: not explained by the description as written, which differs"
        return f"{hz:.5g} Hz (input order {o:.4g}, {why}; {db:.0f} dB)"
    nth = f"the {shaft} shaft's {({1: '1st', 2: '2nd', 3: '3rd'}).get(h, f'{h}th')} harmonic"
    if shaft and line["not_an_order"] is None:  # fixed_on_orders: a speed too steady tells neither
        steady = "the take's speed too steady to tell them apart; a take at another speed tells them apart"
        return f"order {o:.4g} = {hz:.5g} Hz: {nth}, or mains at this speed ({steady}; {db:.0f} dB)"
    if shaft:
        why = f"on {nth}, but its phase follows the clock, not the shaft, as the speed varies: not a gear order "
        return f"{hz:.5g} Hz (input order {o:.4g}, {why}(a fixed frequency such as mains, or a bearing's); {db:.0f} dB)"
    if line.get("not_an_order"):
        why = "no shaft's harmonic: not a gear order (a fixed frequency such as mains, or a bearing's)"
        return f"{hz:.5g} Hz (input order {o:.4g}, {why}; {db:.0f} dB)"
    return f"order {o:.4g} ({hz:.5g} Hz, {db:.0f} dB)"


def render(report: dict, console, width: int = 100) -> None:
    """The report in the terminal: tables (rich) and the order spectrum (plotext)."""
    import plotext
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    sp = report["speed"]
    console.print(
        f"[bold]{escape(report['file'])}[/bold] ({report['format']}): {report['samples']} samples at "
        f"{fmt_hz(report['fs_hz'])} ({escape(report['fs_source'])}), {report['duration_s']:.4g} s; channels: "
        f"{escape(', '.join(map(str, report['channels'])))}; vibration {escape(repr(report['vibration']))}"
        # repr before escape: repr doubles escape's backslash, and '[m/s²]' would be read as markup
        + (f", tacho {escape(repr(report['tacho']))}" if report["tacho"] else "")
        + f"; values: {escape(report['units'])}"
    )
    console.print(
        f"speed {sp['mean_hz']:.5g} Hz ({sp['mean_hz'] * 60:.5g} rpm) {escape(sp['source'])}; "
        f"{sp['min_hz']:.5g} .. {sp['max_hz']:.5g} Hz (variation {sp['variation_percent']:.3g} %); "
        f"{report['revolutions']} input revolutions, order resolution {report['order_resolution']:.3g}"
    )
    if "nominal" in sp:
        console.print(f"[dim]{escape(sp['nominal']['line'])}[/dim]")
    notes = [f"vibration {report['vibration']!r}: {c}" for c in report.get("flaws", ())]
    for note in sp["notes"] + [f"{report['file']}: {w}" for w in report.get("left_out", ())] + notes:
        console.print(f"[yellow]note:[/yellow] {escape(note)}")
    orders, amp = report["spectrum"]
    top = report["max_order"]
    marks = []
    check = report.get("check", {})
    at = f" at {fmt_hz(check['speed_hz'])}" if check.get("speed_hz") else ""
    at += " (declared, not confirmed)" if check.get("speed_confirmed") is False else ""
    if "check" in report:
        marks = [s["expected_order"] for s in report["check"]["stages"]]
        # to the third mesh harmonic, or further where the strongest lines are (harmonics 4-10 of a mesh)
        strongest = max((line["order"] for line in report["lines"][:5]), default=0.0)
        top = min(top, max(3.3 * max(marks), 1.1 * strongest))
    keep = (orders > 0) & (orders <= top)
    x, y = envelope(orders[keep], 20 * np.log10(np.maximum(amp[keep], 1e-12)), 2 * width)  # braille: 2 dots a cell
    plotext.clf()
    plotext.plotsize(width, 18)
    plotext.theme("pro")
    plotext.plot(x.tolist(), y.tolist(), marker="braille")
    for m in marks:
        plotext.vline(m, "red")
    plotext.title(f"order spectrum (dB){at}; red: the description's mesh orders")
    plotext.xlabel("input-shaft order")
    console.print(Text.from_ansi(plotext.build()))

    if "gears" in report:
        named = ", ".join(f"{g['name']} {g['teeth']}T (stage {g['stage']}{_tip_words(g)})" for g in report["gears"])
        first = report["gears"][0]["name"]
        console.print(escape(f'gears, as a scenario\'s faults key names them (e.g. "chip@{first}"): {named}'))
    if "order_table" in report:
        console.print(escape(_hunting_words(report["order_table"])))
    if check.get("speed_confirmed") is False:
        console.print(f"[yellow]speed {escape(check['speed_source'])}[/yellow]")
    if check:
        t = Table(title=f"gearbox {report['gearbox']!r}: mesh orders{at}")
        for col in ("stage", "z1/z2", "expected", "measured", "error", "dB over floor", "z seen", "status"):
            t.add_column(col)
        for s in check["stages"]:
            seen = " / ".join(f"{s[k]:.2f}" for k in ("z1_seen", "z2_seen") if k in s) or "-"
            t.add_row(
                str(s["stage"]),
                f"{s['z1']}/{s['z2']}",
                f"{s['expected_order']:.4f}",
                f"{s['measured_order']:.4f}" if "measured_order" in s else "-",
                f"{s['error_orders']:+.4f}" if "error_orders" in s else "-",
                f"{s['db_over_floor']:.1f}" if "db_over_floor" in s else "-",
                seen,
                "[green]ok[/green]" if s["matched"] else "[red]differs[/red]",
            )
        console.print(t)
        t = Table(title=f"shaft orders{at}")
        for col in ("shaft", "expected", "measured", "from", "status"):
            t.add_column(col)
        for s in check["shafts"]:
            status = {True: "[green]ok[/green]", False: "[red]differs[/red]", None: "-"}[s["matched"]]
            measured = "-" if s["measured_order"] is None else f"{s['measured_order']:.5f}"
            t.add_row(s["shaft"], f"{s['expected_order']:.5f}", measured, escape(s["source"]), status)
        console.print(t)
        if check["unexplained"]:
            console.print(
                "lines the description does not explain: "
                + ", ".join(_unexplained_words(u, sp["mean_hz"]) for u in check["unexplained"])
            )
    t = Table(title=f"time-synchronous average per shaft{at}")
    for col in ("shaft", "revolutions", "TSA rms", "share of signal rms", "strongest orders"):
        t.add_column(col)
    for s in report["tsa"]:
        if "rms" not in s:
            t.add_row(s["shaft"], str(s["revolutions"]), "-", "-", s.get("note", ""))
            continue
        t.add_row(
            s["shaft"],
            str(s["revolutions"]),
            f"{s['rms']:.4g}",
            f"{s['share_of_signal_rms']:.3f}",
            ", ".join(map(str, s["strongest_orders"])) + (f" ({s['note']})" if "note" in s else ""),
        )
    console.print(t)
    if "verdict" in report:
        said = None if check.get("ambiguous") and report["matches"] else report["matches"]  # 'consistent if'
        colour = {True: "green", None: "yellow"}.get(said, "red")
        console.print(f"[bold {colour}]{escape(report['verdict'])}[/bold {colour}]")
    if report.get("axis"):  # a triaxial sensor read on its axial axis
        console.print(f"[yellow]note:[/yellow] {escape(report['axis']['line'])}")
