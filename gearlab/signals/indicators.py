"""Classical gear condition indicators of a time-synchronous average (TSA): FM4, NA4, tooth_energy,
tooth_sync, pinion_sync.

What a gear-diagnosis engineer computes on the input-shaft TSA before any learning
(Stewart 1977; Zakrajsek, Townsend & Decker 1993, NASA TM-106032). With the TSA x of one
revolution on a uniform angle grid and X its order spectrum (order = harmonic of the shaft):

* regular signal: the low shaft orders 1 … *shaft_orders*, the mesh orders (every harmonic
  k·Z of each mesh order Z) and their first *sidebands* orders either side;
* difference signal d = x − regular signal; **FM4** = N Σ (d − d̄)⁴ / (Σ (d − d̄)²)², the
  kurtosis of d: about 3 for a healthy gear, larger when one tooth adds an impulse;
* residual signal r = x − (shaft orders and mesh harmonics, sidebands kept); **NA4** = the
  fourth moment of r over the square of its variance *averaged over the healthy history*
  (the "trended" denominator), so a run's growing variance does not hide its impulses;
* **tooth_energy**: the revolution cut into one window per tooth of the gear on the TSA's shaft
  (Z windows of 2π/Z, Z the first mesh order), s_k = ln of window k's share of the difference
  signal's energy; each window is standardised by the healthy history's mean and *within-record*
  spread of s_k, and the indicator is the largest of the Z: max_k (s_k − s̄_k)/σ_k. A chipped
  tooth adds energy in one window of the same angle in every revolution; FM4 dilutes it over the
  whole revolution (the demodulation and time-frequency views of the residual localise it in
  angle for the same reason: McFadden 1986; Wang & McFadden 1993). Scale-free like FM4 (a
  share), so a record's level does not enter; how much a new record's largest z may vary is
  left to the threshold rule, as for every score. It calls *any* change of where in the
  revolution the energy lies, including non-synchronous impulses that leak through the
  average (a bearing; docs/real_data.md).
* **tooth_sync**: tooth_energy read on the *synchronous* part of each window. A TSA of N
  revolutions keeps what repeats at one input angle every revolution (a pinion tooth) and, of
  what does not (noise, a bearing's impulses, which slip in angle from one revolution to the
  next), an energy of about V_k/N, V_k the per-revolution variance of the difference signal in
  window k about the TSA (the variance of a mean of N independent draws). The window's
  synchronous energy S_k = E_k − V_k/N is estimated without a floor as the mean product of the
  difference signals of *different* revolutions of the unit over the window (noise of two
  revolutions is independent: its products average to 0), taken as a share of the TSA's mean
  window energy, u_k = S_k / mean_j E_j, standardised per window by the healthy history like
  tooth_energy (mean of the records' means, pooled within-record spread); the indicator is
  max_k (u_k − ū_k)/σ_k. An asynchronous burst train raises E_k and V_k/N alike and leaves S_k
  (it only dilutes u_k, through mean_j E_j), where tooth_energy's log share of E_k rises with it.
  A share and linear in energy: the record's level cancels, and a window without synchronous
  content is not blown up as by a logarithm of a near-zero estimate. Damage that repeats at one
  input angle every q revolutions (a tooth on a shaft turning q times slower: on the PHM rig the
  idler, q = 3, and the output, q = 5) is synchronous with the input too, at 1/q of its size:
  FM4 and tooth_energy call it. Given the *slow* periods, tooth_sync leaves out the pairs of
  revolutions whose lag is a multiple of one, and such damage then scores 0 (sync_shares).
* **pinion_sync**: which shaft a localised fault turns with. For every shaft turning once every q
  input revolutions (whole q, read from the same tacho: the revolutions' phases r mod q) the shaft's
  TSA holds q copies of the input revolution; their mean is the input TSA. A pinion tooth appears in
  every copy at one input angle (on a rig without a hunting tooth it meets the same q teeth of the slow
  shaft's gear), scaled by any smooth, non-reversing modulation of that shaft's turn (an eccentric
  idler); a tooth of the slow shaft appears in one copy. What the copies hold beyond the modulated mean
  (modulated_residual) is the slow shaft's own; the score is the input TSA's largest localised excess
  that no slow shaft's tooth explains (shaft_parts, shaft_strengths).

All orders refer to the shaft the TSA is synchronous with (here the input shaft: mesh
orders 32 for stage 1 and 16 for stage 2 of the PHM 2009 spur rig).
"""

from __future__ import annotations

import numpy as np

INDICATORS = ("fm4", "na4", "tooth_energy", "tooth_sync", "pinion_sync")
# what a scenario computes when it names none (the localised ones are asked for by name)
DEFAULT_INDICATORS = ("fm4", "na4")


def _masked(x: np.ndarray, mesh_orders, shaft_orders: int, sidebands: int) -> np.ndarray:
    """*x* (rows: revolutions) with the named orders removed from its order spectrum."""
    X = np.fft.rfft(np.asarray(x, dtype=np.float64), axis=-1)
    top = X.shape[-1] - 1
    remove = np.zeros(X.shape[-1], dtype=bool)
    remove[0 : shaft_orders + 1] = True  # the mean and the low shaft orders
    for z in mesh_orders:
        for centre in range(z, top + 1, z):
            remove[max(0, centre - sidebands) : min(top, centre + sidebands) + 1] = True
    X[..., remove] = 0.0
    return np.fft.irfft(X, n=x.shape[-1], axis=-1)


def difference_signal(x: np.ndarray, mesh_orders, shaft_orders: int = 2, sidebands: int = 1) -> np.ndarray:
    return _masked(x, mesh_orders, shaft_orders, sidebands)


def band_limited(x: np.ndarray, points: int | None = None, max_order: int | None = None) -> np.ndarray:
    """*x* (rows: revolutions) at *points* samples per revolution (None: as many as it has), its
    orders below points / 2 kept and none above *max_order* (None or 0: all): a revolution is
    periodic, so truncating its order spectrum is the exact band-limited resampling (no filter, no
    edge). Rows are never lengthened; rows with nothing to cut are returned as they are."""
    x = np.asarray(x)
    n = x.shape[-1] if points is None else min(points, x.shape[-1])
    keep = n // 2 + 1 if n == x.shape[-1] else (n + 1) // 2  # rfft bins; a shortened row drops its Nyquist bin
    if max_order:
        keep = min(keep, max_order + 1)
    if n == x.shape[-1] and keep == n // 2 + 1:
        return x
    X = np.fft.rfft(x, axis=-1)[..., :keep]
    return (np.fft.irfft(X, n=n, axis=-1) * (n / x.shape[-1])).astype(x.dtype, copy=False)


def residual_signal(x: np.ndarray, mesh_orders, shaft_orders: int = 2) -> np.ndarray:
    return _masked(x, mesh_orders, shaft_orders, 0)


def fm4(x: np.ndarray, mesh_orders, shaft_orders: int = 2, sidebands: int = 1) -> np.ndarray:
    """FM4 of each row of *x* (one TSA revolution per row)."""
    d = difference_signal(np.atleast_2d(x), mesh_orders, shaft_orders, sidebands)
    d = d - d.mean(axis=-1, keepdims=True)
    d2 = np.square(d)  # what d**2 computes; d**4 as its square, as fourth_power does
    return d.shape[-1] * np.sum(np.square(d2), axis=-1) / np.maximum(np.sum(d2, axis=-1) ** 2, 1e-300)


def na4_reference(history: np.ndarray, mesh_orders, shaft_orders: int = 2) -> float:
    """NA4's denominator: the residual variance averaged over the healthy history's TSAs."""
    r = residual_signal(np.atleast_2d(history), mesh_orders, shaft_orders)
    return float(np.mean(np.var(r, axis=-1)))


def na4(x: np.ndarray, mesh_orders, reference_variance: float, shaft_orders: int = 2) -> np.ndarray:
    """NA4 of each row of *x* against the history's mean residual variance."""
    r = residual_signal(np.atleast_2d(x), mesh_orders, shaft_orders)
    r = r - r.mean(axis=-1, keepdims=True)
    return np.mean(fourth_power(r), axis=-1) / max(reference_variance, 1e-300) ** 2


def fourth_power(x: np.ndarray) -> np.ndarray:
    """x⁴ as (x²)²: numpy's x**4 calls pow() per sample, ten times the CPU of two squares (FM4 and NA4 of a
    detection's units spent most of their time there); within an ulp of it (two roundings, not one)."""
    return np.square(np.square(x))


def _edges(n: int, teeth: int) -> np.ndarray:
    """The *teeth* + 1 edges of equal angle windows of *n* samples: the nearest samples to 2πk/teeth."""
    if not 1 <= teeth <= n:
        raise ValueError(f"expected 1 … {n} tooth windows, got {teeth}")
    return np.append(np.round(np.arange(teeth) * n / teeth).astype(int), n)


def window_energy(d: np.ndarray, teeth: int) -> np.ndarray:
    """Mean square of each row of *d* over *teeth* equal angle windows, (rows, teeth)."""
    edges = _edges(d.shape[-1], teeth)
    return np.add.reduceat(d**2, edges[:-1], axis=-1) / np.diff(edges)


def tooth_windows(x: np.ndarray, teeth: int, mesh_orders, shaft_orders: int = 2, sidebands: int = 1) -> np.ndarray:
    """s_k: ln of each of the *teeth* equal angle windows' share of the difference signal's energy,
    (rows of *x*, teeth)."""
    d = difference_signal(np.atleast_2d(x), mesh_orders, shaft_orders, sidebands)
    energy = np.maximum(window_energy(d, teeth), 1e-300)
    return np.log(energy / energy.mean(axis=-1, keepdims=True))


def async_floor(revolutions: np.ndarray, teeth: int, mesh_orders, shaft_orders: int = 2, sidebands: int = 1):
    """V_k: the per-revolution variance of the difference signal in each of *teeth* windows about
    the TSA of all *revolutions* of one record (unbiased, n − 1), i.e. what does not repeat every
    revolution; a TSA of N of them keeps about V_k / N of it. NaN with fewer than 2 revolutions."""
    d = difference_signal(np.atleast_2d(revolutions), mesh_orders, shaft_orders, sidebands)
    n = len(d)
    if n < 2:
        return np.full(teeth, np.nan)
    return window_energy(d - d.mean(axis=0), teeth).sum(axis=0) / (n - 1)


def window_gram(revolutions: np.ndarray, teeth: int, mesh_orders, shaft_orders: int = 2, sidebands: int = 1):
    """G[k, r, s]: the mean over tooth window k of the product of revolutions r and s's difference
    signals, (teeth, revolutions, revolutions); its diagonal is each revolution's window energy."""
    d = difference_signal(np.atleast_2d(revolutions), mesh_orders, shaft_orders, sidebands)
    edges = _edges(d.shape[-1], teeth)
    return np.stack([d[:, a:b] @ d[:, a:b].T / (b - a) for a, b in zip(edges[:-1], edges[1:])])


def pair_mask(n: int, slow=()) -> np.ndarray:
    """(n, n): the pairs of revolutions r ≠ s whose lag r − s is no multiple of any of the *slow*
    shafts' periods (in input revolutions)."""
    lag = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    keep = lag > 0
    for q in slow:
        keep &= lag % q != 0
    return keep


def sync_shares(
    revolutions: np.ndarray,
    block: int,
    stride: int,
    teeth: int,
    mesh_orders,
    slow=(),
    shaft_orders: int = 2,
    sidebands: int = 1,
    gram: np.ndarray | None = None,
) -> np.ndarray:
    """u_k of each TSA unit of *block* consecutive *revolutions* of one record (units starting at 0,
    stride, 2·stride, … as kinds.detection_records.tsa_units makes them), (units, teeth): each window's
    synchronous energy S_k as a share of the unit's TSA mean window energy. S_k is the mean of
    G[k, r, s] (window_gram) over the unit's pairs of different revolutions (pair_mask): what
    repeats every revolution adds its energy to every pair, independent noise and impulses that
    slip in angle (a bearing) add nothing in expectation — the same as the TSA's window energy less
    the floor V_k/N of its revolution-to-revolution variance. Leaving out the pairs whose lag is a
    multiple of a *slow* shaft's period q removes what repeats every q revolutions and not every
    one (a tooth on that shaft): it then scores |s|² − Σ_a |d_a|² / (q(q − 1)) for a signal
    s + d_(r mod q), 0 for one impulse every q revolutions. block = 1: each revolution paired
    with every other revolution of the record. *gram*: the record's window_gram, when already made."""
    if gram is None:
        gram = window_gram(revolutions, teeth, mesh_orders, shaft_orders, sidebands)
    n = gram.shape[-1]
    diagonal = np.einsum("krr->rk", gram)
    if block == 1:
        mask = pair_mask(n, slow)
        sync = np.einsum("krs,rs->rk", gram, mask) / np.maximum(mask.sum(axis=1), 1)[:, None]
        return sync / np.maximum(diagonal.mean(axis=1, keepdims=True), 1e-300)
    mask = pair_mask(block, slow)
    out = []
    for s in range(0, n - block + 1, stride):
        g = gram[:, s : s + block, s : s + block]
        sync = np.sum(g * mask, axis=(1, 2)) / max(mask.sum(), 1)
        energy = g.sum(axis=(1, 2)) / block**2  # the TSA's window energies
        out.append(sync / max(energy.mean(), 1e-300))
    return np.array(out).reshape(-1, teeth)


def _first_harmonic_basis(q: int) -> tuple[np.ndarray, float]:
    """An orthonormal basis (rows) of the gains a smooth once-per-turn modulation gives the q copies
    of the input revolution in one turn of a shaft of period q: g_j = m + Re(β e^{2πij/q}), the mean
    and the first harmonic of the shaft's angle; and α, the cone |β| <= m (the modulation never
    reverses the sign: m(φ) >= 0 over the whole turn) in the basis' coordinates, |b| <= α·t with t the
    mean's coordinate and b the harmonic's."""
    j = np.arange(q)
    if q == 2:  # one harmonic direction: g = m + β(−1)^j, |β| <= m
        return np.array([np.ones(2), np.cos(np.pi * j)]) / np.sqrt(2), 1.0
    rows = [
        np.ones(q) / np.sqrt(q),
        np.cos(2 * np.pi * j / q) * np.sqrt(2 / q),
        np.sin(2 * np.pi * j / q) * np.sqrt(2 / q),
    ]
    return np.array(rows), 1.0 / np.sqrt(2)  # |b|² = |β|² q/2, t² = m² q


def modulation_distance(gains: np.ndarray) -> np.ndarray:
    """Squared distance of each row of *gains* (…, q) from the gains a non-negative, smooth
    once-per-turn modulation can give the q copies (_first_harmonic_basis): the part beyond the first
    harmonic plus the distance from the cone |β| <= m, projected in the (t, |b|) plane."""
    basis, alpha = _first_harmonic_basis(gains.shape[-1])
    coef = gains @ basis.T
    beyond = np.maximum(np.sum(gains**2, axis=-1) - np.sum(coef**2, axis=-1), 0.0)
    t, r = coef[..., 0], np.linalg.norm(coef[..., 1:], axis=-1)
    c, s = 1.0 / np.sqrt(1 + alpha**2), alpha / np.sqrt(1 + alpha**2)  # the cone's edge in (t, r)
    along = np.maximum(t * c + r * s, 0.0)
    off = np.where(r <= alpha * t, 0.0, (t - along * c) ** 2 + (r - along * s) ** 2)
    return beyond + off


def single_phase_residual(q: int) -> float:
    """What modulated_residual keeps of a tooth on a shaft of period q (one impulse of window energy 1
    in one of the q copies, none in the others), per copy: its gains against the symmetric part are
    q at its phase and 0 elsewhere (m = 1 and |β| = 2: a modulation that would reverse sign, outside
    the cone), and the symmetric part's energy is 1/q². 1/27 for the idler (q = 3), 0.093 for q = 5; 0 for
    q = 2, whose full modulation 1 + cos φ empties one copy (a tooth on a half-speed shaft cannot be
    told from a pinion chip seen at every other turn)."""
    gains = np.zeros(q)
    gains[0] = q
    return float(modulation_distance(gains)) / q**3


def modulated_residual(gram: np.ndarray, q: int) -> np.ndarray:
    """The localised content of a unit's slow-shaft TSA that no input-synchronous event explains, per
    tooth window, (teeth,): a shaft of period q (whole input revolutions) sees the unit's revolutions in
    q phases j = r mod q (its TSA is q input revolutions long: the q phase TSAs c_j in turn). Its
    q-fold symmetric part is their mean p, the input TSA; a chipped pinion tooth appears in every copy
    at the same input angle, and a modulation of the mesh smooth in the shaft's angle (an eccentric
    idler) scales the copies unequally, c_j = g_j p with g_j = m + Re(β e^{2πij/q}), |β| <= m, adding
    no localised content; a tooth on the slow shaft appears in one copy only. Per window k:
    R_k = min over those gains of (1/q) Σ_j |c_j − g_j p|²_k = (1/q)(Σ_j |c_j|² − Σ_j ⟨c_j, p⟩²/|p|²
    + |p|² d²(g*)), g*_j = ⟨c_j, p⟩/|p|² the free gains and d² their modulation_distance. Every
    product is synchronous: ⟨c_i, c_j⟩ is the mean window product of revolution pairs r ∈ i, s ∈ j,
    r ≠ s (window_gram's off-diagonal: noise and slipping impulses average to 0). A pinion chip gives
    R ≈ 0 however its copies are modulated within the cone; a slow-shaft tooth of window energy A²
    gives A²·single_phase_residual(q) (A²/27 for the idler) beside an input image A²/q². Where p has
    no synchronous energy (|p|² <= 0) nothing is symmetric and R_k = (1/q) Σ_j |c_j|². *gram*: the
    unit's window_gram, (teeth, revolutions, revolutions); NaN when a phase has no pair."""
    teeth, b, _ = gram.shape
    phase = np.arange(b) % q
    member = (phase[None, :] == np.arange(q)[:, None]).astype(np.float64)  # (q, b)
    count = member.sum(axis=1)
    if b < 2 * q:  # a phase held once has no pair of its own: the shaft's turn is not seen twice
        return np.full(teeth, np.nan)
    off = gram * (1.0 - np.eye(b))  # products of different revolutions only
    pairs = np.outer(count, count) - np.diag(count)
    M = np.einsum("ir,krs,js->kij", member, off, member) / pairs  # ⟨c_i, c_j⟩, (teeth, q, q)
    cp = M.mean(axis=2)  # ⟨c_j, p⟩
    pp = M.mean(axis=(1, 2))  # |p|²
    own = np.einsum("kii->k", M)
    ok = pp > 0
    safe = np.where(ok, pp, 1.0)
    free = cp / safe[:, None]
    left = own - np.sum(cp**2, axis=1) / safe + safe * modulation_distance(free)
    return np.where(ok, left, own) / q


def shaft_parts(
    revolutions: np.ndarray,
    block: int,
    stride: int,
    teeth: int,
    mesh_orders,
    shafts=(),
    shaft_orders: int = 2,
    sidebands: int = 1,
    gram: np.ndarray | None = None,
) -> np.ndarray:
    """Which shaft each tooth window's synchronous content turns with, (units, 1 + len(shafts), teeth).

    Row 0 is the input shaft's part, sync_shares with every pair: |s_k|², the energy in window k of
    what repeats every input revolution (the slow shafts' TSAs' symmetric part). Row i is what shaft
    i's TSA (q = shafts[i] input revolutions; whole q: on the PHM rig the idler, 3, and the output, 5)
    holds beyond that part once each of its q copies may carry its own gain of a smooth, non-reversing
    once-per-turn modulation (modulated_residual): 0 for a chipped pinion tooth however eccentric the
    idler, A²·single_phase_residual(q) for a tooth of that shaft, whose input image is A²/q². All rows
    are shares of the unit's TSA mean window energy, as sync_shares' (the record's level cancels; the
    rows compare in one unit). Units as sync_shares: *block* consecutive revolutions moved by
    *stride*; block = 1: each revolution with every other of the record for the input part, the whole
    record's phases for the slow shafts (one revolution has one phase), each as a share of the
    revolution's own energy. A unit too short to hold each phase of a slow shaft twice has no part for
    it (NaN). *gram*: the record's window_gram, when already made (one per record serves every unit
    kind)."""
    if gram is None:
        gram = window_gram(revolutions, teeth, mesh_orders, shaft_orders, sidebands)
    n = gram.shape[-1]
    rows = []
    if block == 1:  # each revolution's own energy is the unit of its shares, as in sync_shares
        diagonal = np.einsum("krr->kr", gram)
        energy = np.maximum(diagonal.mean(axis=0), 1e-300)
        inputs = ((gram.sum(axis=2) - diagonal) / max(n - 1, 1)).T / energy[:, None]  # every other revolution
        slow = np.stack([modulated_residual(gram, q) for q in shafts]) if shafts else np.empty((0, teeth))
        return np.stack([np.vstack([inputs[r], slow / energy[r]]) for r in range(n)])
    mask = pair_mask(block)
    for s in range(0, n - block + 1, stride):
        g = gram[:, s : s + block, s : s + block]
        norm = max(g.sum(axis=(1, 2)).mean() / block**2, 1e-300)  # the TSA's mean window energy
        sync = np.sum(g * mask, axis=(1, 2)) / max(mask.sum(), 1)
        rows.append(np.stack([sync / norm] + [modulated_residual(g, q) / norm for q in shafts]))
    return np.array(rows).reshape(-1, 1 + len(shafts), teeth)


def shaft_strengths(parts: np.ndarray, shafts, reference) -> np.ndarray:
    """How strongly a localised fault turns with each shaft, (units, 1 + len(shafts)), from the units'
    shaft_parts against *reference* = (mean, spread) of the history's parts (window_reference of the
    flattened parts; the mean is used), in the parts' common unit (a share of the TSA's window energy)
    brought to the energy A² of the tooth that would give them, so the shafts compare. e_ik: the excess
    of part i in tooth window k over the history's mean. The input shaft's strength is max_k e_0k (a
    pinion tooth: A²; the input TSA's localised content, whatever turns it). A tooth on a shaft of
    period q shows in two views that must agree: what that shaft's TSA holds beyond any modulated
    input-synchronous event, e_qk = A²·f_q (f_q = single_phase_residual(q)), and its image in the input
    TSA, e_0k = A²/q²; the shaft's strength is max_k min(e_qk/f_q, q²·e_0k), the smaller of the two
    sightings at one size. A pinion tooth leaves no residual (e_qk ≈ 0) and a residual with no image in
    the input TSA is no tooth on a shaft. A shaft whose residual cannot see a tooth (f_q = 0: q = 2,
    whose full modulation 1 + cos φ empties one copy) has no strength (NaN)."""
    mean = np.asarray(reference[0]).reshape(parts.shape[1:])
    excess = parts - mean  # (units, 1 + shafts, teeth)
    out = [excess[:, 0].max(axis=-1)]
    for i, q in enumerate(shafts, start=1):
        f = single_phase_residual(q)
        if f <= 1e-12:
            out.append(np.full(len(parts), np.nan))
            continue
        out.append(np.minimum(excess[:, i] / f, q * q * excess[:, 0]).max(axis=-1))  # NaN stays NaN
    return np.stack(out, axis=1)


def pinion_sync(parts: np.ndarray, shafts, reference) -> np.ndarray:
    """pinion_sync of each unit from its shaft_parts: the largest localised excess of the input TSA
    that no tooth of a slow shaft explains, max_k (e_0k − max_q X_qk), e_0k the input part's excess in
    window k (shaft_strengths) and X_qk = min(2·e_qk/(f_q q²), e_0k) the share of it shaft q's residual
    explains. The residual's sighting of a tooth of shaft q predicts its input image: e_qk/f_q = A²,
    the image A²/q², so r_k = e_qk/(f_q q² e_0k) is 0 for a pinion tooth (no residual however the
    idler modulates it) and 1 for a tooth of that shaft; the image counts as explained from r = 1/2,
    the midpoint, up (the estimates scatter around both: a TSA10's residual sees an idler tooth at
    0.8 of its image). A chipped pinion tooth scores A²; a tooth on the idler about 0; a chipped pinion
    beside other damage keeps its own window's A². A slow shaft that lost ground against the history
    (e_qk < 0: a strong bearing dilutes every share) or that the unit is too short to see (NaN) explains
    nothing."""
    mean = np.asarray(reference[0]).reshape(parts.shape[1:])
    excess = parts - mean  # (units, 1 + shafts, teeth)
    inputs = excess[:, 0]
    explained = np.zeros_like(inputs)
    for i, q in enumerate(shafts, start=1):
        f = single_phase_residual(q)
        if f > 1e-12:
            image = np.nan_to_num(np.maximum(2.0 * excess[:, i] / (f * q * q), 0.0), nan=0.0)
            explained = np.maximum(explained, np.minimum(image, np.maximum(inputs, 0.0)))
    return (inputs - explained).max(axis=-1)


def window_reference(groups, dofs=None):
    """A localised indicator's (mean, spread) per window from the healthy history, given as one
    array (units, windows) per history record: the mean of the records' means (each record counts
    once) and the pooled within-record standard deviation (the unit-to-unit spread, which the
    history estimates well; the record-to-record part stays in the threshold rule). *dofs*: each
    record's degrees of freedom of its sum of squares (default n − 1; overlapping TSA windows have
    fewer: gearlab.kinds.record_effects.overlap_dof), so the spread is that of independent units."""
    keep = [i for i, g in enumerate(groups) if len(g)]
    if not keep:
        raise ValueError("no history units")
    groups = [groups[i] for i in keep]
    dof = sum(len(g) - 1 for g in groups) if dofs is None else float(sum(dofs[i] for i in keep))
    mean = np.mean([g.mean(axis=0) for g in groups], axis=0)
    if dof > 0:
        spread = np.sqrt(sum(np.sum((g - g.mean(axis=0)) ** 2, axis=0) for g in groups) / dof)
    else:  # one unit per record: only the spread between them is known
        spread = np.concatenate(groups).std(axis=0)
    return mean, np.maximum(spread, 1e-12)


def tooth_reference(history, teeth: int, mesh_orders, shaft_orders: int = 2, sidebands: int = 1, dofs=None):
    """tooth_energy's (mean, spread) per window (window_reference) from the history's TSA units,
    one array per history record."""
    return window_reference([tooth_windows(h, teeth, mesh_orders, shaft_orders, sidebands) for h in history], dofs)


def tooth_energy(x: np.ndarray, mesh_orders, reference, shaft_orders: int = 2, sidebands: int = 1) -> np.ndarray:
    """tooth_energy of each row of *x*: the largest standardised tooth-window energy share, against
    *reference* = tooth_reference(...) (its length is the number of windows)."""
    mean, spread = reference
    s = tooth_windows(x, len(mean), mesh_orders, shaft_orders, sidebands)
    return np.max((s - mean) / spread, axis=-1)


def tooth_sync(shares: np.ndarray, reference) -> np.ndarray:
    """tooth_sync of each unit from its sync_shares: the largest standardised synchronous window
    share, against *reference* = window_reference of the history's sync_shares."""
    mean, spread = reference
    return np.max((shares - mean) / spread, axis=-1)


def input_synchronous_share(
    revolutions: np.ndarray, ratio: int, mesh_orders, shaft_orders: int = 2, sidebands: int = 1
) -> float:
    """Which shaft a record's impulsive content turns with: the share of the energy of its
    difference signal, averaged over one turn of a shaft that turns *ratio* times slower than
    the input (``ratio`` consecutive input revolutions), that lies at whole input orders.

    A chipped input pinion repeats every input revolution: its energy is at whole input orders
    and the share tends to 1. Damage on the slower shaft (on the PHM rig the idler, 96/32 = 3)
    repeats every *ratio* input revolutions, at the same input angle when the ratio is a whole
    number, so the input-shaft TSA shows it too (at 1/ratio of its size) and FM4 of that TSA
    cannot tell the two apart; here its energy spreads over every 1/ratio order and the share
    is about 1/ratio, as for noise and for a bearing, which turns with neither shaft. Orders
    are removed as for FM4 (*mesh_orders*, *shaft_orders*, *sidebands* in input orders)."""
    revolutions = np.atleast_2d(np.asarray(revolutions, dtype=np.float64))
    if ratio < 1 or len(revolutions) < ratio:
        raise ValueError(f"expected a whole ratio >= 1 and at least {ratio} revolutions, got {len(revolutions)}")
    n = len(revolutions) // ratio * ratio
    turn = revolutions[:n].reshape(n // ratio, -1).mean(axis=0)  # the slow shaft's TSA
    d = difference_signal(turn[None], [z * ratio for z in mesh_orders], shaft_orders * ratio, sidebands * ratio)[0]
    power = np.abs(np.fft.rfft(d)) ** 2
    whole = np.arange(len(power)) % ratio == 0
    return float(power[whole].sum() / max(power.sum(), 1e-300))
