"""Issue 19, sixteenth round: what a network reaches when it is taught the real chip's form.

An oracle, not a method: it reads a fault label of the records, which the issue rules out for the
goals. It bounds what the learned rows could reach on these records with a chip model of the right
form: the same network, seeds, learned input, thresholds and figures as the kind, with the
simulator replaced by real units. Per condition the source is the history's sliding TSA30 units
(healthy) and the sliding TSA30 units of one chipped take (``--teach``, a take of the positive
label: 1 or 2), and the figures (record30: AUC, detected / false alarms % at the history's
threshold) are taken over the test records *other than* the one taught. What is left is the
limit of the data themselves: a history of two records, a threshold fitted to their spread, and
another take of the same chipped build.

    python benchmarks/phm09_real_chip.py scenarios/phm09_chip.toml OUT [--teach 1] [--swap-takes]
        [--methods source_only] [--seeds 3]

About 1 min for ``source_only`` on this machine (the plain source only; the scenario's
`[corrected]` source is not trained).
"""

from __future__ import annotations

import dataclasses
import json
import re
from unittest import mock

import numpy as np
from phm09_localised import learned_parser, learned_scenario, run_detection

from gearlab.kinds import detection

UNIT, BLOCK = "record30", 30


@dataclasses.dataclass(frozen=True)
class Units:
    """What source_split reads of a dataset: the real units and their labels."""

    spec: object
    X: np.ndarray
    fault: np.ndarray


def taught(spec, conditions, take: str) -> tuple[dict, dict]:
    """{source name: Units} per condition, and {condition: the path of the chipped take taught}."""
    positive = spec["target"].positive
    labels = {f.path: f.label for f in spec["target"].files}
    units, paths = {}, {}
    for c, cond in conditions.items():
        chipped = [
            (f.path, revs)
            for f, revs in cond["test"]
            if labels[f.path] == positive and re.search(rf"_{take}\.zip$", f.path)
        ]
        if not chipped:
            raise SystemExit(f"condition '{c}': no test record of label '{positive}' and take {take}")
        path, revs = chipped[0]
        faults = detection.tsa_units(revs, BLOCK, max(1, BLOCK // detection.HISTORY_STRIDES))
        healthy = cond["history_units"][UNIT]
        source = detection.source_for(spec["source"], cond, spec["source_speed"])
        X = np.concatenate([healthy, faults]).astype(np.float32)
        y = np.r_[np.zeros(len(healthy), dtype=np.int64), np.ones(len(faults), dtype=np.int64)]
        units[source.name] = Units(source, X, y)
        paths[c] = path
    return units, paths


def figures(record: dict, skip: str, labels: dict, positive: str) -> str:
    scores = {p: np.asarray(u[UNIT]) for p, u in record["test_scores"].items() if p != skip}
    threshold = record["thresholds"][UNIT]
    pos = np.concatenate([s for p, s in scores.items() if labels[p] == positive])
    neg = np.concatenate([s for p, s in scores.items() if labels[p] != positive])
    auc = detection.auc(neg, pos)
    return f"{auc:.2f}, {np.mean(pos > threshold) * 100:.0f} / {np.mean(neg > threshold) * 100:.0f}"


def main() -> None:
    parser = learned_parser(__doc__.splitlines()[0])
    parser.add_argument("--teach", default="1", help="the take of the chipped records taught")
    args = parser.parse_args()
    scenario = learned_scenario(args)
    spec = scenario.spec
    spec["corrected"] = None  # one source: the real units
    conditions = detection.read_target(spec["target"], spec["blocks"], lambda e: None)
    units, paths = taught(spec, conditions, args.teach)
    load = detection.load_or_build

    def real_units(dataset_spec, *rest, **kwargs):
        if dataset_spec.name in units:
            return units[dataset_spec.name], None
        return load(dataset_spec, *rest, **kwargs)

    with mock.patch.object(detection, "load_or_build", real_units):
        path = run_detection(scenario, args.out)
    labels = {f.path: f.label for f in spec["target"].files}
    records = [json.loads(line) for line in (path / "results.jsonl").read_text().splitlines() if line.strip()]
    print(f"taught: the chipped take {args.teach}{' (takes swapped)' if args.swap_takes else ''}; {path}")
    print(f"| condition | row | source AUC (seeds) | {UNIT} AUC, det / FA, the take not taught |")
    print("|---|---|---|---|")
    for r in records:
        if r.get("seed") is None and r.get("source_auc") is not None:  # a method's ensemble (or its one training)
            part = r.get("part_source_auc") or [r["source_auc"]]
            shown = figures(r, paths[r["condition"]], labels, spec["target"].positive)
            print(
                f"| {r['condition']} | {r['method']} (real chip) | {r['source_auc']:.2f} "
                f"({min(part):.2f}-{max(part):.2f}) | {shown} |"
            )


if __name__ == "__main__":
    main()
