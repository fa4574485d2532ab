"""Issue 19, which shaft: pinion_sync and its attribution on the PHM 2009 records.

For a detection scenario (the records, conditions, alignment and history exactly as the detection
kind reads them; no training), computes the kind's ``pinion_sync`` record per condition
(``detection.classical_record``: each unit's synchronous part per shaft, the shaft it is put on,
the threshold from the history alone) beside ``tooth_sync`` and prints, per condition and unit,
the ROC AUC and detection / false alarms (%) at the history's threshold, then the share of each
test label's units put on each shaft (input, idler, output or nothing), and the median strength
per shaft and label. The test labels are read only to print these figures.

    python benchmarks/phm09_shafts.py scenarios/phm09_chip.toml [--swap-takes] [--units record30,record10]

``--swap-takes``: the other file list the shared folder allows (phm09_localised.swapped). About 20 s.
"""

from __future__ import annotations

import numpy as np
from phm09_localised import command_line

from gearlab.kinds.detection import Rule, auc, classical_record, read_target


def main() -> None:
    args, spec, target, labels = command_line(__doc__.splitlines()[0], indicators="tooth_sync,pinion_sync")
    conditions = read_target(target, spec["blocks"], lambda e: None)
    units = args.units.split(",")
    print("| condition | indicator | unit | AUC | det / FA % | called % per label |")
    print("|---|---|---|---|---|---|")
    attributions = []
    for name, cond in conditions.items():
        rule = Rule(spec["threshold"], spec["false_alarm"], cond["history_records"])
        for indicator in args.indicators.split(","):
            r = classical_record(indicator, name, cond, spec["classical"], rule)
            for u in units:
                thr = r["thresholds"][u]
                neg = np.concatenate([s[u] for p, s in r["test_scores"].items() if labels[p] != target.positive])
                pos = np.concatenate([s[u] for p, s in r["test_scores"].items() if labels[p] == target.positive])
                by_label: dict[str, list] = {}
                for p, s in r["test_scores"].items():
                    by_label.setdefault(labels[p], []).extend(s[u])
                called = ", ".join(f"{k} {100 * np.mean(np.array(v) > thr):.0f}" for k, v in by_label.items())
                print(
                    f"| {name} | {indicator} | {u} | {auc(neg, pos):.2f} | "
                    f"{100 * np.mean(pos > thr):.0f} / {100 * np.mean(neg > thr):.0f} | {called} |"
                )
            if "shafts" in r:
                attributions.append((name, r))
    for u in units:
        print(f"\n{u}: % of each label's units put on each shaft; median strength per shaft\n")
        print("| condition | label | input | idler | output | nothing | strengths (input, idler, output) |")
        print("|---|---|---|---|---|---|---|")
        for name, r in attributions:
            a = r["shafts"]
            named: dict[str, list] = {}
            strength: dict[str, list] = {}
            for p in a["named"]:
                named.setdefault(labels[p], []).extend(a["named"][p][u])
                strength.setdefault(labels[p], []).extend(a["strengths"][p][u])
            thr = f"input threshold {a['thresholds'][u]:.2f}"
            for label, n in named.items():
                shares = " | ".join(f"{100 * n.count(s) / len(n):.0f}" for s in [*a["names"], "nothing"])
                med = ", ".join(f"{m:.2f}" for m in np.median(np.array(strength[label]), axis=0))
                print(f"| {name} | {label} | {shares} | {med} ({thr}) |")


if __name__ == "__main__":
    main()
