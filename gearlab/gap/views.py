"""Feature views of angle-domain revolutions: where a gap between two sets of data can lie.

Every view turns a set of revolutions ``X`` (n, P) — one input-shaft revolution per row,
P samples per revolution, so that spectral line k is exactly shaft order k — into a
feature matrix (n, d) with one name per column (:class:`View`). The statistics of
:mod:`gearlab.gap.stats` compare the rows of a source and a target set view by view.

Order bands (:func:`order_views`, layout in :class:`BandPlan`), energies in dB of the
power in the band (10·log10 of the mean-square the band contributes, so that the powers of
all orders add up to the row's mean square):

* ``shaft``: shaft orders 1..S (S = 3, fewer when the pinion has few teeth);
* ``mesh``: each mesh harmonic k·Z1, k = 1..K, up to where the noise floor starts;
* ``sidebands``: k·Z1 ± m, m = 1..M (M = 3), one feature per (k, m), both sides summed —
  a modulation at shaft order m shows at ±m whatever its phase;
* ``non_synchronous``: everything between these families, one band per gap between
  consecutive mesh harmonics. With one revolution per row every line sits on an integer
  order, so "non-synchronous" here means *not at a shaft, mesh or sideband order*: a truly
  asynchronous tone (order q not an integer) leaks into the two nearest integer orders
  (81 % of its power at worst, half-way between) and is counted here;
* ``noise_floor``: the top of the order range (from 3/4 of the Nyquist order P/2, or above
  the last resolved mesh sideband if that is higher), in a few equal sub-bands. Mesh
  harmonics that high are counted in the floor: at 4096 points per revolution they lie
  far above any measured bandwidth.
* Output-shaft orders (multiples of Z1/Z2) are *not* resolved from single revolutions: a
  row spans 1 input revolution, i.e. Z1/Z2 of an output revolution, so its spectrum has a
  resolution of one input order and an output-shaft line leaks into the neighbouring
  integer orders (shaft and non-synchronous bands). When the rows are *consecutive*
  revolutions of one record, :func:`output_shaft_view` joins R = Z2/gcd(Z1, Z2) of them
  (a whole number of turns of both shafts), where every output order falls on a line.

TSA residual (:func:`tsa_residual_view`): each row minus a synchronous average (the set's
own, leave-one-out, or a given reference such as the source's TSA), with the DC and the
mesh harmonics removed, as energy (dB) per angular sector — Z1 sectors, one tooth pitch
each — so the report can say *where in the revolution* the target deviates.

Waveform statistics (:func:`waveform_view`): mean, RMS, peak-to-peak, crest factor,
skewness, kurtosis (Pearson's: 3 for Gaussian data) of each row.

Latent features (:func:`latent_views`): the feature extractor of a network trained on the
source, through any callable ``embed(X) -> (n, d)`` (:func:`network_embed` wraps a gearlab
network). Up to 64 units (the fast network's latent) are compared as they are; wider layers (cnn3 has ~30 000) are
projected on the leading principal components of both sets pooled, so that a direction in
which only the target varies is kept.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import GearlabInputError
from ..signals import order_spectrum
from ..signals.checks import check_array

# A band with no power at all (a noise-free synthetic line that is absent) reads -300 dB
# rather than -inf, so that differences and standard deviations stay finite.
POWER_FLOOR = 1e-30
# A TSA residual below this share of its row's mean square is floating-point rounding (a float32
# round trip leaves ~1e-14, float64 arithmetic ~1e-26): it reads as this floor (-200 dB re the row).
RESIDUAL_FLOOR = 1e-20


@dataclass(frozen=True)
class View:
    """A feature view of n rows: ``features`` (n, d) float64, one name per column."""

    name: str
    features: np.ndarray
    names: tuple[str, ...]
    unit: str = ""

    @property
    def size(self) -> int:
        return self.features.shape[1]


def _db(power: np.ndarray) -> np.ndarray:
    return 10.0 * np.log10(power + POWER_FLOOR)


# --- inputs ----------------------------------------------------------------------------------


def gear_ratio(pair) -> tuple[int, int]:
    """(Z1, Z2) of a gear pair given as a GearPair (anything with ``Z1`` and ``Z2``), a
    ``(Z1, Z2)`` pair of whole numbers, or the name of a gear-pair preset ("meng2020")."""
    if isinstance(pair, str):
        from ..physics.presets import gear_pair

        pair = gear_pair(pair)
    if hasattr(pair, "Z1") and hasattr(pair, "Z2"):
        teeth = (pair.Z1, pair.Z2)
    elif isinstance(pair, (tuple, list)) and len(pair) == 2:
        teeth = tuple(pair)
    else:
        raise GearlabInputError(f"gear pair must be a GearPair, a (Z1, Z2) pair or a preset name, got {pair!r}")
    for label, z in zip(("Z1", "Z2"), teeth):
        if isinstance(z, bool) or not isinstance(z, numbers.Integral) or z < 3:
            raise GearlabInputError(f"gear pair: {label} must be a whole number of teeth >= 3, got {z!r}")
    return int(teeth[0]), int(teeth[1])


def check_revolutions(X, name: str = "revolutions") -> np.ndarray:
    """*X* as a finite float64 (n, P) array: n revolutions of P angle samples."""
    arr = check_array(X, name)
    if arr.ndim != 2:
        raise GearlabInputError(f"{name} must be 2-D (revolutions x samples per revolution), got shape {arr.shape}")
    return arr


def without_line(X: np.ndarray, order: float) -> np.ndarray:
    """The rows less each one's least-squares sinusoid at shaft order *order* (its own amplitude and phase:
    a tone's phase differs from revolution to revolution); the rows as they are for order 0. The same two of
    a revolution's dimensions go from every set (gearlab.gap.lines: a tone's line taken out of what the other
    effects are scored on). Zeroing the orders its line stands out in left its leakage beyond them: a bearing
    and low-pass scored 14,141 there against the low-pass alone's 7,341 (with the tone: 1.8)."""
    if not order:
        return X
    turn = 2.0 * np.pi * order * np.arange(np.shape(X)[1]) / np.shape(X)[1]
    basis = np.stack([np.sin(turn), np.cos(turn)], axis=1)
    coef, *_ = np.linalg.lstsq(basis, np.asarray(X, dtype=np.float64).T, rcond=None)
    return X - (basis @ coef).T


def offset_removed(X, takes: tuple[int, ...] = ()) -> np.ndarray:
    """*X* (n, P) with each record's mean removed: *takes* counts the rows of each record laid end
    to end (gearlab.data.chain.Chain.takes; () or counts that do not add up to n: one record).

    An accelerometer measures no constant acceleration, so a record's mean is its electronics' (a
    DC-coupled sensor bias, an ADC offset), not vibration; a simulation has none. The diagnosis
    compares source and target rows each without it, so an offset makes no gap (its waveform view's
    mean, RMS and crest factor read it otherwise) and the simulated side, whose mean is ~0, stays."""
    X = check_revolutions(X)
    counts = list(takes) if len(takes) and sum(takes) == len(X) else [len(X)]
    out = X.copy()
    start = 0
    for count in counts:
        out[start : start + count] -= X[start : start + count].mean()
        start += count
    return out


def healthy_rows(dataset, physical: bool = True, name: str = "") -> np.ndarray:
    """The healthy rows (label 0) of a gearlab Dataset, float64 (n, P).

    *physical*: undo the dataset's standardisation (X · std + mean of its healthy
    reference, eq. 2.112) so that two domains are compared in the same units. Each domain
    is standardised against its *own* healthy reference; compared as standardised, a
    target with extra noise would show every clean synchronous band lowered by the rescale.
    """
    name = name or f"dataset '{getattr(dataset.spec, 'name', '?')}'"
    rows = np.asarray(dataset.X)[np.asarray(dataset.label) == 0].astype(np.float64)
    if len(rows) == 0:
        raise GearlabInputError(f"{name} has no healthy revolutions (label 0); the gap is measured on healthy data")
    if physical:
        mean, std = dataset.reference
        rows = rows * std + mean
    return rows


def gear_pair_of(spec):
    """The GearPair a DatasetSpec simulates (through its model plugin and preset)."""
    _, pair, _ = spec.check_model()
    return pair


# --- order bands -------------------------------------------------------------------------------


@dataclass(frozen=True)
class BandPlan:
    """Which shaft orders make up which order band, for P points per revolution and Z1/Z2 teeth.

    ``shaft_orders`` S, ``sidebands`` M and ``harmonics`` K are the effective values: M is
    at most (Z1 − 1)//2 so that the sidebands of neighbouring harmonics never share an
    order, and S < Z1 − M so the shaft orders stay below the first lower sideband.

    ``highest``: the highest order compared (0: the Nyquist order P/2). A measured record holds
    data only below its own Nyquist order (its passband, the gap's max_order); above it both sets
    are zero up to floating-point rounding (-290 dB), and bands there compared rounding with
    rounding: 1e-14 changes in the arithmetic moved a null target's gap from 1.4 to 2.5 and its
    p-value from 0.30 to 0.04. The plan then ends there: mesh harmonics and the noise floor are
    laid out below it.
    """

    points: int
    z1: int
    z2: int
    shaft_orders: int
    sidebands: int
    harmonics: int
    floor_start: int
    floor_bands: int
    highest: int = 0

    @classmethod
    def make(
        cls,
        points: int,
        pair,
        shaft_orders: int = 3,
        sidebands: int = 3,
        floor_fraction: float = 0.75,
        floor_bands: int = 4,
        highest: int = 0,
    ) -> BandPlan:
        z1, z2 = gear_ratio(pair)
        for label, value in (("shaft_orders", shaft_orders), ("sidebands", sidebands), ("floor_bands", floor_bands)):
            if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
                raise GearlabInputError(f"order bands: {label} must be a whole number >= 1, got {value!r}")
        if not 0.0 < floor_fraction < 1.0:
            raise GearlabInputError(f"order bands: floor_fraction must lie in (0, 1), got {floor_fraction!r}")
        m = min(int(sidebands), (z1 - 1) // 2)
        s = min(int(shaft_orders), z1 - m - 1)
        nyquist = points // 2
        if isinstance(highest, bool) or not isinstance(highest, numbers.Integral) or highest < 0:
            raise GearlabInputError(f"order bands: highest must be a whole number >= 0 (0: P/2), got {highest!r}")
        if nyquist <= z1 + m:
            raise GearlabInputError(
                f"{points} points per revolution are too few for a {z1}-tooth pinion: the highest order "
                f"P/2 = {nyquist} must exceed the first mesh order {z1} plus its {m} sidebands ({z1 + m}); "
                f"expected at least {2 * (z1 + m + 1)} points per revolution"
            )
        if highest and highest <= z1 + m:
            raise GearlabInputError(
                f"order bands: the highest order compared ({highest}, the record's passband) must exceed the "
                f"first mesh order {z1} plus its {m} sidebands ({z1 + m})"
            )
        highest = min(int(highest), nyquist) if highest else 0
        nyquist = highest or nyquist
        nominal = max(math.ceil(floor_fraction * nyquist), 1)
        # Resolve every harmonic whose upper sidebands end below the floor; at least the first.
        k = max(1, (nominal - 1 - m) // z1)
        start = max(nominal, k * z1 + m + 1)
        bands = min(int(floor_bands), nyquist - start + 1)
        return cls(points, z1, z2, s, m, k, start, bands, highest)

    @property
    def nyquist(self) -> int:
        """The highest order compared: P/2, or the record's passband (``highest``)."""
        return self.highest or self.points // 2

    def bands(self) -> dict[str, list[tuple[str, np.ndarray]]]:
        """View name -> [(feature name, the orders it sums)], in the order of the views."""
        z, m, k_max = self.z1, self.sidebands, self.harmonics
        shaft = [(f"shaft {s}x (order {s})", np.array([s])) for s in range(1, self.shaft_orders + 1)]
        mesh = [(f"mesh {k}x (order {k * z})", np.array([k * z])) for k in range(1, k_max + 1)]
        side = [
            (f"mesh {k}x ±{j} (orders {k * z - j}, {k * z + j})", np.array([k * z - j, k * z + j]))
            for k in range(1, k_max + 1)
            for j in range(1, m + 1)
        ]
        # What lies between: below the first lower sideband, between consecutive harmonics'
        # sidebands, and above the last resolved harmonic up to the noise floor.
        between = []
        edges = [self.shaft_orders + 1] + [k * z + m + 1 for k in range(1, k_max + 1)]
        ends = [k * z - m - 1 for k in range(1, k_max + 1)] + [self.floor_start - 1]
        for i, (lo, hi) in enumerate(zip(edges, ends)):
            if lo > hi:
                continue
            where = "below mesh 1x" if i == 0 else f"mesh {i}x-{i + 1}x" if i < k_max else f"above mesh {k_max}x"
            between.append((f"orders {lo}-{hi} ({where})", np.arange(lo, hi + 1)))
        floor = [
            (f"orders {part[0]}-{part[-1]}", part)
            for part in np.array_split(np.arange(self.floor_start, self.nyquist + 1), self.floor_bands)
        ]
        return {"shaft": shaft, "mesh": mesh, "sidebands": side, "non_synchronous": between, "noise_floor": floor}

    def describe(self) -> dict:
        z = self.z1
        return {
            "points_per_revolution": self.points,
            "Z1": z,
            "Z2": self.z2,
            "shaft_orders": list(range(1, self.shaft_orders + 1)),
            "mesh_harmonics": self.harmonics,
            "mesh_orders": [z, self.harmonics * z],
            "sidebands": self.sidebands,
            "noise_floor_orders": [self.floor_start, self.nyquist],
            "output_shaft_order": self.z1 / self.z2,
        }


def order_power(X: np.ndarray) -> np.ndarray:
    """Power per shaft order (n, P//2 + 1): the mean square each order contributes to a row.

    From the amplitude spectrum A of :func:`gearlab.signals.order_spectrum`, a line
    A·cos(kθ + φ) carries A²/2, DC and the Nyquist line A²; the powers of a row sum to its
    mean square (Parseval), so band powers are shares of the row's energy.
    """
    return power_of_spectrum(np.fft.rfft(X, axis=1), X.shape[1])


def power_of_spectrum(spectrum: np.ndarray, P: int) -> np.ndarray:
    """:func:`order_power` from the rows' rfft (n, P//2 + 1): 2|F|²/P² per line, |F|²/P² at DC
    and (P even) at the Nyquist line."""
    power = (spectrum.real**2 + spectrum.imag**2) * (2.0 / (P * P))
    power[:, 0] *= 0.5
    if P % 2 == 0:
        power[:, -1] *= 0.5
    return power


def order_views(X, pair, plan: BandPlan | None = None) -> list[View]:
    """The five order-band views (shaft, mesh, sidebands, non_synchronous, noise_floor), dB."""
    X = check_revolutions(X)
    plan = plan or BandPlan.make(X.shape[1], pair)
    if plan.points != X.shape[1]:
        raise GearlabInputError(f"band plan is for {plan.points} points per revolution, the rows have {X.shape[1]}")
    return order_views_of_power(order_power(X), plan)


def _band_layout(plan: BandPlan) -> list[tuple[str, tuple[str, ...], np.ndarray, np.ndarray]]:
    """Per view: (name, feature names, every band's orders one after the other, where each band
    starts in them): one gather and one np.add.reduceat sum every band of every row exactly."""
    layout = []
    for view, bands in plan.bands().items():
        orders = np.concatenate([o for _, o in bands] or [np.zeros(0)]).astype(np.intp)
        starts = np.cumsum([0] + [len(o) for _, o in bands[:-1]]).astype(np.intp)
        layout.append((view, tuple(name for name, _ in bands), orders, starts))
    return layout


_LAYOUTS: dict = {}


def order_views_of_power(power: np.ndarray, plan: BandPlan) -> list[View]:
    """The five order-band views from the power per order (n, P//2 + 1) of :func:`order_power`."""
    layout = _LAYOUTS.get(plan)
    if layout is None:
        layout = _LAYOUTS.setdefault(plan, _band_layout(plan))
    return [
        View(
            view,
            _db(np.add.reduceat(power[:, orders], starts, axis=1)) if len(names) else np.empty((len(power), 0)),
            names,
            "dB",
        )
        for view, names, orders, starts in layout
    ]


def output_shaft_view(X, pair, plan: BandPlan | None = None, multiples: int = 3) -> View:
    """Output-shaft orders j·Z1/Z2 and the mesh sidebands at ± those orders, dB, from
    *consecutive* revolutions.

    Rows must be consecutive revolutions of one record (not TSAs, not independent
    simulations). Blocks of R = Z2/gcd(Z1, Z2) rows span whole turns of both shafts, so
    their spectrum has lines every 1/R order and each output order falls on one. One feature
    row per block (n // R rows); multiples that are whole input orders are left out (they
    are input-shaft lines).
    """
    X = check_revolutions(X)
    z1, z2 = gear_ratio(pair)
    plan = plan or BandPlan.make(X.shape[1], pair)
    per_block = z2 // math.gcd(z1, z2)
    blocks = len(X) // per_block
    if blocks < 1:
        raise GearlabInputError(
            f"output-shaft orders need at least {per_block} consecutive revolutions (Z2/gcd(Z1, Z2)), got {len(X)}"
        )
    P = X.shape[1]
    joined = X[: blocks * per_block].reshape(blocks, per_block * P)
    _, amp = order_spectrum(joined, per_revolution=P)
    power = amp * amp / 2.0  # no DC or Nyquist line is ever picked below
    names, columns = [], []
    for j in range(1, multiples + 1):
        line = j * z1 // math.gcd(z1, z2)  # j·Z1/Z2 in lines of 1/R order
        if line % per_block == 0:
            continue
        names.append(f"output {j}x (order {j * z1 / z2:.3g})")
        columns.append(power[:, line])
        mesh = np.arange(1, plan.harmonics + 1) * z1 * per_block
        mesh = mesh[(mesh - line > 0) & (mesh + line < power.shape[1] - 1)]  # both sidebands inside the spectrum
        if len(mesh):
            names.append(f"mesh ± output {j}x ({len(mesh)} harmonics)")
            columns.append(power[:, mesh - line].sum(axis=1) + power[:, mesh + line].sum(axis=1))
    if not columns:
        raise GearlabInputError(
            f"gear ratio {z1}/{z2}: the first {multiples} output-shaft orders are all whole input orders"
        )
    return View("output_shaft", _db(np.stack(columns, axis=1)), tuple(names), "dB")


# --- the record: lines below and between the first shaft orders ----------------------------------

RECORD_BLOCK = 10  # revolutions per block: lines every 1/10 order
RECORD_ORDERS = 3  # the fractional lines below this order are compared
RECORD_RATE = 16  # points per revolution the record is averaged down to (orders below 8 kept)
RECORD_MIN_BLOCKS = 3  # half-overlapping blocks per set, at least (20 rows)


def record_blocks(n: int, block: int = RECORD_BLOCK) -> int:
    """How many half-overlapping blocks of *block* consecutive revolutions *n* rows give."""
    return 0 if n < block else (n - block) // (block // 2) + 1


def record_view(X, block: int = RECORD_BLOCK, orders: int = RECORD_ORDERS) -> View:
    """The fractional lines below *orders* shaft orders, dB, from *consecutive* revolutions.

    One revolution cannot place a line below one order (a 10 Hz tone at 40 Hz is a slow drift
    across the row) nor tell one between orders from its integer neighbours; *block* consecutive
    revolutions give lines every 1/block order. Each row minus the set's own synchronous average
    (the shaft-synchronous part lies on whole orders only; removed, no window leaks it into the
    fractional lines), averaged down to RECORD_RATE points per revolution (a boxcar: aligned with
    the revolutions, the same linear filter over the whole record; it nulls orders RECORD_RATE k),
    joined into one record, cut into half-overlapping blocks, a periodic Hann window on each: the
    power at order k/block for every k below *orders* x block that is not a multiple of *block*.
    One feature row per block (:func:`record_blocks`). Rows must be consecutive revolutions of one
    record, as a measured record's are (gearlab.gap.scoring.Rows.consecutive)."""
    X = check_revolutions(X)
    n, P = X.shape
    blocks = record_blocks(n, block)
    if blocks < 1:
        raise GearlabInputError(f"record view: needs at least {block} consecutive revolutions, got {n}")
    residual = X - X.mean(axis=0)
    edges = np.round(np.arange(RECORD_RATE + 1) * P / RECORD_RATE).astype(int)
    low = np.add.reduceat(residual, edges[:-1], axis=1) / np.diff(edges)
    record = low.reshape(-1)
    length, hop = block * RECORD_RATE, (block // 2) * RECORD_RATE
    starts = np.arange(blocks) * hop
    frames = record[starts[:, None] + np.arange(length)]
    window = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(length) / length)
    spectrum = np.fft.rfft(frames * window, axis=1)
    lines = np.array([k for k in range(1, orders * block) if k % block])
    power = np.abs(spectrum[:, lines]) ** 2 * (2.0 / (length * np.sum(window**2)))
    floor = RESIDUAL_FLOOR * float(np.mean(X * X))
    names = tuple(f"order {k / block:.3g}" for k in lines)
    return View("record", _db(np.maximum(power, floor)), names, "dB")


# --- TSA residual --------------------------------------------------------------------------------


def tsa_residual_view(X, pair, reference=None, sectors: int | None = None) -> View:
    """Residual energy (dB) per angular sector after the synchronous average and the mesh harmonics.

    *reference*: the synchronous average (P,) to remove, e.g. the source set's mean row
    (its TSA) when the rows are the target's. None: each row's own set, leave-one-out —
    row i minus the mean of the *other* rows, so that a row's noise is not partly removed
    with its own contribution to the mean (the residual energy of a set against its own
    mean reads (1 − 1/n) low; against the others' mean (1 + 1/(n−1)), as a new row against
    the full mean (1 + 1/n)). The DC line and every mesh harmonic k·Z1 are then removed —
    the mesh view measures those — and the energy is averaged over *sectors* equal angular
    sectors (default Z1: one per tooth pitch, sector 1 starting at the revolution's start).
    """
    X = check_revolutions(X)
    z1, _ = gear_ratio(pair)
    n, P = X.shape
    sectors = z1 if sectors is None else int(sectors)
    if not 1 <= sectors <= P:
        raise GearlabInputError(f"TSA residual: sectors must lie in 1..{P}, got {sectors}")
    if reference is None:
        if n < 2:
            raise GearlabInputError("TSA residual: a set's own average needs at least 2 revolutions")
        residual = (X - X.mean(axis=0)) * (n / (n - 1))  # = x_i − mean of the other rows
    else:
        reference = check_array(reference, "TSA reference")
        if reference.shape != (P,):
            raise GearlabInputError(f"TSA reference must have shape ({P},), got {reference.shape}")
        residual = X - reference
    return residual_view_of_spectrum(np.fft.rfft(residual, axis=1), P, z1, np.mean(X * X, axis=1), sectors)


def residual_view_of_spectrum(
    spectrum: np.ndarray, P: int, z1: int, row_power: np.ndarray, sectors: int | None = None
) -> View:
    """The TSA residual view from the residual's rfft (n, P//2 + 1) (overwritten: DC and mesh
    harmonics are zeroed) and each row's mean square *row_power* (n,).

    The residual energy is floored at RESIDUAL_FLOOR of the row's own mean square: a residual
    that is only floating-point rounding (two noise-free sets of one simulator: about 1e-26 of
    the row's power, -261 dB) reads as the floor in both sets, not as a gap made of rounding."""
    return residual_view_of_rows(mesh_free(spectrum, P, z1), z1, row_power, sectors)


def mesh_free(spectrum: np.ndarray, P: int, z1: int) -> np.ndarray:
    """The rows (n, P) of the rfft *spectrum* (n, P//2 + 1; overwritten) without their DC line and mesh harmonics."""
    spectrum[:, 0] = 0.0
    spectrum[:, z1::z1] = 0.0
    return np.fft.irfft(spectrum, n=P, axis=1)


def residual_view_of_rows(residual: np.ndarray, z1: int, row_power: np.ndarray, sectors: int | None = None) -> View:
    """residual_view_of_spectrum's view of the residual rows (n, P) themselves (mesh_free)."""
    sectors = z1 if sectors is None else int(sectors)
    P = residual.shape[1]
    edges = np.round(np.arange(sectors + 1) * P / sectors).astype(int)
    energy = np.add.reduceat(residual * residual, edges[:-1], axis=1) / np.diff(edges)
    energy = np.maximum(energy, RESIDUAL_FLOOR * np.asarray(row_power, dtype=np.float64)[:, None])
    degrees = 360.0 * edges / P
    names = tuple(f"sector {i + 1} ({degrees[i]:.1f}-{degrees[i + 1]:.1f} deg)" for i in range(sectors))
    return View("tsa_residual", _db(energy), names, "dB")


# --- waveform statistics --------------------------------------------------------------------------

WAVEFORM_STATS = ("mean", "rms", "peak_to_peak", "crest_factor", "skewness", "kurtosis")


def waveform_view(X) -> View:
    """Mean, RMS, peak-to-peak, crest factor (max|x|/RMS), skewness and kurtosis of each row.

    RMS and crest factor include the mean (they are what a meter reads); skewness and
    kurtosis are of the centred row, kurtosis Pearson's (3 for Gaussian data, higher for
    impulsive data, 1.5 for a pure tone).
    """
    X = check_revolutions(X)
    mean = X.mean(axis=1)
    rms = np.sqrt(np.mean(X * X, axis=1))
    centred = X - mean[:, None]
    square = centred * centred
    var = np.mean(square, axis=1)
    # A constant row has no shape: skewness and kurtosis 0 (and crest factor 0 for a zero
    # row) keep every feature finite.
    shaped = var * var > 0.0
    skew = np.divide(np.mean(square * centred, axis=1), var**1.5, out=np.zeros(len(X)), where=shaped)
    kurt = np.divide(np.mean(square * square, axis=1), var * var, out=np.zeros(len(X)), where=shaped)
    crest = np.divide(np.abs(X).max(axis=1), rms, out=np.zeros(len(X)), where=rms > 0.0)
    features = np.stack([mean, rms, np.ptp(X, axis=1), crest, skew, kurt], axis=1)
    return View("waveform", features, WAVEFORM_STATS, "")


# --- network latent features --------------------------------------------------------------------


def embed_rows(X: np.ndarray, embed: Callable, name: str = "rows") -> np.ndarray:
    """``embed(X)`` checked: a finite (n, d) array with d >= 1."""
    Z = np.asarray(embed(X), dtype=np.float64)
    if Z.ndim == 1:
        Z = Z[:, None]
    if Z.ndim != 2 or Z.shape[0] != len(X) or Z.shape[1] < 1:
        raise GearlabInputError(f"embed({name}) must return an (n, d) array for {len(X)} rows, got shape {Z.shape}")
    return check_array(Z, f"latent features of the {name}")


@dataclass(frozen=True)
class LatentBasis:
    """How latent vectors become features: centred at ``mean``, projected on ``components``
    (k, d) — or, with no components, every unit as it is."""

    mean: np.ndarray
    components: np.ndarray | None

    @classmethod
    def fit(cls, *latents: np.ndarray, max_units: int = 64, n_components: int = 8, seed: int = 0) -> LatentBasis:
        pooled = np.concatenate(latents)
        mean = pooled.mean(axis=0)
        if pooled.shape[1] <= max_units:
            return cls(mean, None)
        from sklearn.utils.extmath import randomized_svd

        k = min(n_components, *pooled.shape)
        # Randomised SVD: cnn3's ~30 000 units would make a full SVD the slowest step.
        _, _, vt = randomized_svd(pooled - mean, n_components=k, random_state=seed)
        return cls(mean, vt)

    def project(self, Z: np.ndarray) -> View:
        centred = Z - self.mean
        if self.components is None:
            return View("latent", centred, tuple(f"unit {i + 1}" for i in range(Z.shape[1])))
        return View("latent", centred @ self.components.T, tuple(f"PC{i + 1}" for i in range(len(self.components))))


def latent_views(source_X: np.ndarray, target_X: np.ndarray, embed: Callable, **basis_options) -> tuple[View, View]:
    """The latent views of both sets, on one basis fitted to both (LatentBasis.fit)."""
    zs, zt = embed_rows(source_X, embed, "source rows"), embed_rows(target_X, embed, "target rows")
    if zs.shape[1] != zt.shape[1]:
        raise GearlabInputError(
            f"embed gave {zs.shape[1]} latent features for the source, {zt.shape[1]} for the target"
        )
    basis = LatentBasis.fit(zs, zt, **basis_options)
    return basis.project(zs), basis.project(zt)


def network_embed(network, batch_size: int = 256) -> Callable[[np.ndarray], np.ndarray]:
    """``embed`` for a gearlab network (gearlab.learn.networks.Network): its feature
    extractor in evaluation mode, batch by batch, on the rows as given (pass rows scaled as
    the network was trained, e.g. standardised)."""
    import torch

    def embed(X: np.ndarray) -> np.ndarray:
        device = next(network.parameters()).device
        was_training = network.training
        network.eval()
        try:
            with torch.no_grad():
                parts = [
                    network.embed(torch.as_tensor(X[i : i + batch_size], dtype=torch.float32, device=device))
                    for i in range(0, len(X), batch_size)
                ]
        finally:
            network.train(was_training)
        return torch.cat(parts).reshape(len(X), -1).cpu().numpy().astype(np.float64)

    return embed


def row_views(X, pair, plan: BandPlan | None = None, reference=None) -> list[View]:
    """Every per-row view of one set except the latent one: the order bands, the TSA
    residual (against *reference*, or the set's own leave-one-out average) and the
    waveform statistics."""
    X = check_revolutions(X)
    plan = plan or BandPlan.make(X.shape[1], pair)
    return [*order_views(X, pair, plan), tsa_residual_view(X, pair, reference), waveform_view(X)]
