"""Scenario kind `noise_study`: the chapter-4 noise-robustness study (thesis 4.1-4.4).

    [study]      noises: which noise types; each gives a noisy and a TSA dataset
                 (presets A-casing_noise-<noise> and A-casing_TSA-<noise>, Table 4.1)
    [dataset]    overrides applied to both presets alike (teeth, duplicates, healthy,
                 revolutions, faults, effects = [{name = "sensor_noise", snr_db, seed}], ...)
    [network]    name (fast | cnn3), dropout
    [protocol]   runs, test_fraction, val_fraction, batch, lr, epochs, patience, seed

A unit of work is (noise type, noisy | tsa, run). Output: results.jsonl (one record per
unit), summary.json (per noise type and variant: accuracy and fault-as-healthy rate as
mean ± std over runs, curves per fault type against intensity and RFA, the confusion
matrix compiled over runs), table.md/table.csv (noise type x noisy/TSA) and the figures
of Figures 4.4-4.6.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from ..charts import Chart, Curve
from ..data import cache
from ..data.cache import load_or_build
from ..data.spec import DatasetSpec, dataset_preset
from ..errors import GearlabInputError, did_you_mean
from ..events import Event, UnitProgress, report_begins, standing
from ..executors import one_thread
from ..learn.bounds import class_bound, class_bound_steps
from ..learn.config import NetworkSettings
from ..learn.noise_study import (
    VARIANTS,
    NoiseProtocol,
    aggregate,
    check_batch,
    check_split,
    mean_std,
    noise_law,
    run_unit,
    split,
)
from ..runs import RunDir
from ..scenario import Scenario, Table, keys_of, location
from ..settings import setting
from ..signals import NOISE_KINDS
from .common import (
    BUILDS,
    DATASET_TABLE,
    NOISE_EFFECT,
    DatasetEntry,
    class_sizes,
    dataset_spec,
    device_of,
    executor_for,
    no_compare,
    no_table,
    no_title,
    noise_spec,
)

# What a study may change in the chapter-4 presets; the preset itself, the noise kind and
# TSA are what the study varies.
_OVERRIDES = (
    "model",
    "model_preset",
    "channel",
    "speed",
    "load",
    "faults",
    "teeth",
    "duplicates",
    "healthy",
    "revolutions",
    "seed",
    "fs",
)


@dataclass(frozen=True, kw_only=True)
class Study:
    """[study]"""

    noises: list = setting(
        list, list(NOISE_KINDS), doc=f"noise types, each studied noisy and with TSA: {', '.join(NOISE_KINDS)}"
    )


@dataclass(frozen=True, kw_only=True)
class StudyDataset(DatasetEntry):
    """[dataset]: the keys of _OVERRIDES and the noise's level (its kind is what the study varies)."""

    effects: list | None = setting(
        list, None, doc="[{name = 'sensor_noise', snr_db = 0, seed = 0}]: the noise; its kind comes from [study] noises"
    )


STUDY_NOISE = f'effects = [{{ name = "{NOISE_EFFECT}", snr_db = 0.0, seed = 0 }}]'
TABLES = {
    "study": Table(keys_of(Study)),
    "dataset": Table(
        keys_of(StudyDataset, (*_OVERRIDES, "effects")),
        moved={"noise": f"the study's noise is an effect: {STUDY_NOISE} (its kind comes from [study] noises)"},
    ),
    "network": Table(keys_of(NetworkSettings, name=NoiseProtocol.network, dropout=NoiseProtocol.dropout)),
    "protocol": Table(keys_of(NoiseProtocol)),
}
OVERRIDES: tuple[str, ...] = ()  # no key is set from the command line


def preset_name(noise: str, variant: str) -> str:
    return f"A-casing_{'TSA' if variant == 'tsa' else 'noise'}-{noise}"


@dataclass(frozen=True)
class Spec:
    """What build() checked: {noise type: {variant: its dataset}} and the protocol."""

    datasets: dict[str, dict[str, DatasetSpec]]
    protocol: NoiseProtocol


def check(spec: Spec, path) -> None:
    """The split and the batch size against the class sizes (all the study's datasets share them)."""
    where = location(path, "dataset")
    dataset = next(iter(spec.datasets.values()))["noisy"]
    sizes = class_sizes(dataset, where)
    check_split(sizes, spec.protocol, where)
    check_batch(sizes, spec.protocol, location(path, "protocol", "batch"))


def build(scenario: Scenario) -> Spec:
    t = scenario.tables
    noises = t["study"]["noises"]
    where = location(scenario.path, "study", "noises")
    if not noises:
        raise GearlabInputError(f"{where}: expected a non-empty list of noise types ({', '.join(NOISE_KINDS)})")
    for noise in noises:
        if noise not in NOISE_KINDS:
            raise GearlabInputError(
                f"{where}: unknown noise type {noise!r}{did_you_mean(str(noise), NOISE_KINDS)}; "
                f"known: {', '.join(NOISE_KINDS)}"
            )
    if len(set(noises)) != len(noises):
        raise GearlabInputError(f"{where}: lists a noise type twice")
    p = t["protocol"]
    protocol = NoiseProtocol(
        network=t["network"]["name"], dropout=t["network"]["dropout"], device=device_of(scenario), **p
    )
    if protocol.start == "clean" and protocol.network != "shapes":
        raise GearlabInputError(
            f"{location(scenario.path, 'protocol', 'start')}: the clean start sets the shapes network's templates; "
            f"expected [network] name = 'shapes' (got '{protocol.network}')"
        )
    if protocol.network == "shapes" and not protocol.residual:
        raise GearlabInputError(
            f"{location(scenario.path, 'protocol', 'residual')}: the shapes network scores residuals from the healthy "
            "revolution; expected residual = true"
        )
    spec = Spec({noise: {v: _dataset(scenario, noise, v) for v in VARIANTS} for noise in noises}, protocol)
    check(spec, scenario.path)
    return spec


def _dataset(scenario: Scenario, noise: str, variant: str) -> DatasetSpec:
    """The chapter-4 preset of (noise, variant) with the [dataset] overrides, through the same
    path as a [[datasets]] entry."""
    overrides = scenario.tables["dataset"]
    where = location(scenario.path, "dataset")
    name = preset_name(noise, variant)
    here, tables = f"{where} key 'effects'", overrides["effects"]
    one = isinstance(tables, list) and len(tables) == 1 and isinstance(tables[0], dict)
    if tables is not None and not (one and tables[0].get("name") == NOISE_EFFECT):
        raise GearlabInputError(
            f"{here}: a noise study's one effect is its noise, {STUDY_NOISE} (its kind comes from [study] noises)"
        )
    user_noise = {k: v for k, v in (tables or [{}])[0].items() if k != "name"}
    if "kind" in user_noise:
        raise GearlabInputError(f"{here}: the noise kind comes from [study] key 'noises'; give only snr_db and seed")
    # the preset's noise (its kind is the study's), the snr_db and seed given changed
    noise_of = noise_spec({"kind": noise, **user_noise}, f"{here} #1 ({NOISE_EFFECT})", dataset_preset(name).noise)
    entry = {k: key.default for k, key in DATASET_TABLE.keys.items()}
    entry.update({k: overrides[k] for k in _OVERRIDES})
    entry.update(preset=name)
    spec = dataset_spec(entry, where, scenario.path.parent).with_(noise=noise_of)
    spec.check(where)
    return spec


def describe(scenario: Scenario) -> str:
    """One line for `gearlab validate` and the TUI: what the scenario will do."""
    spec = scenario.spec
    return (
        f"noise types {', '.join(spec.datasets)}, noisy and TSA, network {spec.protocol.network}: "
        f"{len(units(spec))} training runs"
    )


def quick(scenario: Scenario) -> None:
    """Smoke run: the first noise type, 4 teeth, every third intensity step, 2 duplicates,
    as many healthy samples as fault samples, J <= 8, one run of a few short epochs."""

    def shrink(spec: DatasetSpec) -> DatasetSpec:
        faults = tuple((f, steps[1::3] or steps) for f, steps in spec.faults)
        teeth = spec.teeth[:4] if spec.teeth is not None else (1, 5, 9, 13)
        duplicates = min(spec.duplicates, 2)
        n_faults = sum(len(steps) for _, steps in faults) * len(teeth) * duplicates
        return spec.with_(
            faults=faults,
            teeth=teeth,
            duplicates=duplicates,
            healthy=min(spec.healthy, n_faults),
            revolutions=min(spec.revolutions, 8),
        )

    spec = scenario.spec
    noise, variants = next(iter(spec.datasets.items()))
    p = spec.protocol
    scenario.spec = Spec(
        {noise: {v: shrink(s) for v, s in variants.items()}},
        replace(p, runs=1, epochs=min(p.epochs, 15), patience=min(p.patience, 5), batch=min(p.batch, 32)),
    )
    check(scenario.spec, scenario.path)


def units(spec: Spec) -> list[tuple[str, int, str]]:
    """(noise, run, variant): a noise type's noisy and TSA runs alternate, so a cut-short study
    still holds paired results."""
    return [(noise, r, v) for noise in spec.datasets for r in range(spec.protocol.runs) for v in VARIANTS]


def unit_name(noise: str, run: int, variant: str) -> str:
    return f"{noise}/{variant}/run{run}"


def unit_modules(scenario: Scenario) -> tuple[str, ...]:
    return (*BUILDS, "torch", __name__)  # the datasets' units, then the trainings (train_unit, here)


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    spec = scenario.spec
    protocol = spec.protocol
    with executor_for(scenario) as executor:
        done = {r["unit"] for r in run.records()}
        todo = units(spec)
        pending = [(noise, r, v) for noise, r, v in todo if unit_name(noise, r, v) not in done]
        with_bound = not run.file("bound.json").exists()
        bound: dict[str, dict[str, list[float]]] = {}
        for noise in dict.fromkeys(noise for noise, _, _ in pending + (todo if with_bound else [])):
            for variant, s in spec.datasets[noise].items():  # built (or found) once, before training
                data, _ = load_or_build(s, executor, on_event)
                if with_bound and s.noise is not None:
                    bound.setdefault(noise, {})[variant] = bayes_bound(data, s, protocol, executor, on_event)
                del data  # one dataset in memory at a time
        if with_bound:
            run.write_json("bound.json", bound)
        on_event(Event("stage", stage="runs", total=len(todo), message=f"{len(todo)} training runs"))
        finished = len(todo) - len(pending)
        on_event(Event("advance", stage="runs", done=finished, total=len(todo)))

        def record_done(_: int, record: dict) -> None:
            nonlocal finished
            run.append(record)
            finished += 1
            on_event(
                Event(
                    "log",
                    message=f"{record['unit']}: test accuracy {record['accuracy']:.1f} %, fault-as-healthy "
                    f"{record['fault_as_healthy']:.1f} % (epoch {record['best_epoch']}, "
                    f"{record['train_seconds']:.0f} s)",
                )
            )
            on_event(Event("record", stage="runs", record=record))
            on_event(Event("advance", stage="runs", done=finished, total=len(todo)))

        # the datasets by cache entry path: a worker process may not share this one's environment
        tasks, twins = [], set()
        for noise, r, variant in pending:
            dataset = spec.datasets[noise][variant]
            twin = dataset.with_(noise=None) if protocol.start == "clean" else None
            if twin is not None and twin not in twins:  # the clean start's shapes: built (or found) once, here
                load_or_build(twin, executor, on_event)
                twins.add(twin)
            twin_path = cache.entry_path(twin) if twin is not None else None
            tasks.append((protocol, dataset, cache.entry_path(dataset), twin, twin_path, noise, r, variant, run.path))
        executor.map(train_unit, tasks, on_done=record_done, gpu=protocol.device != "cpu")
        summarise(scenario, run)


def bayes_bound(data, spec: DatasetSpec, protocol: NoiseProtocol, executor=None, on_event=lambda e: None) -> list:
    """The accuracy (%) on each run's test part of the Bayes classifier with the true shapes
    (gearlab.learn.bounds.class_bound): the most any network can reach on *data*. Needs the
    dataset's noise-free twin (built, or found in the cache). A stage of its own: the twin, torch,
    then each class and block of rows (a Student-t set takes minutes; it was one log line: issue 41)."""
    label = np.asarray(data.label, dtype=np.int64)
    stage, steps = f"bound {spec.name}", 2 + class_bound_steps(label)

    def step(done: int) -> None:
        on_event(Event("advance", stage=stage, done=done, total=steps))

    on_event(Event("stage", stage=stage, total=steps, message=f"Bayes bound of {spec.name}"))
    on_event(Event("log", message=f"the Bayes bound of {spec.name}: its noise-free twin and the class likelihoods"))
    clean, _ = load_or_build(spec.with_(noise=None), executor, on_event)
    step(1)
    with standing(on_event, stage, "loading torch for the class likelihoods"):
        import torch  # noqa: F401 (class_bound would load it within its first step)
    step(2)
    pred = class_bound(data.X, clean.X, label, noise_law(spec), on_step=lambda done: step(2 + done))
    tests = [split(label, protocol, r).test for r in range(protocol.runs)]
    return [100.0 * float((pred[t] == label[t]).mean()) for t in tests]


def train_unit(task: tuple) -> dict:
    """One training run, in this process or a worker, on one torch thread (as the transfer
    kind's units: a result does not depend on how many run side by side). It says what it does
    from its start: torch and the dataset take seconds in a fresh worker (issue 41)."""
    protocol, dataset_spec_, path, twin, twin_path, noise, r, variant, run_path = task
    unit = unit_name(noise, r, variant)
    with UnitProgress(run_path, unit) as progress:
        progress("starting: importing torch")
        # torch loads here, not at the top (checking a scenario loads none); the caller's thread count back after
        with one_thread():

            def report(epoch: int, history) -> None:
                progress(f"epoch {epoch + 1}, validation accuracy {100 * history.val_acc[-1]:.1f} %")

            progress("starting: reading the dataset")
            data = cache.load(dataset_spec_, path)
            clean = cache.load(twin, twin_path) if twin is not None else None
            progress("starting: training")
            result = run_unit(protocol, data, r, on_epoch=report, twin=clean)
    return {"unit": unit, "noise": noise, "variant": variant, **result}


def results(records: list[dict]) -> dict:
    """{noise: {variant: aggregate over runs}}, plus the paired TSA - noisy accuracy gain."""
    out: dict[str, dict] = {}
    for noise in dict.fromkeys(r["noise"] for r in records):
        mine = [r for r in records if r["noise"] == noise]
        out[noise] = {
            v: aggregate([r for r in mine if r["variant"] == v])
            for v in VARIANTS
            if any(r["variant"] == v for r in mine)
        }
        acc = {v: {r["run"]: r["accuracy"] for r in mine if r["variant"] == v} for v in VARIANTS}
        paired = [acc["tsa"][k] - acc["noisy"][k] for k in sorted(set(acc["tsa"]) & set(acc["noisy"]))]
        if paired:
            out[noise]["tsa_gain"] = {
                "mean": float(np.mean(paired)),
                "std": float(np.std(paired, ddof=1)) if len(paired) > 1 else 0.0,
                "n": len(paired),
            }
    return out


def _cell(stats: dict | None, key: str) -> str:
    return _mean_text((stats or {}).get(key))


def _mean_text(c: dict | None) -> str:
    return f"{c['mean']:.1f} ± {c['std']:.1f}" if c and c.get("mean") is not None else ""


def bound_cells(bound: dict | None, runs: int) -> dict:
    """{noise: {variant: mean ± std}} of the bound over the first *runs* runs (those trained)."""
    return {
        noise: {v: mean_std(acc[:runs]) for v, acc in variants.items()} for noise, variants in (bound or {}).items()
    }


def table_md(res: dict, bound: dict | None = None) -> str:
    """Noise type x noisy/TSA; with *bound* (bound_cells) the Bayes bound beside each accuracy."""
    extra = " noisy bound (%) | TSA bound (%) |" if bound else ""
    lines = [
        "| noise | noisy accuracy (%) | TSA accuracy (%) | TSA gain (points) | noisy fault-as-healthy (%) "
        "| TSA fault-as-healthy (%) | runs |" + extra,
        "|---|---|---|---|---|---|---|" + ("---|---|" if bound else ""),
    ]
    for noise, r in res.items():
        gain = r.get("tsa_gain")
        gain_text = f"{gain['mean']:+.1f} ± {gain['std']:.1f}" if gain else ""
        runs = "/".join(str(r[v]["runs"]) for v in VARIANTS if v in r)
        b = (bound or {}).get(noise, {})
        bound_text = "".join(f" {_mean_text(b.get(v))} |" for v in VARIANTS) if bound else ""
        lines.append(
            f"| {noise} | {_cell(r.get('noisy'), 'accuracy')} | {_cell(r.get('tsa'), 'accuracy')} | "
            f"{gain_text} | "
            f"{_cell(r.get('noisy'), 'fault_as_healthy')} | {_cell(r.get('tsa'), 'fault_as_healthy')} | {runs} |"
            + bound_text
        )
    return "\n".join(lines) + "\n"


def table_csv(res: dict, bound: dict | None = None) -> str:
    columns = [f"{v}_{m}_{s}" for v in VARIANTS for m in ("accuracy", "fault_as_healthy") for s in ("mean", "std")]
    columns += [f"{v}_bound_{s}" for v in VARIANTS for s in ("mean", "std")] if bound else []
    rows = [
        "noise," + ",".join(columns[:8]) + ",tsa_gain_mean,tsa_gain_std,runs" + "".join("," + c for c in columns[8:])
    ]
    for noise, r in res.items():
        cells = []
        for v in VARIANTS:
            for m in ("accuracy", "fault_as_healthy"):
                c = r.get(v, {}).get(m) or {}
                cells += [_number(c.get(s)) for s in ("mean", "std")]
        gain = r.get("tsa_gain") or {}
        cells += [_number(gain.get(s)) for s in ("mean", "std")]
        cells.append(str(min(r[v]["runs"] for v in VARIANTS if v in r)))
        if bound:
            cells += [_number((bound.get(noise, {}).get(v) or {}).get(s)) for v in VARIANTS for s in ("mean", "std")]
        rows.append(f"{noise}," + ",".join(cells))
    return "\n".join(rows) + "\n"


def _number(x: float | None) -> str:
    return f"{x:.4f}" if x is not None else ""


# report.html's captions of the figures drawn below: {file stem: (the thesis figure it repeats or "", what it shows)}
CAPTIONS = {
    "accuracy_vs_intensity": (
        "Figure 4.4",
        "Test accuracy (%) per fault type against the intensity step (1-20), all faults (black) and faults "
        "predicted healthy (green, dashed); mean ± std over runs; noisy left, TSA right.",
    ),
    "accuracy_vs_rfa": (
        "Figure 4.5",
        "Test accuracy (%) per fault type against relative fault area (%, up to 50 %); mean ± std over runs.",
    ),
    "confusion": (
        "Figure 4.6",
        "Confusion matrices compiled over all runs (counts; shading: share of the true class).",
    ),
}


def summarise(scenario: Scenario, run: RunDir) -> None:
    spec = scenario.spec
    records = run.records()
    res = results(records)
    bound_path = run.file("bound.json")
    bound = bound_cells(run.read_json("bound.json"), spec.protocol.runs) if bound_path.exists() else None
    summary = {
        "kind": "noise_study",
        "scenario": scenario.name,
        "protocol": asdict(spec.protocol),
        "datasets": {
            noise: {v: {"name": s.name, "key": s.key(), "spec": asdict(s)} for v, s in variants.items()}
            for noise, variants in spec.datasets.items()
        },
        "results": res,
        "bound": bound,
        "units": len(records),
    }
    run.write_json("summary.json", summary)
    run.write_text("table.md", table_md(res, bound))
    run.write_text("table.csv", table_csv(res, bound))
    report_begins()  # the run's 'report' stage, before matplotlib loads (seconds)
    from .noise_study_figures import draw  # here, not at the top: start-up time (matplotlib)

    draw(run.figures, res)


def summary_lines(run: RunDir) -> list[str]:
    summary = run.read_json("summary.json")
    return [
        "test accuracy and fault-as-healthy rate [%], mean ± std over runs (thesis 4.3):",
        table_md(summary["results"], summary.get("bound")).rstrip(),
    ]


def records_table(scenario: Scenario, records: list[dict]) -> str:
    return table_md(results(records))


def charts(scenario: Scenario, run: RunDir) -> list[Chart]:
    """Per noise type and variant: accuracy against intensity step, all faults pooled (Figure 4.4's black curve)."""
    out = []
    for noise, variants in results(run.records()).items():
        curves = []
        for variant in VARIANTS:
            c = variants.get(variant, {}).get("curves", {}).get("all")
            if c:
                curves.append(Curve(variant, c["steps"], c["accuracy_mean"], c["accuracy_std"]))
        out.append(
            Chart(f"{noise} noise: fault accuracy against intensity", "intensity step", "accuracy (%)", tuple(curves))
        )
    return out


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """Per noise, what the TSA changes: accuracy, faults called healthy, beside the Bayes bound
    (report.html opens with it)."""
    lines = []
    for noise, res in (summary.get("results") or {}).items():
        noisy, tsa, gain = res.get("noisy"), res.get("tsa"), res.get("tsa_gain")
        if not noisy or not tsa:
            continue
        bound = (summary.get("bound") or {}).get(noise) or {}
        limits = [f"{bound[v]['mean']:.1f} %" for v in VARIANTS if bound.get(v)]
        lines.append(
            f"{noise} noise: test accuracy {noisy['accuracy']['mean']:.1f} % on the noisy signals, "
            f"{tsa['accuracy']['mean']:.1f} % after the TSA"
            + (f" ({gain['mean']:+.1f} points over {gain['n']} runs)" if gain else "")
            + f"; faults called healthy {noisy['fault_as_healthy']['mean']:.1f} -> "
            f"{tsa['fault_as_healthy']['mean']:.1f} %"
            + (f"; Bayes bound {' -> '.join(limits)}" if limits else "")
            + "."
        )
    return lines


verdict_table, compare_table = no_table, no_compare  # the summary lines say the rest
table_title = no_title


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    return CAPTIONS
