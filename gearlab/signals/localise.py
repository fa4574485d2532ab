"""Which gear: the shaft, and the gear on it, whose synchronous average carries a localised change.

A localised tooth fault (chip, crack, broken tooth) strikes once per revolution of its shaft. Its
signature is periodic in that shaft's angle and nothing else's, and being short it spreads its
energy evenly over many harmonics of that shaft. The train's speed ratios are fractions of tooth
counts (gearlab.gearbox.orders), so these harmonics can be told apart:

Grand period. After P input revolutions (the order table's train period, P = 15 on the PHM 2009
rig: input 1, idler 1/3, output 1/5) every shaft s has turned a whole number n_s = o_s P of times
(15, 5, 3). The record, resampled in the input angle, is averaged over its grand periods (a TSA of
P input revolutions) and read in grand-period orders q (q / P input orders). A component
synchronous with shaft s lives only at q multiple of n_s; q synchronous with several shafts is
shared (every input order, q = 15k, is also an idler and an output order), q synchronous with s
alone is *exclusive* to s. Mesh harmonics, shared by all, are left out with their first
sidebands (the regular content a difference signal removes). An input-pinion chip is periodic in
the idler's turn too -- three equal impulses per idler revolution -- but only at idler orders
multiple of 3, so it is not read as idler content.

Evidence. Per order, the synchronous power S(q) = |X̄(q)|² − n(q) (n: the scatter of the averaged
periods about their mean over their number, smoothed over neighbouring orders) is compared with
the healthy history's, Δ(q) = S(q) − S_h(q). The history's units are blocks of one length (half the
shortest record under 4 records). Where the grand period does not fit (Fallback) another shaft's
lines leak into a shaft's average by an amount set by the length averaged, so a record's S is
there the mean over its blocks of that length (a healthy 24/79 + 27/72 take read whole against
half-record units: input z 5-6; in blocks 0 ± 1, development seeds). Each order's Δ is read in sds
of its null spread (signals.evidence: the fault's excess is largest where that spread is; after the take's
level, read from its noise floor, and its lines' gain; off them a heavier load's). A fault on shaft s adds a
level L_s, about flat across a band in those units, at every order synchronous with s: in each band of orders
the mean of each class (the set of shafts an order is synchronous with) is Σ_{s in class} L_s, solved by least
squares (on the rig: L_idler from the idler-exclusive orders, L_output from the output-exclusive
ones, L_input from the shared orders less both). The bands combine into z_s = L_s / sd(L_s); the
shafts rank by z. A shaft is flagged above a threshold fixed on the history alone: the largest z of
its records, each left out of the reference in turn, at least the Gaussian quantile at the false-alarm
rate shared among the shafts.

Which gear on a shaft. Given the gearbox description's simulated events (*templates*, from a layer
that may simulate: gearlab.data.which_templates), a two-gear shaft's gear is the one whose
simulated tooth-fault event fits the record's clearly better (signals.which_template: a stage-1
wheel's and a stage-2 pinion's force pulse reach the sensor through different modes). Without them,
by the length of the event (which_template.which_by_width): a tooth fault lasts while its tooth is
in mesh, about a pitch of its own gear, so the finer gear's (more teeth) is shorter. The shaft's
own orders (those no faster shaft shares) from 1/2 to 4 times the finer gear's tooth count
(WIDTH_BAND), each weighted by its new share as for the tooth, give an envelope whose RMS width w
about its peak is read in pitches of the finer gear. u = log w / log(Z_fine / Z_coarse) names the
finer gear up to U_FINE, the coarser above U_COARSE; both (as the shaft) between, or when the tooth
counts differ by less than MIN_RATIO, or more than WIDTH_LOW of the excess lies below half the
finer gear's tooth order (a low mode's ring sets the width), or z < WIDTH_Z and the event reads
wide (noise widens an event, never narrows it). The width follows the structure's modes as well as
the teeth, and a pit or spall lasts a part of its pitch, so the two gears' u overlap. The event's
mesh phase (which_template.mesh_phases: its content about each gear's mesh line, at its peak, against
that line; in phase for the damaged gear's own mesh) names the gear of counts under MIN_RATIO where
one leads by PHASE_MARGIN and the other is not in anti-phase; of counts further apart where the width abstains
(a low mode rings, z < WIDTH_Z), the one gear whose event stands with its mesh line, or against it, at the
1st and 2nd harmonic alike (which_template._by_phases_alike: a tooth lifts or lowers its own mesh). "Both" is
no safe answer: a scenario
watching either gear counts it as its own.

Tooth. The named shaft's orders, each weighted by the share of its power that is new (clip(Δ /
|X̄|², 0, 1)), form its residual; the peak of its envelope's energy over one pitch, in the shaft's
angle o_s θ (θ the continuous input angle, zero at the first tacho mark) over the pitch 2π/z, is
the tooth of each gear on the shaft (tooth n spans pitches n − 1 … n). A tacho of N marks per turn
starts a take at any of them: a take is first advanced by the m/N turn whose mean revolution
correlates best with the first history record's (:func:`turned`), so every take counts from that
record's mark. On a shaft of order a/b (b > 1: the idler's 1/3) the count is defined only up to
steps of z/b teeth: a take's first mark finds that shaft at any of b angles, and nothing tells
which (the take's grand-period mean against the first record's: right for 7 of 120 takes,
development seeds). The tooth says so ("step"); a step of a tooth or less fixes nothing across takes, said
plainly. The tacho's own shaft is fixed to its mark: its tooth counts from it ("mark", the take's turn
added back), at N marks a turn up to steps of z/N (alike marks: "step"). A strike's ring moves the peak
later by its decay.

Fallback. When the record holds fewer than *min_periods* grand periods (tooth counts with few
common factors: 17/43 turns the output 17 times in 43 input revolutions), each shaft's own TSA
is taken instead, the record resampled at that shaft's angle, and an absolute order x = m o_s of
shaft s's TSA is synchronous with shaft r when x / o_r is whole: the same classes, each order read
from the TSA of the fastest shaft it is synchronous with. The result says which was used. A shaft's
TSA averages the record less the faster shafts' averages (their lines, at no whole order of it, leak
into its average and its turn-to-turn scatter: see SWEEPS); its noise is the scatter of its turns less
every other shaft's average, plus what those leave in its mean (signals.shaft.shaft_averages).

Everything is numpy: no torch, nothing from the layers above.
"""

from __future__ import annotations

import hashlib
import json
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from fractions import Fraction
from statistics import NormalDist

import numpy as np

from ..errors import GearlabInputError
from .checks import check_array, check_int
from .evidence import (  # noqa: F401 (read as localise's)
    KAPPA,
    WEIGHT_SMOOTH,
    Spread,
    _null_var,
    order_z,
    shaft_levels,
    spread,
)
from .shaft import averaged, shaft_averages, uniform_filter1d
from .which_template import (  # noqa: F401 (the width's settings: read by tests and docs as localise's)
    MIN_RATIO,
    RULE_SIMULATED,
    RULE_WIDTH,
    U_COARSE,
    U_FINE,
    WEAK_LEAD,
    WEAK_RIGHT,
    WIDTH_BAND,
    WIDTH_LOW,
    WIDTH_Z,
    envelope,
    favoured_first,
    fit_words,
    lead_words,
    mesh_combs,
    mesh_contrasts,
    mesh_phases,
    phase_words,
    two_harmonic_phases,
    weak_lead,
    weakly,
    which_by_template,
    which_by_width,
)

# Fallback: each shaft's TSA of the record less the faster shafts' averages (one pass, fastest first). Two
# passes (less every other shaft's) flagged the input on a slower gear's crack: its lines at orders the
# input shares are then weighed by their own noise (development, tests/test_localise_blocks.py)
SWEEPS = 1
MIN_PERIODS = 4  # grand periods a record must hold for the grand-period average
SIDEBANDS = 1  # sidebands of each mesh harmonic left out with it (its regular content)
FALSE_ALARM = 0.01  # the Gaussian floor of the thresholds, shared out among the shafts


# --- the train: shafts, gears, orders ------------------------------------------------------------


@dataclass(frozen=True)
class Gear:
    shaft: str
    stage: int
    role: str  # "pinion" (the stage's driver) or "wheel"
    teeth: int

    @property
    def name(self) -> str:
        kind = "pinion" if self.role == "pinion" else "gear"
        return f"{self.shaft} {kind} {self.teeth}T (stage {self.stage})"


def gears_of(table) -> dict[str, list[Gear]]:
    """The gears on each shaft of an order table (gearlab.gearbox.orders.OrderTable), input first."""
    out: dict[str, list[Gear]] = {s: [] for s in table.shafts}
    for st in table.stages:
        out[st.pinion_shaft].append(Gear(st.pinion_shaft, st.index, "pinion", st.pinion_teeth))
        out[st.wheel_shaft].append(Gear(st.wheel_shaft, st.index, "wheel", st.wheel_teeth))
    return out


@dataclass(frozen=True)
class Layout:
    """The orders read, and what each is: the same for a record and its history.

    mode: "grand" (one average over grand periods of *period* input revolutions) or "shafts"
    (each shaft's own TSA); orders: input orders of the kept lines; sync: (orders, shafts) bool,
    synchronous with each shaft; source: the shaft whose TSA an order is read from (-1: the grand
    average); index: the order's bin in that average; owners: (orders, stages) bool, the stages whose
    mesh harmonic is the order's nearest mesh-harmonic position; carrier: the order is a mesh
    harmonic (read for the gear on a shaft, never as evidence)."""

    mode: str
    period: int
    shafts: tuple[str, ...]
    shaft_orders: tuple[Fraction, ...]
    points: int
    orders: np.ndarray
    sync: np.ndarray
    source: np.ndarray
    index: np.ndarray
    owners: np.ndarray
    carrier: np.ndarray
    meshes: tuple[float, ...]
    min_order: float
    max_order: float
    band: float
    note: str


def _excluded(x: np.ndarray, table, sidebands: int) -> tuple[np.ndarray, np.ndarray]:
    """(mesh harmonics and their first *sidebands* sidebands by either shaft of the stage, the
    mesh harmonics alone)."""
    out, harmonic = np.zeros(x.shape, bool), np.zeros(x.shape, bool)
    for st in table.stages:
        mesh = float(st.mesh)
        h = np.round(x / mesh)
        d = x - h * mesh
        harmonic |= (h >= 1) & (np.abs(d) < 1e-9 * np.maximum(x, 1))
        for o in {float(st.pinion_shaft_order), float(st.wheel_shaft_order)}:
            j = np.round(d / o)
            out |= (h >= 1) & (np.abs(j) <= sidebands) & (np.abs(d - j * o) < 1e-9 * np.maximum(x, 1))
    return out, harmonic


def _owners(x: np.ndarray, table) -> np.ndarray:
    """(orders, stages) bool: the stages with a mesh harmonic at each order's nearest harmonic position."""
    meshes = np.array([float(st.mesh) for st in table.stages])
    cand = []
    for m in meshes:
        h = np.maximum(np.floor(x / m), 1)
        cand += [h * m, (h + 1) * m]
    cand = np.stack(cand, axis=1)
    pos = cand[np.arange(x.size), np.argmin(np.abs(cand - x[:, None]), axis=1)]
    r = pos[:, None] / meshes[None, :]
    return np.abs(r - np.round(r)) < 1e-9


def layout(
    table,
    points: int,
    revolutions: int,
    *,
    max_order: float | None = None,
    min_order: float | None = None,
    band: float | None = None,
    sidebands: int = SIDEBANDS,
    min_periods: int = MIN_PERIODS,
) -> Layout:
    """The orders a record of *revolutions* input revolutions at *points* per revolution is read at."""
    points = check_int(points, "points per revolution", minimum=8)
    revolutions = check_int(revolutions, "revolutions", minimum=1)
    shafts = tuple(table.shafts)
    o = tuple(Fraction(f) for f in table.shaft_orders)
    lowest_mesh = min(float(st.mesh) for st in table.stages)
    top = 0.45 * points if max_order is None else float(max_order)
    lo = lowest_mesh / 2 if min_order is None else float(min_order)
    width = max(lowest_mesh / 2, 2.0) if band is None else float(band)
    if not 0 < lo < top <= points / 2:
        raise GearlabInputError(
            f"localisation band {lo:g} … {top:g} input orders: expected 0 < min_order < max_order <= {points / 2:g} "
            f"(half the {points} points per revolution)"
        )
    P = int(table.train_period)
    if revolutions // P >= min_periods:
        q = np.arange(1, int(math.floor(top * P)) + 1)
        x = q / P
        n = np.array([int(f * P) for f in o])
        sync = (q[:, None] % n[None, :]) == 0
        source = np.full(q.size, -1)
        index = q
        turns = ", ".join(f"{s} {k}" for s, k in zip(shafts, n))
        note = f"grand period of {P} input revolutions ({turns} turns), {revolutions // P} averaged"
    else:
        xs, syncs, sources, idx = [], [], [], []
        fastest = np.argsort([-float(f) for f in o], kind="stable")
        for s in range(len(shafts)):
            m = np.arange(1, int(math.floor(top / float(o[s]))) + 1)
            # k o_s / o_r whole where den(o_s) num(o_r) divides k num(o_s) den(o_r): exact integers (Python's where
            # int64 could overflow); a Fraction division each took 1.5 s of CPU a three-stage box's layout
            k = m.astype(object) if m.size * max(a.numerator * b.denominator for a in o for b in o) >= 2**62 else m
            whole = [k * (o[s].numerator * r.denominator) % (o[s].denominator * r.numerator) == 0 for r in o]
            sy = np.stack(whole, axis=1).astype(bool).reshape(m.size, len(o))
            first = fastest[np.argmax(sy[:, fastest], axis=1)]  # every row holds its own shaft's
            keep = first == s
            xs.append(m[keep] * float(o[s]))
            syncs.append(sy[keep])
            sources.append(np.full(int(keep.sum()), s))
            idx.append(m[keep])
        x, sync, source, index = (np.concatenate(a) for a in (xs, syncs, sources, idx))
        order = np.argsort(x, kind="stable")
        x, sync, source, index = x[order], sync[order], source[order], index[order]
        note = (
            f"per-shaft TSAs: the grand period ({P} input revolutions) fits {revolutions // P} time(s) in "
            f"{revolutions} revolutions, fewer than {min_periods}"
        )
    excluded, harmonic = _excluded(x, table, sidebands)
    keep = sync.any(axis=1) & (x <= top) & (((x >= lo) & ~excluded) | harmonic)
    if not (keep & ~harmonic).any():
        raise GearlabInputError(f"no shaft-synchronous order left between orders {lo:g} and {top:g} to localise with")
    x, harmonic = x[keep], harmonic[keep]
    return Layout(
        "grand" if source[0] == -1 else "shafts",
        P,
        shafts,
        o,
        points,
        x,
        sync[keep],
        source[keep],
        index[keep],
        _owners(x, table),
        harmonic,
        tuple(float(st.mesh) for st in table.stages),
        lo,
        top,
        width,
        note,
    )


# --- one unit's synchronous content ----------------------------------------------------------------


@dataclass(frozen=True)
class Content:
    """One unit (a record, or a piece of a history record) at a layout's orders.

    mean: complex mean amplitude per order; noise: the noise power of that mean; power: the
    synchronous power |mean|² − noise, or its mean over *blocks* of the record;
    periods: the averages behind it (grand periods, or the fewest shaft revolutions)."""

    mean: np.ndarray
    noise: np.ndarray
    power: np.ndarray
    periods: int
    first_revolution: int
    blocks: int = 1
    source: np.ndarray | None = None  # the layout's source of each order: noise is smoothed within one TSA


def content(
    revolutions: np.ndarray, lay: Layout, first_revolution: int = 0, block: int | None = None, sweeps: int = SWEEPS
) -> Content:
    """The synchronous content of consecutive input *revolutions* (R, points) at *lay*'s orders.

    *first_revolution*: the input revolution revolutions[0] is, counted from the angle's zero (the
    first tacho mark): the slower shafts' angles, and so the tooth index, are measured from there.
    *block*: the power is the mean of the record's whole blocks of that many revolutions (the
    history's units: see the module's docstring, "Evidence"); the mean is the whole record's. *sweeps*:
    per-shaft TSAs of the record less the other shafts' averages so far (Fallback; 1: the faster
    shafts'), 0: of the record itself (a noise-free simulation's difference from the healthy one)."""
    revs = check_array(revolutions, "revolutions", min_ndim=2)
    if revs.ndim != 2 or revs.shape[1] != lay.points:
        raise GearlabInputError(
            f"revolutions of shape {revs.shape}: expected (revolutions, {lay.points}) consecutive input revolutions"
        )
    first_revolution = check_int(first_revolution, "first revolution", minimum=0)
    record = hashlib.blake2b(np.ascontiguousarray(revs), digest_size=20)
    record.update(repr((revs.shape, revs.dtype.str)).encode())
    read = hashlib.blake2b(repr((lay.mode, lay.period, lay.points, lay.shaft_orders, lay.shafts)).encode())
    for part in (lay.orders, lay.source, lay.index):  # what a content reads of its layout
        read.update(np.ascontiguousarray(part).tobytes())
    key = (record.digest(), read.digest(), first_revolution, block, sweeps)
    with _READ_LOCK:
        if key in _READ:
            _READ.move_to_end(key)
            return _READ[key]
    found = _content(revs, lay, first_revolution, block, sweeps)
    with _READ_LOCK:
        _READ[key] = found
        while len(_READ) > READ_KEPT:
            _READ.popitem(last=False)
    return found


# The contents last read, by record and layout (their digests), first revolution, block and sweeps: a
# detection reads its target take for its stored localisation and again for its score, and inspect
# --history builds one history twice; each read is a record's rfft, 2 x denser irfft and reading per shaft
# (signals.shaft.shaft_averages), and the same data gives the same content (not to be changed in place).
READ_KEPT = 64
_READ: OrderedDict = OrderedDict()
_READ_LOCK = threading.Lock()


def _content(revs: np.ndarray, lay: Layout, first_revolution: int, block: int | None, sweeps: int) -> Content:
    """content() of checked *revs*, read afresh."""
    R, pts = revs.shape
    y = revs.reshape(-1)
    mean = np.zeros(lay.orders.size, complex)
    noise = np.zeros(lay.orders.size)
    if lay.mode == "grand":
        P = lay.period
        n = R // P
        if n < 2:
            raise GearlabInputError(f"{R} revolutions hold {n} grand period of {P}; expected at least 2")
        m, v = averaged(y[: n * P * pts].reshape(n, P * pts), int(lay.index.max()), P)
        mean[:], noise[:] = m[lay.index], v[lay.index]
        periods = n
    else:
        mean, noise, periods = shaft_averages(y, lay, first_revolution, R, sweeps)
    whole = Content(mean, noise, np.abs(mean) ** 2 - noise, int(periods), first_revolution, 1, lay.source)
    if block and R > block:
        return in_blocks(_units(revs, first_revolution, lay, block), whole)
    return whole


def in_blocks(parts: list[Content], whole: Content | None = None) -> Content:
    """A record's content read in blocks (content's *block*): its blocks' power and noise, and the mean and turns of
    *whole*, the record read whole (history() has the blocks already, as its units: each a shaft_averages of a 2 x
    denser reading). None: the blocks' mean and turns, where nothing reads them (a history record's left-out levels
    read the power and noise alone; read whole, its records doubled the history's reading)."""
    power = np.mean([u.power for u in parts], axis=0)
    noise = np.mean([u.noise for u in parts], axis=0) / len(parts)
    if whole is None:
        mean, periods = np.mean([u.mean for u in parts], axis=0), sum(u.periods for u in parts)
        return Content(mean, noise, power, periods, parts[0].first_revolution, len(parts), parts[0].source)
    return Content(whole.mean, noise, power, whole.periods, whole.first_revolution, len(parts), whole.source)


# --- the history --------------------------------------------------------------------------------------


# --- the evidence ------------------------------------------------------------------------------------


def shaft_label(shaft: str, gears: list[Gear]) -> str:
    """What a flag on *shaft* names: its gear, or the shaft with both of its gears."""
    if len(gears) == 1:
        return gears[0].name
    kinds = (f"{g.teeth}T {'pinion' if g.role == 'pinion' else 'gear'} (stage {g.stage})" for g in gears)
    return f"{shaft} shaft: {' or '.join(kinds)}"


@dataclass(frozen=True)
class ShaftEvidence:
    shaft: str
    gears: tuple[str, ...]
    level: float  # L_s: the excess synchronous power per order, in null sds of an order's Δ (signals.evidence)
    sd: float
    z: float
    threshold: float
    orders: int  # exclusive orders of the shaft read
    flagged: bool
    gear: str  # what a flag names: the gear, or the shaft with both its gears (shaft_label)
    which: str | None = None  # of two gears on the shaft, the one the event's length names
    stage_evidence: dict = field(default_factory=dict)
    tooth: dict = field(default_factory=dict)  # gear name -> {"pitches": float, "tooth": int}

    def describe(self) -> dict:
        return {
            "shaft": self.shaft,
            "gears": list(self.gears),
            "level": self.level,
            "sd": self.sd,
            "z": self.z,
            "threshold": self.threshold,
            "exclusive_orders": self.orders,
            "flagged": self.flagged,
            "gear": self.gear,
            "which": self.which,
            "stage_evidence": self.stage_evidence,
            "tooth": self.tooth,
        }


def _harmonics(lay: Layout, shaft: int, sel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the orders of *sel* read from the shaft's average, their harmonic numbers of the shaft)."""
    if lay.mode == "grand":
        return sel, lay.index[sel] // int(lay.shaft_orders[shaft] * lay.period)
    sel = sel & (lay.source == shaft)
    return sel, lay.index[sel]


def tooth_index(
    rec: Content, ref: Spread, lay: Layout, shaft: int, gears: list[Gear], turn=None, tacho=False, free=False, pulses=1
) -> dict:
    """Peak of the shaft's residual envelope in the shaft's angle, in tooth pitches of each gear on it.
    *turn*: the take's advance (m/marks, :func:`turned`) where this is the tacho's own shaft (one mark
    per turn: its angle from the mark is known, so is the tooth); *tacho*: the history has a tacho;
    *free*: it has none, a take's zero is its first sample (History.free); *pulses*: the marks a turn of this
    shaft's own tacho, alike (its tooth is known up to steps of z / pulses)."""
    sel, m = _harmonics(lay, shaft, lay.sync[:, shaft] & ~lay.carrier)
    o = lay.shaft_orders[shaft]
    offset = 2 * math.pi * float((o * rec.first_revolution) % 1) if lay.mode == "grand" else 0.0
    offset += 0.0 if turn is None or o == 1 else 2 * math.pi * float((o * turn) % 1)  # the input's: the first record's
    if not sel.any():
        return {}
    size = int(2 ** math.ceil(math.log2(8 * max(int(m.max()), max(g.teeth for g in gears)) + 1)))
    env = envelope(rec, ref, sel, m, size)
    # the energy over one pitch of the finer gear: inside a one-tooth event the envelope follows
    # the carrier's waveform, whose own peak may lie anywhere in the mesh cycle
    width = max(1, int(round(size / max(g.teeth for g in gears))))
    env = uniform_filter1d(env, size=width, mode="wrap")
    i = int(np.argmax(env))
    a, b, c = env[i - 1], env[i], env[(i + 1) % size]
    shift = 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) < 0 else 0.0
    angle = (2 * math.pi * (i + shift) / size + offset) % (2 * math.pi)
    out = {"angle_deg": math.degrees(angle)}
    for g in gears:
        pitches = angle / (2 * math.pi / g.teeth)
        out[g.name] = {"pitches": pitches, "tooth": int(math.floor(pitches)) % g.teeth + 1, "of": g.teeth}
        if turn is not None:
            out[g.name] |= {"mark": True} | ({"step": g.teeth / pulses, "tacho": True} if pulses > 1 else {})
        elif free:  # a take's zero is its first sample: no shaft's angle there is known, the input's neither
            out[g.name] |= {"free": True, "tacho": False}
        elif o.denominator > 1:  # see the module's docstring, "Tooth": defined up to steps of z / b
            out[g.name] |= {"step": g.teeth / o.denominator, "tacho": bool(tacho)}
    return out


def turned(revolutions: np.ndarray, reference: np.ndarray, marks: int) -> tuple[int, np.ndarray]:
    """(m, *revolutions* advanced by m/*marks* of a turn): m = 0 … marks − 1, the advance whose mean
    revolution correlates best with *reference*; cut again m/marks of a turn later, continuously,
    one revolution shorter when m > 0; an advance rounds to the nearest point."""
    revs = np.asarray(revolutions)
    if marks <= 1:
        return 0, revs
    pts = revs.shape[1]
    # circular cross-correlation: corr[k] = Σ reference(i) mean(i + k), at every point at once
    corr = np.fft.irfft(np.conj(np.fft.rfft(reference)) * np.fft.rfft(revs.mean(axis=0)), n=pts)
    at = [round(m * pts / marks) % pts for m in range(marks)]
    m = int(np.argmax(corr[at]))
    if at[m] == 0:
        return 0, revs
    flat = revs.reshape(-1)[at[m] :]
    return m, flat[: (flat.size // pts) * pts].reshape(-1, pts)


THIS_TAKE = "in this take only: the tooth is not fixed across takes"  # a step of a tooth or less (tooth_words)
FROM_MARK = "counted from the tacho's mark on this shaft"  # the tacho's own shaft at one mark a turn


def tooth_words(t: dict) -> str:
    """ "17 of 96", with the step it is defined up to on a shaft of no whole input order; a step of a
    tooth or less defines nothing across takes (a 19/71 + 28/47 output gear: any of 3337 angles, a
    number no one can act on: said plainly), as is any tooth without a tacho ("free"); on the tacho's own
    shaft, fixed to its mark."""
    if t.get("mark") and t.get("step", 2) > 1:
        steps = f", up to {t['step']:g}-tooth steps between takes: its marks are alike" if "step" in t else ""
        return f"{t['tooth']} of {t['of']} ({FROM_MARK}{steps})"
    if t.get("free") or ("step" in t and t["step"] <= 1):
        # a take starts at its first tacho mark, or without a tacho at its first sample
        known = "relative to the tacho" if t.get("tacho") else "at a take's start"
        return f"{t['tooth']} of {t['of']} ({THIS_TAKE}; this shaft's angle {known} is not known)"
    return f"{t['tooth']} of {t['of']}" + (f" (up to {t['step']:g}-tooth steps between takes)" if "step" in t else "")


def which_line(evidence: dict, which: str | None) -> str:
    """A shaft's evidence for which of its two gears (ShaftEvidence.stage_evidence), in words; ""
    for a one-gear shaft."""
    if not evidence:
        return ""
    expected = " / ".join(f"{g.split(' (')[0]} ~{v:.2f}" for g, v in evidence["expected"].items())
    # the widths expected beside the width read: after the phases a user read 'phases ... 0.39 / 0.08,
    # expected ~0.88 / ~1.30' as a phase match of 0.39 where 0.88 was expected
    read = f"{evidence['width']:.2f} " if "width" in evidence else "not read, in "
    said = f"event width {read}{evidence['event width']} (expected {expected}), " + phase_words(evidence)
    said = (said + fit_words(evidence)).removesuffix(", ")
    rule = evidence.get("rule", RULE_WIDTH)  # evidence stored before the rule was said: the width's
    if which:
        lead = weak_lead(evidence)
        weak = (
            ""
            if lead is None
            else f"; weak: a phase lead of {lead_words(lead)}, under {WEAK_LEAD:g} (so led, right in {WEAK_RIGHT})"
        )
        return f"; named {rule} ({said}){weak}"
    return f"; which of the two: undecided {rule} ({said}; {evidence['undecided']})"


def threshold_floor(shafts: int, false_alarm: float = FALSE_ALARM) -> float:
    return NormalDist().inv_cdf(1 - false_alarm / shafts)


@dataclass(frozen=True)
class Localisation:
    """The shafts ranked by the z of their localised excess; *named*: the gear named first, or None
    (nothing localised: no shaft over its threshold)."""

    method: str
    ranking: tuple[ShaftEvidence, ...]
    named: str | None
    named_shaft: str | None

    def summary(self) -> str:
        top = self.ranking[0]
        if self.named is None:
            return f"nothing localised (largest: {top.shaft} z = {top.z:.2f}, threshold {top.threshold:.2f})"
        ev = next(e for e in self.ranking if e.shaft == self.named_shaft)
        teeth = [ev.tooth[g] for g in ([ev.which] if ev.which else ev.gears) if g in ev.tooth]
        at = (", tooth " + " / ".join(map(tooth_words, teeth))) if teeth else ""
        which = which_line(ev.stage_evidence, ev.which)
        return f"{self.named}: z = {ev.z:.2f} (threshold {ev.threshold:.2f}){at}{which}"

    def describe(self) -> dict:
        return {
            "method": self.method,
            "named": self.named,
            "named_shaft": self.named_shaft,
            "summary": self.summary(),
            "shafts": [e.describe() for e in self.ranking],
        }


@dataclass(frozen=True)
class History:
    """A healthy history read for localisation: its layout, the spread of its units and the thresholds."""

    layout: Layout
    spread: Spread
    thresholds: np.ndarray
    left_out_z: np.ndarray  # (history records, shafts): each record's z against the rest
    note: str
    args: dict = field(default_factory=dict)  # layout()'s arguments: the layout is remade from them
    marks: int = 1  # tacho marks per turn: each take is turned to *reference* (see turned)
    reference: np.ndarray | None = None  # the first history record's mean revolution
    block: int | None = None  # revolutions of a unit: a record's power is read in blocks of as many
    tacho: str = ""  # the shaft the tacho reads ("": none, or not said)
    pulses: int = 1  # its marks per turn
    free: bool = False  # no tacho: a take's zero is its first sample, no gear's tooth is fixed across takes
    envelope: object = None  # the same takes' envelopes in each band (signals.envelope_sync.Bank), where read

    def state(self) -> dict[str, np.ndarray]:
        """Plain arrays (np.savez) from which :meth:`restored` remakes this history, records unread."""
        sp = self.spread
        return {
            "power": sp.power,
            "line": sp.line,
            "between": sp.between,
            "unit_noise": sp.unit_noise,
            "units": np.array(sp.units),
            "excess": sp.excess,
            "periods": np.array(sp.periods),
            "thresholds": self.thresholds,
            "left_out_z": self.left_out_z,
            "note": np.array(self.note),
            "args": np.array(json.dumps(self.args)),
            "marks": np.array(self.marks),
            "reference": np.zeros(0) if self.reference is None else self.reference,
            "block": np.array(self.block or 0),
            "tacho": np.array(self.tacho),
            "pulses": np.array(self.pulses),
            "free": np.array(self.free),
        }

    @staticmethod
    def restored(state: dict, table) -> History:
        """The history :meth:`state` saved, for the gearbox of order table *table*."""
        args = json.loads(str(state["args"]))
        lay = layout(table, **args)
        if lay.orders.size != state["power"].size:
            raise GearlabInputError(
                f"a saved localisation history holds {state['power'].size} orders, the gearbox's layout "
                f"{lay.orders.size}: saved for another gearbox description, or by a gearlab of another layout rule"
            )
        excess = state["excess"] if "excess" in state else np.zeros(0)  # saved before: the noise model alone
        periods = float(state["periods"]) if "periods" in state else 0.0  # saved before: the take's level not read
        arrays = (state[k] for k in ("power", "line", "between", "unit_noise"))
        sp = Spread(*arrays, int(state["units"]), excess, periods)
        # a history saved before takes were turned to a mark (no "marks"): one mark, nothing turned
        marks = int(state["marks"]) if "marks" in state else 1
        reference = state["reference"] if marks > 1 else None
        block = int(state["block"]) if "block" in state else None  # saved before blocks: the whole record
        tacho = (str(state["tacho"]), int(state["pulses"])) if "tacho" in state else ("", 1)  # saved before: not said
        kept = (state["thresholds"], state["left_out_z"], str(state["note"]), args, marks, reference, block or None)
        return History(lay, sp, *kept, *tacho, bool(state["free"]) if "free" in state else False)


def _units(revs: np.ndarray, first: int, lay: Layout, block: int) -> list[Content]:
    """*revs* as consecutive units of *block* revolutions (the whole record when shorter)."""
    if revs.shape[0] < block:
        return [content(revs, lay, first)]
    return [content(revs[i : i + block], lay, first + i) for i in range(0, revs.shape[0] - block + 1, block)]


def _mark(hist: History, shaft: str, m: int) -> tuple[Fraction | None, bool, bool, int]:
    """tooth_index's (turn, tacho, free, pulses) for *shaft* of a take advanced *m*/marks: the tacho's own shaft
    counts its teeth from the mark (at N marks a turn, not the input, up to steps of z / N)."""
    # the tacho's own shaft at N marks a turn too (not the input): its turn added back, its tooth then known up to
    # steps of z / N (a 4-mark tacho on a 25/52 + 16/81 box's intermediate shaft: a 52T crack read 3.55 and 30.55
    # pitches from the mark in two takes, said 'not fixed across takes'; turned back, 3.55 and 42.55: 13-tooth steps)
    own = shaft == hist.tacho
    pulses = hist.pulses if own and shaft != hist.layout.shafts[0] else 1
    return (Fraction(m, hist.marks) if own else None), bool(hist.tacho), hist.free, pulses


def history(
    records: list[np.ndarray],
    table,
    *,
    first_revolutions: list[int] | None = None,
    false_alarm: float = FALSE_ALARM,
    revolutions: int | None = None,
    marks: int = 1,
    tacho: str = "",
    pulses: int = 1,
    free: bool = False,
    **options,
) -> History:
    """Read a healthy history: *records* of consecutive input revolutions (R_i, points) of one gearbox.

    Units: blocks of the shortest record's length, or of half of it when the history holds fewer
    than 4 records (two units at least are needed for a spread), a whole number of grand periods in
    grand mode; every record gives as many as it holds. Thresholds: per shaft, the largest z of a history record
    against the units of the others (left out in turn), and at least the Gaussian quantile at
    *false_alarm* / the number of shafts. *revolutions* (default: the shortest record) fixes the
    layout's mode; *options* go to :func:`layout`. *marks*: the tacho's marks per turn, each record
    turned to the first's mark (:func:`turned`); *tacho*: the shaft the tacho reads ("": none), *pulses* its marks
    per turn; *free*: no tacho, each record's zero its first sample (no tooth is fixed across takes)."""
    if not records:
        raise GearlabInputError("no history record to localise against; expected healthy records of the same gearbox")
    revs = [check_array(r, f"history record {i}", min_ndim=2) for i, r in enumerate(records)]
    marks = check_int(marks, "tacho marks per turn", minimum=1)
    reference = revs[0].mean(axis=0) if marks > 1 else None
    revs = [turned(r, reference, marks)[1] for r in revs]
    firsts = first_revolutions or [0] * len(revs)
    shortest = min(r.shape[0] for r in revs)
    args = {"points": int(revs[0].shape[1]), "revolutions": int(revolutions or shortest), **options}
    lay = layout(table, **args)
    step = lay.period if lay.mode == "grand" else 1
    block = (shortest // (1 if len(revs) >= 4 else 2)) // step * step
    block = block if block >= 2 * step else shortest
    # the record read in blocks where other shafts' lines leak by the length (shafts mode; Evidence)
    read = block if lay.mode == "shafts" else None
    units = [_units(r, f, lay, block) for r, f in zip(revs, firsts)]
    flat = [u for us in units for u in us]
    ref = spread(flat, ~lay.carrier)
    floor = threshold_floor(len(lay.shafts), false_alarm)
    loo = []
    for i, r in enumerate(revs):
        rest = [u for j, us in enumerate(units) if j != i for u in us]
        if len(rest) < 2:
            continue
        # content(r, lay, firsts[i], read) without the whole record's mean: its blocks are its units, read above
        rec = in_blocks(units[i]) if read and r.shape[0] > read else content(r, lay, firsts[i])
        level, sd = shaft_levels(rec, spread(rest, ~lay.carrier), lay)
        loo.append(level / sd)
    loo = np.array(loo).reshape(-1, len(lay.shafts))
    thr = np.maximum(floor, np.nanmax(loo, axis=0)) if loo.size else np.full(len(lay.shafts), floor)
    note = (
        f"{len(revs)} history record(s) in {len(flat)} units; thresholds: the largest left-out z, at least "
        f"{floor:.2f} (false alarm {false_alarm:g} shared by {len(lay.shafts)} shafts)"
    )
    return History(lay, ref, np.asarray(thr, float), loo, note, args, marks, reference, read, tacho, pulses, free)


def localise(revolutions: np.ndarray, hist: History, table, first_revolution: int = 0, templates=None) -> Localisation:
    """Rank the shafts of *table* by the localised change *revolutions* carry against *hist*. *templates*:
    a function of the layout giving each two-gear shaft's simulated events (signals.which_template);
    None: the gear is named by the event's width."""
    lay = hist.layout
    m, revolutions = turned(check_array(revolutions, "revolutions", min_ndim=2), hist.reference, hist.marks)
    rec = content(revolutions, lay, first_revolution, hist.block)
    level, sd = shaft_levels(rec, hist.spread, lay)
    z = level / sd
    gears = gears_of(table)
    excl = lay.sync & ((lay.sync.sum(axis=1) == 1) & ~lay.carrier)[:, None]
    # a shaft's own orders, for its gear: those no faster shaft shares (the exclusive ones, and those
    # shared with a slower shaft alone: 22/36 + 21/63 leaves the intermediate shaft no exclusive order)
    faster = np.array([[b > a for b in lay.shaft_orders] for a in lay.shaft_orders])
    own = lay.sync & ~lay.carrier[:, None] & ~np.stack([(lay.sync & f).any(axis=1) for f in faster], axis=1)
    out = []
    for s, name in enumerate(lay.shafts):
        zs = float(z[s]) if np.isfinite(z[s]) else -math.inf
        flagged = zs > hist.thresholds[s]
        on = gears[name]
        harmonics = _harmonics(lay, s, own[:, s])
        which, dens = None, {}
        if len(on) == 2 and flagged:
            phases = mesh_phases(rec, hist.spread, lay, s, harmonics, on)
            both = two_harmonic_phases(rec, hist.spread, lay, s, harmonics, on)
            which, dens = which_by_width(rec, hist.spread, harmonics, on, zs, phases, both)
        if len(on) == 2 and flagged and templates is not None:  # simulate and compare, unless the structure differs
            oz = order_z(rec, hist.spread, lay)  # the record's own sidebands: their comb, their contrast
            sidebands = mesh_combs(oz, harmonics, on), mesh_contrasts(oz, harmonics, on)
            by, fits = which_by_template(rec, hist.spread, lay, harmonics, on, templates(lay), *sidebands)
            which, dens = (which, {**dens, **fits}) if by is False else (by, {**dens, "undecided": "", **fits})
            dens["rule"] = dens.get("rule", RULE_WIDTH) if by is False else fits.get("rule", RULE_SIMULATED)
        elif dens:  # the width's evidence, or the mesh phase's where it named the gear
            dens.setdefault("rule", RULE_WIDTH)
        on = on if which is not None else favoured_first(on, dens)  # both named: the likelier first, where known
        out.append(
            ShaftEvidence(
                name,
                tuple(g.name for g in on),
                float(level[s]),
                float(sd[s]),
                zs,
                float(hist.thresholds[s]),
                int(excl[:, s].sum()),
                bool(flagged),
                shaft_label(name, on) if which is None else which.name,
                None if which is None else which.name,
                dens,
                tooth_index(rec, hist.spread, lay, s, on, *_mark(hist, name, m)) if flagged else {},
            )
        )
    ranking = tuple(sorted(out, key=lambda e: -e.z))
    top = next((e for e in ranking if e.flagged), None)
    method = lay.note + "; " + hist.note
    if hist.marks > 1:  # turned's m: the record cut again m/marks of an input turn later
        cut = f"were cut {m}/{hist.marks} of a turn later to line up with" if m else "already line up with"
        method += (
            f"; teeth counted from the first history record's tacho mark (the mark falls at any of {hist.marks} "
            f"points of an input turn: this record's input revolutions {cut} that record's)"
        )
    return Localisation(method, ranking, None if top is None else top.gear, None if top is None else top.shaft)
