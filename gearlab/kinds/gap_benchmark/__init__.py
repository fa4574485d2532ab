"""Scenario kind `gap_benchmark`: the blind benchmark of the gap diagnosis (`gearlab gap benchmark`).

    [benchmark]   trials, seed, library (effect names; [] = every registered effect),
                  target_revolutions (healthy revolutions written per target), kinds (the trial
                  kinds to run, of those drawn; [] = all)
    [source]      the simulator configuration, a dataset preset with overrides as in [[datasets]]
                  (default B-6-ch5; only its healthy revolutions are used; without a `noise` table
                  it gets the base sensor noise, Gaussian 30 dB, in source and target alike)
    [search]      the diagnosis's settings: budget, max_effects, healthy, bootstrap, permutations, alpha

One unit = one trial (gearlab.kinds.gap_benchmark.trials.trial_task): draw -> simulate -> write target.npz ->
diagnose from the file -> score. Output: results.jsonl (one record per trial), targets/trial_NNN/
(target.npz, answers.json, diagnosis.json), summary.json (trials, top1, top3, median_shrink,
median_param_error, null_correct, out_of_library_unexplained, per_effect, ...), table.md, a figure
and report.html. docs/gap_benchmark.md explains the mix, the ranges and the scoring.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, replace

import numpy as np

from ...charts import Chart, Curve
from ...data.spec import DatasetSpec
from ...effects import default_candidates
from ...errors import GearlabInputError, did_you_mean
from ...events import Event
from ...gap.diagnose import Settings
from ...registry import get_registry
from ...runs import RunDir
from ...scenario import Scenario, Table, keys_of, location
from ...settings import setting, shrunk, typed
from ..common import (
    FITS,
    NOISE_MOVED,
    SOURCE_KEYS,
    SourceEntry,
    dataset_spec,
    executor_for,
    no_compare,
    no_table,
    no_title,
)
from . import trials as bench

MAX_TRIALS = 10000
MAX_SEED = 2**32 - 1


def _kinds(value, where: str) -> list:
    known = bench.KINDS + bench.EXTRA_KINDS
    for kind in value:
        if kind not in known:
            hint = did_you_mean(kind, known) if isinstance(kind, str) else ""
            raise GearlabInputError(f"{where}: {kind!r} is not a trial kind ({', '.join(known)}){hint}")
    return value


@dataclass(frozen=True, kw_only=True)
class Benchmark:
    """[benchmark]"""

    trials: int = setting(int, 40, low=1, high=MAX_TRIALS, doc="number of trials (>= 40 for the acceptance numbers)")
    seed: int = setting(int, 0, low=0, high=MAX_SEED, doc="seeds the trials' draws and the diagnosis")
    library: list = setting(
        list, [], doc="candidate effects (registered names); [] = every registered effect but the opt-in ones"
    )
    target_revolutions: int = setting(
        int, 80, low=bench.MIN_TARGET_REVOLUTIONS, high=100000, doc="healthy revolutions in each written target"
    )
    kinds: list = setting(
        list,
        [],
        check=_kinds,
        doc="trial kinds to run (single, pair, null, withheld, suborder); [] = the first four. The trials "
        'are drawn as for those, then only the named ones run (kinds = ["withheld"] with trials = 50: '
        "10 out-of-library trials, the same ones a full run of 50 holds); 'suborder' adds `trials` "
        "trials of an interfering tone below one shaft order or between the first orders",
    )


SEARCH = ("budget", "max_effects", "healthy", "bootstrap", "permutations", "alpha")
TABLES = {
    "benchmark": Table(keys_of(Benchmark)),
    "source": Table(SOURCE_KEYS, moved=NOISE_MOVED),
    # the diagnosis's own settings, declared once on gearlab.gap.scoring.Settings
    "search": Table(keys_of(Settings, SEARCH)),
}
OVERRIDES: tuple[str, ...] = ("trials", "seed")  # [benchmark] keys that `gearlab gap FILE` and the TUI may set


@dataclass(frozen=True)
class Spec:
    """What build() checked: the source, the effect library, the drawn trials, the diagnosis's settings
    ([search] and the [benchmark] seed; the candidates are each trial's) and the target revolutions."""

    source: DatasetSpec
    library: tuple[str, ...]
    trials: list
    settings: Settings
    revolutions: int


def search_values(settings: Settings) -> dict:
    """The [search] keys and the seed of *settings*: the plain dict each trial task takes (picklable, the
    trial adds its candidates) and summary.json shows."""
    return {name: getattr(settings, name) for name in (*SEARCH, "seed")}


def build(scenario: Scenario) -> Spec:
    """Everything checked before any simulation: the library's names, the source, the trial draw."""
    t = scenario.tables
    path = scenario.path
    registry = get_registry()
    b = typed(Benchmark, t["benchmark"])
    where = location(path, "benchmark", "library")
    library = b.library or default_candidates(registry)
    if not all(isinstance(n, str) for n in library):
        raise GearlabInputError(f"{where}: expected a list of effect names, got {library!r}")
    for name in library:
        registry.get("effect", name, where)  # unknown names: "did you mean" and the known list
    if len(set(library)) != len(library):
        raise GearlabInputError(f"{where}: names an effect twice")
    if len(library) < 2:
        raise GearlabInputError(f"{where}: needs at least 2 effects (pairs and withheld trials), got {len(library)}")
    entry = asdict(typed(SourceEntry, t["source"]))
    source = dataset_spec(entry, location(path, "source"), path.parent)
    noise = source.noise if "effects" in scenario.raw.get("source", {}) else bench.BASE_NOISE  # its own, or none
    source = source.with_(faults=(), healthy=t["search"]["healthy"], noise=noise)
    source.check(location(path, "source"))
    library = tuple(library)
    trials = bench.draw_trials(b.trials, b.seed, library, source)
    if b.kinds:
        trials = [trial for trial in trials if trial.kind in b.kinds]
        if "suborder" in b.kinds:
            first = max((t.index for t in trials), default=-1) + 1
            trials += bench.draw_suborder_trials(b.trials, b.seed, library, source, first)
        if not trials:
            raise GearlabInputError(
                f"{location(path, 'benchmark', 'kinds')}: no trial of {b.kinds} among {b.trials} trials; "
                "expected more trials"
            )
    settings = replace(typed(Settings, t["search"]), seed=b.seed)
    return Spec(source, library, trials, settings, b.target_revolutions)


def describe(scenario: Scenario) -> str:
    spec = scenario.spec
    counts = {k: sum(t.kind == k for t in spec.trials) for k in bench.KINDS + bench.EXTRA_KINDS}
    mix = ", ".join(f"{c} {k}" for k, c in counts.items() if c)
    return (
        f"{len(spec.trials)} blind trials ({mix}) on {spec.source.name} ({spec.source.model}), "
        f"{len(spec.library)} candidate effects, budget {spec.settings.budget} per fit"
    )


def quick(scenario: Scenario) -> None:
    """Smoke run: 4 trials (one of each kind), small searches and statistics: a few minutes on 2 cores."""
    spec = scenario.spec
    n = min(len(spec.trials), 4)
    settings = shrunk(spec.settings)  # the --quick limits declared on Settings
    scenario.spec = replace(
        spec,
        trials=bench.draw_trials(n, settings.seed, spec.library, spec.source),
        settings=settings,
        source=replace(spec.source, healthy=settings.healthy),
        revolutions=min(spec.revolutions, 40),
    )


def unit_modules(scenario: Scenario) -> tuple[str, ...]:
    return (*FITS, __name__ + ".trials")  # a trial is a diagnosis


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    started = time.perf_counter()
    spec = scenario.spec
    with executor_for(scenario) as executor:
        trials = spec.trials
        done = {r["unit"] for r in run.records()}
        pending = [t for t in trials if bench.unit_key(t.index) not in done]
        total = len(trials)
        finished = total - len(pending)
        on_event(Event("stage", stage="trials", total=total, message=f"{total} blind trials"))
        on_event(Event("advance", stage="trials", done=finished, total=total))

        def record_done(_: int, record: dict) -> None:
            nonlocal finished
            run.append(record)
            finished += 1
            on_event(Event("log", message=f"{record['unit']} ({record['kind']}): {_verdict(record)}{_cost(record)}"))
            on_event(Event("record", stage="trials", record=record))
            on_event(Event("advance", stage="trials", done=finished, total=total))

        tasks = [
            bench.TrialTask(
                t,
                spec.source,
                search_values(spec.settings),
                run.file("targets", f"trial_{t.index:03d}"),
                spec.revolutions,
            )
            for t in pending
        ]
        executor.map(bench.trial_task, tasks, on_done=record_done)
        summarise(scenario, run, elapsed=time.perf_counter() - started)


def _cost(r: dict) -> str:
    """'; 1094 score evaluations, 99 s': what a trial cost, its diagnosis's score evaluations and the
    trial's time (a record from before the count says its time alone)."""
    n = r.get("evaluations")
    return f"; {'' if n is None else f'{n} score evaluations, '}{r.get('seconds', 0):.0f} s"


def _verdict(r: dict) -> str:
    if r["kind"] == "null":
        return "no significant gap (correct)" if r["null_correct"] else f"named {r['accepted'] or 'a gap'} (wrong)"
    if r["kind"] == "withheld":
        return f"withheld {r['withheld']}: " + (
            "unexplained (correct)"
            if r["out_of_library_unexplained"]
            else f"{r.get('verdict') or 'explained'}, named {r['accepted']} (wrong)"
        )
    hidden = "+".join(h[0] for h in r["hidden"])
    shrink = f", gap shrinks {100 * r['shrink']:.0f} %" if r["shrink"] is not None else ""
    verdict = f", {r['verdict']}" if r.get("verdict") else ""
    if r.get("too_weak"):
        top = f"too weak to be seen (oracle {_pct(r['oracle_seen'])}): no gap is the right answer"
    else:
        top = f"top-1 {'hit' if r['top1'] else 'miss'}"
        if r.get("below_noise_width"):
            top += " (a gap seen, within the noise width: below what the diagnosis attributes)"
    return f"hidden {hidden}, named {r['accepted'] or 'nothing'}: {top}{shrink}{verdict}"


def summarise(scenario: Scenario, run: RunDir, elapsed: float | None = None) -> None:
    spec = scenario.spec
    records = sorted(run.records(), key=lambda r: r["index"])
    summary = {
        "kind": "gap_benchmark",
        "scenario": scenario.name,
        "source": asdict(spec.source),
        "library": list(spec.library),
        "settings": search_values(spec.settings),
        "mix": dict(bench.MIX),
        "target_revolutions": spec.revolutions,
        **bench.summarise(records, spec.library),
    }
    summary["trial_seconds"] = float(sum(r.get("seconds", 0.0) for r in records))  # summed over trials (all workers)
    add_evaluations(summary, records)
    summary["elapsed_seconds"] = elapsed  # wall time of this session of the run (a resumed run: since resuming)
    run.write_json("summary.json", summary)
    run.write_text("table.md", table_md(summary))
    from ..gap_benchmark_figures import draw  # here, not at the top: start-up time (matplotlib)

    draw(run.figures, summary, records)


def _pct(v) -> str:
    return "" if v is None else f"{100 * v:.0f} %"


def _null_trials(summary: dict) -> str:
    """'75 % (by format: csv 100 %, wav 50 %)', or 'none run' (it read ' (by format: )': issue 41)."""
    if summary.get("null_correct") is None:
        return "none run"
    formats = ", ".join(f"{k} {_pct(v)}" for k, v in (summary.get("null_correct_by_format") or {}).items())
    return _pct(summary["null_correct"]) + (f" (by format: {formats})" if formats else "")


def _num(v, fmt=".2f") -> str:
    return "" if v is None else format(v, fmt)


def add_evaluations(summary: dict, records: list[dict]) -> dict:
    """The trials' diagnoses' score evaluations: summary['evaluations'] {total, trials, median} and each
    effect's median over the trials it was hidden in (older records, without the count: left out)."""
    counts = [r["evaluations"] for r in records if r.get("evaluations") is not None]
    summary["evaluations"] = {"total": sum(counts), "trials": len(counts), "median": bench._median(counts)}
    for name, e in summary["per_effect"].items():
        e["median_evaluations"] = bench._median(
            r["evaluations"]
            for r in records
            if r["kind"] in bench.EFFECT_KINDS
            and r.get("evaluations") is not None
            and any(h[0] == name for h in r["hidden"])
        )
    return summary


def table_md(summary: dict) -> str:
    """Per effect: trials it was hidden in, top-1/top-3, shrink, parameter error, withheld behaviour;
    then the overall line."""
    lines = [
        "| effect | trials | top-1 | top-3 | median shrink | median param error | ... on determined ones "
        "| not identifiable | withheld | unexplained when withheld | named wrongly | median evaluations |",
        "|---|" + "---|" * 11,
    ]
    for name, e in summary["per_effect"].items():
        lines.append(
            f"| {name} | {e['trials']} | {_pct(e['top1'])} | {_pct(e['top3'])} | {_pct(e['median_shrink'])} "
            f"| {_num(e['median_param_error'])} | {_num(e.get('median_param_error_determined'))} "
            f"| {e.get('not_identifiable', '')} | {e['withheld']} | {_pct(e['unexplained_when_withheld'])} "
            f"| {e['named_wrongly']} | {_num(e.get('median_evaluations'), '.0f')} |"
        )
    lines.append(
        f"| **all** ({summary['trials']} trials) | {sum(summary['by_kind'].get(k, 0) for k in bench.EFFECT_KINDS)} "
        f"| {_pct(summary['top1'])} | {_pct(summary['top3'])} | {_pct(summary['median_shrink'])} | "
        f"{_num(summary['median_param_error'])} | {_num(summary.get('median_param_error_determined'))} | "
        f"| {summary['by_kind']['withheld']} | {_pct(summary['out_of_library_unexplained'])} | "
        f"| {_num((summary.get('evaluations') or {}).get('median'), '.0f')} |"
    )
    lines += [
        "",
        f"null trials with no significant gap: {_null_trials(summary)}; "
        f"right effect first and explained (or partly, with >= 50 % of the gap): "
        f"{_pct(summary.get('explained_or_partly_when_identified'))}",
        "",
        f"right answer on effect trials (the right effect first, or no gap on the "
        f"{summary.get('too_weak', 0)} targets too weak to show one): {_pct(summary.get('right_answer'))}; "
        f"of the misses, {summary.get('below_noise_width', 0)} with a gap seen but within the noise width "
        "(nothing named: below what the diagnosis attributes)",
    ]
    return "\n".join(lines) + "\n"


# report.html's captions of the figures (kinds.gap_benchmark_figures): {file stem: (the thesis figure
# it repeats or "", what it shows)}
CAPTIONS = {
    "gap_benchmark": (
        "",
        "The blind benchmark: gap before and after per trial, and how often each hidden effect is named first.",
    )
}


def summary_lines(run: RunDir) -> list[str]:
    s = run.read_json("summary.json")
    met = s["met"]
    mark = {True: "ok", False: "below target"}
    return [
        table_md(s).rstrip(),
        f"{s['trials']} trials ({', '.join(f'{c} {k}' for k, c in s['by_kind'].items())})",
        f"top-1 {_pct(s['top1'])} ({mark[met['top1']]}, target 85 %), top-3 {_pct(s['top3'])}; right answer "
        f"{_pct(s.get('right_answer'))} (the right effect first, or no gap on the {s.get('too_weak', 0)} "
        "too weak to show one)",
        f"median gap shrink when identified {_pct(s['median_shrink'])} ({mark[met['median_shrink']]}, target 70 %); "
        f"median parameter error {_num(s['median_param_error'])}",
        f"null: no significant gap {_pct(s['null_correct'])} ({mark[met['null_correct']]}, target 90 %)",
        f"out of library: unexplained {_pct(s['out_of_library_unexplained'])} "
        f"({mark[met['out_of_library_unexplained']]}, target 80 %)",
        f"when the right effect was named first: explained {_pct(s.get('explained_when_identified'))}, "
        f"further effects the target lacks named too {_pct(s.get('extra_names_when_identified'))}",
    ] + evaluations_lines(s.get("evaluations"))


def evaluations_lines(counts: dict | None) -> list[str]:
    """What the trials' diagnoses cost in score evaluations (none from a summary before the count)."""
    if not counts or not counts["trials"]:
        return []
    return [
        f"score evaluations of the diagnoses: {counts['total']} over {counts['trials']} trials "
        f"(median {counts['median']:.0f} a trial)"
    ]


def records_table(scenario: Scenario, records: list[dict]) -> str:
    """The per-effect table of the trials finished so far (the TUI fills it as trials finish)."""
    records = sorted(records, key=lambda r: r["index"])
    return table_md(add_evaluations(bench.summarise(records, scenario.spec.library), records))


def charts(scenario: Scenario, run: RunDir) -> list[Chart]:
    """Gap before and after, trial by trial; top-1 per effect (x = the effect's place in the library)."""
    records = sorted(run.records(), key=lambda r: r["index"])
    if not records:
        return [Chart("gap benchmark", "", "", (), notes=("no trial finished yet",))]
    idx = [r["index"] for r in records]
    gap = Chart(
        "gap before / after per trial (log10)",
        "trial",
        "log10 gap",
        (
            Curve("before", idx, [float(np.log10(max(r["gap_before"], 1e-6))) for r in records]),
            Curve("after", idx, [float(np.log10(max(r["gap_after"], 1e-6))) for r in records]),
        ),
    )
    summary = bench.summarise(records, scenario.spec.library)
    names = list(summary["per_effect"])
    per = Chart(
        "top-1 per hidden effect",
        "effect",
        "top-1 (%)",
        (Curve("top-1", list(range(len(names))), [100 * (summary["per_effect"][n]["top1"] or 0) for n in names]),),
        categories=names,
    )
    return [gap, per]


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """The benchmark's four measures against their targets (report.html opens with it)."""
    s, said = summary, []
    for key, what in (
        ("top1", "named the hidden effect first"),
        ("median_shrink", "shrank the gap (median, when identified) by"),
        ("null_correct", "saw no gap in the null targets"),
        ("out_of_library_unexplained", "left unexplained the out-of-library targets"),
    ):
        if s.get(key) is not None:
            met = "met" if s["met"][key] else "below"
            said.append(f"{what} {_pct(s[key])} (target {_pct(s['targets'][key])}: {met})")
    if not said:
        said.append("measured nothing against its targets (no trial of a kind that is scored)")
    weak = f" ({s['too_weak']} too weak to show a gap)" if s.get("too_weak") else ""
    return [f"On {s['trials']} blind trials{weak}, the diagnosis " + "; ".join(said) + "."]


verdict_table, compare_table = no_table, no_compare  # the summary lines say the rest
table_title = no_title


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    return CAPTIONS
