"""Build a dataset from its spec: simulate the unique cases, then cut, shift, add noise, average.

Structure exploited (docs/physics.md, Builder):

* Steady state is periodic in the input-shaft revolution (fixed speed, healthy or a fault
  on the input pinion), so one steady revolution per simulation is the whole clean signal.
  A fault on a slower gear repeats once per turn of its shaft (3 input turns for the PHM
  2009 rig's idler, 5 for its output gear): a sample's J revolutions then follow that
  period from the revolution in which the damaged tooth meshes (period_turn).
* Tooth-shift symmetry: the steady response to a fault on tooth n is the tooth-1 response
  shifted by (n - 1)/Z1 of a revolution. The integration rate is rounded up to a whole
  number of steps per tooth pitch, so the shift is an exact whole-sample rotation of the
  periodic revolution: one simulation per fault and intensity serves all Z1 teeth.
* A later mesh of no whole input order (a description's 17/59 then 26/83) repeats only after a
  cycle of mesh_cycle input revolutions, at another phase in each: a unit then holds the whole
  cycle, and each sample's revolutions are consecutive ones of it from a revolution drawn per
  sample (gearlab.data.realise, "A train's cycle"), as in a recording. A train repeating only after
  more than placement.MAX_PERIOD turns (hunting-tooth pairs: 19/47 + 23/59 + 29/71, 2773) holds a
  stretch of steady revolutions instead, each record cut within it (steady_stretch, stretch_start).
* Noise and TSA are added per sample from the sample's own seeded generator, in chunks,
  so memory stays bounded and results do not depend on the worker count.

Effects (gearlab.effects; docs/gap.md) act in order of level: the model-level ones make
the simulator configuration, the excitation-level ones act inside each simulation, the
signal-level ones on each sample's J revolutions before the dataset's own noise and TSA.
When one of them breaks the tooth-shift symmetry every tooth is simulated; the steady state
stays periodic in one revolution either way.
"""

from __future__ import annotations

import contextlib
import functools
import math
import time
from collections import OrderedDict
from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .. import events
from ..dynamics.config import ModelConfig
from ..effects import EffectChain, config_of, model_of
from ..errors import GearlabInputError
from ..events import Event, standing
from ..executors import LocalExecutor
from ..physics.faults import place_fault
from ..registry import get_registry
from ..signals import Standardiser, resample_revolutions, steady_start, tsa
from ..signals.angle import TWO_PI
from ..signals.shaft import shaft_revolutions, without_input_orders
from . import placement
from .placement import fault_parts, shaft_names
from .realise import CYCLE_STREAM, REFERENCE_ROW, Seeds, first_revolution, realise, record, row_seed
from .rows import TurnedRows, entries, made
from .slow_box import cost, first_blocks, next_blocks
from .spec import POINTS, Dataset, DatasetSpec, NoiseSpec

if TYPE_CHECKING:
    from ..dynamics.newmark import Simulator

STEADY_RTOL = 1e-6
CHUNK = 256  # samples per noise task


def whole_steps_rate(fs: float, speed_hz: float, Z1: int) -> float:
    """The lowest rate >= fs that puts a whole number of steps in one tooth pitch."""
    return math.ceil(fs / (speed_hz * Z1) - 1e-9) * speed_hz * Z1


@functools.lru_cache(maxsize=8)
def _simulator(model: str, preset: str, fs: float, warn_step: bool = True) -> Simulator:
    from ..dynamics.newmark import Simulator  # here, not at the top: start-up time (numba)

    return Simulator(get_registry().get("model", model), preset, fs, warn_step=warn_step)


@functools.lru_cache(maxsize=8)
def _configured_simulator(config: ModelConfig, fs: float, warn_step: bool = True) -> Simulator:
    """The simulator of a configuration made by model-level effects (cached per worker process)."""
    from ..dynamics.newmark import Simulator  # start-up time

    model = model_of(config)
    overrides = config.overrides(model)
    return Simulator(
        model, config.preset, fs, overrides=overrides, mesh_damping=config.mesh_damping, warn_step=warn_step
    )


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
    return steady_response(sim, faults, speed, load, channel)[0]


def steady_response(
    sim: Simulator, faults, speed: float, load: float, channel: str, effects=(), whole_cycle: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`steady_revolution` under excitation-level *effects* ((Effect, params) pairs): the
    revolution and, when an effect moved the shaft angle, its angle from 0 to 2 pi (else None).

    Excitation effects keep the shaft turning once per 1/speed (whole orders), so the
    revolution is still whole steps long and starts at a tacho zero. With a fault on a gear
    other than the input pinion the steady response repeats only after sim.period(faults)
    input revolutions (3 for the 96T idler gear of the PHM 2009 rig, 5 for its 80T output
    gear): what is returned is then that many revolutions, one period, from a tacho zero.
    A train whose later mesh is no whole input order (a description's 21/53 then 29/61: order
    609/53) repeats only after mesh_cycle(sim) turns: steadiness is judged on such cycles, and
    the last period of the last cycle is returned (the later mesh at one phase), or with
    *whole_cycle* the whole last cycle (a dataset's rows, a record: the later mesh at every phase).
    """
    per_rev = int(round(sim.fs / speed))
    period = sim.period(faults)
    cycle = math.lcm(period, mesh_cycle(sim))
    if cycle > placement.MAX_PERIOD:  # a healthy train too (a wheel of over 1000 teeth): hours of simulation
        labels = ", ".join(f.label for f in faults) or "healthy"
        raise GearlabInputError(
            f"model '{sim.model.name}' ({labels}): the steady response repeats only every {cycle} input "
            f"revolutions (the meshes' orders); a steady simulation takes at most {placement.MAX_PERIOD}"
        )
    per_block = per_rev * cycle
    blocks = first_blocks(per_rev, period, cycle, lambda: settle_revolutions(sim, speed))
    most = 256 if cycle == period else 12
    result = None
    while True:
        # a longer run continues the shorter one (the same floats as a run from the start: Simulator.run)
        duration = blocks * cycle / speed
        if effects:
            result = sim.run(faults, speed, load, duration=duration, channels=[channel], effects=effects, after=result)
            x = result.channels[channel][(blocks - 2) * per_block : blocks * per_block]
        else:  # only the last two blocks are held (Simulator.tail): what the check and the rows read
            result = sim.tail(faults, speed, load, channel, duration, (blocks - 2) * per_block, after=result)
            x = result.x[: 2 * per_block]
        # steady when the second-to-last block is within STEADY_RTOL of the last (steady_start's first
        # steady block is then at most blocks - 2; it compares each block with the last alone)
        x = x.reshape(2, per_block)
        try:
            steady = steady_start(x, rtol=STEADY_RTOL) == 0
        except GearlabInputError:
            steady = False
        if steady:
            angle, kept = None, cycle if whole_cycle else period
            if effects and result.angle is not None:
                angle = result.angle[blocks * per_block - kept * per_rev : blocks * per_block] - 2 * np.pi * (
                    blocks * cycle - kept
                )
            return x[-1, -kept * per_rev :].copy(), angle
        if blocks >= most:
            labels = ", ".join(f.label for f in faults) or "healthy"
            raise GearlabInputError(
                f"model '{sim.model.name}' ({labels}, {speed:g} Hz): the response does not settle within "
                f"{blocks * cycle} revolutions"
            )
        blocks = next_blocks(blocks, period, cycle, lambda: settle_revolutions(sim, speed), most)


def mesh_cycle(sim: Simulator) -> int:
    """Input revolutions after which every mesh of the train repeats: 1 when each further mesh is a
    whole input order (the built-in models: 16 on the PHM 2009 rig), else its order's denominator."""
    orders = [Fraction(mesh.ratio * mesh.pair.Z1).limit_denominator(10_000) for mesh in sim.meshes]
    return math.lcm(1, *(order.denominator for order in orders))


# --- a long train: a stretch of steady revolutions, not its whole period ------------------------------
#
# A train whose steady response repeats only after more than placement.MAX_PERIOD input turns (the
# meshes of a 19/47 + 23/59 + 29/71 train: 2773; damage on the output gear of 19/71 + 28/47: 3337)
# needs no such period: the simulator reads each mesh's TVMS at its own gear's angle. A unit then
# holds a stretch of consecutive steady revolutions from a tacho zero, after the start-up transient
# has died away (settle_revolutions: a duration, not a comparison of periods), and each record is
# cut from the stretch without wrapping (stretch_start).
STRETCH = 64  # revolutions of a long train's stretch beyond the longest record it serves (at least as many)
SETTLE_SAFETY = 2.0  # the slowest mode's decay to STEADY_RTOL, this many times over
# Steps of a stretch's lead at most (lead_revolutions): a run holds ~91 bytes a step (a 15-DOF
# three-stage model), so a stretch's run stays within 0.8 GB plus its own revolutions'. Such a model is
# refused before it is simulated (R's gap profile ran a 1 N s/m casing's 846,000-turn settle: 21.9 GB).
SETTLE_STEPS = 1 << 23


def train_cycle(sim: Simulator, faults) -> int:
    """Input revolutions after which the train with *faults* repeats, from the tooth counts exactly
    (lcm of mesh_cycle and the faulted gears' periods; placement.train_period)."""
    pairs = (sim.pair, *(m.pair for m in sim.meshes))
    periods = (placement.train_period(pairs, f.stage, f.gear) for f in faults)
    return math.lcm(placement.mesh_cycle_of(pairs), *periods)


def _modes(sim: Simulator) -> tuple[np.ndarray, np.ndarray]:
    """The decay rate of every mode (the state matrix's eigenvalues at every mesh's mean stiffness and
    damping) and its share of strain energy in the meshes (sum_i k_i |P_i v|^2 / v^H K v, v its
    displacements): 1 for a mode that is all mesh, ~0 for a casing bouncing on its mounts."""
    n = len(sim.dofs)
    K, C = sim.Kc.copy(), sim.Cc.copy()
    meshes = ((sim.P, sim.k_mean, sim.mu), *zip(sim.mesh_P, sim.mesh_means, sim.mesh_mu))
    for P, k, mu in meshes:
        K, C = K + k * np.outer(P, P), C + mu * k * np.outer(P, P)
    Minv = np.linalg.inv(sim.M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
    lam, V = np.linalg.eig(A)
    v = V[:n]
    strain = np.einsum("ij,ik,kj->j", v.conj(), K, v).real
    mesh = sum(k * np.abs(P @ v) ** 2 for P, k, _ in meshes)
    return -lam.real, np.clip(mesh / np.maximum(strain, np.finfo(float).tiny), 0.0, 1.0)


def settle_revolutions(sim: Simulator, speed: float) -> int:
    """Whole input revolutions after which the start-up transient has decayed to STEADY_RTOL of its
    size, SETTLE_SAFETY times over: the slowest decay rate among the model's modes (the state matrix
    at every mesh's mean stiffness and damping). 23 revolutions for the 19/47 + 23/59 + 29/71 train at
    40 Hz (its slowest mode, 439 Hz, decays at 48.8 1/s). A long train's stretch starts this many
    turns from the gears' zero (steady_stretch): which turns of its meshes' grand cycle it shows."""
    decay = float(_modes(sim)[0].min())
    if not decay > 0:
        raise GearlabInputError(f"model '{sim.model.name}': a mode is undamped, so its response never settles")
    return math.ceil(SETTLE_SAFETY * math.log(1 / STEADY_RTOL) / decay * speed)


def lead_revolutions(sim: Simulator, speed: float) -> int:
    """Whole input revolutions a stretch's run starts before the stretch (from the static equilibrium
    there): every mode's start-up transient decayed to STEADY_RTOL, SETTLE_SAFETY times over, from a
    size of sqrt of its mesh strain-energy share (_modes), not 1. The start is the static equilibrium
    under the load at the mean stiffnesses; what sets a mode moving is the meshes' stiffness
    fluctuation, which reaches a mode through the mesh deflection it makes. An estimate, not a bound:
    a development box's casing bouncing on soft mounts (13.7 Hz at 1.6 1/s, share 1.7e-11; 31.6 Hz at
    0.8 1/s, 7.2e-9) showed transients 120 and 85 times under it in its casing_x and casing_y channels
    (3.4e-8, 1e-6 of the response); a two-stage 19/71 + 28/47's slowest mode (70 1/s, share 1.1e-4)
    3 times over it, which the safety factor covers (1.4e-10 left after its 11-turn lead). The soft-mounted box:
    163 turns, not the 506 a full-size transient takes (settle_revolutions).

    Refused (one line) when that lead is over SETTLE_STEPS steps: a run holds ~91 bytes a step (a
    15-DOF three-stage model)."""
    decay, share = _modes(sim)
    if not decay.min() > 0:
        raise GearlabInputError(f"model '{sim.model.name}': a mode is undamped, so its response never settles")
    size = np.maximum(np.sqrt(share), STEADY_RTOL)  # a mode below STEADY_RTOL needs no lead of its own
    slowest = int(np.argmax(np.log(size / STEADY_RTOL) / decay))
    lead = math.ceil(SETTLE_SAFETY * float(np.max(np.log(size / STEADY_RTOL) / decay)) * speed)
    if lead * round(sim.fs / speed) > SETTLE_STEPS:
        raise GearlabInputError(
            f"model '{sim.model.name}': its mode decaying at {decay[slowest]:.3g} 1/s settles only after {lead} "
            f"input revolutions; a settle of at most {SETTLE_STEPS} steps ({SETTLE_STEPS // round(sim.fs / speed)} "
            f"revolutions at {sim.fs:g} Hz) is simulated"
        )
    return max(lead, 1)


def steady_stretch(
    sim: Simulator, faults, speed: float, load: float, channel: str, effects, revolutions: int
) -> tuple[np.ndarray, np.ndarray | None, int]:
    """*revolutions* consecutive steady input revolutions of *channel* from a tacho zero, with the
    sample that ends them (revolutions x per_rev + 1 samples), settle_revolutions after the start;
    the shaft angle over them from 0 when an effect moved it (else None); and that settle count.
    The run starts lead_revolutions before the stretch, every series at its own absolute step
    (Simulator.run's start): the same steady turns as a run from the start, without its long settle."""
    per_rev = int(round(sim.fs / speed))
    settle = settle_revolutions(sim, speed)
    lead = min(lead_revolutions(sim, speed), settle)
    duration, start = (lead + revolutions) / speed, (settle - lead) * per_rev
    lo, hi = lead * per_rev, (lead + revolutions) * per_rev + 1
    if not effects:  # the stretch alone is held (Simulator.tail), not the lead's series
        return sim.tail(faults, speed, load, channel, duration, lo, start=start).x[: hi - lo].copy(), None, settle
    result = sim.run(faults, speed, load, duration=duration, channels=[channel], effects=effects, start=start)
    angle = None if result.angle is None else result.angle[lo:hi] - 2 * np.pi * settle
    return result.channels[channel][lo:hi].copy(), angle, settle


def stretch_row(x: np.ndarray, revolutions: int, angle: np.ndarray | None = None) -> np.ndarray:
    """A stretch of steady_stretch as one row of revolutions x POINTS angles."""
    per_rev = (len(x) - 1) // revolutions
    theta = 2 * np.pi * np.arange(len(x)) / per_rev if angle is None else angle - angle[0]
    theta[-1] = max(theta[-1], 2 * np.pi * revolutions)  # the last revolution whole, up to rounding
    while math.floor(theta[-1] / TWO_PI) < revolutions:  # 2π·22 / 2π is 21.999999999999996 (turned)
        theta[-1] = np.nextafter(theta[-1], np.inf)
    return resample_revolutions(x, theta, POINTS, count=revolutions).reshape(-1)


def stretch_start(seed: int, i: int, revolutions: int, count: int, hits=None) -> int:
    """The revolution of a long train's stretch of *revolutions* at which record *i* of a dataset
    seeded *seed* starts, leaving *count* revolutions after it (no wrap): drawn as realise's
    first_revolution draws (its stream), among *hits* (the revolutions in which a damaged tooth
    meshes) where given and any fits."""
    last = max(revolutions - count, 0)
    choices = [k for k in (hits or ()) if 0 <= k <= last] or range(last + 1)
    if len(choices) <= 1:
        return choices[0]
    return int(choices[int(np.random.default_rng([seed, i, CYCLE_STREAM]).integers(len(choices)))])


def tooth_revolutions(pairs, stage: int, gear: str, tooth: int, first: int, revolutions: int) -> list[int]:
    """The revolutions first .. first + revolutions - 1 (counted from the tacho zero at which every
    gear starts) in which *tooth* of (stage, gear) comes into mesh: tooth n of a gear of Z teeth
    meshing at input order q meets at (n - 1 + m Z) / q input turns."""
    turns = Fraction(1)
    for pair in pairs[: stage - 1]:
        turns *= Fraction(pair.Z1, pair.Z2)
    pair = pairs[stage - 1]
    q, Z = turns * pair.Z1, (pair.Z1 if gear == "pinion" else pair.Z2)
    m = max(0, math.ceil(first * q / Z - (tooth - 1) / Z) - 1)
    out = []
    while (k := math.floor((tooth - 1 + m * Z) / q)) < first + revolutions:
        if k >= first:
            out.append(k - first)
        m += 1
    return out


def angle_samples(periodic: np.ndarray, points: int = POINTS, angle: np.ndarray | None = None) -> np.ndarray:
    """Resample one periodic revolution (time samples from a tacho zero) to *points* angles.

    *angle*: the shaft angle of each sample (0 .. 2 pi), when it does not advance uniformly
    in time (a speed fluctuation); the resampling is then order tracking at the true angle.
    """
    n = len(periodic)
    if angle is None:
        theta = 2 * np.pi * np.arange(n + 1) / n
        theta[-1] = 2 * np.pi  # exactly one turn: 2 pi n / n rounds below 2 pi for some n (1920)
    else:
        theta = np.append(np.asarray(angle, dtype=float) - angle[0], 2 * np.pi)  # angle[0] is 0 up to rounding
    return resample_revolutions(np.append(periodic, periodic[0]), theta, points)[0]


class SimTask(NamedTuple):
    """One unit of simulation: a fault case (or healthy) on one tooth, rows for *teeth*."""

    model: str
    preset: str
    fs: float
    speed: float
    load: float
    channel: str
    fault: str | None
    step: int | None
    teeth: tuple[int, ...]
    effects: tuple = ()  # the dataset's effects (canonical); the model and excitation ones act here
    tooth: int = 1  # the tooth carrying the fault; the rows of the other teeth are its shifts
    stretch: int = 0  # a long train's revolutions per row (0: its whole cycle, or STRETCH x 2 when that is long)
    lazy: bool = False  # a cycle's rows as TurnedRows (made when a sample reads them: build_dataset), not stacked


def simulate_unit(task: tuple) -> np.ndarray | TurnedRows:
    """Steady revolutions (len(teeth), R x POINTS) of one fault case on every requested tooth: R the
    revolutions after which the train repeats (1; a slower damaged gear's period; a later mesh's
    cycle), from the revolution in which the tooth meshes. With task.lazy, R > 1 rows come as the
    cycle they are made from (data.rows.TurnedRows) where that is smaller.

    Without a symmetry-breaking effect the fault sits on *tooth* and every requested tooth
    is an exact whole-sample rotation of that revolution (tooth-shift symmetry).
    """
    task = SimTask(*task)
    if not task.effects:
        sim = _simulator(task.model, task.preset, task.fs)
        excitation, channel = (), task.channel
    else:
        chain = EffectChain.load(task.effects)
        config = chain.model_config(config_of(task.model, task.preset, task.channel))
        sim = _configured_simulator(config, task.fs)
        excitation, channel = chain.at("excitation"), config.channel

    def placed(on: int) -> list:
        faults = []
        if task.fault is None:
            return faults
        for name, stage, gear in fault_parts(task.fault, shaft_names(task.preset, sim.stages), f"model '{task.model}'"):
            pair = sim.pair if stage == 1 else sim.meshes[stage - 2].pair
            tooth = on if gear == "pinion" or not faults else (on - 1) % pair.Z2 + 1  # the wheel tooth it meets
            faults.append(place_fault(get_registry(), pair, name, tooth, step=task.step, gear=gear, stage=stage))
        return faults

    faults = placed(task.tooth)  # one fault, or a pinion's and the wheel tooth's it meets (tooth n: mesh n - 1)
    stretch = task.stretch or (2 * STRETCH if train_cycle(sim, faults) > placement.MAX_PERIOD else 0)
    if stretch:  # a long train: each tooth simulated itself, from the same tacho zero (no symmetry assumed)
        rows = []
        for n in task.teeth:
            x, angle, _ = steady_stretch(sim, placed(n), task.speed, task.load, channel, excitation, stretch)
            rows.append(stretch_row(x, stretch, angle))
        return np.stack(rows)
    periodic, angle = steady_response(sim, faults, task.speed, task.load, channel, excitation, whole_cycle=True)
    if angle is not None and tuple(task.teeth) != (task.tooth,):
        raise RuntimeError("an excitation effect moved the shaft angle but does not declare breaks_symmetry")
    cycle = math.lcm(sim.period(faults), mesh_cycle(sim))
    if cycle > 1:
        if faults:
            turns = [period_turn(sim, faults[0], len(periodic), cycle, n, task.tooth) for n in task.teeth]
        else:
            turns = [((n - task.tooth) * (len(periodic) // cycle // sim.pair.Z1), 0) for n in task.teeth]
        rows = TurnedRows(periodic, cycle, angle, turns)
        # made when read where the cycle is the smaller (every tooth's rows from one cycle): a row of
        # one tooth (every tooth simulated) at a slow speed has fewer points than its time samples
        return rows if task.lazy and rows.nbytes < len(rows) * rows.row_size * 8 else rows.stacked()
    per_tooth = len(periodic) // sim.pair.Z1  # whole by construction of fs
    return np.stack([angle_samples(np.roll(periodic, (n - task.tooth) * per_tooth), angle=angle) for n in task.teeth])


def period_turn(sim: Simulator, fault, length: int, period: int, n: int, tooth: int) -> tuple[int, int]:
    """How the *period* steady input revolutions (*length* time samples) of a fault on a slower gear
    (or a later mesh's cycle, a whole number of its periods) are turned (data.rows.turned) into the
    row of tooth *n*: (the shift in samples, the revolution it starts at), starting with the
    revolution in which tooth *n* comes into mesh (a sample's first revolution shows the damage; its
    J revolutions follow the gears' turns). The simulation holds the fault on *tooth*: on a one-stage
    train tooth n's response is it turned by n - tooth pitches (the tooth-shift symmetry; else n is
    *tooth*). Tooth n of a gear meshing at input order q comes into mesh (n - 1)/q input turns after
    tooth 1, which mesh at the period's start."""
    per_rev = length // period
    pair = sim.pair if fault.stage == 1 else sim.meshes[fault.stage - 2].pair
    order = Fraction(sim.gear_turns(fault.stage, fault.gear) * (pair.Z1 if fault.gear == "pinion" else pair.Z2))
    first = math.floor((n - 1) / order.limit_denominator(10_000))  # the input revolution tooth n meshes in
    return (n - tooth) * (per_rev // sim.pair.Z1), first


# The simulations this process made, newest last: a run that builds a source, its corrected
# variant and that one's noise-free twin (signal-level effects apart) simulates the rig once.
_SIMULATED: OrderedDict[SimTask, np.ndarray | TurnedRows] = OrderedDict()
KEEP_SIMULATED = 256 * 2**20  # bytes: a two-stage run's 161 revolutions a speed are 5 MB


def _remember(task: SimTask, rows: np.ndarray | TurnedRows) -> None:
    rows.setflags(write=False)  # shared by the datasets that reuse it
    _SIMULATED[task] = rows
    kept = sum(r.nbytes for r in _SIMULATED.values())
    while kept > KEEP_SIMULATED:
        kept -= _SIMULATED.popitem(last=False)[1].nbytes


class RowsTask(NamedTuple):
    """A chunk of samples: their clean revolutions and how to make the kept rows."""

    clean: np.ndarray
    seeds: list
    noise_kind: str | None
    snr_db: float
    revolutions: int
    use_tsa: bool
    reference: tuple[float, float]
    effects: tuple = ()  # the dataset's effects (canonical); the signal-level ones act here
    speed_hz: float = 0.0
    reference_rms: float = 0.0  # RMS of the clean healthy revolution
    starts: tuple = ()  # per sample, the revolution of its clean cycle its record starts at (realise.record)
    shaft: tuple = ()  # (p, q): rows of the shaft turning p/q per input turn (DatasetSpec.unit_shaft)
    offsets: tuple = ()  # per sample, the input revolution of the simulation its clean row starts at


def noisy_rows(task: tuple) -> np.ndarray:
    """Rows for a chunk of samples: clean revolutions -> J revolutions realised (signal effects,
    noise; gearlab.data.realise, seeds Seeds.of_row) -> kept row (the first revolution, or the TSA
    of all J)."""
    task = RowsTask(*task)
    mean, std = task.reference
    signal = EffectChain.load(task.effects).at("signal") if task.effects else ()
    chain = EffectChain(signal)
    noise = None if task.noise_kind is None else NoiseSpec(task.noise_kind, task.snr_db)  # its seed is in task.seeds
    out = np.empty((len(task.clean), POINTS), dtype=np.float32)
    last: dict = {}  # the Row made last (data.rows)
    for i, (row, seed) in enumerate(zip(task.clean, task.seeds)):
        revs = made(row, last).reshape(-1, POINTS)  # one revolution, or a slower gear's period or a mesh cycle of them
        start = task.starts[i] if task.starts else 0
        if task.shaft:
            kept = shaft_row(task, revs, start, task.offsets[i] if task.offsets else 0, chain, noise, seed)
        elif task.noise_kind is None and not chain:  # clean: the TSA of J revolutions differs only over a period
            kept = revs[start] if len(revs) == 1 or not task.use_tsa else tsa(record(revs, task.revolutions, start))
        else:
            j = task.revolutions if task.use_tsa else 1  # the first of J revolutions is the same either way
            # J consecutive revolutions of one record, sampled at POINTS x speed
            realised = _realised(task, record(revs, j, start), chain, noise, seed, average=task.use_tsa)
            kept = realised if task.use_tsa else realised[0]
        out[i] = (kept - mean) / std  # eq. 2.112 / 4.6; TSA of standardised = standardised TSA
    return out


def _realised(task: RowsTask, revolutions: np.ndarray, chain, noise, seed, average: bool = False) -> np.ndarray:
    """Consecutive revolutions of a row's record realised at the task's speed (data.realise)."""
    fs = POINTS * task.speed_hz
    return realise(
        revolutions,
        chain,
        noise,
        Seeds.of_row(seed),
        fs=fs,
        speed_hz=task.speed_hz,
        reference_rms=task.reference_rms,
        average=average,
    )


def shaft_row(task: RowsTask, revs: np.ndarray, start: int, offset: int, chain, noise, seed) -> np.ndarray:
    """A row of the shaft turning p/q per input turn (task.shaft): enough consecutive input
    revolutions of the clean cycle *revs* from *start* realised as one record (signal effects,
    noise), then cut on that shaft's angle (signals.shaft) from its first whole turn: its first
    revolution, or the TSA of J. The shaft is at angle 0 where the simulation starts (the tacho's
    zero), so it is at p/q x (offset + start) turns where the row starts."""
    ratio = Fraction(*task.shaft)
    j = task.revolutions if task.use_tsa else 1
    count = math.ceil((j + 1) / ratio) + 1  # input revolutions that hold j whole turns of the shaft
    if len(revs) % ratio.denominator == 0:  # whole turns of the shaft: as a record's units (signals.shaft)
        revs = without_input_orders(revs, ratio.numerator)
    realised = _realised(task, record(revs, count, start), chain, noise, seed)
    phase = float((ratio * (offset + start)) % 1)
    turns = shaft_revolutions(realised, float(ratio), phase)[:j]
    return turns.mean(axis=0) if task.use_tsa else turns[0]


def row_tasks(
    spec: DatasetSpec,
    n: int,
    clean_of: Callable[[range], object],
    reference: tuple,
    speed: float,
    reference_rms: float,
    period_of: Callable[[int], int] = lambda i: 1,
    offset_of: Callable[[int], int] = lambda i: 0,
    starts_of: Callable[[int], int] | None = None,
) -> list[RowsTask]:
    """The row tasks of *spec*'s *n* samples, CHUNK samples a task: *clean_of(idx)* gives the clean
    revolutions of samples idx, each sample's row seed is row_seed(spec, i) (gearlab.data.realise),
    *reference* the domain's (mean, std); sample i's record starts at realise.first_revolution of its
    clean cycle, a whole number of *period_of(i)* (its damaged gear's period) in; or, for a long
    train's stretches, at *starts_of(i)*."""
    kind, snr = (spec.noise.kind, spec.noise.snr_db) if spec.noise else (None, 0.0)
    tasks = []
    for idx in (range(lo, min(n, lo + CHUNK)) for lo in range(0, n, CHUNK)):
        clean = clean_of(idx)
        starts = tuple(
            first_revolution(spec.seed, i, row.size // POINTS, period_of(i)) if starts_of is None else starts_of(i)
            for i, row in zip(idx, clean)
        )
        seeds = [row_seed(spec, i) for i in idx]
        tasks.append(
            RowsTask(
                clean,
                seeds,
                kind,
                snr,
                spec.revolutions,
                spec.tsa,
                reference,
                spec.effects,
                speed,
                reference_rms,
                starts,
                spec.unit_shaft,
                tuple(offset_of(i) for i in idx) if spec.unit_shaft else (),
            )
        )
    return tasks


def healthy_reference(spec: DatasetSpec, healthy: np.ndarray, speed: float, reference_rms: float) -> Standardiser:
    """The domain's healthy reference (eq. 2.112, 4.6): the clean healthy revolution (a later mesh's
    cycle of them), or 64 consecutive revolutions of it through the signal-level effects and the
    dataset's noise when it has them."""
    signal = EffectChain(EffectChain.load(spec.effects).at("signal")) if spec.effects else EffectChain()
    if spec.noise is None and not signal:
        return Standardiser.fit(healthy)
    realised = realise(
        record(healthy.reshape(-1, POINTS), 64),
        signal,
        spec.noise,
        Seeds.of_row(row_seed(spec, REFERENCE_ROW)),
        fs=POINTS * speed,
        speed_hz=speed,
        reference_rms=reference_rms,
    )
    return Standardiser.fit(realised)


def record_span(spec: DatasetSpec) -> int:
    """Consecutive input revolutions one record of *spec* takes (noisy_rows, shaft_row)."""
    j = spec.revolutions if spec.tsa else 1
    if not spec.unit_shaft:
        return j
    return math.ceil((j + 1) / Fraction(*spec.unit_shaft)) + 1


def stretch_of(spec: DatasetSpec, pairs, classes) -> int:
    """0 when *spec*'s train with every class's damage repeats within placement.MAX_PERIOD input
    turns (its rows: whole cycles), else the revolutions of each unit's stretch: STRETCH more than
    the longest record (and the healthy reference's 64) takes."""
    cycle = math.lcm(placement.mesh_cycle_of(pairs), *(on.period for on in classes.values()))
    if cycle <= placement.MAX_PERIOD:
        return 0
    return max(record_span(spec), 64) + STRETCH


def _unit_simulator(task: SimTask) -> Simulator:
    """The simulator simulate_unit makes for *task*."""
    if not task.effects:
        return _simulator(task.model, task.preset, task.fs)
    config = EffectChain.load(task.effects).model_config(config_of(task.model, task.preset, task.channel))
    return _configured_simulator(config, task.fs)


def _first_simulation() -> Callable[[], str]:
    """What the simulations' bar waits for before its first step, once it stood STANDING_S: the
    workers' start-up, imports and compiled loops (13 s at load 6 on 2 cores, the bar at 0 of 13 with
    no sign why: issue 41); nothing said before, so a warm pool's first step shows no line at all."""
    began = time.monotonic()

    def text() -> str:
        stood = time.monotonic() - began >= events.STANDING_S
        return "the first one starts up: imports, compiled loops" if stood else ""

    return text


def build_dataset(
    spec: DatasetSpec, executor: LocalExecutor | None = None, on_event: Callable[[Event], None] = lambda e: None
) -> Dataset:
    spec.check()
    executor = executor or LocalExecutor(1)
    registry = get_registry()
    model, pair, teeth = spec.check_model()
    speed, load = operating_point(spec)
    fs = whole_steps_rate(spec.fs, speed, pair.Z1)

    # 1. unique simulations: the healthy case and each fault intensity on tooth 1, shifted to every
    #    tooth; on every tooth itself when an effect or the model (a second mesh of another pitch)
    #    breaks the tooth-shift symmetry
    chain = spec.effect_chain() if spec.effects else EffectChain()
    cases = [(None, None)] + [(name, step) for name, steps in spec.faults for step in steps]
    classes = spec.fault_classes() if spec.faults else {}  # each class's gear and teeth

    def teeth_of(case):
        return teeth if case[0] is None else classes[case[0]].teeth

    symmetric = not chain.breaks_symmetry and not getattr(model, "breaks_symmetry", False)
    if symmetric:
        units = [(case, 1, teeth_of(case)) for case in cases]
    else:
        units = [(cases[0], 1, (1,))] + [(case, n, (n,)) for case in cases[1:] for n in teeth_of(case)]
    # a simulation sees the model- and excitation-level effects only (the signal-level ones act on
    # its rows, below), so datasets that differ in those alone share it (_SIMULATED)
    mechanical = tuple(e for e in spec.effects if registry.get("effect", e[0]).level != "signal")
    pairs = placement.train_pairs(model, spec.preset, f"dataset '{spec.name}'")
    stretch = stretch_of(spec, pairs, classes)  # 0, or a long train's revolutions per row (every unit's)
    tasks = [
        SimTask(spec.model, spec.preset, fs, speed, load, spec.channel, f, s, rows, mechanical, n, stretch, True)
        for (f, s), n, rows in units
    ]
    todo = [task for task in dict.fromkeys(tasks) if task not in _SIMULATED]
    if todo:
        reused = f" ({len(tasks) - len(todo)} done before)" if len(todo) < len(tasks) else ""
        settle = lambda: settle_revolutions(_simulator(spec.model, spec.preset, fs), speed)  # noqa: E731
        periods = [on.period for on in classes.values()]
        said = f"{spec.name}: {len(todo)} simulations{reused}" + (
            "" if stretch else cost(fs, speed, pairs, periods, len(todo), settle)
        )
        on_event(Event("stage", stage="simulate", total=len(todo), message=said))
    else:
        on_event(Event("log", message=f"{spec.name}: its {len(tasks)} simulations done before"))
    done = 0
    first = contextlib.ExitStack()  # the line that stands until the first simulation ends

    def advance(stage, total):
        def callback(i, result):
            nonlocal done
            done += 1
            first.close()
            on_event(Event("advance", stage=stage, done=done, total=total))

        return callback

    with first:
        if todo:
            first.enter_context(standing(on_event, "simulate", _first_simulation()))
        fresh = dict(zip(todo, executor.map(simulate_unit, todo, advance("simulate", len(todo)))))
    base: dict = {}  # each case's rows, teeth in order: arrays, or Rows a sample's task makes (data.rows)
    for (case, _, _), task in zip(units, tasks):
        base.setdefault(case, []).extend(entries(fresh[task] if task in fresh else _SIMULATED[task]))
    for task, rows in fresh.items():
        _remember(task, rows)

    # 2. the samples and their labels
    label, intensity, tooth, rfa, source = [], [], [], [], []
    for _ in range(spec.healthy):
        label.append(0), intensity.append(0), tooth.append(0), rfa.append(0.0), source.append(((None, None), 0))
    for c, (name, steps) in enumerate(spec.faults, start=1):
        on = classes[name]
        fault = registry.get("fault", on.name)
        view = on.pair.seen_from(on.gear)  # the plugin's ladder and area on the faulted gear
        for step in steps:
            area = fault.rfa(fault.at_step(view, step), view)
            for t_index, n in enumerate(on.teeth):
                for _ in range(spec.duplicates):
                    label.append(c), intensity.append(step), tooth.append(n), rfa.append(area)
                    source.append(((name, step), t_index))

    # 3. the domain's healthy reference (eq. 2.112, 4.6)
    reference_row = made(base[(None, None)][0])
    reference_rms = float(np.sqrt(np.mean(reference_row**2)))
    reference = healthy_reference(spec, reference_row, speed, reference_rms)

    # 4. signal effects, noise, TSA and standardisation, streamed in chunks
    n = len(label)

    def twin_of(i: int) -> tuple:
        """Where sample i's clean rows come from in the healthy twin (spec.healthy_twin): the healthy
        cycle as its fault's rows were made (from the same tacho zero: the later mesh at the same
        phase), turned as its tooth's rows are when one simulation serves every tooth of the input
        pinion; a fault on a slower gear starts a whole number of that gear's turns into its cycle,
        and its twin is then that far off."""
        (name, _), t = source[i]
        if name is None:
            return source[i]
        on = classes[name]
        turned = symmetric and (on.stage, on.gear) == (1, "pinion") and on.teeth[t] in teeth
        return ((None, None), teeth.index(on.teeth[t]) if turned else 0)

    def clean_of(idx: range):
        rows = [base[src[0]][src[1]] for src in (twin_of(i) if spec.healthy_twin else source[i] for i in idx)]
        if len({r.size for r in rows}) == 1 and all(isinstance(r, np.ndarray) for r in rows):
            return np.stack(rows)
        return rows  # rows of 1 or a period's revolutions; Rows made in the task

    # a sample of damage on a slower gear starts where its tooth meshes: a whole number of the gear's periods in;
    # cut on that gear's own shaft (unit_shaft) each turn holds every tooth at its angle: any revolution, as a
    # healthy row (where it meshes, a later stage's pinion's rows all at one: test_builder_later_stage_teeth)
    periods = {key: math.lcm(*(placement.gear_period(pairs, *p[1:]) for p in on.parts)) for key, on in classes.items()}
    shaft = {Fraction(*spec.unit_shaft)} if spec.unit_shaft else None
    turns = {k: {placement.gear_turns(pairs, *g[1:]) for g in on.parts} for k, on in classes.items()}
    periods.update({k: 1 for k in classes if turns[k] == shaft})

    def period_of(i: int) -> int:
        name = source[i][0][0]
        return 1 if name is None else periods[name]

    def offset_of(i: int) -> int:
        """The input revolution of its simulation at which sample i's clean row starts: where its
        tooth comes into mesh (period_turn), 0 for a healthy row; a twin, as its fault's row."""
        (name, _), t = source[i]
        if name is None:
            return 0
        on = classes[name]
        turns = Fraction(1)
        for pair in pairs[: on.stage - 1]:
            turns *= Fraction(pair.Z1, pair.Z2)
        order = turns * pairs[on.stage - 1].Z1  # the gear's teeth that mesh per input turn (the stage's mesh order)
        return math.floor((on.teeth[t] - 1) / order)

    offsets, starts_of = offset_of, None
    if stretch:  # a long train's rows: stretches from settle revolutions in, each record within its stretch
        settle = settle_revolutions(_unit_simulator(tasks[0]), speed)
        count = record_span(spec)

        def offsets(i: int) -> int:
            return settle

        def starts_of(i: int) -> int:
            (name, _), t = source[i]
            hits = None
            if name is not None:
                on = classes[name]
                hits = tooth_revolutions(pairs, on.stage, on.gear, on.teeth[t], settle, stretch)
            return stretch_start(spec.seed, i, stretch, count, hits)

    chunks = row_tasks(
        spec, n, clean_of, (reference.mean, reference.std), speed, reference_rms, period_of, offsets, starts_of
    )
    on_event(Event("stage", stage="samples", total=len(chunks), message=f"{spec.name}: {n} samples"))
    done = 0
    X = np.empty((n, POINTS), dtype=np.float32)
    for lo, rows in zip(range(0, n, CHUNK), executor.map(noisy_rows, chunks, advance("samples", len(chunks)))):
        X[lo : lo + len(rows)] = rows
    meta = {"fs_hz": fs, "speed_hz": speed, "load_nm": load, "Z1": pair.Z1}
    if spec.effects:  # what the model-level effects made of the source model
        config = spec.model_config()
        meta.update(model=model_of(config).name, channel=config.channel, simulations=len(tasks))
    return Dataset(
        spec=spec,
        X=X,
        label=np.asarray(label, dtype=np.int8),
        fault=(np.asarray(label) > 0).astype(np.int8),
        intensity=np.asarray(intensity, dtype=np.int8),
        tooth=np.asarray(tooth, dtype=np.int8 if max(tooth, default=0) < 128 else np.int16),
        rfa=np.asarray(rfa, dtype=np.float32),
        revolution=np.full(n, -1 if spec.tsa else 0, dtype=np.int16),
        domain=np.zeros(n, dtype=np.int8),
        domains=(spec.domain or spec.name,),
        reference=(reference.mean, reference.std),
        meta=meta,
    )
