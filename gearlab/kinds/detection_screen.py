"""A detection scenario's takes screened by `gearlab validate` and the TUI's Validate (data.readers.headers.validating):
a history too short for its units, or a test take's run-up too short at its history's speed, known from each take's
tacho alone, is refused there in the run's own line.

A history of three 3 s takes of a 39/61 drive sweeping 15 % about 30 Hz passed validate ('OK') and the run then
stopped at 'gives 3 record30 units ...; expected at least 8' (each take's steady part, 32 of 89 turns, one record30
unit): a text file's header gives no length, and how many of a take's turns are steady is in its speeds, which its
tacho alone gives (detection_in_band.steady). So each history take's tacho column is read, without its vibration:
its revolutions' speeds cut to the steady part as the run cuts them, grouped by speed as the run groups them, and
counted into units of every kind (an upper bound: a start-up the run drops, transient = 'stats', reads in the
vibration). Where a condition's bound falls short, the takes are read as the run reads them (detection_records.
read_target), which refuses in the run's words; a tacho-less history (its speed in its vibration's mesh lines) is
left to the run. A 60 s, 20 kHz CSV take's tacho column reads in 0.5 s, the take itself in 0.9 s; a 3 s take's in
0.07 s and 0.18 s; phm09_chip's 8 zipped text history takes a few seconds in all (a text's tacho column parsed alone:
history_short), so a run, which reads them whole at once, the TUI's tree and a comparison leave it out.

A test take's tacho is read alike where the history's read: a run-up or coast-down is cut at its condition's history
speed as the run cuts it (detection_in_band.cut_run_ups), and one whose stretch there holds no unit is refused in the
run's line (a 3 s take of the 39/61 drive sweeping 60 % about its 30 Hz history holds 7 of its 89 turns in the band,
30 needed: validate said OK, the run stopped). A steady test take too short for a unit kind is no refusal: the run
scores it 'not scored' for that kind. phm09_chip's validate, its 8 history and 16 test takes zipped text: 8 s of CPU
(11 s with every field of the texts parsed), on a 2-core machine."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..data.channel_series import series
from ..data.readers.text import asked_numbers_only
from ..data.recordings import CutRecording, Recording, channel_key, read_contents, sampling_rate, shaft_angle
from ..errors import GearlabInputError
from ..parts.measured import Target
from ..signals.checks import revolution_speeds, speed_varies
from .detection_in_band import cut_run_ups, steady_histories
from .detection_records import HISTORY_STRIDES, MIN_HISTORY_UNITS, UnitShaft, conditions_of


def _from_tacho(target: Target, file) -> CutRecording | None:
    """*file*'s input revolutions as its tacho alone gives them (no vibration read: an empty row each), with their
    speeds and the run-up words cut_recording gives a take whose speed varies; None where it has no tacho."""
    from ..gearbox import resolve_gearbox

    keys = target.keys_of(file)
    if keys["tacho"] is None:
        return None
    name, path = channel_key(keys["tacho"]), file.resolved
    contents, fmt = read_contents(path, [name], {name: "tacho"})
    tacho = series(contents.found[name], name, "tacho", path)
    fs, fs_source = sampling_rate(contents, keys["fs"], tacho.size, path)
    rec = Recording(path, fmt, [], name, np.empty(tacho.size), fs, fs_source, name, tacho, "")
    box = resolve_gearbox(target.gearbox) if target.gearbox else None
    _, angle, how = shaft_angle(
        rec, pulses_per_rev=keys["pulses_per_rev"], gearbox=box, tacho_shaft=keys["tacho_shaft"]
    )
    speeds = revolution_speeds(angle, fs)
    mean = (angle[-1] - angle[0]) / (2 * math.pi) * fs / (angle.size - 1)  # as cut_revolutions reads it
    how += speed_varies(angle, fs)
    return CutRecording(str(file.path), np.empty((speeds.size, 0)), mean, fs, tacho.size, 0, how, speeds=speeds)


def history_short(target: Target, blocks, shaft: UnitShaft | None, where: str) -> bool:
    """Whether the takes' tachos alone show a condition's history too short for a unit kind (fewer than
    MIN_HISTORY_UNITS units, or a take whose steady part holds none: detection_in_band.steady_histories), at the most
    units its takes can give, or a test take's run-up too short at its history's speed (run_up_short); False where a
    history take has no tacho or its tacho does not read (the run says why). A text take's tacho column is parsed
    alone (readers.text.asked_numbers_only); where that shows a take short, the takes are read again with each row
    parsed whole, which a text with a field no number in another column fails, as the run's read does (the history's
    then left to the run, such a test take skipped): what is refused is what the whole parse refuses."""
    with asked_numbers_only():
        if not _short(target, blocks, shaft, where):
            return False  # the whole parse reads the same tacho, or fails: it would not refuse either
    return _short(target, blocks, shaft, where)


def _short(target: Target, blocks, shaft: UnitShaft | None, where: str) -> bool:
    """history_short with the takes' tachos read as the reader reads them."""
    history = [f for f in target.files if f.role == "history"]
    try:
        records = {f.path: _from_tacho(target, f) for f in history}
    except GearlabInputError:
        return False
    if not history or any(r is None for r in records.values()):
        return False
    turns = 1.0 if shaft is None else float(shaft.ratio)
    try:
        steady_histories(history, records, blocks, turns, where)
    except GearlabInputError:
        return True
    named = conditions_of(history, {p: r.speed_hz for p, r in records.items()})
    units: dict[tuple[str, int], int] = {}
    for f in history:
        n = math.floor(len(records[f.path].revolutions) * turns + 1e-9)  # the units' shaft's turns, at most
        for b in (1, *blocks):
            stride = max(1, b // HISTORY_STRIDES)
            key = (named[f.path], b)
            units[key] = units.get(key, 0) + len(range(0, n - b + 1, stride))
    return any(count < MIN_HISTORY_UNITS for count in units.values()) or run_up_short(
        target, history, records, blocks, turns, where
    )


def run_up_short(target: Target, history, records: dict, blocks, turns: float, where: str) -> bool:
    """Whether a test take's tacho shows a run-up or coast-down whose longest stretch at its condition's history speed
    holds no unit (detection_in_band.cut_run_ups, on the test takes grouped with the *history* takes' steady *records*
    as the run groups them); a test take without a tacho, or whose tacho does not read, is left to the run."""
    tests = {}
    for f in (f for f in target.files if f.role == "test"):
        try:
            rec = _from_tacho(target, f)
        except GearlabInputError:
            continue
        if rec is not None:
            tests[f] = rec
    files = [*history, *tests]
    held = {**records, **{f.path: rec for f, rec in tests.items()}}
    named = conditions_of(files, {p: r.speed_hz for p, r in held.items()})
    try:
        cut_run_ups(files, held, named, blocks, turns, where)
    except GearlabInputError:
        return True
    return False


def screen_histories(target: Target, blocks, shaft: UnitShaft | None, where: str, read: Callable[[], object]) -> None:
    """Refuse, in the run's own line, a history its tachos show too short for its units, or a test take's run-up too
    short at its history's speed (history_short): *read* reads the takes as the run does (detection_records.
    read_target), which raises it."""
    if history_short(target, blocks, shaft, where):
        read()
