"""Which gear, in the envelope: a tooth strike whose ring's carrier phase wanders from turn to turn.

A damaged tooth may strike once per turn of its shaft and ring a structural resonance: a ring at a fixed frequency
in Hz, while the speed wanders a little and the strike's instant jitters by a fraction of a ring period from turn
to turn. The ring's carrier phase against the shaft's angle then wanders, and every shaft's time-synchronous average
cancels it (signals.localise reads nothing); the non-synchronous check (signals.nonsync) leaves out the envelope's
lines at the shafts' orders, since synchronous lines belong to the shafts. The ring's *envelope* keeps the strike:
its squared magnitude does not depend on the carrier's phase, and the strike comes back at one angle of its shaft
every turn.

So the record less every shaft's synchronous average (signals.nonsync.residual) is turned into its squared envelope
(|analytic signal|², over its mean: a level in units of the residual's own power), read at POINTS a revolution, and
that envelope is localised as a record is (signals.localise): each shaft's synchronous average of it at the orders
ORDERS, each order's excess over the healthy history's in sds of its null spread (signals.evidence), the shafts'
levels by least squares over the order classes in bands of BAND orders, each shaft's threshold the history's own
(the largest left-out z, at least the Gaussian quantile at the false-alarm rate shared among the shafts). A shaft
flagged so is named with its gear where it carries one; a shaft of two gears is named as the shaft (the envelope's
width follows the ring's decay, not the tooth's pitch: signals.which_template's rules do not apply). The tooth is
the envelope peak's angle on the shaft (signals.localise.tooth_index), later than the strike by the ring's decay.

The band. A weak ring lies in a few orders about its resonance (its half-power width twice the damping ratio times
its frequency), under a residual of every order the record holds: over the whole residual the noise's envelope buries
it. The envelope is demodulated in one band of a fixed set (bands(): the whole residual and the levels of a binary
tree over the orders the history holds, each level's bands overlapping by half), the one where the take is most
impulsive beyond its history: the band's spectral kurtosis (the kurtogram's, Antoni 2006-2007: of the band's complex
envelope c, mean |c|⁴ / (mean |c|²)² − 2, nil for Gaussian noise, positive for transients) less the history takes'
largest in it. The band is chosen from the take and the history alone, and the history's envelopes are read in
every band (Bank: one signals.localise history each), so the take's z is against its band's history, like for like.
Its threshold is not its band's alone: the band is the one of many where the take is most impulsive, and a healthy
take's z there is larger than one band's left-out takes read (a three-stage healthy take: 4.54 in its band, whose
threshold was the Gaussian floor 4.06; the history takes, each choosing its band so, read at most 2.8 there, and at
most 5.19 over every band). A shaft over its band's threshold is read against Bank.thresholds(): the largest over
every band, a bound on the z of whichever band a healthy take chooses, and at least the Gaussian floor at the
false-alarm rate shared among the bands too (the union bound: a few history takes' largest left-out z missed a
healthy take's 4.46 over 4.06, development seed 349; 4.92 with 4 shafts and 57 bands, 4.78 with 2).
A take's kurtosis is read in every band, each band's squared envelope at the fewest points that hold it whole (its
mean and its square's are there what they are at POINTS a turn, to round-off), its envelope in its band alone; a
band's history is read on its first use (a take's band; every band where a take passes its band's threshold, or the
history is saved for `gearlab score`).

The record's ends. nonsync.residual removes each shaft order's bins; a line between bins (a record that is no whole
number of turns of a shaft: a take of another length than the history's) leaves its Gibbs remainder near the record's
ends, at the line's level (the load's) and as large as where between the bins it falls (the length's), not the
gearbox's health: its squared envelope beats at the shafts' orders, locked to the tacho mark, and the band's spectral
kurtosis reads it as impulsive. So the strong lines are fitted out at their exact orders first
(less_lines_between_bins), and the envelope is read away from the ends (sound(): a turn of the slowest shaft left out
at either end of the residual's first piece, where the bins removed are not exact), the kurtosis over the whole
record (the band's choice: those ends are what the fit leaves weakest). A healthy 3.0 s take of a 23/71 + 29/83 box
against 4.0 s history takes named the 83T gear at z 10.6 over 10.1 (tests/test_envelope_offspeed.py); the ends left
out alone cleared it but a take at 1.4 times the history's level was named (z 12.5 over 8.8: a faster shaft's lines
leave theirs farther in); the fit alone cleared both but left the history's own z up to 13.7 in some bands, and on a
three-stage box a run-down take named the 107T gear (z 28.1 over 27.6); both: that box's run-down, 1.4x-load and
healthy takes name nothing, the two-stage box's largest z 0.9 over 4.0.

data.which_gear reads it where the synchronous averages name nothing (and read no other shaft near its threshold:
elsewhere): a synchronous fault is named as before.

Everything is numpy: no torch, nothing from the layers above.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import threading
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from ..errors import GearlabInputError
from . import localise as L
from . import nonsync as NS
from .fft import fft, ifft, rfft

POINTS = 256  # envelope samples per input revolution (orders up to 128: past ORDERS)
ORDERS = (0.5, 24.0)  # input orders of the envelope read: a strike's envelope lies at its shaft's first orders
BAND = 6.0  # input orders per band of the least squares over the order classes
# The thresholds' Gaussian floor, shared among the shafts: a second search, read where the averages named nothing,
# so a healthy take must hardly ever pass it. Healthy takes of the localisation benchmark's boxes read the envelope's
# shafts at z 0.02 +- 0.94, the largest of 128 takes 3.08, 3 over the averages' floor at 0.01 (2.71; dev seed 53);
# at that floor the benchmark named one of 40 healthy takes and one fault on another shaft (dev seed 52); a strike the
# averages cancel reads z 17-370 at 0.5-1 of the mesh amplitude (tests/jittered_strikes.py)
FALSE_ALARM = 1e-4
# A synchronous change under its threshold leaks into the envelope, and there may read on another shaft (a random
# train's output-gear chip, its average at z 2.4 of 2.71, put the intermediate shaft's envelope at 4.34 over 3.99, dev
# seed 54): the envelope names no shaft where another shaft's average reads over this share of its threshold (at 0.5
# a healthy shaft's average passes it about one take in ten: the jittered 39/61 strikes of tests/jittered_strikes.py
# named 14 -> 10 of 20 at 0.3 of the mesh amplitude; at 0.8 none lost, dev seed 55)
OTHER_SHARE = 0.8
LEVELS = 4  # levels of the binary tree of demodulation bands (bands())
SELECTED = "the envelope's thresholds the largest over every band, the floor's false alarm shared by the bands too"
# The meshes' lines fitted out at their exact orders (less_lines_between_bins): those whose bin holds over STRONG of the
# record's power (a line's remainder past the bins removed is about 2 % of its power: under 2e-5 of the record's, under
# a 25 dB noise's 3e-3), each harmonic with SIDEBANDS of each of its shafts' orders on either side
STRONG, SIDEBANDS = 1e-3, 2
SEEN = "seen in the envelope of the record less every shaft's synchronous average"


def bands(top: float) -> np.ndarray:
    """The candidate demodulation bands (n, 2), input orders [lo, hi): row 0 the whole residual, then each level
    k = 1 .. LEVELS of the binary tree over orders 0 .. *top* (the highest every history take holds), bands top / 2^k
    wide, each level's bands overlapping by half (a resonance on one band's edge lies inside another's)."""
    out = [(0.0, np.inf)]
    for k in range(1, LEVELS + 1):
        width = top / 2**k
        out += [(j * width / 2, j * width / 2 + width) for j in range(2 ** (k + 1) - 1)]
    return np.asarray(out)


def less_lines_between_bins(revolutions: np.ndarray, table) -> np.ndarray:
    """*revolutions* (R, points) less the shafts' and meshes' strong lines (each mesh harmonic, SIDEBANDS of its
    shafts' orders beside it and the shafts' own), each fitted at its exact order by least squares: a line between the
    bins of the record (or of nonsync.residual's pieces) is an exact sinusoid in angle, so it goes whole; removing
    its bins alone leaves its Gibbs remainder at the record's ends, which depends on where between the bins it lies
    (the take's length: a run-down's, a slower take's) and on its level (the load's), not on the gearbox's health,
    and its envelope beats at the shafts' orders (a 22/71 + 27/86 + 34/107 box's output run-out, 17.56 turns in
    its 568-turn piece, put 20-30 times the residual's power into the first output turn). A line is strong where
    its bin holds over STRONG of the record's power.

    A line at order o over the revolutions' turns i and shares j / points of a turn is the outer product of
    u = exp(2πi o i) and v = exp(2πi o j / points): its least squares reads the record through two products of the
    (R, points) record with v's parts and its 2 x 2 normal matrix from sums over u and v alone (|z|² and z² of an
    outer product are their sums' products), and it leaves as two outer products; the lines go one after another, as
    each is fitted on the record the earlier ones left (89 revolutions of 4096 points, 10 lines: 0.05 s of CPU, where
    each line's full-length product took 0.6 s)."""
    revs = np.asarray(revolutions, dtype=np.float64)
    count, points = revs.shape
    y = revs - revs.mean()
    power = np.abs(np.fft.rfft(y.reshape(-1))) ** 2
    floor = STRONG * power.sum()
    turns, within = np.arange(count), np.arange(points) / points  # the angle in turns: a turn and a share of one
    stages = [(s.mesh, s.pinion_shaft_order, s.wheel_shaft_order) for s in table.stages]
    orders = np.concatenate([_line_orders(*stage, points) for stage in stages])
    at = orders * count  # each line's place in bins; a line on a bin goes whole too
    inside = (orders > 0) & (at < power.size - 1)
    inside[inside] = ~(power[np.round(at[inside]).astype(int)] < floor)
    for o in orders[inside]:
        u, v = np.exp(2j * np.pi * o * turns), np.exp(2j * np.pi * o * within)
        # the line's cosine and sine against the record, c·y + i s·y (einsum: no BLAS threads spun for a product of a
        # few ms, which on a busy machine took 16 ms of CPU for 0.35)
        yv = np.einsum("ij,kj->ik", y, np.stack([v.real, v.imag]))
        t = u @ (yv[:, 0] + 1j * yv[:, 1])
        # c·c + s·s and c·c - s·s + 2i c·s: the sums of |z|² and z² of the outer product
        whole, sq = np.sum(np.abs(u) ** 2) * np.sum(np.abs(v) ** 2), np.sum(u * u) * np.sum(v * v)
        gram = np.array([[whole + sq.real, sq.imag], [sq.imag, whole - sq.real]]) / 2
        a, b = np.linalg.solve(gram, np.array([t.real, t.imag]))
        wu = (a - 1j * b) * u  # a c + b s: the real part of (a - ib) z
        y -= np.outer(wu.real, v.real)
        y += np.outer(wu.imag, v.imag)
    return y


@functools.lru_cache(maxsize=32)
def _line_orders(mesh, pinion, wheel, points: int) -> np.ndarray:
    """The input orders of a stage's lines less_lines_between_bins fits, in its order: each mesh harmonic h (0: the
    shafts' own lines) with SIDEBANDS of its shafts' orders *pinion*, *wheel* beside it, up to half of *points* (exact
    fractions: a line two shafts share is fitted once); the same for every take of a gearbox read at one length."""
    shafts = (pinion, wheel)
    found = []
    for h in range(int(points / 2 / mesh) + 1):
        found += [float(o) for o in {h * mesh + j * s for s in shafts for j in range(-SIDEBANDS, SIDEBANDS + 1)}]
    return np.array(found)


def sound(revolutions: int, table) -> tuple[int, int]:
    """The input revolutions [a, b) of a record of *revolutions* whose residual (nonsync.residual) the envelope reads:
    all of it where cut to whole grand periods (each shaft's bins removed exactly); else the first piece less one turn
    of the slowest shaft at either end (module doc, "The record's ends")."""
    whole = NS.read_turns(revolutions, table)
    if revolutions >= NS.GRAND * table.train_period:
        return 0, whole
    end = math.ceil(1 / min(float(o) for o in table.shaft_orders) - 1e-9)
    if whole - 2 * end < end:  # fewer turns of the slowest shaft than it leaves out
        raise GearlabInputError(
            f"envelope: {revolutions} input revolutions hold {whole / end:.3g} turns of the slowest shaft; expected "
            "at least 3 (one left out at either end)"
        )
    return end, whole - end


def _spectrum(revolutions: np.ndarray, table) -> tuple[np.ndarray, int, int, tuple[int, int]]:
    """(the full spectrum of the record *revolutions* less every shaft's synchronous average, its revolutions, the
    points of each, the revolutions [a, b) its envelope is read in: sound())."""
    revs = less_lines_between_bins(np.asarray(revolutions, dtype=np.float64), table)
    r = NS.residual(revs, table)
    if not np.any(r):
        raise GearlabInputError("envelope: no residual left (the record is constant); expected a signal")
    return fft(r), r.size // revs.shape[1], revs.shape[1], sound(revs.shape[0], table)


def _bins(n: int, count: int, band) -> tuple[int, int, bool]:
    """(first, stop, wide) of *band* (input orders [lo, hi)) in a spectrum of n bins and *count* revolutions: its bins
    first … stop - 1, none at 0 nor past the half; wide: demodulated at the whole record's length (_band)."""
    lo, hi = band
    first = max(math.ceil(lo * count), 1)
    stop = min(math.ceil(hi * count) if np.isfinite(hi) else n, math.ceil(n / 2))
    return first, max(stop, first), not hi - lo < POINTS / 2


def _band(X: np.ndarray, count: int, points: int, kept: tuple[int, int], band) -> tuple[np.ndarray, float]:
    """(the squared envelope (b - a, POINTS) over its mean of the residual of spectrum *X* in *band* (input orders
    [lo, hi); hi past the spectrum's half: the whole residual), in the revolutions *kept* [a, b) alone, its spectral
    kurtosis there (_kurtosis))."""
    e, wide, kurt = _squared(X, count, points, kept, band)
    a, b = kept
    if not wide:
        return (e / e.mean()).reshape(b - a, POINTS), kurt
    E = rfft(e / e.mean())[: (b - a) * POINTS // 2 + 1]  # low-passed to POINTS / 2 orders
    return np.fft.irfft(E, n=(b - a) * POINTS).reshape(b - a, POINTS) * (POINTS / points), kurt


def _squared(X: np.ndarray, count: int, points: int, kept: tuple[int, int], band) -> tuple[np.ndarray, bool, float]:
    """_band's squared envelope in the revolutions *kept*, not yet over its mean nor low-passed, whether the band is
    wide (read at *points* a turn, to be low-passed; else shifted down, at POINTS), its spectral kurtosis over the
    whole record: all that _kurtosis reads of a band it cannot read in its own transforms (the whole residual: half
    the cost of its _band, whose low-pass is two more transforms of the record's length)."""
    lo, hi = band
    n = X.size
    a, b = kept
    first, stop, wide = _bins(n, count, band)
    if not wide:  # the band shifted down to orders 0 .. hi - lo: its envelope is whole at POINTS a turn
        H = np.zeros(count * POINTS, dtype=complex)
        H[: stop - first] = X[first:stop]
        e, step = np.abs(ifft(H)) ** 2, POINTS
    else:
        h = np.zeros(n)
        h[first:stop] = 2.0
        h[0] = 1.0 if lo <= 0 else 0.0
        if n % 2 == 0 and hi * count > n / 2:
            h[n // 2] = 1.0
        e, step = np.abs(ifft(X * h)) ** 2, points
    kurt = _normalised(np.mean(e**2) / e.mean() ** 2 - 2, X[first:stop]) if e.mean() > 0 else np.nan
    e = e[a * step : b * step]  # the envelope is read in the kept revolutions, the kurtosis over the whole record
    if not e.mean() > 0:
        raise GearlabInputError(f"envelope: no residual in input orders {lo:g}-{hi:g}; expected a signal")
    return e, wide, kurt


def _normalised(kurt: float, bins: np.ndarray) -> float:
    """The spectral kurtosis *kurt* of a band of spectrum *bins* in sds of its estimate on Gaussian noise: 2 / √N over
    the band's N independent bins, 2 (Σ P)² / Σ P² of its bins' powers P (a periodogram's P spread as an
    exponential's: N where the band is flat, fewer where its power lies in a few bins)."""
    p = np.abs(bins) ** 2
    return float(kurt * np.sqrt(2 * p.sum() ** 2 / (p**2).sum()) / 2)


def _kurtosis(
    X: np.ndarray, count: int, points: int, kept: tuple[int, int], candidates: np.ndarray, read: Mapping | None = None
) -> np.ndarray:
    """_band's spectral kurtosis of the residual of spectrum *X* in each band of *candidates*, its squared envelope
    read at the fewest points that hold it whole (twice the band's bins: the mean of the envelope and of its square
    are there what they are at POINTS a turn, or at the record's length, to round-off), the bands of one length in one
    transform: a take reads its kurtosis in every band, its envelope in one. *read*: {candidate index: its kurtosis}
    of the bands the caller read with _band already (history(): the whole residual's, whose envelope it reads)."""
    from scipy.fft import next_fast_len

    n = X.size
    out = np.empty(len(candidates))
    rows: dict[int, list] = {}
    for i, band in enumerate(candidates):
        if read and i in read:
            out[i] = read[i]
            continue
        first, stop, wide = _bins(n, count, band)
        lo, hi = band
        if wide and n % 2 == 0 and hi * count > n / 2:  # the half's bin in it (the whole residual): as _band
            out[i] = _squared(X, count, points, kept, band)[2]
            continue
        # a wide band from order 0 holds the DC at half the weight of its other bins (_band's analytic signal)
        held = np.concatenate([X[:1], 2 * X[first:stop]]) if wide and lo <= 0 else X[first:stop]
        rows.setdefault(next_fast_len(2 * held.size, real=False), []).append((i, first, stop, held))
    for size, group in rows.items():
        H = np.zeros((len(group), size), dtype=complex)
        for r, (_, _, _, held) in enumerate(group):
            H[r, : held.size] = held
        e = np.abs(np.fft.ifft(H, axis=-1)) ** 2
        mean = e.mean(axis=-1)
        for r, (i, first, stop, _) in enumerate(group):
            if not mean[r] > 0:
                lo, hi = candidates[i]
                raise GearlabInputError(f"envelope: no residual in input orders {lo:g}-{hi:g}; expected a signal")
            out[i] = _normalised(np.mean(e[r] ** 2) / mean[r] ** 2 - 2, X[first:stop])
    return out


def envelope(revolutions: np.ndarray, table, band=(0.0, np.inf)) -> np.ndarray:
    """The squared envelope (b - a, POINTS) over its mean of the record *revolutions* (R, points: consecutive input
    revolutions) less every shaft's synchronous average (nonsync.residual), in its revolutions [a, b) (sound(R): its
    first revolution is the record's plus a), in *band* (input orders [lo, hi); default: the whole residual)."""
    return _band(*_spectrum(revolutions, table), band)[0]


def kurtosis(revolutions: np.ndarray, table, candidates: np.ndarray) -> np.ndarray:
    """The spectral kurtosis of the residual of *revolutions* in each band of *candidates* (bands())."""
    return _kurtosis(*_spectrum(revolutions, table), candidates)


class Histories(Sequence):
    """A bank's band histories, each read on its first use (*read*: the histories of a list of band indices): a take
    is read in one band, and a history read for `gearlab score` (state()) in all of them. Until then *read* holds what
    they are read from (history(): the history takes' residual spectra, as long as the takes)."""

    def __init__(self, count: int, read: Callable[[list[int]], list[L.History]]):
        self._count, self._read, self._kept, self._lock = count, read, {}, threading.Lock()

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, i):
        wanted = range(self._count)[i]
        with self._lock:
            missing = [j for j in (wanted if isinstance(i, slice) else [wanted]) if j not in self._kept]
            if missing:
                self._kept.update(zip(missing, self._read(missing)))
                if len(self._kept) == self._count:  # every band read: what they were read from is let go
                    self._read = None
            return tuple(self._kept[j] for j in wanted) if isinstance(i, slice) else self._kept[wanted]

    def read_now(self) -> dict[int, L.History]:
        """{band index: its history} of the bands read so far."""
        with self._lock:
            return dict(self._kept)


@dataclasses.dataclass(frozen=True)
class Bank:
    """The healthy history's envelopes in each candidate band (bands(): *candidates*), *histories* one per band (a
    sequence: Histories reads each on first use), and *kurtosis*: the history takes' mean spectral kurtosis in each
    (in sds of its estimate on noise: _band)."""

    candidates: np.ndarray
    histories: Sequence[L.History]
    kurtosis: np.ndarray

    @property
    def layout(self) -> L.Layout:
        """The envelope's layout: every band's history is laid out alike (the whole residual's, read at once)."""
        return self.histories[0].layout

    def chosen(self, kurt: np.ndarray) -> int:
        """The band a take of spectral kurtosis *kurt* (one per band, as *kurtosis*) is read in: where it exceeds the
        history's most."""
        return int(np.argmax(np.asarray(kurt) - self.kurtosis))

    def thresholds(self) -> np.ndarray:
        """Each shaft's threshold for a take read in its chosen band: the largest of every band's (each the largest
        left-out z of a history take in that band), at least the Gaussian floor at the false-alarm rate shared among
        the shafts and the bands. A take's band is the one of many where it is most impulsive, and a healthy take's
        z there is no draw from one band's null: the largest over every band bounds it whatever band a take chooses
        (module doc). Reads every band's history."""
        every = np.max([h.thresholds for h in self.histories[:]], axis=0)
        return np.maximum(every, L.threshold_floor(every.size, FALSE_ALARM / len(self.candidates)))


def history(records: list[np.ndarray], table, top: float | None = None, **options) -> Bank:
    """The healthy history of the records' envelopes in each candidate band (bands(*top*); default: 0.45 of the
    points a revolution), each band's as signals.localise.history reads it at ORDERS, on its first use (the whole
    residual's now: what cannot be read so says so here); *options*: its first revolutions, marks, tacho, pulses,
    free."""
    lo, hi = ORDERS
    candidates = bands(0.45 * np.shape(records[0])[-1] if top is None else top)
    specs = [_spectrum(r, table) for r in records]
    # the whole residual's envelope, read below (hists[0]) and its kurtosis with it: each record's envelope once
    whole = [_band(*s, candidates[0]) for s in specs]
    kurt = np.mean([_kurtosis(*s, candidates, {0: w[1]}) for s, w in zip(specs, whole)], axis=0)
    firsts = options.pop("first_revolutions", None) or [0] * len(records)
    options["first_revolutions"] = [f + s[3][0] for f, s in zip(firsts, specs)]  # each envelope's first revolution

    def read(indices: list[int]) -> list[L.History]:
        return [
            L.history(
                [w[0] if i == 0 else _band(*s, candidates[i])[0] for s, w in zip(specs, whole)],
                table,
                min_order=lo,
                max_order=hi,
                band=BAND,
                false_alarm=FALSE_ALARM,
                **options,
            )
            for i in indices
        ]

    hists = Histories(len(candidates), read)
    hists[0]  # noqa: B018 (read now: a record too short for it, or a layout of no band, raises here)
    return Bank(candidates, hists, kurt)


def localise(revolutions: np.ndarray, bank: Bank, table, first_revolution: int = 0) -> L.Localisation:
    """The envelope of *revolutions* in the band bank.chosen() localised against that band's history (history()): a
    shaft of two gears named as the shaft."""
    spec = _spectrum(revolutions, table)
    kurt = _kurtosis(*spec, bank.candidates)
    i = bank.chosen(kurt)
    env, hist = _band(*spec, bank.candidates[i])[0], bank.histories[i]
    first_revolution += spec[3][0]  # the envelope's first revolution (sound())
    found = L.localise(env, hist, table, first_revolution)
    if any(e.flagged for e in found.ranking):  # over its band's own threshold: read against the selection's (Bank)
        honest = np.maximum(hist.thresholds, bank.thresholds())
        note = f"{hist.note}; {SELECTED}"
        found = L.localise(env, dataclasses.replace(hist, thresholds=honest, note=note), table, first_revolution)
    gears = L.gears_of(table)
    ranking = tuple(
        e if len(e.gears) == 1 else dataclasses.replace(e, gear=L.shaft_label(e.shaft, gears[e.shaft]), which=None)
        for e in found.ranking
    )
    ranking = tuple(dataclasses.replace(e, stage_evidence={}) for e in ranking)
    top = next((e for e in ranking if e.flagged), None)
    named, shaft = (None, None) if top is None else (top.gear, top.shaft)
    lo, hi = bank.candidates[i]
    where = "the whole residual" if i == 0 else f"input orders {lo:.4g}-{hi:.4g}"
    band = f"demodulated in {where} (spectral kurtosis {kurt[i]:.3g} sd, the history's {bank.kurtosis[i]:.3g})"
    return L.Localisation(f"{SEEN}, {band}: {found.method}", ranking, named, shaft)


def elsewhere(synchronous: L.Localisation, shaft: str) -> bool:
    """The synchronous averages (*synchronous*, naming nothing) read another shaft than *shaft* over OTHER_SHARE of its
    threshold: the envelope's flag on *shaft* may be that change's leak, and names nothing."""
    return any(e.shaft != shaft and e.z > OTHER_SHARE * e.threshold for e in synchronous.ranking)


def described(found: L.Localisation, synchronous: str) -> dict:
    """*found* (localise()) as data.which_gear returns a localisation, each shaft marked as read in the envelope (its
    call's words: which_template.IN_ENVELOPE), its summary saying so beside the synchronous averages' *synchronous*
    summary."""
    out = found.describe()
    out["shafts"] = [s | {"seen": "envelope"} for s in out["shafts"]]
    out["summary"] = f"{found.summary()}; {SEEN} (the synchronous averages: {synchronous})"
    return out | {"seen": "envelope"}


def _prefix(i: int) -> str:
    """The prefix of band *i*'s arrays in state(): the whole residual's 'envelope_', as a run saved before the bands
    were read holds it."""
    return f"envelope{i}_" if i else "envelope_"


def state(bank: Bank | None) -> dict:
    """The arrays (History.state) to save the envelope's bank *bank* with: the whole residual's history prefixed
    'envelope_' (as a run saved before the bands were read holds it), band i's 'envelope{i}_'; {} for None."""
    if bank is None:
        return {}
    out = {"envelope_bands": bank.candidates, "envelope_kurtosis": bank.kurtosis}
    for i, h in enumerate(bank.histories[:]):  # every band's: those not read yet are read now
        out |= {_prefix(i) + k: v for k, v in h.state().items()}
    return out


def read_state(bank: Bank | None) -> dict:
    """state() of the bands *bank* has read so far alone ('envelope_read': their indices), for a history kept between
    calls (data.which_gear_cache): reading every band for it would cost a first call more than the cache saves."""
    if bank is None:
        return {}
    kept = bank.histories.read_now() if isinstance(bank.histories, Histories) else dict(enumerate(bank.histories))
    out = {
        "envelope_bands": bank.candidates,
        "envelope_kurtosis": bank.kurtosis,
        "envelope_read": np.array(sorted(kept)),
    }
    for i, h in kept.items():
        out |= {_prefix(i) + k: v for k, v in h.state().items()}
    return out


def _saved_band(arrays: Mapping, prefix: str) -> dict:
    """The arrays saved under *prefix*, without it: only those read (a run's saved arrays are read as used)."""
    return {k.removeprefix(prefix): arrays[k] for k in arrays if k.startswith(prefix)}


def restored_read(arrays: dict, table, rest: Callable[[], Bank]) -> Bank | None:
    """The bank read_state() saved in *arrays* (None where none was): its saved bands restored, any other read from
    rest()'s bank (the history's takes read again) on its first use."""
    if "envelope_read" not in arrays:
        return None
    saved = {int(i) for i in np.asarray(arrays["envelope_read"])}

    def read(indices: list[int]) -> list[L.History]:
        return [
            L.History.restored(
                {k.removeprefix(_prefix(i)): v for k, v in arrays.items() if k.startswith(_prefix(i))}, table
            )
            if i in saved
            else rest().histories[i]
            for i in indices
        ]

    candidates = np.asarray(arrays["envelope_bands"], dtype=np.float64)
    return Bank(candidates, Histories(len(candidates), read), np.asarray(arrays["envelope_kurtosis"], dtype=np.float64))


def restored(arrays: dict, table) -> Bank | None:
    """The envelope's bank state() saved in *arrays*; None where none was (a run stored before it was read); the
    whole residual's alone where no band was (a run stored before the bands were read: read as it was then). Each
    band's history is remade on its first use (the whole residual's now: one saved for another gearbox says so)."""
    if not any(k.startswith("envelope_") for k in arrays):
        return None
    if "envelope_bands" not in arrays:
        return Bank(bands(0.0)[:1], (L.History.restored(_saved_band(arrays, "envelope_"), table),), np.zeros(1))
    candidates = np.asarray(arrays["envelope_bands"], dtype=np.float64)

    def read(indices: list[int]) -> list[L.History]:
        return [L.History.restored(_saved_band(arrays, _prefix(i)), table) for i in indices]

    hists = Histories(len(candidates), read)
    hists[0]  # noqa: B018 (remade now: a history saved for another gearbox says so here)
    return Bank(candidates, hists, np.asarray(arrays["envelope_kurtosis"], dtype=np.float64))
