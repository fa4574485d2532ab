"""Issue 19, other damage: which of phm09_chip.toml's decision rows call damage that is not a chipped
input pinion a pinion fault?

The hidden check of the issue runs the scenario on "other fault cases with a good 32T pinion, a
chipped pinion among other damage" of the same rig. The shared folder holds none, so this writes
synthetic records of the rig's layout (tests/textrecords.py `rig_record`: the rig's rate 66.67 kHz,
a mesh tone at order 32, noise, 46 revolutions at *speed*) — a history of a healthy gearbox and one
with an eccentric idler (as spur1 and spur3 are), and as test records: a new healthy gearbox, an
eccentric idler alone, a chipped input pinion (alone, under an eccentric idler, beside an idler
tooth), a chipped idler-shaft tooth (every 3rd input revolution at one input angle; alone and under
an eccentric idler), a chipped output-shaft tooth (every 5th) and an outer-race bearing defect (3.05
impulses a revolution; at the chip's size and three times it) — and phm09_chip.toml with only its
file list replaced (*out*/phm09_other.toml).

It prints, for every classical indicator of the scenario and each record-level unit, the share (%)
of each test record's units called at the history's threshold (the kind's own classical_record and
Rule: the thresholds come from the history alone). A pinion-fault row should call the three
"pinion" records (100) and none of the others (0). The learned methods' rows come from running the
scenario written here (its table.md lists the called % per test label for every method):

    python benchmarks/phm09_other_damage.py OUT [--speed 35] [--size 4]
    gearlab run OUT/phm09_other.toml --out OUT/runs          # every method, one condition: 28 trainings

The first command takes about 30 s.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the synthetic record writer the tests use

import textrecords  # noqa: E402

from gearlab.engine import load_scenario  # noqa: E402
from gearlab.kinds.detection import Rule, classical_record, read_target  # noqa: E402

# name: (role, label, fault sizes in units of the chip's ring, eccentric idler swing)
RECORDS = {
    "healthy_1": ("history", "healthy", {}),
    "eccentric_1": ("history", "eccentric idler", {"eccentric": 0.6}),
    "healthy_2": ("test", "healthy", {}),
    "eccentric_2": ("test", "eccentric idler", {"eccentric": 0.6}),
    "pinion": ("test", "fault", {"chip": 1.0}),
    "pinion_eccentric": ("test", "fault", {"chip": 1.0, "eccentric": 0.9}),
    "pinion_idler": ("test", "fault", {"chip": 1.0, "idler": 1.0}),  # a chipped pinion among other damage
    "idler": ("test", "idler tooth", {"idler": 1.0}),
    "idler_eccentric": ("test", "idler tooth", {"idler": 1.0, "eccentric": 0.6}),
    "output": ("test", "output tooth", {"output": 1.0}),
    "bearing": ("test", "bearing outer race", {"bearing": 1.0}),
    "bearing_strong": ("test", "bearing outer race", {"bearing": 3.0}),
}
SIZED = ("chip", "idler", "output", "bearing")


def write(out: Path, speed: float, size: float) -> Path:
    """The records and the scenario (phm09_chip.toml, its file list replaced) in *out*."""
    textrecords.FS = 66666.67  # the rig's rate, as the scenario's fs says
    data = out / "data"
    data.mkdir(parents=True, exist_ok=True)
    for i, (name, (_, _, sizes)) in enumerate(RECORDS.items()):
        scaled = {k: v * size if k in SIZED else v for k, v in sizes.items()}
        textrecords.rig_record(data / f"{name}.zip", speed=speed, seed=10 + i, phase=0.9 * i, **scaled)
    listed = "files = [\n" + "".join(
        f'  {{ path = "data/{name}.zip", role = "{role}", label = "{label}" }},\n'
        for name, (role, label, _) in RECORDS.items()
    )
    shipped = (ROOT / "scenarios" / "phm09_chip.toml").read_text()
    text, n = re.subn(r"files = \[\n(.*\n)*?\]", lambda _: listed + "]", shipped)
    assert n == 1, "phm09_chip.toml: no file list found"
    path = out / "phm09_other.toml"
    path.write_text(text)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="folder for the records and the scenario")
    ap.add_argument("--speed", type=float, default=35.0, help="input shaft speed, Hz (default 35)")
    ap.add_argument("--size", type=float, default=4.0, help="the chip's ring amplitude, m/s^2 (default 4)")
    args = ap.parse_args()
    path = write(args.out, args.speed, args.size)
    spec = load_scenario(path).spec
    ((name, cond),) = read_target(spec["target"], spec["blocks"], lambda e: None).items()
    rule = Rule(spec["threshold"], spec["false_alarm"], cond["history_records"])
    indicators = spec["classical"]["indicators"]
    called: dict[str, dict] = {}
    for indicator in indicators:
        r = classical_record(indicator, name, cond, spec["classical"], rule)
        for p, units in r["test_scores"].items():
            for u, s in units.items():
                if u != "revolution":
                    called.setdefault((u, Path(p).stem), {})[indicator] = 100.0 * np.mean(
                        np.asarray(s) > r["thresholds"][u]
                    )
    print(f"{path}: {name}, chip ring {args.size:g} m/s^2; % of each test record's units called a pinion fault\n")
    print("| unit | record | label | " + " | ".join(indicators) + " |")
    print("|---|---|---|" + "---|" * len(indicators))
    for (u, record), by in called.items():
        label = RECORDS[record][1]
        print(f"| {u} | {record} | {label} | " + " | ".join(f"{by[i]:.0f}" for i in indicators) + " |")


if __name__ == "__main__":
    main()
