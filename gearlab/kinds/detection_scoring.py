"""Day-to-day scoring of the detection kind (`gearlab score`; gearlab.kinds.detection): what a
finished run keeps for it (store_scoring), new recordings scored by the run's trained methods at
its thresholds with nothing trained again (score), and the trend of what was scored."""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..data.channel_units import kept_gain, read_gain
from ..data.readers.base import is_rate_or_time
from ..data.recordings import channel_key, channel_listing, cut_recording, read_header
from ..data.textzip import CALIBRATION, calibration
from ..data.which_gear import Take
from ..errors import GearlabInputError, did_you_mean
from ..events import Event
from ..executors import one_thread
from ..files import split_take
from ..gearbox.orders import TachoShaft
from ..gearbox.simulation import gearbox_of
from ..learn.protocol import fault_score
from ..parts import scoring
from ..parts.measured import ACQUISITION, TargetFile, held
from ..runs import RunDir, input_digest
from ..scenario import check_type
from ..settings import in_bounds, setting
from ..signals import Standardiser
from ..signals.checks import VARIES_WORDS, read_off_mark, turned_line
from ..signals.regrid import at_points
from ..signals.spikes import without_spikes
from . import record_effects
from .common import MEASURED
from .detection_classical import classical_record
from .detection_fit import (
    gearbox_line,
    history_stages,
    inspected,
    moved_tacho,
    other_gearbox,
    tacho_shaft,
    tooth_counts_differ,
)
from .detection_in_band import IN_BAND, span, stretch, too_narrow
from .detection_in_band import in_band as shared_in_band
from .detection_level import (
    called_level,
    clipped_call,
    history_spread,
    kept_level,
    level_line,
    level_ratio,
    most_called,
    reversed_call,
    take_level,
)
from .detection_own import (
    asked_off,
    by_level,
    condition_of,
    off_history,
    own_conditions,
    own_words,
    refused_why,
    skipped_rows,
)
from .detection_records import (
    aligned,
    asynchronous_orders,
    learned_input,
    longest_tsa,
    synchronous_input,
    unit_revolutions,
    unit_sets,
    unit_shaft,
    unit_window,
    varies,
)
from .detection_settings import Spec, stored_classical
from .detection_trend import first_called
from .detection_units import Rule
from .detection_verdict import one_take
from .detection_which_gear import (
    decided_call,
    decision_of,
    is_level_change,
    is_other,
    is_undetermined,
    localisation_of,
    localise_scored,
    not_read,
    stale_calls,
    unwatched,
)
from .scoring_gain import full_scale_elsewhere

# What the learned methods see (detection_records.synchronous_input), kept in a run's scoring.json:
# its models and thresholds hold for that input only. 1: a later mesh of no whole input order zeroed
# at the whole orders beside its harmonics (1c8fae6); 2: fitted out of each revolution (d9a4d9b);
# 3: and each record shifted into register as one signal, not row by row (aligned, continuous).
# Bump it with every change of what they see.
INPUT_VERSION = 3
# what each version did to a later mesh of no whole input order, for the refusal's line
LATER_INPUT = {
    1: "zeroed at the whole orders beside it",
    2: "fitted out of each revolution turned on itself",
    3: "fitted out of each revolution of a record shifted as one signal",
}


def store_scoring(run: RunDir, spec: Spec, conditions: dict) -> None:
    """What `gearlab score` needs of the finished run: the target's keys, the units and threshold
    rule, and per condition its speed, standardiser, alignment reference and history revolutions
    (the thresholds and classical references are made from them as the run made them)."""
    target, d = spec.target, spec.detection
    out = {
        # cut_recording's keys; without a tacho, the declared speed and the description (a resolved path)
        # whose mesh orders give a new record's speed
        "target": _plain(
            {
                k: getattr(target, k)
                for k in ("vibration", "tacho", "pulses_per_rev", "sensitivity", "gain", "fs", "transient")
                + ("speed_hz", "gearbox", "unit", "settle_window")
            }
        )
        # a tacho on another shaft: {name, a, b}, a/b turns per input turn (absent: the input)
        | ({} if target.tacho_shaft is None else {"tacho_shaft": asdict(target.tacho_shaft)}),
        "file_keys": file_keys(target.files),  # a new file in a test file's format: read with its keys
        # the columns marking a logger's takes the run's files were split by: a new file with one, split so too
        "takes": sorted({take[1] for f in target.files if (take := split_take(f.path))}),
        "marks": target.marks,  # the input angles the run's records were aligned at (a new file's own too)
        # which records had a tacho: "all" aligned by its marks, else as records without one
        "tacho_records": tacho_records(target),
        "blocks": list(d.blocks),
        "threshold": d.threshold,
        "false_alarm": d.false_alarm,
        "points": d.points,
        "input": d.input,
        "input_version": INPUT_VERSION,
        # the later mesh orders the learned methods never see (detection_records.asynchronous_orders)
        "later_orders": list(asynchronous_orders(spec.source, unit_shaft(spec.source))),
        # the units' shaft, turning p/q per input turn (detection_records.unit_shaft); absent: the input
        # (cut with the input shaft's own content out first: detection_records.without_input_shaft)
        **({} if (shaft := unit_shaft(spec.source)) is None else {"unit_shaft": [shaft.name, *_ratio(shaft)]}),
        **({} if shaft is None else {"input_shaft_out": True}),
        "spikes_out": True,  # a record's isolated spikes bridged before it is cut (without_spikes)
        "classical": {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(spec.classical).items()},
        "conditions": {},
    }
    for i, (name, cond) in enumerate(conditions.items()):
        history = np.concatenate([r for _, r in cond["history"]])
        file = f"condition{i}.npz"
        scoring.save_arrays(
            run.file("scoring", file),
            standardiser=np.array([cond["standardiser"].mean, cond["standardiser"].std]),
            reference=cond["reference"],
            history=history.astype(np.float32),
        )
        out["conditions"][name] = {
            "file": file,
            "speed_hz": float(np.median([cond["speeds"][f.path] for f, _ in cond["history"]])),
            "max_order": cond["max_order"],
            "unit_max_order": cond["unit_max_order"],
            "history": [[f.path, len(r)] for f, r in cond["history"]],
            "level_reference": cond["level_reference"],  # its takes' median level in m/s² (history_level)
        }
    run.write_json(scoring.SCORING_FILE, out)


def file_format(path: str) -> str:
    """A file's format as gearlab score matches a new file to the run's: its suffix in lower case, with the
    one before it where the last is a compression's (.txt.gz)."""
    suffixes = [s.lower() for s in Path(path).suffixes]
    return "".join(suffixes[-2:] if suffixes[-1:] in ([".gz"], [".zip"], [".bz2"]) else suffixes[-1:])


def file_keys(files) -> dict:
    """The run's files' own acquisition keys (a [target] 'files' entry's, as Target holds them), for
    gearlab score: 'formats', {format: keys} where every file of that format gives the same ({}: the
    [target]'s), 'sets', {format: each distinct keys of its files, in order} (a logger's CSVs beside
    headerless ones), and 'tests', the test files' where they all agree."""
    by: dict[str, list[dict]] = {}
    for f in files:
        by.setdefault(file_format(f.path), []).append(_plain(f.keys))
    tests = [_plain(f.keys) for f in files if f.role == "test"]
    return {
        "formats": {e: ks[0] for e, ks in by.items() if all(k == ks[0] for k in ks)},
        "sets": {e: [k for i, k in enumerate(ks) if k not in ks[:i]] for e, ks in by.items()},
        "tests": tests[0] if tests and all(k == tests[0] for k in tests) else {},
    }


def _plain(keys) -> dict:
    """A file's own keys as scoring.json keeps them: a tacho_shaft (a TachoShaft) as {name, a, b}, a full scale's gain
    as channel_units.FULL_SCALE (reading_keys reads it back)."""
    kept = {k: asdict(v) if k == "tacho_shaft" and v is not None else v for k, v in dict(keys).items()}
    return kept | ({"gain": kept_gain(kept["gain"])} if "gain" in kept else {})


def tacho_records(target) -> str:
    """Which of *target*'s records were read with a tacho: "all", "some" or "none"."""
    has = {target.keys_of(f)["tacho"] is not None for f in target.files}
    return "all" if has == {True} else "some" if len(has) > 1 else "none"


def _tacho_records(meta: dict) -> str:
    """tacho_records of a run (one saved before: its [target]'s tacho said it)."""
    return meta.get("tacho_records") or ("none" if meta["target"]["tacho"] is None else "all")


def remembered(meta: dict, file: str, given: dict | None = None) -> tuple[dict, str]:
    """The acquisition keys the run's own files read a new *file* with (file_keys), the first whose
    vibration and tacho channels (--key's over them) its header holds: its format's files' (each set of keys
    its files were read with, where they differ), else the [target]'s; for a format the run had none of, the
    [target]'s alone (no other file's channels, gain or unit on it); a file none fits: one line naming the
    channels tried, the file's and --key. (keys, whose they are)."""
    kept = meta.get("file_keys") or {}
    formats, fmt = kept.get("formats", {}), file_format(file) if file else ""
    if not file:
        return formats.get(fmt, kept.get("tests") or {}), ""
    tried = [(formats[fmt], f"the run's {fmt} files'")] if fmt in formats else []
    if fmt not in formats:
        tried += [(k, f"the run's {fmt} files'") for k in kept.get("sets", {}).get(fmt, [])]
    # a format the run read none of: the [target]'s keys alone, as they apply to every file; another file's own
    # keys do not (a next-week npz in volts, read with an HDF5 test file's sensitivity = "", scored 98 x too small)
    foreign = not tried
    tried.append(({}, "the [target]'s"))
    header = read_header(file)
    said: dict[str, list[str]] = {}
    named = [(keys, whose) for keys, whose in tried if _fits(header, meta["target"] | keys | (given or {}), False)]
    for keys, whose in named + tried:  # a set naming the file's channels before one counting its columns
        channels = meta["target"] | keys | (given or {})
        if _fits(header, channels, True):
            return keys, whose
        names = _channel_names(channels)
        said.setdefault(", ".join(f"{k} '{n}'" for k, n in names.items()), []).append(whose)
    asked = " --key tacho=NAME" if _tacho_records(meta) != "none" else ""
    if foreign:
        others = ", ".join(e for e, k in formats.items() if k)  # none: every file read with the [target]'s
        others = f", not another file's own (the run's {others} files')" if others else ""
        raise GearlabInputError(
            f"{file}: a {fmt or 'suffix-less'} file, a format the run read none of, is read with the [target]'s keys "
            f"alone{others}: {', '.join(said)} not in it; the file has: "
            f"{channel_listing(header.channels)}; expected its channels, and its units where the [target]'s do not "
            f"hold: gearlab score RUN FILE --key vibration=NAME{asked} [--key sensitivity=... | gain=... | unit=...]"
        )
    raise GearlabInputError(
        f"{file}: the run's channel keys are not in it: tried "
        + "; ".join(f"{k} ({', '.join(dict.fromkeys(w))})" for k, w in said.items())
        + f"; the file has: {channel_listing(header.channels)}; expected its channels: gearlab score RUN FILE "
        f"--key vibration=NAME{asked}"
    )


def _channel_names(channels: dict) -> dict:
    return {k: channel_key(channels[k]) for k in ("vibration", "tacho") if channels.get(k) not in (None, "")}


def _fits(header, channels: dict, indexed: bool) -> bool:
    """Whether *header* holds the vibration and tacho *channels* name, by name (or, *indexed*, by column index)."""
    names = _channel_names(channels).values()
    if indexed:  # a column index on the file's time column is none (the reader refuses it: readers.base.not_time)
        return not header.channels or all(header.find(n) and not _on_time(header, n) for n in names)
    return bool(header.channels) and all(header.resolve(n) in header.channels for n in names)


def _on_time(header, name: str) -> bool:
    """Whether channel *name* is a column index landing on *header*'s time or rate column (a WAV run's '0' on a CSV's
    'time_s')."""
    index = str(name).strip()
    return name not in header.channels and index.isdigit() and is_rate_or_time(header.channels[int(index)])


def _ratio(shaft) -> list[int]:
    return [shaft.ratio.numerator, shaft.ratio.denominator]


def _scoring_condition(
    run: RunDir, meta: dict, name: str, records: list[tuple[TargetFile, np.ndarray]], levels: dict, marks=None
) -> dict:
    """A condition as read_target makes it, from the stored history and the new *records*
    (standardised and aligned as the run's records were; *levels*: {path: its take_level, read as the run read
    its takes'}; *marks*: {path: the input angles a record's first tacho mark may find it at} where its own tacho
    shaft or marks a turn are not the run's)."""
    c = meta["conditions"][name]
    arrays = scoring.load_arrays(run.file("scoring", c["file"]))
    standardiser = Standardiser(*(float(v) for v in arrays["standardiser"]))
    parts = np.split(arrays["history"], np.cumsum([n for _, n in c["history"]])[:-1])
    typical, old = kept_level(c, parts, standardiser.std)
    ratio = {f.path: level_ratio(levels[f.path], typical) for f, _ in records}
    # a history saved at other points a revolution (an older gearlab's records): the takes read on its grid
    records = [(f, at_points(revs, arrays["history"].shape[1])) for f, revs in records]
    history = [(TargetFile(path, path, "history", "", name), revs) for (path, _), revs in zip(c["history"], parts)]
    keys = meta["target"]
    # a run from before "marks" was kept aligned at the [target]'s marks alone
    reference, ppr = arrays["reference"], meta.get("marks") or tacho_shaft(keys).marks(keys["pulses_per_rev"])
    tacho = True if _tacho_records(meta) == "all" else None  # aligned by its marks (aligned()'s flag)
    if "unit_shaft" in meta:  # a slower shaft's revolutions: turned by correlation, as the run's were
        tacho = None
    continuous = bool(meta.get("later_orders"))  # as read_target shifted the run's records
    # a new file's own marks beside the run's, as the run aligned files of other marks (Target.marks): an output
    # tacho's 2 marks on a 21/59 box find the input at 42 angles, where the run's input tacho found it at 1
    at = {f.path: math.lcm(ppr, (marks or {}).get(f.path, ppr)) for f, _ in records}
    test = [(f, aligned(reference, standardiser.apply(revs), tacho, at[f.path], continuous)[1]) for f, revs in records]
    blocks = meta["blocks"]
    per_record = [unit_sets(r, blocks, True) for _, r in history]
    return {
        "history": history,
        "test": test,
        "max_order": c["max_order"],
        "unit_max_order": c.get("unit_max_order", c["max_order"]),
        "history_units": {u: np.concatenate([s[u] for s in per_record]) for u in per_record[0]},
        "history_records": {
            u: [(len(s[u]), record_effects.independent_units(len(s[u]), *unit_window(u))) for s in per_record]
            for u in per_record[0]
        },
        "test_units": {f.path: unit_sets(r, blocks, False) for f, r in test},
        "levels": {  # another load? a take reversed against the history (by the marks or, no tacho, any turn)?
            f.path: "; ".join(  # or turned off its marks (the box running the other way)?
                w for w in (level_line(ratio[f.path]), old, turned_line(t, reference, not tacho)) if w
            )
            for (f, r), (_, t) in zip(records, test)
        },
        # read off its tacho's marks, not reversed (the box running the other way?): its tooth, turned_tooth's, at so
        # many marks a turn
        "turned": {f.path: at[f.path] for f, t in test if read_off_mark(t, reference, not tacho)},
        "level_ratio": ratio,  # the run's measure (take_level over history_level), its reference as the run kept it
        # how far the history's own takes lie off their median level (the largest |log|; its revolutions as stored,
        # their scale not the standardiser's): a take further off, called with no gear named, is told its level
        # whatever LEVEL_OFF says (called_level)
        "level_spread": history_spread([r for _, r in history]),
    }


def _same_input(run: RunDir, meta: dict) -> None:
    """A run whose learned methods saw another input than this gearlab gives them is refused: on
    the outside-user check's gearbox E (18/67 + 29/71), a run trained on version 1's input scored
    its healthy take with version 2's 40 of 40 record10 units called by likelihood_ratio (0 of 40
    with its own input). A run of an older version of a train with no such mesh saw what this one
    gives."""
    made = meta.get("input_version", 1)
    if made == INPUT_VERSION or (made in LATER_INPUT and not meta.get("later_orders")):
        return

    def said(v) -> str:
        known = isinstance(v, int) and v in LATER_INPUT
        return f"a later mesh of no whole input order {LATER_INPUT[v]}" if known else "not one this gearlab knows"

    raise GearlabInputError(
        f"{run.path}: {scoring.SCORING_FILE}: input_version {made} ({said(made)}); this gearlab's learned input "
        f"is version {INPUT_VERSION} ({said(INPUT_VERSION)}), for which the run's models and thresholds do not "
        "hold; expected a run of this version: run the scenario again"
    )


_stretch = stretch  # the shared rule's (detection_in_band: one for a detection run and for score)


def in_band(meta: dict, path: str, rec, asked: str | None, far: str = "") -> tuple[str, object, str]:
    """(condition, the part of *rec* scored, what was scored in words) of a take whose speed varies (a run-up or
    coast-down): its longest stretch of revolutions within IN_BAND of a condition's history speed (the condition
    *asked*, else the one of the longest), its mean speed the part's (detection_in_band.in_band, as a detection run
    cuts its own test takes). None there: one line, *far* (why its mean speed is no condition's) and how many
    revolutions lay in the band, and how many a unit needs."""
    names = [condition_of(meta, path, rec.speed_hz, asked)] if asked is not None else list(meta["conditions"])
    whose = " input" if "unit_shaft" in meta else ""  # the units: another shaft's revolutions
    got = shared_in_band(rec, {c: meta["conditions"][c]["speed_hz"] for c in names}, whose)
    if not got.said:
        said = f"; {got.inside} of its {len(rec.speeds)} revolutions within {IN_BAND:.1%} of the history's "
        said += f"{got.centre:.2f} Hz ('{got.condition}'), a unit needs 1"
        raise GearlabInputError(
            f"{far or f'{path}: {span(rec.angle_source)}'}{said}"
            + ("" if far else "; expected a take that runs a while at a trained condition's speed")
        )
    return got.condition, got.record, got.said


def _units_of_part(meta: dict, path: str, said: str, units: int) -> str:
    """in_band's words *said* of a run-up's part that makes *units* revolutions of the units' shaft, with the unit
    kinds it is too short for (not scored); one line where it makes none (a slower shaft's turn is longer)."""
    shaft = f"{meta['unit_shaft'][0]}-shaft " if "unit_shaft" in meta else ""
    if not units:
        raise GearlabInputError(
            f"{path}: {said}: 0 {shaft}revolutions, a unit needs 1; expected a take that runs a while at a trained "
            "condition's speed"
        )
    short = [b for b in meta["blocks"] if b > units]
    if not short:
        return said
    kinds = ", ".join(f"record{b}" for b in short)
    return f"{said}; {kinds} not scored: a unit needs {', '.join(map(str, short))} {shaft}revolutions, it has {units}"


def _learned_scores(run: RunDir, record: dict, seen: dict, rule: Rule, by_unit: dict) -> dict:
    """{path: {unit: scores}} of a learned method's record (one training, an ensemble of seeds, or
    crossed folds) on the units *seen* ({path: {unit: X}} as the method sees them)."""
    models = scoring.MODELS

    def raw(unit: str) -> dict:
        model = scoring.load_model(run.file(*models), unit)
        return {p: {u: fault_score(model, X, "cpu") for u, X in units.items()} for p, units in seen.items()}

    if "members" in record:  # an ensemble: the median of its members' history-standardised scores
        members = [by_unit[m] for m in record["members"]]
        parts = []
        for m in members:
            scored, ms = raw(m["unit"]), rule.models(m["history_scores"])
            parts.append({p: {u: ms[u].standardised(s) for u, s in units.items()} for p, units in scored.items()})
        return {p: {u: np.median([q[p][u] for q in parts], axis=0) for u in seen[p]} for p in seen}
    if "folds" in record:  # crossed: the mean over the folds, each standardised by its training's records
        parts = []
        for k, name in enumerate(record["folds"]):
            fold = by_unit[name]
            keep = [i for i in range(len(record["folds"])) if i != k]
            scored = raw(name)
            fitted = {u: rule.model(u, fold["history_scores"][u], keep=keep) for u in fold["history_scores"]}
            parts.append({p: {u: fitted[u].standardised(s) for u, s in units.items()} for p, units in scored.items()})
        return {p: {u: np.mean([q[p][u] for q in parts], axis=0) for u in seen[p]} for p in seen}
    return raw(record["unit"])


def _named_shaft(name: str, box) -> TachoShaft:
    """--key tacho_shaft's shaft of the run's description *box*; one line where it has none or no such shaft."""
    if box is not None:
        return TachoShaft.of(box, name, "--key tacho_shaft")
    if name != "input":
        raise GearlabInputError(
            f"--key tacho_shaft={name}: a shaft of a gearbox description, and the run has none; expected "
            "tacho_shaft=input (or a run whose [source] gives a 'gearbox' description)"
        )
    return TachoShaft(name)


def _marks(keys: dict) -> int:
    """The input angles a record read with *keys* (reading_keys') finds the input at its first tacho mark."""
    return tacho_shaft(keys).marks(keys.get("pulses_per_rev") or 1)


def _typed(value: str, types):
    """A --key's text as the [target]'s key takes it: a whole number for a key of integers alone."""
    types = types if isinstance(types, tuple) else (types,)
    whole = value.strip().lstrip("+-").isdigit()
    return int(value) if whole and int in types and str not in types else value


def reading_keys(meta: dict, condition: str | None, given: dict | None = None, file: str = "", box=None) -> dict:
    """cut_recording's keys for a new record, as the run read its target: its tacho; or without
    one the run's declared speed and description (the speed from its mesh orders). A run whose
    speeds were declared per file only gives a new record the speed of its condition's history:
    the condition asked (--condition), or the run's only one. *given*: acquisition keys of the new
    files ({'vibration': 'vib', 'fs': '25.6 kHz'}: gearlab score's --key, as a [target] 'files'
    entry gives them) over those the run's files of *file*'s format were read with (remembered), over
    the run's [target] keys: every key a 'files' entry takes (parts.measured.ACQUISITION), a tacho_shaft
    of the run's description (*box* where its keys have none: the one its source simulates)."""
    keys = dict(meta["target"]) | remembered(meta, file, given)[0]
    keys["gain"] = read_gain(keys.get("gain"))
    for key, value in (given or {}).items():
        at = f"--key {key}"
        # "" takes none of the run's (gain, sensitivity, unit, fs), as a [target] files entry's "" does: a next-week
        # npz in g beside a [target] gain in volts had no way to drop it ('expected KEY=VALUE ... did you mean gain')
        if key in ("vibration", "tacho", "pulses_per_rev") and value == "":  # no value of the run to drop
            raise GearlabInputError(f"{at}=: expected a value (without --key {key}, the run's is taken)")
        if key not in ACQUISITION:
            raise GearlabInputError(
                f"{at}={value}: expected KEY=VALUE, KEY one of {', '.join(ACQUISITION)}{did_you_mean(key, ACQUISITION)}"
            )
        if key in ("tacho", "tacho_shaft", "pulses_per_rev") and _tacho_records(meta) == "none":
            raise GearlabInputError(
                f"{at}: the run read its records without a tacho (their speed declared or from the mesh orders); "
                "expected no tacho (the new records are read as the run's were)"
            )
        if value != "":  # as the [target]'s are checked: its type, bounds, one line each
            declared = setting(**MEASURED[key]).metadata["setting"]
            value = _typed(value, declared.types)
            check_type(value, declared.types, at)
            in_bounds(declared, value, at)
        if key not in CALIBRATION:
            keys[key] = held(key, value, at)
    keys |= calibration({k: v for k, v in (given or {}).items() if k in CALIBRATION}, lambda k: f"--key {k}")
    gearbox = keys.pop("gearbox", None)  # a run from before the target could go without a tacho has none
    if gearbox:
        from ..gearbox import resolve_gearbox

        keys["gearbox"] = resolve_gearbox(gearbox)
    if isinstance(keys.get("tacho_shaft"), str):  # --key tacho_shaft=NAME: that shaft of the run's description
        keys["tacho_shaft"] = _named_shaft(keys["tacho_shaft"], keys.get("gearbox") or box)
    if "tacho_shaft" in keys:
        keys["tacho_shaft"] = tacho_shaft(keys)
    if keys["tacho"] is None and keys.get("speed_hz") is None and not gearbox:
        names = list(meta["conditions"])
        if condition is None and len(names) > 1:
            raise GearlabInputError(
                "--condition: missing; the run's records had no tacho and their speeds were declared per file: "
                f"expected the condition whose speed a new record runs at; known: {', '.join(names)}"
            )
        name = condition if condition is not None else names[0]
        if name in meta["conditions"]:  # an unknown one is refused, with the known ones, by condition_of
            keys["speed_hz"] = meta["conditions"][name]["speed_hz"]
    return keys


def score(
    run: RunDir, files, condition: str | None = None, on_event=lambda e: None, given: dict | None = None
) -> list[dict]:
    """New recordings scored by a finished run's trained methods at its thresholds, nothing trained
    again: one row per file, method and unit kind (its units' scores, how many are called, the
    threshold and the record's decision: more than half its units called, a fault (half, a tie such as 1
    of 2, is healthy) -- or "other damage: <gear>" when the record's change is localised on a gear the run
    does not watch, as the run's own which-gear table calls it (detection_which_gear.decision_of) -- with
    the localisation's evidence), appended to the run's scoring history."""
    meta = run.read_json(scoring.SCORING_FILE)
    if meta is None:
        raise GearlabInputError(
            f"{run.path}: no {scoring.SCORING_FILE}: not a finished detection run (or one from before gearlab "
            "score kept its models); expected a finished run: run the scenario again"
        )
    _same_input(run, meta)
    described = (localisation_of(run) or {}).get("preset")  # the source's description (or the run's copy), if any
    described = gearbox_of(described) if described else None
    # a bad --key or a missing condition: refused before any file is read
    reading_keys(meta, condition, given, box=described)
    cut, raw, found, marks, chosen, far, takes = {}, {}, {}, {}, {}, {}, own_conditions(run)
    levels: dict[str, float] = {}  # {file: its take_level, read as the run read its takes'}
    skipped: dict[str, str] = {}  # {file: why} of the takes refused, of several given
    history: dict = {}  # {condition: its history's stages as inspect reads them (history_stages)}
    for i, file in enumerate(files):
        digest = input_digest(Path(file))  # its content: a take scored again, renamed or not, is one take
        try:
            mine = takes.get(digest) if condition is None else None  # a take of the run's own: the run's condition
            asked = mine[0] if mine else condition
            keys = reading_keys(meta, asked, given, str(file), described)
            marks[str(file)] = _marks(keys)
            rec, scored_on = cut_recording(str(file), **keys, keep_read=True), None  # read once: the fit check's too
            speeds = rec.speeds is not None and len(rec.speeds) == len(rec.revolutions)
            try:
                name = condition_of(meta, str(file), rec.speed_hz, asked)
            except GearlabInputError as off:  # a speed far from every condition: another gearbox's record?
                other = other_gearbox(meta, str(file), keys, rec.speed_hz, box=described, read=rec.read)
                if other or VARIES_WORDS not in rec.angle_source or not speeds:
                    moved = moved_tacho(meta, str(file), keys, rec.speed_hz, described, rec.read)  # a tacho elsewhere
                    raise GearlabInputError((other or f"{off}{varies(rec.angle_source)}") + moved) from None
                # a run-up or coast-down: its revolutions at a condition's history speed
                name, rec, scored_on = in_band(meta, str(file), rec, asked, f"{off} ({span(rec.angle_source)})")
            else:
                if VARIES_WORDS in rec.angle_source and speeds:  # its mean speed a condition's, not its revolutions'
                    name, rec, scored_on = in_band(meta, str(file), rec, asked)
                elif asked is None:
                    name, chosen[str(file)] = by_level(run, meta, name, rec)
                else:
                    chosen[str(file)] = own_words(mine[1]) if mine else asked_off(meta, name, rec.speed_hz)
                    far[str(file)] = "" if mine else off_history(meta, name, rec.speed_hz)
            too_narrow(str(file), rec.fs, rec.speed_hz, meta["conditions"][name]["max_order"], "")  # as the run refuses
            # tooth counts within a condition's speed too: a count that differs for certain is another gearbox's take,
            # not scored (its changed mesh was called damage by every method); a doubtful one scored, said so
            report = inspected(meta, str(file), keys, rec.speed_hz, described, rec.read)
            box = keys.get("gearbox") or described
            if report is not None and name not in history:  # the run's history read as the take is, once a call
                history[name] = history_stages(run, meta, name, box)
            other = None if report is None else tooth_counts_differ(report, history[name])
            differs = gearbox_line(report, str(file), box, rec.speed_hz, far=False, other=other)
            if other is not None:
                raise GearlabInputError(differs)
            if differs:
                on_event(Event("log", message=f"warning: {differs}"))
            own, whose = remembered(meta, str(file), given)
            said = f"{whose} keys" if {k for k in own if k not in (given or {})} else ""
            revs = rec.revolutions
            if meta.get("spikes_out", False):  # the run's units: a sensor's isolated spikes bridged
                turns = meta["unit_shaft"][1] / meta["unit_shaft"][2] if "unit_shaft" in meta else 1.0
                revs = without_spikes(revs, rec.fs, rec.speed_hz, turns)
            levels[str(file)] = take_level(revs)  # before the units' shaft, as the run's (run_levels)
            if "unit_shaft" in meta:  # the run's units: revolutions of the watched gear's shaft, in its band
                _, p, q = meta["unit_shaft"]
                band = meta["conditions"][name]["max_order"]
                revs = unit_revolutions(revs, p, q, band, meta.get("input_shaft_out", False), rec.first_revolution)
            if scored_on:
                scored_on = _units_of_part(meta, str(file), scored_on, len(revs))
            # a run-up scored in band: its speed source's words say the span, not that its mean speed is its condition
            source = rec.angle_source
            if scored_on:
                source = source.rsplit("; ", 1)[0] + f"; {span(rec.angle_source)}"
            line = f"{file}: {rec.speed_hz:.3f} Hz, from {source}" + (said and f"; read with {said}")
            on_event(Event("log", message=line + (f"; {scored_on}" if scored_on else "")))
            # shown per file: a file of a format the run had none of borrows another file's keys, its calibration
            # too (an npz in volts read with an HDF5 test file's sensitivity = "": m/s², 98 x too small, 'nothing')
            found[str(file)] = (
                rec.speed_hz,
                source,
                said,
                rec.units,
                differs,
                scored_on,
                rec.warnings + full_scale_elsewhere(meta, given, file_format(str(file))),
                digest,
            )
            cut.setdefault(name, []).append((TargetFile(str(file), str(file), "test", "", name), revs))
            if not far.get(str(file)):  # far off the history's speed: its shafts' residuals are not comparable
                raw.setdefault(name, []).append((str(file), Take.of(rec)))  # as the run's own (detection_which_gear)
        except GearlabInputError as refused:  # of one take of several: the others are scored, this one named
            if len(files) == 1:
                raise
            skipped[str(file)] = refused_why(str(file), refused)
            for made in (marks, chosen, far):
                made.pop(str(file), None)
            on_event(Event("log", message=f"{file}: not scored: {skipped[str(file)]}"))
        on_event(Event("advance", stage="records", done=i + 1, total=len(files)))
    if not cut:  # every take refused: as one take is, in one line (each alone says its own why), nothing written
        first, why = next(iter(skipped.items()))
        raise GearlabInputError(f"none of the {len(files)} takes scored ({', '.join(skipped)}); {first}: {why}")
    conds = {name: _scoring_condition(run, meta, name, records, levels, marks) for name, records in cut.items()}
    turned = {p: m for c in conds.values() for p, m in c["turned"].items()}  # read off their marks: the tooth so
    localised = localise_scored(run, raw, turned)  # which gear each record's change is on (detection_which_gear)
    localised.update({p: not_read(w) for p, w in far.items() if w and described is not None})  # far off: not read
    stale = stale_calls(run, localised)  # a take of the run's own, its table decided by an older rule
    for path, line in stale.items():
        on_event(Event("log", message=f"warning: {path}: {line}"))
    by_unit = {r["unit"]: r for r in run.records()}
    classical = stored_classical(meta["classical"])
    rows = []
    for name, records in cut.items():
        cond = conds[name]
        rule = Rule(meta["threshold"], meta["false_alarm"], cond["history_records"])
        shown = synchronous_input(
            learned_input(meta["input"], meta["points"], classical, cond["unit_max_order"]),
            tuple(meta.get("later_orders", ())),
        )
        seen = {p: {u: shown(X) for u, X in units.items()} for p, units in cond["test_units"].items()}
        for r in by_unit.values():
            if r["condition"] != name or r.get("seed") is not None or r.get("fold") is not None:
                continue
            if r["adapter"] is None:
                made = classical_record(r["method"], name, cond, classical, rule)
                scores, thresholds = made["test_scores"], made["thresholds"]
            else:
                with one_thread():  # as the run scored its takes: the run's own take gets its scores bit for bit
                    scores, thresholds = _learned_scores(run, r, seen, rule, by_unit), r["thresholds"]
            for f, _ in records:
                for u, s in scores[f.path].items():
                    s = np.asarray(s, dtype=np.float64)
                    called = int(np.sum(s > thresholds[u]))
                    where = localised.get(f.path, {})
                    ratio = cond["level_ratio"][f.path]  # off its history's, nothing localised: a level change
                    decision = decision_of(most_called(s, thresholds[u]), where.get("call"), ratio)
                    if not s.size:  # a take (a run-up's part: _units_of_part) too short for this unit: no 0/0 healthy
                        decision = "not scored"
                    rows.append(
                        {
                            "file": f.path,
                            "condition": name,
                            "condition_by": chosen.get(f.path, ""),  # by level at one speed; or --condition far off
                            "method": r["method"],
                            "unit": u,
                            "units": int(s.size),
                            "called": called,
                            "threshold": float(thresholds[u]),
                            "rule": meta["threshold"],
                            "median_score": float(np.median(s)) if s.size else None,
                            # over half its units called (a tie, 1 of 2: healthy): a fault, or other damage
                            # where the record's change lies on another gear (the detection run's which-gear rule)
                            "decision": decision,
                            "speed_hz": found[f.path][0],
                            "speed_from": found[f.path][1],  # the tacho, a declared speed, the mesh orders
                            "read_with": found[f.path][2],  # whose keys read the file ("": the [target]'s, --key's)
                            "values": found[f.path][3],  # how its values became m/s² (its units)
                            "gearbox": found[f.path][4],  # where its lines do not fit the run's description
                            "scored_on": found[f.path][5],  # a run-up's revolutions at the history's speed (in_band)
                            "flaws": list(found[f.path][6]),  # what its acquisition did: clipped, a dropout, a drift
                            "digest": found[f.path][7],  # its content: scored again or renamed, one take of the history
                            "level": cond["levels"][f.path],  # off its history's: another load (level_warnings)
                            "level_ratio": cond["level_ratio"][f.path],  # the run's table's measure (run_levels)
                            # its thresholds of one history take, as the run's verdict says it (one_take)
                            "history": one_take(name, [(r.get("history_models") or {}).get(u)]),
                            "localised": where.get("named"),
                            "call": where.get("call"),
                            "evidence": where.get("evidence"),  # z per shaft over its threshold, the tooth
                            "table_call": stale.get(f.path),  # the run's own take, called otherwise in its table
                            "nonsync": where.get("nonsync"),  # the residual's z, threshold, strike order
                            "scores": [float(x) for x in s],
                        }
                    )
        for f, _ in records:  # the level said where the call may be its change, whichever method's threshold
            mine = [r for r in rows if r["file"] == f.path]
            called = any(r["decision"] == "fault" or is_undetermined(r["decision"]) for r in mine)
            ratio, takes = cond["level_ratio"][f.path], len(cond["history"])
            said = called_level(called, mine[0]["localised"], ratio, cond["level_spread"], takes)
            for r in mine if said else ():
                r["level"] = "; ".join(w for w in (said, r["level"]) if w)
            flagged = any(r["decision"] not in ("healthy", "not scored") for r in mine)
            flaws, scored_on = clipped_call(flagged, mine[0]["flaws"]), reversed_call(flagged, mine[0]["scored_on"])
            # no flag's name beside every 'healthy': the take's call says nothing was called; other damage localised
            # on an unwatched gear stays said (unwatched)
            call = decided_call(mine[0]["call"], flagged)
            # a level change (decision_of) is the take's call, in the history too: not 'watched-gear fault (not ...)'
            call = next((r["decision"] for r in mine if is_level_change(r["decision"])), call)
            for r in mine:
                r["flaws"], r["scored_on"], r["call"] = flaws, scored_on, call
    # in the order the files were given (week 1, 2, 3, ...), not grouped by condition: the printout and the trend
    given = {str(f): i for i, f in enumerate(files)}
    rows.sort(key=lambda r: given[r["file"]])
    notes = unwatched(rows)
    for r in rows:  # kept per take in the history: its trend point is marked (score_trends), not a plain 'healthy'
        r["unwatched"] = notes.get(r["file"])
    scoring.append_history(run, rows)
    if skipped:  # the scored takes' rows, then one per take refused (its why), in the order given; kept apart
        rows = sorted(rows + skipped_rows(skipped), key=lambda r: given[r["file"]])
        scoring.append_skipped(run, [r for r in rows if r.get("skipped")])
    trends = score_trends(run)
    if trends:
        from .detection_figures import score_trend

        score_trend(trends, run.file("figures", "score_trend.png"))
        # the report's text under the chart (report.build_report: a figure's note): when it first crossed, where
        run.file("figures", "score_trend.txt").write("\n".join(first_called(scoring.read_history(run))))
    return rows


def score_trends(run: RunDir) -> list:
    """Per condition and method: the median score of each scored record's longest TSA units, in the
    order they were scored, less the threshold, over the method's largest (gearlab.parts.scoring's
    history); the title names each point's file, the records a method called other damage (on a
    gear the run does not watch) and those localised there that no method called (unwatched)."""
    from ..charts import Chart, Curve

    rows = scoring.read_history(run)
    out, scored = [], {r.get("digest") for r in rows}
    # the takes refused among several scored at once, not scored since (by content): no point, named under each chart
    skipped = scoring.read_skipped(run)
    refused = {Path(r["file"]).name: r["skipped"] for r in skipped if r["digest"] is None or r["digest"] not in scored}
    for c in dict.fromkeys(r["condition"] for r in rows):
        # the longest unit kind a take of the condition was scored on: a history of takes all too short for the
        # longest kind (record30 'not scored' on 11 output-shaft turns) drew no chart where record10 had points
        held = [r for r in rows if r["condition"] == c]
        longest = longest_tsa(r["unit"] for r in held) or "revolution"
        unit = longest_tsa(r["unit"] for r in held if r["median_score"] is not None) or "revolution"
        picked = [r for r in held if r["unit"] == unit and r["median_score"] is not None]
        curves, other, files, tops, parts = [], {}, [], [], {}
        quiet = unwatched(held)  # from the rows, so a history scored before the note was kept is marked too
        for m in dict.fromkeys(r["method"] for r in picked):
            mine = [r for r in picked if r["method"] == m]
            files = files if len(files) >= len(mine) else [Path(r["file"]).name for r in mine]
            x = list(range(1, len(mine) + 1))
            y = [r["median_score"] - r["threshold"] for r in mine]
            # each method's margin over its largest: a likelihood ratio's hundreds flattened a matched
            # filter's 0.1 onto the line, its crossing unseen (outside check D); the sign, the call, stays
            top = max(abs(v) for v in y) or 1.0
            curves.append(Curve(m, x, [v / top for v in y]))
            tops.append(f"{m} {top:.3g}")
            for i, r in enumerate(mine, 1):
                d = r["decision"]
                if is_other(d) or is_undetermined(d) or is_level_change(d):  # no watched gear's fault
                    other.setdefault(r["decision"], set()).add(i)
                elif r["file"] in quiet:  # damage on a gear not watched, under every threshold: marked all the same
                    other.setdefault(quiet[r["file"]], set()).add(i)
                if r.get("scored_on"):  # a run-up's part: which revolutions the point is of
                    parts[f"record {i}"] = r["scored_on"]
        said = "".join(
            f"; records {', '.join(map(str, sorted(n)))}: {d}" if len(n) > 1 else f"; record {min(n)}: {d}"
            for d, n in other.items()
        )
        # a run-up whose part is too short for this unit: no point, said so
        left = [r for r in rows if r["condition"] == c and r["unit"] == unit and r.get("scored_on")]
        parts |= {Path(r["file"]).name: r["scored_on"] for r in left if r["median_score"] is None}
        said += "".join(f"\n{k}: {w}" for k, w in parts.items())
        if longest != unit:
            said += f"\n{longest}: not scored, every take too short for its unit ({unit} shown)"
        said += "".join(f"\nnot scored: {n}: {w.split('; ')[0]}" for n, w in list(refused.items())[-3:])
        said += "".join(f"\n{line}" for line in first_called(held))  # which take first crossed, where
        named = [f"{i} {f}" for i, f in enumerate(files, 1)]  # which take each point is, in the TUI too
        named = named if len(named) <= 12 else [*named[:5], "...", *named[-5:]]
        if curves:
            out.append(
                Chart(
                    f"{c}: scored records, {unit} (median score less the threshold, over each method's largest: "
                    f"above 0 is called){said}\nrecords: {', '.join(named)}; largest: {', '.join(tops)}",
                    "record scored (in order)",
                    "(score - threshold) / largest",
                    tuple(curves),
                    xticks=list(range(1, len(files) + 1)) if len(files) <= 20 else None,
                    hlines=(0.0,),
                )
            )
    return out
