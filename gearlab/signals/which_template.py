"""Which gear on a two-gear shaft, by simulate and compare: the record's event against each gear's
simulated event.

A tooth fault is a force pulse near order zero at its mesh, filtered by the structure on its way to
the sensor (gearlab.signals.localise, "Which gear on a shaft"). A stage-1 wheel's and a stage-2
pinion's mesh load different degrees of freedom, so the same pulse reaches the sensor through
different modes: the event's *shape* tells the two apart where its width alone often cannot. The
caller (a layer that may simulate: gearlab.data.which_templates) simulates the healthy train and a
tooth fault on each candidate gear at the record's speed and passes, per gear, the templates: the
fault's synchronous mean less the healthy one at the layout's orders (a few fault kinds each). Here,
numpy only: the record's residual on the shaft's own orders (each order's mean weighted by
the share of its power that is new, as for the tooth) is compared with each template by normalised
cross-correlation maximised over every shift of the shaft's angle (the tooth placed is not the
tooth found), its best over the gear's kinds is the gear's fit; the gear whose fit exceeds the
other's by MARGIN is named, else both (None).

The templates are only as right as the simulator's structure: records simulated with bearings 2x
stiffer or 0.3-0.5x as stiff as the templates' were named on the wrong gear of the two in up to 2/3
of cases (the width rule in up to 1/3: it follows the modes too). So where the history's mesh
harmonics spread about the simulated healthy train's by over SHAPE_DB (structure_gap) the whole shape
is not compared: the event's phases about its own gear's mesh harmonics are, which the fault and the
mesh set and the structure leaves (reference_phase_match), one gear named where its match leads by over
REFERENCE_MARGIN (by WEAK_LEAD where the structures differ by over FAR_DB), else both; a line both meshes share
that the record's structure turns against the simulated one is not read (lines_against); the gap diagnosis's
corrected description is still what to simulate from.
Figures: docs/real_data.md ("Which gear").
"""

from __future__ import annotations

import math
from decimal import ROUND_DOWN, Decimal

import numpy as np

WIDTH_BAND = (0.5, 4.0)  # orders read for the event's width, in the finer gear's tooth counts
U_FINE, U_COARSE = 0.0, 0.1  # log width / log tooth ratio naming the finer (<=), the coarser (>) gear
MIN_RATIO = 1.3  # tooth ratio of a shaft's two gears below which their widths are too alike (the phase decides)
WIDTH_Z = 10.0  # z of the shaft under which the width is too noisy to name one gear
WIDTH_LOW = 0.3  # share of the excess below half the finer gear's tooth order: a low mode's ring
MARGIN = 0.05  # fit of one gear over the other's below which both stay named
# spread (dB) of the history's mesh harmonics about the simulated healthy train's over which the events' whole
# shape is not compared, only their phases about each gear's own mesh (reference_phase_match). Development
# (benchmarks/localisation.py, two-stage box, seed 21): the simulator's own structure under noise 0.3-0.7 dB;
# bearings 0.5x as stiff 4.0-4.9 dB, there the whole shape named the 24T pinion's faults the 63T wheel's in 4
# of 10, the right gear in none; bearings 2x as stiff 5.1-6.7 dB
SHAPE_DB = 2.0
PHASE_BAND = 0.2  # orders about a gear's mesh line read for the event's phase there, in that gear's tooth counts
PHASE_MARGIN = 0.3  # cos of the mesh phase of one gear over the other's that names it (counts under MIN_RATIO)
# cos under which the other gear's line is read in anti-phase: an event that lowers its own mesh (a hand-written
# dip, tests/test_localise.py) would otherwise name the other gear; both are named instead
PHASE_ANTI = -0.5
# Where the width leaves far-apart counts undecided (a low mode rings, a weak event): the damaged tooth lifts or
# lowers its own mesh, so the event stands at that line's phase or against it at its 1st and 2nd harmonics alike
# (|cos| >= PHASE_ALIKE, one sign); the other mesh's two lines at random angles pass as well in ~30 % (both named).
# Development (a generator written outside gearlab, 22/69 + 25/74 and 14/53 + 18/59 + 23/67 boxes): a crack's
# event stood at cos -0.7..-0.95 on both of its own lines, a spall's at +0.86..+1.00, the other gear's at random
PHASE_ALIKE = 0.35
# which rule named (or left undecided) a two-gear shaft's gear, as localise's report says it
RULE_SIMULATED, RULE_WIDTH = "by the simulated events", "by the event's width"
RULE_PHASE = "by the event's mesh phase"
RULE_REFERENCE = "by the mesh phases of the simulated events"
# harmonics of each gear's mesh whose phases are compared with the simulated events', each weighted by the record's
# event-to-noise ratio there (s / (1 + s)): a harmonic the noise buries reads a random phase. Development
# (benchmarks/localisation.py, seed 41, bearings 0.5x / 2x, casing path, sensor resonance; 220 flagged records of
# the two-stage box's, the rig's and random trains' two-gear shaft), named first / both / wrong: harmonics 1-6
# unweighted by 0.15 with 3 kinds 158/45/17, with 5 (data.which_templates.KINDS) 164/41/15; 1-8 weighted by 0.05
# 184/17/19 (seed 42, not tuned on, 171 records: 131/28/12 -> 147/11/13); 10-12 no better (under the noise there)
REFERENCE_HARMONICS = 8
REFERENCE_HALF = 0.2  # orders about each mesh harmonic read, in the coarser gear's tooth counts (at least 2)
LINE_REACH = 4  # orders either side of a mesh line its event content is interpolated from (event_free_lines)
# lead of one gear's match over the other's at or under which both stay named: the shaft with both gears, which a
# scenario watching either calls its fault unless the phases lean (EVEN_LEAD; the call says the lead). Development
# (benchmarks/localisation.py, 20 trials each of the rig, the 21/63 + 24/56 box and random trains, the records
# simulated with bearings 0.5x or 2x as stiff, a casing path, or a sensor resonance at 3 kHz, zeta 0.05; seeds
# 41 + 42 / 44: 696 / 327 records of damage on a two-gear shaft's gear decided by these phases): the gear leading by
# 0.05 or less right in 21 of 38 / 8 of 16, by 0.05-0.15 in 53 of 75 / 25 of 32, by 0.15-0.3 in 115 of 130 / 64 of
# 70, by 0.3 or more in 436 of 453 / 203 of 209
REFERENCE_MARGIN = 0.15
# a lead under this names the gear weakly, said so. Seeds 41 / 42 / 44 (44 not tuned on), against 0.05 (397 / 399 /
# 377 flagged records of such damage): named first / both / wrong 341/21/35 -> 316/60/21, 353/23/23 -> 325/59/15,
# 333/21/23 -> 308/53/16 (right where one gear is named 90.7 -> 93.8 %, 93.9 -> 95.6 %, 93.5 -> 95.1 %); the damaged
# gear's own scenario calls its fault in 76.7 -> 79.7 %, 78.3 -> 80.0 %, 73.8 -> 75.2 % of records, the shaft's other
# gear's scenario too in 11.9 -> 17.2 %, 9.4 -> 15.2 %, 8.3 -> 13.5 %. By 0.3: 94.8, 97.5, 96.1 % right, the other's
# 30.1, 26.5, 26.9 %. Naming under 0.3 only where the record's own-mesh combs do not stand higher for the other gear
# split 41 + 42's leads of 0.15-0.3 into 66 of 70 right and 49 of 60, 44's into 29 of 32 and 35 of 38: no rule
WEAK_LEAD = 0.3
# where the phases leave both named (within FAR_DB) the gear they favour is listed first (lean; the call says "the first
# leads by"); over this lead only its scenario calls the flag its fault (detection_which_gear.call_of), at or under it
# the sign says little and either's does. Development (benchmarks/localisation.py as for WEAK_LEAD; seeds 41 + 42 tuned
# / 44): the favoured gear right at leads of 0.05 or less in 21 of 38 / 8 of 16, of 0.05-0.15 in 53 of 75 / 25 of 32
EVEN_LEAD = 0.05
WEAK_RIGHT = "87-91 %"  # led by REFERENCE_MARGIN to WEAK_LEAD, right (seeds 41 / 42 / 44: 61/68, 54/62, 64/70)
# structure gap (dB) over which a lead under WEAK_LEAD leaves both named: the simulated structures above read 2.0-10.2
# dB, and there the gap left the phases' figures alike (leads 0.15-0.3 right in 90 % under 4 dB, 84-91 % at 4-8 dB,
# 90 % over 8 dB); an outside generator's 13/43 + 31/67 + 41/97 box read 17.5-18 dB, its own fault form matched by no
# simulated kind (best cos 0.01-0.56): its 31T pinion's faults named its 43T wheel in 7 of 7 at leads 0.06-0.26 and
# 0.55, now both in 6; its 43T wheel's, both in 2 (leads under 0.01), the 31T in 2 (0.47, 0.48). Past 12 dB no
# simulated record tells how far the phases hold
FAR_DB = 12.0
# cos of the phase of a line both gears' meshes share to the simulated healthy line's (the shaft's angle offset and a
# common phase fitted over all the gears' mesh lines) under which the line is not read (lines_against). Development
# (benchmarks/localisation.py, the rig with bearings 2x, seeds 41, 42, 45; each record against the same record simulated
# without effects): the idler's order 96 (the 96T's 1st mesh harmonic, the 48T's 2nd) turned the event's phase by a
# median 128°, the other lines 7-35°, and its line stood 115-160° off the simulated; with that one line's phase from the
# effect-free record, named first 94 of 100 flagged (as read, 80), wrong 0 (11). At 90° (cos 0); offline 90-130° read
# alike, 60° and 150° worse. benchmarks/localisation.py, rig, the four effects, seeds 41 + 42: listed first 235 ->
# 243 of 259 flagged, wrong 12 -> 8 (bearings 2x 53 -> 58 of 65; seed 45, 2x: 27 -> 34 of 35); random 224 -> 225 of 249
LINE_AGAINST = 0.0
# Where the structure differs (gap over SHAPE_DB), first the record's own sidebands, as a gear engineer reads them: a
# local fault on a gear modulates its own mesh, so the record's excess over the history (each own order's z,
# signals.evidence.order_z, clipped at 0) rises about that gear's mesh harmonics and falls between them: periodic in
# the shaft's harmonics with the gear's tooth count. mesh_combs: the excess's correlation with cos(2π m / Z) at each
# gear's Z, in sds of the same at the other whole periods from COMB_SHORTEST to COMB_SPAN times the larger count (none
# within COMB_CLEAR of a multiple or 1/2-1/4 of either count). A gear is named at COMB_Z or more, the other's under.
# Needs no simulator: on records whose structure and fault differ from it (an outside generator: a 25/52 + 16/81 box's
# 16T chip as a dip and phase step of its mesh plus a strike) the phases matched neither gear's simulated kinds (cos
# -0.3..0.25). Development: that box's 16T chip 7.9-11.6 (26 takes, seeds 601-620 and helper H's 6; the phases named
# the 16T in 15, the 52T in 4), its 52T crack 2.6-3.3 (under: the phases decide), healthy takes up to 4.9; the
# simulator's faults under bearings 0.5x / 2x or a casing path (268 flagged, rig, 21/63 + 24/56, random trains, seed
# 41) at most 4.0: its events excite the structure broadly, not as sidebands, and the phases decide
COMB_Z = 6.0
# Where neither comb reaches COMB_Z nor a contrast names (below), one gear's comb reaching COMB_ALONE while the
# other's stays at its decoys' (COMB_QUIET or under) names the first: a fault on one gear's own mesh only.
# Development: an outside generator's 42/63 + 23/71 box heard at its output bearing (its dip modulates only its
# mesh's 1st harmonic, so the comb is weak): the 23T's faults 2.8 (the 63T's -0.6..-0.2), the 63T's 2.2-4.3 with its
# ring, 1.5-3.0 without (the 23T's -0.4..0.3); its phases against the simulated events (10.9 dB apart) named the
# 23T's 63T in 4 of 6, the 63T's 23T in 4 of 6. The simulator's faults under bearings 0.5x / 2x or a casing path
# (benchmarks/localisation.py two + random, seed 41, 64 records): their own gear's comb up to 2.44, the other's up to
# 2.35 (a 24T pinion's 63T, its own -1.62): none named by this; fresh (seed 1000, code frozen, 63 records) none named,
# the other's up to 2.40: the margin under COMB_ALONE is thin where a structure's ring lifts the other gear's comb
COMB_ALONE, COMB_QUIET = 2.5, 0.5
COMB_SHORTEST = 8
COMB_SPAN = 1.5
COMB_CLEAR = 2  # a decoy period stands more than this many harmonics off a count's multiple or fraction
RULE_SIDEBANDS = "by the sidebands about its own mesh"
# Where neither comb reaches COMB_Z: a fault whose sidebands gather about its mesh's first harmonic and fade by the
# 3rd holds too few periods for the comb (that box's 52T crack: most excess at orders 38-59 of the intermediate
# shaft, a decoy period of 56 fits it as well, comb 2.2-3.2). So, as an engineer compares a mesh's sidebands with
# the orders between its harmonics (mesh_contrasts): within CONTRAST_NEAR of each of the gear's first
# CONTRAST_HARMONICS mesh harmonics against CONTRAST_NEAR..1/2 of its count off them (orders within CONTRAST_NEAR
# of the other gear's harmonics left out), mean excess over mean excess. A gear is named where that ratio reaches
# CONTRAST_EACH at every one of them and CONTRAST_POOLED over all, its comb CONTRAST_COMB (the excess repeats at its
# own period), and the other gear's pooled ratio is under CONTRAST_OTHER. Development: the 52T crack (40 takes, seeds
# 1671-1690 and 601-620; the phases had named it in 31) least 1.84-3.54, pooled 2.77-4.33, comb 2.15-3.19, the 16T's
# pooled 0.68-1.22; the 16T chip's 52T pooled 0.55-0.75; the simulator's faults (260 records named on a two-gear
# shaft, bearings 0.5x / 2x, casing path, seed 41) never over all four: the nearest, a 24T crack's 50T (least 1.55,
# comb 1.66, pooled 1.8: a mode about its 3rd harmonic) and a 24T fault's 63T (1.79, 2.32, 6.34; the 24T's 10.0)
CONTRAST_HARMONICS = 3
CONTRAST_NEAR = 0.25  # of the gear's tooth count: its sidebands' reach about each mesh harmonic
CONTRAST_EACH = 1.5
CONTRAST_POOLED = 2.5
CONTRAST_COMB = 1.5
CONTRAST_OTHER = 1.5
CONTRAST_FLOOR = 1.0  # null sds: the least mean excess a ratio divides by
RULE_CONTRAST = "by the sidebands about its own mesh harmonics"


def residual(rec, ref, sel: np.ndarray) -> np.ndarray:
    """The record's residual at the orders *sel*: each mean weighted by the share of its power that is new."""
    X = rec.mean[sel]
    return np.clip((rec.power[sel] - ref.power[sel]) / np.maximum(np.abs(X) ** 2, 1e-300), 0, 1) * X


def fit(R: np.ndarray, D: np.ndarray, m: np.ndarray) -> float:
    """Normalised cross-correlation of two spectra at harmonics *m*, maximised over every circular
    shift of the shaft's angle: 1 for the same event anywhere in the turn."""
    norm = float(np.linalg.norm(R) * np.linalg.norm(D))
    if m.size == 0 or norm <= 0:
        return 0.0
    size = int(2 ** math.ceil(math.log2(2 * int(m.max()) + 2)))
    a, b = np.zeros(size, complex), np.zeros(size, complex)
    a[m], b[m] = R, D
    return float(np.abs(np.fft.ifft(a * np.conj(b))).max() * size / norm)


def structure_gap(ref, lay, healthy: np.ndarray) -> float:
    """Spread (dB) of the history's mesh-harmonic powers about the simulated healthy train's, less
    their mean difference (the load and the sensor's gain are not known to the simulation), over the
    harmonics that are lines of the history (localise.Spread.line): a harmonic the noise buries says
    nothing of the structure (13.5 dB of noise: 5.3-5.7 dB over every harmonic, 0.6-0.8 over the lines)."""
    sel = lay.carrier & ref.line & (ref.power > 0) & (np.abs(healthy) > 0)
    if sel.sum() < 3:
        return math.inf
    return float(np.std(10 * np.log10(ref.power[sel] / np.abs(healthy[sel]) ** 2)))


def which_by_template(
    rec, ref, lay, harmonics: tuple[np.ndarray, np.ndarray], gears, templates: dict, combs=None, contrasts=None
):
    """(the gear whose simulated event fits the record's clearly better, or None: both; the fits).
    *harmonics*: the shaft's own orders and their harmonic numbers of the shaft (localise._harmonics);
    *templates*: {"healthy": the simulated healthy mean, "gears": {gear name: [template, ...]}}.
    Where the simulator's structure differs from the history's (structure_gap over SHAPE_DB) the events'
    phases at their own mesh are compared instead (reference_phase_match). False instead of a gear: the
    events are not used (not simulated, too few clear lines to compare the structures, no phase read). *combs*:
    mesh_combs of the record, read first where the structure differs (by_sidebands; None: not read); *contrasts*: its
    mesh_contrasts, read next (by_contrasts), then a comb alone (by_sidebands at COMB_ALONE)."""
    if "healthy" not in templates:  # the description could not be simulated: said, and the width decides
        return False, {"not used": f"not simulated: {templates['not simulated']}"}
    gap = structure_gap(ref, lay, templates["healthy"])
    ev = {"structure gap dB": gap}
    if not math.isfinite(gap):
        return False, {**ev, "not used": "too few of the history's mesh harmonics stand clear of its noise"}
    if gap > SHAPE_DB:  # another structure: the sidebands about each gear's own mesh, else the phases there
        if combs:
            ev["own-mesh sidebands"] = combs
            by = by_sidebands(combs, gears)
            if by is not None:
                return by, {**ev, "rule": RULE_SIDEBANDS}
        if combs and contrasts:
            ev["own-mesh sideband contrast"] = {g: min(c["each"]) for g, c in contrasts.items()}
            by = by_contrasts(contrasts, combs, gears)
            if by is not None:
                return by, {**ev, "rule": RULE_CONTRAST}
        if combs and (by := by_sidebands(combs, gears, COMB_ALONE)) is not None:  # one comb alone over its decoys'
            return by, {**ev, "rule": RULE_SIDEBANDS}
        return _by_reference_phases(rec, ref, lay, harmonics, gears, templates, ev)
    sel, m = harmonics
    R = residual(rec, ref, sel)
    fits = {g.name: max((fit(R, t[sel], m) for t in templates["gears"].get(g.name, ())), default=0.0) for g in gears}
    (best, a), (_, b) = sorted(fits.items(), key=lambda kv: -kv[1])
    ev.update({"simulated fit": fits, "margin": MARGIN})
    if a - b <= MARGIN:
        return None, {**ev, "undecided": f"the simulated events fit alike ({a:.2f} / {b:.2f})"}
    return next(g for g in gears if g.name == best), ev


def _by_reference_phases(rec, ref, lay, harmonics, gears, templates: dict, ev: dict):
    """which_by_template's answer where the structure differs (gap over SHAPE_DB): reference_phase_match."""
    match = reference_phase_match(rec, ref, lay, lay.shafts.index(gears[0].shaft), harmonics, gears, templates)
    said = f"the simulated mesh harmonics differ from the history's by {ev['structure gap dB']:.1f} dB"
    if not match:
        return False, {**ev, "not used": f"{said}; the event's phases at the mesh harmonics not read"}
    ev = {**ev, "own-mesh phase match": match, "rule": RULE_REFERENCE}
    (best, a), (_, b) = sorted(match.items(), key=lambda kv: -kv[1])
    # the shaft named with both: either's scenario calls the flag its own, or the favoured's only (callable_gears)
    if a - b <= REFERENCE_MARGIN or (ev["structure gap dB"] > FAR_DB and a - b < WEAK_LEAD):
        why = f"{said}; the phases at each gear's own mesh lead by {lead_words(a - b)}, {_bound(ev)}"
        return None, {**ev, "undecided": why}
    return next(g for g in gears if g.name == best), ev


def _bound(ev: dict) -> str:
    """The bound a lead that left both gears named is under, in words."""
    far = ev["structure gap dB"] > FAR_DB
    return f"under {WEAK_LEAD:g} at a structure gap over {FAR_DB:g} dB" if far else f"not over {REFERENCE_MARGIN:g}"


def decoy_periods(teeth: list[int]) -> list[int]:
    """The whole periods (shaft harmonics) mesh_combs reads a comb's null at: COMB_SHORTEST to COMB_SPAN times the
    largest of *teeth*, none within COMB_CLEAR of a count's multiple (up to 4 times) or its half,
    third or quarter."""
    near = [t * k for t in teeth for k in (1, 2, 3, 4)] + [t / k for t in teeth for k in (2, 3, 4)]
    top = int(COMB_SPAN * max(teeth))
    return [p for p in range(COMB_SHORTEST, top + 1) if all(abs(p - n) > COMB_CLEAR for n in near)]


def _comb(m: np.ndarray, excess: np.ndarray, period: float) -> float:
    """Correlation of *excess* (at harmonics *m*) with cos(2π m / *period*): 1 for an excess all at its multiples."""
    x, c = excess - excess.mean(), np.cos(2 * np.pi * m / period)
    norm = math.sqrt(float(np.sum(x**2) * np.sum(c**2)))
    return float(np.sum(x * c)) / norm if norm > 0 else 0.0


def mesh_combs(z: np.ndarray, harmonics: tuple[np.ndarray, np.ndarray], gears) -> dict:
    """{gear name: the record's excess correlation with the gear's mesh comb, in sds of the decoy periods'} ({}: not
    read: fewer than 5 decoys, no excess). *z*: each order's z (signals.evidence.order_z); *harmonics*: the shaft's
    own orders and their harmonic numbers (localise._harmonics)."""
    sel, m = harmonics
    excess = np.clip(z[sel], 0, None)
    decoys = decoy_periods([g.teeth for g in gears])
    if len(decoys) < 5 or m.size < 3 or not excess.any():
        return {}
    null = np.array([_comb(m, excess, p) for p in decoys])
    if null.std() <= 0:
        return {}
    return {g.name: (_comb(m, excess, g.teeth) - float(null.mean())) / float(null.std()) for g in gears}


def by_sidebands(combs: dict, gears, least: float = COMB_Z):
    """The one gear whose mesh comb (mesh_combs) reaches *least*, the other's under it, or where *least* is
    COMB_ALONE, the other's COMB_QUIET or under (None: neither, or both)."""
    over = [g for g in gears if combs.get(g.name, -math.inf) >= least]
    quiet = least == COMB_Z or all(combs.get(g.name, math.inf) <= COMB_QUIET for g in gears if g not in over)
    return over[0] if len(over) == 1 and quiet else None


def weak_lead(evidence: dict) -> float | None:
    """The lead of the named gear's own-mesh phase match over the other's where under WEAK_LEAD, else None."""
    match = sorted(evidence.get("own-mesh phase match", {}).values(), reverse=True)
    if evidence.get("rule") != RULE_REFERENCE or evidence.get("undecided") or len(match) < 2:  # "": decided
        return None
    return match[0] - match[1] if match[0] - match[1] < WEAK_LEAD else None


def undecided_lead(evidence: dict) -> float | None:
    """The lead of the own-mesh phase match where it left both gears named (_by_reference_phases), else None."""
    match = sorted(evidence.get("own-mesh phase match", {}).values(), reverse=True)
    if evidence.get("rule") != RULE_REFERENCE or not evidence.get("undecided") or len(match) < 2:
        return None
    return match[0] - match[1]


def lean(evidence: dict) -> str | None:
    """The gear the own-mesh phases favour where they left both gears named (undecided_lead), the structures within
    FAR_DB (past it an outside generator's phases favoured the wrong gear in 7 of 7); else None: the description's
    order."""
    if undecided_lead(evidence) is None or evidence["structure gap dB"] > FAR_DB:
        return None
    match = evidence["own-mesh phase match"]
    return max(match, key=match.get)


def favoured_first(gears: list, evidence: dict) -> list:
    """A two-gear shaft's *gears* (localise.Gear) the gear lean() names first, else as given."""
    first = lean(evidence)
    return sorted(gears, key=lambda g: g.name != first) if first else list(gears)


def callable_gears(ev: dict) -> list[str]:
    """The gears of a flagged shaft (as localise.ShaftEvidence.describe()) whose scenario calls the flag its fault: the
    one named; both where undecided, only the one the phases favour (lean()) where it leads by over EVEN_LEAD."""
    evidence = ev.get("stage_evidence") or {}
    lead = undecided_lead(evidence)
    first = ev.get("which") or (lean(evidence) if lead is not None and lead > EVEN_LEAD else None)
    return [first] if first else list(ev["gears"])


IN_ENVELOPE = " (in the envelope: a strike whose ring's phase wanders from turn to turn)"  # a call's words (weakly)


def weakly(ev: dict) -> str:
    """ ", weakly over <the shaft's other gear> (phase lead L)" of a shaft's evidence (as
    localise.ShaftEvidence.describe()) whose gear is named by a phase lead under WEAK_LEAD; " (undecided by the mesh
    phases: lead L, ...)" of one whose two gears the phases left named (undecided_lead); else "": the call says it as
    the evidence does (an outside lab's burst on a 34T pinion was 'other damage: intermediate gear 65T' at 0.21)."""
    if ev.get("seen") == "envelope":  # read in the envelope (signals.envelope_sync), not the averages: said so
        return IN_ENVELOPE
    evidence = ev.get("stage_evidence") or {}
    if not ev.get("which"):
        lead = undecided_lead(evidence) if len(ev.get("gears", ())) == 2 else None
        if lead is None:
            return ""
        if not lean(evidence):
            return f" (undecided by the mesh phases: lead {lead_words(lead)}, {_bound(evidence)})"
        even = f"not over {EVEN_LEAD:g}: either as likely" if lead <= EVEN_LEAD else _bound(evidence)
        return f" (undecided by the mesh phases: the first leads by {lead_words(lead)}, {even})"
    lead = weak_lead(evidence)
    if lead is None:
        return ""
    return f", weakly over {' / '.join(g for g in ev['gears'] if g != ev['which'])} (phase lead {lead_words(lead)})"


def lead_words(lead: float) -> str:
    """A lead under WEAK_LEAD in two decimals, cut, not rounded: 0.2996 rounded read 'a phase lead of 0.30,
    under 0.3' (a three-stage box's which-gear line)."""
    return f"{Decimal(repr(lead)).quantize(Decimal('0.01'), rounding=ROUND_DOWN):.2f}"


def mesh_contrasts(z: np.ndarray, harmonics: tuple[np.ndarray, np.ndarray], gears) -> dict:
    """{gear name: {"each": the record's mean excess within CONTRAST_NEAR of each of the gear's first
    CONTRAST_HARMONICS mesh harmonics over that in the flanks between them (at least CONTRAST_FLOOR), "pooled": the
    same over all of them}} ({}: fewer than two harmonics read for a gear). *z*, *harmonics*: as mesh_combs."""
    sel, m = harmonics
    excess = np.clip(z[sel], 0, None)
    out = {}
    for g in gears:
        # the other gear's sidebands about its own harmonics are its evidence, not this gear's flanks
        clear = np.ones(m.size, bool)
        for o in (o for o in gears if o is not g):
            clear &= np.abs(m - o.teeth * np.round(m / o.teeth)) > CONTRAST_NEAR * o.teeth
        each, near_sum, flank_sum = [], 0.0, 0.0
        for k in range(1, CONTRAST_HARMONICS + 1):
            d = np.abs(m - k * g.teeth)
            near = clear & (d <= CONTRAST_NEAR * g.teeth)
            flank = clear & (d > CONTRAST_NEAR * g.teeth) & (d <= g.teeth / 2)
            if near.sum() < 2 or flank.sum() < 2:
                continue
            # flanks of noise alone read as one null sd: a faint excess over none is no contrast (flagged healthy takes'
            # quiet 52T read 2-9 unfloored, 0.1-0.5 floored)
            a, b = float(excess[near].mean()), max(float(excess[flank].mean()), CONTRAST_FLOOR)
            each.append(a / b)
            near_sum, flank_sum = near_sum + a, flank_sum + b
        if len(each) < 2:
            return {}
        out[g.name] = {"each": each, "pooled": near_sum / flank_sum}
    return out


def by_contrasts(contrasts: dict, combs: dict, gears):
    """The one gear whose sidebands stand over its flanks by CONTRAST_EACH at each of its first mesh harmonics and
    CONTRAST_POOLED over all, its comb at least CONTRAST_COMB, the other's pooled under CONTRAST_OTHER (None: neither,
    or both; mesh_contrasts)."""

    def named(g) -> bool:
        return (
            min(contrasts[g.name]["each"]) >= CONTRAST_EACH
            and contrasts[g.name]["pooled"] >= CONTRAST_POOLED
            and combs.get(g.name, -math.inf) >= CONTRAST_COMB
            and all(o.name in contrasts and contrasts[o.name]["pooled"] < CONTRAST_OTHER for o in gears if o is not g)
        )

    over = [g for g in gears if g.name in contrasts and named(g)]
    return over[0] if len(over) == 1 else None


def fit_words(evidence: dict) -> str:
    """The simulated events' evidence in words, for localise.which_line ("" without it)."""
    if "own-mesh sidebands" in evidence:
        said = " / ".join(f"{g.split(' (')[0]} {v:.1f}" for g, v in evidence["own-mesh sidebands"].items())
        names = f"{COMB_Z:g} names, or {COMB_ALONE:g} the other's {COMB_QUIET:g} or under"
        combs = f"sidebands about each gear's own mesh (sds over other periods, {names}) {said}, "
        rest = {k: v for k, v in evidence.items() if k != "own-mesh sidebands"}
        return combs + ("" if evidence.get("rule") == RULE_SIDEBANDS else fit_words(rest))
    if "own-mesh sideband contrast" in evidence:
        said = " / ".join(f"{g.split(' (')[0]} {v:.2f}" for g, v in evidence["own-mesh sideband contrast"].items())
        first = f"about each gear's first {CONTRAST_HARMONICS} mesh harmonics over the orders between them"
        bounds = f"least ratio, {CONTRAST_EACH:g} names, the other's under {CONTRAST_OTHER:g}"
        words = f"sidebands {first} ({bounds}) {said}, "
        rest = {k: v for k, v in evidence.items() if k != "own-mesh sideband contrast"}
        return words + ("" if evidence.get("rule") == RULE_CONTRAST else fit_words(rest))
    if "own-mesh phase match" in evidence:
        said = (f"{g.split(' (')[0]} {v:.2f}" for g, v in evidence["own-mesh phase match"].items())
        return "own-mesh phases matched to the simulated events' (mean cos) " + " / ".join(said) + ", "
    if "simulated fit" in evidence:
        return (
            "simulated event's fit "
            + " / ".join(f"{g.split(' (')[0]} {v:.2f}" for g, v in evidence["simulated fit"].items())
            + ", "
        )
    return f"simulated events not used ({evidence['not used']}), " if "not used" in evidence else ""


def phase_words(evidence: dict) -> str:
    """The mesh phases (mesh_phases) in words, for localise.which_line ("" without them, or where the
    simulated events decided, not the phase)."""
    if evidence.get("rule") in (RULE_SIMULATED, RULE_REFERENCE, RULE_SIDEBANDS, RULE_CONTRAST):
        return ""
    if "mesh phases" in evidence:  # two harmonics (_by_phases_alike)
        said = (f"{g.split(' (')[0]} {a:.2f}, {b:.2f}" for g, (a, b) in evidence["mesh phases"].items())
        return "mesh phase cos at 1st, 2nd harmonic " + " / ".join(said) + ", "
    if "mesh phase" not in evidence:
        return ""
    said = (f"{g.split(' (')[0]} {v:.2f}" for g, v in evidence["mesh phase"].items())
    return "mesh phase cos " + " / ".join(said) + ", "


def envelope(rec, ref, sel: np.ndarray, m: np.ndarray, size: int) -> np.ndarray:
    """The shaft's residual envelope at *size* points per turn: its harmonics *m* (orders *sel*) each
    weighted by the share of its power that is new (clip(Δ / |X̄|², 0, 1))."""
    X = rec.mean[sel]
    gain = np.clip((rec.power[sel] - ref.power[sel]) / np.maximum(np.abs(X) ** 2, 1e-300), 0, 1)
    spec = np.zeros(size, complex)
    np.add.at(spec, m, gain * X)
    return np.abs(np.fft.ifft(spec)) ** 2  # analytic: positive orders only


def _peak(X: np.ndarray, m: np.ndarray) -> float:
    """The shaft's angle (rad) at which the residual *X* at harmonics *m* peaks (envelope())."""
    size = int(2 ** math.ceil(math.log2(8 * int(m.max()) + 1)))
    spec = np.zeros(size, complex)
    np.add.at(spec, m, X)
    return 2 * math.pi * int(np.argmax(np.abs(np.fft.ifft(spec)))) / size


def _phasor(X, m, peak: float, lines: np.ndarray, lay, shaft: int, z: int, half: float, least: int):
    """exp(iψ) of the event *X* (at harmonics *m*) within *half* orders of the shaft's harmonic *z* (a
    mesh line), demodulated at *peak*, against the line *lines* holds there; None where it is not read
    (no line at the layout's orders, fewer than *least* orders about it, no content)."""
    x = z * float(lay.shaft_orders[shaft])
    line = np.flatnonzero(lay.carrier & (np.abs(lay.orders - x) < 1e-9 * x))
    near = np.abs(m - z) <= half
    if line.size == 0 or near.sum() < least or abs(lines[line[0]]) == 0:
        return None
    event = np.sum(X[near] * np.exp(1j * (m[near] - z) * peak)) / lines[line[0]]
    return None if event == 0 else event / abs(event)


def mesh_phases(rec, ref, lay, shaft: int, harmonics: tuple[np.ndarray, np.ndarray], gears, harmonic: int = 1) -> dict:
    """{gear name: cos ψ} for the gears of a two-gear shaft ({}: not read). ψ: the phase of the event's
    content within PHASE_BAND of the gear's mesh line (its tooth count in the shaft's harmonics; *harmonic*
    times it: that harmonic of the mesh), demodulated at the event's peak, against the record's own line
    there. A tooth that meshes softer deepens its own mesh's cycle while in mesh: in phase with that line
    (ψ near 0; a stiffness lost, against it), whatever the structure, as both pass it at one frequency; the
    other mesh's line stands at any angle to the event (which tooth). No simulation: the description's
    tooth counts suffice."""
    sel, m = harmonics
    if m.size < 3:
        return {}
    R = residual(rec, ref, sel)
    peak = _peak(R, m)
    out = {}
    for g in gears:
        p = _phasor(R, m, peak, rec.mean, lay, shaft, harmonic * g.teeth, PHASE_BAND * g.teeth, 3)
        if p is None:
            return {}
        out[g.name] = float(p.real)
    return out


def own_mesh_phasors(X, lines, lay, shaft: int, m: np.ndarray, gear, half: float) -> np.ndarray:
    """exp(iψ_h) of the event *X* about its gear's mesh harmonics h = 1 … REFERENCE_HARMONICS (_phasor;
    nan: not read), demodulated at the event's own peak."""
    peak = _peak(X, m)
    out = [_phasor(X, m, peak, lines, lay, shaft, h * gear.teeth, half, 2) for h in range(1, REFERENCE_HARMONICS + 1)]
    return np.array([np.nan if p is None else p for p in out], complex)


def event_free_lines(X, m: np.ndarray, lines, lay, shaft: int, gears) -> np.ndarray:
    """*lines* (a record's means) with each of the gears' mesh harmonics h Z (h = 1 … REFERENCE_HARMONICS) less the
    event *X*'s content there, interpolated between the nearest of its orders *m* on each side (within LINE_REACH),
    demodulated at its peak: a strong event's own content at a mesh line turns the line it is compared with."""
    out = np.array(lines, complex)
    peak = _peak(X, m)
    at = dict(zip(m.tolist(), X * np.exp(1j * m * peak)))
    for g in gears:
        for h in range(1, REFERENCE_HARMONICS + 1):
            z = h * g.teeth
            x = z * float(lay.shaft_orders[shaft])
            line = np.flatnonzero(lay.carrier & (np.abs(lay.orders - x) < 1e-9 * x))
            lo = next((k for k in range(z - 1, z - LINE_REACH - 1, -1) if k in at), None)
            hi = next((k for k in range(z + 1, z + LINE_REACH + 1) if k in at), None)
            if line.size == 0 or lo is None or hi is None:
                continue
            event = (at[lo] * (hi - z) + at[hi] * (z - lo)) / (hi - lo) * np.exp(-1j * z * peak)
            out[line[0]] = lines[line[0]] - event  # once where the two gears' harmonics share a line (96T, 2 x 48T)
    return out


def own_mesh_weights(X, noise, m: np.ndarray, gear, half: float) -> np.ndarray:
    """Per harmonic of own_mesh_phasors, s / (1 + s) of the event's power within *half* orders of it over the
    noise power of those orders' means (*noise*): near 1 where the event stands clear, near 0 where noise sets
    the phase."""
    out = []
    for h in range(1, REFERENCE_HARMONICS + 1):
        near = np.abs(m - h * gear.teeth) <= half
        s = float(np.sum(np.abs(X[near]) ** 2)) / max(float(np.sum(noise[near])), 1e-300)
        out.append(s / (1 + s))
    return np.array(out)


def lines_against(lines, healthy, lay, shaft: int, gears) -> list[int]:
    """The lines both gears' meshes share (shaft harmonics h Z of each, h = 1 … REFERENCE_HARMONICS: the rig's 96T and
    48T at 96, 192, 288, 384) whose record line (*lines*) stands over 90° off the simulated healthy line (*healthy*)
    once the shaft's angle offset and a common phase are fitted over all the gears' mesh lines (the record's tacho mark
    need not sit at the simulator's zero; LINE_AGAINST). Such a line is the sum of two meshes' lines, each through its
    own dynamics and path: where the structure turns it that far from the simulator's, the mix differs and neither
    mesh's event stands at the simulated phase to it. A line of one mesh passes with its event (the other lines'
    phases turned 7-35° there; leaving out any line turned that far cost random trains: 1 of 34 flagged)."""
    zs, psi = [], []
    for z in sorted({h * g.teeth for g in gears for h in range(1, REFERENCE_HARMONICS + 1)}):
        x = z * float(lay.shaft_orders[shaft])
        line = np.flatnonzero(lay.carrier & (np.abs(lay.orders - x) < 1e-9 * x))
        if line.size and abs(healthy[line[0]]) > 0 and abs(lines[line[0]]) > 0:
            zs.append(z)
            psi.append(lines[line[0]] / healthy[line[0]] / abs(lines[line[0]] / healthy[line[0]]))
    if len(zs) < 3:
        return []
    z, psi = np.array(zs), np.array(psi)
    step = math.gcd(*zs)
    delta = np.linspace(0, 2 * math.pi / step, 16 * int(z.max()) // step + 16, endpoint=False)
    fits = (psi[None, :] * np.exp(-1j * z[None, :] * delta[:, None])).sum(axis=1)
    k = int(np.argmax(np.abs(fits)))
    off = psi * np.exp(-1j * z * delta[k]) * np.conj(fits[k]) / abs(fits[k])
    first, second = ({h * g.teeth for h in range(1, REFERENCE_HARMONICS + 1)} for g in gears[:2])
    return [int(a) for a, o in zip(z, off) if o.real < LINE_AGAINST and a in first & second]


def reference_phase_match(rec, ref, lay, shaft: int, harmonics, gears, templates: dict) -> dict:
    """{gear name: the mean cos between the record's event phases about the gear's own mesh harmonics and
    those of the gear's simulated event (own_mesh_phasors), each harmonic weighted by the record's event-to-
    noise ratio there (own_mesh_weights), the best over its fault kinds} ({}: fewer than two harmonics read for
    a gear). A tooth fault changes its own mesh while in mesh, so about that mesh's harmonics h Z the event
    stands at a phase to the line set by the fault and the mesh: the same for every tooth (h Z 2π n / Z is whole
    turns), and the same through another structure, whose response turns a line and the orders within
    REFERENCE_HALF of it alike (noise-free, bearings 0.5x: cos 0.9-1.0 to the simulator's at most harmonics);
    about the other gear's mesh the phase moves with the tooth. So the sequence over h is compared, not the
    whole shape, which follows the structure's modes. The record's lines are read less the event's own content
    there (event_free_lines), as the simulated event's are against the simulated healthy lines; a harmonic at a line
    both meshes share that the structure turns against the simulated one (lines_against) is left out where two
    others are read."""
    sel, m = harmonics
    if m.size < 3:
        return {}
    half = max(2.0, REFERENCE_HALF * min(g.teeth for g in gears))
    R = residual(rec, ref, sel)
    lines = event_free_lines(R, m, rec.mean, lay, shaft, gears)
    against = lines_against(lines, templates["healthy"], lay, shaft, gears)
    out = {}
    for g in gears:
        mine = own_mesh_phasors(R, lines, lay, shaft, m, g, half)
        weight = own_mesh_weights(R, rec.noise[sel], m, g, half)
        kept = weight * ~np.isin(np.arange(1, REFERENCE_HARMONICS + 1) * g.teeth, against)
        weight = kept if np.count_nonzero(kept * ~np.isnan(mine)) >= 2 else weight
        best = None
        for t in templates["gears"].get(g.name, ()):
            sim = own_mesh_phasors(t[sel], templates["healthy"], lay, shaft, m, g, half)
            ok = ~np.isnan(mine) & ~np.isnan(sim)
            if ok.sum() >= 2 and weight[ok].sum() > 0:
                cos = float(np.sum(weight[ok] * np.real(mine[ok] * np.conj(sim[ok]))) / weight[ok].sum())
                best = cos if best is None else max(best, cos)
        if best is None:
            return {}
        out[g.name] = best
    return out


def two_harmonic_phases(rec, ref, lay, shaft: int, harmonics: tuple[np.ndarray, np.ndarray], gears) -> dict:
    """{gear name: [cos ψ at its mesh's 1st harmonic, at its 2nd]} (mesh_phases; {}: either not read)."""
    first, second = (mesh_phases(rec, ref, lay, shaft, harmonics, gears, h) for h in (1, 2))
    return {g: [first[g], second[g]] for g in first} if first and second else {}


def _by_phases_alike(phases: dict, gears):
    """The one gear whose two mesh harmonics' cos share a sign, each at least PHASE_ALIKE (None: neither, or both)."""
    alike = [g for g in gears if g.name in phases and min(map(abs, phases[g.name])) >= PHASE_ALIKE]
    alike = [g for g in alike if phases[g.name][0] * phases[g.name][1] > 0]
    return alike[0] if len(alike) == 1 else None


def _by_phase(phases: dict, gears):
    """(the gear whose mesh phase leads the other's by PHASE_MARGIN, the other's not under PHASE_ANTI, or
    None; the lead)."""
    if len(phases) != 2:
        return None, 0.0
    (a, pa), (_, pb) = sorted(phases.items(), key=lambda kv: -kv[1])
    clear = pa - pb > PHASE_MARGIN and pb >= PHASE_ANTI
    return (next(g for g in gears if g.name == a) if clear else None), pa - pb


def which_by_width(
    rec, ref, harmonics: tuple[np.ndarray, np.ndarray], gears, z: float, phases: dict | None = None, both=None
):
    """(the gear of a two-gear shaft the event's length names, or None: both; the evidence) from the
    shaft's own orders and their harmonic numbers (*harmonics*); *phases*: mesh_phases, which name the
    gear of tooth counts under MIN_RATIO; *both*: two_harmonic_phases, which name the gear of counts
    further apart where the width does not (_by_phases_alike). See gearlab.signals.localise's docstring,
    "Which gear on a shaft"."""
    which, ev = _width(rec, ref, harmonics, gears, z, phases)
    ratio = max(g.teeth for g in gears) / min(g.teeth for g in gears)
    # the width abstained (a low mode rings, or too noisy), not read between the gears: a strong event there
    # (a simulated 27T pinion's, z 13,419) shakes its shaft and lifts the other mesh's lines alike (79T 0.98, 0.99)
    abstained = ev.get("low-order share", 0.0) > WIDTH_LOW or (z < WIDTH_Z and ev.get("u", 0.0) > U_FINE)
    if which is not None or not both or ratio < MIN_RATIO or not abstained:  # too alike: _by_phase
        return which, ev
    said = " / ".join(f"{g.split(' (')[0]} {a:.2f}, {b:.2f}" for g, (a, b) in both.items())
    by = _by_phases_alike(both, gears)
    if by is None:
        why = f"{ev['undecided']}; mesh phase cos at 1st, 2nd harmonic {said}: not one alike"
        return None, {**ev, "undecided": why}
    return by, {**{k: v for k, v in ev.items() if k != "undecided"}, "mesh phases": both, "rule": RULE_PHASE}


def _width(rec, ref, harmonics, gears, z: float, phases: dict | None):
    fine, coarse = sorted(gears, key=lambda g: -g.teeth)
    ratio = fine.teeth / coarse.teeth
    expect = {fine.name: ratio**-0.2, coarse.name: ratio**0.4}
    ev: dict = {"event width": f"pitches of the {fine.teeth}T {fine.role}", "expected": expect}
    phases = (phases or {}) if ratio < MIN_RATIO else {}  # the width tells gears further apart: no phase read
    by, lead = _by_phase(phases, gears)
    if phases:
        ev["mesh phase"] = phases
    if ratio < MIN_RATIO and by is not None:
        return by, {**ev, "rule": RULE_PHASE}
    sel, m = harmonics
    sel = sel.copy()
    excess = np.clip(rec.power[sel] - ref.power[sel], 0, None)
    upto = m <= WIDTH_BAND[1] * fine.teeth
    low = float(excess[upto & (m < fine.teeth / 2)].sum() / max(excess[upto].sum(), 1e-300))
    keep = upto & (m >= WIDTH_BAND[0] * fine.teeth)
    sel[np.flatnonzero(sel)[~keep]] = False
    m, excess = m[keep], excess[keep]
    if ratio < MIN_RATIO:
        said = f" and the mesh phases not clear (lead {lead:.2f})" if phases else ""
        return None, {**ev, "undecided": f"tooth counts {fine.teeth} and {coarse.teeth} too alike{said}"}
    if m.size < 3 or not excess.any():
        return None, {**ev, "undecided": "no new power in the shaft's orders"}
    size = int(2 ** math.ceil(math.log2(16 * WIDTH_BAND[1] * fine.teeth)))
    env = envelope(rec, ref, sel, m, size)
    d = ((np.arange(size) - int(np.argmax(env)) + size // 2) % size - size // 2) / size * fine.teeth
    near = np.abs(d) <= 4  # within 4 pitches of the peak, above the envelope's floor
    e = np.clip(env[near] - np.median(env), 0, None)
    w = math.sqrt(float(np.sum(e * d[near] ** 2) / max(float(e.sum()), 1e-300)))
    u = math.log(max(w, 1e-9)) / math.log(ratio)
    centre = float(np.sum(excess * m) / max(excess.sum(), 1e-300)) / fine.teeth
    ev.update({"width": w, "u": u, "low-order share": low, "centre": centre})
    if z < WIDTH_Z and u > U_FINE:  # noise widens an event, never narrows it: a narrow one stands
        return None, {**ev, "undecided": f"z {z:.1f} under {WIDTH_Z:g}: the width is too noisy"}
    if low > WIDTH_LOW:
        return None, {**ev, "undecided": f"{low:.0%} of the excess below order {fine.teeth / 2:g}: a low mode rings"}
    if U_FINE < u <= U_COARSE:
        return None, {**ev, "undecided": f"width between the two gears' ({U_FINE:g} < u <= {U_COARSE:g})"}
    return (fine if u <= U_FINE else coarse), ev
