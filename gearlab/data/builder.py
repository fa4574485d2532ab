"""Build a dataset from its spec: simulate the unique cases, then cut, shift, add noise, average.

Structure exploited (SPEC section 4):

* Steady state is periodic in the input-shaft revolution (fixed speed, faults on the
  pinion only), so one steady revolution per simulation is the whole clean signal.
* Tooth-shift symmetry: the steady response to a fault on tooth n is the tooth-1 response
  shifted by (n - 1)/Z1 of a revolution. The integration rate is rounded up to a whole
  number of steps per tooth pitch, so the shift is an exact whole-sample rotation of the
  periodic revolution: one simulation per fault and intensity serves all Z1 teeth.
* Noise and TSA are added per sample from the sample's own seeded generator, in chunks,
  so memory stays bounded and results do not depend on the worker count.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from ..dynamics.newmark import Simulator
from ..errors import GearlabInputError
from ..executors import LocalExecutor
from ..physics.faults import place_fault
from ..registry import get_registry
from ..runs import Event
from ..signals import Standardiser, add_noise, resample_revolutions, steady_start, tsa
from .spec import POINTS, Dataset, DatasetSpec

STEADY_RTOL = 1e-6
CHUNK = 256  # samples per noise task


def whole_steps_rate(fs: float, speed_hz: float, Z1: int) -> float:
    """The lowest rate >= fs that puts a whole number of steps in one tooth pitch."""
    return math.ceil(fs / (speed_hz * Z1) - 1e-9) * speed_hz * Z1


@functools.lru_cache(maxsize=8)
def _simulator(model: str, preset: str, fs: float) -> Simulator:
    return Simulator(get_registry().get("model", model), preset, fs)


def operating_point(spec: DatasetSpec) -> tuple[float, float]:
    where = f"dataset '{spec.name}'"
    preset = get_registry().get("model", spec.model, where).preset(spec.preset, where)
    speed = preset["speed_hz"] if spec.speed_hz is None else spec.speed_hz
    load = preset["load_nm"] if spec.load_nm is None else spec.load_nm
    return float(speed), float(load)


def steady_revolution(sim: Simulator, faults, speed: float, load: float, channel: str) -> np.ndarray:
    """One steady revolution of *channel* in time samples, starting at a tacho zero crossing.

    The start-up transient is detected, not assumed: revolutions are cut at the tacho and
    the steady one is where successive revolutions stop changing (signals.steady_start).
    """
    per_rev = int(round(sim.fs / speed))
    revolutions = 8
    while True:
        result = sim.run(faults, speed, load, duration=revolutions / speed, channels=[channel])
        x = result.channels[channel][: revolutions * per_rev].reshape(revolutions, per_rev)
        try:
            first = steady_start(x, rtol=STEADY_RTOL)
        except GearlabInputError:
            first = revolutions
        if first <= revolutions - 2:
            return x[-1].copy()
        if revolutions >= 256:
            labels = ", ".join(f.label for f in faults) or "healthy"
            raise GearlabInputError(
                f"model '{sim.model.name}' ({labels}, {speed:g} Hz): the response does not settle within "
                f"{revolutions} revolutions"
            )
        revolutions *= 4


def angle_samples(periodic: np.ndarray, points: int = POINTS) -> np.ndarray:
    """Resample one periodic revolution (time samples from a tacho zero) to *points* angles."""
    n = len(periodic)
    angle = 2 * np.pi * np.arange(n + 1) / n
    return resample_revolutions(np.append(periodic, periodic[0]), angle, points)[0]


def simulate_unit(task: tuple) -> np.ndarray:
    """Steady revolutions (len(teeth), POINTS) of one fault case on every requested tooth."""
    model, preset, fs, speed, load, channel, fault, step, teeth = task
    sim = _simulator(model, preset, fs)
    faults = [] if fault is None else [place_fault(get_registry(), sim.pair, fault, 1, step=step)]
    periodic = steady_revolution(sim, faults, speed, load, channel)
    per_tooth = len(periodic) // sim.pair.Z1  # whole by construction of fs
    return np.stack([angle_samples(np.roll(periodic, (n - 1) * per_tooth)) for n in teeth])


def noisy_rows(task: tuple) -> np.ndarray:
    """Rows for a chunk of samples: clean revolutions -> J noisy revolutions -> kept row."""
    clean, seeds, noise_kind, snr_db, revolutions, use_tsa, reference = task
    mean, std = reference
    out = np.empty((len(clean), POINTS), dtype=np.float32)
    for i, (row, seed) in enumerate(zip(clean, seeds)):
        if noise_kind is None:
            kept = row
        else:
            rng = np.random.default_rng(seed)
            j = revolutions if use_tsa else 1  # the first of J revolutions is the same either way
            noisy = add_noise(np.broadcast_to(row, (j, POINTS)), snr_db, noise_kind, rng)
            kept = tsa(noisy) if use_tsa else noisy[0]
        out[i] = (kept - mean) / std  # eq. 2.112 / 4.6; TSA of standardised = standardised TSA
    return out


def build_dataset(spec: DatasetSpec, executor: LocalExecutor | None = None,
                  on_event: Callable[[Event], None] = lambda e: None) -> Dataset:
    spec.check()
    executor = executor or LocalExecutor(1)
    registry = get_registry()
    _, pair, teeth = spec.check_model()
    speed, load = operating_point(spec)
    fs = whole_steps_rate(spec.fs, speed, pair.Z1)

    # 1. unique simulations: the healthy case and each fault intensity on tooth 1
    units = [(None, None)] + [(name, step) for name, steps in spec.faults for step in steps]
    tasks = [(spec.model, spec.preset, fs, speed, load, spec.channel, f, s, teeth) for f, s in units]
    on_event(Event("stage", stage="simulate", total=len(tasks), message=f"{spec.name}: {len(tasks)} simulations"))
    done = 0

    def advance(stage, total):
        def callback(i, result):
            nonlocal done
            done += 1
            on_event(Event("advance", stage=stage, done=done, total=total))
        return callback

    base = dict(zip(units, executor.map(simulate_unit, tasks, advance("simulate", len(tasks)))))

    # 2. the samples and their labels
    label, intensity, tooth, rfa, source = [], [], [], [], []
    for i in range(spec.healthy):
        label.append(0), intensity.append(0), tooth.append(0), rfa.append(0.0), source.append(((None, None), 0))
    for c, (name, steps) in enumerate(spec.faults, start=1):
        fault = registry.get("fault", name)
        for step in steps:
            area = fault.rfa(fault.at_step(pair, step), pair)
            for t_index, n in enumerate(teeth):
                for _ in range(spec.duplicates):
                    label.append(c), intensity.append(step), tooth.append(n), rfa.append(area)
                    source.append(((name, step), t_index))

    # 3. the domain's healthy reference (eq. 2.112, 4.6): the healthy revolution, noisy when the domain is
    reference_row = base[(None, None)][0]
    if spec.noise is None:
        reference = Standardiser.fit(reference_row)
    else:
        rng = np.random.default_rng([spec.seed, spec.noise.seed, 2**32 - 1])
        reference = Standardiser.fit(add_noise(np.broadcast_to(reference_row, (64, POINTS)), spec.noise.snr_db,
                                               spec.noise.kind, rng))

    # 4. noise, TSA and standardisation, streamed in chunks
    n = len(label)
    noise_kind = spec.noise.kind if spec.noise else None
    snr = spec.noise.snr_db if spec.noise else 0.0
    noise_seed = spec.noise.seed if spec.noise else 0
    chunks = []
    for lo in range(0, n, CHUNK):
        idx = range(lo, min(n, lo + CHUNK))
        clean = np.stack([base[source[i][0]][source[i][1]] for i in idx])
        seeds = [[spec.seed, noise_seed, i] for i in idx]
        chunks.append((clean, seeds, noise_kind, snr, spec.revolutions, spec.tsa, (reference.mean, reference.std)))
    on_event(Event("stage", stage="samples", total=len(chunks), message=f"{spec.name}: {n} samples"))
    done = 0
    X = np.empty((n, POINTS), dtype=np.float32)
    for lo, rows in zip(range(0, n, CHUNK), executor.map(noisy_rows, chunks, advance("samples", len(chunks)))):
        X[lo:lo + len(rows)] = rows
    return Dataset(
        spec=spec,
        X=X,
        label=np.asarray(label, dtype=np.int8),
        fault=(np.asarray(label) > 0).astype(np.int8),
        intensity=np.asarray(intensity, dtype=np.int8),
        tooth=np.asarray(tooth, dtype=np.int8),
        rfa=np.asarray(rfa, dtype=np.float32),
        revolution=np.full(n, -1 if spec.tsa else 0, dtype=np.int16),
        domain=np.zeros(n, dtype=np.int8),
        domains=(spec.domain or spec.name,),
        reference=(reference.mean, reference.std),
        meta={"fs_hz": fs, "speed_hz": speed, "load_nm": load, "Z1": pair.Z1},
    )
