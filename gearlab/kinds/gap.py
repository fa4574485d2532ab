"""Scenario kind `gap`: the sim-to-real gap diagnosis (docs/gap.md, "Diagnosis").

    [source]      the simulator configuration: a simulated dataset entry (as in [[datasets]])
    [target]      the data to explain: a simulated entry (possibly with effects, which the
                  diagnosis never sees) or a measured file through the importer
    [diagnosis]   candidates, budget, max_effects, healthy, bootstrap, permutations, alpha, seed
    [accuracy]    enabled, methods (DA baselines, detectors), repetitions and training settings (k = 0)
    [network]     name (fast | cnn3), dropout

Units of work (one record each in results.jsonl, so --resume redoes none of them): ``diagnosis`` (where /
which / how far, gearlab.gap.diagnose.diagnose on the target's healthy revolutions alone), then per repetition
the downstream accuracy: a source-only model trained on the uncorrected source, one trained on the corrected
source (the fitted effects added), each detector (matched_filter) with the fault shapes of either source, and
each DA method on the uncorrected source, all scored on the target test set.

Output: summary.json (effects, gap before/after, per-view gaps, two-sample statistics, ranking, accuracy),
table.md, figures, report.html; gearbox_corrected.toml, a description's fitted values (gearlab.gap.corrected).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from ..charts import Chart, Curve
from ..data import cache
from ..data.cache import load_or_build
from ..data.chain import PASSBAND, Chain, chain_of
from ..data.importers import MeasuredSpec
from ..data.spec import DatasetSpec
from ..effects import check_candidate, default_candidates
from ..errors import GearlabInputError
from ..events import Event, report_begins
from ..gap.conclusion import verdict_text  # the kind's log line, summary and report say one verdict
from ..gap.corrected import write_corrected
from ..gap.diagnose import Settings
from ..gearbox.simulation import defaults, gearbox_of, is_reference, referenced
from ..learn.config import NetworkSettings
from ..learn.protocol import Counts, Method, Protocol, check, check_data, domain_adapting, history_of, shared_state
from ..learn.schedule import two_phases
from ..parts import training
from ..parts.bound import bayes_bound
from ..parts.measured import pattern_counts
from ..parts.training import TRAINING, train_unit
from ..registry import get_registry
from ..runs import RunDir
from ..scenario import Scenario, Table, keys_of, location
from ..settings import setting, shrunk, typed
from .common import (
    DATASET_TABLE,
    class_sizes,
    device_of,
    executor_for,
    no_compare,
    no_title,
    planned_counts,
    simulated_spec,
    sized,
    with_source_gearbox,
)
from .gap_inputs import (  # noqa: F401 (unit_modules: the kind contract's)
    Records,
    TargetEntry,
    check_healthy,
    check_points,
    check_sampling,
    read_history,
    short_history,
    target_of,
    unit_modules,
    units_declared,
    units_warning,
)
from .gap_tables import accuracy_md, evaluations_text, params_text, percent, ranking_md, tables_md, views_md
from .gap_verdict import (  # noqa: F401 (headline: the kind contract's; dropped_text, shrink_text: the tests')
    before_after,
    diagnosis_line,
    dropped_rows,
    dropped_text,
    gap_lines,
    headline,
    not_accepted_rows,
    shrink_text,
)

_DATASET = Table(DATASET_TABLE.keys, required=True, moved=DATASET_TABLE.moved)


@dataclass(frozen=True, kw_only=True)
class Accuracy:
    """[accuracy], with the Table 5.3 training keys (TRAINING)."""

    enabled: bool = setting(
        bool, True, doc="train source-only models on the uncorrected and corrected source (needs target labels)"
    )
    methods: list = setting(
        list,
        ["mmd", "dann", "matched_filter"],
        doc="shown beside (adapter or detector names): unsupervised DA baselines, on "
        "the uncorrected source; detectors, on both sources",
    )
    repetitions: int = setting(int, 3, low=1, high=1000)


UNCORRECTED, CORRECTED = "uncorrected", "corrected"
TABLES = {
    "source": _DATASET,
    "target": Table(keys_of(TargetEntry), required=True, moved=DATASET_TABLE.moved),
    # declared once, on gearlab.gap.scoring.Settings: keys, checks, --quick limits and docs
    "diagnosis": Table(keys_of(Settings)),
    "accuracy": Table({**keys_of(Accuracy), **TRAINING}),
    "network": Table(keys_of(NetworkSettings, name="fast")),
}
OVERRIDES: tuple[str, ...] = ()  # no key is set from the command line


# --- build: every check before any work ---------------------------------------------------------


@dataclass(frozen=True)
class Spec:
    """What build() checked: the source, the target (simulated, imported or measured records), the
    diagnosis settings, the accuracy's protocol and whether the accuracy is measured."""

    source: DatasetSpec
    target: DatasetSpec | MeasuredSpec | Records
    settings: Settings
    protocol: Protocol
    accuracy: bool


def build(scenario: Scenario) -> Spec:
    t = scenario.tables
    path = scenario.path
    # file paths are relative to the scenario's own folder (a run's copy keeps it as scenario.base)
    base = scenario.base or path.parent
    source = simulated_spec(t["source"], location(path, "source"), base)
    entry = with_source_gearbox(t["target"], t["source"], location(path, "target"), base)
    target = target_of(entry, location(path, "target"), base, gearbox_of(source))  # the source's tacho shafts
    _, pair, _ = source.check_model(location(path, "source"))
    check_sampling(source, pair.Z1, location(path, "source"))
    if isinstance(target, DatasetSpec):
        _, target_pair, _ = target.check_model(location(path, "target"))
        if (target_pair.Z1, target_pair.Z2) != (pair.Z1, pair.Z2):
            raise GearlabInputError(
                f"{location(path, 'target', 'preset')}: the target's gear pair has "
                f"{target_pair.Z1}/{target_pair.Z2} teeth, the source's {pair.Z1}/{pair.Z2}; "
                "effects never change the gear pair"
            )
        check_sampling(target, pair.Z1, location(path, "target"))
        healthy = class_sizes(target)["healthy"]
        check_healthy(healthy, location(path, "target", "healthy"))
    d = typed(Settings, t["diagnosis"])
    short_history(target, source, pair, location(path, "target", "files"))  # warned: a view it leaves out
    settings = replace(d, candidates=candidates(d.candidates, location(path, "diagnosis", "candidates")))
    if settings.reference == "noise" and settings.candidates and "sensor_noise" not in settings.candidates:
        raise GearlabInputError(
            f"{location(path, 'diagnosis', 'reference')}: reference = 'noise' needs "
            "'sensor_noise' among the candidates (the noise fitted alone is the reference)"
        )
    net = t["network"]["name"]
    a = t["accuracy"]
    methods = da_methods(a["methods"], location(path, "accuracy", "methods"))
    protocol = Protocol(
        methods=(Method("source_only", False), *methods),
        network=net,
        dropout=t["network"]["dropout"],
        ks=(0,),
        repetitions=a["repetitions"],
        target_train=a["target_train"],
        batch=a["batch"],
        lr=a["lr"],
        prime_epochs=a["prime_epochs"],
        baseline_epochs=a["baseline_epochs"],
        patience=a["patience"],
        min_epochs=a["min_epochs"],
        max_epochs=a["max_epochs"],
        seed=a["seed"],
        device=device_of(scenario),
    )
    if isinstance(target, DatasetSpec):  # the diagnosis reads the history only (learn.protocol.history_of)
        check_healthy(min(healthy, protocol.target_train), location(path, "accuracy", "target_train"))
    if a["enabled"]:
        if protocol.min_epochs > protocol.max_epochs:
            raise GearlabInputError(
                f"{location(path, 'accuracy', 'min_epochs')}: {protocol.min_epochs} is larger "
                f"than max_epochs = {protocol.max_epochs}"
            )
        check(protocol, str(path))
        planned = planned_counts(source), planned_counts(target)
        # a simulated target without faults has nothing to detect: the accuracy is skipped (run)
        if None not in planned and planned[1].faults:
            check_data(protocol, *planned, f"{path}: [accuracy]")
    return Spec(source, target, settings, protocol, bool(a["enabled"]))


def candidates(names, where: str) -> tuple[str, ...]:
    """Effect names, each registered (with a "did you mean"), none twice; [] = all."""
    registry = get_registry()
    known = registry.names("effect")
    out: list[str] = []
    for i, name in enumerate(names):
        if not isinstance(name, str):
            raise GearlabInputError(f"{where}: entry {i + 1} must be an effect name, got {type(name).__name__}")
        check_candidate(registry, name, f"{where} entry {i + 1}")
        if name in out:
            raise GearlabInputError(f"{where}: '{name}' is listed twice")
        out.append(name)
    if not known:
        raise GearlabInputError(f"{where}: no effect plugins are registered (gearlab plugins lists them)")
    return tuple(out)


def da_methods(names, where: str) -> tuple[Method, ...]:
    """The unsupervised methods beside source_only (k = 0: the target has no labels to supervise
    with): DA baselines and detectors."""
    out: list[Method] = []
    for i, name in enumerate(names):
        if not isinstance(name, str):
            raise GearlabInputError(
                f"{where}: entry {i + 1} must be an adapter or detector name, got {type(name).__name__}"
            )
        if name == "source_only":
            raise GearlabInputError(
                f"{where}: source_only is always trained (on the uncorrected and the "
                "corrected source); list DA methods only"
            )
        m = training.method({"adapter": name, "supervised": False, "params": {}}, f"{where} entry {i + 1}")
        if not (m.is_detector or domain_adapting(m.adapter)):
            raise GearlabInputError(
                f"{where} entry {i + 1}: '{name}' is neither a domain-adaptation method nor "
                "a detector (it trains on the source or target alone)"
            )
        if m in out:
            raise GearlabInputError(f"{where}: '{name}' is listed twice")
        out.append(m)
    return tuple(out)


def describe(scenario: Scenario) -> str:
    spec = scenario.spec
    s = spec.settings
    n = len(s.candidates) or len(default_candidates(get_registry()))
    records = len(spec.target.history) if isinstance(spec.target, Records) else 0  # measured: no classes
    target = f"{records} measured history record{'s' * (records != 1)}" if records else sized(spec.target)
    if records and (matched := pattern_counts(spec.target.history)):
        target += f" ({matched})"
    line = f"gap of {spec.source.name} (simulated) -> {target}: {n} candidate effects x budget {s.budget}, up to "
    line += f"{s.max_effects} greedy rounds, {s.healthy} source healthy revolutions per evaluation"
    if spec.accuracy:
        p = spec.protocol
        columns = [label_of(variant, m) for variant, m in accuracy_columns(p)]
        line += f"; accuracy: {len(columns)} models x {p.repetitions} repetitions ({', '.join(columns)})"
        line += f", trained on the simulated {sized(spec.source)}"
    return line


def quick(scenario: Scenario) -> None:
    """Smoke run: small search budgets, fewer revolutions and resamples, one short repetition."""
    spec = scenario.spec
    scenario.spec = replace(
        spec,
        settings=shrunk(spec.settings),  # the --quick limits declared on Settings
        protocol=shrunk(spec.protocol, repetitions=1),  # and those declared on Protocol
    )


# --- run -------------------------------------------------------------------------------------------


def target_rows(dataset, history: np.ndarray, z1: int, where: str) -> tuple[np.ndarray, str]:
    """The target's history revolutions in physical units, checked; and a note on what was used.
    A labelled target gives its *history* rows only (`learn.protocol.history_of`: healthy rows that
    every repetition trains on, so no test row reaches the diagnosis). An unlabelled measured record
    is taken as healthy throughout (the importer standardises it against all its revolutions alike;
    there is no test set); one whose units are unknown gets a warning."""
    labels = np.asarray(dataset.label)
    mean, std = dataset.reference
    if len(labels) and np.all(labels == -1):
        rows = np.asarray(dataset.X, dtype=np.float64) * std + mean
        note = "the target is unlabelled: all its revolutions are taken as healthy"
    else:
        rows = np.asarray(dataset.X, dtype=np.float64)[history] * std + mean
        note = f"the diagnosis reads the target history: {len(rows)} healthy training revolutions, no test row"
    check_healthy(len(rows), where)
    meta = dataset.meta or {}
    if meta.get("source") == "measured":
        fs, speed = float(meta["fs_hz"]), float(meta["speed_hz"])
        check_points(fs / speed, z1, where, f"the record's {fs:g} Hz at {speed:.4g} Hz shaft speed")
        if str(meta.get("units", "")).startswith("unknown"):  # what fits volts, and m/s² already
            note = "; ".join(filter(None, [note, units_warning(dataset.spec.vibration, rows)]))
    return rows, note


def unit_name(rep: int, variant: str, m: Method) -> str:
    return f"rep{rep}/{variant}/{m.key}"


def on_both_sources(m: Method) -> bool:
    """Methods that learn from the simulation alone (source_only, the detectors' fault shapes)
    are scored with the uncorrected and the corrected source; DA methods with the uncorrected one."""
    return m.is_detector or get_registry().get("adapter", m.adapter).train_on == "source"


def accuracy_columns(protocol: Protocol) -> list[tuple[str, Method]]:
    """(source variant, method) in the accuracy table's column order."""
    both = [m for m in protocol.methods if on_both_sources(m)]
    return [(variant, m) for m in both for variant in (UNCORRECTED, CORRECTED)] + [
        (UNCORRECTED, m) for m in protocol.methods if m not in both
    ]


def accuracy_units(protocol: Protocol) -> list[tuple[int, str, Method]]:
    return [(rep, variant, m) for rep in range(protocol.repetitions) for variant, m in accuracy_columns(protocol)]


def label_of(variant: str, m: Method) -> str:
    return f"{m.adapter} ({variant})" if on_both_sources(m) else m.label


def noise_free(spec: DatasetSpec) -> DatasetSpec:
    """*spec* without its noise effects: the expected response, whose fault shapes a detector
    matches (a template under 0 dB noise would be mostly noise)."""
    registry = get_registry()
    kept = tuple(e for e in spec.effects if not registry.get("effect", e[0]).noise)
    return (
        spec
        if kept == spec.effects
        else spec.with_(effects=kept, name=f"{spec.name}-noise-free", domain=f"{spec.name}-noise-free")
    )


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    from ..gap.diagnose import corrected_source, diagnose
    from ..gap.views import gear_pair_of

    spec = scenario.spec
    with executor_for(scenario) as executor:
        done = {r["unit"]: r for r in run.records()}
        source_spec = spec.source
        z1 = gear_pair_of(source_spec).Z1

        records = isinstance(spec.target, Records)
        settings = spec.settings
        if records:  # measured records: the history's revolutions; the source runs at their speed
            from ..data.builder import operating_point

            described, shaft = operating_point(spec.source)[0], spec.target.target.read_as
            target_X, speed, record_notes, fs, from_mesh, ts = read_history(spec.target, on_event, (described, z1))
            check_points(
                fs / speed,
                z1,
                location(scenario.path, "target", "fs"),
                f"the records' {fs:g} Hz at {speed:.4g} Hz shaft speed",
            )
            source_spec = source_spec.with_(speed_hz=round(speed, 3))
            settings = replace(settings, max_order=Chain(fs=fs, speed=speed).max_order)
            record_notes.append(
                f"compared up to shaft order {settings.max_order} ({PASSBAND:g} of the records' "
                "Nyquist order): the source is low-passed to the records' bandwidth"
            )
            if not spec.target.units_known:  # what fits values in volts, and values in m/s² already
                record_notes.append(units_warning(spec.target.target.vibration, target_X))
            # start fractions not kept (drawn uniformly)
            history = [f for f in spec.target.target.files if f.role == "history"]
            pulses = {spec.target.target.keys_of(f)["pulses_per_rev"] for f in history} if shaft else set()
            ppr = pulses.pop() if len(pulses) == 1 else None
            chain = Chain(
                fs,
                speed,
                speed_from_mesh=from_mesh,
                described_speed=described,
                tacho_shaft=shaft,
                takes=ts,
                pulses_per_rev=ppr,
            )
            note = "; ".join(record_notes)
        else:
            on_event(Event("stage", stage="datasets", total=1, message="target data"))
            target, _ = load_or_build(spec.target, executor, on_event)
            history = history_of(spec.protocol, target)
            target_X, note = target_rows(target, history, z1, location(scenario.path, "target"))
            chain = None
            if (target.meta or {}).get("source") == "measured":
                chain = chain_of(target.meta)
                settings = replace(settings, max_order=chain.max_order)
            on_event(Event("advance", stage="datasets", done=1, total=1))
        if note:
            on_event(Event("log", message=note))

        if "diagnosis" not in done:
            on_event(Event("stage", stage="diagnosis", total=1, message="gap diagnosis"))
            # Only the source configuration and the target's healthy rows go in: nothing of how the
            # target was made (its spec, effects, labels) reaches the diagnosis.
            result = diagnose(source_spec, target_X, settings, executor=executor, on_event=on_event, chain=chain)
            record = {"unit": "diagnosis", "result": result, "note": note}
            run.append(record)
            done["diagnosis"] = record
            on_event(Event("record", stage="diagnosis", record=_brief(record)))
            on_event(Event("advance", stage="diagnosis", done=1, total=1))
        result = done["diagnosis"]["result"]
        on_event(Event("log", message=diagnosis_line(result)))

        notes = [note] if note else []
        if is_reference(source_spec.preset):  # which of the simulator's values are the defaults' guesses
            names = get_registry().get("model", source_spec.model).param_names()
            guessed = ", ".join(defaults(referenced(source_spec.preset), names))
            if guessed:
                notes.append(f"the source's gearbox description leaves to defaults (docs/gearbox.md): {guessed}")
        if spec.accuracy and records:
            notes.append(
                "accuracy skipped: measured history records carry no labelled faults (the detection "
                "kind scores real test files)"
            )
            on_event(Event("log", message=notes[-1]))
        elif spec.accuracy:
            if not (np.asarray(target.fault) == 1).any():
                notes.append("accuracy skipped: the target has no labelled fault samples")
                on_event(Event("log", message=notes[-1]))
            else:
                corrected = corrected_source(source_spec, result)
                if corrected != source_spec:  # a label only (not in the cache key): tells the two apart in logs
                    corrected = corrected.with_(
                        name=f"{source_spec.name}-corrected", domain=f"{source_spec.name}-corrected"
                    )
                accuracy(scenario, run, corrected, history, executor, on_event, done)
        summarise(scenario, run, notes)


def _brief(record: dict) -> dict:
    """The diagnosis record without the per-feature arrays (events stay small)."""
    r = record["result"]
    return {
        "unit": "diagnosis",
        "gap_before": r["gap_before"],
        "gap_after": r["gap_after"],
        "unexplained": r["unexplained"],
        "effects": [e["name"] for e in r["effects"]],
    }


def accuracy(
    scenario: Scenario, run: RunDir, corrected: DatasetSpec, history: np.ndarray, executor, on_event, done: dict
) -> None:
    """Every method trained on the history (and no other target row) and scored on the rest."""
    spec = scenario.spec
    protocol = spec.protocol
    sources = {UNCORRECTED: spec.source, CORRECTED: corrected}

    def source_of(variant: str, m: Method) -> DatasetSpec:
        return noise_free(sources[variant]) if m.is_detector else sources[variant]

    todo = accuracy_units(protocol)
    pending = [u for u in todo if unit_name(*u) not in done]
    on_event(
        Event("stage", stage="accuracy", total=len(todo), message=f"downstream accuracy: {len(todo)} training runs")
    )
    if pending:
        needed = list(dict.fromkeys(source_of(variant, m) for _, variant, m in pending))
        on_event(
            Event(
                "stage",
                stage="sources",
                total=len(needed),
                message=f"source datasets ({', '.join(s.name for s in needed)})",
            )
        )
        target, _ = load_or_build(spec.target, executor, on_event)
        for i, s in enumerate(needed):
            built, _ = load_or_build(s, executor, on_event)
            check_data(protocol, Counts.of(built), Counts.of(target), f"{scenario.path}: [accuracy]")
            on_event(Event("advance", stage="sources", done=i + 1, total=len(needed)))

    # Each source has its own states (its source-only model, its primed network): the unit that
    # needs one first makes it, the others wait for the second phase and load it.
    def state_file(unit: tuple):
        rep, variant, m = unit
        state = shared_state(m, rep, 0, protocol)  # the gap kind scores k = 0 only
        return None if state is None else run.file("states", variant, f"{state}.pt")

    phases = two_phases(pending, state_file)
    finished = len(todo) - len(pending)
    on_event(Event("advance", stage="accuracy", done=finished, total=len(todo)))

    for phase in phases:
        if not phase:
            continue
        target_data = (spec.target, cache.entry_path(spec.target))
        tasks = [
            (protocol, (s, cache.entry_path(s)), target_data, rep, 0, m, run.file("states", variant), history)
            for rep, variant, m in phase
            for s in [source_of(variant, m)]
        ]

        def record_done(i: int, record: dict, phase=phase) -> None:
            nonlocal finished
            rep, variant, m = phase[i]
            record.pop("_latent", None)
            record.update(unit=unit_name(rep, variant, m), variant=variant, method=label_of(variant, m))
            run.append(record)
            finished += 1
            on_event(Event("log", message=f"{record['unit']}: target test accuracy {record['accuracy']:.1f} %"))
            on_event(Event("record", stage="accuracy", record=record))
            on_event(Event("advance", stage="accuracy", done=finished, total=len(todo)))

        executor.map(train_unit, tasks, on_done=record_done, gpu=protocol.device != "cpu")

    if "bound" not in done:  # the best any method could do on these test sets (simulated noisy targets only)
        source, _ = load_or_build(spec.source, executor, on_event)
        target, _ = load_or_build(spec.target, executor, on_event)
        bound = bayes_bound(spec.target, source, target, replace(protocol, ks=(0,)), executor, on_event, history)
        if bound is not None:
            run.append({"unit": "bound", **bound})


# --- summary, tables, charts -----------------------------------------------------------------------


def view_rows(result: dict) -> dict[str, dict]:
    """Per view: gap and share before and after, with their bootstrap intervals."""
    if result["before"] is None:  # a structure difference: no gap measured
        return {}
    before, after = result["before"]["views"], result["after"]["views"]
    noise = (result.get("reference") or {}).get("views", {})  # reference = 'noise': the source with noise alone
    out = {}
    for name, b in before.items():
        a = after.get(name, {})
        out[name] = {
            "gap_before": b["gap"],
            "gap_after": a.get("gap"),
            "share_before": b.get("share"),
            "share_after": a.get("share"),
            "gap_before_interval": b.get("gap_interval"),
            "gap_after_interval": a.get("gap_interval"),
            "share_before_interval": b.get("share_interval"),
            "share_after_interval": a.get("share_interval"),
        }
        if name in noise:
            out[name]["gap_noise"] = noise[name]
    return out


def accuracy_table(records: list[dict], protocol: Protocol) -> dict[str, dict]:
    """{label: {mean, std, n}}: target test accuracy (%) over repetitions, in the column order
    of accuracy_columns."""
    out = {}
    for variant, m in accuracy_columns(protocol):
        label = label_of(variant, m)
        acc = [r["accuracy"] for r in records if r.get("variant") == variant and r.get("method") == label]
        if acc:
            out[label] = {
                "mean": float(np.mean(acc)),
                "std": float(np.std(acc, ddof=1)) if len(acc) > 1 else 0.0,
                "n": len(acc),
            }
    return out


def summarise(scenario: Scenario, run: RunDir, notes: list[str]) -> None:
    spec = scenario.spec
    records = run.records()
    result = next(r["result"] for r in records if r["unit"] == "diagnosis")
    acc = accuracy_table(records, spec.protocol)
    bound = next((r for r in records if r["unit"] == "bound"), None)
    if acc and bound is not None and "accuracy" in bound:  # the reference row, as in the transfer table
        acc[bound["label"]] = bound["accuracy"]["0"]
    elif bound is not None:
        notes = [*notes, f"Bayes bound unavailable: {bound['unavailable']}"]
    before, after = result["before"] or {}, result["after"] or {}  # None: a structure difference, no gap measured
    summary = {
        "kind": "gap",
        "scenario": scenario.name,
        "source": asdict(spec.source),
        "target": asdict(spec.target),
        "effects": [
            {
                "name": e["name"],
                "share_removed": e["share_removed"],
                "params": e["params"],
                "intervals": e.get("intervals", {}),
                "determined": e.get("determined", {}),
                # where a parameter is not identifiable: what the data do determine (gearlab.gap.identify)
                "combinations": e.get("combinations", []),
                "round": e.get("round"),
            }
            for e in result["effects"]
        ],
        "gap_before": result["gap_before"],
        "gap_after": result["gap_after"],
        "shrink": 1 - result["gap_after"] / result["gap_before"] if (result["gap_before"] or 0) > 0 else None,
        "reference": result.get("reference"),  # settings reference = 'noise': the source with its noise alone
        "unexplained": result["unexplained"],
        "verdict": verdict_text(result),
        "dropped": dropped_text(result) if result.get("dropped_effects") else None,
        "dropped_effects": dropped_rows(result),  # their final fit, for the ranking's rows
        "not_accepted": not_accepted_rows(result),  # a round's winner that widened the report's gap, and why
        "explained_share": result.get("explained_share"),
        "evaluations": result.get("evaluations"),  # the diagnosis's score evaluations, its fits' included
        "chain": result.get("chain"),
        "structure": result.get("structure"),  # speed, mesh order and level measured before any effect
        "significant_before": result["significant_before"],
        "significant_after": result["significant_after"],
        "auc_before": before.get("auc"),
        "auc_after": after.get("auc"),
        "p_before": before.get("p_value"),
        "p_after": after.get("p_value"),
        "mmd2_before": before.get("mmd2"),
        "mmd2_after": after.get("mmd2"),
        "views": view_rows(result),
        # consecutive rows: the output-shaft orders (blocks of Z2/gcd revolutions), outside the shares
        "output_shaft": {
            k: ({"gap": v["gap"], "gap_interval": v.get("gap_interval"), "blocks": v.get("blocks")} if v else None)
            for k, v in (
                ("before", before.get("output_shaft")),
                ("after", after.get("output_shaft")),
            )
        },
        "ranking": result["ranking"],
        "corrected_effects": result["corrected_effects"],
        "corrected_description": write_corrected(spec.source, result, run),  # its structural values, written
        "settings": result.get("settings", asdict(spec.settings)),
        "notes": notes + list(result.get("notes", [])) + list(before.get("notes", [])),
    }
    if acc:
        summary["accuracy"] = acc
        summary["accuracy_order"] = list(acc)  # the column order (JSON objects are written with sorted keys)
    run.write_json("summary.json", summary)
    run.write_text("table.md", tables_md(summary))
    report_begins()  # the run's 'report' stage, before matplotlib loads (seconds)
    from .gap_figures import draw  # here, not at the top: start-up time (matplotlib)

    draw(run.figures, summary)


def summary_lines(run: RunDir) -> list[str]:
    s = run.read_json("summary.json")
    names = ", ".join(
        f"{e['name']} ({percent(e['share_removed'])}; final fit: {params_text(e['params'], e.get('determined'))})"
        for e in s["effects"]
    )
    lines = [
        before_after(s),
        f"effects: {names or 'none'}" + (f" ({s['dropped']})" if s.get("dropped") else "") + "; "
        f"verdict: {s.get('verdict') or ('unexplained' if s['unexplained'] else 'explained')}{evaluations_text(s)}",
        *([f"corrected description: {s['corrected_description']}"] if s.get("corrected_description") else []),
    ]
    for e in s["effects"]:
        for c in e.get("combinations", []):
            moved = ", ".join(f"{k} x{v:.3g}" for k, v in c["factors"].items())
            pinned = f"; the data determine {c['determined']} = {c['value']:.4g}" if c.get("determined") else ""
            lines.append(f"{e['name']}: {moved} fits as well (within the score's noise){pinned}")
    ref = s.get("reference")
    if ref:
        lines.append(
            f"against the source with its sensor noise alone ({params_text(ref['params'])}): gap {ref['gap']:.4g} "
            f"-> {s['gap_after']:.4g}; {shrink_text(ref['gap'], s['gap_after'])} removed beyond the noise"
        )
    shaft = s.get("output_shaft") or {}
    if shaft.get("before"):
        after = shaft.get("after") or {}
        lines.append(
            f"orders of the {shaft['before'].get('shaft', 'output shaft')} (consecutive revolutions): gap "
            f"{shaft['before']['gap']:.4g} -> {after.get('gap', float('nan')):.4g}"
        )
    lines += ["per-view gap:", views_md(s["views"]).rstrip()] if s["views"] else []
    if s.get("accuracy"):
        lines += [
            "target fault-detection accuracy (k = 0):",
            accuracy_md(s["accuracy"], s.get("accuracy_order")).rstrip(),
        ]
    lines += [f"note: {n}" for n in s.get("notes", [])]
    return lines


def records_table(scenario: Scenario, records: list[dict]) -> str:
    """What is known so far: the diagnosis once it has finished, the accuracy as units finish."""
    parts = []
    diag = next((r for r in records if r.get("unit") == "diagnosis"), None)
    if diag is not None:
        result = diag["result"]
        parts += [views_md(view_rows(result)), ranking_md(result["ranking"], result["effects"])]
    acc = accuracy_table(records, scenario.spec.protocol)
    if acc:
        parts.append(accuracy_md(acc))
    return "\n".join(parts) if parts else "| diagnosis |\n|---|\n| running |\n"


def charts(scenario: Scenario, run: RunDir) -> list[Chart]:
    records = run.records()
    diag = next((r for r in records if r.get("unit") == "diagnosis"), None)
    out = []
    if diag is None:
        out.append(Chart("per-view gap before/after", "", "", (), notes=("the diagnosis has not finished",)))
    else:
        rows = view_rows(diag["result"])
        names = list(rows)
        x = list(range(len(names)))
        out.append(
            Chart(
                "per-view gap before/after",
                "view",
                "gap (sum of squared effect sizes, 1)",
                (
                    Curve("before", x, [rows[n]["gap_before"] for n in names]),
                    Curve("after", x, [rows[n]["gap_after"] or 0.0 for n in names]),
                ),
                categories=names,
            )
        )
        ranking = diag["result"]["ranking"]
        if ranking:
            out.append(
                Chart(
                    "effect ranking: share of the gap removed",
                    "effect",
                    "share removed (%)",
                    (Curve("round 1", list(range(len(ranking))), [100 * r["share_removed"] for r in ranking]),),
                    categories=[r["name"] for r in ranking],
                )
            )
    acc = accuracy_table(records, scenario.spec.protocol)
    if acc:
        labels = list(acc)
        out.append(
            Chart(
                "target test accuracy (k = 0)",
                "model",
                "accuracy (%)",
                (
                    Curve(
                        "mean",
                        list(range(len(labels))),
                        [acc[n]["mean"] for n in labels],
                        [acc[n]["std"] for n in labels],
                    ),
                ),
                categories=labels,
            )
        )
    return out


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """The named effects and their numbers (gearlab.kinds.gap_verdict)."""
    return gap_lines(summary)


def verdict_table(summary: dict) -> str | None:
    return None  # table.md's per-view, ranking and accuracy tables say it all


compare_table = no_compare  # each gap run's own tables, lettered
table_title = no_title  # its tables are titled


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    return {
        "gap_per_view": (
            "",
            "Where the gap lies: per-view gap (sum of squared effect sizes, dimensionless) of the healthy revolutions "
            "before and after correcting the simulator, with bootstrap intervals.",
        ),
        "gap_effect_ranking": (
            "",
            "Which effect: share of the gap (%) each candidate removes when added to the simulator alone; accepted "
            "effects in blue.",
        ),
        "gap_accuracy": (
            "",
            "How far: target test accuracy (%) at k = 0 of models trained on the uncorrected and the corrected "
            "simulator; mean ± std over repetitions.",
        ),
    }
