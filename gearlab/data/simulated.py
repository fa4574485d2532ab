"""A simulated record of a gearbox as a user would record it: seconds of the housing acceleration
at the logger's sampling rate with a once-per-revolution tacho, for a speed, a load, damage on any
gear of the train, and sensor noise.

    from gearlab.data.simulated import simulated_record
    rec = simulated_record([{"name": "chip", "gear": "output gear", "tooth": 5, "step": 20}],
                           speed_hz=35.0, revolutions=60, snr_db=20.0, seed=3)
    rec.vibration, rec.tacho, rec.angle, rec.fs       # m/s², V, rad, Hz
    rec.write_csv("chipped_output.csv")               # time_s, acc_ms2, tacho_V

Defaults: the PHM 2009 rig (model two_stage, preset phm09, the housing's x channel, 66 666.67 Hz).
Any gearbox description instead, as a scenario's ``[source] gearbox`` simulates it:

    rec = simulated_record(gearbox="rig.toml", speed_hz=31.4, fs=25_000, sim_fs=200_000, snr_db=25)

A fault is a placement table (gearlab.data.placement: name, gear, stage, tooth, step or params)
or a PlacedFault.

Realisation, the dataset builder's (gearlab.data.builder): the rig is simulated at the nearest
rate above fs with a whole number of steps per tooth pitch until the response is steady
(builder.steady_response), one period of it kept: 1 input revolution for a healthy gearbox or a
faulted input pinion, the faulted shaft's period otherwise (3 input turns for the idler's gears,
5 for the output gear). The record repeats that period from a seeded random start, as a recording
starts anywhere in the gears' turns; it is read at the logger's sampling instants through its
Fourier series (components at or above fs/2 left out, as a logger's anti-alias filter does) and
a cubic spline on it 8 times oversampled. Then the signal-level effects and the sensor noise, as
every dataset's J revolutions get them (gearlab.data.realise; seeds [seed, 1] and [seed, 2]).
A train whose period exceeds placement.MAX_PERIOD input turns (19/47 + 23/59 + 29/71: 2773) is
simulated for the record's own turns after its transient has decayed (builder.steady_stretch), read
through a raised-cosine anti-alias filter (0.9 to 1 x fs/2); its start is counted from the gears' zero.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..effects import EffectChain, config_of, effects_from_tables
from ..errors import GearlabInputError, shown
from ..files import atomic_write
from ..physics.faults import place_fault
from ..physics.stiffness import PlacedFault
from ..registry import get_registry
from ..signals import NOISE_KINDS
from . import placement
from .builder import (
    _configured_simulator,
    _simulator,
    mesh_cycle,
    steady_response,
    steady_stretch,
    train_cycle,
    whole_steps_rate,
)
from .placement import gear_name, gear_of, shaft_names
from .realise import Seeds, realise
from .spec import PHM09_FS, NoiseSpec

TACHO_V = 5.0  # the tacho's high level, V (a TTL key-phasor)
TACHO_DUTY = 0.05  # share of a revolution the pulse is high
OVERSAMPLE = 8  # spline grid per simulated step: interpolation error ~1e-4 at the logger's Nyquist
PLACEMENT_KEYS = ("name", "gear", "stage", "tooth", "step", "params")
TAPER = 0.9  # a long train's record: the anti-alias filter's pass band, of fs/2 (_stretch_at)
STRETCH_MARGIN = 2  # input revolutions simulated before and after a long train's record (_stretch_at)


@dataclass(frozen=True)
class SimulatedRecord:
    """One simulated record: what a data logger on the gearbox would hold, and what made it."""

    vibration: np.ndarray  # m/s², the sensor channel at fs
    tacho: np.ndarray  # V, once-per-revolution pulses of the input shaft: rising edge (mid-level) at θ = 2πk
    angle: np.ndarray  # rad, the input shaft's continuous angle at each sample (θ = 0 at a tooth-1 mesh start)
    fs: float  # Hz
    speed_hz: float  # input shaft
    load_nm: float
    channel: str
    faults: tuple[str, ...]  # labels of the placed faults (PlacedFault.label)
    gears: tuple[str, ...]  # the faulted gears in words ("output gear", ...)
    period: int  # input revolutions after which the clean signal repeats (the faulted shaft's, the meshes')
    start: float  # input revolutions into the clean period at the first sample

    @property
    def t(self) -> np.ndarray:
        return np.arange(self.vibration.size) / self.fs

    def write_csv(self, path, sensitivity: float | None = None) -> Path:
        """The record as a CSV the importers read (docs/recordings.md): time_s, the vibration in m/s²
        (acc_ms2) or, with a *sensitivity* in V per m/s², in volts (acc_V), and tacho_V."""
        path = Path(path)
        if sensitivity is None:
            name, values = "acc_ms2", self.vibration
        else:
            name, values = "acc_V", self.vibration * sensitivity
        table = np.column_stack([self.t, values, self.tacho])
        lines = [f"time_s,{name},tacho_V"] + [f"{t:.9g},{v:.9g},{p:.6g}" for t, v, p in table]
        atomic_write(path, "\n".join(lines) + "\n")
        return path


def place(entries: Sequence, sim, preset: str, where: str = "faults") -> list[PlacedFault]:
    """Placement tables (or PlacedFaults, kept) -> PlacedFaults on the simulator's gears."""
    registry = get_registry()
    pairs = (sim.pair, *(m.pair for m in sim.meshes))
    shafts = shaft_names(preset, len(pairs))
    out = []
    for i, entry in enumerate(entries, start=1):
        here = f"{where} #{i}"
        if isinstance(entry, PlacedFault):
            out.append(entry)
            continue
        if not isinstance(entry, Mapping):
            raise GearlabInputError(
                f'{here}: expected a table {{name = "chip", gear = "output gear", tooth = 5, step = 20}}, '
                f"got {shown(entry)}"
            )
        unknown = [k for k in entry if k not in PLACEMENT_KEYS]
        if unknown:
            raise GearlabInputError(f"{here}: unknown key {shown(unknown[0])}; known: {', '.join(PLACEMENT_KEYS)}")
        if not isinstance(entry.get("name"), str):
            raise GearlabInputError(f"{here}: missing 'name' (a fault plugin: {', '.join(registry.names('fault'))})")
        stage, gear = gear_of(entry, shafts, here)
        step = entry.get("step")
        if step is None and entry.get("params") is None:
            raise GearlabInputError(f"{here}: give a ladder 'step' (1..20) or explicit 'params'")
        out.append(
            place_fault(
                registry,
                pairs[stage - 1],
                entry["name"],
                entry.get("tooth", 1),
                step,
                entry.get("params"),
                where=here,
                gear=gear,
                stage=stage,
            )
        )
    return out


def _periodic_at(x: np.ndarray, fs_sim: float, fs: float, times: np.ndarray) -> np.ndarray:
    """A periodic signal *x* (one period at fs_sim) at *times* (s), its components >= fs/2 left out: the
    periodic cubic spline through its band-limited samples OVERSAMPLE times denser.

    The spline is summed from cubic B-splines on that uniform grid, their coefficients c solved in the
    frequency domain: a spline through samples y has (c[k-1] + 4 c[k] + c[k+1]) / 6 = y[k], a circular
    convolution, so C = Y / ((4 + 2 cos(2 pi m / N)) / 6), divided into the spectrum the samples come
    from. The same spline scipy's CubicSpline(bc_type="periodic") builds (4e-12 of the peak apart, on a
    113,000-sample period), without its banded solve and its 4 x N polynomial table for a record that
    reads a fraction of the period (5 x less CPU; the which-gear events' simulated takes spent half
    their time there)."""
    n = x.size
    size = n * OVERSAMPLE
    spectrum = np.fft.rfft(x)
    m = np.arange(spectrum.size)
    spectrum[m * fs_sim / n >= fs / 2] = 0.0  # the logger's anti-alias filter
    spectrum *= OVERSAMPLE * 6.0 / (4.0 + 2.0 * np.cos(2.0 * np.pi * m / size))
    c = np.fft.irfft(spectrum, size)
    period = n / fs_sim
    u = np.mod(times, period) * (size / period)  # in grid steps
    j = np.floor(u)
    f = u - j
    j = j.astype(np.intp)
    f2, g = f * f, 1.0 - f
    # the four B-splines that reach an interval, at f in [0, 1) of it
    out = c[(j - 1) % size] * (g * g * g)
    out += c[j % size] * (3.0 * f2 * f - 6.0 * f2 + 4.0)
    out += c[(j + 1) % size] * (-3.0 * f2 * f + 3.0 * f2 + 3.0 * f + 1.0)
    out += c[(j + 2) % size] * (f2 * f)
    return out / 6.0


def anti_alias(f: np.ndarray, fs: float) -> np.ndarray:
    """A long train's record: the logger's anti-alias filter's gain at frequencies *f* (Hz), 1 up to
    TAPER x fs/2, a raised cosine down to 0 at fs/2."""
    lo, hi = TAPER * fs / 2, fs / 2
    return np.where(f <= lo, 1.0, np.where(f >= hi, 0.0, 0.5 + 0.5 * np.cos(np.pi * (f - lo) / (hi - lo))))


def _stretch_at(x: np.ndarray, fs_sim: float, fs: float, times: np.ndarray) -> np.ndarray:
    """A stretch *x* at fs_sim (not periodic) at *times* (s from its first sample): a logger's
    anti-alias filter (anti_alias) on its spectrum, then a cubic spline at OVERSAMPLE points per
    cycle of fs/2 at least. The filter's reach (a few hundred fine steps) wraps round the stretch's
    ends: STRETCH_MARGIN revolutions there are not read."""
    from scipy.interpolate import CubicSpline

    over = max(1, math.ceil(OVERSAMPLE * fs / fs_sim))
    spectrum = np.fft.rfft(x) * anti_alias(np.arange(x.size // 2 + 1) * fs_sim / x.size, fs)
    fine = np.fft.irfft(spectrum, x.size * over) * over
    return CubicSpline(np.arange(fine.size) / (fs_sim * over), fine)(times)


def _stretch_record(sim, placed, speed_hz, load_nm, channel, excitation, rng, revolutions, fs, n):
    """A long train's record (builder.steady_stretch): its grand period, the start in it (input turns
    from the zero at which every gear starts: the settle revolutions, a margin and a draw within a
    turn of the slowest shaft), the vibration, the input angle, and the stretch when it is healthy."""
    speeds = [sim.gear_turns(s, g) for s in range(1, sim.stages + 1) for g in ("pinion", "wheel")]
    offset = float(rng.uniform(0.0, 1.0 / min(speeds)))  # anywhere in the slowest shaft's turn
    count = math.ceil(offset + revolutions) + 2 * STRETCH_MARGIN
    x, moved, settle = steady_stretch(sim, placed, speed_hz, load_nm, channel, excitation, count)
    fs_sim = sim.fs
    times = (STRETCH_MARGIN + offset) / speed_hz + np.arange(n) / fs
    vibration = _stretch_at(x, fs_sim, fs, times)
    start = settle + STRETCH_MARGIN + offset
    angle = 2 * np.pi * speed_hz * (start / speed_hz + np.arange(n) / fs)
    if moved is not None:  # an excitation effect moved the shaft: its deviation from the nominal
        nominal = 2 * np.pi * np.arange(moved.size) / (fs_sim / speed_hz)
        angle = angle + np.interp(times * fs_sim, np.arange(moved.size), moved - nominal)
    return train_cycle(sim, placed), start, vibration, angle, None if placed else x


def tacho_pulses(angle: np.ndarray, step: float) -> np.ndarray:
    """Once-per-revolution pulses (TACHO_V high for TACHO_DUTY of a turn) whose rising edge crosses the
    mid-level exactly at θ = 2πk: a two-sample linear ramp, so the importers' edge interpolation
    (signals.angle_from_pulses) reads the crossing without a quantisation error. *step*: θ per sample."""
    phase = np.mod(angle + np.pi, 2 * np.pi) - np.pi  # θ - 2πk in [-π, π)
    ramp = np.clip(phase / (2 * step) + 0.5, 0.0, 1.0)
    return TACHO_V * np.where(phase < 2 * np.pi * TACHO_DUTY, ramp, 0.0)


def _what_to_simulate(gearbox, model, preset, channel, speed_hz, load_nm) -> tuple[str, str, str, float, float]:
    """(model, preset, channel, speed, load): a description's (module doc of gearlab.gearbox.simulation)
    where one is named, else the PHM 2009 rig's; what the caller gives wins."""
    if gearbox is None:
        return (
            model or "two_stage",
            preset or "phm09",
            channel or "casing_x",
            30.0 if speed_hz is None else speed_hz,
            20.0 if load_nm is None else load_nm,
        )
    from ..gearbox.simulation import channel as sensor_channel
    from ..gearbox.simulation import model_name, reference, referenced

    if preset is not None:
        raise GearlabInputError(
            f"simulated record: give a 'gearbox' description or a 'preset', not both (got {shown(preset)})"
        )
    try:
        ref = reference(str(gearbox))
    except OSError as exc:
        raise GearlabInputError(f"{gearbox}: cannot read the gearbox description ({exc.strerror or exc})") from None
    box = referenced(ref)
    model = model or model_name(box)
    channel = channel or sensor_channel(box, model, get_registry().get("model", model).channels)
    speed_hz = box.speed_hz if speed_hz is None else speed_hz
    load_nm = box.torque(load_nm)  # times the description's load_level
    for key, value in (("speed", speed_hz), ("load", load_nm)):
        if value is None:
            raise GearlabInputError(
                f"{box.source}: [operation] key '{key}': missing, and the simulated record was given none"
            )
    return model, ref, channel, speed_hz, load_nm


def simulated_record(
    faults: Sequence = (),
    *,
    speed_hz: float | None = None,
    load_nm: float | None = None,
    revolutions: float = 60.0,
    snr_db: float | None = None,
    noise_kind: str = "gaussian",
    effects: Sequence = (),
    seed: int = 0,
    fs: float = PHM09_FS,
    model: str | None = None,
    preset: str | None = None,
    channel: str | None = None,
    gearbox: str | None = None,
    sim_fs: float | None = None,
    own_step: bool = True,
) -> SimulatedRecord:
    """A record of *revolutions* input turns at *fs* of *channel* of *model*/*preset* at *speed_hz* and
    *load_nm*, with *faults* (placement tables or PlacedFaults), *effects* (scenario tables, e.g.
    ``{name = "sensor_lowpass", ...}``) and sensor noise at *snr_db* (dB against the record's RMS, of
    *noise_kind*; None: none). *seed* draws the start in the gears' period and the noise.

    *gearbox*: a description (a file or a built-in name) simulated as a ``[source] gearbox`` is
    (gearlab.gearbox.simulation): its model, its [sensor]'s channel, its [operation] speed and load
    unless given. Else the PHM 2009 rig (two_stage, phm09, casing_x, 30 Hz, 20 N m). *sim_fs*: the
    model's integration rate (default *fs*); a logger's rate is often too low for a stiff mesh's
    natural frequencies, so a description's record is simulated faster and read at *fs*. The simulator
    picks its own step: the rate is raised where lower to 10 steps per period of the model's highest
    natural frequency (Simulator.fs_floor), no warning a user cannot act on; *own_step* False keeps
    the caller's rate (and its warning)."""
    where = "simulated record"
    model, preset, channel, speed_hz, load_nm = _what_to_simulate(gearbox, model, preset, channel, speed_hz, load_nm)
    for key, value, low in (
        ("speed_hz", speed_hz, 0.0),
        ("revolutions", revolutions, 0.0),
        ("fs", fs, 0.0),
        ("sim_fs", fs if sim_fs is None else sim_fs, 0.0),
    ):
        if isinstance(value, bool) or not isinstance(value, int | float) or not (math.isfinite(value) and value > low):
            raise GearlabInputError(f"{where}: '{key}' must be a positive number, got {shown(value)}")
    if snr_db is not None and noise_kind not in NOISE_KINDS:
        raise GearlabInputError(
            f"{where}: 'noise_kind' must be one of {', '.join(NOISE_KINDS)}, got {shown(noise_kind)}"
        )
    registry = get_registry()
    chain = EffectChain.load(effects_from_tables(list(effects), f"{where}: effects")) if effects else EffectChain()
    base = registry.get("model", model, where)
    pair, _ = base.resolve(preset, where=where)
    fs_sim = whole_steps_rate(fs if sim_fs is None else max(sim_fs, fs), speed_hz, pair.Z1)
    config = chain.model_config(config_of(model, preset, channel, where), where) if chain else None

    def simulator(rate: float, warn: bool):
        return _configured_simulator(config, rate, warn) if chain else _simulator(model, preset, rate, warn)

    sim = simulator(fs_sim, not own_step)
    if own_step and sim.fs < sim.fs_floor:  # the record is read at fs: whole steps per tooth pitch
        sim = simulator(whole_steps_rate(sim.fs_floor, speed_hz, pair.Z1), False)
        fs_sim = sim.fs
    if chain:
        excitation, channel = chain.at("excitation"), config.channel
    else:
        excitation = ()
        if channel not in base.channels:
            raise GearlabInputError(
                f"{where}: model '{model}' has no channel '{channel}'; its channels: {', '.join(base.channels)}"
            )
    placed = place(list(faults), sim, preset)
    shafts = shaft_names(preset, sim.stages)
    rng = np.random.default_rng([seed, 0])
    n = int(math.ceil(revolutions * fs / speed_hz))
    long = train_cycle(sim, placed) > placement.MAX_PERIOD
    if long:  # a long train: a stretch of steady revolutions, not its period
        period, start, vibration, angle, healthy = _stretch_record(
            sim, placed, speed_hz, load_nm, channel, excitation, rng, revolutions, fs, n
        )
    else:
        # the whole cycle: a later mesh of no whole input order repeats only after mesh_cycle turns
        clean, moved = steady_response(sim, placed, speed_hz, load_nm, channel, excitation, whole_cycle=True)
        period = math.lcm(sim.period(placed), mesh_cycle(sim))
        start = float(rng.uniform(0.0, period))  # input turns into the clean period at the first sample
        times = (start / speed_hz) + np.arange(n) / fs
        vibration = _periodic_at(clean, fs_sim, fs, times)
        angle = 2 * np.pi * speed_hz * times
        if moved is not None:  # an excitation effect moved the shaft: its (periodic) deviation from the nominal
            nominal = 2 * np.pi * np.arange(moved.size) / (fs_sim / speed_hz)
            deviation = np.interp(np.mod(times, period / speed_hz) * fs_sim, np.arange(moved.size), moved - nominal)
            angle = angle + deviation
        healthy = None
    angle = angle - 2 * np.pi * math.floor(angle[0] / (2 * np.pi))  # the first sample in [0, 2π)
    signal = EffectChain(chain.at("signal"))
    rms = 0.0  # the signal effects' reference: the clean healthy signal's RMS (a simulation: only when needed)
    if signal:
        if healthy is None and long:
            healthy = steady_stretch(sim, [], speed_hz, load_nm, channel, excitation, 64)[0]
        elif healthy is None:
            healthy, _ = steady_response(sim, [], speed_hz, load_nm, channel, excitation)
        rms = float(np.sqrt(np.mean(healthy**2)))
    noise = None if snr_db is None else NoiseSpec(noise_kind, snr_db)
    vibration = realise(
        vibration[None, :], signal, noise, Seeds([seed, 1], [seed, 2]), fs=fs, speed_hz=speed_hz, reference_rms=rms
    )[0]
    return SimulatedRecord(
        vibration=vibration,
        tacho=tacho_pulses(angle, 2 * np.pi * speed_hz / fs),
        angle=angle,
        fs=float(fs),
        speed_hz=float(speed_hz),
        load_nm=float(load_nm),
        channel=channel,
        faults=tuple(f.label for f in placed),
        gears=tuple(gear_name(f.stage, f.gear, shafts) for f in placed),
        period=period,
        start=start,
    )
