"""The random targets of the transfer_benchmark kind: what a trial draws, from its seed and index
alone (docs/learning.md gives the ranges). Nothing here is chosen per target or tuned on one."""

from __future__ import annotations

import math

import numpy as np

from ..data.spec import NOISE_KINDS, DatasetSpec, NoiseSpec
from ..effects import effect_spec

# What a trial draws: (low, high) uniform, (low, high, "log") log-uniform, (low, high, "int") whole
# numbers with both ends. One model mismatch of MODEL_EFFECTS, one sensor of SENSORS ("none" adds
# nothing), a tone in TONE_SHARE of the trials, a noise law of NOISE_KINDS.
SPEED_HZ = (30.0, 50.0)
LOAD_NM = (10.0, 30.0)
SNR_DB = (-3.0, 6.0)
TONE_SHARE = 0.25
FAULT_TYPES = (2, 4, "int")  # how many of the source's fault types the target holds
TEETH_SHARE = (0.5, 1.0)  # of the source's teeth that carry the target's faults
MODEL_EFFECTS = {
    "drive_inertias": {
        "I11": (1e-3, 2e-2, "log"),
        "I22": (1e-3, 2e-2, "log"),
        "k_c": (1e3, 1e5, "log"),
        "c_c": (1.0, 30.0),
    },
    "bearing_stiffness": {"k_factor": (0.3, 3.0, "log"), "c_factor": (0.3, 3.0, "log")},
    "mesh_damping": {"zeta": (0.03, 0.15)},
}
SENSORS = {
    "none": {},
    "sensor_bandwidth": {"f_n": (3e3, 3e4, "log"), "zeta": (0.05, 0.4)},
    "sensor_lowpass": {"f_c": (3e3, 3e4, "log"), "order": (2, 6, "int")},
}
TONE = {"frequency": (5.0, 3000.0, "log"), "ratio": (0.1, 0.8)}


def _value(rng: np.random.Generator, spec: tuple) -> float | int:
    low, high, *scale = spec
    if scale == ["log"]:
        return float(math.exp(rng.uniform(math.log(low), math.log(high))))
    if scale == ["int"]:
        return int(rng.integers(low, high + 1))
    return float(rng.uniform(low, high))


def _effect(rng: np.random.Generator, name: str, ranges: dict):
    params = {key: _value(rng, spec) for key, spec in ranges.items()}
    return effect_spec(name, **params), params


def draw(rng: np.random.Generator, source: DatasetSpec, index: int, target_train: int) -> tuple[DatasetSpec, dict]:
    """Trial *index*'s target and what was drawn (the answers, shown beside the results). Its healthy
    revolutions are the history (*target_train*) plus as many as it has fault revolutions, so that
    the test set is half faulty whatever the mix."""
    _, _, source_teeth = source.check_model()
    speed, load = _value(rng, SPEED_HZ), _value(rng, LOAD_NM)
    model = str(rng.choice(sorted(MODEL_EFFECTS)))
    sensor = str(rng.choice(sorted(SENSORS)))
    effects, drawn = [], {}
    for name, ranges in ((model, MODEL_EFFECTS[model]), (sensor, SENSORS[sensor])):
        if ranges:
            spec, drawn[name] = _effect(rng, name, ranges)
            effects.append(spec)
    tone = bool(rng.random() < TONE_SHARE)
    if tone:
        spec, drawn["interference_tone"] = _effect(rng, "interference_tone", TONE)
        effects.append(spec)
    law, snr = str(rng.choice(NOISE_KINDS)), _value(rng, SNR_DB)
    n_types = min(_value(rng, FAULT_TYPES), len(source.faults))
    faults = tuple(source.faults[i] for i in sorted(rng.choice(len(source.faults), n_types, replace=False)))
    n_teeth = max(1, round(_value(rng, TEETH_SHARE) * len(source_teeth)))
    teeth = tuple(int(t) for t in sorted(rng.choice(np.asarray(source_teeth), n_teeth, replace=False)))
    fault_rows = sum(len(steps) for _, steps in faults) * len(teeth) * source.duplicates
    name = f"trial{index:03d}"
    target = source.with_(
        name=name,
        domain=name,
        speed_hz=round(speed, 3),
        load_nm=round(load, 3),
        effects=source.effects + tuple(effects),
        noise=NoiseSpec(law, round(snr, 3), int(rng.integers(0, 2**31))),
        faults=faults,
        teeth=teeth,
        healthy=target_train + fault_rows,
    )
    answers = {
        "speed_hz": target.speed_hz,
        "load_nm": target.load_nm,
        "model": model,
        "sensor": sensor,
        "tone": tone,
        "noise": law,
        "snr_db": target.noise.snr_db,
        "faults": [n for n, _ in faults],
        "teeth": len(teeth),
        "effects": drawn,
    }
    return target, answers
