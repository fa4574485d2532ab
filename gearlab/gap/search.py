"""The gap diagnosis's search (docs/gap.md, gearlab.gap.diagnose's design, round r): the search
space of one effect (`Space`: unit cube, log scales, options, ordinal parameters), the budgeted
Latin-hypercube design and bounded Nelder-Mead (`_fit_search`), backfitting of the accepted effects,
the jointly fitted noise nuisance, and the executor's units of work `fit_effect` and
`profile_effect` (picklable top-level functions)."""

from __future__ import annotations

import math
import numbers
import time
import warnings
from collections.abc import Callable, Sequence

import numpy as np

from ..data.builder import _configured_simulator, operating_point, settle_revolutions
from ..data.spec import DatasetSpec
from ..errors import GearlabInputError
from ..registry import get_registry
from .identify import LOCAL_STEP, _intervals, _local, _OutOfBudget, _plain, determined, profile
from .scoring import NUISANCE, Rows, Scorer, Settings, _by_level, _scorer, tail_shape

SIGNAL_EVALS = 4  # evaluations per budget unit for signal-level effects (they need no new simulation)
# Simulations per budget unit for a model-level effect: one per MODEL_DIMS of its parameters (at least
# one). A Nelder-Mead step in d dimensions costs about d; with 16 for casing_path's five, its design
# had 8 points in a 5-D cube and lost to a damped sensor resonance on 2 of 5 development casings.
MODEL_DIMS = 2
DESIGN_SHARE = 0.5  # part of a fit's evaluations spent on the space-filling design, the rest refines
# Whole-number parameters with at most ORDINAL_VALUES values are ordinal (a filter's order, 1-8
# poles): after the search, every value gets a local fit of the rest (_ordinal_profile), of
# ORDINAL_EVALS evaluations per free coordinate and one. Local fits (these, and the re-fits of
# accepted effects) start from a simplex LOCAL_STEP wide (unit cube).
# A local fit of one coordinate is a bounded Brent search LOCAL_BRACKET either side of its start.
ORDINAL_VALUES, ORDINAL_EVALS = 8, 4
NOISE_REPLICATES = 64  # bootstrap replicates for the score noise behind the parameter intervals
NUISANCE_SIGNAL_EVALS = 4  # SIGNAL_EVALS for signal-level candidates that carry the nuisance
NUISANCE_WIDE, NUISANCE_LOCAL, NUISANCE_STEP = 8, 4, 6.0  # Brent iterations (first / later points), dB
# --quick's profile: at most this many score evaluations per budget unit and per parameter and one
# (3 x 4 x 6 = 72 for casing_path's five). Unlimited, a three-stage box's casing took 488 simulations
# (7 of a 10-min --quick run) where its fit had taken 12.
QUICK_PROFILE_EVALS = 3


# --- the search space of one effect ------------------------------------------------------------------


class Space:
    """An effect's space() as a unit cube: one coordinate per number (linear or log between
    its bounds, rounded for integers) and one per text option (cut into equal parts).

    *source*: the source spec a search starts from. Where the source's own model already has a
    parameter of the effect (a ten_dof source's casing, motor and load), the search's first point
    takes the source's value, not the effect's default: a diagnosis starts from the source."""

    def __init__(self, effect, source: DatasetSpec | None = None):
        entries = effect.space()
        self.numbers = [e for e in entries if "choices" not in e]
        self.options = [e for e in entries if "choices" in e]
        self.defaults = {e["name"]: e["default"] for e in entries}
        if source is not None:
            own = source.model_config().params
            self.defaults.update(
                {
                    e["name"]: own[e["name"]]
                    for e in self.numbers
                    if e["low"] <= own.get(e["name"], -math.inf) <= e["high"]
                }
            )

    @property
    def dims(self) -> int:
        return len(self.numbers)

    def value(self, entry: dict, u: float) -> float:
        lo, hi, u = entry["low"], entry["high"], min(max(float(u), 0.0), 1.0)
        if entry["log"]:
            x = math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))
        else:
            x = lo + u * (hi - lo)
        x = min(max(x, lo), hi)  # exp/log rounding must not step outside the bounds
        return int(round(x)) if entry["integer"] else x

    def unit(self, entry: dict, x: float) -> float:
        lo, hi = entry["low"], entry["high"]
        if hi == lo:
            return 0.0
        if entry["log"]:
            return (math.log(x) - math.log(lo)) / (math.log(hi) - math.log(lo))
        return (x - lo) / (hi - lo)

    def params(self, u, choice: tuple[str, ...]) -> dict:
        out = {e["name"]: self.value(e, ui) for e, ui in zip(self.numbers, u)}
        out.update({e["name"]: c for e, c in zip(self.options, choice)})
        return out

    def default_point(self) -> tuple[np.ndarray, tuple[str, ...]]:
        return self.point_of(self.defaults)

    def point_of(self, params: dict) -> tuple[np.ndarray, tuple[str, ...]]:
        u = np.array([self.unit(e, params[e["name"]]) for e in self.numbers])
        return u, tuple(params[e["name"]] for e in self.options)

    def choices_at(self, v: np.ndarray) -> tuple[str, ...]:
        return tuple(
            e["choices"][min(int(x * len(e["choices"])), len(e["choices"]) - 1)] for e, x in zip(self.options, v)
        )

    def ordinal(self) -> list[int]:
        """The coordinates of whole-number parameters with at most ORDINAL_VALUES values (a filter's
        order): neighbouring values act alike, so a walk over them can follow the score. (A ripple's
        order of 1-32 is not one: order 3 and 4 make different sidebands.)"""
        return [j for j, e in enumerate(self.numbers) if e["integer"] and e["high"] - e["low"] + 1 <= ORDINAL_VALUES]

    def all_choices(self) -> list[tuple[str, ...]]:
        combos: list[tuple[str, ...]] = [()]
        for e in self.options:
            combos = [c + (x,) for c in combos for x in e["choices"]]
        return combos


def _fit_search(
    space: Space,
    objective: Callable[[dict], float],
    evaluations: int,
    seed: int,
    start: dict | None = None,
    guesses: Sequence[dict] = (),
    guess_step: float | None = None,
) -> list[dict]:
    """Minimise *objective* over *space* with at most *evaluations* calls; every evaluated point.

    *start*: parameters to start from instead of the defaults; with it there is no design,
    only the local refinement (re-fitting an accepted effect next to a new one). *guesses*:
    points tried right after the defaults (the effect's reading of the target; the design
    gets fewer points). *guess_step*: the effect reads its guesses to about this share of each
    range (Effect.guess_step); when a guess beats the design, Nelder-Mead starts that small there."""
    from scipy.optimize import minimize
    from scipy.stats import qmc

    seen: dict = {}
    history: list[dict] = []

    def evaluate(u, choice) -> float:
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        params = space.params(u, choice)
        key = tuple(sorted((k, float(v) if not isinstance(v, str) else v) for k, v in params.items()))
        if key in seen:  # integers and clipping map different u to one point: it costs nothing twice
            return seen[key]
        if len(history) >= evaluations:
            raise _OutOfBudget
        value = objective(params)
        seen[key] = value
        history.append({"u": u.copy(), "choice": choice, "params": params, "score": value})
        return value

    def best() -> dict:
        return min(history, key=lambda h: h["score"])

    rng = np.random.default_rng(seed)
    try:
        u0, c0 = space.default_point() if start is None else space.point_of(start)
        evaluate(u0, c0)
        for guess in guesses:
            evaluate(*space.point_of({**space.defaults, **guess}))
        read = {id(h) for h in history[1:]}  # the guesses as evaluated
        width = space.dims + len(space.options)
        n_design = 0 if start is not None else max(1, math.ceil(DESIGN_SHARE * evaluations)) - 1 - len(guesses)
        if width and n_design > 0:
            design = qmc.LatinHypercube(d=width, seed=rng).random(n_design)
            for row in design:
                evaluate(row[: space.dims], space.choices_at(row[space.dims :]))
        if space.dims:
            local = start is not None
            start = best()
            # Nelder-Mead from the best design point; its first simplex spans about one design
            # cell per coordinate (the scale on which the design has looked), pointing inwards.
            # A local refinement (no design) starts at LOCAL_STEP: with the design's rule it spanned
            # 0.35 of every range and spent its evaluations shrinking back (a sensor's f_n fitted
            # 0.6 % off stayed there, and a second effect was accepted for the residual).
            step = LOCAL_STEP if local else 0.5 / max(2, n_design + 1) ** (1.0 / space.dims)
            if guess_step and not local and id(start) in read:
                # A reading of the target beat the design: a simplex one design cell wide (a tenth of
                # the range) around a tone's line a few tenths of a percent wide spent its evaluations
                # shrinking back and ended 3-8 % off; started at the reading's own precision it
                # stays in the valley.
                step = guess_step
            x0 = start["u"]
            simplex = [x0]
            for i in range(space.dims):
                x = x0.copy()
                x[i] = x[i] + step if x[i] + step <= 1.0 else x[i] - step
                simplex.append(x)
            left = evaluations - len(history) - (len(space.all_choices()) - 1)
            if left > 0:
                try:
                    minimize(
                        lambda u: evaluate(u, start["choice"]),
                        x0,
                        method="Nelder-Mead",
                        bounds=[(0.0, 1.0)] * space.dims,
                        options={"maxfev": left, "initial_simplex": np.array(simplex), "xatol": 1e-4, "fatol": 0.0},
                    )
                except _OutOfBudget:
                    pass
            ordinal = space.ordinal()
            if ordinal:
                # The profile's evaluations come on top of the budget: (values + 1) local fits.
                per_value = ORDINAL_EVALS * (space.dims - len(ordinal) + 1)
                values = sum(int(space.numbers[j]["high"] - space.numbers[j]["low"]) + 1 for j in ordinal)
                evaluations = len(history) + per_value * (values + 1) + len(space.all_choices()) - 1
                _ordinal_profile(space, evaluate, history, ordinal, per_value)
        # The other option choices at the refined point: the design only sampled them coarsely.
        top = best()
        for choice in space.all_choices():
            evaluate(top["u"], choice)
    except _OutOfBudget:
        pass
    return history


def _ordinal_profile(space: Space, evaluate, history: list[dict], ordinal: list[int], per_value: int) -> None:
    """Profile the ordinal parameters (a filter's order): from the best point, every other value in
    turn, stepping away from it in both directions, each a short local fit of the continuous
    parameters (:func:`_local`, *per_value* evaluations) that starts where its neighbour's ended
    (the matching corner moves smoothly with the order); then a last local fit at the best value.
    Nelder-Mead on a rounded coordinate stays at the value where the design found its best point:
    a 3-pole 6.4 kHz low-pass came back as 5 poles at 7.6 kHz (score 1.2e5 against 2.4 at the true
    order) or 2 poles at 5.5 kHz, depending on the seed."""
    free = [j for j in range(space.dims) if j not in ordinal]
    for j in ordinal:
        e = space.numbers[j]
        best = min(history, key=lambda h: h["score"])
        for direction in (1, -1):
            step, value = best, best["params"][e["name"]] + direction
            while e["low"] <= value <= e["high"]:
                u = step["u"].copy()
                u[j] = space.unit(e, value)
                step = _local(space, evaluate, u, best["choice"], free, per_value)
                value += direction
    best = min(history, key=lambda h: h["score"])
    _local(space, evaluate, best["u"], best["choice"], free, 2 * per_value)


def _inside(space: Space, guess: dict) -> bool:
    """A guess that names known parameters, within their bounds (a plugin's guess is not trusted blindly)."""
    entries = {e["name"]: e for e in space.numbers + space.options}
    for name, value in guess.items():
        e = entries.get(name)
        if e is None or ("choices" in e and value not in e["choices"]):
            return False
        if "choices" not in e and not (isinstance(value, numbers.Real) and e["low"] <= value <= e["high"]):
            return False
    return True


# --- one fit: the executor's unit of work ------------------------------------------------------------


def fit_effect(task: tuple) -> dict:
    """Fit effect *name* on top of the *accepted* effects: task = (source spec, effect name,
    accepted effects (canonical), target_X, settings, seed, nuisance, rows (a :class:`Rows`)[, start[,
    refit]]). The source spec is already the search spec (healthy only, the search's noise seed). *start*:
    the parameters of the effect's coarse fit in its round (None: the whole search): then only the fine
    stage runs, from there (:func:`_fine_stage`). *refit*: the indices of accepted signal-level effects
    fitted again at every point (:class:`_SignalRefit`). Returns the best parameters, their score (the gap
    total), the intervals, and how many evaluations and seconds it took."""
    source, name, accepted, target_X, settings, seed, nuisance, rows, *rest = task
    start = rest[0] if rest else None
    refit = tuple(rest[1]) if len(rest) > 1 else ()
    nuisance = bool(nuisance)  # fit sensor noise jointly at every point (see _NoiseNuisance)
    started = time.perf_counter()
    if name is None:
        return _refit_alone(source, accepted, target_X, settings, seed, started, rows)
    registry = get_registry()
    effect = registry.get("effect", name)
    space = Space(effect, source)
    scorer = _scorer(target_X, source, settings, rows)
    errors: list[str] = []

    current = list(accepted)  # the accepted effects a point is scored beside (refit: its own signal fits)

    def spec_of(params: dict, extra: tuple = ()) -> DatasetSpec:
        return source.with_(effects=_by_level(source.effects + tuple(current) + (effect.spec(params),) + extra))

    noise = _NoiseNuisance(lambda params, extra: rows(spec_of(params, extra)), scorer) if nuisance else None
    signal = _SignalRefit(current, refit, lambda params, extra: rows(spec_of(params, extra)), scorer) if refit else None

    def objective(params: dict) -> float:
        try:
            if effect.level == "model":
                settles(spec_of(params))
            if signal is not None:
                signal.begin()
            value = noise.fit(params) if noise is not None else scorer.score(rows(spec_of(params)))
            if signal is not None:
                extra = (noise.effect.spec(noise.at[_key(params)]),) if noise is not None else ()
                value = signal.fit(params, value, extra)
            return value
        except GearlabInputError as exc:  # parameters the effect cannot take here (a tone above Nyquist)
            errors.append(str(exc))
            return math.inf

    evaluations = settings.budget * (
        (NUISANCE_SIGNAL_EVALS if nuisance else SIGNAL_EVALS)
        if effect.level == "signal"
        else max(1, math.ceil(space.dims / MODEL_DIMS))
    )
    with warnings.catch_warnings():
        # Searched parameters stray where the simulator warns (too few steps per period of a
        # stiff mounting's natural frequency); one line per point would bury the progress.
        warnings.simplefilter("ignore", UserWarning)
        guesses = [g for g in effect.guesses(scorer.target, operating_point(source)[0]) if _inside(space, g)]
        if getattr(effect, "guesses_on_top", False):  # a grid of the effect's own (drive_inertias): its design
            evaluations += len(guesses)
        if start is None:
            history = _fit_search(
                space, objective, evaluations, seed, guesses=guesses, guess_step=getattr(effect, "guess_step", None)
            )
        else:  # the coarse fit's best point, its noise fitted again: where the fine stage starts
            history = _fit_search(space, objective, 1, seed, start=start)
        if start is not None and _fine(effect, space, settings):

            def held(params: dict, extra: tuple) -> float:
                try:
                    settles(spec_of(params))
                    return scorer.score(rows(spec_of(params, extra)))
                except GearlabInputError as exc:
                    errors.append(str(exc))
                    return math.inf

            def spread(params: dict, extra: tuple) -> float:
                X = rows(spec_of(params, extra))
                return float(np.std(scorer.replicates(X, NOISE_REPLICATES, [seed, 2])))

            history = _fine_stage(space, history, held, spread, noise, seed)
        law = None
        if name == NUISANCE:
            # The noise alone gets the same wide Brent search that the other candidates' noise
            # nuisance gets, so that "beats the noise alone" compares like with like.
            wide = _NoiseNuisance(
                lambda _, extra: rows(source.with_(effects=_by_level(source.effects + tuple(accepted) + extra))),
                scorer,
            )
            try:
                value = wide.fit({})
                # Its law is the one the residual's tails decide, not the more flexible one that the
                # score may prefer within its noise (_NoiseNuisance).
                law = wide.tails_at[()]
                kind = wide.at[()]["kind"]
                history = [h for h in history if h["params"]["kind"] == kind]
                history.append({"u": None, "choice": None, "params": dict(wide.at[()]), "score": value})
            except GearlabInputError as exc:
                errors.append(str(exc))
    best = min(history, key=lambda h: h["score"])
    if signal is not None:  # the accepted signal effects as fitted beside the best point
        signal.at_point(best["params"])
    result = {
        "name": name,
        "level": effect.level,
        "score": best["score"],
        "evaluations": len(history),
        "params": _plain(best["params"]),
        "intervals": {},
        "seconds": 0.0,
    }
    if law:
        result["tails"] = law  # each law's distance from the target's tails: what chose it
    extra: tuple = ()
    if noise is not None and math.isfinite(best["score"]):
        fitted_noise = noise.at[_key(best["params"])]
        extra = (get_registry().get("effect", NUISANCE).spec(fitted_noise),)
        result["nuisance"] = {
            "name": NUISANCE,
            "params": _plain(fitted_noise),
            "evaluations": noise.evaluations,
            "tails": noise.tails_at[_key(best["params"])],  # each law's distance from the target's tails
        }
    if accepted and math.isfinite(best["score"]):
        # Backfitting: the effects accepted earlier were fitted without this one (a noise level
        # fitted on the wrong model is off), so each is refined once more next to it.
        refit, score, used = _backfit(
            source,
            tuple(current),
            (effect.spec(best["params"]),) + extra,
            scorer,
            best["score"],
            max(2, evaluations // 2),
            seed,
            rows,
        )
        result["evaluations"] += used
        result["score"], result["accepted"] = score, [[n, [list(kv) for kv in p]] for n, p in refit]
    if math.isfinite(best["score"]):
        # The score's own noise: bootstrap replicates of the best point's gap total.
        reps = scorer.replicates(rows(spec_of(best["params"], extra)), NOISE_REPLICATES, [seed, 2])
        result["noise"] = float(np.std(reps))
        result["intervals"] = _intervals(space, history, best, result["noise"])
        result["determined"] = determined(space, result["intervals"])
    else:
        result["error"] = errors[-1] if errors else "no evaluation succeeded"
    result["seconds"] = time.perf_counter() - started
    return result


# The most revolutions a searched model may take to settle (builder.settle_revolutions: its slowest mode
# decayed to STEADY_RTOL twice over): half the 512 a faulty record's build may run (a crack repeats
# every 2 revolutions, up to 256 of them). The healthy search rows settle on fewer, so a fit could end
# where the corrected source's faulty records did not settle: a development drive (I22 0.055, k_c 1.7e5,
# c_c 1.2; slowest mode 2.8 1/s, 316 revolutions at 32.6 Hz) failed the build of its crack records.
SETTLE_MOST = 256


def settles(spec: DatasetSpec) -> None:
    """Refuse (GearlabInputError) a source whose model settles on more than SETTLE_MOST revolutions."""
    speed = operating_point(spec)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        sim = _configured_simulator(spec.model_config(), MODES_FS * speed, False)
    if (turns := settle_revolutions(sim, speed)) > SETTLE_MOST:
        raise GearlabInputError(f"the model settles on {turns} revolutions (most {SETTLE_MOST}): not searched")


MODES_FS = 4096  # samples a revolution of the simulator the modes are read from (any rate: they are M, K, C's)


def _fine(effect, space: Space, settings: Settings) -> bool:
    """Whether an effect's fits get the fine stage (:func:`_fine_stage`): model-level, more than
    MODEL_DIMS parameters (casing_path, drive_inertias), and the default budget or more (--quick
    keeps the coarse search alone, and says that it may miss)."""
    return effect.level == "model" and space.dims > MODEL_DIMS and settings.budget >= Settings().budget


def _fine_stage(
    space: Space,
    history: list[dict],
    held: Callable[[dict, tuple], float],
    noise_of: Callable[[dict, tuple], float],
    noise,
    seed: int,
) -> list[dict]:
    """Coarse to fine, for a model-level effect of more than MODEL_DIMS parameters (casing_path,
    drive_inertias): from the coarse search's best point, the profile's own search
    (gearlab.gap.identify.profile: a second fit from distant starts, then each parameter moved along
    the score's valley and the others re-fitted, again around every better point found).
    The noise nuisance is *held* at the best point's noise and fitted again only where a point beats
    the best so far (fitted at every point it made each evaluation three to four times dearer; held
    at the coarse best's, it stood in for part of that point's misfit and kept the fine stage from
    the truth). *noise_of(params, extra)*: the score's bootstrap spread there. The coarse search (48
    simulations for the casing's five parameters) stopped 1e3-1e4 times above the truth's score on a
    development casing; what it left was taken up by a second round of every candidate (a sensor
    filter fitted and re-fitted beside it) and found only by the final profile. Returns *history*
    with the fine points."""
    best = min(history, key=lambda h: h["score"])
    if not math.isfinite(best["score"]):
        return history
    seen = {_key(h["params"]): h["score"] for h in history}
    trail = [best]
    now = {"best": best, "extra": ()}
    if noise is not None:
        now["extra"] = (noise.effect.spec(noise.at[_key(best["params"])]),)

    def score(params: dict) -> float:
        key = _key(params)
        if key in seen:
            return seen[key]
        value = held(params, now["extra"])
        if noise is not None:
            top = _key(now["best"]["params"])
            noise.at[key], noise.tails_at[key] = noise.at[top], noise.tails_at[top]  # what it was scored with
            if value < now["best"]["score"]:
                try:
                    refit = noise.fit(params)  # records its noise in noise.at[key] ...
                except GearlabInputError:
                    refit = math.inf
                if refit <= value:
                    value = refit
                    now["extra"] = (noise.effect.spec(noise.at[key]),)
                else:  # ... unless the held one scores lower
                    noise.at[key], noise.tails_at[key] = noise.at[top], noise.tails_at[top]
        seen[key] = value
        u, choice = space.point_of(params)
        trail.append({"u": u, "choice": choice, "params": dict(params), "score": value})
        if value < now["best"]["score"]:
            now["best"] = trail[-1]
        return value

    profile(space, score, lambda params: noise_of(params, now["extra"]), dict(best["params"]), [seed, 17], {})
    return history + trail[1:]


def _backfit(
    source: DatasetSpec,
    accepted,
    beside: tuple,
    scorer: Scorer,
    score: float,
    evaluations: int,
    seed: int,
    rows: Rows,
) -> tuple[list, float, int]:
    """Refine each accepted effect once more, from its fitted values, with the effects *beside*
    it held fixed: a local search of *evaluations* points per effect (signal-level ones cost no
    simulation: the clean revolution is cached). Returns (re-fitted effects, score, evaluations)."""
    registry = get_registry()
    refit, used = list(accepted), 0
    for i, (other, params) in enumerate(accepted):
        effect = registry.get("effect", other)

        def objective(p, i=i, effect=effect):
            trial = refit[:i] + [effect.spec(p)] + refit[i + 1 :]
            try:
                spec = source.with_(effects=_by_level(source.effects + tuple(trial) + beside))
                if effect.level == "model":
                    settles(spec)
                return scorer.score(rows(spec))
            except GearlabInputError:
                return math.inf

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            history = _fit_search(Space(effect), objective, evaluations, seed + i + 1, start=dict(params))
        used += len(history)
        if effect.noise:
            # A noise's law stays the one its tails decided (_NoiseNuisance): only its level is refined.
            history = [h for h in history if h["choice"] == history[0]["choice"]]
        top = min(history, key=lambda h: h["score"])
        if top["score"] < score:
            score, refit[i] = top["score"], effect.spec(top["params"])
    return refit, score, used


def _refit_alone(
    source: DatasetSpec, accepted, target_X, settings: Settings, seed: int, started: float, rows: Rows
) -> dict:
    """A later round's baseline (the task with no candidate): the accepted effects re-fitted
    alone, with at least the local search that any candidate's backfitting gives them. Without
    it a candidate would be credited with the better fit of the effects before it — an
    imperfect first fit leaves a residual that any flexible extra effect (noise, a filter, a
    tone) partly absorbs, and extras the target does not have were accepted."""
    scorer = _scorer(target_X, source, settings, rows)
    score = scorer.score(rows(source.with_(effects=_by_level(source.effects + tuple(accepted)))))
    refit, score, used = _backfit(
        source, accepted, (), scorer, score, max(2, SIGNAL_EVALS * settings.budget // 2), seed, rows
    )
    return {
        "name": None,
        "score": score,
        "evaluations": used,
        "params": {},
        "accepted": [[n, [list(kv) for kv in p]] for n, p in refit],
        "seconds": time.perf_counter() - started,
    }


def _key(params: dict) -> tuple:
    return tuple(sorted((k, v if isinstance(v, str) else float(v)) for k, v in params.items()))


class _NoiseNuisance:
    """Sensor noise fitted at every point of another effect's search (a nuisance parameter).

    With a noisy target, a structural candidate judged without noise loses to a noise-like one
    whatever it explains; fitted with the noise that the target needs next to it, it is judged on
    what it adds. The noise is a signal-level effect (no new simulation). The first point gets a
    wide search (bounded Brent over the whole SNR range for every kind); later points a local one
    (within ±NUISANCE_STEP dB).

    **The noise law** (Gaussian, Laplace, Student-t) is decided at every point by the residual's
    tails (:func:`tail_shape`): each law is made at the point's fitted SNR, and the one whose rows'
    tails lie nearest the target's gives the point its score. Chosen by the score, the more flexible
    law won within the score's noise: Gaussian noise at 17.4 dB came out Laplace (6.45 against 6.67
    for the true law on the search rows), and a load ripple with Gaussian noise beside it then removed
    85 % of what that Laplace noise left, on fresh rows, and was named first. Decided once at the
    first point (a candidate's defaults), the law was wrong wherever the candidate itself changes the
    residual: a tone's defaults (24.75 Hz at half the signal's RMS) made Laplace noise beside a 180 Hz
    tone come out Student-t."""

    def __init__(self, rows_of: Callable[[dict, tuple], np.ndarray], scorer: Scorer):
        self.effect = get_registry().get("effect", NUISANCE)
        space = {e["name"]: e for e in self.effect.space()}
        self.low, self.high = space["snr_db"]["low"], space["snr_db"]["high"]
        self.kinds = list(space["kind"]["choices"])
        self.rows_of, self.scorer = rows_of, scorer
        self.best: tuple[float, dict] | None = None  # best (score, noise) over all points
        self.at: dict = {}  # point -> its fitted noise
        self.tails_at: dict = {}  # point -> each law's distance from the target's tails (the decision)
        self.evaluations = 0

    def _rows(self, params: dict, noise: dict) -> np.ndarray:
        self.evaluations += 1
        return self.rows_of(params, (self.effect.spec(noise),))

    def _brent(self, params: dict, kind: str, lo: float, hi: float, iterations: int) -> dict:
        from scipy.optimize import minimize_scalar

        res = minimize_scalar(
            lambda s: self.scorer.score(self._rows(params, {"snr_db": float(s), "kind": kind})),
            bounds=(lo, hi),
            method="bounded",
            options={"maxiter": iterations, "xatol": 0.2},
        )
        return {"snr_db": float(res.x), "kind": kind}

    def fit(self, params: dict) -> float:
        """The score at *params* with the noise fitted beside it: its level by Brent (every law over
        the whole range at the first point; the best point's law within ±NUISANCE_STEP dB of its level
        later, the other laws at that level), its law by the tails."""
        if self.best is None:
            levels = [self._brent(params, kind, self.low, self.high, NUISANCE_WIDE) for kind in self.kinds]
        else:
            s0, k0 = self.best[1]["snr_db"], self.best[1]["kind"]
            lo, hi = max(self.low, s0 - NUISANCE_STEP), min(self.high, s0 + NUISANCE_STEP)
            first = self._brent(params, k0, lo, hi, NUISANCE_LOCAL)
            levels = [first] + [{"snr_db": first["snr_db"], "kind": k} for k in self.kinds if k != k0]
        target, found, tails = self.scorer.tails, None, {}
        for noise in levels:
            X = self._rows(params, noise)
            tails[noise["kind"]] = float(np.abs(tail_shape(X) - target).sum())
            if found is None or tails[noise["kind"]] < tails[found[1]["kind"]]:
                found = (self.scorer.score(X), noise)
        key = _key(params)
        self.at[key], self.tails_at[key] = found[1], tails
        if self.best is None or found[0] < self.best[0]:
            self.best = found
        return found[0]


# A local fit of each re-fitted signal effect (_SignalRefit) at a point of a search: evaluations per
# continuous parameter, and one.
SIGNAL_REFIT_EVALS = 4


class _SignalRefit:
    """Accepted signal-level effects (a sensor filter) fitted again at every point of a model-level
    candidate's search: a short local fit of their continuous parameters (SIGNAL_REFIT_EVALS), from where
    they stood at the best point so far, the noise nuisance held at the point's. No new simulation: a
    signal effect transforms the point's clean revolution.

    A filter fitted alone, before the model effect beside it, took part of that effect's signature: on
    development trial 902/4 (a bearing behind a 7.1 kHz resonance) round 1's resonance sat at 6.2 kHz, and
    beside it the true bearing scored 318 and a softer one 121, so the search ended there (k 0.25 for
    0.58); with the resonance fitted again beside each point the truth scores 3.5, and k 0.49, c 0.90 (near
    the bearing's defaults, the search's first point) 101 for that softer bearing's 110 (gearlab.gap.diagnose's
    filter_refit). Where round 1's filter only tied another shape, re-fitted it stood for the wrong one: on 1327/7
    (a drive behind a 4-pole low-pass at 4.8 kHz) a resonance and a 2-pole low-pass at 1.2 kHz scored 335 and 336
    alone (a tie on fresh rows); the resonance, re-fitted beside the drive, went to 4.4 kHz (zeta 0.2), whose gain
    over the strongest mesh lines (harmonics 4, 6 and 7, 4.4-7.7 kHz) is 2.5-3 times the 4-pole's, and the load read
    beside it paid for that gain (0.23 for 0.69; the truth scores 0.7, that pair 62): filter_refit runs only where
    round 1's filter beat the other filters on fresh rows."""

    def __init__(self, current: list, indices: tuple, rows_of: Callable[[dict, tuple], np.ndarray], scorer: Scorer):
        registry = get_registry()
        self.current, self.indices, self.rows_of, self.scorer = current, indices, rows_of, scorer
        self.effects = {j: registry.get("effect", current[j][0]) for j in indices}
        self.best: tuple[float, dict] | None = None  # best (score, the effects as fitted there) over all points
        self.at: dict = {}  # point -> the effects as fitted there

    def begin(self) -> None:
        """The point starts from the effects as fitted at the best point so far."""
        if self.best is not None:
            for j, spec in self.best[1].items():
                self.current[j] = spec

    def fit(self, params: dict, value: float, extra: tuple) -> float:
        """The score at *params* (*value* beside the effects as they stand) with each effect fitted again."""
        for j in self.indices:
            effect = self.effects[j]
            space = Space(effect)
            u0, choice = space.point_of(dict(self.current[j][1]))
            free = [i for i, e in enumerate(space.numbers) if not e["integer"] and e["high"] > e["low"]]

            def evaluate(u, choice, j=j, effect=effect, space=space) -> float:
                self.current[j] = effect.spec(space.params(np.clip(u, 0.0, 1.0), choice))
                return self.scorer.score(self.rows_of(params, extra))

            found = _local(space, evaluate, u0, choice, free, SIGNAL_REFIT_EVALS * len(free) + 1)
            if found["score"] < value:
                value, self.current[j] = found["score"], effect.spec(found["params"])
            else:
                self.current[j] = effect.spec(space.params(u0, choice))
        fitted = {j: self.current[j] for j in self.indices}
        self.at[_key(params)] = fitted
        if self.best is None or value < self.best[0]:
            self.best = (value, fitted)
        return value

    def at_point(self, params: dict) -> None:
        """The effects set as fitted at *params* (a point of the search)."""
        for j, spec in self.at.get(_key(params), {}).items():
            self.current[j] = spec


def quick_profile_evaluations(space: Space, settings: Settings) -> int | None:
    """The most score evaluations an effect's profile may make: none under the default budget or
    more; below it (--quick) QUICK_PROFILE_EVALS per budget unit and per parameter and one."""
    if settings.budget >= Settings().budget:
        return None
    return QUICK_PROFILE_EVALS * settings.budget * (space.dims + 1)


def profile_effect(task: tuple) -> dict:
    """Profile the *i*-th accepted effect: task = (search spec, accepted effects (canonical, the
    order they were accepted in), i, target_X, settings, seed, rows, the search's intervals), with
    the score the search used and the others held at their fits. Returns :func:`gearlab.gap.identify.profile`'s record
    with the effect's name and index."""
    search, fitted, i, target_X, settings, seed, rows, prior = task
    started = time.perf_counter()
    name, canonical = fitted[i]
    effect = get_registry().get("effect", name)
    scorer = _scorer(target_X, search, settings, rows)

    def rows_of(params: dict, checked: bool = True) -> np.ndarray:
        effects = _by_level(search.effects + fitted[:i] + (effect.spec(params),) + fitted[i + 1 :])
        if checked and effect.level == "model":
            settles(search.with_(effects=effects))
        return rows(search.with_(effects=effects))

    def score(params: dict) -> float:
        try:
            return scorer.score(rows_of(params))
        except GearlabInputError:  # a profile point the effect cannot take here
            return math.inf

    def noise(params: dict) -> float:
        # the score's noise at the point profiled: the bootstrap spread the search's intervals take
        return float(np.std(scorer.replicates(rows_of(params, False), NOISE_REPLICATES, [seed, 2])))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the simulator's accuracy warnings at odd parameters
        space = Space(effect)
        # a search with the fine stage has made the distant starts on this score; --quick's limited
        # profile spends its evaluations on the intervals, as its search keeps the coarse fit
        most = quick_profile_evaluations(space, settings)
        distant = not _fine(effect, space, settings) and most is None
        out = profile(space, score, noise, dict(canonical), seed, prior, distant=distant, evaluations=most)
    return {"index": i, "name": name, **out, "seconds": time.perf_counter() - started}
