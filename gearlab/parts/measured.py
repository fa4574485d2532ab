"""Measured target records: the [target] of the kinds that read a rig's records (detection: history
and test files; gap: the history alone), each file with its role, label and operating condition."""

from __future__ import annotations

import difflib
import math
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..data.recordings import (
    channel_key,
    check_measured_file,
    check_recording,
    cut_recording,
    only_vibration,
    pulses_without_tacho,
)
from ..data.takes import take_paths
from ..data.textzip import CALIBRATION, align_to, align_turn, calibration
from ..errors import GearlabInputError, did_you_mean, shown
from ..files import matched, split_take
from ..gearbox.orders import settle_turns
from ..signals.angle import continued
from ..units import rate_hz

if TYPE_CHECKING:
    from ..gearbox.orders import TachoShaft

ROLES = ("history", "test")
# The acquisition keys a 'files' entry may give for its file alone (the [target]'s own, checked as
# kinds.common.MEASURED declares them): a CSV history with column 'acc', HDF5 tests with dataset 'vib'; and
# gearlab score's --key of new files (a next-week take whose tacho was moved to the output, 2 marks a turn)
ACQUISITION = ("vibration", "tacho", "tacho_shaft", "pulses_per_rev", "sensitivity", "gain", "unit", "fs")
# 'file' as in every kind's measured entry; 'speed' a record's own declared speed (no tacho); 'path',
# the file's name before, is read the same;
# the path, 'takes' the column marking a logger's takes in the file (each a record: takes.take_paths)
FILE_KEYS = ("file", "role", "label", "condition", "speed", *ACQUISITION, "takes", "path")


@dataclass(frozen=True)
class TargetFile:
    path: str  # as written in the scenario (scores.csv's 'file')
    resolved: str
    role: str
    label: str
    condition: str  # "" until known (the record's speed)
    speed_hz: float | None = None  # declared for this record alone (no tacho)
    # its own acquisition keys, (name, value as Target holds it) in ACQUISITION's order: the
    # [target]'s are read where it gives none (Target.keys_of); part of the record's identity
    keys: tuple = ()
    pattern: str = ""  # the entry's glob pattern that matched it ("": named as it is)
    entry: int = 0  # the 'files' entry (1-based) that named it, for messages on its keys (0: none)


@dataclass(frozen=True)
class Target:
    vibration: int | str
    tacho: int | str | None  # None: the speed is declared or found from the description's mesh orders
    pulses_per_rev: int
    sensitivity: float | None  # V per m/s² (None: not given; the values are taken as m/s²)
    fs: float | None  # None: each file's own (a time column, an 'fs' field)
    transient: str
    positive: str
    files: tuple[TargetFile, ...]
    gain: float | None = None  # V per file unit
    speed_hz: float | None = None  # declared input-shaft speed of every record without a tacho
    gearbox: str | None = None  # a description (file or built-in name): the speed from its mesh orders
    unit: str | None = None  # the vibration's unit where its name and file say none (recordings.UNITS)
    tacho_shaft: TachoShaft | None = None  # a tacho on another shaft than the input (None: the input)
    settle_window: int = 1  # the input turns a start-up is judged over: the [source]'s slowest shaft's turn
    # the [source] description's (input speed in Hz, first pinion's teeth): a tacho's count typed a factor off
    # is refused at the read (inspect_tacho.refuse_marks); () where it states no speed
    described: tuple = ()
    # (file path, location, table) of the key each tacho record's pulses_per_rev came from (its entry, the
    # [target], the description's [sensor])
    pulses_at: tuple = ()

    def keys_of(self, file: TargetFile) -> dict:
        """The acquisition keys *file* is read with: its own, else the target's ('tacho_shaft': a TachoShaft,
        None on the input)."""
        return {k: getattr(self, k) for k in ACQUISITION} | dict(file.keys)

    @property
    def marks(self) -> int:
        """The tacho marks a record's input angle may start at, 1/marks of a turn apart (TachoShaft.marks);
        files of other pulses per turn or another tacho shaft: the marks of them all."""
        read = {(self.tacho_shaft, self.pulses_per_rev)}
        read |= {(k["tacho_shaft"], k["pulses_per_rev"]) for k in map(self.keys_of, self.files)}
        return math.lcm(*(p if shaft is None else shaft.marks(p) for shaft, p in read))

    @property
    def tacho_all(self) -> bool:
        """Every record is read with a tacho: its marks align them (else, a record or more without one, all
        are aligned as records without a tacho are, each cut at its own tacho's angle or declared speed)."""
        return all(self.keys_of(f)["tacho"] is not None for f in self.files)

    @property
    def read_as(self) -> str | None:
        """The shaft the tacho is read as (the gap's Chain.tacho_shaft); None: not every record has one (each
        file's own tacho counts: a history of per-file tachos was read 'no tacho: its speed from the mesh lines').
        Files' own tacho_shaft: the first history record's (the structure check and the which-gear history read
        the history; a gap's history has one, target_spec)."""
        if not self.tacho_all:
            return None
        first = next((f for f in self.files if f.role == "history"), None)
        shaft = self.tacho_shaft if first is None else self.keys_of(first)["tacho_shaft"]
        return shaft.name if shaft else "input"

    def read(self, file: TargetFile):
        """One of the target's records, read through the one import path (any format) with its
        channels, tacho and units: its revolutions (recordings.cut_recording). Without a tacho, the
        shaft angle of the record's declared speed (its own, else the target's) or of the speed its
        description's mesh orders show (refining a declared one to ±1 %: recordings.shaft_angle)."""
        from ..gearbox import resolve_gearbox

        keys, at = self.keys_of(file), dict((p, (w, t)) for p, w, t in self.pulses_at).get(file.path)
        marks = None
        if self.described and at and keys["tacho"] is not None:

            def marks(fs: float, speed: float) -> None:
                refuse_marks(fs, speed, self.described, keys["pulses_per_rev"], *at)

        try:
            return cut_recording(
                file.resolved,
                **keys,  # its tacho_shaft too
                transient=self.transient,
                speed_hz=file.speed_hz if file.speed_hz is not None else self.speed_hz,
                gearbox=resolve_gearbox(self.gearbox) if self.gearbox else None,
                settle_window=self.settle_window,
                before_cut=marks,
            )
        except GearlabInputError as exc:  # what the data shows (a ragged row, a NaN): named where it is listed
            said = exc.args and isinstance(exc.args[0], str) and at and exc.args[0].startswith(at[0])
            if exc.args and isinstance(exc.args[0], str) and "[target]" not in exc.args[0] and not said:
                at = f"[target] key 'files' entry {file.entry or self.files.index(file) + 1} key 'file'"  # a take's
                exc.args = (f"{at}: {exc.args[0]}", *exc.args[1:])
            raise


def tacho_shaft_of(name: str, tacho, box, where: str, described: str) -> TachoShaft | None:
    """The shaft a measured entry's tacho reads: *name* (its 'tacho_shaft'; "" when not given), else
    the description *box*'s [sensor] tacho; None: the input (or a shaft as fast), read as ever.
    One line naming *where*'s key for a tacho_shaft without a tacho, another shaft without a
    description (*described*: the key that gives one), or a shaft the description lacks."""
    from ..gearbox.orders import TachoShaft

    at = f"{where} key 'tacho_shaft'"
    if tacho in (None, ""):
        if name:
            raise GearlabInputError(f"{at}: belongs to a tacho; no 'tacho' is given")
        return None
    if box is None:
        if name not in ("", "input"):
            raise GearlabInputError(
                f"{at}: {shown(name)} is a shaft of a gearbox description, and none is given; expected {described} "
                "(its shafts and tooth counts give that shaft's turns per input turn) or tacho_shaft = 'input'"
            )
        return None
    shaft = TachoShaft.of(box, name or box.sensor.tacho, at if name else f"{box.source}: [sensor] key 'tacho'")
    return None if shaft.turns == 1 else shaft


def pulses_of(given: int | None, tacho, box) -> int:
    """A measured entry's tacho marks per turn: *given* (its 'pulses_per_rev'), else the description
    *box*'s [sensor] pulses_per_rev (as tacho_shaft_of takes its [sensor] tacho), else 1."""
    if given is not None:
        return int(given)
    return int(box.sensor.pulses_per_rev) if box is not None and tacho not in (None, "") else 1


def target_files(files, where: str, base: Path, need=ROLES, takes: str = "") -> tuple[TargetFile, ...]:
    """The [target] 'files' list: each {file, role, label, condition?}, paths relative to *base*, a
    glob pattern standing for each file it matches (files.matched), a file of several takes for each take
    (its 'takes', else *takes*: the [target]'s; takes.take_paths); every role in *need* must be
    present (the gap kind needs the history alone)."""
    if not files:
        raise GearlabInputError(f"{where}: expected a list of files, each {{ file, role = 'history' | 'test', label }}")
    out = []
    for i, f in enumerate(files):
        at = f"{where} entry {i + 1}"
        if not isinstance(f, dict):
            raise GearlabInputError(f"{at}: expected a table {{ file, role, label }}, got {shown(f)}")
        for key in f:
            if key not in FILE_KEYS:
                raise GearlabInputError(
                    f"{at}: unknown key '{key}'{did_you_mean(key, FILE_KEYS)}; known keys: {', '.join(FILE_KEYS[:-1])}"
                )
        if "path" in f:
            if "file" in f:
                raise GearlabInputError(f"{at}: give 'file' (the record), not both 'file' and 'path'")
            f = {**f, "file": f["path"]}
        for key in ("file", "role", "label"):
            if not isinstance(f.get(key), str) or not f[key]:
                raise GearlabInputError(f"{at}: '{key}' must be a non-empty text")
        if f["role"] not in ROLES:
            raise GearlabInputError(
                f"{at}: role '{f['role']}'{did_you_mean(f['role'], ROLES)} is not one of {', '.join(ROLES)}"
            )
        condition = f.get("condition", "")
        if not isinstance(condition, str):
            raise GearlabInputError(f"{at}: 'condition' must be a text, e.g. '30 Hz high load'")
        speed = None if f.get("speed") is None else speed_of(f["speed"], f"{at} key 'speed'")
        keys = tuple(acquisition(f, at, [k for k in ACQUISITION if k in f]).items())
        column = f.get("takes", takes)
        if not isinstance(column, str):
            raise GearlabInputError(f"{at} key 'takes': expected the column marking the takes, e.g. 'segment'")
        at_takes = f"{at} key 'takes'" if "takes" in f else where.removesuffix("'files'") + "'takes'"
        names = matched(f["file"], base, f"{at} key 'file'")
        pattern = "" if names == [f["file"]] else f["file"]
        for name in names:  # a pattern's files: one record each, with the entry's other keys
            check_measured_file(base / name, f"{at} key 'file'")  # an absolute name stays itself
            for one in take_paths(base / name, column, at_takes, name) if column else [name]:
                resolved = str(base / one)
                out.append(TargetFile(one, resolved, f["role"], f["label"], condition, speed, keys, pattern, i + 1))
    seen = {}
    for i, f in enumerate(out):
        if seen.setdefault(f.resolved, i) != i:
            first = out[seen[f.resolved]].entry
            raise GearlabInputError(f"{where} entry {f.entry}: {f.path} is listed twice (entry {first})")
    for role in need:
        if not any(f.role == role for f in out):
            raise GearlabInputError(
                f"{where}: no file has role = '{role}'; expected at least "
                + " and ".join(f"one {r}" for r in need)
                + " file"
            )
    return tuple(out)


def pattern_counts(files: tuple[TargetFile, ...]) -> str:
    """What each glob pattern of a 'files' list matched, and each file of several takes held, for `gearlab
    validate`: "'test/*.csv': 6 files, 'log.csv': 3 takes ('segment')" ("" where every file is named as it is)."""
    counts = Counter(f.pattern for f in files if f.pattern)
    takes = Counter(take[:2] for f in files if (take := split_take(f.path)))
    return ", ".join(
        [f"{p!r}: {n} file{'s' * (n != 1)}" for p, n in counts.items()]
        + [f"{file!r}: {n} take{'s' * (n != 1)} ({column!r})" for (file, column), n in takes.items()]
    )


def positive_label(files: tuple[TargetFile, ...], positive: str, where: str) -> None:
    """One line when no test file carries the *positive* label and one carries a near spelling of it
    ('faulty', 'Fault'): every test record was scored as a negative, the report's AUC undefined."""
    if not any(f.role == "test" for f in files) or any(f.label == positive for f in files if f.role == "test"):
        return
    for f in files:
        low, want = f.label.lower(), positive.lower()
        near = low.startswith(want) or low.endswith(want) or difflib.SequenceMatcher(None, low, want).ratio() >= 0.8
        if f.role == "test" and near:
            raise GearlabInputError(
                f"{where} key 'files' entry {f.entry} key 'label': {f.label!r} is not the positive label {positive!r} "
                f"([target] key 'positive'), and no test file has {positive!r}; expected label = {positive!r} on "
                f"the records with the fault to find (or positive = {f.label!r})"
            )


def acquisition(t: dict, where: str, keys=ACQUISITION) -> dict:
    """The acquisition *keys* of a [target] table or a 'files' entry *t* (checked as
    kinds.common.MEASURED declares them) as Target holds them: channels as the readers name them,
    quantities in SI, None where not given."""
    out = {key: held(key, t.get(key), f"{where} key '{key}'") for key in keys if key not in CALIBRATION}
    return out | calibration({k: t.get(k) for k in CALIBRATION if k in keys}, lambda k: f"{where} key '{k}'")


def held(key: str, value, where: str):
    """An acquisition key's *value* as Target holds it (None: not given); *where* names it."""
    if key == "vibration":
        return channel_key(value)
    if value is None or value == "":
        return None
    if key == "tacho":
        return channel_key(value)
    if key == "pulses_per_rev":
        return int(value)
    # fs in Hz ('sensitivity' and 'gain': calibration); a unit, a shaft's name as given (made a TachoShaft where
    # the description is known: target_spec's own_shafts, detection_scoring.reading_keys)
    return value if key in ("unit", "tacho_shaft") else rate_hz(value, where)


def speed_of(value, where: str) -> float:
    """A declared input-shaft speed ('25 Hz', '1500 rpm'; a number: Hz) in revolutions per second."""
    from ..gearbox.description import bare_speed, speed_hz  # rpm is 1/60 Hz there, not pint's 2π/60 rad/s

    speed = speed_hz(value, where)
    if speed > 1e3:
        raise GearlabInputError(
            f"{where}: expected an input-shaft speed up to 1 kHz, e.g. '25 Hz', got {shown(value)}{bare_speed(value)}"
        )
    return speed


def target_spec(t: dict, where: str, base: Path, need=ROLES, box=None) -> Target:
    """The [target] of measured records: the keys of every measured entry (vibration, tacho,
    pulses_per_rev, sensitivity, unit, gain, fs; without a tacho, speed or gearbox: the description,
    a path as the caller resolved it) and the files, each checked against its header
    (recordings.check_recording: its channels, a sampling rate, units) before any work. *t* was
    checked as kinds.common.MEASURED declares its keys (bounds, choices, column indices) when the
    table was read; here the values become SI. *box*: the [source]'s gearbox description, whose
    shafts 'tacho_shaft' (default: its [sensor] tacho) names."""
    from ..inspect_tacho import shaft_ratios  # inspect_tacho imports the data layer: read lazily

    keys = acquisition(t, where)
    vibration, tacho = keys["vibration"], keys["tacho"]
    if vibration == tacho:
        raise GearlabInputError(f"{where} key 'tacho': the same column as the vibration ({t['tacho']!r})")
    speed = None if t.get("speed") is None else speed_of(t["speed"], f"{where} key 'speed'")
    gearbox = t.get("gearbox") or None
    files = target_files(t["files"], f"{where} key 'files'", base, need, t.get("takes") or "")
    if vibration == "" and any("vibration" not in dict(f.keys) for f in files):
        # as inspect takes it: each file's one channel besides the tacho and time
        of = {
            f.path: only_vibration(f.resolved, dict(f.keys).get("tacho", tacho), where)
            for f in files
            if "vibration" not in dict(f.keys)
        }
        found = sorted(set(of.values()))
        if len(found) > 1:
            # each file's own key is the way out (a logger's CSV beside a MAT file): said, with an example
            path, name = next(iter(of.items()))
            raise GearlabInputError(
                f"{where} key 'vibration': missing, and the files' one signal channels differ "
                f"({', '.join(f'{p}: {c!r}' for p, c in of.items())}); expected the vibration channel's name, "
                f"or each file's own ({{ file = '{path}', vibration = '{name}' }})"
            )
        vibration = found[0]
    if tacho is None and t["pulses_per_rev"] not in (None, 1):
        raise pulses_without_tacho(files[0].resolved, f"{where} key 'pulses_per_rev'", lambda c: f"tacho = '{c}'")
    # a file's own tacho (or tacho = "": none) over the [target]'s: records with and without one may mix,
    # each cut at its own tacho's angle or at its declared (or mesh-found) speed
    tachos = [dict(f.keys).get("tacho", tacho) for f in files]
    if len({q is None for q in tachos}) > 1 and "test" not in need:  # the gap: one acquisition chain
        with_one = next(f.path for f, q in zip(files, tachos) if q is not None)
        without = next(f.path for f, q in zip(files, tachos) if q is None)
        raise GearlabInputError(
            f"{where} key 'files': {with_one} has a tacho, {without} none; the gap compares one acquisition chain "
            'with the simulator: expected history records all with a tacho or all without (tacho = "" on a file)'
        )
    for f, ftacho in zip(files, tachos):
        own = dict(f.keys)
        at = f"{where} key 'files' entry {f.entry}"
        if own.get("pulses_per_rev") is not None and ftacho is None:
            raise pulses_without_tacho(f.resolved, f"{at} key 'pulses_per_rev'", lambda c: f"tacho = '{c}'")
        if own and ftacho is not None and own.get("vibration", vibration) == ftacho:
            raise GearlabInputError(f"{at} key 'vibration': the same column as the tacho ({ftacho!r})")
        declared = f.speed_hz if f.speed_hz is not None else speed
        # the shaft angle comes from one of them (recordings.shaft_angle): a tacho, or a speed
        # declared or found from the description's mesh orders; a [target] speed or gearbox is for the
        # files without a tacho, refused where every file has one
        if ftacho is not None and (f.speed_hz is not None or (None not in tachos and (speed is not None or gearbox))):
            own_speed = f"'files' entry {f.entry} key 'speed'"
            at = f"{where} key " + (own_speed if f.speed_hz is not None else "'speed'" if speed else "'gearbox'")
            raise GearlabInputError(
                f"{at}: {f.path} has a tacho ({ftacho!r}), which gives its speed; expected a tacho, or "
                "without one a 'speed' (e.g. '25 Hz') or a 'gearbox' description, not both"
            )
        if ftacho is None and declared is None and not gearbox:
            raise GearlabInputError(
                f"{where} key 'tacho': missing; {f.path} has no tacho, speed or gearbox to know its shaft angle "
                "from; expected a tacho channel, a 'speed' (e.g. '25 Hz') or a 'gearbox' description whose "
                "mesh orders give the speed"
            )
        merged = {**keys, "vibration": vibration, **own}
        check_recording(
            f.resolved,
            at if own else where,
            {"vibration": merged["vibration"], "tacho": merged["tacho"]},
            fs=merged["fs"],
            sensitivity=merged["sensitivity"],
            gain=merged["gain"],
            unit=merged["unit"],
        )
    positive_label(files, t.get("positive") or "fault", where)
    # the files' own tachos count: each file naming its tacho left the description's [sensor] tacho and marks
    # unread (a 3-mark output tacho read as the input's once a turn: 4.4 Hz, 'a 31-tooth pinion')
    some = tacho if tacho is not None else next((q for q in tachos if q is not None), None)
    shaft = tacho_shaft_of(t.get("tacho_shaft") or "", some, box, where, "[source] key 'gearbox'")
    files = own_shafts(files, tachos, box, f"{where} key 'files'", shaft, "test" in need)
    return Target(
        vibration,
        tacho,
        pulses_of(t["pulses_per_rev"], some, box),
        keys["sensitivity"],
        keys["fs"],
        t["transient"],
        t["positive"],
        files,
        keys["gain"],
        speed,
        gearbox,
        keys["unit"],
        shaft,
        settle_turns(box),
        () if box is None or not box.speed_hz else (box.speed_hz, box.stages[0].pinion.z, shaft_ratios(box)),
        tuple(pulses_at(f, q, t, box, where) for f, q in zip(files, tachos) if q is not None),
    )


def pulses_at(f: TargetFile, tacho, t: dict, box, where: str) -> tuple:
    """(path, location, table) of the key *f*'s pulses_per_rev came from (pulses_of's order): its 'files' entry's,
    the [target] table *t*'s, else the description *box*'s [sensor] (1 where none gives one: the [target]'s)."""
    if dict(f.keys).get("pulses_per_rev") is not None:
        return f.path, f"{where} key 'files' entry {f.entry} key 'pulses_per_rev'", "[target] 'files' entry"
    if t.get("pulses_per_rev") is None and box is not None and tacho is not None:
        return f.path, f"{box.source}: [sensor] key 'pulses_per_rev'", "[sensor]"
    return f.path, f"{where} key 'pulses_per_rev'", "[target]"


def refuse_marks(fs: float, speed: float, described: tuple, ppr: int, where: str, table: str) -> None:
    """Refuse a record read at a tacho's *speed* a whole count of marks off the *described* (input speed in Hz, the
    first pinion's teeth, its shafts' ratios) with too few samples a revolution for that mesh (*fs* / *speed*): its
    count typed a factor off (inspect_tacho.speed_marks_line, naming *where* in *table*), not the sampling rate, and
    before the record is cut into that many revolutions (a 60-mark encoder typed as 6: 10 x the revolutions, minutes
    a take)."""
    from ..gap.structure import SIDEBANDS
    from ..inspect_tacho import speed_marks_line

    hz, z1, ratios = described
    line = speed_marks_line(speed, hz, ppr, where, table, ratios)
    if line and fs / speed < 2 * (z1 + SIDEBANDS) + 1:  # the gap's need (gap_inputs.check_points)
        raise GearlabInputError(line)


def own_shafts(files: tuple[TargetFile, ...], tachos: list, box, where: str, shaft, mixed: bool) -> tuple:
    """*files* with their own 'tacho_shaft' (a name, as held) made the TachoShaft of the [source]'s description
    *box* it names (the input's too: a file's own wins over the [target]'s *shaft*), checked as the [target]'s
    is (tacho_shaft_of: one line naming the entry); *tachos*: each file's tacho. Not *mixed* (the gap: one
    acquisition chain), history records read on different shafts are refused."""
    from ..gearbox.orders import TachoShaft

    out = []
    for f, tacho in zip(files, tachos):
        own = dict(f.keys)
        if "tacho_shaft" in own:
            name = own["tacho_shaft"] or ""  # "": not the [target]'s; the description's [sensor] tacho
            read = tacho_shaft_of(name, tacho, box, f"{where} entry {f.entry}", "[source] key 'gearbox'")
            own["tacho_shaft"] = read or (TachoShaft(name) if name else None)
            f = replace(f, keys=tuple((k, own[k]) for k in ACQUISITION if k in own))
        out.append(f)
    on = {f.path: getattr(dict(f.keys).get("tacho_shaft", shaft), "name", "input") for f in out if f.role == "history"}
    if not mixed and len(set(on.values())) > 1:
        (a, x), (b, y) = next((p, q) for p in on.items() for q in on.items() if p[1] != q[1])
        raise GearlabInputError(
            f"{where}: {a} reads its tacho on the {x} shaft, {b} on the {y}; the gap compares one acquisition chain "
            "with the simulator: expected every history record's tacho on one shaft (tacho_shaft)"
        )
    return tuple(out)


def aligned(
    reference: np.ndarray, revs: np.ndarray, tacho, pulses_per_rev: int, continuous: bool = False
) -> tuple[int, np.ndarray]:
    """(turn, *revs* turned into register with *reference*): with a tacho, by one of the N input angles
    its first mark may find (*pulses_per_rev*: Target.marks; textzip.align_to); without one (the
    angle from a speed, zero at the record's first sample) by any whole sample of the revolution,
    the turn whose mean revolution correlates best with *reference* -- align_to's correlation at
    every sample at once (one inverse FFT). Each row is turned on itself, which is the same for what
    repeats every input turn; *continuous* (a train whose later mesh is no whole order of the units'
    shaft: asynchronous_orders) advances the record as one signal instead (signals.angle.continued,
    its last revolution given up), so that mesh runs on from row to row rather than being cut at
    every row's turn, where without_asynchronous's fit of it could not take it out."""
    if tacho is not None:
        if continuous:
            turn = align_turn(reference, revs, pulses_per_rev)
            return turn, continued(revs, turn * revs.shape[-1] / pulses_per_rev)
        return align_to(reference, revs, pulses_per_rev)
    n = reference.shape[-1]
    corr = np.fft.irfft(np.conj(np.fft.rfft(reference)) * np.fft.rfft(np.mean(np.atleast_2d(revs), axis=0)), n=n)
    turn = int(np.argmax(corr))
    if continuous:
        return turn, continued(revs, turn)
    return turn, np.roll(revs, -turn, axis=-1)  # x(θ) -> x(θ + 2π turn / n), as align_to turns
