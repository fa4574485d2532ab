"""Non-synchronous change: what a record holds that no shaft's synchronous average carries.

A localised gear fault strikes once per turn of its shaft, so it lives at that shaft's orders and the
shafts' time-synchronous averages (TSAs) carry it (gearlab.signals.localise). A rolling-element
bearing's defect strikes at a rate that is no whole order of any shaft (an outer race's ball-pass
order, about 0.4 n_b turns of its shaft's speed, 3.57 for 9 balls) and slips a percent or two from
strike to strike: the TSAs average it away. It is left in the *residual*: the record less every
shaft's synchronous average.

Residual. The record, read in the input angle (R consecutive input revolutions of `points` samples),
is cut to a whole number of the train's grand periods (after P input turns every shaft is back at its
start angle: gearlab.gearbox.orders.OrderTable.train_period) where it holds GRAND of them; then each
shaft's orders m o_s fall on whole bins of the record's spectrum (bin k: input order k / R), and a
shaft's TSA over the record is those bins: the residual is the record with every bin at a multiple of
a shaft's order set to zero. A record of fewer grand periods (tooth counts with few common factors) is
read in two pieces of whole periods of its meshes, its first turns and its last (read_turns), and each shaft
order's nearest bin and its neighbours (LEAK) are removed.

Evidence. The residual's squared envelope (|analytic signal|²), over its mean (a level in units of the residual's
own power, so a louder take's noise does not read as a change), is read in blocks of BLOCK input revolutions
(spectral resolution 1 / BLOCK orders) from LOW to HIGH input orders, each bin's power summed with its neighbours (a
slipping strike's line spreads over a few bins) and read as its logarithm (a block's power is skewed, its log nearly
Gaussian: healthy rig records' largest z median 2.8, at most 5.5, against thresholds of 4.9-5.3, 200 records on 40
histories of 2, development seeds). A record's bins are the mean over its n blocks; against the healthy history's N
blocks, each bin's excess is in sds of the difference of the two means, z(f) = (E(f) − μ_h(f)) / (σ_h(f) √(1/n+1/N))
(and the records' spread beyond their blocks' noise, line_z), σ_h pooled over SMOOTH neighbouring bins. The
record's z is its largest. The strike order named is the lowest whose first HARMONICS harmonics' z sum within LOWEST
of the most (the strongest line is often a harmonic, where the ring lies), read finer on the whole residual's
envelope spectrum. The threshold is fixed on the history alone, as the shafts' are, for the maximum over the bins:
Student's t quantile at FALSE_ALARM shared among the bins (Bonferroni, on the pooled sd's degrees of freedom:
student_quantile) times the sd of the history records' line z, each read against the others (the records' spread
beyond their blocks' noise), and at least the largest of those z (healthy rig records over it: 1 of 200; 40
histories of 2, development seeds 300-339). One history take holds no records' spread: its threshold is the t
quantile alone (one_take_threshold; healthy rig records over it 0 of 200, the same seeds). As z holds both means'
noise, the threshold holds at every take's length (a 39/61 box's healthy 3, 6, 9 and 18 s takes against three 3 s
history takes: 0, 0, 3 and 0 of 100 over it, development seeds 300-319).
A gear fault is synchronous: the residual does not carry it (a simulated cracked tooth left z under
the threshold, tests/test_nonsync.py); a bearing's strikes put a line at their order and its
harmonics.

Everything is numpy: no torch, nothing from the layers above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from statistics import NormalDist

import numpy as np

from ..errors import GearlabInputError
from ..memo import ArraysOf
from .shaft import uniform_filter1d

GRAND = 2  # grand periods (or meshes' periods) a record must hold to be read in them (read_turns)
LEAK = 2  # bins on either side of a shaft order's nearest bin removed where the record is read whole (a mesh
# line between bins leaks past 1: box Q's healthy takes, 27/61 + 18/49 read whole, z 6.5-7.1 over 4.1 at LEAK 1 and
# the bins of 2592186, 5.0-6.0 at 2; with beats moved by a shaft order (synchronous_bins) 4.2-5.1 at 1, 2.4-3.3 at 2)
BLOCK = 16  # input revolutions per block of the envelope spectrum (resolution 1/16 order)
# the fewest turns of the slowest shaft a record read whole (fewer than GRAND grand periods) is read with: its
# residual loses 2 LEAK + 1 bins about each of that shaft's orders, spaced by its turns in the record, so at 5 turns
# nothing is left (box B, 25/52 + 16/81, a steady 1.2 s take: 2.75 output turns, residual all zero, z nan; at 5.0
# turns z 2.7-3.1 on rounding noise alone) and at 8 three-eighths of the spectrum (box B's healthy week 1 cut to 6.1
# .. 28 output turns: z 0.3-0.8 against its threshold 4.7). The shafts' own averages (data.which_gear, shafts mode)
# need as many: box B's healthy takes cut short named a gear in 5 of 5 windows at 2.75 output turns, 4 of 30 at 6.1,
# 3 of 57 at 8-12 (z 2.9-3.3 over 2.7), none at 14-19 (the whole takes, 28 turns: z 0.2)
TURNS = 8
LOW, HIGH = 0.3, 40.0  # input orders of the envelope spectrum searched for a non-synchronous line
FUNDAMENTAL = 10.0  # the highest strike order named (cage to inner-race orders, a few shaft orders)
HARMONICS = 4  # harmonics of a strike order whose z are summed to name it
LOWEST = 0.7  # the strike order named: the lowest whose harmonics' z sum to this share of the most
OWN = 0.25  # ... whose own line's z is at least this share of the largest (not a half of the strike order)
LINE = 8  # bins on either side whose median z a line's z is read over (half an order)
BEAT = 5  # mesh harmonics whose first sidebands are left out of the search (synchronous_bins)
SLOW = 4  # harmonics of a slower shaft's order (a mesh's sidebands by the slowest) left out of the search
MATE = 4  # orders of a faulty gear's mate (its mesh's sidebands by the shaft it meshes with) in its products
SUM = 1  # bins on either side summed with each bin (a slipping strike's line spreads)
SMOOTH = 9  # bins over which the history's sd is pooled
BETWEEN = 101  # bins over which the history records' spread beyond their blocks' noise is pooled
FALSE_ALARM = 0.01  # the Gaussian floor of the threshold, shared out among the bins searched
# what the threshold stands for, as detection, score and inspect --history say it: box A of an outside lab (24/83,
# 3 history takes of 10 blocks), healthy takes over it 1 of 115 (z 5.02 / 4.74; 6 histories; seeds 1-4, 31-36,
# 1551-1590), a healthy take's per-bin z sd 1.05 against the left-out 1.15 the threshold scales by
PASSED = f"a healthy take passes it at false alarm {FALSE_ALARM:g}"


# A line of the residual's envelope at the mains frequency or a harmonic of it (within MAINS_SLACK of it, the grid's
# own drift and the strike order's resolution over a take of 80 turns) may be a hum picked up on the sensor's cable or
# a ground loop: its 50, 100, 150 Hz beat in the envelope as a bearing's strikes do (a user's 41/109 box at 29 Hz: a
# 0.3 m/s² hum read z 11.8 at order 1.72, 'other damage: non-synchronous (bearing-like)'). Its frequency alone does not
# say so: a bearing's tone lands there at some speed (hum_or_bearing tells them apart, or says it cannot)
MAINS = (50.0, 60.0)
MAINS_HARMONICS = 4
MAINS_SLACK = 0.01
HUM = "not a gear fault"


def harmonic(hz: float | None) -> tuple[float, float] | None:
    """(the mains frequency, its harmonic) in Hz that *hz* lies within MAINS_SLACK of (MAINS_HARMONICS of MAINS), or
    None."""
    if hz is None:
        return None
    near = [(f, k * f) for f in MAINS for k in range(1, MAINS_HARMONICS + 1) if abs(hz - k * f) <= MAINS_SLACK * k * f]
    return near[0] if near else None


def mains(hz: float | None) -> float | None:
    """The mains frequency (Hz) of which *hz* is a harmonic (MAINS_HARMONICS of MAINS, within MAINS_SLACK), or None."""
    near = harmonic(hz)
    return None if near is None else near[0]


def call(order: float, hz: float | None = None, locked: str = "", why: str = "") -> str:
    """How a detection run, `gearlab score` and `gearlab inspect --history` name a non-synchronous change at input
    order *order* (*hz*: in Hz, where the take's speed is known) whose line is *locked* to "time" (a mains hum, no
    damage), to the shaft's "angle" (a bearing's) or "" (not told apart), *why* the evidence (hum_or_bearing): a line
    on a mains harmonic is a hum only where the take tells it is one."""
    near = harmonic(hz)
    if near is None:
        return f"other damage: non-synchronous (bearing-like), at order {order:.2f}"
    grid, on = near
    if locked == "time":
        return (
            f"{HUM}: mains hum at {hz:.1f} Hz (order {order:.2f}; the {grid:g} Hz mains: electrical pickup on the "
            f"sensor's cable or a ground loop; locked to time, not to a shaft: {why})"
        )
    if locked == "angle":
        return (
            f"other damage: non-synchronous (bearing-like), at order {order:.2f} ({hz:.1f} Hz, within "
            f"{MAINS_SLACK * 100:g} % of the {on:g} Hz mains' harmonic, but locked to the shaft: {why})"
        )
    return (
        f"other damage: non-synchronous (bearing-like) or mains hum, at order {order:.2f} ({hz:.1f} Hz, within "
        f"{MAINS_SLACK * 100:g} % of the {on:g} Hz mains' harmonic at this speed: hum or a bearing, not told apart"
        + (f": {why}" if why else "")
        + "; a take at another speed would tell)"
    )


def too_short(revolutions: int, table) -> str | None:
    """Why a record of *revolutions* consecutive input revolutions of the gearbox of order table *table* is too
    short for the non-synchronous check (fewer than BLOCK, or read whole with fewer than TURNS turns of its
    slowest shaft), in one phrase; None where it is not."""
    if revolutions < BLOCK:
        return f"too short for the non-synchronous check: {revolutions} input revolutions, it needs {BLOCK}"
    if revolutions >= GRAND * table.train_period:  # cut to whole grand periods: each shaft's bins removed exactly
        return None
    turns, shaft = slowest_turns(revolutions, table)
    if turns >= TURNS:
        return None
    return (
        f"too short for the non-synchronous check: {turns:.3g} {shaft}-shaft turns "
        f"({revolutions} input revolutions), it needs {TURNS}"
    )


def revolutions_needed(table) -> int:
    """The input revolutions holding TURNS turns of order table *table*'s slowest shaft: the which-gear check's least
    (data.which_gear), which a followed angle's unsettled ends are not cut below (signals.settled)."""
    return math.ceil(TURNS / min(float(o) for o in table.shaft_orders))


def slowest_turns(revolutions: int, table) -> tuple[float, str]:
    """(turns, name) of the slowest shaft of order table *table* over *revolutions* input revolutions: what TURNS
    counts, here and in the shafts' own averages (data.which_gear)."""
    slow = int(np.argmin([float(o) for o in table.shaft_orders]))
    return float(table.shaft_orders[slow]) * revolutions, table.shafts[slow]


def read_turns(revolutions: int, table) -> int:
    """The input revolutions of each piece of a record of *revolutions* the residual is read in, for the gearbox of
    order table *table*: whole grand periods where it holds GRAND of them (one piece, the rest left); else whole
    periods of the meshes (two pieces, the first turns and the last, so no turn is lost); else all of it."""
    # A healthy gearbox's strongest lines are its meshes' harmonics (with their shafts' sidebands). Read over R turns,
    # a mesh of order M lies at bin M R; where that is not whole (M = 437/62 of a 19/62 + 23/87 box: 0.52 off at 300
    # turns) the record's ends cut the line, whose spectrum leaks as 1/(pi d) of its amplitude d bins away: past the
    # LEAK bins removed, 0.13 of it at d = 2.5, and what is left is the line near the record's two ends (its Gibbs
    # remainder). There the residual's envelope beats the meshes' harmonics, a Mi + b Mj + c o_s, at the load's level:
    # that box's healthy take at twice its history's load, cut from 500 turns, read z 2.8-5.1 (threshold 4.0) at 200,
    # 240, 280 and 299 turns, 1.8-2.8 at 186, 248, 310, 372, 434, 496 (whole periods of its meshes, 62 turns). So a
    # piece is whole periods of the meshes (the turns after which the first stages' meshes are back in phase, as many
    # stages as the record holds GRAND of, keeping TURNS of the slowest shaft): each mesh and the shafts turning
    # whole times in it fall on whole bins, and their LEAK neighbours take what a tracked angle smears (box Q's
    # history, no tacho, read z 4.4-4.8 at 36.75 = M1 + M2 + 4 o_2 with the whole bins alone); the rest (a slower
    # shaft's sidebands) is weak. The bins removed: 21 % of a 399-turn take of that box (19 % read whole), box Q's
    # 279 turns 18 % (15 %)
    if revolutions >= GRAND * table.train_period:
        return revolutions // table.train_period * table.train_period
    period, cut = 1, revolutions
    for st in table.stages:
        period = math.lcm(period, Fraction(st.mesh).denominator)
        keep = revolutions // period * period
        if revolutions < GRAND * period or slowest_turns(keep, table)[0] < TURNS:
            break
        cut = keep
    return cut


def residual(revs: np.ndarray, table) -> np.ndarray:
    """The record *revs* (R consecutive input revolutions, flat in input angle) less every shaft's
    synchronous average (module doc): flat, of R' ≤ R whole revolutions (R' < R only where cut to whole grand
    periods); *table*: the gearbox's order table (gearlab.gearbox.orders.OrderTable)."""
    revs = np.atleast_2d(np.asarray(revs, dtype=np.float64))
    R, P = revs.shape
    whole = read_turns(R, table)
    if R >= GRAND * table.train_period:
        return _less_shafts(revs[:whole], table.shaft_orders, exact=True)
    first = _less_shafts(revs[:whole], table.shaft_orders, exact=False)
    if whole == R:
        return first
    last = _less_shafts(revs[R - whole :], table.shaft_orders, exact=False)  # the turns past the first piece
    return np.concatenate([first, last[(2 * whole - R) * P :]])


def _less_shafts(revs: np.ndarray, shaft_orders, exact: bool) -> np.ndarray:
    """*revs* (R', points) flat, with every bin at a shaft's order zeroed, and its LEAK neighbours where between
    bins or not *exact* (no whole grand period: a line the tracked angle smears a little spreads past its bin)."""
    whole = len(revs)
    y = revs.reshape(-1)
    X = np.fft.rfft(y - y.mean())
    k = np.arange(X.size)
    for o in shaft_orders:
        step = Fraction(o) * whole  # bins between the shaft's orders
        if exact and step.denominator == 1:
            X[k % int(step) == 0] = 0.0
            continue
        at = np.round(np.arange(0, X.size / float(step) + 1) * float(step)).astype(np.int64)
        for d in range(-LEAK, LEAK + 1):
            X[np.clip(at + d, 0, X.size - 1)] = 0.0
    return np.fft.irfft(X, n=y.size)


def envelope_blocks(r: np.ndarray, points: int) -> np.ndarray:
    """(blocks, bins) the squared envelope's power spectrum of each BLOCK-revolution block of the
    residual *r* over its mean, each bin summed with SUM neighbours, bins LOW … HIGH input orders."""
    from scipy.signal import hilbert

    n = BLOCK * points
    count = r.size // n
    if count < 1:
        raise GearlabInputError(
            f"non-synchronous residual: {r.size // points} input revolutions; expected at least {BLOCK}"
        )
    out = []
    for b in range(count):
        e = np.abs(hilbert(r[b * n : (b + 1) * n])) ** 2
        if not e.mean() > 0:  # a constant record (a sensor off) leaves no residual: nothing to read, not nan
            raise GearlabInputError("non-synchronous residual: none left (the record is constant); expected a signal")
        E = np.abs(np.fft.rfft(e - e.mean()) / (e.mean() * e.size)) ** 2
        out.append(np.log(np.maximum(uniform_filter1d(E, size=2 * SUM + 1, mode="nearest"), 1e-300)))
    lo, hi = int(math.ceil(LOW * BLOCK)), int(HIGH * BLOCK)
    return np.asarray(out)[:, lo : hi + 1]


# the bins envelope_blocks keeps, LOW .. HIGH input orders (of revolutions of 2 HIGH points or more)
BINS = int(HIGH * BLOCK) - int(math.ceil(LOW * BLOCK)) + 1


def orders_of_bins(bins: int) -> np.ndarray:
    """The input order of each bin envelope_blocks keeps."""
    return (int(math.ceil(LOW * BLOCK)) + np.arange(bins)) / BLOCK


# what a score says of a history whose saved arrays do not give today's threshold, or are not read (NonSyncHistory)
REFRESH = "running the detection again refreshes the history"
OLDER = (
    "threshold as saved by an older gearlab (its saved history does not give today's): running the detection again "
    "refreshes it"
)


@dataclass(frozen=True)
class NonSyncHistory:
    """The healthy history's envelope-spectrum blocks (one array per record) and the threshold on z."""

    blocks: tuple[np.ndarray, ...]
    threshold: float  # the same at every take length: z carries the noise of the take's mean and the history's (line_z)
    speeds: tuple[float, ...] = ()  # each record's mean input speed (Hz; none where not given): hum_or_bearing
    threshold_from: str = ""  # "": today's rule (threshold_of); else why not (OLDER)
    unread: str = ""  # "": a take is read against it; else why not (restored: bins of another layout than today's)

    def state(self) -> dict:
        """Arrays to save (parts.scoring.save_arrays) and restore (restored)."""
        return {
            "nonsync_sizes": np.array([len(b) for b in self.blocks]),
            "nonsync_blocks": np.concatenate(self.blocks),
            "nonsync_threshold": np.array(self.threshold),
            "nonsync_speeds": np.array(self.speeds, dtype=np.float64),
        }

    @classmethod
    def restored(cls, state: dict, table) -> NonSyncHistory | None:
        """The history state() saved, of the gearbox of order table *table*; None for a state saved without it. Its
        threshold is today's (threshold_of its blocks), not the one saved: an older gearlab's rule held healthy takes
        over it (one take's Gaussian floor called 154 of 200 healthy rig takes; several takes' z, in sds of the
        take's mean alone, were scaled from a lower floor). Where the blocks cannot give it (not told apart by take,
        or bins of another layout than today's), the saved one is kept and said to be (OLDER). Blocks of other bins
        than today's (an older gearlab's BLOCK, LOW or HIGH) are not read against (unread): which order each bin
        was is not saved, and a block of other revolutions is another estimate, not a re-binning of today's."""
        if "nonsync_blocks" not in state:
            return None
        speeds = tuple(float(v) for v in np.asarray(state.get("nonsync_speeds", ())))  # none: saved before them
        every, saved = np.asarray(state["nonsync_blocks"]), float(state["nonsync_threshold"])
        if "nonsync_sizes" not in state:  # one pool of blocks: no take to leave out
            return cls((every,), saved, speeds, OLDER)
        blocks = tuple(np.split(every, np.cumsum(np.asarray(state["nonsync_sizes"]))[:-1]))
        if every.shape[1] != BINS:
            said = f"{BINS} from {LOW:g} to {HIGH:g} input orders in blocks of {BLOCK} revolutions"
            why = f"its saved history holds {every.shape[1]} bins a block, this gearlab reads {said}"
            return cls(blocks, saved, speeds, OLDER, f"non-synchronous check not read: {why}; {REFRESH}")
        return cls(blocks, threshold_of(blocks, table), speeds)


@dataclass(frozen=True)
class NonSync:
    """A record's non-synchronous change: z of its strongest envelope line over the history, the
    strike order named (input orders), the history's threshold on z, and where the line lies on a mains harmonic
    what it is locked to ("time", "angle", "": not told apart) and why (hum_or_bearing)."""

    z: float
    order: float
    threshold: float
    locked: str = ""
    why: str = ""
    shafts: tuple[str, ...] = ()  # the shafts a fault on whose gear puts a line at the strike order (products)
    threshold_from: str = ""  # the history's (NonSyncHistory.threshold_from): "" where today's rule

    @property
    def changed(self) -> bool:
        return self.z > self.threshold

    def describe(self) -> dict:
        said = {"z": self.z, "order": self.order, "threshold": self.threshold, "changed": self.changed}
        said |= {"threshold_from": self.threshold_from} if self.threshold_from else {}
        return said | {"locked": self.locked, "why": self.why, "shafts": list(self.shafts)}


def products(order: float, table, revolutions: float) -> tuple[str, ...]:
    """The shafts a localised tooth fault on whose gear puts the residual's envelope line at input order *order* (its
    peak over *revolutions* input turns: refined), each shaft's name; () for none. A tooth fault strikes its mesh
    once a turn of its shaft s, so it modulates the mesh at every order k o_s, and the mesh carries its sidebands by
    the shaft it meshes with (its mate m, the other shaft of a stage s is on) at their first orders: the residual keeps
    their products, k o_s + n o_m (no whole order of either shaft), and its envelope their differences, of the same
    form. Beside a gear named on s, a line there (|n| <= MATE; n = 0: the shaft's own orders, which a strong fault
    leaks past the bins removed) is the gear's own; a bearing's strike order lies there by chance only. The lattice is
    read within half a bin of the whole take (1 / *revolutions* orders: two lines nearer than that are one line over
    it), not a fixed share of an order (1/32 about every shaft's orders excused 60 % of orders on a 23/59 + 19/71
    box's output shaft, 0.104 input orders, whichever gear was named). Chipped-gear takes' lines excused (development
    seeds 11-18, 21-25, gear named, line over the threshold): 37/89 box 20 of 22 (8 before), 23/59 + 19/71 box 9 of
    11 (8); lines of a bearing beside them excused 3 of 12 (2) and 1 of 8 (5)."""
    tol = 0.5 / revolutions
    got = []
    for i, (name, o) in enumerate(zip(table.shafts, table.shaft_orders)):
        for j in (i - 1, i + 1):
            if not 0 <= j < len(table.shafts):
                continue
            rest = order - np.arange(-MATE, MATE + 1) * float(table.shaft_orders[j])
            k = np.round(rest / float(o))
            if np.any((k >= 0) & (np.abs(rest - k * float(o)) <= tol)):
                got.append(name)
                break
    return tuple(got)


def beside(ns: dict | None, speed_hz: float | None, flagged) -> str:
    """A non-synchronous change read beside a gear's localised one on the shafts *flagged* (their names), as a run,
    `gearlab score` and `inspect --history` add it to their call ("non-synchronous (bearing-like), at order 3.62"): a
    line over its threshold at a strike order that is no product of a flagged shaft's gear fault (products), not a
    mains hum; "" for none (a chipped 38T pinion beside a bearing's outer-race strikes, z 20.2 over 4.47, was called
    the pinion's alone; a 37/89 box's chipped pinion alone, its line at 3 o_1 - 2 o_2, was called a bearing too)."""
    if not ns or not ns.get("changed") or set(ns.get("shafts", ())) & set(flagged) or ns.get("locked") == "time":
        return ""
    hz = None if speed_hz is None else ns["order"] * speed_hz
    return call(ns["order"], hz, ns.get("locked", ""), ns.get("why", "")).removeprefix("other damage: ")


def synchronous_bins(table, bins: int) -> np.ndarray:
    """bool per bin envelope_blocks keeps: within SUM bins of an order a shaft's rotation modulates the
    residual at: every multiple of a shaft turning at least once a turn and of each mesh, the first sidebands of
    each mesh's first BEAT harmonics (its first SLOW by the slowest shaft), the first SLOW of a slower shaft's (an
    eccentric gear's load, turn by turn, modulates the mesh's random part, its level wandering from take to take: the
    PHM 2009 eccentric idler's records read z 8-19 at 1/3 order against healthy ones; a user's 16/37 + 28/71 box's
    3 s healthy takes read their largest z at M2 - 4 o3 .. M2 + 8 o3, 2 of 44 over the threshold with the first
    sidebands alone left out, 1 of 44 so: tests/test_nonsync_null.py)."""
    f = orders_of_bins(bins)
    meshes = [float(st.mesh) for st in table.stages]
    lines = meshes + [float(o) for o in table.shaft_orders if o >= 1]
    at = [k * o for o in lines for k in range(1, int(HIGH / o) + 2)]
    # Two meshes' combinations a Mi + b Mj (+- a shaft order) are searched: read in whole periods of its meshes
    # (read_turns), a record of no whole grand period holds no beat of mesh lines leaking past the bins removed (box
    # Q, 27/61 + 18/49, healthy at 28 Hz, read whole: z 6.5-7.1 at 3.54 = M1 - 3 M2 + o_2). Its healthy takes read z
    # 2.92 and 2.62 with those orders left out or not, and a bearing striking 3.54 times a turn, on that lattice, is
    # named at 3.54, where leaving them out named its harmonic 7.08: box Q searched 442 bins of 0.3-40, not 342, before
    # its mesh's sidebands by the slowest shaft were left out (400 since; tests/test_outside_e)
    for i, mesh in enumerate(meshes):
        sides = [
            c * k * float(table.shaft_orders[s])
            for s in (i, i + 1)
            for k in range(1, (SLOW if table.shaft_orders[s] == min(table.shaft_orders) else 1) + 1)
            for c in (-1, 1)
        ]
        at += [abs(a * mesh + d) for a in range(1, BEAT + 1) for d in (0.0, *sides)]
    at += [k * float(o) for o in table.shaft_orders if o < 1 for k in range(1, SLOW + 1)]
    near = np.abs(f[:, None] - np.asarray(at)[None, :]).min(axis=1)
    return near <= (SUM + 0.5) / BLOCK


def line_z(blocks: np.ndarray, reference: list[np.ndarray], synchronous: np.ndarray) -> np.ndarray:
    """Each bin's line z of a record's envelope blocks against the reference records' blocks (module doc:
    the noise of the mean, plus the records' spread beyond it), 0 on the *synchronous* bins: a bin's z
    less the median z of the LINE bins on either side (a line stands out of its neighbours, where a record
    whose whole envelope changed, another build of the same rig loaded otherwise, lifts them all)."""
    every = np.concatenate(reference)
    within = np.concatenate([r - r.mean(axis=0) for r in reference])
    var = uniform_filter1d(np.sum(within**2, axis=0) / max(len(every) - len(reference), 1), size=SMOOTH, mode="nearest")
    between = np.zeros_like(var)
    if len(reference) > 1:  # the records' means scatter beyond their blocks' noise: pooled over BETWEEN bins
        means = np.array([r.mean(axis=0) for r in reference])
        beyond = means.var(axis=0, ddof=1) - var * np.mean([1.0 / len(r) for r in reference])
        between = np.clip(uniform_filter1d(beyond, size=BETWEEN, mode="nearest"), 0.0, None)
    # the difference of two means, each with its noise: the take's (its blocks', and its record's spread beyond them)
    # and the history's (its blocks' over all N, the records' spread weighted as the mean weights them: n_i / N). The
    # history's left out, a take longer than its takes reads past the spread it had been scaled by (a 39/61 box's
    # healthy 9 s takes against three 3 s ones: 20 of 100 over the threshold; 18 s: 81 of 100)
    sizes = np.array([len(r) for r in reference], dtype=np.float64)
    noise = var / len(blocks) + between + var / sizes.sum() + between * float(np.sum(sizes**2)) / sizes.sum() ** 2
    z = (blocks.mean(axis=0) - every.mean(axis=0)) / np.sqrt(np.maximum(noise, 1e-300))
    from scipy.ndimage import median_filter

    return np.where(synchronous, 0.0, z - median_filter(z, size=2 * LINE + 1, mode="nearest"))


def _z(z: np.ndarray) -> tuple[float, float]:
    """(largest line z, the strike order) of a record's line z (line_z of its envelope blocks against the
    reference records'). The strike order: the lowest f0 ≤ FUNDAMENTAL whose HARMONICS
    harmonics' line z (clipped at 0) sum within LOWEST of the most (a strike's line is often strongest at a
    harmonic, where the resonance it rings lies; its double holds its even harmonics only, its half half of
    them) with a line of its own OWN of the largest, read at that line's peak."""
    lo = int(math.ceil(LOW * BLOCK))
    f0 = np.arange(lo, int(FUNDAMENTAL * BLOCK) + 1)  # candidate orders in bins (order * BLOCK)
    pos = np.round(f0[:, None] * np.arange(1, HARMONICS + 1)[None, :]).astype(np.int64) - lo
    held = pos < z.size
    zh = np.where(held, np.clip(z[np.clip(pos, 0, z.size - 1)], 0.0, None), 0.0)
    total = zh.sum(axis=1)
    own = np.array([z[max(i - 1, 0) : i + 2].max() if i < z.size else 0.0 for i in f0 - lo])
    named = (total >= LOWEST * total.max()) & (own >= OWN * z.max())  # a line of its own, and its harmonics
    best = int(f0[np.flatnonzero(named)[0]] if named.any() else f0[np.argmax(total)]) - lo
    # the fundamental's own peak within a bin or two of the candidate (a slipping line's harmonics spread)
    near = np.arange(max(best - 2, 0), min(best + 3, z.size))
    return float(z.max()), float((lo + near[np.argmax(z[near])]) / BLOCK)


def refined(r: np.ndarray, points: int, order: float) -> tuple[float, float]:
    """(*order* read finer: the power centroid of the whole residual's squared-envelope spectrum (resolution
    1 / its revolutions) within a bin of the blocks' spectrum of it, over that window's median; the line's peak: the
    highest of that spectrum, read in FINE steps a bin, within the SUM + 1/2 bins of it a block's bin sums). A line
    locked to the shafts (products) stands within a fraction of a bin of its order at its peak, where a centroid
    pulled by the lines beside it need not (a 37/89 box's chipped pinion's line at 2.1685, 95 turns: centroid 2.1958,
    peak 2.1684). Its FFTs are gearlab.signals.fft's: a whole take's length has its revolutions' prime factors (a 60
    s take's 2399: 42 s)."""
    from .fft import analytic, rfft

    e = np.abs(analytic(r)) ** 2
    X = rfft(e - e.mean())
    E = np.abs(X) ** 2
    revs = r.size / points
    k = np.arange(int((order - 1.0 / BLOCK) * revs), int((order + 1.0 / BLOCK) * revs) + 2)
    k = k[(k > 0) & (k < E.size)]
    w = np.clip(E[k] - np.median(E[k]), 0.0, None)
    if not w.sum() > 0:
        return order, order
    # the window's bins and ZOOM about them interpolated FINE times a bin (their DFT zero-padded back from them)
    lo, hi = max((order - (SUM + 0.5) / BLOCK) * revs, 1.0), min((order + (SUM + 0.5) / BLOCK) * revs, X.size - 1.0)
    near = np.arange(max(int(lo) - ZOOM, 0), min(int(hi) + ZOOM + 2, X.size))
    fine = np.abs(np.fft.fft(np.fft.ifft(X[near]), n=FINE * near.size)) ** 2
    at = near[0] + np.arange(fine.size) / FINE
    inside = (at >= lo) & (at <= hi)
    return float(np.sum(w * k) / np.sum(w) / revs), float(at[inside][np.argmax(fine[inside])] / revs)


def history(takes: list[np.ndarray], table, speeds: list[float] | None = None) -> NonSyncHistory:
    """The healthy history of *takes* (each (R, points) consecutive input revolutions, *speeds* their mean input
    speeds in Hz where known) of the gearbox of order table *table* (gearlab.gearbox.orders.OrderTable)."""
    # fewer than BLOCK revolutions: envelope_blocks says so, as inspect --history reads it
    short = [w for w in (too_short(len(t), table) for t in takes if len(t) >= BLOCK) if w]
    if short:
        raise GearlabInputError(f"the history's takes: {short[0]}")
    blocks = tuple(take_blocks(t, table) for t in takes)
    if sum(len(b) for b in blocks) < 3:
        raise GearlabInputError(
            f"non-synchronous residual: the history holds {sum(len(b) for b in blocks)} blocks of {BLOCK} "
            "input revolutions; expected at least 3"
        )
    known = () if speeds is None else tuple(float(v) for v in speeds)
    return NonSyncHistory(blocks, threshold_of(blocks, table), known)


def threshold_of(blocks: tuple[np.ndarray, ...], table) -> float:
    """The threshold on z of a history of takes whose envelope blocks (take_blocks) are *blocks*, one array a take, of
    the gearbox of order table *table*: from the blocks alone, so a saved history is restored with it."""
    if len(blocks) == 1:  # no records' spread to read: the blocks' noise alone
        return one_take_threshold(blocks[0], table)
    sync = synchronous_bins(table, blocks[0].shape[1])
    # the record's z is a maximum over the bins searched: its threshold is the family's, Student's t quantile at
    # FALSE_ALARM shared among them (Bonferroni; the Gaussian's let 28 of 1000 synthetic healthy takes through against
    # 3 takes of 4 blocks, t's 7: tests/test_nonsync_null.py), in units of the spread of the history's own line z,
    # each record against the others (it carries the records' spread beyond their blocks' noise, which the pooled sd
    # underrates on a history of few records), and at least their largest
    floor = student_quantile(sum(len(b) for b in blocks) - len(blocks), int((~sync).sum()))
    left_out = []
    for i, b in enumerate(blocks):
        rest = [x for j, x in enumerate(blocks) if j != i]
        if rest and sum(len(x) for x in rest) >= 2:
            left_out.append(line_z(b, rest, sync)[~sync])
    spread = max(float(np.std(np.concatenate(left_out))), 1.0) if left_out else 1.0
    return max([floor * spread, *(float(z.max()) for z in left_out)])


def one_take_threshold(blocks: np.ndarray, table) -> float:
    """The threshold on z of a history of one take, its envelope *blocks* (take_blocks), of the gearbox of order
    table *table*."""
    # No second record: no spread between records to read, and none left out (history's threshold is the Gaussian
    # floor alone, 4.1: healthy rig takes over it 154 of 200, a 39/61 box's 33 of 50). Between two takes of the blocks'
    # noise alone a bin's z (line_z: in sds of the difference of the two means) is Student's t on the history's
    # n_h - 1 degrees of freedom a bin, pooled (student_quantile: nu 13.8 at 4 blocks; the rig takes' z read as t at
    # 15, past the Gaussian 3.7 at 1e-4: 4.9). Threshold 5.9 (4 blocks) and 5.4 (the 39/61 box's 5): healthy rig takes
    # over it 0 of 200, development seeds 300-339. Cutting the take into halves, each left out against the other as
    # history does for records, read the halves' noise (fewer blocks) in the Gaussian floor: 6 of 200 over, where 2
    # are asked
    return student_quantile(len(blocks) - 1, int((~synchronous_bins(table, blocks.shape[1])).sum()))


def student_quantile(dof: int, bins: int) -> float:
    """Student's t quantile at FALSE_ALARM shared among *bins* (Bonferroni), on the degrees of freedom of a sd pooled
    over SMOOTH bins of *dof* each (the history's blocks less its takes' means), bins that share their SUM neighbours:
    a bin correlates with the next as the 2 SUM + 1 bins they sum in common, nu = dof SMOOTH^2 / sum rho^2 over the
    window's pairs."""
    width, k = 2 * SUM + 1, np.arange(-(SMOOTH - 1), SMOOTH)
    rho = np.clip((width - np.abs(k)) / width, 0.0, None)
    nu = dof * SMOOTH**2 / float(np.sum((SMOOTH - np.abs(k)) * rho**2))
    from scipy.stats import t as student  # here, not at the top: start-up time

    return float(student.ppf(1.0 - FALSE_ALARM / bins, nu))


def take_blocks(take: np.ndarray, table) -> np.ndarray:
    """envelope_blocks of a history take's residual (*take*: (R, points)), read once per take and gearbox
    (TAKE_BLOCKS), shared read-only."""
    return TAKE_BLOCKS.of(take, repr(table), lambda: (envelope_blocks(residual(take, table), np.shape(take)[-1]),))[0]


# The history takes' envelope blocks last read, by take (its digest, shape and type) and gearbox (its order table):
# `inspect --history` reads the history again for every take it inspects, and each of a history's takes is two to
# four FFTs of its whole length and its blocks' envelopes (tests/test_outside_cn.py read one history of 4 takes 6
# times: 24 residuals, 8.8 s); a take's blocks are 5 kB per 16 input revolutions (a 400-turn take's: 130 kB).
TAKE_BLOCKS = ArraysOf(64)


def nonsync(take: np.ndarray, hist: NonSyncHistory, table, speeds: np.ndarray | None = None) -> NonSync:
    """*take* (R, points) read against the history *hist* of the gearbox of order table *table* (*speeds*: each
    revolution's input speed in Hz, where known); a take too short for it (too_short) is refused in that phrase."""
    return read_take(take, hist, table, speeds)[0]


def read_take(
    take: np.ndarray, hist: NonSyncHistory, table, speeds: np.ndarray | None = None
) -> tuple[NonSync, np.ndarray]:
    """(nonsync's reading of *take*, each bin's line z of it (line_z; bins from orders_of_bins)): the residual,
    its envelope blocks and their z read once for both, where `inspect --history` shows the strongest lines too
    (a take's residual is two to four FFTs of its whole length); a strike order on a mains harmonic at the take's
    *speeds* (each revolution's, Hz) read as hum or a bearing (hum_or_bearing)."""
    short = too_short(len(take), table) or hist.unread
    if short:
        raise GearlabInputError(short)
    r = residual(take, table)
    blocks = envelope_blocks(r, np.shape(take)[-1])
    lines = line_z(blocks, list(hist.blocks), synchronous_bins(table, blocks.shape[1]))
    z, order = _z(lines)
    order, top = refined(r, np.shape(take)[-1], order)
    shafts = products(top, table, r.size / np.shape(take)[-1])
    if speeds is None or len(speeds) != len(take) or harmonic(order * mean_speed(speeds)) is None:
        return NonSync(z, order, hist.threshold, shafts=shafts, threshold_from=hist.threshold_from), lines
    locked = hum_or_bearing(r, np.shape(take)[-1], order, speeds, hist, table)
    return NonSync(z, order, hist.threshold, *locked, shafts=shafts, threshold_from=hist.threshold_from), lines


def mean_speed(speeds: np.ndarray) -> float:
    """The mean speed (Hz) of revolutions turning at *speeds* (Hz each): turns over their time."""
    return float(len(speeds) / np.sum(1.0 / np.asarray(speeds, dtype=np.float64)))


# Hum or a bearing. A bearing's strikes are locked to its shaft's angle (a fixed order, slipping a percent or two),
# mains to time (a fixed Hz, whatever the speed). Within a take whose speed varies (each revolution's speed from the
# tacho or the found angle), a line read over the angle keeps a bearing's power and smears a hum's over o (Δs / s)
# orders; read over time, the other way round. Over R turns in T seconds (resolution 1/R orders, 1/T Hz) that smear
# must be a bin or more, o (Δs / s) R ≳ 1: over 75 turns the 50 Hz envelope line at 30 Hz (order 1.67) needs a sweep
# of about 3 %, a line at 150 Hz (order 5) about 1 %. Each reading is the line's peak power within ZOOM bins (FINE
# steps a bin) less the noise's (the median power 3 .. FLOOR bins about it); ρ = the power read in Hz over that read
# in orders, a pure tone's ρ > 1, a bearing's < 1. A slipping bearing's strikes wander as a random walk (SLIP a
# strike) that may mimic a speed change: its reach is the 1 - FALSE_ALARM quantile of log ρ of DRAWS such bearings at
# the line's order, read through the take's noise (skewed: at a 1 % sweep, 149 Hz, 77 turns, a 2 % slip, 2.0 where
# mean + 2.33 sd says 1.6). The take tells the two apart where a mains tone reads past that reach; then the line is a
# hum where its log ρ passes the reach and its noise (the one-sided Gaussian quantile at FALSE_ALARM times the sd of
# log ρ from the noise beside each reading), a bearing's where it is below minus its noise, else not told apart, said
# with why (a steady speed, the PHM 2009 rig's 0.2 % drift: a tone within reach). A hum read in the residual is less
# sharp in Hz than a pure tone (the residual loses the bins about the shafts' orders its smeared components cross):
# tests/test_hum_or_bearing.py's drive (74 turns at 30 Hz, 3 % sweep, 0.3 m/s² hum) ρ 1.4-1.6, a tone 2.1.
# Across takes: a history take at another speed carries a hum at the same Hz, at another order; a line there (its
# take's own blocks over its neighbours, z over the one-sided Gaussian quantile at FALSE_ALARM shared by the SEEN
# bins read) is a hum. A history without it says nothing: a hum may have begun since.
ZOOM, FINE = 2, 10
FLOOR = 40  # bins either side whose median power is the noise beside a line (a smeared line covers fewer)
KEEP = 32  # envelope samples per revolution read for it (to order 16: past FUNDAMENTAL, the highest order named)
SLIP, DRAWS = 0.02, 200  # a rolling element's slip, sd per strike interval (the upper end of 1-2 %); bearings drawn
SEEN = 3  # bins about the history take's order of the line read for it (the line's order known to a bin)


def hum_or_bearing(r: np.ndarray, points: int, order: float, speeds, hist: NonSyncHistory, table) -> tuple[str, str]:
    """(what the residual *r*'s (flat, *points* a revolution) envelope line at input order *order* is locked to:
    "time", "angle", or "" not told apart; why, in words) from its revolutions' *speeds* (Hz each) and the history
    *hist*'s takes at other speeds (module comment above)."""
    from scipy.signal import hilbert

    revs = r.size // points
    s = np.asarray(speeds[:revs], dtype=np.float64)
    e = np.abs(hilbert(r[: revs * points])) ** 2
    e = np.fft.irfft(np.fft.rfft(e - e.mean())[: KEEP // 2 * revs + 1], n=KEEP * revs)  # low-passed, KEEP a turn
    k = np.arange(e.size) // KEEP
    angle = np.arange(e.size) / KEEP  # turns
    t = np.r_[0.0, np.cumsum(1.0 / s)[:-1]][k] + (angle - k) / s[k]
    T = float(np.sum(1.0 / s))
    hz = order * revs / T
    in_hz = _kernels(hz, 1.0 / T, t, 1.0 / (KEEP * s[k] * T))  # each sample's time over the take's
    in_orders = _kernels(order, 1.0 / revs, angle, np.full(e.size, 1.0 / e.size))

    def sharper_in_hz(x: np.ndarray) -> np.ndarray:
        """log ρ of each row of *x* (pure models: no noise beside)."""
        return np.log((np.abs(in_hz[0] @ x.T) ** 2).max(axis=0) / (np.abs(in_orders[0] @ x.T) ** 2).max(axis=0))

    got, sd = _line_ratio(e, in_hz, in_orders)
    rng = np.random.default_rng(0)  # the same bearings drawn for every take: one take, one call
    walk = np.cumsum(rng.normal(0.0, SLIP * math.sqrt(order / KEEP), (DRAWS, e.size)), axis=1)
    slipping = sharper_in_hz(np.cos(2 * np.pi * (order * angle + walk))) + sd * rng.standard_normal(DRAWS)
    reach = float(np.quantile(slipping, 1.0 - FALSE_ALARM))  # read through this take's noise
    tone = float(sharper_in_hz(np.cos(2 * np.pi * hz * t)[None, :])[0])
    sure = NormalDist().inv_cdf(1.0 - FALSE_ALARM) * sd  # the line's log ρ beyond its noise, one-sided
    spread = f"the take's {100 * (s.max() - s.min()) * T / revs:.1f} % speed spread over {revs} turns"
    bearing = f"a slipping bearing's up to {math.exp(reach):.2g}"
    said = f"{math.exp(got):.2g} times the power read in Hz as in orders over {spread}"
    if tone > reach and got > max(reach, sure):
        return "time", f"{said} (a mains tone's {math.exp(tone):.2g}, {bearing})"
    if tone > reach and got < -sure:
        said = f"{math.exp(-got):.2g} times the power read in orders as in Hz over {spread}"
        return "angle", f"{said}: it moves with the speed"
    seen = _at_other_speeds(hist, table, order, hz)
    if seen.startswith("at"):
        return "time", seen
    seen = f" ({seen}: a hum may have begun since)" if seen else ""
    if tone <= reach:
        return (
            "",
            f"{spread} reads a mains tone {math.exp(tone):.2g} times as strong in Hz as in orders, {bearing}{seen}",
        )
    return "", f"{said}: within {bearing} or the noise{seen}"


def _kernels(centre: float, step: float, at: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the Fourier kernels within ZOOM bins of *centre* in FINE steps a bin of *step*; those at the whole bins
    ZOOM + 1 .. FLOOR either side, the noise beside it), over the samples' *at* (turns or seconds) each *weight*ed."""
    zoom = np.arange(-ZOOM * FINE, ZOOM * FINE + 1) / FINE
    beside = np.r_[-FLOOR:-ZOOM, ZOOM + 1 : FLOOR + 1]
    return tuple(np.exp(-2j * np.pi * np.outer(centre + d * step, at)) * weight for d in (zoom, beside))


def _line_ratio(e: np.ndarray, in_hz: tuple, in_orders: tuple) -> tuple[float, float]:
    """(log ρ of the envelope *e*'s line: its peak power read with the kernels *in_hz* over that *in_orders*, each less
    the median power beside it; the sd of that log from the noise)."""
    lines, noises, peaks = [], [], []
    for zoom, beside in (in_hz, in_orders):
        read = np.abs(zoom @ e) ** 2
        noises.append(float(np.median(np.abs(beside @ e) ** 2)) / math.log(2.0))  # the median of an exponential
        lines.append(max(float(read.max()) - noises[-1] * math.log(2.0), 1e-300))
        peaks.append(zoom[read.argmax()])
    # a line of power L read with noise of mean power N: |L + n|² - L ≈ 2 Re(√L n*), the sd of its log sqrt(2 N / L);
    # the two readings of one take's noise correlate as their kernels at the peaks do (1 at a steady speed)
    u, v = peaks
    c = abs(np.vdot(v, u)) / math.sqrt(np.vdot(u, u).real * np.vdot(v, v).real)
    a, b = noises[0] / lines[0], noises[1] / lines[1]
    return math.log(lines[0] / lines[1]), math.sqrt(2.0 * max(a + b - 2.0 * c * math.sqrt(a * b), 0.0))


def _at_other_speeds(hist: NonSyncHistory, table, order: float, hz: float) -> str:
    """Where a history take at another speed (*hist*.speeds) carries a line at *hz* (a take's line at input order
    *order*) at its own order, in words, starting "at"; where those read hold none, that, starting "no"; "" where
    none is read (none at another speed)."""
    sync = synchronous_bins(table, hist.blocks[0].shape[1])
    lo = int(math.ceil(LOW * BLOCK))
    over = NormalDist().inv_cdf(1.0 - FALSE_ALARM / SEEN)
    read = []
    for blocks, speed in zip(hist.blocks, hist.speeds):
        there = hz / speed
        at = int(round(there * BLOCK)) - lo
        if abs(there - order) * BLOCK <= 2 * SUM or not 0 <= at < blocks.shape[1] or sync[at] or len(blocks) < 2:
            continue  # the same bins as the take's line (the same speed), out of the band, or a shaft's
        near = np.arange(max(at - LINE, 0), min(at + LINE + 1, blocks.shape[1]))
        around = near[np.abs(near - at) > SUM + SEEN // 2]  # its neighbours, past the line's own bins
        mean, sd = blocks.mean(axis=0), float(np.median(blocks[:, near].std(axis=0, ddof=1)))
        line = mean[max(at - SEEN // 2, 0) : at + SEEN // 2 + 1].max()
        z = (line - np.median(mean[around])) * np.sqrt(len(blocks)) / sd
        if z > over:
            return f"at {hz:.1f} Hz too in the history's take at {speed:.1f} Hz (order {there:.2f} there, z {z:.1f})"
        read.append(f"{speed:.1f}")
    return f"no line at {hz:.1f} Hz in the history's takes at {', '.join(read)} Hz" if read else ""
