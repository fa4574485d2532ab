"""Scenario kind `transfer`: the chapter-5 calibration experiments (Experiments A and B).

    [source] / [target]   a dataset preset with overrides (as in [[datasets]])
    [network]             name (fast | cnn3), dropout
    [[methods]]           adapter, supervised, params
    [protocol]            ks, repetitions, target_train, batch, lr, epochs, seed

Output: results.jsonl (one record per repetition x k x method), summary.json with
`table` = {method label: {k: {mean, std}}}, table.md/table.csv in the Table 5.4 layout,
figures (Figures 5.5-5.9) and report.html.
"""

from __future__ import annotations

import io
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from ..charts import Chart, Curve
from ..data import cache
from ..data.cache import load_or_build
from ..data.importers import MeasuredSpec
from ..data.spec import DatasetSpec
from ..errors import GearlabInputError
from ..events import Event, report_begins
from ..learn.config import Calibration
from ..learn.protocol import (
    KS,
    Counts,
    Method,
    Protocol,
    check,
    check_data,
    domain_adapting,
    shared_state,
    unit_key,
)
from ..learn.schedule import longest_first, two_phases
from ..parts.bound import BOUND, STEPS, bayes_bound
from ..parts.training import CALIBRATION, METHOD_KEYS, NETWORK, TRAINING, check_training, method, train_unit
from ..runs import RunDir
from ..scenario import Scenario, Table, keys_of, location
from ..settings import setting, shrunk
from .common import BUILDS, DATASET_TABLE, TRAINS, dataset_spec, device_of, executor_for, planned_counts, sized
from .transfer_verdict import experiment, transfer_lines, transfer_table


@dataclass(frozen=True, kw_only=True)
class Shots:
    """[protocol] ks: the rest of [protocol] is declared on Protocol and Calibration."""

    ks: list = setting(list, list(KS), doc="numbers of target fault samples in the target training set")


_DATASET = Table(DATASET_TABLE.keys, required=True, moved=DATASET_TABLE.moved)
TABLES = {
    "source": _DATASET,
    "target": _DATASET,
    "network": NETWORK,
    "methods": Table(METHOD_KEYS, array=True, required=True),
    "protocol": Table(
        {
            **keys_of(Shots),
            **keys_of(Protocol, ("repetitions",)),
            **TRAINING,
            **CALIBRATION,
        }
    ),
}
OVERRIDES: tuple[str, ...] = ()  # no key is set from the command line


@dataclass(frozen=True)
class Spec:
    """What build() checked: the source and target datasets (simulated or measured) and the protocol."""

    source: DatasetSpec | MeasuredSpec
    target: DatasetSpec | MeasuredSpec
    protocol: Protocol


def build(scenario: Scenario) -> Spec:
    """Resolve and check everything that can be checked before any dataset is built."""
    t = scenario.tables
    path = scenario.path
    p = t["protocol"]  # its false_alarm: the detectors' too (one rate a scenario)
    methods = [method(m, location(path, "methods", index=i), p["false_alarm"]) for i, m in enumerate(t["methods"])]
    seen: dict[tuple, int] = {}
    for i, m in enumerate(methods):
        # the same training twice, whatever the spelling (variant = "classifier" or 1)
        first = seen.setdefault((m.adapter, m.supervised, m.params), i)
        if first != i:
            raise GearlabInputError(
                f"{location(path, 'methods', index=i)}: {m.label} is the same method as "
                f"#{first + 1}, {methods[first].label}"
            )
    ks = p["ks"]
    # whole numbers checked first: set() of a list holding a list would fail
    if (
        not ks
        or not all(isinstance(k, int) and not isinstance(k, bool) and k >= 0 for k in ks)
        or len(set(ks)) != len(ks)
    ):
        raise GearlabInputError(
            f"{location(path, 'protocol', 'ks')}: expected a list of distinct whole numbers >= 0, got {ks!r}"
        )
    check_training(t, path)
    protocol = Protocol(
        methods=tuple(methods),
        network=t["network"]["name"],
        dropout=t["network"]["dropout"],
        ks=tuple(ks),
        repetitions=p["repetitions"],
        **{key: p[key] for key in TRAINING},
        device=device_of(scenario),
        calibration=Calibration(**{key: p[key] for key in CALIBRATION}),
    )
    protocol.calibration.check(str(path))
    check(protocol, str(path))
    base = scenario.base or path.parent  # a run's copy of the scenario keeps its folder (--resume)
    source = dataset_spec(t["source"], location(path, "source"), base)
    target = dataset_spec(t["target"], location(path, "target"), base)
    if isinstance(target, MeasuredSpec) and target.labels is None:
        # its k-shot training and its accuracy read the target's labels: unlabelled, every k stopped the run later
        raise GearlabInputError(
            f"{location(path, 'target', 'labels')}: missing; the transfer kind trains on and scores the target's "
            f"labels, {target.path} given none (a channel of each revolution's class, class_names); recordings "
            "without labels: kind = 'detection' (docs/your_gearbox.md)"
        )
    planned = planned_counts(source, location(path, "source")), planned_counts(target, location(path, "target"))
    if None not in planned:
        check_data(protocol, *planned, str(path))
    return Spec(source, target, protocol)


def describe(scenario: Scenario) -> str:
    """One line for `gearlab validate` and the TUI: what the scenario will do."""
    spec = scenario.spec
    p = spec.protocol
    return (
        f"{sized(spec.source)} -> {sized(spec.target)}, network {p.network}, {len(p.methods)} methods x "
        f"{len(p.ks)} k x {p.repetitions} repetitions = {len(p.methods) * len(p.ks) * p.repetitions} training runs"
    )


def quick(scenario: Scenario) -> None:
    """Smoke run: 2 repetitions, k in {0, 4}, short training."""
    p = shrunk(scenario.spec.protocol)  # the --quick limits declared on Protocol
    ks = tuple(k for k in p.ks if k in (0, 4)) or p.ks[:1]
    scenario.spec = replace(scenario.spec, protocol=replace(p, ks=ks))


def units(protocol: Protocol) -> list[tuple[int, int, Method]]:
    return [(rep, k, m) for rep in range(protocol.repetitions) for k in protocol.ks for m in protocol.methods]


def unit_modules(scenario: Scenario) -> tuple[str, ...]:
    """What every training loads first (2.7 s of CPU): the datasets' and the bound's units wait for it, the
    trainings not at all."""
    return BUILDS + TRAINS


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    spec = scenario.spec
    protocol = spec.protocol
    with executor_for(scenario) as executor:
        on_event(Event("stage", stage="datasets", total=2, message="datasets"))
        source, _ = load_or_build(spec.source, executor, on_event)
        on_event(Event("advance", stage="datasets", done=1, total=2))
        target, _ = load_or_build(spec.target, executor, on_event)
        on_event(Event("advance", stage="datasets", done=2, total=2))
        check_data(protocol, Counts.of(source), Counts.of(target), str(scenario.path))
        # a stage of its own: the noise-free twin and the likelihood ratios take seconds (issue 41)
        steps = STEPS  # a target with no bound (measured, noise-free) ends the stage at once
        on_event(Event("stage", stage="bound", total=steps, message="Bayes bound of the target test sets"))
        bound = bayes_bound(
            spec.target,
            source,
            target,
            protocol,
            executor,
            on_event,
            on_step=lambda done: on_event(Event("advance", stage="bound", done=done, total=steps)),
        )
        if bound is not None:
            run.write_json("bound.json", bound)
        on_event(Event("advance", stage="bound", done=steps, total=steps))
        done = {r["unit"] for r in run.records()}
        todo = units(protocol)
        pending = [(rep, k, m) for rep, k, m in todo if unit_key(rep, k, m) not in done]

        # The first unit that needs a repetition's shared state (priming, source-only model) makes
        # it; every other unit waits for phase 2 and loads it from the run directory.
        def state_file(unit: tuple) -> Path | None:
            rep, k, m = unit
            state = shared_state(m, rep, k, protocol)
            return None if state is None else run.file("states", f"{state}.pt")

        phases = schedule(pending, state_file, protocol)
        first = [u for u in phases[0] if state_file(u) is not None]  # the shared states' makers
        if first:
            on_event(
                Event(
                    "stage",
                    stage="priming",
                    total=len(first),
                    message=f"priming: {len(first)} shared states (primed and source-only models)",
                )
            )
        on_event(Event("stage", stage="runs", total=len(todo), message=f"{len(todo)} training runs"))
        finished = len(todo) - len(pending)
        on_event(Event("advance", stage="runs", done=finished, total=len(todo)))
        priming = {unit_key(*u) for u in first}

        def record_done(_: int, record: dict) -> None:
            nonlocal finished
            latent = record.pop("_latent", None)
            if latent is not None and record["rep"] == 0:
                save_latent(run, record["unit"], latent)
            run.append(record)
            finished += 1
            if record["unit"] in priming:
                priming.discard(record["unit"])
                on_event(Event("advance", stage="priming", done=len(first) - len(priming), total=len(first)))
            on_event(
                Event(
                    "log",
                    message=f"{record['unit']}: target test accuracy {record['accuracy']:.1f} %, "
                    f"{record['predicted_fault_share']:.0f} % predicted faulty",
                )
            )
            on_event(Event("record", stage="runs", record=record))
            on_event(Event("advance", stage="runs", done=finished, total=len(todo)))

        for phase in phases:
            # the cache entries by path: a worker process may not share this one's environment
            data = [(d, cache.entry_path(d)) for d in (spec.source, spec.target)]
            tasks = [(protocol, *data, rep, k, m, run.file("states")) for rep, k, m in phase]
            # a unit asks the executor for a GPU unless the scenario trains on the CPU
            executor.map(train_unit, tasks, on_done=record_done, gpu=protocol.device != "cpu")
        summarise(scenario, run)


def schedule(pending: list, state_file, protocol: Protocol) -> tuple[list, list]:
    """The two phases of *pending* (learn.schedule.two_phases): phase 1 the units that make the
    shared states, in their order, and behind them every unit that needs none (target_only, the
    detectors), so that a worker done with its share of the primings takes those instead of
    standing until the last priming ends; phase 2 the units that load a state. Each phase's added
    units go longest first (the joint trainings, then the other trainings, the detectors last),
    so that short units fill in at the end. Results do not depend on the order: each unit is
    seeded by itself."""

    def cost(unit: tuple) -> tuple:
        _, _, m = unit
        return domain_adapting(m.adapter), not m.is_detector

    makers, rest = two_phases(pending, state_file)
    free = [u for u in rest if state_file(u) is None]
    loading = [u for u in rest if state_file(u) is not None]
    return makers + longest_first(free, cost), longest_first(loading, cost)


def save_latent(run: RunDir, unit: str, latent: dict) -> None:
    buf = io.BytesIO()
    np.savez(buf, **latent)
    run.write_text(f"latent/{unit.replace('/', '_')}.npz", buf.getvalue())


def columns(protocol: Protocol) -> list[Method]:
    """The methods in the column order of Table 5.4: the unsupervised ones, then the supervised
    ones, each in the scenario's order."""
    return sorted(protocol.methods, key=lambda m: m.supervised)


def table(records: list[dict], protocol: Protocol, measure: str = "accuracy") -> dict:
    """{method label: {k: {mean, std, n}}}: a measure (%) of the records over the repetitions,
    target test accuracy by default (records written before a measure existed are left out)."""
    out: dict[str, dict[str, dict]] = {}
    records = sorted(records, key=lambda r: r.get("rep", 0))  # the same sums whatever order units ended in
    for m in columns(protocol):
        out[m.label] = {}
        for k in protocol.ks:
            acc = [r[measure] for r in records if r["method"] == m.label and r["k"] == k and measure in r]
            if acc:
                out[m.label][str(k)] = {
                    "mean": float(np.mean(acc)),
                    "std": float(np.std(acc, ddof=1)) if len(acc) > 1 else 0.0,
                    "n": len(acc),
                }
    return out


def table_md(tab: dict, ks, methods: list[str]) -> str:
    """Table 5.4 layout: a row per k, a column per method and supervision, mean ± std."""
    lines = ["| k (target fault samples) | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
    for k in ks:
        cells = []
        for m in methods:
            c = tab[m].get(str(k))
            cells.append(f"{c['mean']:.2f} ± {c['std']:.1f}" if c else "")
        if any(cells):  # a run still going shows the rows it has
            lines.append(f"| {k} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def measures_md(summary: dict, ks) -> str:
    """The balanced accuracy and the faults found at 1 % false alarms, in the same layout."""
    out = ""
    bound = summary.get("bound")
    for key, title in (
        (
            "balanced_accuracy",
            "Balanced accuracy (%), the mean of the healthy and the fault recall: the score on a half-healthy test set",
        ),
        (
            "detection_at_1pct",
            "Faults found (%) at the threshold that lets 1 % of the test "
            "set's healthy revolutions through (an evaluation with the test labels)",
        ),
    ):
        tab = {m: c for m, c in summary.get(key, {}).items() if c}
        if key == "detection_at_1pct" and bound:
            tab[BOUND] = bound["detection_at_1pct"]
        if tab:
            out += f"\n{title}:\n\n" + table_md(tab, ks, list(tab))
    return out


def table_csv(tab: dict, ks) -> str:
    rows = ["method,k,mean,std,n"]
    for m, per_k in tab.items():
        for k in ks:
            c = per_k.get(str(k))
            if c:
                rows.append(f'"{m}",{k},{c["mean"]:.4f},{c["std"]:.4f},{c["n"]}')
    return "\n".join(rows) + "\n"


def summarise(scenario: Scenario, run: RunDir) -> None:
    protocol = scenario.spec.protocol
    records = run.records()
    from ..learn.training import pick_device  # start-up time (torch)

    tab = table(records, protocol)
    summary = {
        "kind": "transfer",
        "scenario": scenario.name,
        "source": asdict(scenario.spec.source),
        "target": asdict(scenario.spec.target),
        "protocol": {k: v for k, v in asdict(protocol).items() if k != "methods"},
        "methods": list(tab),  # the column order (JSON objects are written with sorted keys)
        "table": tab,
        # measures that do not hinge on the test set's healthy share (gearlab.learn.protocol)
        "balanced_accuracy": table(records, protocol, "balanced_accuracy"),
        "detection_at_1pct": table(records, protocol, "detection_at_1pct"),
        "units": len(records),
        "device": str(pick_device(protocol.device)),  # where the units trained (cuda when present, by default)
        "healthy_share_of_test": float(np.mean([r["healthy_share"] for r in records])) if records else None,
    }
    bound = run.read_json("bound.json") if run.file("bound.json").exists() else {}
    if "accuracy" in bound:
        summary["bound"] = bound
        tab = {**tab, BOUND: summary["bound"]["accuracy"]}  # the reference column of table.md/csv
    elif "unavailable" in bound:
        summary["bound_unavailable"] = bound["unavailable"]
    run.write_json("summary.json", summary)
    run.write_text("table.md", table_md(tab, protocol.ks, list(tab)) + measures_md(summary, protocol.ks))
    run.write_text("table.csv", table_csv(tab, protocol.ks))
    report_begins()  # the run's 'report' stage, before matplotlib loads (seconds)
    from .transfer_figures import draw  # here, not at the top: start-up time (matplotlib)

    draw(run.file(), records, tab, protocol.ks)


def summary_lines(run: RunDir) -> list[str]:
    summary = run.read_json("summary.json")
    ks = summary["protocol"]["ks"]
    tab, methods = summary["table"], summary["methods"]
    if "bound" in summary:
        tab, methods = {**tab, BOUND: summary["bound"]["accuracy"]}, [*methods, BOUND]
    lines = [
        "target-domain test accuracy [%], mean ± std over repetitions (Table 5.4 layout):",
        table_md(tab, ks, methods).rstrip(),
    ]
    if summary.get("bound_unavailable"):
        lines.append(f"Bayes bound unavailable: {summary['bound_unavailable']}")
    if summary.get("healthy_share_of_test") is not None:
        lines.append(f"healthy share of the target test sets: {summary['healthy_share_of_test']:.2f} %")
    if summary.get("device"):
        lines.append(f"trained on: {summary['device']}")
    return lines


def records_table(scenario: Scenario, records: list[dict]) -> str:
    """The Table 5.4 layout of the records so far (the TUI fills it as units finish)."""
    protocol = scenario.spec.protocol
    tab = table(records, protocol)
    return table_md(tab, protocol.ks, list(tab))


def charts(scenario: Scenario, run: RunDir) -> list[Chart]:
    """Accuracy against k with a ± std band per method (Figures 5.5/5.6)."""
    protocol = scenario.spec.protocol
    tab = table(run.records(), protocol)
    curves = []
    for label, per_k in tab.items():
        ks = [k for k in protocol.ks if str(k) in per_k]
        if ks:
            curves.append(Curve(label, ks, [per_k[str(k)]["mean"] for k in ks], [per_k[str(k)]["std"] for k in ks]))
    return [
        Chart(
            "target test accuracy against k",
            "target fault samples k",
            "accuracy (%)",
            tuple(curves),
            xticks=list(protocol.ks),
        )
    ]


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """The best method per k, collapses, the bound and the thesis (gearlab.kinds.transfer_verdict)."""
    return transfer_lines(summary, records)


def verdict_table(summary: dict) -> str | None:
    """Table 5.4's layout with the bound and, for Experiments A and B, the thesis's rows."""
    return transfer_table(summary, table_md) if summary.get("table") else None


def table_title(summary: dict, index: int, table: str) -> str:
    """The first table: Table 5.4's layout (verdict_table)."""
    if index != 1:
        return ""
    return "Target test accuracy (%), mean ± std over the repetitions, in the layout of thesis Table 5.4" + (
        "; reference rows in italics: the thesis's values" if "(thesis" in table else ""
    )


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    """Figures 5.5/5.6 (or the thesis figure of the experiment the run repeats), 5.7, 5.8 and 5.9."""
    protocol = summary.get("protocol") or {}
    reps = protocol.get("repetitions") or protocol.get("runs")
    over = f" over {reps} repetitions" if reps else ""
    found = experiment(summary)
    return {
        "accuracy_vs_k": (
            found[2] if found else "Figures 5.5/5.6",
            f"Target test accuracy (%) against the number of target fault samples k in the training set: "
            f"mean{over}, band ± one standard deviation; solid lines supervised, dashed unsupervised.",
        ),
        "training_curves": (
            "Figure 5.7",
            "Training curves of the first repetition at the middle k: source validation accuracy (%, left axis), "
            "domain discrepancy and λ (dimensionless, right axis) against epoch; the dashed line marks the epoch "
            "kept.",
        ),
        "confusion_k0": (
            "Figure 5.8",
            f"Confusion matrices at k = {min(protocol.get('ks') or [0])}, summed{over} (counts of target test "
            "samples; rows: true class, columns: predicted class).",
        ),
        "latent_maps": (
            "Figure 5.9",
            "Latent features of the first repetition after adaptation: source (with the target's noise where "
            "training added it) and target training samples projected on their first two principal components "
            "(PCA, dimensionless); colour: domain, marker: "
            "class (o healthy, x fault) where the run stored the labels.",
        ),
    }


def compare_table(runs: list[tuple]) -> tuple[str, str] | None:
    """(title, Markdown) of transfer runs side by side: a row per method and k, a column per run
    (mean ± std) and, for each run after the first, its difference to A in points. *runs*:
    (letter, scenario, records, summary) in the order compared."""
    cells = [table(records, scenario.spec.protocol) for _, scenario, records, _ in runs]
    letters = [letter for letter, *_ in runs]
    methods = list(dict.fromkeys(m for tab in cells for m in tab))
    ks = list(dict.fromkeys(k for _, scenario, *_ in runs for k in scenario.spec.protocol.ks))
    head = ["method", "k", *letters] + [f"{letter} − {letters[0]}" for letter in letters[1:]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for m in methods:
        for k in ks:
            got = [tab.get(m, {}).get(str(k)) for tab in cells]
            if not any(got):
                continue
            shown = [f"{g['mean']:.2f} ± {g['std']:.1f}" if g else "" for g in got]
            delta = [f"{g['mean'] - got[0]['mean']:+.2f}" if g and got[0] else "" for g in got[1:]]
            lines.append(f"| {m} | {k} | " + " | ".join(shown + delta) + " |")
    return "Target test accuracy (%) of each run, mean ± std over repetitions", "\n".join(lines) + "\n"
