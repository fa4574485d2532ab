"""The gap diagnosis's scoring (docs/gap.md): its settings ([diagnosis], `Settings`) and input
checks, the source's healthy revolutions simulated through the builder's own steps (`source_rows`,
`measured_rows`, `Rows`), the cheap score of a corrected source against the target (`Scorer`: the
gap total without bootstrap or tests), the paired-bootstrap acceptance test and the full report.
The search (gearlab.gap.search) and the diagnosis loop (gearlab.gap.diagnose) score through these."""

from __future__ import annotations

import functools
import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..data import placement
from ..data.builder import (
    SimTask,
    _unit_simulator,
    healthy_reference,
    noisy_rows,
    operating_point,
    record_span,
    row_tasks,
    settle_revolutions,
    simulate_unit,
    stretch_of,
    stretch_start,
    whole_steps_rate,
)
from ..data.chain import Chain, fit_offset, sampled, tracked
from ..data.realise import Seeds, first_revolution, parts, realise, row_seed
from ..data.realise import record as cycle_record
from ..data.spec import POINTS, DatasetSpec
from ..effects import LEVELS, EffectChain, check_candidate, default_candidates
from ..errors import GearlabInputError
from ..memo import SharedArrays
from ..registry import get_registry
from ..settings import MAX_SEED, declared, in_bounds, setting
from ..signals.indicators import band_limited
from .level import best_factor
from .level import bounds as level_bounds
from .stats import MIN_REVOLUTIONS, SD_FLOOR, effect_sizes, gap_report, resampled_moments, view_gaps
from .tally import counted
from .views import (
    POWER_FLOOR,
    RECORD_MIN_BLOCKS,
    RESIDUAL_FLOOR,
    WAVEFORM_STATS,
    BandPlan,
    gear_ratio,
    mesh_free,
    offset_removed,
    order_views_of_power,
    power_of_spectrum,
    record_blocks,
    record_view,
    residual_view_of_rows,
    residual_view_of_spectrum,
    waveform_view,
    without_line,
)

ACCEPT_REPLICATES = 200  # paired bootstrap replicates for the acceptance test
ACCEPT_CONFIDENCE = 0.95
NUISANCE = "sensor_noise"  # fitted jointly with every other candidate while it is not yet accepted


REFERENCES = ("source", "noise")
SCALED_STATS = ("mean", "rms", "peak_to_peak")  # the waveform statistics a scale of the rows scales (Scorer.at_factor)


def _open_fraction(value, where: str) -> float:
    # an open interval: alpha = 0 would never call a gap significant, alpha = 1 always
    if not 0.0 < value < 1.0 or not math.isfinite(value):
        raise GearlabInputError(f"{where}: expected a significance level between 0 and 1 (exclusive), got {value!r}")
    return float(value)


def _consecutive(value, where: str):
    if value not in (True, False, "auto") or isinstance(value, (int, float)) and not isinstance(value, bool):
        raise GearlabInputError(f"{where}: expected true, false or 'auto', got {value!r}")
    return value


@dataclass(frozen=True)
class Settings:
    """The diagnosis's settings, declared once (gearlab.settings): the scenario's [diagnosis] keys,
    their checks, the --quick limits and docs/settings.md all follow from these fields."""

    candidates: tuple[str, ...] = setting(
        (list, tuple),
        (),
        doc="effect names to try (gearlab plugins lists them); [] = every registered effect "
        "but the opt-in ones (load_level) and those that add only a constant (sensor_offset)",
    )
    budget: int = setting(
        int, 16, low=1, high=10_000, quick=4, doc="source simulations per effect fit (the search budget)"
    )
    max_effects: int = setting(int, 3, low=1, high=20, quick=2, doc="greedy rounds: most effects added to the source")
    healthy: int = setting(
        int, 40, low=MIN_REVOLUTIONS, high=100_000, quick=20, doc="source healthy revolutions simulated per evaluation"
    )
    bootstrap: int = setting(
        int,
        200,
        low=0,
        high=100_000,
        quick=50,
        doc="bootstrap replicates of the before/after reports (searches use a cheap score)",
    )
    permutations: int = setting(
        int, 500, low=1, high=1_000_000, quick=200, doc="MMD permutations of the before/after reports"
    )
    alpha: float = setting(float, 0.05, check=_open_fraction, doc="significance level of the two-sample test")
    seed: int = setting(int, 0, low=0, high=MAX_SEED, doc="seeds the search's and the reports' noise")
    # What "closes the gap" is measured against (EXPLAINED_SHRINK): the plain source, or the source
    # with the sensor noise fitted alone -- for a measured target, which always carries noise that a
    # noise-free simulator lacks: against the plain source that noise alone makes any shrink look whole.
    reference: str = setting(
        str,
        "source",
        choices=REFERENCES,
        doc="what the shrink that closes the gap is measured against: the plain source, or the "
        "source with its sensor noise fitted alone (measured targets)",
    )
    consecutive: bool | str = setting(
        (bool, str),
        "auto",
        check=_consecutive,
        doc="the target's rows are consecutive revolutions of one record: the before/after reports then resolve "
        "the output-shaft orders too (outside the shares); 'auto' = true for a measured target",
    )
    # The highest shaft order the target holds (a measured record's acquisition bandwidth, below its
    # Nyquist order): every source set is low-passed to it, so the comparison stays where the target
    # has data (simulated revolutions, and the noise added to them, reach order POINTS / 2). 0: all.
    # Not a scenario key: the gap kind reads it off the measured target.
    max_order: int = 0


# --- input checks ---------------------------------------------------------------------------------


def check_settings(settings: Settings) -> tuple[str, ...]:
    """Every setting checked against its declaration; returns the candidate effect names (all
    registered ones for ())."""
    if not isinstance(settings, Settings):
        raise GearlabInputError(f"gap diagnosis: expected gearlab.gap.scoring.Settings, got {type(settings).__name__}")
    for name, (meta, _) in declared(Settings).items():
        value, where = getattr(settings, name), f"gap diagnosis: settings '{name}'"
        if meta.types is int and (isinstance(value, bool) or not isinstance(value, numbers.Integral)):
            raise GearlabInputError(f"{where} must be a whole number, got {value!r}")
        if meta.types is float and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
            raise GearlabInputError(f"{where} must be a number, got {value!r}")
        if meta.types is str and not isinstance(value, str):
            raise GearlabInputError(f"{where} must be a text, got {value!r}")
        if name == "candidates" and (isinstance(value, str) or not isinstance(value, (tuple, list))):
            raise GearlabInputError(f"{where} must be a list of effect names, got {value!r}")
        in_bounds(meta, value, where)
    if (
        isinstance(settings.max_order, bool)
        or not isinstance(settings.max_order, numbers.Integral)
        or settings.max_order < 0
    ):
        raise GearlabInputError(
            f"gap diagnosis: settings 'max_order' must be a whole number >= 0, got {settings.max_order!r}"
        )
    registry = get_registry()
    names = tuple(settings.candidates) or tuple(default_candidates(registry))
    for i, name in enumerate(names, start=1):
        if not isinstance(name, str):
            raise GearlabInputError(f"gap diagnosis: candidate #{i} must be an effect name, got {name!r}")
        check_candidate(registry, name, f"gap diagnosis: candidate #{i}")
    if len(set(names)) != len(names):
        raise GearlabInputError(f"gap diagnosis: candidates repeat a name: {', '.join(names)}")
    if settings.reference == "noise" and NUISANCE not in names:
        raise GearlabInputError(f"gap diagnosis: settings reference = 'noise' needs '{NUISANCE}' among the candidates")
    return names


def check_target(target_X) -> np.ndarray:
    """target_X as float64 (n, POINTS): 2-D, finite, at least MIN_REVOLUTIONS rows."""
    try:
        X = np.asarray(target_X, dtype=np.float64)
    except (TypeError, ValueError):
        raise GearlabInputError(
            "gap diagnosis: target_X must be a numeric array (n, 4096) of healthy revolutions"
        ) from None
    if X.ndim != 2:
        raise GearlabInputError(
            f"gap diagnosis: target_X must be 2-D (revolutions x {POINTS} points), got shape {X.shape}"
        )
    if X.shape[1] != POINTS:
        raise GearlabInputError(
            f"gap diagnosis: target revolutions have {X.shape[1]} samples, the source's "
            f"{POINTS}; resample the target to {POINTS} points per revolution"
        )
    if len(X) < MIN_REVOLUTIONS:
        raise GearlabInputError(
            f"gap diagnosis: too few healthy target revolutions: {len(X)}; expected at least {MIN_REVOLUTIONS}"
        )
    if not np.all(np.isfinite(X)):
        raise GearlabInputError("gap diagnosis: target_X contains NaN or infinite values")
    return X


def _check_source(source: DatasetSpec):
    if not isinstance(source, DatasetSpec):
        raise GearlabInputError(
            f"gap diagnosis: the source must be a simulated DatasetSpec, got {type(source).__name__}"
        )
    where = f"gap diagnosis: source '{source.name}'"
    source.with_(faults=(), healthy=max(source.healthy, 1)).check(where)
    _, pair, _ = source.check_model(where)
    return pair


# --- simulating the source's healthy revolutions (through the builder's own steps) ---------------


def _by_level(effects) -> tuple:
    """Canonical effects in the order they act (model, excitation, signal; stable within a level),
    the order a scenario list is stored in, so the corrected source shares its cache key."""
    registry = get_registry()
    return tuple(sorted(effects, key=lambda e: LEVELS.index(registry.get("effect", e[0]).level)))


@functools.lru_cache(maxsize=64)
def _clean_revolution(
    model: str, preset: str, fs: float, speed: float, load: float, channel: str, effects: tuple, turns: int = 0
) -> np.ndarray:
    """The steady healthy revolution (POINTS,) under the model- and excitation-level *effects*; a
    later mesh's cycle of them (R x POINTS,) where it is no whole input order (builder.mesh_cycle);
    a long train's stretch of *turns* steady revolutions (source_turns; 0: the builder's default).

    Cached per process: a signal-level candidate only transforms this revolution, so its
    whole fit costs one simulation. It is the builder's own simulation unit for the healthy
    case on tooth 1, the row build_dataset uses for its healthy samples and reference.
    """
    return simulate_unit(tuple(_healthy_task(model, preset, fs, speed, load, channel, effects, turns)))[0]


def _healthy_task(model, preset, fs, speed, load, channel, effects, turns: int = 0) -> SimTask:
    return SimTask(model, preset, fs, speed, load, channel, None, None, (1,), effects, 1, turns)


def source_turns(spec: DatasetSpec, model, record: bool = False) -> int:
    """0 for a train whose healthy response repeats within placement.MAX_PERIOD input turns (its
    whole cycle is simulated, the rows read it as periodic); for a long train, the revolutions of
    the stretch its rows need, so that none is cut across the stretch's end (a stretch is not
    periodic: joined end to start it holds a step no gearbox makes): the builder's (stretch_of:
    every record starts within it), and for *record* (consecutive rows of one record through a
    chain) the healthy rows and their two neighbours, all it reads (measured_rows; the noise's
    reference RMS over them: on a development box's 22 turns -0.005 dB from the 128's)."""
    turns = stretch_of(spec, placement.train_pairs(model, spec.preset, f"dataset '{spec.name}'"), {})
    return spec.healthy + 2 if turns and record else turns


def _reference(spec: DatasetSpec, clean: np.ndarray, speed: float, reference_rms: float) -> tuple[float, float]:
    """The domain's healthy reference (mean, std), made as build_dataset makes it: the rows are
    stored standardised in float32, and only the same round trip makes "the same simulator" give
    the same rows (a noise-free target against a noise-free source sees its rounding)."""
    reference = healthy_reference(spec, clean, speed, reference_rms)
    return reference.mean, reference.std


def source_rows(
    spec: DatasetSpec, max_order: int = 0, chain: Chain | None = None, consecutive: bool = False
) -> np.ndarray:
    """The healthy rows of *spec* in physical units, (spec.healthy, POINTS) float64: exactly
    ``healthy_rows(build_dataset(spec.with_(faults=())))``, without the cache or the fault
    simulations.

    The builder's steps are reused, not copied: its simulation unit for the healthy case
    (model and excitation effects; cached here per process, so a signal-level candidate
    costs no simulation) and its row task (signal effects, the dataset's noise and TSA, with
    the same per-sample seeds [seed, noise seed, i] and the float32 standardisation), then
    the standardisation undone as healthy_rows does.

    *chain*: a measured target's acquisition (gearlab.data.chain): the rows are then made as the
    target's were -- one revolution each, read at the record's rate and start fractions, noise
    effects in time before the order tracking, rounded to its step -- by :func:`measured_rows`;
    *consecutive* (with a chain): as consecutive revolutions of one record.
    """
    registry = get_registry()
    model, pair, _ = spec.check_model()
    speed, load = operating_point(spec)
    fs = whole_steps_rate(spec.fs, speed, pair.Z1)
    physics = tuple(e for e in spec.effects if registry.get("effect", e[0]).level != "signal")
    turns = source_turns(spec, model, chain is not None and consecutive)
    clean = _clean_revolution(spec.model, spec.preset, fs, speed, load, spec.channel, physics, turns)
    reference_rms = float(np.sqrt(np.mean(clean**2)))
    if chain is not None:
        rows = measured_rows(spec, clean, speed, reference_rms, chain, pair.Z1, consecutive)
        return band_limited(rows, max_order=max_order)
    mean, std = _reference(spec, clean, speed, reference_rms)
    placed = {}
    if turns:  # a long train: each record within the stretch, from where build_dataset starts it
        span = record_span(spec)
        placed["starts_of"] = lambda i: stretch_start(spec.seed, i, turns, span)
        if spec.unit_shaft:  # the shaft's phase counts the settle turns before the stretch
            task = _healthy_task(spec.model, spec.preset, fs, speed, load, spec.channel, physics, turns)
            settle = settle_revolutions(_unit_simulator(task), speed)
            placed["offset_of"] = lambda i: settle
    tasks = row_tasks(
        spec,
        spec.healthy,
        lambda idx: np.broadcast_to(clean, (len(idx), clean.size)),
        (mean, std),
        speed,
        reference_rms,
        **placed,
    )
    out = np.concatenate([noisy_rows(tuple(task)) for task in tasks] or [np.empty((0, POINTS), np.float32)])
    return band_limited(out.astype(np.float64) * std + mean, max_order=max_order)


# The deterministic part of measured rows, sampled at the record's times (gearlab.data.chain.sampled),
# per source set without its noise: a search re-fits the sensor noise at every point (the nuisance,
# 6-24 noise levels each) and the signal effects' fits share one simulation, so the same sampled
# rows came back hundreds of times per fit (80 % of a fit's time went into making them again).
_sampled = SharedArrays(32)


def measured_rows(
    spec: DatasetSpec,
    clean: np.ndarray,
    speed: float,
    reference_rms: float,
    chain: Chain,
    teeth: int = 1,
    consecutive: bool = False,
) -> np.ndarray:
    """The healthy rows of *spec* through a measured target's chain (gearlab.data.chain): each row
    one revolution; the non-noise signal effects act in the angle domain on row i's record (the
    builder's seeds [seed, noise seed, i]), the noise effects and the dataset's noise in time at the
    record's rate, where a sensor's noise is white. The tacho offset is the chain's, or fitted to the
    target's synchronous average for this very set (a free rotation: it follows whatever the effects
    do to the waveform's phase). The rows before the noise are kept per set (`_sampled`).

    *consecutive*: the rows are consecutive revolutions of one record, as a measured target's are:
    the non-noise signal effects act on all of them as one record (seeds [seed, noise seed, 0]). A
    tone that is not shaft-synchronous then runs on from one revolution into the next, as in the
    target, instead of starting at a random phase in every row: its line is as narrow as the
    target's, and its share in the synchronous average the same."""
    shaping, noisy = parts(EffectChain.load(spec.effects) if spec.effects else EffectChain())
    seeds = [Seeds.of_row(row_seed(spec, i)) for i in range(spec.healthy)]  # the builder's
    revs = clean.reshape(-1, POINTS)  # a later mesh's cycle of revolutions, else one

    def deterministic() -> tuple:
        # a later mesh's cycle makes consecutive rows a record even without an effect: its line runs on
        record = consecutive and (bool(shaping) or len(revs) > 1)
        here = {"fs": POINTS * speed, "speed_hz": speed, "reference_rms": reference_rms}
        if record:
            # One record, a revolution longer at each end: those two are read only as the
            # neighbours of the first and last rows (gearlab.data.chain.sampled, record).
            D = realise(cycle_record(revs, spec.healthy + 2), shaping, None, seeds[0], **here)
            rows = D[1:-1]
        else:  # each row its own record: the builder's revolution of the cycle for its row i
            starts = [first_revolution(spec.seed, i, len(revs)) for i in range(spec.healthy)]
            own = revs[starts] if len(revs) > 1 else np.broadcast_to(clean, (spec.healthy, POINTS))
            D = realise(own, shaping, None, seeds, **here)
            rows = D
        offset = chain.offset
        if offset is None:
            offset = fit_offset(rows.mean(axis=0), chain.reference, teeth) if chain.reference is not None else 0.0
        return sampled(D, chain, offset, record=record)

    registry = get_registry()
    quiet = spec.with_(effects=tuple(e for e in spec.effects if not registry.get("effect", e[0]).noise))
    reference = None if chain.reference is None else hash(np.asarray(chain.reference).tobytes())
    x, u = _sampled.get_or_make((quiet, chain, reference, teeth, consecutive), deterministic)

    def noise(i: int, x: np.ndarray) -> np.ndarray:
        return realise(x, noisy, spec.noise, seeds[i], fs=chain.fs, speed_hz=speed, reference_rms=reference_rms)

    return tracked(x, u, chain, noise if (noisy or spec.noise is not None) else None)


@dataclass(frozen=True)
class Rows:
    """How the source's rows are made for one target (picklable, handed to every fit): the band it
    is compared in (max_order) and, for a measured target, its acquisition chain and whether its rows
    are consecutive revolutions of one record (settings.consecutive)."""

    max_order: int = 0
    chain: Chain | None = None
    consecutive: bool = False
    # The target's load (gearlab.gap.level): every set of rows scaled by *load* (a factor held; None: the
    # source's own load); or, with *free_load* (the factor's bounds), left at the source's load and
    # scored at its own best factor within them (the search's Scorer made from these Rows profiles it).
    load: float | None = None
    free_load: tuple[float, float] | None = None
    line: float = 0.0  # a tone's shaft order taken out of every row, as of the target's (gearlab.gap.lines; 0: none)

    def __call__(self, spec: DatasetSpec) -> np.ndarray:
        X = without_line(offset_removed(source_rows(spec, self.max_order, self.chain, self.consecutive)), self.line)
        return X * self.load if self.load is not None else X


# --- the cheap score ---------------------------------------------------------------------------------


class Scorer:
    """The search's score of a source set against the fixed target_X, and the report's gap total.

    **The search score** (:meth:`score`) is the mismatch of the per-feature means on the
    *target's* scale: Σ_f [(μ_t − μ_s)² − v_s/n_s − v_t/n_t] / s_t², s_t the target's own
    spread (floored as the report floors). The report's effect size divides by the spread
    pooled over both sets, so an effect that only adds noise to the source (sensor_noise,
    interference_tone) inflated it and shrank every effect size without matching anything:
    noise-like candidates won for the wrong reason. Here the scale is the target's, which no
    candidate can change, so adding noise lowers the score only where the target really is
    noisy (its noise-floor, residual and kurtosis features). The subtracted terms remove the
    sampling bias of (μ_t − μ_s)², so the score of a right model is ≈ 0 whatever its noise.
    The source's term is v_s capped at the target's v_t: uncapped, a source far noisier than
    the target lowered the score without bound (a 3 Hz tone at 10x the signal, the bound of its
    ratio, scored -1.8e5 against a target the right drive inertias scored 0.3 on, and won its
    round); capped, a source noisier than the target is credited no more than the target's own
    spread (that point scores +6.6e4, the plain source 9.1e3), and a right model, v_s ≈ v_t,
    keeps its ≈ 0.

    **Cheap**: the target's order bands, waveform statistics, rfft and mesh-free rows are computed
    once; a source set costs one rfft (its order power and, by linearity, its TSA and both residuals'
    spectra), the inverse FFT of its own residual and of its average's, and the band sums (np.add.reduceat).

    :meth:`report_gap` is the report's gap total (gap_report, pooled spread) on the same
    features, for the before/after numbers and tests.
    """

    def __init__(
        self,
        target_X: np.ndarray,
        pair,
        max_order: int = 0,
        consecutive: bool = False,
        free_load: tuple[float, float] | None = None,
    ):
        self.target = np.asarray(target_X, dtype=np.float64)
        self.free_load = free_load  # the load factor's bounds where it is profiled out (load_factor)
        # Consecutive rows (a measured record's): the record's fractional lines join the score
        # (gearlab.gap.views.record_view), a second group of rows, one per block.
        self.target_record = (
            record_view(self.target).features if consecutive and self._has_record(self.target) else None
        )
        self.pair = gear_ratio(pair)
        self.z1 = self.pair[0]
        self.points = self.target.shape[1]
        self.plan = BandPlan.make(self.points, self.pair, highest=max_order)
        self.target_fft = np.fft.rfft(self.target, axis=1)
        self.target_power = np.mean(self.target * self.target, axis=1)
        self.target_residual = mesh_free(self.target_fft.copy(), self.points, self.z1)
        order = order_views_of_power(power_of_spectrum(self.target_fft, self.points), self.plan)
        self.target_order = np.concatenate([v.features for v in order], axis=1)
        self.target_wave = waveform_view(self.target).features
        self.sizes = [v.size for v in order] + [self.z1, self.target_wave.shape[1]]

    @functools.cached_property
    def tails(self) -> np.ndarray:
        """The target's :func:`tail_shape`: what decides the noise law (_NoiseNuisance)."""
        return tail_shape(self.target)

    def features(self, source_X: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[int]]:
        """(source features, target features, view sizes): gap_report's views without the
        latent one; the target's TSA residual is taken against the source's average."""
        X = np.asarray(source_X, dtype=np.float64)
        n, P = X.shape
        F = np.fft.rfft(X, axis=1)
        order = order_views_of_power(power_of_spectrum(F, P), self.plan)
        tsa = F.mean(axis=0)  # the rfft of the source's synchronous average (linearity)
        own = residual_view_of_spectrum((F - tsa) * (n / (n - 1)), P, self.z1, np.mean(X * X, axis=1))
        # the target's residual against the source's average, by linearity: its own mesh-free rows (made once) less
        # the average's, one inverse FFT of a row where one of every target row was made per call
        against = self.target_residual - mesh_free(tsa[None, :].copy(), P, self.z1)
        target_res = residual_view_of_rows(against, self.z1, self.target_power)
        Fs = np.concatenate([v.features for v in order] + [own.features, waveform_view(X).features], axis=1)
        Ft = np.concatenate([self.target_order, target_res.features, self.target_wave], axis=1)
        return Fs, Ft, list(self.sizes)

    @staticmethod
    def _scale(Ft: np.ndarray, ms: np.ndarray) -> np.ndarray:
        mt = Ft.mean(axis=0)
        return np.maximum(Ft.std(axis=0, ddof=1), SD_FLOOR * np.maximum(1.0, np.maximum(np.abs(ms), np.abs(mt))))

    @staticmethod
    def mismatch(Fs: np.ndarray, Ft: np.ndarray) -> float:
        ms, mt = Fs.mean(axis=0), Ft.mean(axis=0)
        vs, vt = Fs.var(axis=0, ddof=1), Ft.var(axis=0, ddof=1)
        scale2 = Scorer._scale(Ft, ms) ** 2
        return float(np.sum(((mt - ms) ** 2 - np.minimum(vs, vt) / len(Fs) - vt / len(Ft)) / scale2))

    @staticmethod
    def _has_record(X: np.ndarray) -> bool:
        return record_blocks(len(X)) >= RECORD_MIN_BLOCKS

    def record(self, source_X: np.ndarray) -> np.ndarray | None:
        """The source's record features (blocks of consecutive rows), or None where the score has
        no record group (independent rows, or too few rows for RECORD_MIN_BLOCKS blocks)."""
        if self.target_record is None or not self._has_record(source_X):
            return None
        return record_view(source_X).features

    def score(self, source_X: np.ndarray) -> float:
        counted()  # for the line of the stage whose fits run (gearlab.gap.tally)
        source_X, Fs, Ft = self._leveled_features(source_X)
        Rs = self.record(source_X)
        return self.mismatch(Fs, Ft) + (self.mismatch(Rs, self.target_record) if Rs is not None else 0.0)

    def replicates(self, source_X: np.ndarray, replicates: int, seed) -> np.ndarray:
        """Bootstrap replicates of :meth:`score` (rows of both sets resampled as multinomial
        counts, the scale held at the full target's): the same *seed* resamples the same row
        indices, so two sources' replicates are paired."""
        source_X, Fs, Ft = self._leveled_features(source_X)
        rng = np.random.default_rng(seed)
        out = self._replicates(Fs, Ft, replicates, rng)
        Rs = self.record(source_X)
        if Rs is not None:  # the blocks resampled as rows of their own group
            out = out + self._replicates(Rs, self.target_record, replicates, rng)
        return out

    @classmethod
    def _replicates(cls, Fs: np.ndarray, Ft: np.ndarray, replicates: int, rng: np.random.Generator) -> np.ndarray:
        mt = Ft.mean(axis=0)
        scale = cls._scale(Ft, Fs.mean(axis=0))
        a, va = resampled_moments(Fs, mt, scale, replicates, rng)
        b, vb = resampled_moments(Ft, mt, scale, replicates, rng)
        # A replicate's squared difference carries the sampling noise twice (data and resampling).
        return np.sum((b - a) ** 2 - 2.0 * (np.minimum(va, vb) / len(Fs) + vb / len(Ft)), axis=1)

    # --- the load profiled out (gearlab.gap.level, "The load") ---------------------------------------

    def leveled(self, source_X: np.ndarray) -> np.ndarray:
        """*source_X* at its own best load factor (:meth:`load_factor`) where the load is free, else as it is."""
        return source_X if self.free_load is None else source_X * self.load_factor(source_X)

    def _leveled_features(self, source_X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(the rows at their own best load factor, as :meth:`leveled`; their features and the target's, as
        :meth:`features`): where the load is free, the features at the factor come from those the factor
        was found on (:meth:`_features_at`), so a score reads the rows' spectra once, not twice."""
        if self.free_load is None:
            Fs, Ft, _ = self.features(source_X)
            return source_X, Fs, Ft
        at = self._features_at(source_X)
        c = best_factor(lambda c: self.mismatch(*at(c)), self.free_load)
        return source_X * c, *at(c)

    def load_factor(self, source_X: np.ndarray) -> float:
        """The load factor c within free_load at which the score of c * *source_X* is least: the
        rows' features read once, the score of each c from them (:meth:`at_factor`)."""
        return best_factor(self.at_factor(source_X), self.free_load or level_bounds())

    def at_factor(self, source_X: np.ndarray) -> Callable[[float], float]:
        """The score of c * *source_X* (without a record group) as a function of c (:meth:`_features_at`;
        tests: it equals :meth:`score` of the scaled rows)."""
        at = self._features_at(source_X)
        return lambda c: self.mismatch(*at(c))

    def _features_at(self, source_X: np.ndarray) -> Callable[[float], tuple[np.ndarray, np.ndarray]]:
        """:meth:`features` (source's, target's) of c * *source_X* as a function of c, from the rows'
        features read once: the dB features move by 20 log10 c (their floors aside), the mean, RMS and
        peak-to-peak scale by c, the shape statistics stay; the target's residual from c times the
        source's average has, per row and sector, the energy E_tt - 2 c E_ts + c^2 E_ss. Each c then
        costs no FFT."""
        X = np.asarray(source_X, dtype=np.float64)
        n, P = X.shape
        F = np.fft.rfft(X, axis=1)
        order = np.concatenate([v.features for v in order_views_of_power(power_of_spectrum(F, P), self.plan)], axis=1)
        tsa = F.mean(axis=0)
        own = residual_view_of_spectrum((F - tsa) * (n / (n - 1)), P, self.z1, np.mean(X * X, axis=1)).features
        decibels = np.concatenate([order, own], axis=1)
        wave = waveform_view(X).features
        T, starts, widths, E_tt = self._target_residual
        average = tsa.copy()
        average[0] = 0.0
        average[self.z1 :: self.z1] = 0.0
        s = np.fft.irfft(average, n=P)
        E_ts = np.add.reduceat(T * s, starts, axis=1) / widths
        E_ss = np.add.reduceat(s * s, starts) / widths
        floor = RESIDUAL_FLOOR * self.target_power[:, None]
        scaled = np.array([name in SCALED_STATS for name in WAVEFORM_STATS], dtype=float)

        def at(c: float) -> tuple[np.ndarray, np.ndarray]:
            energy = np.maximum(E_tt - 2.0 * c * E_ts + c * c * E_ss, floor)
            target_res = 10.0 * np.log10(energy + POWER_FLOOR)
            Fs = np.concatenate([decibels + 20.0 * math.log10(c), wave * (1.0 + scaled * (c - 1.0))], axis=1)
            Ft = np.concatenate([self.target_order, target_res, self.target_wave], axis=1)
            return Fs, Ft

        return at

    @functools.cached_property
    def _target_residual(self) -> tuple:
        """The target's rows with DC and the mesh harmonics taken out (as the residual view takes them),
        where each residual sector starts, its width, and each row's energy per sector (E_tt)."""
        F = self.target_fft.copy()
        F[:, 0] = 0.0
        F[:, self.z1 :: self.z1] = 0.0
        T = np.fft.irfft(F, n=self.points, axis=1)
        edges = np.round(np.arange(self.z1 + 1) * self.points / self.z1).astype(int)
        starts, widths = edges[:-1], np.diff(edges)
        return T, starts, widths, np.add.reduceat(T * T, starts, axis=1) / widths

    def report_gap(self, source_X: np.ndarray) -> float:
        """gap_report's total (bias-corrected squared effect sizes on the pooled spread)."""
        Fs, Ft, sizes = self.features(source_X)
        return float(view_gaps(effect_sizes(Fs, Ft)["d"], sizes, len(Fs), len(Ft)).sum())


def _scorer(target_X, source: DatasetSpec, settings: Settings, rows: Rows) -> Scorer:
    """The search's score against *target_X*, with the record's lines where the rows are consecutive."""
    target = np.asarray(target_X, dtype=np.float64)
    return Scorer(target, _check_source(source), settings.max_order, rows.consecutive, rows.free_load)


# Where the residual's tails are read (tail_shape): the central 80, 98 and 99.8 % of its values.
TAIL_LEVELS = (0.9, 0.99, 0.999)


def tail_shape(X: np.ndarray) -> np.ndarray:
    """The shape of the rows' residual from their synchronous average (the noise, and whatever else
    is not shaft-synchronous), pooled over every sample: ln of each central TAIL_LEVELS range over
    the interquartile range (the central 99 % is 3.82 IQR wide for Gaussian noise, 6.64 for Laplace,
    12.2 for Student-t with nu = 2). Quantiles rather than the kurtosis: Student-t with nu = 2 has no
    finite fourth moment (its sample kurtosis wanders with the record's length), but every quantile."""
    R = np.asarray(X, dtype=np.float64)
    R = (R - R.mean(axis=0)).ravel()
    levels = [0.25, 0.75] + [q for p in TAIL_LEVELS for q in ((1.0 - p) / 2.0, (1.0 + p) / 2.0)]
    q = np.quantile(R, levels)
    iqr = q[1] - q[0]
    if not iqr > 0.0:
        return np.zeros(len(TAIL_LEVELS))
    return np.log(np.maximum(q[3::2] - q[2::2], 1e-300) / iqr)


# --- the diagnosis -----------------------------------------------------------------------------------


def _paired_removal(scorer: Scorer, current_X: np.ndarray, candidate_X: np.ndarray, seed: int) -> dict:
    """The gap the candidate removes from the current source, with a paired bootstrap: both
    comparisons resample the same source row indices (common random numbers make row i the
    same noise draw in both) and the same target rows."""
    now, new = scorer.score(current_X), scorer.score(candidate_X)
    rc = scorer.replicates(current_X, ACCEPT_REPLICATES, [seed, 3])
    rn = scorer.replicates(candidate_X, ACCEPT_REPLICATES, [seed, 3])
    removed = rc - rn
    tail = 100.0 * (1.0 - ACCEPT_CONFIDENCE)
    return {
        "gap_now": now,
        "gap_new": new,
        "removed": now - new,
        "removed_low": float(np.percentile(removed, tail)),  # one-sided: removed > 0 with 95 %
        "removed_interval": [float(x) for x in np.percentile(removed, [2.5, 97.5])],
    }


def _report(source_X, target_X, pair, settings: Settings, bootstrap: int | None = None, on_part=lambda: None) -> dict:
    """A gap report; the full ones (before, after) resolve the output-shaft orders when the target's
    rows are consecutive (settings.consecutive, resolved by diagnose). The source's rows stand in as
    consecutive: a one-revolution-periodic simulation's revolutions differ only by their noise."""
    full = bootstrap is None
    return gap_report(
        source_X,
        target_X,
        pair,
        seed=settings.seed,
        bootstrap=settings.bootstrap if full else bootstrap,
        permutations=settings.permutations,
        alpha=settings.alpha,
        consecutive=full and settings.consecutive is True,
        max_order=settings.max_order,
        on_part=on_part,
    )


def _prepared(source: DatasetSpec, target_X, settings: Settings, chain: Chain | None) -> tuple:
    """What every diagnosis starts from: the target (checked, band-limited), its chain (its tacho
    offset fitted per set against the target's average unless fixed), how rows are made, the
    settings ('consecutive' resolved), the gear pair and the source as the search and the reports
    simulate it."""
    # each record without its mean (views.offset_removed), as Rows makes the source's rows
    target = band_limited(check_target(target_X), max_order=settings.max_order)
    target = offset_removed(target, chain.takes if chain is not None else ())
    if chain is not None and chain.offset is None:
        chain = replace(chain, reference=target.mean(axis=0))
    if settings.consecutive == "auto":  # a measured record's rows are its consecutive revolutions
        settings = replace(settings, consecutive=chain is not None)
    pair = _check_source(source)
    for i, effect in enumerate(source.effects, start=1):  # the source's own effects must load too
        get_registry().get("effect", effect[0], f"gap diagnosis: source '{source.name}' effect #{i}")
    # Two noise seeds: one for the search (common random numbers), one for the reports, so the
    # fitted parameters are judged on rows they were not fitted to.
    search_seed, report_seed = (int(s) for s in np.random.SeedSequence([settings.seed, 9]).generate_state(2))
    base = source.with_(faults=(), healthy=settings.healthy, teeth=None, duplicates=1)
    rows = Rows(settings.max_order, chain, chain is not None and settings.consecutive is True)
    return target, chain, rows, settings, pair, base.with_(seed=search_seed), base.with_(seed=report_seed)


def plain_report(source: DatasetSpec, target_X, settings: Settings, chain: Chain | None = None) -> dict:
    """The diagnosis's "before" report alone: the plain source (the reports' rows) against the
    target, as :func:`diagnose` makes it (gap_seen says whether it shows a significant gap)."""
    check_settings(settings)
    target, chain, rows, settings, pair, _, fresh = _prepared(source, target_X, settings, chain)
    return _report(rows(fresh), target, pair, settings)
