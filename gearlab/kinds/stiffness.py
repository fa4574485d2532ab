"""Scenario kind `stiffness`: TVMS of a gear pair for fault ladders and explicit cases.

The verification scenario (scenarios/stiffness_verification.toml) sweeps all four faults
over their 20 steps on tooth 5 of the luo2019 pair: Figures 2.32 and 2.33 of the thesis.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from ..charts import Chart, Curve
from ..confined import read_file
from ..errors import GearlabInputError
from ..events import Event, figures_ahead, report_begins
from ..physics.faults import LADDER_STEPS, place_fault
from ..physics.presets import PAIR_PRESETS, gear_pair
from ..physics.stiffness import MeshStiffnessModel, PlacedFault, StiffnessOptions, table_gear, table_slots
from ..registry import get_registry
from ..runs import RunDir
from ..scenario import Scenario, Table, keys_of, location, plain_name
from ..settings import setting, typed
from .common import no_compare, no_table, no_title, no_unit_modules


@dataclass(frozen=True, kw_only=True)
class Pair:
    """[stiffness]"""

    pair: str = setting(str, choices=PAIR_PRESETS, doc="gear-pair preset")
    points: int = setting(int, 4096, low=64, high=1 << 20, doc="samples over one pinion revolution")
    fillet: bool = setting(bool, True, doc="include the fillet-foundation term")
    root_region: bool = setting(bool, True, doc="include the straight root region d_1")


@dataclass(frozen=True, kw_only=True)
class Sweep:
    """[sweep]"""

    faults: list = setting(list, [], doc="fault plugin names to sweep over their ladders")
    tooth: int = setting(int, 5, low=1, doc="pinion tooth carrying the fault")
    steps: list = setting(list, [1, LADDER_STEPS], doc="first and last ladder step, inclusive")


@dataclass(frozen=True, kw_only=True)
class CaseEntry:
    """[[cases]]"""

    name: str = setting(str, check=plain_name, doc="case name (file name of its CSV)")
    faults: list = setting(list, [], doc="list of {kind, tooth, step} or {kind, tooth, params}")


TABLES = {
    "stiffness": Table(keys_of(Pair), required=True),
    "sweep": Table(keys_of(Sweep)),
    "cases": Table(keys_of(CaseEntry), array=True),
}
OVERRIDES: tuple[str, ...] = ()  # no key is set from the command line


@dataclass(frozen=True)
class Case:
    name: str
    faults: tuple[PlacedFault, ...]
    fault: str = ""  # sweep cases: the fault type and its step
    step: int = 0


@dataclass
class Spec:
    pair: object
    options: StiffnessOptions
    points: int
    cases: list[Case]
    sweep_faults: list[str]
    tooth: int


def build(scenario: Scenario) -> Spec:
    t = scenario.tables
    registry = get_registry()
    st, sweep = typed(Pair, t["stiffness"]), typed(Sweep, t["sweep"])
    pair = gear_pair(st.pair)
    where = scenario.where("sweep", "steps")
    steps = sweep.steps
    if len(steps) != 2 or not all(isinstance(s, int) and not isinstance(s, bool) for s in steps):
        raise GearlabInputError(f"{where}: expected [first, last] whole numbers, got {steps!r}")
    if not 1 <= steps[0] <= steps[1] <= LADDER_STEPS:
        raise GearlabInputError(f"{where}: expected 1 <= first <= last <= {LADDER_STEPS}, got {steps!r}")
    if not 1 <= sweep.tooth <= pair.Z1:
        raise GearlabInputError(
            f"{scenario.where('sweep', 'tooth')}: tooth must lie in 1..{pair.Z1}, got {sweep.tooth}"
        )
    cases = [Case("healthy", ())]
    for i, name in enumerate(sweep.faults):
        here = f"{scenario.where('sweep', 'faults')} item {i + 1}"
        if not isinstance(name, str):
            raise GearlabInputError(f"{here}: expected a fault name, got {name!r}")
        for step in range(steps[0], steps[1] + 1):
            placed = place_fault(registry, pair, name, sweep.tooth, step=step, where=here)
            cases.append(Case(f"{name}_step{step:02d}", (placed,), name, step))
    for i, case in enumerate(typed(CaseEntry, c) for c in t["cases"]):
        placed = []
        for j, f in enumerate(case.faults):
            here = f"{location(scenario.path, 'cases', 'faults', i)} item {j + 1}"
            if not isinstance(f, dict) or "kind" not in f or "tooth" not in f:
                raise GearlabInputError(
                    f"{here}: expected a table {{kind = ..., tooth = ..., step = ...}} or with params"
                )
            unknown = set(f) - {"kind", "tooth", "step", "params", "gear"}
            if unknown:
                raise GearlabInputError(
                    f"{here}: unknown key(s) {', '.join(sorted(unknown))}; expected kind, tooth, step, params, gear"
                )
            # the types place_fault relies on (a list as 'kind' cannot even be looked up)
            if not isinstance(f["kind"], str):
                raise GearlabInputError(f"{here} key 'kind': expected a fault name, got {f['kind']!r}")
            if isinstance(f["tooth"], bool) or not isinstance(f["tooth"], int):
                raise GearlabInputError(f"{here} key 'tooth': expected a tooth number, got {f['tooth']!r}")
            if not isinstance(f.get("params", {}), dict):
                raise GearlabInputError(f"{here} key 'params': expected a table of parameters, got {f['params']!r}")
            gear = f.get("gear", "pinion")  # pinion and wheel faults in one case: the hunting-tooth period
            placed.append(
                place_fault(registry, pair, f["kind"], f["tooth"], f.get("step"), f.get("params"), here, gear=gear)
            )
        cases.append(Case(case.name, tuple(placed)))
    names = [c.name for c in cases]
    if len(set(names)) != len(names):
        raise GearlabInputError(
            f"{scenario.path}: case names must be unique; repeated: {sorted({n for n in names if names.count(n) > 1})}"
        )
    options = StiffnessOptions(fillet=st.fillet, root_region=st.root_region)
    return Spec(pair, options, st.points, cases, list(sweep.faults), sweep.tooth)


def describe(scenario: Scenario) -> str:
    """One line for `gearlab validate` and the TUI: what the scenario will do."""
    return f"{len(scenario.spec.cases)} TVMS cases"


def quick(scenario: Scenario) -> None:
    """Smoke run: three steps of each ladder (healthy, middle, worst)."""
    spec = scenario.spec
    spec.cases = [c for c in spec.cases if not c.fault or c.step in (1, 10, LADDER_STEPS)]


def read_csv(path) -> tuple[np.ndarray, np.ndarray]:
    data = np.loadtxt(io.BytesIO(read_file(path)), delimiter=",", skiprows=1, ndmin=2)
    return data[:, 0], data[:, 1]


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    spec: Spec = scenario.spec
    model = MeshStiffnessModel(spec.pair, spec.options)
    done = {r["unit"] for r in run.records()}
    total = len(spec.cases)
    on_event(Event("stage", stage="stiffness", total=total, message=f"{total} TVMS cases on {spec.pair.name}"))
    for i, case in enumerate(spec.cases):
        if case.name not in done:
            ms = model.mesh_stiffness(case.faults, spec.points)
            run.write_text(f"cases/{case.name}.csv", ms.csv_text())
            record = {
                "unit": case.name,
                "fault": case.fault,
                "step": case.step,
                "faults": [
                    {
                        "kind": p.fault.name,
                        "tooth": p.tooth,
                        "params": p.params,
                        "rfa": p.fault.rfa(p.params, spec.pair.seen_from(p.gear)),
                        **({} if p.gear == "pinion" else {"gear": p.gear}),
                    }
                    for p in case.faults
                ],
                "rfa": max((p.fault.rfa(p.params, spec.pair.seen_from(p.gear)) for p in case.faults), default=0.0),
                "mean_N_per_m": float(ms.k.mean()),
                "min_N_per_m": float(ms.k.min()),
                "max_N_per_m": float(ms.k.max()),
            }
            run.append(record)
            on_event(Event("record", stage="stiffness", record=record))
        on_event(Event("advance", stage="stiffness", done=i + 1, total=total))
    summarise(scenario, run)


# report.html's captions of the figures drawn below: {file stem: (the thesis figure it repeats or "", what it shows)}
CAPTIONS = {
    "rfa": (
        "Figure 2.32",
        "Relative fault area (fraction of the healthy tooth) against intensity step per fault type.",
    ),
    "tvms_ladders": (
        "Figure 2.33",
        "Time-varying mesh stiffness (1e8 N/m) against pinion angle (deg) for every step of each fault ladder; "
        "colour: intensity step.",
    ),
    "tvms_cases": ("", "Time-varying mesh stiffness (1e8 N/m) against pinion angle (deg) of the scenario's cases."),
}


def summarise(scenario: Scenario, run: RunDir) -> None:
    spec: Spec = scenario.spec
    records = {r["unit"]: r for r in run.records()}
    pair = spec.pair
    sweep = _sweep(spec, records)
    healthy = records["healthy"]
    summary = {
        "kind": "stiffness",
        "scenario": scenario.name,
        "pair": pair.describe(),
        "healthy": {"mean": healthy["mean_N_per_m"], "min": healthy["min_N_per_m"], "max": healthy["max_N_per_m"]},
        "sweep": sweep,
        "cases": {
            name: {k: r[k] for k in ("mean_N_per_m", "min_N_per_m", "max_N_per_m", "rfa", "faults")}
            for name, r in records.items()
        },
    }
    run.write_json("summary.json", summary)
    run.write_text("table.md", _table_md(sweep))
    run.write_text("table.csv", _table_csv(sweep))

    report_begins()  # the run's 'report' stage, before matplotlib loads (seconds)
    from ..plots import tvms_figure  # here, not at the top: start-up time (matplotlib)
    from .stiffness_figures import ladder_grid, rfa_curves

    pitch = 360.0 / pair.Z1
    lo = (spec.tooth - 2) * pitch
    window = (lo, lo + 3 * pitch + np.degrees(pair.theta_d))
    panels = {}
    for case in spec.cases:
        if case.fault:
            theta, k = read_csv(run.file("cases", f"{case.name}.csv"))
            panels.setdefault(case.fault, []).append((case.step, theta, k))
    figures_ahead(1 + 2 * bool(panels))  # the run's 'report' stage counts i of n
    if panels:
        ladder_grid(
            panels,
            run.figures / "tvms_ladders.png",
            window,
            f"TVMS, faults on pinion tooth {spec.tooth} of {pair.name} (Figure 2.33)",
        )
        rfa_curves(
            {f: ([int(s) for s in v], [v[s]["rfa"] for s in v]) for f, v in sweep.items()}, run.figures / "rfa.png"
        )
    other = [c for c in spec.cases if not c.fault]
    curves = [(c.name, *read_csv(run.file("cases", f"{c.name}.csv"))) for c in other]
    # a wheel's or both gears' table spans more than a pinion turn: drawn against the pinion angle
    slots = [table_slots(pair, table_gear(c.faults)) for c in other]
    curves = [(n, theta if z == pair.Z1 else theta * z / pair.Z1, k) for (n, theta, k), z in zip(curves, slots)]
    over = "one pinion revolution" if set(slots) <= {pair.Z1} else f"{max(slots) / pair.Z1:g} pinion revolutions"
    tvms_figure(curves, f"TVMS over {over}, {pair.name}", run.figures / "tvms_cases.png")


def _sweep(spec: Spec, records: dict[str, dict]) -> dict[str, dict[str, dict]]:
    """{fault: {step: mean/min/max stiffness and RFA}} of the finished ladder cases."""
    sweep: dict[str, dict[str, dict]] = {}
    for case in spec.cases:
        r = records.get(case.name)
        if case.fault and r is not None:
            sweep.setdefault(case.fault, {})[str(case.step)] = {
                "mean": r["mean_N_per_m"],
                "min": r["min_N_per_m"],
                "max": r["max_N_per_m"],
                "rfa": r["rfa"],
            }
    return sweep


def _table_md(sweep) -> str:
    if not sweep:
        return ""
    faults = list(sweep)
    steps = sorted({int(s) for v in sweep.values() for s in v})
    lines = [
        "| step | " + " | ".join(f"{f} mean (1e8 N/m) | {f} RFA" for f in faults) + " |",
        "|---|" + "---|---|" * len(faults),
    ]
    for s in steps:
        cells = []
        for f in faults:
            r = sweep[f].get(str(s))
            cells += [f"{r['mean'] / 1e8:.4f}", f"{r['rfa']:.3f}"] if r else ["", ""]
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _table_csv(sweep) -> str:
    rows = ["fault,step,mean_N_per_m,min_N_per_m,max_N_per_m,rfa"]
    for f, steps in sweep.items():
        for s, r in sorted(steps.items(), key=lambda kv: int(kv[0])):
            rows.append(f"{f},{s},{r['mean']:.10g},{r['min']:.10g},{r['max']:.10g},{r['rfa']:.6g}")
    return "\n".join(rows) + "\n"


def summary_lines(run: RunDir) -> list[str]:
    summary = run.read_json("summary.json")
    h = summary["healthy"]
    lines = [f"healthy TVMS: mean {h['mean']:.4g} N/m, min {h['min']:.4g}, max {h['max']:.4g}"]
    for fault, steps in summary["sweep"].items():
        last = steps[max(steps, key=int)]
        lines.append(f"{fault}: worst step mean {last['mean']:.4g} N/m, min {last['min']:.4g}, RFA {last['rfa']:.3f}")
    return lines


def records_table(scenario: Scenario, records: list[dict]) -> str:
    return _table_md(_sweep(scenario.spec, {r["unit"]: r for r in records}))


def charts(scenario: Scenario, run: RunDir) -> list[Chart]:
    """TVMS over one pinion revolution: the healthy case, each fault's worst finished step and
    the named cases; and the RFA of each ladder."""
    spec: Spec = scenario.spec
    done = {r["unit"]: r for r in run.records()}
    worst = {}
    for case in spec.cases:  # ladder order: the last finished step of each fault wins
        if case.fault and case.name in done:
            worst[case.fault] = case
    shown = [c for c in spec.cases if not c.fault] + list(worst.values())
    curves = []
    for case in shown:
        path = run.file("cases", f"{case.name}.csv")
        if case.name in done and path.is_file():
            theta, k = read_csv(path)
            curves.append(Curve(case.name, np.degrees(theta), k / 1e8))
    out = [Chart(f"TVMS of {spec.pair.name}", "pinion angle (deg)", "k (1e8 N/m)", tuple(curves))]
    sweep = _sweep(spec, done)
    if sweep:
        rfa = tuple(Curve(f, [int(s) for s in steps], [v["rfa"] for v in steps.values()]) for f, steps in sweep.items())
        out.append(Chart("relative fault area of each ladder (eq. 2.113)", "intensity step", "RFA", rfa))
    return out


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """The healthy TVMS, and how far each fault's largest step lowers its mean (report.html opens with it)."""
    h = summary.get("healthy")
    if not h:
        return []
    name = (summary.get("pair") or {}).get("name", "the pair")
    lines = [
        f"Healthy TVMS of {name}: mean {h['mean']:.4g} N/m, from {h['min']:.4g} to {h['max']:.4g} N/m over a "
        "pinion revolution."
    ]
    falls = []
    for fault, steps in (summary.get("sweep") or {}).items():
        last = steps[max(steps, key=int)]
        falls.append(f"{fault} {100 * (1 - last['mean'] / h['mean']):.1f} % (RFA {last['rfa']:.3f})")
    if falls:
        lines.append("At each fault's largest step the mean TVMS falls by: " + ", ".join(falls) + ".")
    return lines


verdict_table, compare_table = no_table, no_compare  # the summary lines say the rest
table_title = no_title
unit_modules = no_unit_modules  # its run maps nothing


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    return CAPTIONS
