"""What the scenario kinds share: the dataset table of a scenario and its resolution into a
dataset spec (simulated preset or measured file), class sizes known before anything is
built, the executor and device of [execution], and the --quick shrinking of a training
protocol. The kind contract itself is gearlab.kinds.contract.ScenarioKind."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

from ..data.channel_units import declared_unit
from ..data.importers import MeasuredSpec
from ..data.placement import canonical_faults, model_shafts
from ..data.recordings import (
    channel_key,
    check_measured_file,
    check_recording,
    only_vibration,
    pulses_without_tacho,
)
from ..data.spec import CH5_STEPS, DATASET_PRESETS, FAULTS, POINTS, DatasetSpec, NoiseSpec, dataset_preset
from ..data.textzip import CALIBRATION, calibration, parse_sensitivity
from ..effects import effects_from_tables
from ..errors import GearlabInputError, shown
from ..executors import make_executor
from ..files import one_file, take_file
from ..learn.protocol import Counts
from ..parts.measured import ACQUISITION, pulses_of, tacho_shaft_of
from ..registry import get_registry
from ..scenario import Scenario, Table, check_type, keys_of, location, plain_name
from ..settings import from_inline, in_bounds, setting
from ..units import rate_hz, to_si

# --- the keys of a measured recording, declared once ---------------------------------------------
# Every table that reads a recording ([[datasets]] and the [source]'s 'file', the gap's and the
# detection's [target]) names these keys with measured(): one wording, one set of bounds and one
# one-line error each, checked when the table is read (`gearlab validate`); a kind gives only its
# own default where it differs (docs/settings.md lists it per table).


def _column(value, where: str):
    """A channel: a name, or a 0-based column index."""
    if isinstance(value, int) and not isinstance(value, bool) and value < 0:
        raise GearlabInputError(f"{where}: a column index is 0 or more, got {value}")
    return value


def _unit(value, where: str):
    """A declared unit, or '' (none declared: what a run's resolved scenario.toml writes back)."""
    return declared_unit(value, where)


def _quantity_of(key: str):
    def check(value, where: str):
        _quantity(value, key, where)
        return value  # as written: the kind converts it (quantity) when it builds

    return check


def _sensitivity(value, where: str):
    parse_sensitivity(value, where)
    return value


def _gain(value, where: str):
    calibration({"gain": value}, lambda _: where)
    return value


def _files(value, where: str):
    """A 'files' list: each entry's own acquisition keys (parts.measured.ACQUISITION) checked as this
    table declares the [target]'s (MEASURED: types, bounds, choices), one line naming the entry."""
    for i, entry in enumerate(value):
        for key in ACQUISITION:
            # "" on a file: the [target]'s value not taken (a history in volts, a test file in m/s²: sensitivity = "")
            if isinstance(entry, dict) and key in entry and entry[key] != "":
                at = f"{where} entry {i + 1} key '{key}'"
                meta = setting(**MEASURED[key]).metadata["setting"]
                check_type(entry[key], meta.types, at)
                in_bounds(meta, entry[key], at)
    return value


TRANSIENTS = ("stats", "none")
_SAME = object()  # measured(): the declared default

MEASURED = {
    "file": {
        "types": str,
        "default": "",
        "doc": "measured data: a .csv, .txt, .zip (of one text file), .npz, .h5, .wav or .mat file, relative "
        "to the scenario; a glob pattern: the one file it matches ([[datasets]]: a dataset of each)",
    },
    "files": {
        "types": list,
        "default": [],
        "check": _files,
        "doc": "measured records, each {file, role = 'history' | 'test', label, condition, speed (the last "
        "two optional)}, relative to the scenario ('file' a glob pattern: each file it matches); a gap "
        "diagnosis reads the history (healthy, one speed); "
        f"an entry may give its own {', '.join(ACQUISITION[:-1])} or {ACQUISITION[-1]}",
    },
    "vibration": {
        "types": (int, str),
        "default": "",
        "check": _column,
        "doc": "measured data: the vibration channel (name or 0-based column; default: the file's one "
        "channel besides the tacho and time)",
    },
    "tacho": {
        "types": (int, str),
        "default": "",
        "check": _column,
        "doc": "measured data: a tacho channel (shaft angle or pulses; name or 0-based column); or give "
        "'speed' or 'gearbox'",
    },
    "tacho_shaft": {
        "types": str,
        "default": "",
        "doc": "measured data: the shaft the tacho reads, a shaft of the gearbox description (the [source]'s, "
        "or this table's 'gearbox'), e.g. 'output' (default: its [sensor] tacho, else the input); its angle "
        "over that shaft's turns per input turn is the input's",
    },
    "pulses_per_rev": {
        "types": int,
        "default": None,
        "low": 1,
        "high": 10_000,
        "doc": "measured data: tacho pulses per revolution of the shaft it reads (default: the gearbox "
        "description's [sensor] pulses_per_rev, else 1)",
    },
    "speed": {
        "types": (int, float, str),
        "default": None,
        "unit": "Hz",
        "check": _quantity_of("speed"),
        "doc": "input-shaft speed in (0, 1 kHz], e.g. '25 Hz' or '1500 rpm': a simulation's; of measured "
        "data without a tacho, the records' (a 'files' entry may give its own), refined to ±1 % by "
        "a 'gearbox' description's mesh orders",
    },
    "fs": {
        "types": (int, float, str),
        "default": None,
        "unit": "Hz",
        "check": _quantity_of("fs"),
        "doc": "sampling rate in (0, 10 MHz], e.g. '200 kHz' or '51.2 kS/s' (an angle's unit, rpm or rad/s, is "
        "refused: a shaft's speed): a simulation's integration rate; of measured "
        "data, when a file carries none",
    },
    "gearbox": {
        "types": str,
        "default": "",
        "doc": "a gearbox description (file relative to the scenario, or a built-in name): of measured data "
        "without a tacho, the mesh orders each record's speed is found from (with one, the shafts "
        "'tacho_shaft' names; a [target]'s default: the [source]'s, whose tooth counts and speed it must "
        "have); without 'file' or 'files', "
        "the simulator (its model, values, channel, speed, load; 'preset' then gives only the faults and "
        "sizes)",
    },
    "sensitivity": {
        "types": (int, float, str),
        "default": None,
        "unit": "V*s^2/m",
        "check": _sensitivity,
        "doc": "measured data: sensor sensitivity, e.g. '10 mV/g' or '10 g/V' (a number: V per m/s²); without it "
        "or 'gain' the units are unknown",
    },
    "unit": {
        "types": str,
        "default": "",
        "check": _unit,
        "doc": "measured data: the vibration channel's unit where neither its name ('acc_V', 'acc [g]') nor "
        "the file says it (a headerless column): 'm/s^2', 'g', or 'V' / 'mV' with a 'sensitivity'",
    },
    "gain": {
        "types": (int, float, str),
        "default": None,
        "unit": "V",
        "check": _gain,
        "doc": "measured data: volts per file unit with a 'sensitivity', e.g. '0.3 mV' per count of an integer "
        "record (WAV: at full scale); or, without one, g per volt ('10 g/V') or per file unit ('50 g' at full scale)",
    },
    "takes": {
        "types": str,
        "default": "",
        "doc": "measured data: the column marking each sample's take in a logger's file of several takes one after "
        "another (e.g. 'segment'): each take a record of its own, named 'file.csv[segment=3]' (one take alone: "
        "file = 'file.csv[segment=3]')",
    },
    "transient": {
        "types": str,
        "default": "stats",
        "choices": TRANSIENTS,
        "doc": "measured data: 'stats' drops a start-up transient, 'none' keeps every revolution",
    },
}


def measured(name: str, default=_SAME):
    """The settings field of the measured-data key *name* (MEASURED), with a kind's own *default*
    where it differs (dataclasses.MISSING: required)."""
    declared = dict(MEASURED[name])
    if default is not _SAME:
        declared["default"] = default
    return setting(**declared)


@dataclass(frozen=True, kw_only=True)
class DatasetEntry:
    """A dataset table ([[datasets]], [source], [target]): a simulated preset or a measured file."""

    preset: str = setting(str, "", doc=f"dataset preset: {', '.join(DATASET_PRESETS)} (or give 'gearbox' or 'file')")
    file: str = measured("file")
    vibration: int | str = measured("vibration")
    tacho: int | str = measured("tacho")
    tacho_shaft: str = measured("tacho_shaft")
    pulses_per_rev: int = measured("pulses_per_rev")
    gearbox: str = measured("gearbox")
    labels: str = setting(str, "", doc="measured data: an optional label channel")
    class_names: list = setting(list, ["healthy", "fault"], doc="measured data: class names, healthy first")
    transient: str = measured("transient")
    sensitivity: float | str | None = measured("sensitivity")
    unit: str = measured("unit")
    gain: float | str | None = measured("gain")
    takes: str = measured("takes")
    name: str = setting(
        str, "", check=lambda v, where: v and plain_name(v, where), doc="label (default: the preset name)"
    )
    model: str = setting(str, "", doc="dynamic model plugin (default: the preset's)")
    model_preset: str = setting(str, "", doc="the model's parameter preset (default: the preset's)")
    channel: str = setting(str, "", doc="measurement channel, e.g. pinion_x, casing_x")
    speed: float | str | None = measured("speed")
    load: float | str | None = setting((int, float, str), None, doc="load torque, e.g. '7 N*m'", unit="N*m")
    faults: dict | list | None = setting(
        (dict, list),
        None,
        doc="{fault = [steps]} replacing the preset's ladders (input pinion), or a list of "
        "{name, gear, stage, steps}, gear 'pinion', 'wheel' or words ('output gear')",
    )
    teeth: list | None = setting(list, None, doc="teeth carrying faults (default: all of the faulted gear)")
    duplicates: int | None = setting(int, None, low=1, doc="samples per fault, ladder step and tooth")
    healthy: int | None = setting(int, None, low=0, doc="healthy samples")
    revolutions: int | None = setting(int, None, low=1, doc="J noisy revolutions per sample (TSA averages them)")
    tsa: bool | None = setting(bool, None, doc="a sample is the synchronous average of its J revolutions")
    seed: int | None = setting(int, None, low=0, high=2**32 - 1, doc="seeds the dataset's noise and effect draws")
    fs: float | str | None = measured("fs")
    effects: list | None = setting(
        list,
        None,
        doc="unmodelled effects, the recording's noise among them, e.g. [{name = 'drive_inertias'}, "
        "{name = 'sensor_noise', kind = 'laplace', snr_db = 0, seed = 1}] (gearlab plugins lists them); "
        "they replace the preset's, its noise too. A sensor_noise with a seed is drawn from that seed "
        "after every other effect (list it last); without one, at its place from the effects' streams",
    )


# The one declaration of a recording's noise is this effect; a table's older noise key says so
NOISE_EFFECT = "sensor_noise"
NOISE_MOVED = {
    "noise": 'a recording\'s noise is an effect: effects = [{ name = "sensor_noise", kind = "laplace", '
    "snr_db = 0.0, seed = 1 }] (with a seed it is drawn from it after every other effect; docs/scenarios.md)"
}
DATASET_TABLE = Table(keys_of(DatasetEntry), array=True, required=True, moved=NOISE_MOVED)


@dataclass(frozen=True, kw_only=True)
class SourceEntry(DatasetEntry):
    """The [source] of a benchmark kind (gap_benchmark, transfer_benchmark): a simulated entry."""

    preset: str = setting(str, "B-6-ch5", doc="dataset preset of the source simulator (default B-6-ch5)")


# Records without a 'condition' whose speeds lie within this fraction are one operating condition: a detection run's
# history (detection_records.conditions_of) and a gap's (gap_inputs.read_history) alike.
SPEED_GROUP = 0.05

# Samples a simulated dataset may hold (4096 float32 each: 16 GB); the thesis's largest has
# 12 800. The table's keys bound no product, so absurd sizes are refused before any work.
MAX_SAMPLES = 10**6


# keys of a measured 'file' entry that mean nothing to a simulated preset
MEASURED_ONLY = (
    "vibration",
    "tacho",
    "tacho_shaft",
    "labels",
    "sensitivity",
    "unit",
    "gain",
    "pulses_per_rev",
    "takes",
)


# a benchmark's simulated [source] takes the dataset keys but a measured file's and its labels'
_NOT_SIMULATED = ("file", "class_names", "transient", *MEASURED_ONLY)
SOURCE_KEYS = keys_of(SourceEntry, tuple(k for k in DATASET_TABLE.keys if k not in _NOT_SIMULATED))


def dataset_spec(entry: dict, where: str, base: Path) -> DatasetSpec | MeasuredSpec:
    """A dataset preset with the entry's overrides applied, or a measured file to import
    (shared by the dataset, transfer and gap kinds). *base*: the scenario's folder."""
    if bool(entry["preset"] or entry.get("gearbox") and not entry["file"]) == bool(entry["file"]):
        raise GearlabInputError(
            f"{where}: give exactly one of 'preset' or 'gearbox' (simulated) or 'file' (measured data)"
        )
    if entry["file"]:
        if entry.get("effects"):
            raise GearlabInputError(f"{where} key 'effects': effects act on simulations; a measured 'file' has none")
        return measured_spec(entry, where, base)
    for key in MEASURED_ONLY:  # said of a simulation, such a key would be silently ignored
        if entry.get(key) not in (None, "") and not (key == "pulses_per_rev" and entry[key] == 1):
            raise GearlabInputError(
                f"{where} key '{key}': a key of measured data ('file'); a simulated 'preset' has none"
                + (" (its channel is chosen with 'channel')" if key == "vibration" else "")
            )
    spec = dataset_preset(entry["preset"], where) if entry["preset"] else None
    if entry.get("gearbox"):
        spec = described_spec(entry, where, base, spec)
    changes = {}
    for key in ("model", "channel"):
        if entry[key]:
            changes[key] = entry[key]
    if entry["model_preset"]:
        changes["preset"] = entry["model_preset"]
    if entry["name"]:
        changes["name"] = changes["domain"] = entry["name"]
    for key in ("speed", "load", "fs"):
        if entry[key] is not None and not (key == "load" and entry.get("gearbox")):  # described_spec's
            changes[{"speed": "speed_hz", "load": "load_nm", "fs": "fs"}[key]] = quantity(entry, key, where)
    if entry["faults"] is not None:  # {fault = [steps]} or [{name, gear, stage, steps}]: data.placement
        shafts = model_shafts(changes.get("model", spec.model), changes.get("preset", spec.preset), where)
        changes["faults"] = canonical_faults(entry["faults"], shafts, where)
    if entry["teeth"] is not None:
        if not all(isinstance(t, int) and not isinstance(t, bool) for t in entry["teeth"]):
            raise GearlabInputError(
                f"{where} key 'teeth': expected a list of tooth numbers, got {shown(entry['teeth'])}"
            )
        changes["teeth"] = tuple(entry["teeth"])
    for key in ("duplicates", "healthy", "revolutions", "tsa", "seed"):
        if entry[key] is not None:
            changes[key] = entry[key]
    if entry.get("effects") is not None:
        changes["effects"], changes["noise"] = effects_and_noise(entry["effects"], f"{where} key 'effects'")
    spec = spec.with_(**changes)
    spec.check(where)
    spec.check_model(where)  # model, preset, channel, faults and teeth: refused before any work
    total = sum(class_sizes(spec, where).values())
    if total > MAX_SAMPLES:
        raise GearlabInputError(
            f"{where}: dataset '{spec.name}' would hold {shown(total)} samples; expected at most "
            f"{MAX_SAMPLES} (fewer duplicates, teeth or healthy samples)"
        )
    return spec


def described_spec(entry: dict, where: str, base: Path, preset: DatasetSpec | None) -> DatasetSpec:
    """The simulator a 'gearbox' description implies (gearlab.gearbox.simulation): its model (or the
    entry's 'model'), its values, the channel of its [sensor] (or 'channel'), the speed and load of
    its [operation] (or 'speed', 'load'), the load times its load_level. The faults and sizes: *preset*'s
    when one is named, else the chapter-5 ladders (CH5_STEPS) on every pinion tooth with a quarter more
    healthy samples."""
    from ..gearbox.simulation import channel, model_name, reference, referenced

    here = f"{where} key 'gearbox'"
    if entry["model_preset"]:
        raise GearlabInputError(
            f"{where} key 'model_preset': the 'gearbox' description gives the model's values; give one of the two"
        )
    ref = reference(gearbox_name(entry["gearbox"], here, base))
    try:
        box = referenced(ref)
        model = entry["model"] or model_name(box)
        plugin = get_registry().get("model", model, where)
        plugin.preset(ref)  # the model takes the description (its number of stages)
        chan = entry["channel"] or channel(box, model, plugin.channels)
    except GearlabInputError as exc:
        raise GearlabInputError(f"{here}: {exc}") from None
    operation = {}
    for key, value, unit in (("speed", box.speed_hz, "input-shaft speed"), ("load", box.load_nm, "output torque")):
        if value is None and entry[key] is None:
            raise GearlabInputError(
                f"{here}: {box.source}: [operation] key '{key}': missing; a simulation needs the {unit} "
                f"(or give '{key}' here)"
            )
        operation[f"{key}_{'hz' if key == 'speed' else 'nm'}"] = value
    given = None if entry["load"] is None else quantity(entry, "load", where)
    operation["load_nm"] = box.torque(given)  # the load times the description's load_level
    if preset is None:
        faults = tuple((name, CH5_STEPS[name]) for name in FAULTS)
        preset = DatasetSpec(box.name, model, ref, chan, faults=faults, healthy=15 * box.stages[0].pinion.z)
        preset = preset.with_(domain=box.name)
    else:
        preset = preset.with_(name=f"{box.name}_{preset.name}", domain=f"{box.name}_{preset.name}")
    return preset.with_(model=model, preset=ref, channel=chan, **operation)


# Ranges of a dataset's quantities (unit, largest value, as said): beyond them a value is a
# mistake (fs = 1e300 would ask for more samples per revolution than any memory holds).
QUANTITIES = {"speed": ("Hz", 1e3, "1 kHz"), "load": ("N*m", 1e6, "1e6 N*m"), "fs": ("Hz", 1e7, "10 MHz")}


def quantity(entry: dict, key: str, where: str) -> float:
    """A speed, load or rate of a dataset entry in SI units, checked against its range."""
    return _quantity(entry[key], key, f"{where} key '{key}'")


def _quantity(given, key: str, where: str) -> float:
    unit, high, said = QUANTITIES[key]
    value = rate_hz(given, where) if key == "fs" else to_si(given, unit, where)
    if key == "speed" and 0 < value < 1e5:  # '1500 rpm' is 25 turns a second, not pint's 157 (rad/s)
        from ..gearbox.description import speed_hz

        value = speed_hz(given, where)
    if value < 0 or value == 0 and key != "load":
        raise GearlabInputError(f"{where}: expected a positive value, got {shown(given)}")
    if value > high:
        raise GearlabInputError(f"{where}: {shown(given)} is outside {'[0' if key == 'load' else '(0'} {unit}, {said}]")
    return value


def simulated_spec(entry: dict, where: str, base: Path) -> DatasetSpec:
    """A [source] entry that must be a simulation (the gap and detection kinds: measured data
    can only be their [target])."""
    spec = None if entry.get("file") else dataset_spec(entry, where, base)  # the file's header is not read
    if not isinstance(spec, DatasetSpec):
        raise GearlabInputError(
            f"{where} key 'file': the source is a simulator configuration; give a 'preset' or a 'gearbox' "
            "description (measured data can only be the [target])"
        )
    return spec


def measured_spec(entry: dict, where: str, base: Path) -> MeasuredSpec:
    """A measured 'file' entry, checked against the file's header (its channels, rate and units:
    recordings.check_recording) so that `gearlab validate` finds a wrong name before any work."""
    if entry.get("takes"):  # a logger's file of several takes: one of them is a dataset's record
        raise GearlabInputError(
            f"{where} key 'takes': a 'file' is one recording; expected one take by its name, file = "
            f"'{entry['file']}[{entry['takes']}=1]' (the takes of the column's marks), and no 'takes'"
        )
    path = base / one_file(entry["file"], base, f"{where} key 'file'")  # an absolute name stays itself
    check_measured_file(path, f"{where} key 'file'")
    if entry["vibration"] == "":  # as inspect takes it: the file's one channel besides the tacho and time
        entry = {**entry, "vibration": only_vibration(path, entry["tacho"], where)}
    # a tacho's marks per turn where no tacho is (1: what runs wrote back when 1 was the default)
    if entry["tacho"] == "" and entry.get("pulses_per_rev") not in (None, 1):
        raise pulses_without_tacho(path, f"{where} key 'pulses_per_rev'", lambda c: f"tacho = '{c}'")
    speed = quantity(entry, "speed", where) if entry["speed"] is not None else None
    fs = quantity(entry, "fs", where) if entry["fs"] is not None else None
    units = units_of(entry, where)
    channels = {key: entry[key] for key in ("vibration", "tacho", "labels")}
    check_recording(path, where, channels, fs=fs, **units)
    gearbox = box = None
    if entry.get("gearbox"):  # with a tacho, the description names the shaft it reads
        from ..gearbox import resolve_gearbox

        gearbox = gearbox_name(entry["gearbox"], f"{where} key 'gearbox'", base)
        box = resolve_gearbox(gearbox)
    shaft = tacho_shaft_of(entry.get("tacho_shaft") or "", entry["tacho"], box, where, "'gearbox'")
    names = entry["class_names"]
    if not names or not all(isinstance(n, str) for n in names):
        raise GearlabInputError(f"{where} key 'class_names': expected a list of names, healthy first")
    spec = MeasuredSpec(
        name=entry["name"]
        or take_file(path).stem + path.name.removeprefix(take_file(path).name),  # a take's: log[take=2]
        path=str(path),
        vibration=channel_key(entry["vibration"]),
        tacho=None if entry["tacho"] == "" else channel_key(entry["tacho"]),
        speed_hz=speed,
        fs=fs,
        labels=entry["labels"] or None,
        class_names=tuple(names),
        transient=entry["transient"],
        pulses_per_rev=pulses_of(entry.get("pulses_per_rev"), entry["tacho"], box),
        gearbox=gearbox,
        tacho_shaft=None if shaft is None else shaft.name,
        **units,
    )
    spec.check(where)
    return spec


def gearbox_name(value: str, where: str, base: Path) -> str:
    """A gearbox description as a measured entry names it: a built-in name, or a file relative to
    the scenario (returned resolved); loaded here so that a bad description fails validate."""
    from ..gearbox import builtin_gearboxes, resolve_gearbox

    if value not in builtin_gearboxes():
        path = Path(value)
        value = str(path if path.is_absolute() else base / path)
    try:
        resolve_gearbox(value)
    except GearlabInputError as exc:
        raise GearlabInputError(f"{where}: {exc}") from None
    return value


def with_source_gearbox(target: dict, source: dict, where: str, base: Path) -> dict:
    """The [target] table of measured records without a tacho, given the [source]'s gearbox
    description when it names none: the same gearbox, whose mesh lines refine a declared speed (a
    motor's nameplate 2400 rpm ran at 39.96-40.05 Hz: read at 40 Hz flat, 400 revolutions slipped a
    fifth of a turn and every TSA lost its mesh) and follow it through each record; with no speed
    declared either, the description gives it. The gap and detection kinds alike: a user writes the
    gearbox once, in [source] (docs/your_gearbox.md step 3). A [target] gearbox the [source]'s
    contradicts (tooth counts, speed) is refused in one line (*where*: the [target] table)."""
    if target.get("gearbox") and source.get("gearbox"):
        _same_gearbox(target["gearbox"], source["gearbox"], f"{where} key 'gearbox'", base)
    files = target.get("files") or []
    declared = target.get("speed") is not None or any(isinstance(f, dict) and "speed" in f for f in files)
    # a record without a tacho: the [target]'s none, or a file's own tacho = "" (records with one may mix)
    lacks = [
        (f.get("tacho", target.get("tacho")) if isinstance(f, dict) else target.get("tacho")) in ("", None)
        for f in files
    ]
    if (
        (declared or files)
        and (any(lacks) if files else target.get("tacho") in ("", None))
        and not target.get("gearbox")
        and source.get("gearbox")
    ):
        return {**target, "gearbox": source["gearbox"]}
    return target


def _same_gearbox(target: str, source: str, where: str, base: Path) -> None:
    """A [target] gearbox with the [source]'s tooth counts and speed; else one line naming both."""
    from ..gearbox import resolve_gearbox

    ours, theirs = (resolve_gearbox(gearbox_name(g, where, base)) for g in (target, source))

    def facts(box) -> tuple[str, str]:
        speed = "no speed" if box.speed_hz is None else f"{box.speed_hz:g} Hz"
        return " + ".join(f"{s.pinion.z}/{s.wheel.z}" for s in box.stages), speed

    speeds = (ours.speed_hz, theirs.speed_hz)
    if facts(ours)[0] != facts(theirs)[0] or None not in speeds and not math.isclose(*speeds, rel_tol=1e-9):
        raise GearlabInputError(
            f"{where}: {shown(target)} describes {', '.join(facts(ours))}, the [source]'s {shown(source)} "
            f"{', '.join(facts(theirs))}; expected one gearbox: leave [target] gearbox out (the [source]'s "
            "is used) and give the records' speed as [target] 'speed'"
        )


def units_of(entry: dict, where: str) -> dict:
    """sensitivity (V per m/s²), gain (V per file unit) and unit (one of UNITS) of a measured 'file'
    entry, as given."""
    out = {"unit": entry["unit"]} if entry.get("unit") else {}
    given = calibration({k: entry.get(k) for k in CALIBRATION}, lambda k: f"{where} key '{k}'")
    return out | {k: v for k, v in given.items() if v is not None}


def stored_forms(data: dict) -> dict:
    """A run directory's copy of its scenario read as the tables are now: a dataset table's
    ``noise = {kind, snr_db, seed}`` of a run made before the one noise declaration becomes the
    sensor_noise with that seed (seed 0 where none was given), listed after the table's effects; an
    empty one, ``effects = []`` where none were given. The same dataset spec, so the same cache key:
    such a run is compared, shown and resumed as it was made."""
    out = {}
    for name, table in data.items():
        entries = table if isinstance(table, list) else [table]
        if all(isinstance(e, dict) for e in entries) and any(isinstance(e.get("noise"), dict) for e in entries):
            entries = [_stored_noise(e) for e in entries]
            table = entries if isinstance(table, list) else entries[0]
        out[name] = table
    return out


def _stored_noise(entry: dict) -> dict:
    if not isinstance(entry.get("noise"), dict):
        return entry
    out = {k: v for k, v in entry.items() if k != "noise"}
    noise = entry["noise"]
    effects = list(out.get("effects") or [])
    if noise:
        effects.append({"name": NOISE_EFFECT, **noise, "seed": noise.get("seed", 0)})
    return out | {"effects": effects}


def effects_and_noise(entries, where: str) -> tuple[tuple, NoiseSpec | None]:
    """A dataset's ``effects`` list: its effects (canonical, gearlab.effects), and the dataset's noise
    a ``sensor_noise`` with a ``seed`` declares (None without one). Such a noise is drawn from its own
    seed after every other effect (data.realise), so it must be the last signal effect listed; a
    ``sensor_noise`` without a seed stays an effect, drawn at its place from the effects' streams."""
    given = list(entries) if isinstance(entries, list) else []
    seeded = [
        i for i, e in enumerate(given) if isinstance(e, Mapping) and e.get("name") == NOISE_EFFECT and "seed" in e
    ]
    plain = [{k: v for k, v in e.items() if k != "seed"} if i in seeded else e for i, e in enumerate(given)]
    effects = effects_from_tables(plain if isinstance(entries, list) else entries, where)
    if not seeded:
        return effects, None
    here = f"{where} #{seeded[-1] + 1} ({NOISE_EFFECT})"
    if len(seeded) > 1:
        raise GearlabInputError(
            f"{here}: one sensor_noise has a seed (the dataset's noise, after every effect); "
            f"#{seeded[0] + 1} has one already (without a seed it is drawn at its place)"
        )
    registry = get_registry()
    later = [e["name"] for e in plain[seeded[0] + 1 :] if registry.get("effect", e["name"]).level == "signal"]
    if later:
        raise GearlabInputError(
            f"{here}: with a seed the noise is drawn after every other effect; list it after '{later[0]}' "
            "(or give it no seed: it then acts at its place, from the effects' streams)"
        )
    params = dict(effects[-1][1])  # the last signal effect in the chain's order (effects_from_tables)
    noise = noise_spec({"kind": params["kind"], "snr_db": params["snr_db"], "seed": given[seeded[0]]["seed"]}, here)
    return effects[:-1], noise


def noise_spec(table: dict, where: str, defaults: NoiseSpec | None = None) -> NoiseSpec | None:
    """A scenario's noise table (None when empty: no noise), checked as NoiseSpec declares it;
    *defaults*: the values a key left out takes (a preset's noise)."""
    if not table:
        return None
    return from_inline(NoiseSpec, table, where, asdict(defaults) if defaults is not None else None)


def class_sizes(spec: DatasetSpec | MeasuredSpec, where: str = "") -> dict[str, int] | None:
    """Samples per class of a simulated dataset from its spec alone (as data.builder lays it
    out), so that protocols are checked before anything is built; None for measured data."""
    if not isinstance(spec, DatasetSpec):
        return None
    spec.check_model(where)
    teeth = {key: len(c.teeth) for key, c in spec.fault_classes(where).items()}  # each on its gear's teeth
    sizes = {name: len(steps) * teeth[name] * spec.duplicates for name, steps in spec.faults}
    return {"healthy": spec.healthy, **sizes}


def sized(spec: DatasetSpec | MeasuredSpec) -> str:
    """'name (N samples: H healthy, F fault)', for the one-line descriptions."""
    sizes = class_sizes(spec)
    if sizes is None:
        return f"{spec.name} (measured)"
    total = sum(sizes.values())
    said = f"{spec.name} ({total} samples: {sizes['healthy']} healthy, {total - sizes['healthy']} fault)"
    return said + simulation_cost(spec)


def simulation_cost(spec: DatasetSpec) -> str:
    """What a slow box's simulations cost, said before they start (data.slow_box.cost, its longest simulation's;
    the run's line counts them); '' for a box simulated quickly, or a long train's stretch (lead_revolutions)."""
    from ..data import builder, placement
    from ..data.slow_box import cost

    model, pair, _ = spec.check_model()
    speed = builder.operating_point(spec)[0]
    fs = builder.whole_steps_rate(spec.fs, speed, pair.Z1)
    pairs = placement.train_pairs(model, spec.preset, f"dataset '{spec.name}'")
    classes = spec.fault_classes() if spec.faults else {}
    if builder.stretch_of(spec, pairs, classes):
        return ""
    simulator = builder._simulator  # noqa: SLF001 - the one the run builds, cached
    settle = lambda: builder.settle_revolutions(simulator(spec.model, spec.preset, fs), speed)  # noqa: E731
    return cost(fs, speed, pairs, [on.period for on in classes.values()], None, settle)


def planned_counts(spec: DatasetSpec | MeasuredSpec, where: str = "") -> Counts | None:
    """Sample length and class sizes of a simulated dataset, known before it is built (as
    data.builder lays it out); None for measured data, known only once imported."""
    sizes = class_sizes(spec, where)
    if sizes is None:
        return None
    return Counts(spec.name, POINTS, sizes.pop("healthy"), sum(sizes.values()))


def executor_for(scenario: Scenario, address: str | None = None):
    """The scenario's [execution] executor. For Ray, `address` (the CLI's --ray-address) wins over
    RAY_ADDRESS, which wins over the scenario's `address`. Called at a run's start: the workers load what
    the kind's units load first (Scenario.unit_modules) before the first map, whichever step maps first (a
    multi-file detection target is read on the pool)."""
    ex = scenario.tables["execution"]
    executor = make_executor(
        ex["executor"], ex["workers"] or None, address=address, scenario_address=ex.get("address") or None
    )
    executor.warm(scenario.unit_modules)
    return executor


def device_of(scenario: Scenario) -> str:
    """The scenario's [execution] device for training, checked here when units train in this
    machine's processes (a Ray cluster's workers may have a GPU that this machine lacks)."""
    ex = scenario.tables["execution"]
    # auto and cpu always resolve (the key allows nothing else), so only cuda is looked for,
    # and torch imported only then (start-up time: checking a scenario loads no torch)
    if ex["executor"] == "local" and ex["device"] == "cuda":
        from ..learn.training import pick_device

        try:
            pick_device(ex["device"])
        except GearlabInputError as exc:
            raise GearlabInputError(f"{location(scenario.path, 'execution', 'device')}: {exc}") from None
    return ex["device"]


# The kind contract's defaults for a kind whose summary lines say it all (gearlab.kinds.contract).
def no_unit_modules(scenario: Scenario) -> tuple[str, ...]:
    return ()


# What the kinds' units load first (ScenarioKind.unit_modules): a dataset's simulation, a gap fit, a training
BUILDS = ("gearlab.data.builder",)
FITS = (*BUILDS, "gearlab.gap.search", "scipy.optimize", "scipy.stats")
TRAINS = ("torch", "gearlab.parts.training")


def no_verdict(summary: dict, records: list[dict]) -> list[str]:
    return []


def no_table(summary: dict) -> str | None:
    return None


def no_compare(runs: list[tuple]) -> tuple[str, str] | None:
    return None  # `gearlab compare` letters each run's own table


def no_title(summary: dict, index: int, table: str) -> str:
    return ""  # report.html titles an untitled table from its header


def unconfirmed_speed(found: dict[str, str], speeds: dict[str, float]) -> tuple[str, str] | None:
    """(the first record, the words) of a declared speed that no history record's mesh lines confirm (each
    record's speed source, *found*, says UNCONFIRMED), or None: a gap diagnosis or a detection run read at it
    compares smeared lines (a 29/73 box described as 28/73, or given its output's speed, trained and scored)."""
    from ..data.recordings import UNCONFIRMED
    from ..signals.checks import fmt_hz

    if not found or not all(UNCONFIRMED in how for how in found.values()):
        return None
    path, how = next(iter(found.items()))
    words = f"{fmt_hz(speeds[path])} declared, but no history record's mesh lines confirm it "
    return path, words + f"({path}: {how.split(f'{UNCONFIRMED}: ')[-1]})"
