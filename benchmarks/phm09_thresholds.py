"""Issue 19, eighth round: threshold rules for a new record, from finished phm09_chip runs.

Every method's threshold is fixed on the history alone; with the PHM data's two history records per
condition the take-to-take spread sigma_a (record_effects) rests on one degree of freedom. This
re-thresholds the scores a run stored (results.jsonl: each training's history and test scores, an
ensemble's members one by one) by several rules and prints, per condition, method and unit, the ROC
AUC and the detection / false alarms (%) at each rule's threshold. No training: the scores are the
run's. The test labels are read only to print the figures.

Rules (each fixed on the history's scores only):

* ``records``: the kind's rule, `record_effects.fit` on the condition's own history records;
* ``records, ratio pooled``: the same model with sigma_a^2 = lambda * sigma_e^2, lambda the mean over
  the run's conditions of each condition's unbiased estimate of sigma_a^2 / sigma_e^2 (the record
  variance in units of the within-record variance, as a property of the method and the rig, so it
  rests on one degree of freedom per condition instead of one);
* ``pooled``: the Gumbel law fitted to the pooled history units by their quartiles (the former rule).

An ensemble (a method trained with several seeds) is re-made under each rule as the kind makes it:
each member standardised by its own history model, the median per unit, thresholded by the rule.

    python benchmarks/phm09_thresholds.py SCENARIO RUN [RUN ...] [--swap-takes] [--units record30,record10]

SCENARIO gives the history's record structure (its records are read: about 20 s) and the labels;
RUN is a run folder (or a folder holding one) of that scenario, or of parts of it (its conditions
are matched by name, so runs of single conditions combine).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from phm09_localised import swapped

from gearlab.engine import load_scenario
from gearlab.kinds import record_effects
from gearlab.kinds.detection import _window, auc, read_target
from gearlab.learn.history import gumbel_quantile

RULES = ("records", "records, ratio pooled", "pooled")


def records_of(folder: Path) -> list[dict]:
    """Every record of results.jsonl under *folder* (the newest run when it holds several)."""
    found = sorted(folder.glob("**/results.jsonl"), key=lambda p: p.stat().st_mtime)
    if not found:
        raise SystemExit(f"{folder}: no results.jsonl")
    return [json.loads(line) for line in found[-1].read_text().splitlines() if line.strip()]


def groups_of(scores, counts) -> list[np.ndarray]:
    return np.split(np.asarray(scores, dtype=np.float64), np.cumsum(counts)[:-1])


class Thresholds:
    """The rules' models of one unit kind's history scores, per condition."""

    def __init__(self, structure: dict, p: float):
        self.structure, self.p = structure, p  # {condition: {unit: [(units, independent)]}}

    def _args(self, condition: str, unit: str, scores) -> tuple:
        counts = [n for n, _ in self.structure[condition][unit]]
        independent = [m for _, m in self.structure[condition][unit]]
        dofs = [record_effects.overlap_dof(n, *_window(unit)) for n in counts]
        return groups_of(scores, counts), independent, dofs

    def ratio(self, histories: dict, unit: str) -> float:
        """lambda: the mean over conditions of sigma_a^2 / sigma_e^2 (unbiased, untruncated)."""
        ratios = []
        for c, s in histories.items():
            _, within, _, estimate = record_effects.moments(*self._args(c, unit, s))
            if estimate is not None and within > 0:
                ratios.append(estimate / within)
        return max(0.0, float(np.mean(ratios))) if ratios else 0.0

    def model(self, rule: str, condition: str, unit: str, scores, ratio: float) -> record_effects.RecordEffects:
        groups, independent, dofs = self._args(condition, unit, scores)
        if rule == "records":
            return record_effects.fit(groups, self.p, independent, dofs)
        _, within, _, _ = record_effects.moments(groups, independent, dofs)
        return record_effects.fit(groups, self.p, independent, dofs, record_var=ratio * within)

    def threshold(self, rule: str, condition: str, unit: str, scores, ratio: float) -> float:
        if rule == "pooled":
            return gumbel_quantile(np.asarray(scores, dtype=np.float64), self.p)
        return self.model(rule, condition, unit, scores, ratio).threshold


def ensemble(rule: str, thresholds: Thresholds, unit: str, per_condition: dict) -> dict[str, tuple]:
    """{condition: (history scores, {path: test scores})} of a method under *rule*: its one record's
    scores, or its members' scores standardised by each member's own history model (under the rule;
    the Gumbel rule keeps the kind's `records` standardisation) and their median per unit."""
    out = {}
    seeds = sorted({r.get("seed") for rs in per_condition.values() for r in rs}, key=str)
    member = {s: {c: next(r for r in rs if r.get("seed") == s) for c, rs in per_condition.items()} for s in seeds}
    ratio = {s: thresholds.ratio({c: r["history_scores"][unit] for c, r in member[s].items()}, unit) for s in seeds}
    for c, rs in per_condition.items():
        if len(rs) == 1:
            out[c] = (
                np.asarray(rs[0]["history_scores"][unit]),
                {p: np.asarray(s[unit]) for p, s in rs[0]["test_scores"].items()},
            )
            continue
        how = "records" if rule == "pooled" else rule
        models = {s: thresholds.model(how, c, unit, member[s][c]["history_scores"][unit], ratio[s]) for s in seeds}

        def median(get, c=c, models=models):
            return np.median([models[s].standardised(get(member[s][c])) for s in seeds], axis=0)

        out[c] = (
            median(lambda r: r["history_scores"][unit]),
            {p: median(lambda r, p=p: r["test_scores"][p][unit]) for p in rs[0]["test_scores"]},
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--swap-takes", action="store_true")
    ap.add_argument("--units", default="record30")
    args = ap.parse_args()
    spec = load_scenario(args.scenario).spec
    target = swapped(spec["target"]) if args.swap_takes else spec["target"]
    labels = {f.path: f.label for f in target.files}
    conditions = read_target(target, spec["blocks"], lambda e: None)
    thresholds = Thresholds({c: cond["history_records"] for c, cond in conditions.items()}, 1.0 - spec["false_alarm"])
    # {method: {condition: [its record, or an ensemble's members]}}
    by_method: dict[str, dict[str, list[dict]]] = {}
    for run in args.runs:
        for r in records_of(run):
            if r["condition"] in conditions and not r.get("members"):  # ensembles are re-made from their members
                by_method.setdefault(r["method"], {}).setdefault(r["condition"], []).append(r)
    print("| condition | method | unit | AUC | " + " | ".join(f"{rule}: det / FA" for rule in RULES) + " |")
    print("|---|---|---|---|" + "---|" * len(RULES))
    for method, per_condition in by_method.items():
        for unit in args.units.split(","):
            made = {rule: ensemble(rule, thresholds, unit, per_condition) for rule in RULES}
            for c in per_condition:
                cells = []
                for rule in RULES:
                    ratio = thresholds.ratio({c2: made[rule][c2][0] for c2 in per_condition}, unit)
                    hist, test = made[rule][c]
                    t = thresholds.threshold(rule, c, unit, hist, ratio)
                    pos = np.concatenate([s for p, s in test.items() if labels[p] == target.positive])
                    neg = np.concatenate([s for p, s in test.items() if labels[p] != target.positive])
                    cells.append(f"{100 * np.mean(pos > t):.0f} / {100 * np.mean(neg > t):.0f}")
                _, test = made["records"][c]
                pos = np.concatenate([s for p, s in test.items() if labels[p] == target.positive])
                neg = np.concatenate([s for p, s in test.items() if labels[p] != target.positive])
                a = auc(neg, pos)
                print(f"| {c} | {method} | {unit} | {'–' if a is None else f'{a:.2f}'} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
