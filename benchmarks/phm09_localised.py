"""Issue 19, 30 Hz low load: designs that could find the PHM 2009 chip where FM4 cannot.

For a detection scenario (the records, conditions, alignment and history exactly as the
detection kind reads them; no training), scores the test units with the classical
indicators and with the candidates below, thresholds each at the history's random-effects
threshold (``[detection] threshold = "records"``, 1 % false alarms asked) and prints per
condition the ROC AUC and detection / false alarms (%) of the test units. The test labels
are read only to print these figures.

* ``fm4``, ``tooth_energy``: the kind's indicators (gearlab.signals.indicators);
* ``tooth_energy (record sd)`` / ``(pooled record sd)``: the tooth windows standardised by the
  predictive spread of a new record (each window's own record variance, from two records one
  degree of freedom; or the record variance pooled over the windows) instead of the
  within-record spread;
* ``<indicator> ch0+ch1``: the output-side accelerometer (column 1) too, read by the kind as
  if the scenario named it and turned by column 0's tacho marks; each channel's score
  standardised by its own history model, fused by the larger of the two (``max``) or their sum
  over √2 (``sum``); for tooth_energy the windows are fused before the maximum (the same window
  of both housings);
* ``tooth_sync``: the kind's indicator with the scenario's ``slow_shafts`` (row ``tooth_sync
  ch0``) and with ``slow_shafts`` = [] (all pairs of revolutions), [5] and [3, 5]; ``tooth_sync + own se``:
  each window's z divided by √(σ_k² + se_k²) instead of σ_k, se_k the unit's own jackknife
  (leave one revolution out) standard error of its synchronous share (``jackknife_variant``);
* the fifth round's first synchronous variants (``floor_variants``): each window's TSA energy
  E_k against the non-synchronous floor F_k = V_k/N that its record's revolution-to-revolution
  spread predicts (``async_floor``, all revolutions of the record): ``sync share, record
  floor`` ((E_k − F_k) / mean_j E_j, the first form of tooth_sync), ``ln E/F`` (the window's
  TSA energy over its floor), ``ln sync share`` (ln of max(E_k − F_k, 0) + F_k·√(2/L_k) over
  its mean, L_k the window's samples: the noise's standard error as the least), ``ln V share``
  (the floor's own localisation: ln of V_k's share, V_k of the unit's own N revolutions), each
  standardised per window by the history's within-record spread, and ``sync share, record
  floor`` by each window's record SD and by the record variance pooled over the windows;
* the halves check (``halves``): do the two halves of one record differ as much as two takes
  of the same gearbox do? (what splitting history records into more "records" assumes).

    python benchmarks/phm09_localised.py scenarios/phm09_chip.toml [--swap-takes] [--units record30,record10]

``--swap-takes`` exchanges the roles of take 1 and take 2 of every record that is not the
positive label's (history take 2, test take 1): the other file list the shared folder allows.
Reads 24 records twice (both channels); about 30 s.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
from pathlib import Path
from unittest import mock

import numpy as np

from gearlab.data.spec import PHM09_CHIP_STEPS
from gearlab.engine import load_scenario
from gearlab.kinds import detection, record_effects
from gearlab.kinds.detection import ROLES, Rule, _window, auc, classical_record, read_target, tsa_units
from gearlab.learn.protocol import Method
from gearlab.runs import RunDir
from gearlab.signals.indicators import (
    async_floor,
    difference_signal,
    fm4,
    pair_mask,
    tooth_windows,
    window_energy,
    window_gram,
    window_reference,
)


def swapped(target):
    """The target with take 1 and take 2 of every non-positive record exchanged in role."""
    roles = {f.path: f.role for f in target.files}

    def other(path: str) -> str:
        return re.sub(r"_(1|2)\.zip$", lambda m: f"_{3 - int(m.group(1))}.zip", path)

    files = tuple(
        dataclasses.replace(f, role=roles[other(f.path)]) if f.label != target.positive else f for f in target.files
    )
    return dataclasses.replace(target, files=files)


def model(groups, unit: str, p: float) -> record_effects.RecordEffects:
    return record_effects.fit(
        groups,
        p,
        [record_effects.independent_units(len(g), *_window(unit)) for g in groups],
        [record_effects.overlap_dof(len(g), *_window(unit)) for g in groups],
    )


def split_history(cond: dict, unit: str, X: np.ndarray) -> list[np.ndarray]:
    return np.split(X, np.cumsum([n for n, _ in cond["history_records"][unit]])[:-1])


def tooth_z(cond: dict, unit: str, orders, how: str):
    """(history z per record, test z per file): (unit, window) standardised tooth-window shares."""
    hist = [tooth_windows(X, orders[0], orders) for X in split_history(cond, unit, cond["history_units"][unit])]
    fits = [model([g[:, k] for g in hist], unit, 0.5) for k in range(orders[0])]
    mean = np.array([f.mean for f in fits])
    if how == "within":
        sd = np.array([f.unit_sd for f in fits])
    elif how == "record":
        sd = np.array([f.predictive_sd for f in fits])
    else:  # the record variance pooled over the windows
        record = np.mean([(f.record_sd or 0.0) ** 2 for f in fits])
        sd = np.sqrt(record + np.array([f.unit_sd**2 + f.mean_se**2 for f in fits]))
    test = {p: (tooth_windows(u[unit], orders[0], orders) - mean) / sd for p, u in cond["test_units"].items()}
    return [(g - mean) / sd for g in hist], test


def floor_variants(cond: dict, unit: str, orders) -> dict[str, tuple]:
    """{variant: (history z per record, test z per file)}: the synchronous variants above, (unit,
    window) standardised; the floor of every unit from all revolutions of its own record."""
    n = _window(unit)[0]
    teeth = orders[0]

    def block_floors(revs, stride):  # V_k of each unit's own N revolutions (for ln V share)
        return np.stack([async_floor(revs[s : s + n], teeth, orders) for s in range(0, len(revs) - n + 1, stride)])

    def stats(X, floor, blocks):
        energy = window_energy(difference_signal(X, orders), teeth)
        f = floor[None] / n
        share = np.maximum(energy - f, 0.0) + f * np.sqrt(2.0 / (X.shape[-1] / teeth))
        return {
            "sync share, record floor": (energy - f) / energy.mean(axis=1, keepdims=True),
            "ln E/F": np.log(energy / f),
            "ln sync share": np.log(share / share.mean(axis=1, keepdims=True)),
            "ln V share": np.log(blocks / blocks.mean(axis=1, keepdims=True)),
        }

    hist_x = split_history(cond, unit, cond["history_units"][unit])
    hist = [
        stats(X, async_floor(r, teeth, orders), block_floors(r, _window(unit)[1]))
        for X, (_, r) in zip(hist_x, cond["history"])
    ]
    revs = {f.path: r for f, r in cond["test"]}
    test = {
        p: stats(u[unit], async_floor(revs[p], teeth, orders), block_floors(revs[p], n))
        for p, u in cond["test_units"].items()
    }
    out = {}
    for name in hist[0]:
        hs = [h[name] for h in hist]
        fits = [model([g[:, k] for g in hs], unit, 0.5) for k in range(teeth)]
        mean = np.array([f.mean for f in fits])
        spreads = {"": np.array([f.unit_sd for f in fits])}
        if name == "sync share, record floor":
            spreads[" (record sd)"] = np.array([f.predictive_sd for f in fits])
            record = np.mean([(f.record_sd or 0.0) ** 2 for f in fits])
            spreads[" (pooled record sd)"] = np.sqrt(record + np.array([f.unit_sd**2 + f.mean_se**2 for f in fits]))
        for how, sd in spreads.items():
            out[name + how] = ([(g - mean) / sd for g in hs], {p: (t[name] - mean) / sd for p, t in test.items()})
    return out


def jackknife_variant(cond: dict, unit: str, orders, slow) -> tuple:
    """tooth_sync's window z with the unit's own jackknife standard error beside the history's
    spread: (u_k − ū_k) / √(σ_k² + se_k²); (history z per record, test z per file)."""
    n, stride = _window(unit)
    teeth = orders[0]

    def shares(revs, step):
        gram = window_gram(revs, teeth, orders)
        mask = pair_mask(n, slow)
        total, each = mask.sum(), mask.sum(axis=1)
        u, se = [], []
        for s in range(0, len(revs) - n + 1, step):
            g = gram[:, s : s + n, s : s + n]
            t = np.sum(g * mask, axis=(1, 2))
            left = (t[:, None] - 2 * np.einsum("krs,rs->kr", g, mask)) / (total - 2 * each)[None]
            scale = (g.sum(axis=(1, 2)) / n**2).mean()
            u.append(t / total / scale)
            se.append(np.sqrt((n - 1) / n * np.sum((left - left.mean(axis=1, keepdims=True)) ** 2, axis=1)) / scale)
        return np.array(u), np.array(se)

    hist = [shares(r, stride) for _, r in cond["history"]]
    dofs = [record_effects.overlap_dof(len(u), n, stride) for u, _ in hist]
    mean, spread = window_reference([u for u, _ in hist], dofs)
    test = {f.path: shares(r, n) for f, r in cond["test"]}

    def z(u, se):
        return (u - mean) / np.sqrt(spread**2 + se**2)

    return [z(*h) for h in hist], {p: z(*t) for p, t in test.items()}


def figures(hist_groups, test, labels, positive, unit, p):
    threshold = model(hist_groups, unit, p).threshold
    neg = np.concatenate([s for f, s in test.items() if labels[f] != positive])
    pos = np.concatenate([s for f, s in test.items() if labels[f] == positive])
    a = auc(neg, pos)
    return (
        f"{'–' if a is None else f'{a:.2f}'} {100 * np.mean(pos > threshold):.0f}/{100 * np.mean(neg > threshold):.0f}"
    )


def second_channel(target, blocks, first: dict) -> dict:
    """The records' column 1 (output-side accelerometer), read as the kind reads a vibration column
    but turned by the tacho marks found on column 0 (one tacho: the same revolutions, and the
    same tooth windows on both housings; column 1 aligned on its own picks other marks)."""
    marks = iter([cond["shifts"][f.path] for cond in first.values() for role in ROLES for f, _ in cond[role]])

    def turned(reference, signal, n):
        m = next(marks)
        orders = np.arange(signal.shape[-1] // 2 + 1)
        out = np.fft.irfft(np.fft.rfft(signal, axis=-1) * np.exp(2j * np.pi * orders * m / n), n=signal.shape[-1])
        return m, out.astype(signal.dtype, copy=False)

    with mock.patch.object(detection, "align_to", turned):
        return read_target(dataclasses.replace(target, vibration=1), blocks, lambda e: None)


def learned_parser(description: str) -> argparse.ArgumentParser:
    """The command line of the phm09 benchmarks that train: the scenario, an output folder for the
    kind's runs, the methods, seeds, --swap-takes and --fault."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("scenario", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--methods", nargs="+", default=["source_only"])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--swap-takes", action="store_true")
    parser.add_argument("--fault", help="a fault plugin in place of the source's chip, at the same ladder steps")
    return parser


def learned_scenario(args):
    """The scenario of *args* (learned_parser) with its seeds, methods and, asked, the takes swapped
    and the source's fault replaced."""
    overrides = {"detection": {"seeds": args.seeds}}
    if args.fault:
        overrides["source"] = {"faults": {args.fault: list(PHM09_CHIP_STEPS)}}
    scenario = load_scenario(args.scenario, overrides)
    spec = scenario.spec
    if args.swap_takes:
        spec["target"] = swapped(spec["target"])
    spec["protocol"] = dataclasses.replace(spec["protocol"], methods=tuple(Method(m, False) for m in args.methods))
    return scenario


def run_detection(scenario, out: Path) -> Path:
    """The detection kind run on *scenario* in a new run folder under *out*; its path."""
    run = RunDir.create(out, scenario)
    with run.lock():
        detection.run(scenario, run, lambda e: None)
    return run.path


def command_line(description: str | None = None, indicators: str | None = None):
    """The phm09 benchmarks' common command line: the scenario, --swap-takes, --units and, given
    a default, --indicators. Returns (args, the scenario's spec, its target with the takes swapped
    when asked, {file path: label})."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("scenario")
    ap.add_argument("--swap-takes", action="store_true")
    ap.add_argument("--units", default="record30")
    if indicators is not None:
        ap.add_argument("--indicators", default=indicators)
    args = ap.parse_args()
    spec = load_scenario(args.scenario).spec
    target = swapped(spec["target"]) if args.swap_takes else spec["target"]
    return args, spec, target, {f.path: f.label for f in target.files}


def main() -> None:
    args, spec, target, labels = command_line()
    classical, p = spec["classical"], 1.0 - spec["false_alarm"]
    orders = classical["mesh_orders"]
    first = read_target(target, spec["blocks"], lambda e: None)
    channels = [first, second_channel(target, spec["blocks"], first)]
    rows: dict[str, dict[str, str]] = {}
    for unit in args.units.split(","):
        for c, cond in channels[0].items():
            rule = Rule("records", spec["false_alarm"], cond["history_records"])
            key = f"{c}, {unit}"
            # per channel: the indicators' scores, as (history groups, test per file)
            per = {}
            for ch, conds in enumerate(channels):
                for name in ("fm4", "tooth_energy", "tooth_sync"):
                    if ch == 1 and name == "tooth_sync":
                        continue
                    r = classical_record(name, c, conds[c], classical, rule)
                    hist = split_history(conds[c], unit, np.asarray(r["history_scores"][unit]))
                    test = {f: np.asarray(s[unit]) for f, s in r["test_scores"].items()}
                    per[(name, ch)] = (hist, test)
                    if ch == 0 or name == "fm4":
                        rows.setdefault(f"{name} ch{ch}", {})[key] = figures(
                            hist, test, labels, target.positive, unit, p
                        )
                for how in ("record", "pooled"):
                    if ch == 0:
                        h, t = tooth_z(conds[c], unit, orders, how)
                        name = f"tooth_energy ({'record' if how == 'record' else 'pooled record'} sd)"
                        rows.setdefault(name, {})[key] = figures(
                            [z.max(1) for z in h], {f: z.max(1) for f, z in t.items()}, labels, target.positive, unit, p
                        )
            for slow in ((), (5,), (3, 5)):
                r = classical_record("tooth_sync", c, channels[0][c], {**classical, "slow_shafts": slow}, rule)
                rows.setdefault(f"tooth_sync, slow_shafts = {list(slow)}", {})[key] = figures(
                    split_history(channels[0][c], unit, np.asarray(r["history_scores"][unit])),
                    {f: np.asarray(s[unit]) for f, s in r["test_scores"].items()},
                    labels,
                    target.positive,
                    unit,
                    p,
                )
            for slow in (classical["slow_shafts"], ()):
                h, t = jackknife_variant(channels[0][c], unit, orders, slow)
                rows.setdefault(f"tooth_sync + own se, slow_shafts = {list(slow)}", {})[key] = figures(
                    [z.max(1) for z in h], {f: z.max(1) for f, z in t.items()}, labels, target.positive, unit, p
                )
            for name, (h, t) in floor_variants(channels[0][c], unit, orders).items():
                rows.setdefault(f"{name} (variant)", {})[key] = figures(
                    [z.max(1) for z in h], {f: z.max(1) for f, z in t.items()}, labels, target.positive, unit, p
                )
            for name in ("fm4", "tooth_energy"):  # scores standardised per channel, then fused
                z = []
                for ch in (0, 1):
                    hist, test = per[(name, ch)]
                    m = model(hist, unit, p)
                    z.append(([m.standardised(g) for g in hist], {f: m.standardised(s) for f, s in test.items()}))
                for how, op in (("max", np.maximum), ("sum", lambda a, b: (a + b) / np.sqrt(2))):
                    if name == "tooth_energy":  # the same window of both housings, then the largest
                        h = [tooth_z(channels[ch][c], unit, orders, "within") for ch in (0, 1)]
                        hist = [op(a, b).max(1) for a, b in zip(h[0][0], h[1][0])]
                        test = {f: op(h[0][1][f], h[1][1][f]).max(1) for f in h[0][1]}
                    else:
                        hist = [op(a, b) for a, b in zip(z[0][0], z[1][0])]
                        test = {f: op(z[0][1][f], z[1][1][f]) for f in z[0][1]}
                    rows.setdefault(f"{name} ch0+ch1 {how}", {})[key] = figures(
                        hist, test, labels, target.positive, unit, p
                    )
    keys = list(dict.fromkeys(k for r in rows.values() for k in r))
    print(f"AUC det/FA (%) at the history's threshold{' (takes swapped)' if args.swap_takes else ''}")
    print("| method | " + " | ".join(keys) + " |")
    print("|---|" + "---|" * len(keys))
    for name, r in rows.items():
        print(f"| {name} | " + " | ".join(r.get(k, "") for k in keys) + " |")
    halves(channels[0], target, orders)


def halves(conditions: dict, target, orders) -> None:
    """Would splitting each history record into halves give more "records" for the threshold's
    record variance? Only if two halves of one record differ as two takes of the same gearbox
    do. The random-effects model's record SD of FM4 (TSA30 sliding windows, the kind's
    units) fitted to the two halves of each record, against that fitted to the two takes of
    the same gearbox and condition (every non-positive record with both takes among the files:
    a check of the assumption on healthy takes, not a rule; no threshold uses it)."""

    def units(revs):
        return fm4(tsa_units(revs, 30, 3), orders)

    def record_sd(groups) -> float:
        return model(groups, "record30", 0.5).record_sd or 0.0

    by_halves, by_takes = [], []
    for cond in conditions.values():
        revs = {f.path: r for role in ROLES for f, r in cond[role] if f.label != target.positive}
        for path, r in revs.items():
            n = len(r) // 2
            by_halves.append(record_sd([units(r[:n]), units(r[n:])]))
            twin = re.sub(r"_1\.zip$", "_2.zip", path)
            if twin != path and twin in revs:
                by_takes.append(record_sd([units(r), units(revs[twin])]))
    print(
        f"\nFM4 TSA30 record SD (random effects, within-record noise removed): two halves of one record "
        f"{np.sqrt(np.mean(np.square(by_halves))):.3f} (RMS over {len(by_halves)} records; "
        f"{sum(s == 0 for s in by_halves)} estimated as 0), two takes of one gearbox "
        f"{np.sqrt(np.mean(np.square(by_takes))):.3f} (RMS over {len(by_takes)} pairs)"
    )


if __name__ == "__main__":
    main()
