"""Example recordings for docs/your_gearbox.md: CSV files as a data logger would write them.

    python examples/your_gearbox/make_recordings.py [FOLDER]

The single-stage spur gearbox of rig16.toml (beside this script; the guide's step 1 writes the
same description): 16/48 teeth, input shaft at 25 Hz and 7 N m, an accelerometer at 100 mV/g on
the housing (x), a once-per-revolution tacho; 20 kHz, columns time_s, acc_V, tacho_V. The
vibration is gearlab's own simulation of that description (the ten-DOF model, the lumped values
it leaves to their defaults) with sensor noise (25 dB), so what the gap diagnosis should find is
known. Files: history1.csv, history2.csv (healthy), test_healthy.csv,
test_chip.csv (a chipped pinion tooth), next_week.csv (chipped too).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

SPEED = 25.0  # Hz, input shaft
LOAD = 7.0  # N m
DESCRIPTION = Path(__file__).with_name("rig16.toml")
FS = 20_000.0  # the logger's rate: 800 samples per revolution
SIM_FS = 200_000.0  # the simulation's rate
SENSITIVITY = 0.1 / 9.80665  # 100 mV/g, in V per m/s²
SNR_DB = 25.0
REVOLUTIONS = 45  # 1.8 s a take: two history takes give a record30 detection 10 units of its 8 at least

FILES = {  # name: (chip step or None, seed)
    "history1.csv": (None, 1),
    "history2.csv": (None, 2),
    "test_healthy.csv": (None, 3),
    "test_chip.csv": (20, 4),
    "next_week.csv": (20, 5),
}


def revolution(chip: int | None) -> np.ndarray:
    """One steady revolution of the housing's x acceleration (m/s²) at the logger's rate."""
    from gearlab.data.builder import _simulator, steady_revolution
    from gearlab.gearbox.simulation import reference
    from gearlab.physics.faults import place_fault
    from gearlab.registry import get_registry

    sim = _simulator("ten_dof", reference(str(DESCRIPTION)), SIM_FS)
    faults = [] if chip is None else [place_fault(get_registry(), sim.pair, "chip", 1, step=chip)]
    rev = steady_revolution(sim, faults, SPEED, LOAD, "casing_x")
    per_rev = int(round(FS / SPEED))
    spectrum = np.fft.rfft(rev)[: per_rev // 2] * per_rev / rev.size  # orders below the logger's Nyquist
    return np.fft.irfft(spectrum, n=per_rev)


def write(folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    revs = {chip: revolution(chip) for chip in {c for c, _ in FILES.values()}}
    paths = []
    for name, (chip, seed) in FILES.items():
        rng = np.random.default_rng(seed)
        start = int(rng.integers(revs[chip].size))  # a record starts anywhere in a revolution
        acc = np.roll(np.tile(revs[chip], REVOLUTIONS + 1), -start)[: REVOLUTIONS * revs[chip].size]
        acc = acc + rng.standard_normal(acc.size) * acc.std() * 10 ** (-SNR_DB / 20)
        t = np.arange(acc.size) / FS
        theta = 2 * np.pi * ((np.arange(acc.size) + start) % revs[chip].size) / revs[chip].size
        tacho = 2.5 - 2.5 * np.cos(theta)  # one smooth pulse per revolution
        table = np.column_stack([t, acc * SENSITIVITY, tacho])
        path = folder / name
        np.savetxt(path, table, fmt="%.7g", delimiter=",", header="time_s,acc_V,tacho_V", comments="")
        paths.append(path)
    return paths


if __name__ == "__main__":
    for p in write(Path(sys.argv[1] if len(sys.argv) > 1 else ".")):
        print(p)
