"""`gearlab inspect --history`: which shaft and gear a record's change lies on, against healthy records
of the same gearbox.

    record, history files ─► complete input revolutions     each file read as inspect reads it (tacho or
                                                             found speed), cut as a detection's take is
                          ─► localised change per shaft      data.which_gear: the one decision a detection
                                                             run and `gearlab score` make
                          ─► non-synchronous change          signals.nonsync: the record less every shaft's
                                                             synchronous average, its envelope's lines
                                                             against the history's, as a detection run reads it
                          ─► the call                        a gear named, else other damage where the
                                                             residual changed (bearing-like), else no change
"""

from __future__ import annotations

import dataclasses
import functools
import warnings

import numpy as np

from .data import which_gear as W
from .data import which_gear_cache as C
from .data.channel_units import level_why
from .data.recordings import prefixed, tacho_kind
from .errors import GearlabInputError
from .gearbox import Gearbox, order_table
from .gearbox.orders import TachoShaft
from .inspect import InspectOptions, measured_speed, read_record, settle_speed, unconfirmed
from .signals import POINTS, resample_revolutions
from .signals import envelope_sync as E
from .signals import localise as L
from .signals import nonsync as NS
from .signals.checks import revolution_speeds, settled
from .signals.localise import weakly
from .signals.pipeline import first_complete


def input_revolutions(path: str, box: Gearbox, options: InspectOptions, history: bool = False, taken=()) -> tuple:
    """(complete input revolutions at the pipeline's points, the first one's number from the angle's zero modulo
    the train period, the Nyquist order, the tacho's marks per turn, the speed, the rate, each revolution's speed
    (Hz; None where not one a revolution)) of one file as read (a *history* file: inspect.read_record's); *taken*:
    (its record, its speed or None) as inspect_record kept them, neither read again."""
    rec, speed = taken or (read_record(path, options, history), None)
    if speed is None:
        speed = measured_speed(rec, box, options)
        if unconfirmed(rec, box, speed):  # read at the speed inspect's rows are read at
            speed = settle_speed(rec, box, options, speed)[0]
    # without a tacho the angle is zero at the first sample, as a detection's or score's take has it
    angle = speed.angle if rec.tacho is not None else speed.angle - speed.angle[0]
    with prefixed(f"{rec.path}: vibration '{rec.vibration}'"):  # a followed angle's unsettled ends out, as a run's
        kept = settled(angle, rec.fs, speed.ends, NS.revolutions_needed(order_table(box)))
        revs = resample_revolutions(rec.signal, angle, points=POINTS)[kept]
    first = first_complete(angle) + kept.start  # numbered as a detection's or score's take (recordings.CutRecording)
    # the tacho marks a take may start at (localisation turns each take to the first history take's)
    kind = None if rec.tacho is None else options.tacho_kind if options.tacho_kind != "auto" else tacho_kind(rec.tacho)
    shaft = TachoShaft.of(box, options.tacho_shaft or box.sensor.tacho, "--tacho-shaft")
    marks = shaft.marks(options.pulses_per_rev or box.sensor.pulses_per_rev if kind == "pulses" else 1) if kind else 1
    turns = revolution_speeds(angle, rec.fs)[kept]  # a non-synchronous line on a mains harmonic: hum or a bearing
    return revs, first, rec.fs / (2 * speed.mean_hz), marks, speed, rec.fs, turns if len(turns) == len(revs) else None


def localisation(path: str, history: list, box: Gearbox, options: InspectOptions, taken: tuple = ()) -> dict:
    """Which shaft and gear the record's synchronous average carries a localised change on, against healthy
    *history* records of the same gearbox, each a path read with the record's *options* or a (path, its own
    InspectOptions) pair: data.which_gear's one decision, as a detection run and `gearlab score` make it (orders
    up to those every history record holds; a shaft's two gears by the description's simulated events at the
    record's speed and rate, where the history's mesh harmonics agree with the simulation's). *taken*: the record
    and its speed as inspect_record kept them (input_revolutions)."""
    if not history:
        raise GearlabInputError("--history: give the healthy records of the same gearbox to localise against")
    table = order_table(box)
    revs, first, _, _, speed, fs, turns = input_revolutions(path, box, options, taken=taken)
    read = [(h, options) if isinstance(h, str) else h for h in history]
    hist, quiet, level, keep = read_history(read, box, options, table)
    ns = nonsync_lines(revs, quiet, table, speed.mean_hz, turns)
    if isinstance(hist, GearlabInputError):
        out = {"method": "", "named": None, "named_shaft": None, "summary": f"not localised: {hist}", "shafts": []}
    else:  # a non-synchronous call sets the envelope aside, as a detection run does (data.which_gear)
        take = W.Take(revs, first, speed.mean_hz, fs)
        try:
            out = W.which_gear(take, hist, table, W.events(box.source), envelope=not ns.get("changed"))
        except GearlabInputError as exc:
            out = {"method": "", "named": None, "named_shaft": None, "summary": f"not localised: {exc}", "shafts": []}
    keep()  # the envelope's band the take was read in kept too: the next take read in it reads no file again
    out["history"] = [p for p, _ in read]
    out["nonsync"] = ns
    out["call"] = call_of(out, out["nonsync"], speed.mean_hz)
    # a take at another load than its history's: its call said beside the level, as a run and score warn of it (a 38/103
    # box's healthy take at 1.5 x its one-load history's mesh level read 'localised change: input pinion 38T', no more)
    out["level"] = float(np.std(revs)) / level
    if len(read) == 1 and not out["call"].startswith("no change"):  # its thresholds: one take's own blocks
        out["call"] += (
            "; of one history take: how far takes of other days lie apart is not measured, a healthy take may pass "
            "its thresholds more often than asked (--history two or more takes, from different days)"
        )
    if why := level_why(out["level"]):
        out["call"] += (
            f"; the take's level {out['level']:.2g} x its history's ({why}): a history at that load "
            "compares like with like"
        )
    return out


def read_history(read: list, box: Gearbox, options: InspectOptions, table) -> tuple:
    """(the history read for localisation, or why not; its non-synchronous residual's (signals.nonsync), or why not;
    the median of its takes' rms; keep(): kept for later calls, with the envelope's bands read meanwhile) of the
    history files *read* ((path, InspectOptions) pairs), kept between calls (data.which_gear_cache: the same files,
    options, gearbox and code read it once; an envelope band not kept yet reads them again)."""
    files = [C.file_identity(p) for p, _ in read]
    key = None if None in files else C.key_of("history", files, [o for _, o in read], options, box, table)
    if key is not None and (kept := C.load("history", key)) is not None:
        hist, quiet, level = restored_history(kept, table, lambda: _read_history(read, box, options, table)[0].envelope)
        had = len(kept.get("envelope_read", ()))
        said = [str(w) for w in kept.get("warnings", ())]
        for text in said:  # what the files' first reading warned of (a reader's note), said again
            warnings.warn(text, stacklevel=2)
    else:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            hist, quiet, level = _read_history(read, box, options, table)
        said = [str(w.message) for w in caught]
        for w in caught:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        had = -1

    def keep() -> None:
        if key is None or not isinstance(hist, (L.History, GearlabInputError)):  # no history read: nothing to keep
            return
        if _bands_read(hist) > had:
            C.save("history", key, kept_arrays(hist, quiet, level) | {"warnings": np.array(said, dtype=str)})

    return hist, quiet, level, keep


def _bands_read(hist) -> int:
    bank = None if isinstance(hist, GearlabInputError) else hist.envelope
    if bank is None:
        return 0
    return len(bank.histories.read_now()) if isinstance(bank.histories, E.Histories) else len(bank.histories)


def _read_history(read: list, box: Gearbox, options: InspectOptions, table) -> tuple:
    """read_history's reading of the files."""
    past = []
    for p, o in read:
        try:
            past.append(input_revolutions(p, box, o, history=True))
        except GearlabInputError as exc:
            # read with its own keys, its channel too (a --history-key gain alone keeps the record's channel names)
            if o is not options and (o.vibration, o.tacho) != (options.vibration, options.tacho):
                raise
            name = p.replace("\\", "/").rsplit("/", 1)[-1]
            raise GearlabInputError(
                f"{exc} (a history file read with the record's keys; its own: --history-key '{name}:{own_key(exc)}')"
            ) from None
    takes = [W.Take(r, f, s.mean_hz, rate, turns) for r, f, _, _, s, rate, turns in past]
    tacho = (options.tacho_shaft or box.sensor.tacho) if options.tacho is not None else ""  # the shaft it reads
    pulses = options.pulses_per_rev or box.sensor.pulses_per_rev
    try:  # a history too short for it is said, as a detection run says it (detection_which_gear)
        hist = W.history_of(takes, table, marks=max(k for *_, k, _, _, _ in past), tacho=tacho, pulses=pulses)
    except GearlabInputError as exc:
        hist = exc
    try:
        quiet = NS.history([t.revolutions for t in takes], table, [t.speed_hz for t in takes])
    except GearlabInputError as exc:
        quiet = exc
    return hist, quiet, float(np.median([np.std(t.revolutions) for t in takes]))


def kept_arrays(hist, quiet, level: float) -> dict:
    """read_history's result as plain arrays (as a detection run saves its history for `gearlab score`, the
    envelope's bands read so far alone: signals.envelope_sync.read_state) or the reasons it was not read."""
    arrays = {"level": np.array(level)}
    if isinstance(hist, GearlabInputError):
        arrays["history_not_read"] = np.array(str(hist))
    else:
        arrays |= hist.state() | E.read_state(hist.envelope)
    not_read = isinstance(quiet, GearlabInputError)
    return arrays | ({"nonsync_not_read": np.array(str(quiet))} if not_read else quiet.state())


def restored_history(kept: dict, table, envelope) -> tuple:
    """read_history's result from the arrays it kept; an envelope band not kept from *envelope*() (the history's
    envelope bank read again) on its first use."""
    if "history_not_read" in kept:
        hist = GearlabInputError(str(kept["history_not_read"]))
    else:
        again = functools.cache(envelope)
        bank = E.restored_read(kept, table, again)
        hist = dataclasses.replace(L.History.restored(kept, table), envelope=bank)
    if "nonsync_not_read" in kept:
        quiet = GearlabInputError(str(kept["nonsync_not_read"]))
    else:
        quiet = NS.NonSyncHistory.restored(kept, table)
    return hist, quiet, float(kept["level"])


# The take's acquisition options read every history file (one chain, the normal case); a refusal of one of them on a
# history file that states its own unit or rate names the --history-key that gives that file its own: '' drops one
_CHAIN_KEYS = {"--sensitivity": "sensitivity=", "--gain": "gain=", "--unit": "unit=", "sampling rate given": "fs="}


def own_key(exc: GearlabInputError) -> str:
    """The --history-key KEY=VALUE that reads a history file a refusal *exc* of the take's options names; else its
    vibration channel's."""
    said = str(exc)
    return next((key for words, key in _CHAIN_KEYS.items() if words in said), "vibration=NAME")


LINES = 5  # the strongest non-synchronous envelope lines shown


def nonsync_lines(revs, history, table, speed_hz: float, speeds=None, takes: list | None = None) -> dict:
    """The record's non-synchronous change against the *history* takes' (a list of their revolutions, or their
    NonSyncHistory read before, or why it could not be: read_history) (signals.nonsync, as a detection run
    reads it: z of its strongest envelope line, the strike order named, the history's threshold; on a mains harmonic
    read as hum or a bearing's from its revolutions' *speeds* and the history's W.Take *takes*' speeds, where given)
    with the LINES strongest lines' orders and z, strongest first; where the takes are too short for it, why not."""
    try:
        if isinstance(history, GearlabInputError):  # read_history's: the history is too short for it
            raise history
        if not isinstance(history, NS.NonSyncHistory):
            history = NS.history(history, table, None if takes is None else [t.speed_hz for t in takes])
        found, z = NS.read_take(revs, history, table, speeds)
    except GearlabInputError as exc:
        return {"note": f"not read: {exc}"}
    orders = NS.orders_of_bins(z.size)
    inner = np.r_[False, (z[1:-1] >= z[:-2]) & (z[1:-1] > z[2:]), False]  # each line's peak bin
    peaks = sorted(np.flatnonzero(inner | (z == z.max())), key=lambda i: -z[i])[:LINES]
    lines = [{"order": float(orders[i]), "hz": float(orders[i] * speed_hz), "z": float(z[i])} for i in peaks]
    return found.describe() | {"hz": found.order * speed_hz, "lines": lines}


def call_of(loc: dict, ns: dict, speed_hz: float | None = None) -> str:
    """What the record's change is, by the rule a detection run calls a flag with (its watched gear aside): the
    gears (or shafts) the synchronous averages name (data.which_gear.flagged_shafts), with a non-synchronous line
    beside them (nonsync.beside); else other damage where the non-synchronous residual changed; else no change."""
    if loc["named"]:  # every shaft whose change is its own, the named first (damage on two gears: both)
        shafts = W.flagged_shafts(loc) if loc.get("shafts") else [{"gear": loc["named"]}]
        flagged = [s.get("shaft", loc.get("named_shaft")) for s in shafts]
        bearing = NS.beside(ns, speed_hz, flagged)  # a bearing's line beside a gear's change: said too
        also = f"; also other damage: {bearing}" if bearing else ""
        return "localised change: " + "; ".join(s["gear"] + weakly(s) for s in shafts) + also
    if ns.get("changed"):
        return NS.call(ns["order"], ns.get("hz"), ns.get("locked", ""), ns.get("why", ""))
    if loc.get("summary", "").startswith("not localised: ") and "note" in ns:  # neither read: no call, not 'no change'
        return f"not read against the history: {loc['summary'][15:]}"
    why = "; non-synchronous " + ns["note"] if "note" in ns else ", no non-synchronous line over its threshold"
    return f"no change against the history: nothing localised{why}"


def render_localisation(loc: dict, console) -> None:
    """The per-shaft evidence of `gearlab inspect --history` in the terminal."""
    from rich.markup import escape
    from rich.table import Table

    t = Table(title="which gear: localised change per shaft (against the history)")
    for col in ("shaft", "gears", "z", "threshold", "flagged", "tooth (peak, pitches)"):
        t.add_column(col)
    for s in loc["shafts"]:
        found = [v for k, v in s["tooth"].items() if k != "angle_deg"]
        teeth = "; ".join(f"{v['tooth']} of {v['of']} ({v['pitches']:.1f})" for v in found)
        t.add_row(
            s["shaft"],
            escape(", ".join(s["gears"])),
            f"{s['z']:.2f}",
            f"{s['threshold']:.2f}",
            "[red]yes[/red]" if s["flagged"] else "no",
            teeth or "-",
        )
    if loc["shafts"]:  # none where the takes were not localised (its summary says why)
        console.print(t)
        console.print(f"[dim]{escape(loc['method'])}[/dim]")
    colour = "yellow" if loc["named"] else "green"
    console.print(f"[bold {colour}]{escape(loc['summary'])}[/bold {colour}]")
    ns = loc["nonsync"]
    if "lines" in ns:
        t = Table(
            title="non-synchronous envelope lines: the record less every shaft's synchronous average, against the "
            f"history's (threshold z {ns['threshold']:.2f}, {NS.PASSED}; strike order {ns['order']:.2f}, "
            f"{ns['hz']:.4g} Hz)"
        )
        for col in ("input order", "Hz", "z", "over the threshold"):
            t.add_column(col)
        for x in ns["lines"]:
            over = x["z"] > ns["threshold"]
            t.add_row(f"{x['order']:.2f}", f"{x['hz']:.4g}", f"{x['z']:.2f}", "[red]yes[/red]" if over else "no")
        console.print(t)
    else:
        console.print(f"[dim]non-synchronous: {escape(ns['note'])}[/dim]")
    colour = "green" if loc["call"].startswith("no change") else "yellow"
    console.print(f"[bold {colour}]call: {escape(loc['call'])}[/bold {colour}]")
