"""Which gear, on simulated PHM 2009 rig records: how often the localiser names the damaged gear.

Each trial draws a condition -- input speed (30, 35, 40, 45 or 50 Hz), output load (5-40 N m),
sensor noise (10-30 dB under the record's RMS) -- and simulates, at the records' 66 666.67 Hz
with a once-per-revolution tacho (gearlab.data.simulated.simulated_record), 4 s records: a
healthy history of 2 records (each at the load times 1 + 3 % N(0, 1): no two takes alike), a
healthy test record, and one record with damage on each of the four gears (32T input pinion, 96T
idler gear, 48T idler pinion, 80T output gear): a chip, crack, broken tip, spall or pit at ladder
step 12-20 on a random tooth. Every record is cut from its tacho (signals.cut_revolutions) and
localised against the history (gearlab.signals.localise), orders up to 90 % of the records'
Nyquist order.

Per damaged gear it prints: how many records the localiser flags (a shaft over its history
threshold), of those how many it names first with the damaged gear's shaft (the idler's two gears
share a shaft and are named together, with the leaning of their meshes' modulation), and how many
records are called a fault of the *watched* gear, the input pinion that scenarios/phm09_chip.toml
looks for (goal: none but the input pinion's own). The tooth found is scored against the tooth
placed (the simulator's shafts are at their zero when the input is, so the record's first tacho
mark gives every shaft's angle).

Selection rule (docs/learning.md): settings are tuned on seeds below 1000; figures are reported
on seeds from 1000 on, drawn after the code was frozen.

    python benchmarks/localisation.py --trials 40 --seed 1000 [--workers 2]
"""

from __future__ import annotations

import argparse
import math
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor

import numpy as np

GEARS = ("input pinion", "idler gear", "idler pinion", "output gear")
KINDS = ("chip", "crack", "broken_tip", "spall", "pit")
SPEEDS = (30.0, 35.0, 40.0, 45.0, 50.0)
SECONDS = 4.0
WATCHED = "input pinion 32T (stage 1)"  # the gear phm09_chip.toml's source faults


def _cut(rec):
    from gearlab.signals import cut_revolutions

    cut = cut_revolutions(rec.vibration, rec.fs, pulses=rec.tacho, transient="none")
    # the first complete revolution starts at the first tacho edge: the input turn after the start
    first = (math.floor(rec.start) + 1) % rec.period if rec.period > 1 else 0
    return cut.revolutions, first


def trial(args: tuple[int, int]) -> list[dict]:
    from gearlab.data.simulated import simulated_record
    from gearlab.gearbox import order_table, resolve_gearbox
    from gearlab.signals import localise as L

    seed, index = args
    rng = np.random.default_rng([seed, index])
    speed = float(rng.choice(SPEEDS))
    load = float(rng.uniform(5.0, 40.0))
    snr = float(rng.uniform(10.0, 30.0))
    table = order_table(resolve_gearbox("phm09"))
    seeds = iter(rng.integers(0, 2**31, size=16))

    def record(faults=()):
        take = load * (1 + 0.03 * rng.standard_normal())
        rec = simulated_record(
            list(faults), speed_hz=speed, load_nm=take, revolutions=SECONDS * speed, snr_db=snr, seed=int(next(seeds))
        )
        return _cut(rec), rec

    history = [record()[0][0] for _ in range(2)]
    top = 0.9 * 66666.67 / 2 / speed
    hist = L.history(history, table, max_order=top)
    cases = [("healthy", None)]
    for gear in GEARS:
        z = {"input pinion": 32, "idler gear": 96, "idler pinion": 48, "output gear": 80}[gear]
        cases.append(
            (
                gear,
                {
                    "name": str(rng.choice(KINDS)),
                    "gear": gear,
                    "tooth": int(rng.integers(1, z + 1)),
                    "step": int(rng.integers(12, 21)),
                },
            )
        )
    out = []
    for gear, fault in cases:
        (revs, first), rec = record([fault] if fault else [])
        res = L.localise(revs, hist, table, first_revolution=first)
        row = {
            "trial": index,
            "speed": speed,
            "load": load,
            "snr": snr,
            "case": gear,
            "fault": fault,
            "named": res.named,
            "shaft": res.named_shaft,
            "z": {e.shaft: e.z for e in res.ranking},
        }
        if fault and res.named_shaft:
            ev = next(e for e in res.ranking if e.shaft == res.named_shaft)
            name = next((g for g in ev.gears if g.startswith(gear)), None)
            row["leaning"] = ev.leaning
            row["right_gear"] = name
            if name and name in ev.tooth:
                t = ev.tooth[name]
                gap = (t["pitches"] - (fault["tooth"] - 0.5) + t["of"] / 2) % t["of"] - t["of"] / 2
                row["tooth_off"] = gap
        out.append(row)
    return out


def report(rows: list[dict]) -> None:
    by = defaultdict(list)
    for r in rows:
        by[r["case"]].append(r)
    print(
        f"{'damage':14s} {'records':>7s} {'flagged':>8s} {'named 1st':>10s} {'called input pinion':>20s}"
        f" {'tooth: offset, ±0.5':>19s} {'leaning right':>14s}"
    )
    for case in ("healthy", *GEARS):
        rs = by.get(case, [])
        if not rs:
            continue
        flagged = [r for r in rs if r["named"] is not None]
        shaft = case.split()[0] if case != "healthy" else None
        named = [r for r in flagged if r["shaft"] == shaft]
        watched = [r for r in rs if r["named"] == WATCHED]
        gaps = np.array([r["tooth_off"] for r in named if "tooth_off" in r])
        middle = float(np.median(gaps)) if gaps.size else 0.0
        lean = [r for r in named if r.get("leaning")]
        right = sum(r["leaning"] == r["right_gear"] for r in lean)

        def pct(a, b):
            return f"{100 * a / b:5.1f} %" if b else "    -  "

        print(
            f"{case:14s} {len(rs):7d} {len(flagged):4d} {pct(len(flagged), len(rs)):>8s}"
            f" {pct(len(named), len(flagged)) if shaft else '':>10s}"
            f" {len(watched):4d} {pct(len(watched), len(rs)):>8s}"
            + (f" {middle:+6.2f} {pct(np.sum(np.abs(gaps - middle) < 0.5), gaps.size)}" if gaps.size else " " * 16)
            + f" {pct(right, len(lean)) if lean else '':>14s}"
        )
    print("named 1st: of the flagged records, the damaged gear's shaft ranked first and over its threshold;")
    print("called input pinion: of all records, named 'input pinion' (the gear phm09_chip watches);")
    print("tooth: the peak's median offset from the placed tooth's middle (pitches; the simulator's tooth n")
    print("  meshes from (n - 1) pitches on, and the strike rings), and the share within half a pitch of that;")
    print("leaning right: of the idler's two gears, the one whose mesh shows the modulation is the damaged one.")


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--trials", type=int, default=40)
    p.add_argument("--seed", type=int, default=1000, help="below 1000: development; from 1000: reported figures")
    p.add_argument("--workers", type=int, default=1, choices=(1, 2))
    args = p.parse_args(argv)
    jobs = [(args.seed, i) for i in range(args.trials)]
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            rows = [r for rs in pool.map(trial, jobs) for r in rs]
    else:
        rows = [r for job in jobs for r in trial(job)]
    kind = "development" if args.seed < 1000 else "fresh"
    print(f"localisation on simulated PHM 2009 rig records: {args.trials} trials, seed {args.seed} ({kind})")
    report(rows)


if __name__ == "__main__":
    main()
