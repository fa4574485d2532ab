"""Issue 39: a detector's threshold from a history of few takes. A detector is made of the history
itself (its reference the history's median revolution, its noise level the history's), so a history
take scores nearer it than a new take of the same gearbox does; with three takes, the threshold set on
those scores let a new healthy take's units through far more often than asked. Each history take is
now scored by the detector made without it (detection_units.train_unit's *left_out*)."""

from __future__ import annotations

import numpy as np
import torch

from gearlab.confined import Confined
from gearlab.kinds import record_effects
from gearlab.kinds.detection_records import tsa_units
from gearlab.kinds.detection_units import Rule, train_unit, without_each
from gearlab.learn.detector_contract import Detector
from gearlab.learn.protocol import Method, Protocol

L = 512  # samples per revolution
THETA = 2 * np.pi * np.arange(L) / L
TEETH = 37
BLOCK, STRIDE = 10, 1  # record10: the history's sliding windows (detection_records.unit_window)


def take(rng, revolutions: int = 40, chip: float = 0.0) -> np.ndarray:
    """A take of a one-stage box: its own mounting gain, path phase and size of each mesh harmonic
    and noise level (what differs between takes), a chip's ring on one tooth when *chip*."""
    gain, phase, size = np.exp(rng.normal(0, 0.15)), rng.normal(0, 0.3, 3), np.exp(rng.normal(0, 0.15, 3))
    lift = 1 + 0.1 * np.cos(THETA + 0.3)  # the pinion's runout: sidebands about each harmonic
    mesh = enumerate(zip((1, 0.5, 0.25), size, phase))
    x = gain * lift * sum(a * s * np.cos((h + 1) * TEETH * THETA + p) for h, (a, s, p) in mesh)
    # what the take's mounting passes of the box's broadband synchronous content: its own at each order
    orders = np.arange(50, 200)
    x = x + 0.03 * np.cos(orders[:, None] * THETA + rng.uniform(0, 2 * np.pi, (orders.size, 1))).sum(axis=0)
    since = np.angle(np.exp(1j * (THETA - 2 * np.pi * 11.5 / TEETH)))  # tooth 11
    x = x + chip * np.where(since > 0, np.exp(-since * TEETH / 2.0), 0.0) * np.sin(120 * since)
    noise = 0.5 * np.exp(rng.normal(0, 0.25))
    return x + rng.normal(0, noise, (revolutions, L))


def source() -> tuple[np.ndarray, np.ndarray]:
    """The simulator's rows: the nominal healthy revolution, and the chip's ring on every tooth."""
    healthy = sum(a * np.cos((h + 1) * TEETH * THETA) for h, a in enumerate((1, 0.5, 0.25)))
    chips = []
    for tooth in range(TEETH):
        since = np.angle(np.exp(1j * (THETA - 2 * np.pi * (tooth + 0.5) / TEETH)))
        chips.append(healthy + np.where(since > 0, np.exp(-since * TEETH / 2.0), 0.0) * np.sin(120 * since))
    return np.array([healthy] * 20 + chips), np.array([0] * 20 + [1] * TEETH)


def called(seed: int, tmp_path, left_out: bool, takes: int = 3) -> tuple[float, float]:
    """(share of new healthy takes' record10 units called, of chipped takes') by matched_filter at 1 %
    asked, thresholded on *takes* history takes (*left_out*: each scored as detection.run scores it,
    without_each)."""
    rng = np.random.default_rng([seed, 39])
    history = [take(rng) for _ in range(takes)]
    tests = {f"h{i}": take(rng) for i in range(4)} | {f"f{i}": take(rng, chip=6.0) for i in range(2)}
    units = [tsa_units(h, BLOCK, STRIDE) for h in history]
    rule = Rule(
        "records",
        0.01,
        {"record10": [(len(u), record_effects.independent_units(len(u), BLOCK, STRIDE)) for u in units]},
    )
    Xs, ys = source()
    rows = without_each(takes, lambda k: np.concatenate([h for j, h in enumerate(history) if j != k]))
    task = (
        Protocol(methods=(Method("matched_filter", False),)),
        Method("matched_filter", False),
        "",
        "c",
        None,
        None,
        (Xs, ys, Xs[:4], ys[:4]),
        np.concatenate(history),
        {"record10": np.concatenate(units)},
        {p: {"record10": tsa_units(x, BLOCK)} for p, x in tests.items()},
        Confined(tmp_path, ("states",)),
        rule,
        False,
        tuple(rows) if left_out and rows else None,
    )
    record = train_unit(task)
    threshold = record["thresholds"]["record10"]
    share = {
        k: np.mean(
            [np.mean(np.asarray(s["record10"]) > threshold) for p, s in record["test_scores"].items() if p[0] == k]
        )
        for k in "hf"
    }
    return share["h"], share["f"]


def test_each_history_take_scored_without_itself_lets_a_new_takes_units_through_about_as_asked(tmp_path):
    """Eight boxes of three history takes, four new healthy takes and two chipped ones: scored by the
    detector made on all three, the history's takes let 20 % of the new healthy takes' record10 units
    through (1 % asked); each take scored by the detector made without it, none (the chips: 7 of 8 boxes'
    every unit)."""
    now = np.array([called(seed, tmp_path, left_out=True) for seed in range(8)])
    before = np.array([called(seed, tmp_path, left_out=False) for seed in range(8)])
    assert now[:, 0].mean() <= 0.02, now
    assert now[:, 1].mean() >= 0.75, now
    assert before[:, 0].mean() >= 0.1, before  # what the threshold was set on before: the takes themselves


def test_a_history_take_is_scored_by_the_whole_detector_referenced_on_the_other_takes(tmp_path, monkeypatch):
    """Left-out scoring swaps what the history gives a detector, its reference (the median of the other
    takes' rows) and its noise level (their median residual norm), and keeps all else of the detector
    made on the whole history (its shapes, path, lines and threshold): one fit, not one per take. On
    development boxes (60, three takes, record30, 1 % asked) refitting it all found 25 % of the chipped
    takes' units and let 0.8 % of the new healthy ones through; this 22 % and 1.1 %; the reference
    alone 35 % and 2.8 %."""
    from gearlab.learn import protocol as chapter5
    from gearlab.learn.detectors import template_statistic

    fits = []
    train_method = chapter5.train_method
    monkeypatch.setattr(chapter5, "train_method", lambda *a, **k: fits.append(1) or train_method(*a, **k))
    rng = np.random.default_rng([3, 39])
    history = [take(rng) for _ in range(3)]
    units = [tsa_units(h, BLOCK, STRIDE) for h in history]
    rule = Rule("records", 0.01, {"record10": [(len(u), len(u)) for u in units]})
    Xs, ys = source()
    rows = tuple(np.concatenate([h for j, h in enumerate(history) if j != k]) for k in range(3))
    method = Method("matched_filter", False)
    task = (Protocol(methods=(method,)), method, "", "c", None, None, (Xs, ys, Xs[:4], ys[:4]))
    task += (np.concatenate(history), {"record10": np.concatenate(units)}, {}, Confined(tmp_path, ("states",)))
    record = train_unit((*task, rule, False, rows))
    assert len(fits) == 1
    whole = template_statistic(Xs, ys, np.concatenate(history), None)
    threshold = Detector.threshold(Detector.score(whole, np.concatenate(history)), 0.01)
    for k, got in enumerate(rule.groups("record10", record["history_scores"]["record10"])):
        with torch.no_grad():
            whole.reference.copy_(torch.as_tensor(np.median(rows[k], axis=0), dtype=torch.float32))
            whole.norm.fill_(float(whole.residual(torch.as_tensor(rows[k], dtype=torch.float32)).norm(dim=1).median()))
        assert np.allclose(got, Detector.score(whole, units[k]) - threshold, atol=1e-5)


def test_of_two_history_takes_each_is_scored_by_the_detector_referenced_on_the_other(tmp_path):
    """Two takes are enough (detection_units.LEFT_OUT): eight boxes of two history takes, four new healthy takes
    and two chipped ones, each history take scored by the detector referenced on the other take let none of the
    new healthy takes' record10 units through (1 % asked) and found every chipped unit; scored by the detector
    made of both, its own take included (as before, when three were asked for), 48 %."""
    now = np.array([called(seed, tmp_path, left_out=True, takes=2) for seed in range(8)])
    assert now[:, 0].mean() <= 0.02 and now[:, 1].mean() >= 0.9, now
    before = np.array([called(seed, tmp_path, left_out=False, takes=2) for seed in range(8)])
    assert before[:, 0].mean() >= 0.2, before


def test_a_new_take_is_scored_by_the_detectors_that_scored_the_history_takes(tmp_path):
    """With history takes left out in turn, a new take's units are scored by the mean of the detectors that
    scored the history (each referenced without one take: detectors.MeanOf), not by the detector made of all
    takes: a threshold holds for scores made as the ones it was set on. likelihood_ratio divides a unit's
    correlations by the unit's own residual scale, which holds its reference's error, so a detector referenced
    on one take of two scores a take otherwise than the one made of both (synthetic rig records, 20 conditions
    of two history takes, record10, 1 % asked: the new healthy takes' units called 6.0 -> 4.0 %)."""
    from gearlab.learn.detectors import likelihood_statistic, referenced_on

    rng = np.random.default_rng([5, 39])
    history = [take(rng), take(rng)]
    units = [tsa_units(h, BLOCK, STRIDE) for h in history]
    rule = Rule("records", 0.01, {"record10": [(len(u), len(u)) for u in units]})
    Xs, ys = source()
    new = tsa_units(take(rng), BLOCK)
    rows = tuple(without_each(2, lambda k: history[1 - k]))
    method = Method("likelihood_ratio", False)
    task = (Protocol(methods=(method,)), method, "", "c", None, None, (Xs, ys, Xs[:4], ys[:4]))
    task += (np.concatenate(history), {"record10": np.concatenate(units)}, {"new": {"record10": new}})
    record = train_unit((*task, Confined(tmp_path, ("states",)), rule, False, rows))
    whole = likelihood_statistic(Xs, ys, np.concatenate(history), None)
    whole.threshold.fill_(Detector.threshold(Detector.score(whole, np.concatenate(history)), 0.01))
    parts = [referenced_on(whole, r) for r in rows]
    for k, got in enumerate(rule.groups("record10", record["history_scores"]["record10"])):
        assert np.allclose(got, Detector.score(parts[k], units[k]) - whole.threshold.item(), atol=1e-4)
    made = np.mean([Detector.score(m, new) for m in parts], axis=0) - whole.threshold.item()
    assert np.allclose(record["test_scores"]["new"]["record10"], made, atol=1e-4)
    assert not np.allclose(made, Detector.score(whole, new) - whole.threshold.item(), atol=1e-2)
