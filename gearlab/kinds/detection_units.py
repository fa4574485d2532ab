"""The detection kind's learned units (gearlab.kinds.detection): one training of a method at one
condition (and seed, and left-out history record), the threshold rule that fixes a score's
threshold from the healthy history alone (Rule), the records of an ensemble of seeds and of a
crossed history fit, and what the source teaches: its training and held-out split and the bound
of its held-out ranking (source_bound)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..confined import Confined
from ..data.cache import load_or_build
from ..data.spec import DatasetSpec
from ..events import UnitProgress
from ..executors import one_thread, unshared
from ..learn import protocol as chapter5  # train_method looked up at call time (a test spies on it)
from ..learn.bounds import bayes_scores
from ..learn.history import gumbel_quantile
from ..learn.protocol import Method, Protocol, StateStore, domain_adapting, fault_score
from ..parts import scoring
from ..parts.roc import auc
from ..registry import get_registry
from . import record_effects
from .detection_records import unit_window


def to_lists(scores: dict) -> dict:
    return {k: (to_lists(v) if isinstance(v, dict) else [float(s) for s in v]) for k, v in scores.items()}


def seeds_of(method: Method, seeds: int) -> tuple:
    """The seeds a method is trained with: (None,) for one training (repetition 0, the record
    named after the method) and for a detector (no network, nothing random); else 0 … seeds-1,
    each a member of the method's ensemble."""
    if seeds == 1 or method.is_detector:
        return (None,)
    return tuple(range(seeds))


def unit_name(
    condition: str, method: Method, seed: int | None = None, variant: str = "", fold: int | None = None
) -> str:
    """A record's name in results.jsonl: one per condition, method and source (*variant*: the
    corrected source's label); an ensemble's members: one per seed besides; with
    history_fit = "crossed" the trainings that left out one history record (*fold*) besides."""
    return (
        f"{condition}/{method.key}"
        + (f"@{variant}" if variant else "")
        + ("" if seed is None else f"/seed{seed}")
        + ("" if fold is None else f"/fold{fold}")
    )


# The fewest history records of which each is scored by what the others made (without_each): a detector's
# reference and noise level (its median revolution, detectors.referenced_on), a classical indicator's windows.
# Made with a record's own units they are pulled towards them, so its scores are less than a new take's and the
# threshold set on them lets new healthy takes through above the rate asked. Two: each scored on the other take
# (synthetic rig records, 20 conditions of 2 history + 6 healthy new takes, 1 % asked: matched_filter's record10
# 7.7 -> 1.2 % of the new takes' units, record30 5.0 -> 0.8 %, a chip of 1/8 the size's record10 units 98 -> 96 %
# found; the classical indicators': detection_classical). A new take is then scored by the mean of those detectors
# (detectors.MeanOf), as the history was: likelihood_ratio divides by a unit's own residual scale, which holds its
# reference's error, so the detector made of both takes spread a new take's scores otherwise (record10 6.0 -> 4.0 %,
# record30 2.5 -> 1.7 %; fresh seeds 4.0 -> 3.5 %, 4.2 -> 2.5 %; matched_filter's record10 1.2 -> 2.1 %, fresh 0.8 ->
# 1.0 %; chips all found). What likelihood_ratio still let through was its scores' right skew (1.1-1.6 within a
# take), whose tail the normal quantile misses: a detector's threshold takes its scores' own law (within_laws)
LEFT_OUT = 2


def without_each(records: int, made_without: Callable) -> list | None:
    """What scores each of *records* history records: made_without(i), made of the records but i, for each
    i, of LEFT_OUT records or more; None below (each scored by what the whole history made)."""
    return [made_without(i) for i in range(records)] if records >= LEFT_OUT else None


def train_unit(task: tuple) -> dict:
    """One method at one condition (one seed of it), in this process or a worker: trained on the
    source and the history's training revolutions, then its scores of the history units (for the
    threshold; a detector handed *left_out*, the history rows without each record in turn: each
    record's units scored by the detector referenced without it) and, only now, of the test units (by
    the mean of those detectors where there are: detectors.MeanOf, the model kept for `gearlab score`). It
    says what it does from its start: torch takes seconds to load in a fresh worker (issue 41)."""
    (
        protocol,
        method,
        variant,
        condition,
        seed,
        fold,
        split,
        train,
        history_units,
        test_units,
        states,
        rule,
        whiten,
        left_out,
    ) = task
    started = time.perf_counter()
    Xs, ys, Xv, yv = unshared(split)  # (a local pool's workers read what every unit takes once: Shared)
    train, history_units, test_units = unshared(train), unshared(history_units), unshared(test_units)
    unit = unit_name(condition, method, seed, variant, fold)
    with UnitProgress(states.root, unit) as progress:
        progress("starting: importing torch")
        with one_thread():  # (torch loads here) the caller's thread count restored after
            from ..learn.training import pick_device  # here, not at the top: start-up time

            device = pick_device(protocol.device)
            point = aligned_to_a_point(protocol, method, Xs, ys)
            # Against a single point the domain discrepancy falls by a few per cent every 25 epochs for as
            # long as the training lasts: the stopping rule's "it has
            # stopped moving" never holds, and no epoch after the ramp is nearer convergence than the
            # ramp's end. Such a training ends there, at the first epoch its kept model may come from.
            trained = replace(protocol, max_epochs=protocol.min_epochs) if point else protocol
            progress("starting: training")

            def report(epoch: int, history, what: str = "") -> None:
                progress(what or f"epoch {epoch + 1}")  # what: a shared state's training (the priming)

            def made(rows: np.ndarray):
                model, history, _ = chapter5.train_method(
                    trained,
                    method,
                    (Xs, ys),
                    (Xv[:, 0] if Xv.ndim == 3 else Xv, yv),  # one draw decides when to stop: an epoch's cost
                    (rows, np.zeros(len(rows), dtype=np.int64)),
                    seed or 0,  # the repetition: its own torch seed and draws
                    0,
                    StateStore(states),
                    device,
                    report,
                )
                if whiten and method.is_detector:
                    # a detector sees every row through the whitening filter of its own history rows' residuals
                    # (gearlab.learn.whiten: their coloured leftover ranked single healthy revolutions); the
                    # filter is kept in the model, so the units below and `gearlab score`'s pass through it too
                    from ..learn.whiten import whitened, whitening_of

                    params = dict(method.params)
                    false_alarm = get_registry().get("detector", method.adapter).values(params)["false_alarm"]
                    model = whitened(model.to("cpu"), whitening_of(rows), rows, float(false_alarm)).to(device)
                return model, history

            model, history = made(train)
            if left_out is not None:  # the whole detector referenced on the history without each record in turn
                from ..learn.detectors import referenced_on

                others = [referenced_on(model, unshared(rows)) for rows in left_out]
                left_out = None if any(m is None for m in others) else others  # a plugin's own: in-sample
            # what a network learned of the simulator, from training data only: its scores of the source's
            # held-out revolutions, every draw of them (0.5: it does not tell the simulated fault from
            # healthy). A detector is built in the target's frame (the history's reference, the path to
            # it), where a source revolution means nothing.
            held_out = None if method.is_detector else fault_score(model, Xv.reshape(-1, Xv.shape[-1]), device)
            y_held = np.repeat(yv, len(held_out) // len(yv)) if held_out is not None else yv
            # the model is fixed: the history's units fix the thresholds, then the test units are scored
            if left_out is None:
                hist = {u: fault_score(model, X, device) for u, X in history_units.items()}
            else:  # each history record's units scored by the detector referenced without it
                from ..learn.detectors import MeanOf

                hist = {
                    u: np.concatenate([fault_score(m, X_k, device) for m, X_k in zip(left_out, rule.groups(u, X))])
                    for u, X in history_units.items()
                }
                model = MeanOf(left_out)  # and a new take by those detectors, their mean (detectors.MeanOf)
            laws = None
            if method.is_detector:  # a detector's scores need not be normal within a record (within_laws)
                parts = left_out or [model] * len(next(iter(rule.records.values())))  # what scored each record
                laws = within_laws(lambda i, X: fault_score(parts[i], X, device), rule, history_units, hist)
            fixed = rule.decide(hist, laws=laws)
            test = {
                path: {u: fault_score(model, X, device) for u, X in units.items()} for path, units in test_units.items()
            }
            # kept, so that `gearlab score` scores new records with it without training again
            scoring.save_model(Confined(states.root, scoring.MODELS), unit, model)
            return {
                "unit": unit,
                "condition": condition,
                "method": method_name(method, variant),
                "adapter": method.adapter,
                "source": variant or "source",
                "seed": seed,
                **({} if fold is None else {"fold": fold}),
                "history_scores": to_lists(hist),
                **fixed,
                "test_scores": to_lists(test),
                "history": history.as_dict() if history is not None else None,
                "source_auc": None if held_out is None else auc(held_out[y_held == 0], held_out[y_held != 0]),
                # held-out rows scored, healthy and faulty (every draw: for a network that has learned
                # nothing of the fault, its scores of the draws are as independent as those of samples)
                "source_units": [int(np.sum(y_held == 0)), int(np.sum(y_held != 0))],
                "aligned_to_a_point": point,
                "seconds": time.perf_counter() - started,
            }


def aligned_to_a_point(protocol: Protocol, method: Method, Xs: np.ndarray, ys: np.ndarray) -> bool:
    """Whether a method's domain loss aligns the history with a single point: a joint adapter whose
    source rows for the alignment (the healthy ones with alignment = "healthy", all of them with
    "marginal"), with no fresh noise on its batches, are one input over and over -- the difference
    signal of a noise-free simulator's healthy revolution, which is zero. The loss can then only
    pull every history unit onto the network's image of
    that input, and leaves a record unlike the history wherever the training's path puts it; such a
    training ends at its ramp's end (train_unit). From the training arrays alone."""
    if not domain_adapting(method.adapter) or protocol.calibration.source_noise != "off":
        return False
    rows = Xs[np.asarray(ys) == 0] if protocol.calibration.alignment == "healthy" else Xs
    rows = np.asarray(rows).reshape(-1, rows.shape[-1])  # draws, if any, are rows too
    return len(rows) > 0 and float(np.ptp(rows, axis=0).max()) <= 1e-6 * float(np.abs(rows).max())


DRAWS = 1000  # TSAs drawn again from each history record's revolutions (within_laws): 10 a record above 99 %


def within_laws(
    score: Callable, rule: Rule, history_units: dict, history_scores: dict
) -> dict[str, record_effects.WithinLaw] | None:
    """{unit kind: the law of a method's unit scores within a history record (record_effects.WithinLaw)}. A TSA's:
    for each record, `DRAWS` TSAs of its kind made of that record's own revolutions drawn again with replacement
    (the record's mean revolution plus the mean of the drawn revolutions' deviations from it, scaled by
    sqrt(n / (n - 1)) so that their mean varies as that of new revolutions: the same fixed part, another draw of
    the noise), scored by *score*(record index, units) as that record's history units were, less their mean,
    pooled over the records. A revolution's: the *history_scores* of the records' revolutions, less each record's
    mean (a revolution drawn again is one of them). Its variance is the model's sigma_e^2: a TSA's taken from the
    history's own sliding TSAs rests on a few independent ones (4.4 of 10 revolutions in a record of 44): on
    synthetic rig records (2 history takes, development seeds) half the redrawn TSAs' in some conditions, and
    likelihood_ratio let 0.83 -> 0.42 % of new takes' TSA10s through, 0.83 -> 0 % of their TSA30s (1 % asked;
    matched_filter's 0.62 -> 0 %, 0.83 -> 0.83 %; the chips all found); the redrawn TSAs of a soft maximum spread a
    little more than new ones (their noise lies in the span of a record's revolutions), so it errs high. Its
    shape sets the quantile: a soft maximum over many shapes, likelihood_ratio's log-sum-exp, is skewed to the
    right where the normal quantile is symmetric (record_effects' docstring). Only the history enters. None
    without the history's revolutions (units handed without them: the units' own spread, the normal quantile)."""
    if "revolution" not in history_units:
        return None
    rng = np.random.default_rng(0)
    groups = rule.groups("revolution", history_units["revolution"])
    laws = {}
    for u in history_units:
        if u == "revolution":
            parts = [s - s.mean() for s in rule.groups(u, history_scores[u])]
        else:
            block, parts = unit_window(u)[0], []
            for i, revs in enumerate(groups):
                mean = revs.mean(axis=0, dtype=np.float64)
                spread = np.sqrt(len(revs) / max(len(revs) - 1, 1))
                drawn = rng.multinomial(block, np.full(len(revs), 1.0 / len(revs)), size=DRAWS) / block
                # in float32, as they are scored: the float64 product (1000 x 39 @ 39 x 4096 a record) was 2/3 of
                # the time here; its TSAs differ from the float64 ones by 2 float32 roundings (5e-7 of 2.2)
                tsas = (spread * drawn).astype(np.float32) @ (revs - mean).astype(np.float32)
                tsas += mean.astype(np.float32)
                s = score(i, tsas)
                parts.append(s - s.mean())
        law = np.concatenate(parts)
        variance = float(np.sum(law**2)) / max(len(law) - len(parts), 1)
        laws[u] = record_effects.WithinLaw(
            law / max(float(law.std()), 1e-300), variance, float(sum(len(r) - 1 for r in groups))
        )
    return laws


@dataclass(frozen=True)
class Rule:
    """How a threshold is fixed from the history's unit scores alone ([detection] threshold and
    false_alarm), with the history's record structure: {unit: [(units, independent units) per
    history record, in the order of the concatenated scores]}."""

    how: str
    false_alarm: float
    records: dict

    def groups(self, u: str, scores) -> list[np.ndarray]:
        """The history's *scores* (or units, rows) of unit kind *u*, one array per history record."""
        counts = [n for n, _ in self.records[u]]
        scores = np.asarray(scores)
        return np.split(scores if scores.ndim > 1 else scores.astype(np.float64), np.cumsum(counts)[:-1])

    def model(self, u: str, scores, keep=None, floor: float | None = None, law=None) -> record_effects.RecordEffects:
        """The random-effects model (record effect + within-record spread) of the history's *scores*
        of unit kind *u*, over the records *keep* (default: all); *floor*: the scores are sizes above it;
        *law*: their within-record law, a detector's (record_effects.WithinLaw, fit)."""
        groups = self.groups(u, scores)
        keep = range(len(groups)) if keep is None else keep
        return record_effects.fit(
            [groups[i] for i in keep],
            1.0 - self.false_alarm,
            [self.records[u][i][1] for i in keep],
            [record_effects.overlap_dof(self.records[u][i][0], *unit_window(u)) for i in keep],
            floor,
            law,
        )

    def models(
        self, history_scores: dict, floor: float | None = None, laws: dict | None = None
    ) -> dict[str, record_effects.RecordEffects]:
        """{unit: the random-effects model of its scores} (*laws*: {unit: its within-record law})."""
        return {u: self.model(u, s, floor=floor, law=(laws or {}).get(u)) for u, s in history_scores.items()}

    def decide(self, history_scores: dict, floor: float | None = None, laws: dict | None = None) -> dict:
        """The record's "thresholds" (by this rule), the history models and both rules' thresholds
        (so a run shows what the other rule would have called); *floor*: the scores are sizes above it
        (NA4), modelled on the log scale; *laws*: {unit: the scores' within-record law}, a
        detector's (`within_laws`; record_effects.fit)."""
        models = self.models(history_scores, floor, laws)
        by_rule = {
            "records": {u: m.threshold for u, m in models.items()},
            # the 1 - false_alarm quantile of the Gumbel law fitted by its quartiles to the pooled
            # history units (gearlab.learn.history.gumbel_quantile)
            "pooled": {
                u: gumbel_quantile(np.asarray(s, dtype=np.float64), 1.0 - self.false_alarm)
                for u, s in history_scores.items()
            },
        }
        return {
            "thresholds": by_rule[self.how],
            "thresholds_by_rule": by_rule,
            "history_models": {u: m.as_dict() for u, m in models.items()},
        }


def ensemble_record(unit: str, members: list[dict], rule: Rule) -> dict:
    """A method trained with several seeds: each member's scores standardised by its own history
    model (mean and predictive spread of a new healthy record's units, so the members' logit
    scales compare), their median per unit, thresholded by *rule* on the history like any score."""
    models = [rule.models(m["history_scores"]) for m in members]

    def median(get) -> np.ndarray:
        return np.median(np.stack([get(m, ms) for m, ms in zip(members, models)]), axis=0)

    hist = {
        u: median(lambda m, ms, u=u: ms[u].standardised(m["history_scores"][u])) for u in members[0]["history_scores"]
    }
    test = {
        path: {u: median(lambda m, ms, p=path, u=u: ms[u].standardised(m["test_scores"][p][u])) for u in units}
        for path, units in members[0]["test_scores"].items()
    }
    first = members[0]
    return {
        "unit": unit,
        "condition": first["condition"],
        "method": first["method"],
        "adapter": first["adapter"],
        "members": [m["unit"] for m in members],
        "history_scores": to_lists(hist),
        **rule.decide(hist),
        "test_scores": to_lists(test),
        **trained_together(members),
    }


def trained_together(parts: list[dict]) -> dict:
    """An ensemble's or a crossed training's source AUC (the median of its parts') and training
    time (their sum); nothing for records written before units kept them."""
    aucs = [p["source_auc"] for p in parts if p.get("source_auc") is not None]
    if not all("seconds" in p and "source_units" in p for p in parts):
        return {}
    return {
        "source_auc": float(np.median(aucs)) if aucs else None,
        "part_source_auc": [p.get("source_auc") for p in parts],
        "source_units": parts[0]["source_units"],  # one held-out split for every part
        "source": parts[0].get("source", "source"),
        "aligned_to_a_point": any(p.get("aligned_to_a_point", False) for p in parts),
        "seconds": float(sum(p["seconds"] for p in parts)),
    }


def crossed_record(unit: str, folds: list[dict], rule: Rule) -> dict:
    """One training's scores made from its folds (history_fit = "crossed"): fold k was trained with
    history record k left out of its training rows. Each fold's scores are standardised by the
    model of the records it trained on (record_effects; with one record, its mean and within-record
    spread), so record k's units, standardised by fold k, are what a *new* record's units score
    against a model aligned to the others -- the record-to-record spread the threshold needs, which
    a network scoring the very records it was aligned to hides (on the PHM 2009 records, with TSAs
    of the history as the target: the history's two records 0.0-0.4 sigma_e apart, a new take of the
    eccentric idler 0.1-5.5). A test unit's score is the mean over the folds (none saw it).
    Thresholded by *rule* on the history scores so made."""
    first = folds[0]
    hist: dict[str, np.ndarray] = {}
    test: dict[str, dict[str, np.ndarray]] = {p: {} for p in first["test_scores"]}
    for u in first["history_scores"]:
        out, tests = [], []
        for k, fold in enumerate(folds):
            scores = fold["history_scores"][u]
            model = rule.model(u, scores, keep=[i for i in range(len(folds)) if i != k])
            out.append(model.standardised(rule.groups(u, scores)[k]))
            tests.append({p: model.standardised(fold["test_scores"][p][u]) for p in fold["test_scores"]})
        hist[u] = np.concatenate(out)
        for p in test:
            test[p][u] = np.mean([t[p] for t in tests], axis=0)
    return {
        "unit": unit,
        "condition": first["condition"],
        "method": first["method"],
        "adapter": first["adapter"],
        "seed": first["seed"],
        "folds": [f["unit"] for f in folds],
        "history_scores": to_lists(hist),
        **rule.decide(hist),
        "test_scores": to_lists(test),
        **trained_together(folds),
    }


def method_name(m: Method, variant: str = "") -> str:
    return m.adapter + "".join(f", {k}={v}" for k, v in m.shown) + (f" ({variant})" if variant else "")


def source_split(source, protocol: Protocol, draws: int = 1):
    """The source's training and held-out samples (X, y, X, y); with *draws* > 1 the dataset's
    runs of that many noise draws of one sample (corrected_spec) as X (n, draws, L), split by
    sample, so that no draw of a held-out sample is trained on."""
    X, y = source.X, source.fault.astype(np.int64)
    if draws > 1:
        X, y = X.reshape(-1, draws, X.shape[-1]), y[::draws]
    rng = np.random.default_rng([protocol.seed, 0])
    order = rng.permutation(len(X))
    n_val = max(1, round(protocol.val_fraction * len(order)))
    tr, va = np.sort(order[n_val:]), np.sort(order[:n_val])
    return X[tr], y[tr], X[va], y[va]


def noise_effects(spec: DatasetSpec) -> list:
    """The effects of *spec* that declare themselves noise."""
    registry = get_registry()
    return [e for e in spec.effects if getattr(registry.get("effect", e[0]), "noise", False)]


def noise_free_twin(spec: DatasetSpec, draws: int) -> DatasetSpec:
    """*spec* less its noise effects, one sample for each of its runs of *draws* noise draws: sample
    i of the twin is the noise-free signal of draws i·draws ... (i + 1)·draws - 1 of *spec*."""
    noise = noise_effects(spec)
    return spec.with_(
        effects=tuple(e for e in spec.effects if e not in noise),
        duplicates=spec.duplicates // draws,
        healthy=spec.healthy // draws,
        name=f"{spec.name} (noise free)",
        domain=f"{spec.name} (noise free)",
    )


def healthy_twin(spec: DatasetSpec) -> DatasetSpec:
    """*spec*'s healthy twin (DatasetSpec.healthy_twin): row i is sample i with its fault taken out."""
    return spec.with_(healthy_twin=True, name=f"{spec.name} (healthy twin)", domain=f"{spec.name} (healthy twin)")


def signature_rows(X: np.ndarray, y: np.ndarray, twin: np.ndarray) -> np.ndarray:
    """The source's training rows *X* ((n, L), or (n, D, L) draws) as a detector's templates should
    see them: each fault row less its healthy twin (*twin*, the same rows of the healthy twin
    dataset, as the learned methods see them), put on the healthy rows' median, from which the
    detectors take their shapes (gearlab.learn.detectors). A detector's shape is then the
    simulated fault alone. On a train whose later mesh is no whole input order a fault row minus
    the healthy median holds mostly the row's own revolution of the cycle (what the input's fit of
    that mesh leaves: its shaft's sidebands, the order bins beside it), not the fault: on the
    18/67 + 29/71 development records 90 % of each template, by which the best template then
    ranked single healthy revolutions (likelihood_ratio's revolution AUC 0.38). The twin shares
    the row's cycle revolution, tooth turn, effects and noise draws, so the difference is the
    fault's response."""
    mean = X.mean(axis=1) if X.ndim == 3 else X
    out = np.array(X, copy=True)
    out[y == 1] = np.median(mean[y == 0], axis=0) + (X[y == 1] - twin[y == 1])
    return out


def source_bound(spec: DatasetSpec, source, protocol: Protocol, draws: int, executor, on_event) -> float | None:
    """The best ranking of the source's held-out samples (every draw) that any learned method could
    reach: the ROC AUC of the likelihood-ratio detector that knows the source's noise-free fault
    shapes and its noise law (gearlab.learn.bounds), the shapes from the source's noise-free twin
    (its effects less the one that declares itself noise). From training data only. None for a
    source with no noise effect (noise free: every simulated fault differs from healthy) or more
    than one (no single law)."""
    noise = noise_effects(spec)
    if len(noise) != 1:
        return None
    clean, _ = load_or_build(noise_free_twin(spec, draws), executor, on_event)
    Xs, ys, Xv, yv = source_split(source, protocol, draws)
    healthy = Xs[ys == 0].reshape(-1, Xs.shape[-1])  # fixes the scale between the twin and the source
    kind = dict(noise[0][1]).get("kind", "gaussian")
    scores = bayes_scores(Xv.reshape(-1, Xv.shape[-1]), healthy, clean, kind)
    y = np.repeat(yv, len(scores) // len(yv))
    return auc(scores[y == 0], scores[y != 0])
