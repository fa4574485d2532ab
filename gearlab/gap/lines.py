"""A tone's line taken out of what the other effects are scored on (docs/gap.md, "A tone's line").

An interfering machine's tone (interference_tone) is a narrow line at a non-integer shaft order, the same
in every revolution but at another phase: the rows' residual from their synchronous average holds it, and
a simulator's rows, whose residual is their noise, do not. Beside a sensor filter and a model effect, a
search that adds one effect a round lost both: the tone won round 1, at a level relative to the clean RMS
that the others move, and a filter and a model effect fitted beside it scored against that line (a bearing
behind a low-pass beside a 340 Hz tone: the pair 467 beside the tone at round 1's level, 42 at its own;
a casing path alone 108, and named). So where the target's history holds such a line and the plain source
does not, each row's sinusoid at the line's order is taken out of the target and of every set scored
(`Rows.line`) while the other effects are searched, and the tone is fitted last, against the whole rows
(gearlab.gap.diagnose)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .scoring import Scorer
from .views import without_line

TONE = "interference_tone"
# The running median that reads the residual's floor around each bin: wider than a line's leakage above
# it (a tone at 0.8 of the signal's RMS over noise at the signal's level: 20-odd orders either side), so
# a line does not lift its own floor.
FLOOR_ORDERS = 129


def _power(X: np.ndarray, top: int) -> np.ndarray:
    """Each row's power at shaft orders 1 .. *top* in its residual from the rows' synchronous average."""
    R = np.asarray(X, dtype=np.float64)
    return np.abs(np.fft.rfft(R - R.mean(axis=0), axis=1)[:, 1 : top + 1]) ** 2


def residual_power(X: np.ndarray, top: int) -> np.ndarray | None:
    """Each shaft order's power (1 .. *top*) in the rows' residual (:func:`_power`), each row over its own
    median (a heavy-tailed noise's loud rows weigh as much as the others), averaged over the rows: about
    1 / ln 2 per order for white noise. None where the rows hold no residual."""
    P = _power(X, top)
    level = np.median(P, axis=1, keepdims=True)
    if not np.all(level > 0.0):
        return None
    return np.mean(P / level, axis=0)


def excess(Q: np.ndarray, rows: int, alpha: float) -> np.ndarray:
    """Each order's residual power *Q* (:func:`residual_power` of *rows* rows) over the floor read around it,
    where it stands above that floor at significance *alpha* over all orders (Bonferroni: a row's power over
    its floor is exponential for noise, the mean of *rows* of them a gamma of shape *rows*), else 0."""
    from scipy.ndimage import median_filter
    from scipy.stats import gamma

    floor = median_filter(Q, size=FLOOR_ORDERS, mode="reflect")  # (repeated at the ends, order 1 was its own floor)
    over = Q > floor * gamma.isf(alpha / Q.size, a=rows, scale=1.0 / rows)
    return np.where(over, Q - floor, 0.0)


def tone_bins(target: np.ndarray, plain: np.ndarray, alpha: float, max_order: int = 0) -> tuple[int, ...]:
    """The shaft orders (rfft bins of a revolution) where a non-synchronous line of the *target* history
    holds more power than the *plain* source's residual (a long train's other shafts put lines in both;
    a noise-free source's residual is its rounding): () where none."""
    top = max_order or (np.shape(target)[1] // 2)
    Q = residual_power(target, top)
    if Q is None:
        return ()
    level = np.median(_power(target, top), axis=1, keepdims=True)
    lines = excess(Q, len(target), alpha) * np.mean(level)  # in the rows' units
    own = np.mean(_power(plain, top), axis=0)
    over = lines > own
    # A line is two orders or more: a tone at a non-integer order puts its power into both neighbours,
    # where one order alone over the floor is the test's false alarm (one in 1 / alpha targets).
    pair = over[1:] & over[:-1]
    line = np.zeros_like(over)
    line[1:] |= pair
    line[:-1] |= pair
    return tuple(int(k) + 1 for k in np.flatnonzero(line))


# The grid the line's order is first read on (shaft orders): finer than one revolution's main lobe (one
# order wide), so the refinement that follows starts inside it.
ORDER_STEP = 0.1


def line_order(target: np.ndarray, orders: tuple[int, ...]) -> float:
    """The shaft order of the sinusoid that takes the most power out of the *target* rows' residual, among
    the *orders* a line stands out in (:func:`tone_bins`; the order one either side included): on a grid of
    ORDER_STEP, then a bounded search within one step of its best."""
    from scipy.optimize import minimize_scalar

    X = np.asarray(target, dtype=np.float64)
    R = X - X.mean(axis=0)

    def left(order: float) -> float:
        return float(np.sum(without_line(R, order) ** 2))

    grid = np.arange(max(min(orders) - 1.0, ORDER_STEP), max(orders) + 1.0, ORDER_STEP)
    best = float(grid[np.argmin([left(v) for v in grid])])
    found = minimize_scalar(left, bounds=(best - ORDER_STEP, best + ORDER_STEP), method="bounded")
    return float(found.x)


def tone_line(target: np.ndarray, plain: np.ndarray, settings, candidates) -> float:
    """The shaft order of a tone's line in the *target* history that the *plain* source's rows lack, at the
    diagnosis's *settings* (its significance level and band), where the tone is among the *candidates* (it
    is fitted last, against the whole rows); else 0."""
    if TONE not in candidates:
        return 0.0
    orders = tone_bins(target, plain, settings.alpha, settings.max_order)
    return line_order(target, orders) if orders else 0.0


def masked(run, order: float):
    """A diagnosis's shared state (gearlab.gap.diagnose._Run) with the line at shaft order *order* taken out of
    the target and of every set it scores: its score, its rows (search and judging) and its round-1 baselines."""
    rows = replace(run.rows, line=order)
    target = without_line(run.target, order)
    scorer = Scorer(target, run.pair, run.settings.max_order, rows.consecutive, rows.free_load)
    judged = lambda effects: without_line(run.judged(effects), order)  # noqa: E731 (the run's own, less the line)
    return replace(
        run,
        scorer=scorer,
        rows=rows,
        target=target,
        judged=judged,
        gap0=scorer.score(rows(run.search)),
        judged0=scorer.score(judged(())),
    )
