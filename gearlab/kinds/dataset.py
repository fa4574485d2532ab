"""Scenario kind `dataset`: build (or load from the cache) datasets and show what is in them."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..data.cache import load_or_build
from ..data.importers import MeasuredSpec
from ..data.spec import DATASET_PRESETS, DatasetSpec, NoiseSpec, dataset_preset
from ..effects import effects_from_tables
from ..errors import GearlabInputError, shown
from ..events import Event
from ..executors import make_executor
from ..runs import RunDir
from ..scenario import Key, Scenario, Table, in_range, location, plain_name
from ..units import to_si

DATASET_TABLE = Table(
    {
        "preset": Key(str, "", doc=f"dataset preset: {', '.join(DATASET_PRESETS)} (or give 'file')"),
        "file": Key(str, "", doc="measured data: a .csv, .npz, .h5, .wav or .mat file, relative to the scenario"),
        "vibration": Key(str, "", doc="measured data: the vibration channel"),
        "tacho": Key(str, "", doc="measured data: a tacho channel (shaft angle or pulses); or give 'speed'"),
        "labels": Key(str, "", doc="measured data: an optional label channel"),
        "class_names": Key(list, ["healthy", "fault"], doc="measured data: class names, healthy first"),
        "transient": Key(str, "stats", doc="measured data: 'stats' drops a start-up transient, 'none' keeps all"),
        "sensitivity": Key((int, float, str), None, doc="measured data: sensor sensitivity, e.g. '10 mV/g' (a number: "
                                                        "V per m/s²); without it or 'gain' the units are unknown"),
        "gain": Key((int, float, str), None, doc="measured data: volts per file unit, e.g. '0.3 mV' per count of "
                                                 "an integer record (WAV: at full scale)"),
        "name": Key(str, "", lambda v, where: v and plain_name(v, where), "label (default: the preset name)"),
        "model": Key(str, "", doc="dynamic model plugin (default: the preset's)"),
        "model_preset": Key(str, "", doc="the model's parameter preset (default: the preset's)"),
        "channel": Key(str, "", doc="measurement channel, e.g. pinion_x, casing_x"),
        "speed": Key((int, float, str), None, doc="input-shaft speed, e.g. '25.2 Hz'"),
        "load": Key((int, float, str), None, doc="load torque, e.g. '7 N*m'"),
        "faults": Key(dict, None, doc="{fault = [steps]} replacing the preset's ladders"),
        "teeth": Key(list, None, doc="pinion teeth carrying faults (default: all)"),
        "duplicates": Key(int, None, in_range(1)),
        "healthy": Key(int, None, in_range(0)),
        "revolutions": Key(int, None, in_range(1), "J noisy revolutions per sample (TSA averages them)"),
        "noise": Key(dict, None, doc="{kind = 'laplace', snr_db = 0, seed = 0}; an empty table removes noise"),
        "tsa": Key(bool, None),
        "seed": Key(int, None, in_range(0, 2**32 - 1)),
        "fs": Key((int, float, str), None, doc="integration rate, e.g. '200 kHz'"),
        "effects": Key(list, None, doc="unmodelled effects, e.g. [{name = 'sensor_noise', kind = 'laplace', "
                                       "snr_db = 0}, {name = 'drive_inertias'}] (gearlab plugins lists them)"),
    },
    array=True,
    required=True,
)
TABLES = {"datasets": DATASET_TABLE}


# Samples a simulated dataset may hold (4096 float32 each: 16 GB); the thesis's largest has
# 12 800. The table's keys bound no product, so absurd sizes are refused before any work.
MAX_SAMPLES = 10**6


def dataset_spec(entry: dict, where: str, base: Path) -> DatasetSpec | MeasuredSpec:
    """A dataset preset with the entry's overrides applied, or a measured file to import
    (shared by the dataset, transfer and gap kinds). *base*: the scenario's folder."""
    if bool(entry["preset"]) == bool(entry["file"]):
        raise GearlabInputError(f"{where}: give exactly one of 'preset' (simulated) or 'file' (measured data)")
    if entry["file"]:
        if entry.get("effects"):
            raise GearlabInputError(f"{where} key 'effects': effects act on simulations; a measured 'file' has none")
        return measured_spec(entry, where, base)
    spec = dataset_preset(entry["preset"], where)
    changes = {}
    for key in ("model", "channel"):
        if entry[key]:
            changes[key] = entry[key]
    if entry["model_preset"]:
        changes["preset"] = entry["model_preset"]
    if entry["name"]:
        changes["name"] = changes["domain"] = entry["name"]
    for key in ("speed", "load", "fs"):
        if entry[key] is not None:
            changes[{"speed": "speed_hz", "load": "load_nm", "fs": "fs"}[key]] = quantity(entry, key, where)
    if entry["faults"] is not None:
        faults = []
        for name, steps in entry["faults"].items():
            if not isinstance(steps, list) or not all(isinstance(s, int) and not isinstance(s, bool) for s in steps):
                raise GearlabInputError(f"{where} key 'faults': '{name}' must map to a list of ladder steps, got {shown(steps)}")
            faults.append((name, tuple(steps)))
        changes["faults"] = tuple(faults)
    if entry["teeth"] is not None:
        if not all(isinstance(t, int) and not isinstance(t, bool) for t in entry["teeth"]):
            raise GearlabInputError(f"{where} key 'teeth': expected a list of tooth numbers, got {shown(entry['teeth'])}")
        changes["teeth"] = tuple(entry["teeth"])
    for key in ("duplicates", "healthy", "revolutions", "tsa", "seed"):
        if entry[key] is not None:
            changes[key] = entry[key]
    if entry["noise"] is not None:
        changes["noise"] = noise_spec(entry["noise"], f"{where} key 'noise'")
    if entry.get("effects") is not None:
        changes["effects"] = effects_from_tables(entry["effects"], f"{where} key 'effects'")
    spec = spec.with_(**changes)
    spec.check(where)
    spec.check_model(where)  # model, preset, channel, faults and teeth: refused before any work
    total = sum(class_sizes(spec, where).values())
    if total > MAX_SAMPLES:
        raise GearlabInputError(f"{where}: dataset '{spec.name}' would hold {shown(total)} samples; expected at most "
                                f"{MAX_SAMPLES} (fewer duplicates, teeth or healthy samples)")
    return spec


# Ranges of a dataset's quantities (unit, largest value, as said): beyond them a value is a
# mistake (fs = 1e300 would ask for more samples per revolution than any memory holds).
QUANTITIES = {"speed": ("Hz", 1e3, "1 kHz"), "load": ("N*m", 1e6, "1e6 N*m"), "fs": ("Hz", 1e7, "10 MHz")}


def quantity(entry: dict, key: str, where: str) -> float:
    """A speed, load or rate of a dataset entry in SI units, checked against its range."""
    unit, high, said = QUANTITIES[key]
    value = to_si(entry[key], unit, f"{where} key '{key}'")
    if value < 0 or value == 0 and key != "load":
        raise GearlabInputError(f"{where} key '{key}': expected a positive value, got {shown(entry[key])}")
    if value > high:
        raise GearlabInputError(f"{where} key '{key}': {shown(entry[key])} is outside "
                                f"{'[0' if key == 'load' else '(0'} {unit}, {said}]")
    return value


def simulated_spec(entry: dict, where: str, base: Path) -> DatasetSpec:
    """A [source] entry that must be a simulation (the gap and detection kinds: measured data
    can only be their [target])."""
    spec = dataset_spec(entry, where, base)
    if not isinstance(spec, DatasetSpec):
        raise GearlabInputError(f"{where} key 'file': the source is a simulator configuration; give a 'preset' "
                                "(measured data can only be the [target])")
    return spec


def measured_spec(entry: dict, where: str, base: Path) -> MeasuredSpec:
    if not entry["vibration"]:
        raise GearlabInputError(f"{where}: a measured 'file' needs 'vibration' (the vibration channel)")
    path = Path(entry["file"])
    path = path if path.is_absolute() else base / path
    speed = quantity(entry, "speed", where) if entry["speed"] is not None else None
    fs = quantity(entry, "fs", where) if entry["fs"] is not None else None
    names = entry["class_names"]
    if not names or not all(isinstance(n, str) for n in names):
        raise GearlabInputError(f"{where} key 'class_names': expected a list of names, healthy first")
    spec = MeasuredSpec(
        name=entry["name"] or path.stem, path=str(path), vibration=entry["vibration"], tacho=entry["tacho"] or None,
        speed_hz=speed, fs=fs, labels=entry["labels"] or None, class_names=tuple(names),
        transient=entry["transient"], **units_of(entry, where),
    )
    spec.check()
    return spec


def units_of(entry: dict, where: str) -> dict:
    """sensitivity (V per m/s²) and gain (V per file unit) of a measured 'file' entry, as given."""
    from ..data.textzip import parse_sensitivity

    out = {}
    if entry.get("sensitivity") is not None:
        out["sensitivity"] = parse_sensitivity(entry["sensitivity"], f"{where} key 'sensitivity'")
    if entry.get("gain") is not None:
        gain = to_si(entry["gain"], "V", f"{where} key 'gain'")
        if not gain > 0:
            raise GearlabInputError(f"{where} key 'gain': expected a positive voltage per file unit such as "
                                    f"'0.3 mV', got {shown(entry['gain'])}")
        out["gain"] = gain
    return out


def noise_spec(table: dict, where: str) -> NoiseSpec | None:
    if not table:
        return None
    unknown = set(table) - {"kind", "snr_db", "seed"}
    if unknown:
        raise GearlabInputError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}; expected kind, snr_db, seed")
    if "kind" not in table or "snr_db" not in table:
        raise GearlabInputError(f"{where}: expected {{kind = 'gaussian'|'laplace'|'student_t', snr_db = number}}")
    snr = table["snr_db"]
    # abs() < 1e300 also refuses nan, inf and integers too large for a float
    if isinstance(snr, bool) or not isinstance(snr, (int, float)) or not abs(snr) < 1e300:
        raise GearlabInputError(f"{where}: snr_db must be a finite number of dB, got {str(snr)[:40]}")
    seed = table.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= 2**32 - 1:
        raise GearlabInputError(f"{where}: seed must be a whole number in [0, {2**32 - 1}], got {shown(seed)}")
    return NoiseSpec(str(table["kind"]), float(snr), seed)


def build(scenario: Scenario) -> list[DatasetSpec | MeasuredSpec]:
    specs = [dataset_spec(entry, location(scenario.path, "datasets", index=i), scenario.base or scenario.path.parent)
             for i, entry in enumerate(scenario.tables["datasets"])]
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise GearlabInputError(f"{scenario.path}: dataset names must be unique; give each entry a 'name'")
    return specs


def class_sizes(spec: DatasetSpec | MeasuredSpec, where: str = "") -> dict[str, int] | None:
    """Samples per class of a simulated dataset from its spec alone (as data.builder lays it
    out), so that protocols are checked before anything is built; None for measured data."""
    if not isinstance(spec, DatasetSpec):
        return None
    _, _, teeth = spec.check_model(where)
    return {"healthy": spec.healthy, **{name: len(steps) * len(teeth) * spec.duplicates for name, steps in spec.faults}}


def sized(spec: DatasetSpec | MeasuredSpec) -> str:
    """'name (N samples: H healthy, F fault)', for the one-line descriptions."""
    sizes = class_sizes(spec)
    if sizes is None:
        return f"{spec.name} (measured)"
    total = sum(sizes.values())
    return f"{spec.name} ({total} samples: {sizes['healthy']} healthy, {total - sizes['healthy']} fault)"


def describe(scenario: Scenario) -> str:
    """One line for `gearlab validate` and the TUI: what the scenario will do."""
    return f"{len(scenario.spec)} dataset(s): " + ", ".join(sized(s) for s in scenario.spec)


def quick(scenario: Scenario) -> None:
    """Smoke run: two teeth, the top intensity of each fault, a few healthy samples, J <= 4."""
    scenario.spec = [
        s.with_(teeth=(1, 2), faults=tuple((f, steps[-1:]) for f, steps in s.faults), duplicates=1,
                healthy=min(s.healthy, 4), revolutions=min(s.revolutions, 4)) if isinstance(s, DatasetSpec) else s
        for s in scenario.spec
    ]


def executor_for(scenario: Scenario, address: str | None = None):
    """The scenario's [execution] executor. For Ray, `address` (the CLI's --ray-address) wins over
    RAY_ADDRESS, which wins over the scenario's `address`."""
    ex = scenario.tables["execution"]
    return make_executor(ex["executor"], ex["workers"] or None, address=address,
                         scenario_address=ex.get("address") or None)


def device_of(scenario: Scenario) -> str:
    """The scenario's [execution] device for training, checked here when units train in this
    machine's processes (a Ray cluster's workers may have a GPU that this machine lacks)."""
    ex = scenario.tables["execution"]
    if ex["executor"] == "local":
        from ..learn.training import pick_device

        try:
            pick_device(ex["device"])
        except GearlabInputError as exc:
            raise GearlabInputError(f"{location(scenario.path, 'execution', 'device')}: {exc}") from None
    return ex["device"]


def class_counts(dataset) -> dict[str, int]:
    return {name: int((dataset.label == c).sum()) for c, name in enumerate(dataset.spec.class_names)}


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    with executor_for(scenario) as executor:
        done = {r["unit"]: r for r in run.records()}
        summary = {"kind": "dataset", "scenario": scenario.name, "datasets": {}}
        for spec in scenario.spec:
            dataset, cached = load_or_build(spec, executor, on_event)
            record = done.get(spec.name) or {
                "unit": spec.name, "key": spec.key(), "cached": cached, "n": len(dataset),
                "counts": class_counts(dataset), "reference": list(dataset.reference), "meta": dataset.meta,
            }
            if spec.name not in done:
                run.append(record)
                on_event(Event("record", stage="datasets", record=record))
            summary["datasets"][spec.name] = {**record, "spec": asdict(spec), "shape": list(dataset.X.shape)}
            figures(dataset, run)
        run.write_json("summary.json", summary)
        run.write_text("table.md", table_md(summary))


def table_md(summary: dict) -> str:
    names = list(summary["datasets"])
    classes = []
    for d in summary["datasets"].values():
        classes += [c for c in d["counts"] if c not in classes]
    lines = ["| class | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for c in classes + ["total"]:
        cells = [str(d["n"] if c == "total" else d["counts"].get(c, 0)) for d in summary["datasets"].values()]
        lines.append(f"| {c} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def figures(dataset, run: RunDir) -> None:
    from ..plots import dataset_signals

    dataset_signals(dataset, run.file("figures", f"signals_{dataset.spec.name}.png"))


def summary_lines(run: RunDir) -> list[str]:
    summary = json.loads((run.path / "summary.json").read_text())
    lines = [table_md(summary).rstrip()]
    for name, d in summary["datasets"].items():
        lines.append(f"{name}: {d['n']} samples x {d['shape'][1]}, cache key {d['key']}"
                     + (" (from cache)" if d["cached"] else ""))
    return lines


def records_table(scenario: Scenario, records: list[dict]) -> str:
    return table_md({"datasets": {r["unit"]: r for r in records}})


def charts(scenario: Scenario, run: RunDir) -> list:
    """Per dataset (from the cache; nothing is rebuilt to draw it): a revolution of each class at
    its top intensity, and their order spectra."""
    from ..charts import Chart, Curve, dataset_examples
    from ..data import cache
    from ..signals import order_spectrum

    done = {r["unit"] for r in run.records()}
    out = []
    for spec in scenario.spec:
        if spec.name not in done:
            continue
        dataset = cache.load(spec)
        if dataset is None:
            out.append(Chart(f"dataset {spec.name}", "", "", (), notes=("not in the dataset cache any more",)))
            continue
        examples = dataset_examples(dataset, per_class=1)
        angle = np.arange(dataset.X.shape[1]) * 360.0 / dataset.X.shape[1]
        out.append(Chart(f"{spec.name}: one revolution per class", "input-shaft angle (deg)", "standardised",
                         tuple(Curve(label, angle, dataset.X[i]) for _, label, i in examples)))
        spectra = []
        for _, label, i in examples:
            orders, amp = order_spectrum(dataset.X[i])
            keep = orders <= 200
            spectra.append(Curve(label, orders[keep], amp[keep]))
        out.append(Chart(f"{spec.name}: order spectra", "shaft order", "amplitude", tuple(spectra)))
    return out
