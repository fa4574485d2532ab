"""Issue 19, 30 Hz low load across take orders: is the two-record history the limit, and does
pooling the record-to-record variance over conditions help?

For a detection scenario (records, conditions, alignment and history exactly as the detection kind
reads them; no training), for each classical indicator and record-level unit:

* the history's random-effects model per condition (record_effects.fit: the two history records'
  means, σ_a on one degree of freedom, σ_e the within-record spread of a new record's unit, √Var μ̂)
  and its threshold, with the detection / false alarms (%) it gives;
* the record-to-record spread of the healthy statistic over the condition's *four* healthy-pinion
  records (the two history takes and the two healthy test takes; a diagnostic of what the threshold
  needs, never a threshold): the SD of their record means, against σ_e;
* thresholds with σ_a² pooled over conditions — only history records, of the same scenario: over
  the two loads of a speed ("loads"), over the two speeds of a load ("speeds"), over all four
  ("all") — as σ_a² itself, or as the ratio σ_a²/σ_e² (the record effect in units of the unit
  spread, which is what a scale-free indicator may share across conditions); each condition keeps
  its own μ and σ_e. Detection / false alarms (%) at each.

    python benchmarks/phm09_pooling.py scenarios/phm09_chip.toml [--swap-takes] [--units record30]

The test labels are read only to print the figures (and the healthy test takes' record means).
"""

from __future__ import annotations

import numpy as np
from phm09_localised import command_line
from scipy.stats import norm

from gearlab.kinds.detection import Rule, auc, classical_record, read_target


def threshold(model: dict, record_var: float, m: list[float], p: float) -> float:
    """The predictive quantile with the record variance *record_var* in place of the model's own."""
    within = model["unit_sd"] ** 2
    mean_var = sum(record_var + within / k for k in m) / len(m) ** 2
    return model["mean"] + norm.ppf(p) * np.sqrt(record_var + within + mean_var)


def main() -> None:
    indicators = "fm4,na4,tooth_energy,tooth_sync,pinion_sync"
    args, spec, target, labels = command_line(__doc__.splitlines()[0], indicators=indicators)
    p = 1.0 - spec["false_alarm"]
    conditions = read_target(target, spec["blocks"], lambda e: None)
    groups = {"loads": lambda c: c.split(" ")[0], "speeds": lambda c: c.split(" ", 2)[2], "all": lambda c: ""}
    for u in args.units.split(","):
        for indicator in args.indicators.split(","):
            fitted = {}
            for name, cond in conditions.items():
                rule = Rule(spec["threshold"], spec["false_alarm"], cond["history_records"])
                r = classical_record(indicator, name, cond, spec["classical"], rule)
                m = [k for _, k in cond["history_records"][u]]
                counts = [n for n, _ in cond["history_records"][u]]
                hist = np.split(np.asarray(r["history_scores"][u]), np.cumsum(counts)[:-1])
                test = {q: np.asarray(s[u]) for q, s in r["test_scores"].items()}
                fitted[name] = (r["history_models"][u], m, hist, test)
            print(f"\n{indicator}, {u}" + (" (takes swapped)" if args.swap_takes else ""))
            print(
                "\n| condition | history record means | σ_a | σ_e | √Var μ̂ | threshold | det / FA | AUC "
                "| healthy-pinion record means (test takes) | SD of the 4 | SD / σ_e |"
                " loads: σ_a² | det / FA | σ_a²/σ_e² | det / FA | speeds: σ_a² | det / FA | all: σ_a² | det / FA "
                "| σ_a²/σ_e² | det / FA |"
            )
            print("|---" * 21 + "|")
            for name, (model, m, hist, test) in fitted.items():
                neg = np.concatenate([s for q, s in test.items() if labels[q] != target.positive])
                pos = np.concatenate([s for q, s in test.items() if labels[q] == target.positive])
                healthy_tests = [s.mean() for q, s in test.items() if labels[q] != target.positive]
                four = [h.mean() for h in hist] + healthy_tests
                cells = []

                def rates(t: float, pos=pos, neg=neg) -> str:
                    return f"{100 * np.mean(pos > t):.0f} / {100 * np.mean(neg > t):.0f}"

                for how in ("loads", "speeds", "all"):
                    peers = [v for c, v in fitted.items() if groups[how](c) == groups[how](name)]
                    var = float(np.mean([(v[0]["record_sd"] or 0.0) ** 2 for v in peers]))
                    ratio = float(np.mean([(v[0]["record_sd"] or 0.0) ** 2 / v[0]["unit_sd"] ** 2 for v in peers]))
                    cells.append(f"{var:.3g} | {rates(threshold(model, var, m, p))}")
                    if how != "speeds":
                        by_ratio = ratio * model["unit_sd"] ** 2
                        cells.append(f"{ratio:.3g} | {rates(threshold(model, by_ratio, m, p))}")
                print(
                    f"| {name} | {', '.join(f'{h.mean():.3g}' for h in hist)} | {model['record_sd'] or 0:.3g} "
                    f"| {model['unit_sd']:.3g} | {model['mean_se']:.3g} | {model['threshold']:.3g} "
                    f"| {rates(model['threshold'])} | {auc(neg, pos):.2f} "
                    f"| {', '.join(f'{h:.3g}' for h in healthy_tests)} | {np.std(four, ddof=1):.3g} "
                    f"| {np.std(four, ddof=1) / model['unit_sd']:.1f} | " + " | ".join(cells) + " |"
                )


if __name__ == "__main__":
    main()
