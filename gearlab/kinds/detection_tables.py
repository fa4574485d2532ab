"""The detection kind's results (gearlab.kinds.detection): scores.csv, shafts.csv, summary.json
and table.md/table.csv made from a run's records, where the test labels come in for the first
time (to score what was decided), and the tables the CLI, the TUI and report.html show."""

from __future__ import annotations

import csv
import io
from dataclasses import asdict

import numpy as np

from ..learn.protocol import domain_adapting
from ..parts.measured import Target
from ..parts.roc import auc
from ..runs import RunDir
from ..scenario import Scenario
from .contract import VERDICT
from .detection_level import called_levels
from .detection_records import longest_tsa
from .detection_summary import judged, verdict
from .detection_units import method_name
from .detection_verdict import watched_calls
from .detection_which_gear import which_gear_summary, with_levels


def summarise(scenario: Scenario, run: RunDir) -> None:
    spec = scenario.spec
    target: Target = spec.target
    labels = {f.path: f.label for f in target.files}
    everything = run.records()
    by_unit = {r["unit"]: r for r in everything}
    records = judged(everything)
    thresholds = {r["unit"]: r["thresholds"] for r in records}
    # scores.csv: every test unit's score and decision
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["file", "unit", "index", "method", "score", "decision"])
    for r in sorted(records, key=lambda r: r["unit"]):  # not in the order the trainings finished
        for path, units in r["test_scores"].items():
            for u, scores in units.items():
                thr = thresholds[r["unit"]][u]
                for i, s in enumerate(scores):
                    w.writerow([path, u, i, r["method"], repr(float(s)), int(s > thr)])
    run.write_text("scores.csv", buf.getvalue())
    attributed = [r for r in records if "shafts" in r]
    if attributed:
        run.write_text("shafts.csv", shafts_csv(attributed))

    # the labels come in only here, to score what was decided
    def split(r: dict, u: str) -> tuple[np.ndarray, np.ndarray]:
        neg = [r["test_scores"][p][u] for p in r["test_scores"] if labels[p] != target.positive]
        pos = [r["test_scores"][p][u] for p in r["test_scores"] if labels[p] == target.positive]
        return np.concatenate(neg or [np.empty(0)]), np.concatenate(pos or [np.empty(0)])

    rows = []
    # the shaft whose revolutions the units are, per condition (detection_records.unit_shaft)
    shafts = {c: v.get("unit_shaft", "input") for c, v in (run.read_json("conditions.json") or {}).items()}
    for r in records:
        for u in r["history_scores"]:
            thr = thresholds[r["unit"]][u]
            neg, pos = split(r, u)
            # scores that are not numbers (a broken method) are counted and shown, never ranked
            broken = int(np.sum(~np.isfinite(np.concatenate([neg, pos, np.asarray(r["history_scores"][u])]))))
            other = {
                rule: (
                    100.0 * float(np.mean(pos > t[u])) if len(pos) else None,
                    100.0 * float(np.mean(neg > t[u])) if len(neg) else None,
                )
                for rule, t in r.get("thresholds_by_rule", {}).items()
            }
            by_label = {}
            for p, units in r["test_scores"].items():
                by_label.setdefault(labels[p], []).extend(units[u])
            rows.append(
                {
                    "condition": r["condition"],
                    "unit": u,
                    "method": r["method"],
                    "auc": auc(neg, pos),
                    "detection": 100.0 * float(np.mean(pos > thr)) if len(pos) else None,
                    "false_alarm": 100.0 * float(np.mean(neg > thr)) if len(neg) else None,
                    "n_positive": int(len(pos)),
                    "n_negative": int(len(neg)),
                    "non_finite": broken,
                    "threshold": thr,
                    # none of a unit kind on takes too short for it: '–', not NaN and numpy's 'Mean of empty slice'
                    "called_by_label": {
                        k: 100.0 * float(np.mean(np.asarray(v) > thr)) if v else None for k, v in by_label.items()
                    },
                    # detection and false alarms (%) at each threshold rule's threshold
                    "by_rule": {rule: {"detection": d, "false_alarm": f} for rule, (d, f) in other.items()},
                    "member_auc": [auc(*split(by_unit[m], u)) for m in r.get("members", [])],
                    "shaft": shafts.get(r["condition"], "input"),
                    # the history's random-effects model behind the threshold (the verdict's record_spread)
                    "history_model": (r.get("history_models") or {}).get(u),
                }
            )
    order = {c: i for i, c in enumerate(dict.fromkeys(r["condition"] for r in records))}
    variants = [""] + ([spec.corrected_label] if spec.corrected is not None else [])
    methods = [method_name(m, v) for v in variants for m in spec.protocol.methods]
    methods += list(spec.classical.indicators)

    def rank(method: str) -> int:
        return methods.index(method) if method in methods else len(methods)

    rows.sort(
        key=lambda r: (
            order[r["condition"]],
            rank(r["method"]),
            r["unit"] != "revolution",
            r["unit"],
        )
    )
    summary = {
        "kind": "detection",
        "scenario": scenario.name,
        "source": asdict(spec.source),
        "target": {**asdict(target), "files": [asdict(f) for f in target.files]},
        "protocol": {k: v for k, v in asdict(spec.protocol).items() if k != "methods"},
        "methods": list(dict.fromkeys(r["method"] for r in records)),
        "false_alarm_asked": spec.detection.false_alarm,
        "threshold_rule": spec.detection.threshold,
        "rows": rows,
        # pinion_sync's attribution per label (shafts_md), shown by the report as table.md shows it
        "shafts_md": shafts_md(attributed, labels),
    }
    conditions = run.read_json("conditions.json")
    # each test record's change localised on a gear; flags on damage elsewhere (detection_which_gear); a flag with
    # nothing localised on a take off its history's level: a level change (with_levels), as `gearlab score` calls it
    loc = with_levels(run.read_json("localisation.json"), conditions)
    summary["which_gear"] = which_gear_summary(loc, records, labels, target.positive)
    bound = {c: v.get("source_bound", {}) for c, v in (conditions or {}).items()}
    summary["learned"] = [
        {
            "condition": r["condition"],
            "method": r["method"],
            "source_auc": r["source_auc"],
            "source_bound": bound.get(r["condition"], {}).get(r.get("source", "source")),
            "part_source_auc": r.get("part_source_auc", []),
            "source_units": r["source_units"],
            "aligned_to_a_point": r.get("aligned_to_a_point", False),
            "aligned_with": aligned_with(r, spec.protocol.calibration.alignment),
            "seconds": r["seconds"],
        }
        for r in sorted(records, key=lambda r: (order[r["condition"]], rank(r["method"])))
        if "source_units" in r
    ]
    if conditions is not None:
        summary["conditions"] = conditions
    summary["records_md"] = records_md(conditions)
    # what the run warned of as it read the records (a take at another load than its history: NA4 reads the size
    # as a change), where the tables are read later: the run's log alone said it
    summary["warnings"] = [f"warning: {line}" for v in (conditions or {}).values() for line in v.get("warnings", [])]
    # a take called with no gear named, off its history's level further than the history's own takes are (as gearlab
    # score says it)
    summary["warnings"] += [f"warning: {line}" for line in called_levels(conditions or {}, records, loc)]
    summary["warnings"] += [f"warning: {line}" for line in unchanged_by_correction(records)]
    run.write_json("summary.json", summary)
    which = summary["which_gear"].get("md", "")
    run.write_text(
        "table.md",
        verdict_md(summary, records)
        + table_md(rows)
        + "\n"
        + labels_md(rows)
        + summary["shafts_md"]
        + which
        + learned_md(summary["learned"])
        + "\n"
        + summary["records_md"]
        + "".join(f"\n{line}\n" for line in summary["warnings"]),
    )
    run.write_text("table.csv", table_csv(rows))


def verdict_md(summary: dict, records: list[dict]) -> str:
    """The verdict table.md opens with, as report.html, the terminal and the TUI open with it
    (detection_summary.verdict, docs/your_gearbox.md step 6); "" where there is none."""
    lines = verdict(summary, records)
    return f"{VERDICT}{lines[0]}\n" + "".join(f"- {line}\n" for line in lines[1:]) + "\n" if lines else ""


def aligned_with(record: dict, alignment: str) -> str:
    """What a learned method's domain loss aligns the history with: nothing for a method without one
    (trained on the source alone, or a detector), a single point (aligned_to_a_point), else the
    source's samples that [protocol] alignment names."""
    if not domain_adapting(record["adapter"]):
        return "– (no domain loss)"
    if record.get("aligned_to_a_point"):
        return "a point"
    return "the source's healthy samples" if alignment == "healthy" else "every source sample"


def _cell(x, fmt="{:.2f}") -> str:
    return "–" if x is None else fmt.format(x)


def _spread(aucs) -> str:
    """An ensemble's member AUCs as their range."""
    aucs = [a for a in aucs or [] if a is not None]
    return f" ({min(aucs):.2f}–{max(aucs):.2f})" if aucs else ""


def table_md(rows: list[dict]) -> str:
    """One table per condition: a row per method; AUC (an ensemble's: with the range of its
    members' AUCs), detection and false alarms (% of the test's positive and negative units
    called at the history's threshold) per unit; above each its title (report.html's caption), which
    counts any scores that are not numbers."""
    units = list(dict.fromkeys(r["unit"] for r in rows))
    out = []
    for c in dict.fromkeys(r["condition"] for r in rows):
        cells = {(r["method"], r["unit"]): r for r in rows if r["condition"] == c}
        first = next(r for r in rows if r["condition"] == c)
        broken = {m: 0 for m in dict.fromkeys(r["method"] for r in rows if r["condition"] == c)}
        for r in rows:
            if r["condition"] == c:
                broken[r["method"]] += r.get("non_finite", 0)
        labels = dict.fromkeys(k for r in rows if r["condition"] == c for k in r.get("called_by_label") or {})
        out.append(
            f"Condition {c}: ROC AUC of each method's test scores, and the test's positive (det %) and negative "
            "(FA %) units called at the threshold fixed on the history, per unit kind"
            # a 17/55 pump's broken-wheel take made FA 50 % here beside the verdict's 0 %: say which counts
            + (
                "; FA % counts the units of every label but the positive one (labels: "
                f"{', '.join(map(repr, labels))}), other damage included: the verdict counts a unit of a record "
                "localised on another gear as neither (the 'watched / other' table)"
                if len(labels) > 2
                else ""
            )
            + ("" if first.get("shaft", "input") == "input" else f" (units: the {first['shaft']} shaft's revolutions)")
            + (
                "; scores that are not numbers (no AUC, '–'): " + ", ".join(f"{m} {n}" for m, n in broken.items() if n)
                if any(broken.values())
                else ""
            )
        )
        out.append(f"| {c}: method | " + " | ".join(f"{u} AUC | det % | FA %" for u in units) + " |")
        out.append("|---|" + "---|---|---|" * len(units))
        for m in dict.fromkeys(r["method"] for r in rows if r["condition"] == c):
            parts = []
            for u in units:
                r = cells.get((m, u))
                parts.append(
                    "| | "
                    if r is None
                    else f"{_cell(r['auc'], '{:.3f}')}{_spread(r.get('member_auc'))} | "
                    f"{_cell(r['detection'], '{:.0f}')} | {_cell(r['false_alarm'], '{:.0f}')}"
                )
            out.append(f"| {m} | " + " | ".join(parts) + " |")
        out.append(
            "| units (pos / neg) | "
            + " | ".join(
                f"{cells[(first['method'], u)]['n_positive']} / {cells[(first['method'], u)]['n_negative']} | |"
                if (first["method"], u) in cells
                else "| |"
                for u in units
            )
            + " |"
        )
        out.append("")
    return "\n".join(out)


def records_md(conditions: dict | None) -> str:
    """Per record: its condition, role, speed and how it was found (a tacho, a declared speed, the
    description's mesh orders: recordings.shaft_angle), and the turn that put it in register with
    its condition's history; without a tacho, what that changes is said under the table."""
    if not conditions:
        return ""
    out = [
        "Records: each record's speed, how it was found, and the turn that aligned it with its condition's history",
        "| condition | file | role | speed Hz | speed from | turned by |",
        "|---|---|---|---|---|---|",
    ]
    tacho, by_marks = True, True
    for c, v in conditions.items():
        tacho = tacho and v.get("tacho", True)
        by_marks = by_marks and v.get("unit_shaft", "input") == "input"
        # by the tacho's marks only where the units are input revolutions (read_target's unit_tacho)
        turn = "{} marks" if v.get("tacho", True) and v.get("unit_shaft", "input") == "input" else "{} samples"
        for role in ("history", "test"):
            for path in v[role]:
                how = v.get("speed_from", {}).get(path, "tacho")
                shift = turn.format(v["start_marks"][path]) if path in v.get("start_marks", {}) else "–"
                out.append(f"| {c} | {path} | {role} | {v['speeds_hz'][path]:.3f} | {how} | {shift} |")
    if not tacho:
        out.append(
            "\nWithout a tacho, each revolution starts where the record does (the shaft angle of its speed, "
            "zero at its first sample): records are aligned with the history by the correlation of their mean "
            "revolution at any whole-sample turn, then together into the frame of the source's healthy mean "
            "revolution, in which the learned methods learned the fault's shape; the tooth a localisation "
            "names is counted from the record's first sample, a relative index, not a tooth number on the gear."
        )
    elif not by_marks:
        out.append(
            "\nThe units are revolutions of another shaft than the input: the tacho gives each record's speed and "
            "angle, and the records are aligned by the correlation of their mean revolution (a turn in samples), "
            "not by its marks."
        )
    return "\n".join(out) + "\n"


def labels_md(rows: list[dict]) -> str:
    """Called units (%) per test label at the history's threshold, for the longest TSA: is other
    damage (a negative label) taken for the fault?"""
    unit = longest_tsa(r["unit"] for r in rows)
    if unit is None:
        return ""
    picked = [r for r in rows if r["unit"] == unit]
    labels = list(dict.fromkeys(k for r in picked for k in r["called_by_label"]))
    out = [
        f"Units called (% of each test label's {unit} units) at the threshold fixed on the history: is other "
        "damage (a negative label) taken for the fault?",
        f"| {unit}: condition | method | " + " | ".join(f"called % '{k}'" for k in labels) + " |",
        "|---|---|" + "---|" * len(labels),
    ]
    for r in picked:
        out.append(
            f"| {r['condition']} | {r['method']} | "
            + " | ".join(_cell(r["called_by_label"].get(k), "{:.0f}") for k in labels)
            + " |"
        )
    return "\n".join(out) + "\n"


def learned_md(learned: list[dict]) -> str:
    """What each method that learns from the simulator learned of it: the ROC AUC of a network's
    scores of the source's held-out revolutions (an ensemble's: the median over its members, with
    their range; a detector's "–": it is built in the target's frame), and the training time, all
    of its trainings together, and what its domain loss aligns the history with (aligned_with; a
    single point: aligned_to_a_point). From training data only: a row near 0.5 cannot tell the simulated fault
    from healthy, so its calls on the records are not what the simulator taught it."""
    if not learned:
        return ""
    out = [
        "\nWhat each method learned of the simulator, from training data only: the ROC AUC of its scores of the "
        "source's held-out samples (0.5 = chance; – for a detector, built on the history), the bound (the "
        "likelihood ratio that knows the source's noise-free fault shapes and noise law; – for a noise-free "
        "source), the training time of all its trainings, and what its domain loss aligns the history with "
        "(a point: the source's samples it aligns with are one input, a noise-free healthy revolution)\n",
        "| condition | method | source AUC | bound | training (s) | history aligned with |",
        "|---|---|---|---|---|---|",
    ]
    for r in learned:
        aligned = r.get("aligned_with") or ("a point" if r.get("aligned_to_a_point") else "–")
        out.append(
            f"| {r['condition']} | {r['method']} | {_cell(r['source_auc'])}{_spread(r['part_source_auc'])} | "
            f"{_cell(r.get('source_bound'))} | {r['seconds']:.0f} | {aligned} |"
        )
    return "\n".join(out) + "\n"


def shafts_csv(records: list[dict]) -> str:
    """One row per test unit of each pinion_sync record: the shaft its localised damage is put on
    ("nothing": no shaft above its threshold) and every shaft's strength."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    names = list(dict.fromkeys(n for r in records for n in r["shafts"]["names"]))
    w.writerow(["condition", "file", "unit", "index", "shaft", *(f"strength_{n}" for n in names)])
    for r in records:
        a = r["shafts"]
        for path, units in a["named"].items():
            for u, named in units.items():
                for i, (shaft, strength) in enumerate(zip(named, a["strengths"][path][u])):
                    values = dict(zip(a["names"], strength))
                    w.writerow(
                        [r["condition"], path, u, i, shaft, *(repr(float(values.get(n, np.nan))) for n in names)]
                    )
    return buf.getvalue()


def shafts_md(records: list[dict], labels: dict) -> str:
    """pinion_sync's attribution per condition and test label, for the longest TSA: the share (%) of
    the label's units put on each shaft."""
    if not records:
        return ""
    unit = longest_tsa(records[0]["shafts"]["thresholds"])
    if unit is None:
        return ""
    names = list(dict.fromkeys(n for r in records for n in r["shafts"]["names"])) + ["nothing"]
    out = [
        f"\nWhich shaft (pinion_sync, {unit}: % of each label's units put on each shaft)\n",
        "| condition | label | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for r in records:
        by_label: dict[str, list[str]] = {}
        for path, units_named in r["shafts"]["named"].items():
            by_label.setdefault(labels[path], []).extend(units_named[unit])
        for label, named in by_label.items():
            out.append(
                f"| {r['condition']} | {label} | "
                + " | ".join(f"{100.0 * named.count(n) / len(named):.0f}" for n in names)
                + " |"
            )
    return "\n".join(out) + "\n"


def table_csv(rows: list[dict]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(
        ["condition", "unit", "method", "auc", "detection", "false_alarm", "n_positive", "n_negative", "threshold"]
    )
    for r in rows:
        w.writerow(
            [
                r["condition"],
                r["unit"],
                r["method"],
                *(("" if r[k] is None else f"{r[k]:.4f}") for k in ("auc", "detection", "false_alarm")),
                r["n_positive"],
                r["n_negative"],
                f"{r['threshold']:.6g}",
            ]
        )
    return buf.getvalue()


def unchanged_by_correction(records: list[dict]) -> list[str]:
    """A line for each corrected method ('matched_filter (corrected)') that scored every test unit as its plain
    twin: a 3-stage box's [corrected] sensor_noise gave rows equal to the plain ones to the last bit, unsaid (the
    template methods take the simulator's noise-free shapes, which a noise effect leaves as they are)."""
    lines = []
    for r in records:
        for q in records:
            same = q["condition"] == r["condition"] and q["method"].startswith(r["method"] + " (")
            if same and q["test_scores"] == r["test_scores"]:
                lines.append(
                    f"{r['condition']}: {q['method']} scored every test unit as {r['method']}: the correction changes "
                    "nothing it uses (a noise effect alone leaves the template methods' noise-free shapes as they are)"
                )
    return list(dict.fromkeys(lines))


def side_by_side(runs: list[tuple]) -> tuple[str, str] | None:
    """(title, Markdown) of detection runs side by side (`gearlab compare`): a row per condition, method and
    unit, a column per run (AUC, detected / false-alarm % at its history's threshold, from summary.json's rows)
    and, for each run after the first, its AUC less A's; a method one run lacks is left blank there."""
    # as each run's verdict counts them (watched_calls): two runs whose fault takes were all named on another gear
    # than the watched one, then half, read '1.000 (100 / 0)' both, beside verdicts of 0 and 50 % detected
    cells = [
        {(r["condition"], r["method"], r["unit"]): watched_calls(r, summary) for r in (summary or {}).get("rows") or []}
        for *_, summary in runs
    ]
    if not any(cells):
        return None
    letters = [letter for letter, *_ in runs]

    def pct(x) -> str:
        return "–" if x is None else f"{x:.0f}"

    head = ["condition", "method", "unit", *letters] + [f"{letter} − {letters[0]} AUC" for letter in letters[1:]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for key in dict.fromkeys(k for rows in cells for k in rows):
        got = [rows.get(key) for rows in cells]
        # a unit kind no test take filled (1 s takes, record30) has no AUC: '–', where compare stopped on a TypeError
        shown = [
            f"{_cell(r['auc'], '{:.3f}')} ({pct(r['detection'])} / {pct(r['false_alarm'])})" if r else "" for r in got
        ]
        delta = [
            f"{r['auc'] - got[0]['auc']:+.3f}" if r and got[0] and None not in (r["auc"], got[0]["auc"]) else ""
            for r in got[1:]
        ]
        lines.append("| " + " | ".join([*key, *shown, *delta]) + " |")
    title = (
        "Each run's ROC AUC (detected / false-alarm % at its history's threshold, a unit on a record whose change lies "
        "on another gear being other damage, neither, as its verdict counts) per condition, method and unit"
    )
    return title, "\n".join(lines) + "\n"
