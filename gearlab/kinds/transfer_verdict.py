"""The verdict of a transfer run (gearlab.kinds.transfer's verdict_lines and verdict_table): the
best method at each k and by how much, the methods that collapsed to one class (with their
predicted-fault share), the Bayes bound, and, for Experiments A and B, how the numbers stand
against the thesis's Tables 5.4 and 5.5, whose values (transfer_thesis.toml) are a reference row
of the table. Method names are read from the results, never assumed: any adapter a plugin adds is
compared like the shipped ones."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..data.spec import DATASET_PRESETS
from ..parts.bound import BOUND

# The thesis's Tables 5.4 (Experiment A) and 5.5 (Experiment B), quoted in transfer_thesis.toml.
_QUOTED = tomllib.loads((Path(__file__).resolve().parent / "transfer_thesis.toml").read_text())
THESIS_COLUMNS: tuple[str, ...] = tuple(_QUOTED["columns"])
THESIS_KS: tuple[int, ...] = tuple(_QUOTED["ks"])


def _thesis_table(rows: list) -> dict[str, dict[int, tuple[float, float]]]:
    """{column: {k: (mean, std)}} of a table's rows (one per k: each column's mean and std in turn)."""
    return {
        column: {k: (float(row[2 * i]), float(row[2 * i + 1])) for k, row in zip(THESIS_KS, rows)}
        for i, column in enumerate(THESIS_COLUMNS)
    }


# (source domain, target domain) -> the experiment, its table and its figure
THESIS = {
    ("A-pinion-ch5", "A-casing-ch5"): ("Experiment A", "Table 5.4", "Figure 5.5", _thesis_table(_QUOTED["table_5_4"])),
    ("B-6-ch5", "B-8-ch5"): ("Experiment B", "Table 5.5", "Figure 5.6", _thesis_table(_QUOTED["table_5_5"])),
}


# the fields that make a dataset what it is (its name and domain label are free to change)
_DATASET_FIELDS = (
    "model",
    "preset",
    "channel",
    "speed_hz",
    "load_nm",
    "faults",
    "teeth",
    "duplicates",
    "healthy",
    "revolutions",
    "tsa",
    "fs",
    "effects",
)


def preset_of(side: Mapping) -> str | None:
    """The chapter-5 dataset preset a summary's [source] or [target] is, complete and unchanged
    but for its name and noise; None for anything else (a reduced or measured dataset)."""
    for name, preset in DATASET_PRESETS.items():
        if name.endswith("-ch5") and all(
            _plain(getattr(preset, key)) == _plain(side.get(key)) for key in _DATASET_FIELDS
        ):
            return name
    return None


def experiment(summary: Mapping) -> tuple[str, str, str, dict] | None:
    """The thesis experiment a transfer run repeats: its domains are the chapter-5 presets,
    complete (the thesis's faults, teeth and sizes), the source clean and the target with
    Laplace noise at 0 dB as in thesis 5.4.1; else None (a reference row would compare
    unlike things)."""
    source, target = summary.get("source") or {}, summary.get("target") or {}
    found = THESIS.get((preset_of(source), preset_of(target)))
    noise = target.get("noise") or {}
    if found is None or source.get("noise") or noise.get("kind") != "laplace" or float(noise.get("snr_db", 1)) != 0.0:
        return None
    return found


def _plain(value):
    """Tuples and lists alike (summary.json holds lists where the specs hold tuples)."""
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _ks_text(ks: Sequence) -> str:
    ks = [str(k) for k in ks]
    return ks[0] if len(ks) == 1 else ", ".join(ks[:-1]) + " and " + ks[-1]


def _span(values: Sequence[float], digits: int = 1) -> str:
    low, high = min(values), max(values)
    return f"{low:.{digits}f}" if round(low, digits) == round(high, digits) else f"{low:.{digits}f}-{high:.{digits}f}"


TIE_POINTS = 0.05  # a margin under this shows as 0.0 points: the methods tie


def best_per_k(table: Mapping[str, Mapping[str, Mapping]], ks: Sequence) -> list[dict]:
    """Per k (where two or more methods have a result): the best method, its mean, the
    runner-up and the margin in points, and whether the margin is within one standard
    deviation of either."""
    out = []
    for k in ks:
        cells = [(m, per_k[str(k)]) for m, per_k in table.items() if str(k) in per_k]
        if not cells:
            continue
        cells.sort(key=lambda c: -c[1]["mean"])
        (best, b), rest = cells[0], cells[1:]
        # methods level with the best (a margin that shows as 0.0 points): a tie, not a win
        tied = [best] + [m for m, c in rest if b["mean"] - c["mean"] < TIE_POINTS]
        rest = rest[len(tied) - 1 :]
        row = {
            "k": k,
            "best": best,
            "tied": tied if len(tied) > 1 else [],
            "mean": b["mean"],
            "std": b["std"],
            "second": None,
            "margin": None,
            "within_std": False,
        }
        if rest:
            second, s = rest[0]
            margin = b["mean"] - s["mean"]
            row.update(second=second, margin=margin, within_std=margin < max(b["std"], s["std"]))
        out.append(row)
    return out


def collapsed(records: Sequence[Mapping]) -> dict[str, dict]:
    """Methods whose model called every target test sample one class in at least half of its
    runs: {method: {runs, of, fault_share}} (fault_share: the mean predicted-fault share of
    those runs, %; 0 = all 'healthy', 100 = all 'fault')."""
    runs: dict[str, list[Mapping]] = {}
    for r in records:
        if "method" in r and "predicted_fault_share" in r:
            runs.setdefault(r["method"], []).append(r)
    out = {}
    for method, rs in runs.items():
        one_class = [r for r in rs if r["predicted_fault_share"] <= 0.0 or r["predicted_fault_share"] >= 100.0]
        if one_class and 2 * len(one_class) >= len(rs):
            out[method] = {
                "runs": len(one_class),
                "of": len(rs),
                "fault_share": float(np.mean([r["predicted_fault_share"] for r in one_class])),
            }
    return out


def transfer_lines(summary: Mapping, records: Sequence[Mapping]) -> list[str]:
    table, ks = summary.get("table") or {}, summary.get("protocol", {}).get("ks", [])
    rows = best_per_k(table, ks)
    if not rows:
        return ["No unit has finished yet: there is nothing to judge."]
    lines = []
    if len(table) == 1 or (rows[0]["second"] is None and not rows[0]["tied"]):
        only = rows[0]["best"]
        lines.append(
            f"One method, {only}: {_span([r['mean'] for r in rows], 2)} % target test accuracy "
            f"at k = {_ks_text([r['k'] for r in rows])}."
        )
    else:
        groups: list[list[dict]] = []
        for row in rows:  # consecutive k with the same winner, told together
            last = groups[-1][-1] if groups else None
            if last is not None and (last["best"], last.get("tied")) == (row["best"], row.get("tied")):
                groups[-1].append(row)
            else:
                groups.append([row])
        parts = []
        for group in groups:
            seconds = list(dict.fromkeys(r["second"] for r in group))
            where = (
                "every k" if len(group) == len(rows) and len(rows) > 1 else f"k = {_ks_text([r['k'] for r in group])}"
            )
            means = _span([r["mean"] for r in group], 2)
            if group[0].get("tied"):
                text = f"{' and '.join(group[0]['tied'])} tie at {where} ({means} %)"
                if seconds != [None]:
                    text += f", {_span([r['margin'] for r in group])} points ahead of {' / '.join(seconds)}"
            else:
                text = (
                    f"{group[0]['best']} is best at {where} ({means} %), "
                    f"{_span([r['margin'] for r in group])} points ahead of {' / '.join(seconds)}"
                )
            close = [r["k"] for r in group if r["within_std"]]
            if close:
                text += f" (within one standard deviation at k = {_ks_text(close)})"
            parts.append(text)
        lines.append("; ".join(parts) + ".")
    gone = collapsed(records)
    if gone:
        test_fault = [100.0 - r["healthy_share"] for r in records if "healthy_share" in r]
        said = ", ".join(
            f"{m} ({'all fault' if c['fault_share'] >= 50 else 'all healthy'}: predicted-fault share "
            f"{c['fault_share']:.0f} %, {c['runs']}/{c['of']} runs)"
            for m, c in gone.items()
        )
        share = f"; the target test sets are {np.mean(test_fault):.0f} % faulty" if test_fault else ""
        lines.append(
            f"Collapsed to one class: {said}{share}, so {'their' if len(gone) > 1 else 'its'} accuracy "
            "is the share of that class, not a detection."
        )
    else:
        lines.append("No method collapsed to one class.")
    if summary.get("bound_unavailable"):
        lines.append(f"No Bayes bound: {summary['bound_unavailable']}.")
    bound = (summary.get("bound") or {}).get("accuracy") or {}
    told = [(r["k"], bound[str(r["k"])]["mean"] - r["mean"]) for r in rows if str(r["k"]) in bound]
    if told:
        lines.append(
            f"The Bayes bound (a detector told the target's own fault shapes and noise law, best threshold) "
            f"is {_span([bound[str(k)]['mean'] for k, _ in told], 2)} %: the best method stays "
            f"{_span([gap for _, gap in told])} points below it."
        )
    found = experiment(summary)
    if found is not None:
        lines.append(thesis_line(table, ks, found))
    return lines


def thesis_line(table: Mapping, ks: Sequence, found: tuple) -> str:
    name, table_name, _, thesis = found
    shared = [m for m in THESIS_COLUMNS if m in table]
    diffs = {}
    for m in shared:
        d = [table[m][str(k)]["mean"] - thesis[m][k][0] for k in ks if str(k) in table[m] and k in thesis[m]]
        if d:
            diffs[m] = float(np.mean(d))
    best_thesis = max(thesis, key=lambda m: thesis[m][0][0])
    ours = {m: per_k["0"]["mean"] for m, per_k in table.items() if "0" in per_k}
    text = f"Against the thesis's {table_name} ({name}; its values are the reference rows of the table): "
    if diffs:
        text += ", ".join(f"{m} {d:+.1f}" for m, d in diffs.items()) + " points on average over k"
    else:
        text += "none of the thesis's methods is in this run"
    if ours:
        top = max(ours, key=ours.get)
        text += (
            f"; at k = 0 the thesis's best is {best_thesis} with {thesis[best_thesis][0][0]:.2f} %, "
            f"gearlab's is {top} with {ours[top]:.2f} %"
        )
    return text + "."


def transfer_table(summary: Mapping, table_md) -> str:
    """The Table 5.4 layout of a transfer run, with the thesis's row under each k for
    Experiments A and B (blank where the thesis has no such method); *table_md* writes the
    kind's table (gearlab.kinds.transfer.table_md)."""
    table, ks, methods = summary["table"], summary["protocol"]["ks"], summary["methods"]
    if summary.get("bound"):  # the reference column of table.md (gearlab.kinds.transfer)
        table, methods = {**table, BOUND: summary["bound"]["accuracy"]}, [*methods, BOUND]
    text = table_md(table, ks, methods)
    found = experiment(summary)
    if found is None:
        return text
    _, table_name, _, thesis = found
    lines = text.rstrip("\n").splitlines()
    out = lines[:2]
    for line in lines[2:]:
        out.append(line)
        k = int(line.strip("| ").split(" |")[0])
        if k in THESIS_KS:
            cells = [f"{thesis[m][k][0]:.2f} ± {thesis[m][k][1]:.1f}" if m in thesis else "" for m in methods]
            out.append(f"| {k} (thesis {table_name}) | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"
