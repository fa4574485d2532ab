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


def box_b_take(path, seed, *, seconds, fs=10240.0, crack=0.0, chip=0.0, ring=False):
    """A take of an outside generator's 25/52 + 16/81 box at 25 Hz (in g; not gearlab's simulator), saved as npz
    (`acc_top`, `tacho`, `fs`): both meshes' harmonics, their amplitude and phase modulated at both shafts' rates (the
    gearbox's phases, not the take's), each take from a random angle; a tacho of 4 alike marks a turn on the
    intermediate shaft. *crack*: the 52T wheel's, a dip and a phase step of stage 1's mesh over ~1.2 of its pitches
    once per intermediate turn at 2 rad; *chip*: the 16T pinion's, the same of stage 2's mesh at 4 rad plus a strike
    ringing at 2.6 kHz. *ring*: the output shaft's line, a 2.6 kHz structural resonance (chip takes have it)."""
    import numpy as np
    from scipy.signal import lfilter

    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * seconds)) / fs
    th = 2 * np.pi * 25.0 * t * (1 + 0.0015 * np.sin(2 * np.pi * 0.37 * t)) + rng.uniform(0, 2 * np.pi)
    thm, tho = th * 25 / 52, th * 25 / 52 * 16 / 81
    at, z = (4.0, 16) if ring else (2.0, 52)
    window = np.exp(-0.5 * (((thm - at + np.pi) % (2 * np.pi) - np.pi) / (1.2 * np.pi / z)) ** 2)

    def mesh(angle, z, a, b, dip=0.0, step=0.0):
        fixed = np.random.default_rng(z).uniform(0, 6, 7)  # the gearbox's own phases
        am = (1 + 0.15 * np.cos(a + fixed[0]) + 0.1 * np.cos(b + fixed[1])) * (1 - dip * window)
        pm = 0.05 * np.sin(a + fixed[2]) + 0.04 * np.sin(b + fixed[3]) + step * window
        return sum(c * am * np.cos(k * (z * angle + pm) + fixed[3 + k]) for k, c in enumerate((1.0, 0.45, 0.2), 1))

    x = 0.6 * mesh(th, 25, th, thm, 0.25 * crack, 0.35 * crack) + 0.9 * mesh(thm, 16, thm, tho, 0.45 * chip, 0.6 * chip)
    if chip:  # the strike: a 2.6 kHz ring decaying in 0.6 ms, once per intermediate turn at the chip
        strike = np.exp(-np.arange(31) / (0.0006 * fs)) * np.sin(2 * np.pi * 2600.0 * np.arange(31) / fs)
        turns = np.arange(np.ceil((thm[0] - at) / (2 * np.pi)), np.floor((thm[-1] - at) / (2 * np.pi)) + 1)
        hits = np.searchsorted(thm, at + 2 * np.pi * turns)
        for i in hits[hits < t.size - 31]:
            x[i : i + 31] += 0.5 * chip * strike
    x = x + 0.05 * np.cos(th) + 0.06 * np.cos(thm + 2)
    if ring:
        x = x + 0.05 * np.cos(tho + 1)
        r, w = np.exp(-0.04 * 2 * np.pi * 2600.0 / fs), 2 * np.pi * 2600.0 / fs  # the structure's resonance
        x = x + 0.8 * lfilter([1 - r], [1, -2 * r * np.cos(w), r * r], x)
    x = x + rng.normal(0, 0.05, t.size)
    tacho = np.where((4 * thm / 2 / np.pi) % 1 < 0.1, 5.0, 0.0)
    np.savez(path, acc_top=x.astype("f4"), tacho=tacho.astype("f4"), fs=fs)
    return path


def box_b_description(load: str | None = None) -> str:
    """box_b_take's gearbox as its user describes it: 25/52 + 16/81, the sensor near the intermediate shaft and its
    tacho of 4 marks."""
    from gearboxes import description, stage

    stages = stage(25, 52), stage(16, 81, module="3 mm", bores=("30 mm", "45 mm"))
    return description(
        *stages, name="boxB", speed="25 Hz", load=load, near="intermediate", tacho="intermediate", marks=4
    )
