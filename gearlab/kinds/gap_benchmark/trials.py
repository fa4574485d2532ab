"""The blind benchmark of the gap diagnosis (docs/gap_benchmark.md).

Each trial hides a configuration — one effect, two effects, no effect (the null), or one
effect that is kept out of the candidate list (out of library) — with parameters drawn in
the range where the effect is visible at all, simulates the target through the dataset
builder, WRITES it to disk as a measured record, and diagnoses it from the file alone:

    draw_trials(...)  ─► Trial (hidden: effects and parameters; public: candidate list)
    write_target(trial, source, folder)
        ─► folder/target.npz      the measured record: vibration, tacho, label, fs — nothing else
        ─► folder/answers.json    the generator's choices, read back only to score
    diagnose_file(path, source, candidates, settings)          <- never sees the Trial
        ─► MeasuredSpec ─► import_measured ─► healthy_rows ─► gearlab.gap.diagnose.diagnose
    score_trial(answers, result)  ─► one record (top-1, top-3, parameter error, shrink, ...)

The separation is structural: :func:`diagnose_file` takes only the path, the source spec
(the simulator configuration, without the hidden effects), the candidate names and the
search settings, and :func:`trial_task` hands it nothing else (tests/test_gap_benchmark.py
inspects the pickled arguments). Every function here is top-level and every argument a
plain value, so trials run in parallel through any gearlab executor.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...confined import Confined
from ...data.spec import DatasetSpec, NoiseSpec
from ...errors import GearlabInputError
from ...events import told_unit, unit_says
from ...settings import declared

# --- the trial mix ----------------------------------------------------------------------------

# Fixed proportions of the four trial kinds (docs/gap_benchmark.md): in 40 trials 20 single
# effects, 6 pairs, 6 nulls and 8 out-of-library effects — at least 4 of each kind the
# acceptance criteria are stated on.
MIX = (("single", 0.50), ("pair", 0.15), ("null", 0.15), ("withheld", 0.20))
KINDS = tuple(k for k, _ in MIX)
# Trial kinds outside the mix, drawn only when [benchmark] kinds names them (so the mix's draws stay
# what they were for every seed): "suborder" hides an interfering tone below one shaft order or
# between the first orders, which one revolution cannot place (a 37.3 Hz tone at 40 Hz came back at
# 23.6 or 55 Hz while the search's source gave each revolution its own tone phase); it needs the
# target's revolutions read as consecutive ones (gearlab.gap.scoring.measured_rows).
EXTRA_KINDS = ("suborder",)
EFFECT_KINDS = ("single", "pair", "suborder")  # scored by the effect named first
SUBORDER_ORDERS = (0.15, 2.9)  # the tone's frequency in shaft orders, log-uniform ...
SUBORDER_CLEAR = 0.05  # ... at least this far from a whole order (a shaft line's own place)

# The measured record's channel names: the file convention of the benchmark, public to both sides.
VIBRATION, TACHO, LABEL = "acc", "tacho", "condition"

# Base sensor noise of every simulation, source and target alike, unless the source says
# otherwise: a real accelerometer is never noise-free, and a noise-free source makes every
# healthy revolution identical (zero spread), so any difference at all reads as infinitely
# significant. 30 dB (signal 1000x the noise power) is a good measurement; independent
# realisations in source and target (different seeds).
BASE_NOISE = NoiseSpec("gaussian", 30.0, 0)

# Parameter ranges the generator draws from, per effect: {param: (low, high, scale)} with scale
# "log" (log-uniform), "lin" (uniform), "int" (whole numbers, uniform) or "circ" (an angle,
# uniform over the turn); a list of ranges means one of them at random (to stay away from a
# neutral value such as a factor of 1). Parameters not named keep the effect's default and are
# not scored; options are drawn uniformly. Why these ranges: plausible values that are clearly
# visible against the base noise with 40-80 healthy revolutions on Dataset B (measured with
# gap_report; docs/gap_benchmark.md has the table). Effects not listed (third-party plugins)
# draw every parameter over its declared bounds.
RANGES: dict[str, dict[str, object]] = {
    "casing_path": {"mf": (5.0, 50.0, "log"), "k_xf": (5e7, 1e9, "log"), "k_yf": (5e7, 1e9, "log")},
    "drive_inertias": {"I11": (1e-3, 2e-2, "log"), "I22": (1e-3, 2e-2, "log"), "k_c": (3e3, 1e5, "log")},
    "bearing_stiffness": {"k_factor": [(0.3, 0.75, "log"), (1.4, 3.0, "log")]},
    "mesh_damping": {"zeta": [(0.02, 0.05, "lin"), (0.1, 0.2, "lin")]},
    "speed_fluctuation": {
        "amplitude": (0.002, 0.03, "log"),
        "order": (1, 4, "int"),
        "phase": (0.0, 2 * math.pi, "circ"),
    },
    "load_fluctuation": {"amplitude": (0.05, 0.3, "log"), "order": (1, 4, "int"), "phase": (0.0, 2 * math.pi, "circ")},
    # weak on six_dof (E6: ~3e-4 of the mesh lines at 20 um): only the top of its bounds shows
    "shaft_eccentricity": {"e": (150e-6, 200e-6, "lin"), "phase": (0.0, 2 * math.pi, "circ")},
    "tooth_friction": {"mu_f": (0.02, 0.15, "lin")},
    "fillet_correction": {"lam": (0.1, 0.6, "lin")},
    "sensor_noise": {"snr_db": (-5.0, 20.0, "lin")},
    "sensor_bandwidth": {"f_n": (3e3, 3e4, "log"), "zeta": (0.05, 0.7, "log")},
    # the anti-alias filter: corners inside every drawn record's passband (>= 22 kHz), 2 to 6 poles
    "sensor_lowpass": {"f_c": (2e3, 1.5e4, "log"), "order": (2, 6, "int")},
    "interference_tone": {"frequency": (10.0, 2000.0, "log"), "ratio": (0.05, 0.5, "log")},
}

MIN_TARGET_REVOLUTIONS = 10  # gearlab.gap.stats.MIN_REVOLUTIONS: fewer and no statistic means much

# How a target is acquired and written (pipeline parity with measured records): a real record is
# sampled at its own rate, so its revolutions start between samples; its tacho mark sits anywhere
# on the shaft; it may store integers. Every trial draws: the samples per revolution as a share
# of the simulation's 4096
# (RATE_SHARES, uniform), the tacho's zero off the simulation's (uniform over the turn) and a
# FORMAT: float64 npz, int16 npz (counts, with a gain) or int16 PCM wav (full-scale fractions).
RATE_SHARES = (0.3, 0.7)
FORMATS = ("npz", "npz-int16", "wav")
# An integer record's full scale: this many times the record's largest value (an acquisition's
# headroom); int16 then rounds to 1/32767 of it.
HEADROOM = 4.0
# The written sensitivity (V per m/s²) and, for integers, gain (V per count / at full scale): the
# calibration sheet beside the record (calibration.json), public to both sides.
SENSITIVITY = 0.01 / 9.80665  # 10 mV/g


@dataclass(frozen=True)
class Acquisition:
    """How a trial's target record is written: rate share, tacho offset (rad), format."""

    rate_share: float
    offset: float
    format: str

    @classmethod
    def draw(cls, rng: np.random.Generator) -> Acquisition:
        return cls(
            float(rng.uniform(*RATE_SHARES)),
            float(rng.uniform(0.0, 2 * math.pi)),
            FORMATS[int(rng.integers(len(FORMATS)))],
        )


def trial_counts(n: int) -> dict[str, int]:
    """Trials per kind for *n* trials: MIX by largest remainder; from 4 trials on, every kind at least once."""
    raw = {k: p * n for k, p in MIX}
    counts = {k: int(math.floor(v)) for k, v in raw.items()}
    order = sorted(KINDS, key=lambda k: (-(raw[k] - counts[k]), KINDS.index(k)))
    for k in order[: n - sum(counts.values())]:
        counts[k] += 1
    if n >= len(KINDS):
        for k in KINDS:
            if counts[k] == 0:
                counts[max(counts, key=counts.get)] -= 1
                counts[k] = 1
    return counts


@dataclass(frozen=True)
class Trial:
    """One trial. *hidden* and *withheld* are the generator's secret; *candidates* is public."""

    index: int
    kind: str  # single | pair | null | withheld
    hidden: tuple  # canonical effect specs ((name, ((param, value), ...)), ...), level-ordered
    withheld: str | None  # the effect kept out of the candidate list (kind "withheld")
    candidates: tuple[str, ...]
    seed: int  # the target's noise and signal-effect seed
    acquisition: Acquisition | None = None  # None: the angle-domain record (fs = 4096 x speed, exact starts)


def _draw_value(rng: np.random.Generator, rule) -> float:
    if isinstance(rule, list):
        rule = rule[int(rng.integers(len(rule)))]
    low, high, scale = rule
    if scale == "log":
        return float(math.exp(rng.uniform(math.log(low), math.log(high))))
    if scale == "int":
        return int(rng.integers(int(low), int(high) + 1))
    return float(rng.uniform(low, high))


def draw_params(effect, rng: np.random.Generator) -> dict:
    """Hidden parameters of *effect*: RANGES where it has an entry, else its declared bounds."""
    rules = RANGES.get(effect.name)
    out: dict = {}
    if rules is None:
        for name, (p, _) in declared(effect.params).items():
            scale = "int" if p.integer else ("log" if name in effect.log_scale and p.low > 0 else "lin")
            out[name] = _draw_value(rng, (p.low, p.high, scale))
    else:
        for name, rule in rules.items():
            out[name] = _draw_value(rng, rule)
    for name, choices in effect.options.items():
        out[name] = choices[int(rng.integers(len(choices)))]
    return out


def draw_trials(n: int, seed: int, library: Sequence[str], source: DatasetSpec, registry=None) -> list[Trial]:
    """*n* trials, a function of (n, seed, library, source) only. Single and withheld effects go
    round the library in a seeded order, so every effect is hidden about equally often."""
    from ...effects import EffectChain
    from ...registry import get_registry

    registry = registry or get_registry()
    library = tuple(library)
    if n < 1:
        raise GearlabInputError(f"benchmark: trials must be >= 1, got {n}")
    if len(library) < 2:
        raise GearlabInputError(
            f"benchmark: the library needs at least 2 effects (pairs, withheld), got {len(library)}"
        )
    rng = np.random.default_rng([seed, 0])
    kinds = [k for k, c in trial_counts(n).items() for _ in range(c)]
    kinds = [kinds[i] for i in rng.permutation(n)]
    singles = [library[i] for i in rng.permutation(len(library))]
    withheld = [library[i] for i in rng.permutation(len(library))]
    used = {"single": 0, "withheld": 0}
    trials = []
    for index, kind in enumerate(kinds):
        r = np.random.default_rng([seed, 1, index])
        for _attempt in range(20):  # a drawn combination the model cannot take is drawn again
            if kind == "null":
                names: tuple[str, ...] = ()
            elif kind == "pair":
                names = tuple(library[i] for i in r.choice(len(library), 2, replace=False))
            else:
                cycle = singles if kind == "single" else withheld
                names = (cycle[(used[kind] + _attempt) % len(cycle)],)
            specs = tuple(
                registry.get("effect", name).spec(draw_params(registry.get("effect", name), r)) for name in names
            )
            try:
                hidden = EffectChain.load(specs).specs()  # level order, as the builder applies them
                source.with_(effects=hidden).check_model("benchmark target")
                break
            except GearlabInputError:
                continue
        else:  # pragma: no cover - every built-in effect acts on the default source
            raise GearlabInputError(f"benchmark: could not draw a {kind} configuration that acts on {source.name}")
        if kind in used:
            used[kind] += 1
        out = names[0] if kind == "withheld" else None
        candidates = tuple(e for e in library if e != out)
        trial_seed = int(r.integers(1, 2**31 - 1))
        acquisition = Acquisition.draw(np.random.default_rng([seed, 2, index]))
        trials.append(Trial(index, kind, hidden, out, candidates, trial_seed, acquisition))
    return trials


def draw_suborder_trials(n: int, seed: int, library: Sequence[str], source: DatasetSpec, first: int = 0) -> list:
    """*n* "suborder" trials (EXTRA_KINDS), a function of (n, seed, library, source) only: an
    interference tone at SUBORDER_ORDERS shaft orders (not within SUBORDER_CLEAR of a whole one), its
    level from RANGES, every library effect a candidate. Indices from *first* on."""
    from ...data.builder import operating_point
    from ...registry import get_registry

    if "interference_tone" not in library:
        raise GearlabInputError("benchmark: 'suborder' trials hide an interference_tone, which the library lacks")
    speed, _ = operating_point(source)
    tone = get_registry().get("effect", "interference_tone")
    trials = []
    for k in range(n):
        r = np.random.default_rng([seed, 3, k])
        while True:
            order = math.exp(r.uniform(*np.log(SUBORDER_ORDERS)))
            if abs(order - round(order)) >= SUBORDER_CLEAR:
                break
        ratio = _draw_value(r, RANGES["interference_tone"]["ratio"])
        hidden = (tone.spec({"frequency": order * speed, "ratio": ratio}),)
        acquisition = Acquisition.draw(np.random.default_rng([seed, 4, k]))
        trials.append(
            Trial(first + k, "suborder", hidden, None, tuple(library), int(r.integers(1, 2**31 - 1)), acquisition)
        )
    return trials


# --- generating the target (knows the answer) --------------------------------------------------


def target_spec(trial: Trial, source: DatasetSpec, revolutions: int) -> DatasetSpec:
    """The hidden configuration: the source with the hidden effects and its own noise realisation."""
    noise = source.noise if source.noise is None else NoiseSpec(source.noise.kind, source.noise.snr_db, trial.seed)
    return source.with_(
        name="target",
        domain="target",
        healthy=revolutions,
        faults=(),
        effects=source.effects + trial.hidden,
        seed=trial.seed,
        noise=noise,
    )


def record_of(rows: np.ndarray) -> dict[str, np.ndarray]:
    """Revolutions (n, P) in physical units -> a measured record, as an acquisition would store it:
    the vibration one revolution after another at fs = P x speed (the angle-domain revolutions
    taken as uniform in time, E3), a wrapped shaft-angle tacho that starts a revolution every P
    samples, a whole-record condition label and the rate. An eighth of a revolution more closes
    the last one whatever the rounding of the unwrapped angle (the importer keeps complete
    revolutions only, and drops the incomplete tail)."""
    n, points = rows.shape
    vib = np.concatenate([rows.reshape(-1), rows[0, : points // 8]])
    i = np.arange(vib.size)
    tacho = 2 * np.pi * ((i % points) / points)  # exactly 0 where a revolution starts
    return {VIBRATION: vib, TACHO: tacho, LABEL: np.array("healthy")}


def acquired_record(
    rows: np.ndarray, speed: float, acquisition: Acquisition, noise: Callable[[np.ndarray, float], np.ndarray]
) -> tuple[dict, float]:
    """Noise-free revolutions (n, P) in m/s², one after another, as an acquisition records them:
    read at acquisition.rate_share x P samples per revolution (a multiple of 1/n: revolutions start
    between samples) by Fourier resampling of the n-turn record (an ideal anti-alias filter below the
    new Nyquist), turned so that the tacho's zero sits at acquisition.offset of the simulation's
    revolution, noise added in time by *noise(x, fs)*. Returns (channels in m/s², fs). The tacho
    is a once-per-revolution pulse whose rising edge is a two-sample ramp through the true start
    (so the importer's edge interpolation finds it between samples)."""
    n, P = rows.shape
    total = int(round(acquisition.rate_share * P * n))
    per_rev = total / n
    fs = per_rev * speed
    F = np.fft.rfft(rows.reshape(-1))
    m = np.arange(F.size)
    F = F * np.exp(2j * np.pi * m * (acquisition.offset / (2 * np.pi)) / n)  # x(θ + offset)
    keep = (total + 1) // 2  # bins strictly below the new Nyquist
    G = np.zeros(total // 2 + 1, dtype=complex)
    G[:keep] = F[:keep] * (total / (n * P))
    vib = noise(np.fft.irfft(G, n=total), fs)
    d = (np.arange(total) / per_rev) % 1.0 * per_rev  # samples since the last revolution start
    d = np.where(d < per_rev / 2, d, d - per_rev)
    tacho = np.clip(0.5 + d / 2.0, 0.0, 1.0) * (d > -1.0)
    return {VIBRATION: vib, TACHO: tacho, LABEL: np.array("healthy")}, fs


def stored(record: dict, fs: float, fmt: str) -> tuple[bytes, str, dict]:
    """(file bytes, file name, calibration) of a record in m/s² in *fmt* (FORMATS): the vibration in
    volts through SENSITIVITY; int16 formats rounded to 1/32767 of HEADROOM x its largest value,
    their gain (V per count, or at full scale for WAV) in the calibration."""
    import io

    volts = record[VIBRATION] * SENSITIVITY
    calibration = {"sensitivity": SENSITIVITY}
    buf = io.BytesIO()
    if fmt == "npz":
        np.savez(buf, **{**record, VIBRATION: volts, "fs": np.array(fs)})
        return buf.getvalue(), "target.npz", calibration
    full = HEADROOM * float(np.max(np.abs(volts)))
    counts = np.round(volts / full * 32767).astype(np.int16)
    if fmt == "npz-int16":
        np.savez(buf, **{**record, VIBRATION: counts, "fs": np.array(fs)})
        return buf.getvalue(), "target.npz", {**calibration, "gain": full / 32767}
    from scipy.io import wavfile

    # WAV has no room for the rate's fraction or a label: the rate is rounded to whole Hz, which
    # the tacho's own speed measure makes harmless; the record is taken as healthy (unlabelled).
    pulses = np.round(record[TACHO] * 16000).astype(np.int16)
    wavfile.write(buf, int(round(fs)), np.stack([counts, pulses], axis=1))
    return buf.getvalue(), "target.wav", {**calibration, "gain": full * 32768 / 32767}


def _held(folder: Path | str | Confined) -> Confined:
    """The trial's folder, reached through Confined: a run directory's targets/trial_NNN as the
    kind gives it, or a plain folder (a test, a benchmark script) below its trusted parent."""
    if isinstance(folder, Confined):
        return folder
    folder = Path(folder)
    return Confined(folder.parent, (folder.name,))


def write_target(trial: Trial, source: DatasetSpec, folder: Path | Confined, revolutions: int, executor=None) -> Path:
    """Simulate the trial's target, write it as folder/target.<ext> (with folder/calibration.json)
    and the answers as folder/answers.json; the path of the target for the importer to read."""
    from ...data.builder import build_dataset, operating_point
    from ...data.realise import EFFECT_STREAM, Seeds, parts, realise
    from ...effects import EffectChain
    from ...gap.views import healthy_rows

    folder = _held(folder)
    spec = target_spec(trial, source, revolutions)
    speed, _ = operating_point(spec)
    acq = trial.acquisition
    if acq is None:
        dataset = build_dataset(spec, executor)
        rows = healthy_rows(dataset)
        record = record_of(rows)
        record["fs"] = np.array(rows.shape[1] * speed)
        import io

        buf = io.BytesIO()
        np.savez(buf, **record)
        data, name, calibration = buf.getvalue(), "target.npz", None
    else:
        # The deterministic target (every effect but noise), then the noise in time at the record's rate.
        # The signal effects act on the record, one revolution after another, as in an acquisition: a
        # tone that is not shaft-synchronous runs on across revolutions (the builder's rows would give
        # each revolution its own tone phase, which no measured record has).
        # Seeds (gearlab.data.realise): the non-noise effects [seed, EFFECT_STREAM, 1], the noise
        # effects [seed, EFFECT_STREAM], the dataset's noise [seed, 5].
        chain = EffectChain.load(spec.effects)
        signal = {item[0].name for item in chain.at("signal")}
        shaping, noisy = parts(chain)
        physics = tuple(e for e in spec.effects if e[0] not in signal)
        rows = healthy_rows(build_dataset(spec.with_(noise=None, effects=physics), executor))
        rms = float(np.sqrt(np.mean(rows**2)))  # the healthy reference RMS the builder's effects take
        rows = realise(
            rows,
            shaping,
            None,
            Seeds([trial.seed, EFFECT_STREAM, 1], ()),
            fs=rows.shape[1] * speed,
            speed_hz=speed,
            reference_rms=rms,
        )
        rms = float(np.sqrt(np.mean(rows**2)))

        def noise(x: np.ndarray, fs: float) -> np.ndarray:
            seeds = Seeds([trial.seed, EFFECT_STREAM], [trial.seed, 5])
            return realise(x[None, :], noisy, spec.noise, seeds, fs=fs, speed_hz=speed, reference_rms=rms)[0]

        record, fs = acquired_record(rows, speed, acq, noise)
        data, name, calibration = stored(record, fs, acq.format)
    (folder / name).write(data)
    if calibration is not None:
        (folder / "calibration.json").write(json.dumps(calibration, indent=1, sort_keys=True))
    answers = {
        "index": trial.index,
        "kind": trial.kind,
        "withheld": trial.withheld,
        "hidden": [[name, dict(params)] for name, params in trial.hidden],
        "seed": trial.seed,
        "candidates": list(trial.candidates),
        "acquisition": None
        if acq is None
        else {"rate_share": acq.rate_share, "offset_deg": math.degrees(acq.offset), "format": acq.format},
    }
    (folder / "answers.json").write(json.dumps(answers, indent=1, sort_keys=True))
    return (folder / name).path


def read_answers(folder: Path | Confined) -> dict:
    return json.loads((_held(folder) / "answers.json").read_bytes())


# --- the diagnosis (knows only the file) ---------------------------------------------------------


def import_target(path: Path):
    """The healthy revolutions of a written target, in physical units (the file's values where it has
    no calibration beside it), through the importer, and its measurement chain (None for the
    angle-domain record, which has none to match)."""
    from ...data.chain import chain_of
    from ...data.importers import MeasuredSpec, import_measured
    from ...gap.views import healthy_rows

    path = Path(path)
    calibration = path.parent / "calibration.json"
    units = json.loads(calibration.read_text()) if calibration.exists() else {}
    wav = path.suffix == ".wav"
    # transient 'none': the record is steady from its first sample (a simulated steady state)
    spec = MeasuredSpec(
        name="target",
        path=str(path),
        vibration="0" if wav else VIBRATION,
        tacho="1" if wav else TACHO,
        labels=None if wav else LABEL,
        transient="none",
        **units,
    )
    dataset = import_measured(spec)
    rows = (
        healthy_rows(dataset)
        if not wav
        else np.asarray(dataset.X, np.float64) * dataset.reference[1] + dataset.reference[0]
    )
    chain = chain_of(dataset.meta)
    if chain.samples_per_rev == rows.shape[1] and not any(chain.fractions) and not chain.step:
        return rows, None, 0  # the angle-domain record: the importer's resampling is the identity
    # Any other record goes through its chain, calibrated or not: a record written elsewhere, with no
    # calibration beside it, had its noise order-tracked by the importer, which the source's noise
    # must be too (else a 200 kHz null was 'explained' by a sensor resonance at its 100 kHz bound).
    return rows, chain, chain.max_order


def _diagnose(
    source: DatasetSpec,
    target_X: np.ndarray,
    settings: Mapping,
    candidates: tuple[str, ...],
    chain=None,
    max_order: int = 0,
) -> dict:
    """gearlab.gap.diagnose.diagnose with the search settings (a plain dict, picklable); imported here
    so that the benchmark loads without it. Serial inside a trial: trials are what runs in parallel."""
    from ...gap import diagnose as d

    settings = {**dict(settings), "max_order": max_order} if max_order else dict(settings)
    return d.diagnose(
        source, target_X, d.Settings(candidates=tuple(candidates), **settings), executor=None, chain=chain
    )


def diagnose_file(path: str | Path, source: DatasetSpec, candidates: Sequence[str], settings: Mapping) -> dict:
    """Diagnose a target from its file alone: the whole of what the diagnosis is given."""
    rows, chain, max_order = import_target(Path(path))
    return _diagnose(source, rows, dict(settings), tuple(candidates), chain, max_order)


# --- scoring ---------------------------------------------------------------------------------------


def param_error(effect, name: str, true: float, fitted: float) -> float:
    """Error of one fitted parameter: |ln(fit/true)| for a log-scale one (the relative error when
    small), the wrapped angle difference / π for a phase (0 exact, 1 opposite), the error relative
    to the true value otherwise (to the bounds' width when the true value is 0)."""
    p = declared(effect.params).get(name, (None,))[0]
    if p is not None and name in effect.log_scale and true > 0 and fitted > 0:
        return abs(math.log(fitted / true))
    if p is not None and p.unit == "rad" and math.isclose(p.high - p.low, 2 * math.pi):
        diff = (fitted - true) % (2 * math.pi)
        return min(diff, 2 * math.pi - diff) / math.pi
    scale = abs(true) if true != 0 else (p.high - p.low if p is not None else 1.0)
    return abs(fitted - true) / scale


def scored_params(name: str, true: Mapping) -> list[str]:
    """The parameters the generator drew (scored), numeric ones only."""
    rules = RANGES.get(name)
    keys = list(rules) if rules is not None else list(true)
    return [k for k in keys if k in true and isinstance(true[k], (int, float)) and not isinstance(true[k], bool)]


def score_trial(answers: Mapping, result: Mapping, registry=None, oracle: float | None = None) -> dict:
    """One trial's record from the generator's answers and the diagnosis's result (contract of
    gearlab.gap.diagnose.diagnose). top1/top3/shrink apply to single and pair trials, null_correct
    to null trials, out_of_library_unexplained to withheld ones (None elsewhere).

    *oracle*: for an effect trial the diagnosis saw no gap in, the share of fresh realisations of
    its target that show one (:func:`oracle_seen`). Under ORACLE_SEEN the effect is too weak for
    these revolutions: ``too_weak`` is set, top1 is None (no effect can be named first where no gap
    is seen), and ``right_answer`` is True -- "no significant gap" is the right answer there. Else
    (or without an oracle) a trial with no gap seen is a miss. ``right_answer`` of an effect trial
    is top1, or no gap named on a too-weak target."""
    from ...registry import get_registry

    registry = registry or get_registry()
    kind = answers["kind"]
    hidden = {name: params for name, params in answers["hidden"]}
    accepted = [e["name"] for e in result.get("effects", [])]
    fitted = {e["name"]: e.get("params", {}) for e in result.get("effects", [])}
    marks = {e["name"]: e.get("determined", {}) for e in result.get("effects", [])}
    ranking = [e["name"] for e in result.get("ranking", [])]
    before, after = (math.nan if result.get(k) is None else float(result[k]) for k in ("gap_before", "gap_after"))
    shrink = 1.0 - after / before if before > 0 and math.isfinite(after) else None
    record = {
        "kind": kind,
        "hidden": [[n, p] for n, p in answers["hidden"]],
        "withheld": answers.get("withheld"),
        "accepted": accepted,
        # named by a round but taken back at the end: the final fit did not need them (needed_effects)
        "unneeded": [e["name"] for e in result.get("unneeded_effects", [])],
        "ranking": ranking[:5],
        "gap_before": before,
        "gap_after": after,
        "significant_before": bool(result.get("significant_before")),
        "significant_after": bool(result.get("significant_after")),
        "unexplained": bool(result.get("unexplained")),
        "shrink": shrink,
        "verdict": result.get("verdict"),
        "explained_share": result.get("explained_share"),
        "evaluations": result.get("evaluations"),  # the diagnosis's score evaluations, its fits' included
        "acquisition": answers.get("acquisition"),
        "top1": None,
        "top3": None,
        "identified": [],
        "param_error": {},
        "param_error_median": None,
        "param_determined": {},
        "param_error_median_determined": None,
        "option_correct": {},
        "null_correct": None,
        "out_of_library_unexplained": None,
        "oracle_seen": oracle,
        "too_weak": None,
        # a gap seen but within the noise width, nothing named: the diagnosis's word that it lies below
        # what it attributes (still a miss of right_answer: the effect shows, but too little to name)
        "below_noise_width": bool(result.get("below_noise_width")) and not accepted,
        "right_answer": None,
        "wrong_names": [n for n in accepted if n not in hidden],
    }
    if kind in EFFECT_KINDS:
        record["top1"] = bool(accepted) and accepted[0] in hidden
        record["top3"] = any(n in hidden for n in ranking[:3])
        record["too_weak"] = not record["significant_before"] and oracle is not None and oracle < ORACLE_SEEN
        if record["too_weak"]:
            record["top1"] = record["top3"] = None
        record["right_answer"] = bool(record["top1"]) or (record["too_weak"] and not accepted)
        errors, sure = [], []
        for name in hidden:
            if name not in fitted:
                continue
            record["identified"].append(name)
            effect = registry.get("effect", name)
            per = {}
            for key in scored_params(name, hidden[name]):
                if isinstance(fitted[name].get(key), (int, float)):
                    per[key] = param_error(effect, key, float(hidden[name][key]), float(fitted[name][key]))
            record["param_error"][name] = per
            errors += list(per.values())
            # the diagnosis's own word on each parameter: determined by the data, or not identifiable
            record["param_determined"][name] = {k: bool(marks[name].get(k, {}).get("determined", True)) for k in per}
            sure += [v for k, v in per.items() if record["param_determined"][name][k]]
            record["option_correct"][name] = {
                k: fitted[name].get(k) == hidden[name][k] for k in effect.options if k in hidden[name]
            }
        record["param_error_median"] = float(np.median(errors)) if errors else None
        record["param_error_median_determined"] = float(np.median(sure)) if sure else None
    elif kind == "null":
        # correct: no significant gap, hence nothing named (a structure difference measured none: not correct)
        record["null_correct"] = result.get("significant_before") is False and not accepted
    else:
        # "unexplained" with no library effect accepted: a partly explained verdict names
        # effects that stand in for the missing one
        record["out_of_library_unexplained"] = record["unexplained"] and not accepted
    return record


# --- one trial, as an executor task ------------------------------------------------------------------


@dataclass(frozen=True)
class TrialTask:
    trial: Trial
    source: DatasetSpec
    settings: dict  # gearlab.gap.scoring.Settings fields except candidates
    folder: str | Confined  # a run directory's targets/trial_NNN (Confined), or a plain folder
    revolutions: int


# How often an effect's target must show a significant gap, over fresh realisations, for a trial
# whose diagnosis saw none to count as a miss rather than as too weak to be seen (oracle_seen).
ORACLE_REPEATS, ORACLE_SEEN = 5, 0.5


def oracle_seen(
    trial: Trial, source: DatasetSpec, settings: Mapping, revolutions: int, folder: Path | Confined
) -> float:
    """The share of ORACLE_REPEATS fresh realisations of *trial*'s target (new noise seeds, the same
    hidden effects and acquisition) in which the plain source shows a significant gap, judged as
    the diagnosis judges its "before" report. The generator's side: it knows the hidden effects,
    and asks only whether this many revolutions can show them at all (a 150 um eccentricity on
    six_dof sits at the edge: docs/gap_benchmark.md, section 3)."""
    from dataclasses import replace

    from ...gap.conclusion import gap_seen
    from ...gap.scoring import Settings, plain_report

    seen = 0
    for k in range(ORACLE_REPEATS):
        unit_says(f"no gap seen: the oracle's realisation {k + 1} of {ORACLE_REPEATS}")
        seed = int(np.random.default_rng([trial.seed, 7, k]).integers(1, 2**31 - 1))
        where = _held(folder) / f"oracle_{k}"
        try:
            rows, chain, max_order = import_target(write_target(replace(trial, seed=seed), source, where, revolutions))
            plain = dict(settings, max_order=max_order) if max_order else dict(settings)
            report = plain_report(source, rows, Settings(candidates=tuple(trial.candidates), **plain), chain)
            seen += gap_seen(report)
        finally:
            where.remove_tree()
    return seen / ORACLE_REPEATS


# minutes a trial, up to eleven: its target, each stage of its diagnosis, the oracle, on its progress line
@told_unit(lambda task: (_held(task.folder).root, unit_key(task.trial.index)))
def trial_task(task: TrialTask) -> dict:
    """Generate + write + diagnose (from the file) + score one trial. The generator's choices reach
    the diagnosis only through the written file; scoring reads them back from answers.json after.
    An effect trial whose diagnosis saw no significant gap is checked by the generator
    (:func:`oracle_seen`): too weak to be seen, "no significant gap" is the right answer."""
    folder = _held(task.folder)
    started = time.perf_counter()
    unit_says("simulating and writing the target")
    path = write_target(task.trial, task.source, folder, task.revolutions)
    generated = time.perf_counter()
    candidates = task.trial.candidates
    result = diagnose_file(path, task.source, candidates, task.settings)
    diagnosed = time.perf_counter()
    (folder / "diagnosis.json").write(json.dumps(result, indent=1, sort_keys=True, default=_jsonable))
    unseen = task.trial.kind in EFFECT_KINDS and not result.get("significant_before")
    oracle = oracle_seen(task.trial, task.source, task.settings, task.revolutions, folder) if unseen else None
    record = score_trial(read_answers(folder), result, oracle=oracle)
    record.update(unit=unit_key(task.trial.index), index=task.trial.index, candidates=len(candidates))
    record.update(seconds=round(diagnosed - started, 3), generate_seconds=round(generated - started, 3))
    return record


def unit_key(index: int) -> str:
    return f"trial {index:03d}"


def _jsonable(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple):
        return list(value)
    raise TypeError(f"not JSON-serialisable: {type(value).__name__}")


# --- summary -------------------------------------------------------------------------------------------


def _rate(values) -> float | None:
    values = [bool(v) for v in values if v is not None]
    return float(np.mean(values)) if values else None


def _median(values) -> float | None:
    values = [float(v) for v in values if v is not None and math.isfinite(float(v))]
    return float(np.median(values)) if values else None


# Acceptance targets (docs/gap_benchmark.md): top-1, median shrink when identified, null, out of library.
TARGETS = {"top1": 0.85, "median_shrink": 0.70, "null_correct": 0.90, "out_of_library_unexplained": 0.80}


def summarise(records: Sequence[Mapping], library: Sequence[str]) -> dict:
    """The benchmark's numbers over finished trials (fields of summary.json)."""
    effect_trials = [r for r in records if r["kind"] in EFFECT_KINDS]
    identified = [r for r in effect_trials if r["top1"]]
    per_effect = {}
    for name in library:
        mine = [r for r in effect_trials if any(h[0] == name for h in r["hidden"])]
        held = [r for r in records if r["kind"] == "withheld" and r["withheld"] == name]
        errors = [v for r in mine for v in r["param_error"].get(name, {}).values()]
        sure = [
            v
            for r in mine
            for k, v in r["param_error"].get(name, {}).items()
            if r.get("param_determined", {}).get(name, {}).get(k, True)
        ]
        per_effect[name] = {
            "trials": len(mine),
            "top1": _rate(r["top1"] for r in mine),
            "top3": _rate(r["top3"] for r in mine),
            "identified": sum(name in r["identified"] for r in mine),
            "median_shrink": _median(r["shrink"] for r in mine if r["top1"]),
            "median_param_error": _median(errors),
            "median_param_error_determined": _median(sure),
            "not_identifiable": sum(not d for r in mine for d in r.get("param_determined", {}).get(name, {}).values()),
            "withheld": len(held),
            "unexplained_when_withheld": _rate(r["unexplained"] for r in held),
            "named_wrongly": sum(name in r["wrong_names"] for r in records),
        }
    summary = {
        "trials": len(records),
        "by_kind": {
            k: sum(r["kind"] == k for r in records)
            for k in KINDS + EXTRA_KINDS
            if k in KINDS or any(r["kind"] == k for r in records)
        },
        "top1": _rate(r["top1"] for r in effect_trials),
        "top3": _rate(r["top3"] for r in effect_trials),
        "top1_single": _rate(r["top1"] for r in effect_trials if r["kind"] == "single"),
        "top1_pair": _rate(r["top1"] for r in effect_trials if r["kind"] == "pair"),
        "top1_suborder": _rate(r["top1"] for r in effect_trials if r["kind"] == "suborder"),
        # every effect trial: the right effect named first, or -- on a target too weak for any gap to
        # be seen in fresh realisations (oracle_seen) -- "no significant gap"; too_weak counts those
        "right_answer": _rate(r.get("right_answer", r["top1"]) for r in effect_trials),
        "too_weak": sum(bool(r.get("too_weak")) for r in effect_trials),
        "below_noise_width": sum(bool(r.get("below_noise_width")) for r in effect_trials),
        "median_shrink": _median(r["shrink"] for r in identified),
        "median_param_error": _median(r["param_error_median"] for r in effect_trials),
        # over the parameters the diagnosis called determined (the goal is on identifiable ones)
        "median_param_error_determined": _median(
            v
            for r in effect_trials
            for name, per in r["param_error"].items()
            for k, v in per.items()
            if r.get("param_determined", {}).get(name, {}).get(k, True)
        ),
        "null_correct": _rate(r["null_correct"] for r in records if r["kind"] == "null"),
        "out_of_library_unexplained": _rate(
            r["out_of_library_unexplained"] for r in records if r["kind"] == "withheld"
        ),
        "wrong_names_when_withheld": _rate(bool(r["wrong_names"]) for r in records if r["kind"] == "withheld"),
        # The other side of the two out-of-library numbers: a diagnosis that always said
        # "unexplained" would pass on withheld trials; here it must not say so when it named right.
        "explained_when_identified": _rate(not r["unexplained"] for r in identified),
        # explained, or partly explained with most of the gap (the share the verdict states)
        "explained_or_partly_when_identified": _rate(
            r.get("verdict") == "explained"
            or (r.get("verdict") == "partly explained" and (r.get("explained_share") or 0.0) >= 0.5)
            for r in identified
        ),
        "null_correct_by_format": {
            f: _rate(
                r["null_correct"]
                for r in records
                if r["kind"] == "null" and (r.get("acquisition") or {}).get("format", "angle") == f
            )
            for f in ("angle",) + FORMATS
            if any((r.get("acquisition") or {}).get("format", "angle") == f for r in records if r["kind"] == "null")
        },
        "extra_names_when_identified": _rate(bool(r["wrong_names"]) for r in identified),
        "per_effect": per_effect,
        "seconds_per_trial": _median(r.get("seconds") for r in records),
    }
    summary["targets"] = TARGETS
    summary["met"] = {k: (summary[k] is not None and summary[k] >= v) for k, v in TARGETS.items()}
    return summary
