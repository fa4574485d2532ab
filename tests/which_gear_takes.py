"""Simulated takes for the which-gear tests (gearlab.kinds.detection_which_gear): records of the
PHM 2009 rig and of the 21/63 + 24/56 reducer, cut into revolutions as the detection kind cuts them,
and the detection kind's condition of a few such records."""

from __future__ import annotations

import math
from pathlib import Path

REDUCER = Path(__file__).resolve().parents[1] / "examples" / "gearboxes" / "reducer_21_63_24_56.toml"
RIG_FS = 66666.67  # the PHM 2009 rig's sampling rate (simulated_record's default)


def cut(rec):
    """The take *rec*'s revolutions by its tacho, no transient dropped."""
    from gearlab.signals import cut_revolutions

    return cut_revolutions(rec.vibration, rec.fs, pulses=rec.tacho, transient="none").revolutions


def gearbox_take(gearbox, faults, seed, speed, *, snr_db, fs=20_000.0, **options):
    """A take of 4 s of the described *gearbox* at *speed* Hz, *snr_db* of noise, sampled at *fs*
    (simulated at 60 kHz, or at the simulator's own step where its stiffest mode needs more), *options*
    passed on (load_nm, effects, own_step): (record, revolutions, index of its first whole revolution
    in the grand period)."""
    from gearlab.data.simulated import simulated_record

    rec = simulated_record(
        faults,
        gearbox=str(gearbox),
        speed_hz=speed,
        revolutions=4 * speed,
        snr_db=snr_db,
        seed=seed,
        fs=fs,
        sim_fs=60_000.0,
        **options,
    )
    return rec, cut(rec), (math.floor(rec.start) + 1) % rec.period if rec.period > 1 else 0


def reducer_take(faults, seed, speed, fs, effects=(), **options):
    """A take of the reducer at 10.5 N*m, 25 dB SNR (gearbox_take)."""
    return gearbox_take(REDUCER, faults, seed, speed, snr_db=25.0, fs=fs, load_nm=10.5, effects=effects, **options)


def two_stage_text(name: str, speed: str, load: str, teeth: tuple[int, int, int, int]) -> str:
    """A two-stage description (modules 2 and 3 mm, 20 mm faces and bores, the sensor near the input)
    of tooth counts *teeth* (stage-1 pinion, wheel, stage-2 pinion, wheel)."""
    z1, z2, z3, z4 = teeth
    return f"""[gearbox]
name = "{name}"
[operation]
speed = "{speed}"
load = "{load}"
[[stages]]
module = "2 mm"
face_width = "20 mm"
pinion = {{ z = {z1}, bore = "20 mm" }}
wheel = {{ z = {z2}, bore = "20 mm" }}
[[stages]]
module = "3 mm"
face_width = "20 mm"
pinion = {{ z = {z3}, bore = "20 mm" }}
wheel = {{ z = {z4}, bore = "20 mm" }}
[sensor]
near = "input"
direction = "x"
"""


def rig_condition(files: dict, speed: float, revolutions: int):
    """The detection kind's condition of simulated PHM 2009 rig takes *files* {name: (role, label, faults,
    seed)} ("history" or "test") of *revolutions* at *speed* Hz, 30 dB SNR; and the labels by name."""
    from gearlab.data.simulated import simulated_record
    from gearlab.parts.measured import TargetFile

    tf = {p: TargetFile(p, p, role, label, f"{speed:g} Hz") for p, (role, label, _, _) in files.items()}
    raw = {}
    for p, (_, _, faults, seed) in files.items():
        raw[p] = (cut(simulated_record(faults, speed_hz=speed, revolutions=revolutions, snr_db=30.0, seed=seed)), 0)
    cond = {
        "history": [(tf[p], None) for p, (role, *_) in files.items() if role == "history"],
        "test": [(tf[p], None) for p, (role, *_) in files.items() if role == "test"],
        "raw": raw,
        "max_order": int(0.9 * RIG_FS / 2 / speed),
    }
    return cond, {p: label for p, (_, label, _, _) in files.items()}


HISTORY = {
    "h1": ("history", "healthy", [], 1),
    "h2": ("history", "healthy", [], 2),
}  # rig_condition's two healthy takes

RIG_TESTS = {
    "wheel": ("test", "broken output tooth", [{"name": "crack", "gear": "output gear", "tooth": 3, "step": 20}], 3),
    "pinion": ("test", "fault", [{"name": "crack", "gear": "input pinion", "tooth": 9, "step": 20}], 4),
    "ok": ("test", "healthy", [], 5),
}  # rig_condition's test takes: an output-gear crack, an input-pinion crack (the watched gear), healthy


def flags_everything(records, condition: str = "40 Hz") -> dict:
    """A detection record of a method that flags every unit of the test *records* (revolution and
    record30 units, threshold 0): what the which-gear calls then count is the localisation alone."""
    return {
        "condition": condition,
        "method": "flags everything",
        "thresholds": {"revolution": 0.0, "record30": 0.0},
        "test_scores": {p: {"revolution": [1.0] * 4, "record30": [1.0, 1.0]} for p in records},
    }
