"""Scenario kind `dataset`: build (or load from the cache) datasets and show what is in them."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..charts import Chart, Curve, dataset_examples
from ..data import cache
from ..data.cache import load_or_build
from ..data.importers import MeasuredSpec
from ..data.spec import DatasetSpec
from ..errors import GearlabInputError
from ..events import Event, figures_ahead
from ..files import matched
from ..runs import RunDir
from ..scenario import Scenario, location
from ..signals import order_spectrum
from .common import BUILDS, DATASET_TABLE, dataset_spec, executor_for, no_compare, no_table, no_title, sized

TABLES = {"datasets": DATASET_TABLE}
OVERRIDES: tuple[str, ...] = ()  # no key is set from the command line


def build(scenario: Scenario) -> list[DatasetSpec | MeasuredSpec]:
    """The [[datasets]]; an entry whose 'file' is a glob pattern (files.matched) stands for one measured
    dataset per file it matches, each named by its file."""
    base = Path(scenario.base or scenario.path.parent)
    specs = []
    for i, entry in enumerate(scenario.tables["datasets"]):
        at = location(scenario.path, "datasets", index=i)
        names = matched(entry["file"], base, f"{at} key 'file'") if entry["file"] else [""]
        if len(names) > 1 and entry["name"]:
            raise GearlabInputError(
                f"{at} key 'name': {entry['name']!r} names one dataset, and {entry['file']!r} matches {len(names)} "
                "files; expected no 'name' (each dataset is named by its file) or an entry for each file"
            )
        specs.extend(dataset_spec({**entry, "file": name} if name else entry, at, base) for name in names)
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise GearlabInputError(f"{scenario.path}: dataset names must be unique; give each entry a 'name'")
    return specs


def describe(scenario: Scenario) -> str:
    """One line for `gearlab validate` and the TUI: what the scenario will do."""
    return f"{len(scenario.spec)} dataset(s): " + ", ".join(sized(s) for s in scenario.spec)


def quick(scenario: Scenario) -> None:
    """Smoke run: two teeth, the top intensity of each fault, a few healthy samples, J <= 4."""
    scenario.spec = [
        s.with_(
            teeth=(1, 2),
            faults=tuple((f, steps[-1:]) for f, steps in s.faults),
            duplicates=1,
            healthy=min(s.healthy, 4),
            revolutions=min(s.revolutions, 4),
        )
        if isinstance(s, DatasetSpec)
        else s
        for s in scenario.spec
    ]


def unlabelled(dataset) -> bool:
    """A recording without a labels channel: every revolution's label is -1 (no class to show)."""
    return len(dataset) > 0 and bool((dataset.label < 0).all())


def class_counts(dataset) -> dict[str, int]:
    if unlabelled(dataset):
        return {"unlabelled": len(dataset)}
    return {name: int((dataset.label == c).sum()) for c, name in enumerate(dataset.spec.class_names)}


def unit_modules(scenario: Scenario) -> tuple[str, ...]:
    return BUILDS


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    with executor_for(scenario) as executor:
        done = {r["unit"]: r for r in run.records()}
        summary = {"kind": "dataset", "scenario": scenario.name, "datasets": {}}
        figures_ahead(len(scenario.spec))  # a figure per dataset, each drawn once it is built
        for spec in scenario.spec:
            dataset, cached = load_or_build(spec, executor, on_event)
            record = done.get(spec.name) or {
                "unit": spec.name,
                "key": spec.key(),
                "cached": cached,
                "n": len(dataset),
                "counts": class_counts(dataset),
                "reference": list(dataset.reference),
                "meta": dataset.meta,
            }
            if spec.name not in done:
                run.append(record)
                on_event(Event("record", stage="datasets", record=record))
            for warning in dataset.meta.get("warnings", []):  # a level that never settled, kept whole
                on_event(Event("log", message=f"WARNING: {warning}"))
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
    from .dataset_figures import dataset_signals, recording_signals  # here, not at the top: start-up time (matplotlib)

    target = run.file("figures", f"signals_{dataset.spec.name}.png")
    if unlabelled(dataset):
        spec = dataset.spec
        title = f"recording {spec.name}: {spec.vibration} of {Path(spec.path).name} (unlabelled)"
        recording_signals(recording_views(dataset), title, target)
    else:
        dataset_signals(dataset, target)


def summary_lines(run: RunDir) -> list[str]:
    summary = run.read_json("summary.json")
    lines = [table_md(summary).rstrip()]
    for name, d in summary["datasets"].items():
        lines.append(
            f"{name}: {d['n']} samples x {d['shape'][1]}, cache key {d['key']}"
            + (" (from cache)" if d["cached"] else "")
        )
    return lines


def records_table(scenario: Scenario, records: list[dict]) -> str:
    return table_md({"datasets": {r["unit"]: r for r in records}})


def charts(scenario: Scenario, run: RunDir) -> list:
    """Per dataset (from the cache; nothing is rebuilt to draw it): a revolution of each class at
    its top intensity, and their order spectra."""
    done = {r["unit"] for r in run.records()}
    out = []
    for spec in scenario.spec:
        if spec.name not in done:
            continue
        dataset = cache.load(spec)
        if dataset is None:
            out.append(Chart(f"dataset {spec.name}", "", "", (), notes=("not in the dataset cache any more",)))
            continue
        if unlabelled(dataset):  # no class to show: the recording itself
            out.extend(recording_views(dataset))
            continue
        examples = dataset_examples(dataset, per_class=1)
        angle = np.arange(dataset.X.shape[1]) * 360.0 / dataset.X.shape[1]
        out.append(
            Chart(
                f"{spec.name}: one revolution per class",
                "input-shaft angle (deg)",
                "standardised",
                tuple(Curve(label, angle, dataset.X[i]) for _, label, i in examples),
            )
        )
        spectra = []
        for _, label, i in examples:
            orders, amp = order_spectrum(dataset.X[i])
            keep = orders <= 200
            spectra.append(Curve(label, orders[keep], amp[keep]))
        out.append(Chart(f"{spec.name}: order spectra", "shaft order", "amplitude", tuple(spectra)))
    return out


def recording_views(dataset, max_order: float = 200.0) -> tuple[Chart, Chart, Chart]:
    """An unlabelled recording (no class to show): (its first, middle and last revolutions; their
    time-synchronous average over every revolution, ± the revolutions' standard deviation; the
    order spectra of one revolution and of the TSA, where what is not synchronous averages away)."""
    X = np.asarray(dataset.X, dtype=np.float64)
    n, points = X.shape
    angle = np.arange(points) * 360.0 / points
    rows = sorted({0, n // 2, n - 1})
    revolution = dataset.revolution
    revolutions = Chart(
        f"{dataset.spec.name}: revolutions (of {n})",
        "input-shaft angle (deg)",
        "standardised",
        tuple(Curve(f"revolution {int(revolution[i])}", angle, X[i]) for i in rows),
    )
    average = X.mean(axis=0)
    tsa = Chart(
        f"{dataset.spec.name}: time-synchronous average of {n} revolutions (band: ± their std)",
        "input-shaft angle (deg)",
        "standardised",
        (Curve("TSA", angle, average, X.std(axis=0)),),
    )
    spectra = []
    for label, y in ((f"revolution {int(revolution[rows[0]])}", X[rows[0]]), ("TSA", average)):
        orders, amp = order_spectrum(y)
        keep = orders <= max_order
        spectra.append(Curve(label, orders[keep], amp[keep]))
    return revolutions, tsa, Chart(f"{dataset.spec.name}: order spectra", "shaft order", "amplitude", tuple(spectra))


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """What each dataset holds: its revolutions per class and their length (report.html opens with it)."""
    lines = []
    for name, d in (summary.get("datasets") or {}).items():
        counts = ", ".join(f"{n} {label}" for label, n in (d.get("counts") or {}).items())
        lines.append(f"{name}: {d['n']} revolutions of {d['shape'][1]} samples ({counts}).")
    return lines


verdict_table, compare_table = no_table, no_compare  # the summary lines say the rest
table_title = no_title


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    """Each dataset's revolutions per class (Figures 2.34-2.39)."""
    return {
        f"signals_{name}": (
            "Figures 2.34-2.39",
            f"Dataset {name}: a revolution per class at low, middle and top intensity (standardised "
            "acceleration against input-shaft angle, deg) and its order spectrum (amplitude against shaft order).",
        )
        for name in summary.get("datasets") or {}
    }
