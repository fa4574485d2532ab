"""Scenario kind `detection`: a fault found in measured records without a single real fault label.

The source is a simulator with healthy and faulty revolutions; the target is a list of
measured text records, each with a *role*: ``history`` (the unlabelled healthy past a method
may learn from and fix its threshold on) or ``test`` (scored only). Every method is trained
and thresholded from the source and the history alone; the test records come in only once
the method's model and threshold are fixed, and their labels only when the figures are made.

    [source]              a dataset preset with overrides (as in [[datasets]]), healthy + faults
    [corrected]           effects (as in [[datasets]]) that make the corrected simulator (e.g. what
                          `gearlab gap` fitted), tsa (revolutions averaged per sample), draws (noise
                          draws of each sample, one at random per batch row), history_units (what of
                          the history its methods train on), label: every method is trained on both
                          sources, the corrected one's rows "<method> (<label>)"
    [target]              vibration, tacho, pulses_per_rev, sensitivity, fs, positive, files = [
                            { path, role = "history" | "test", label, condition (optional) }, ...]
    [[methods]]           adapters (as in a transfer scenario); none listed: every registered
                          adapter that can learn without target labels
    [classical]           indicators (fm4, na4, tooth_energy, tooth_sync, pinion_sync) of the input-shaft TSA,
                          mesh_orders, shaft_orders, sidebands, slow_shafts (tooth_sync), shafts (pinion_sync:
                          the other shafts, {name = period in input revolutions})
    [detection]           blocks (revolutions per record-level TSA), false_alarm (asked of the threshold),
                          threshold (records | pooled), seeds (trainings per network method),
                          history_fit (all | crossed: each history record scored by a training
                          that left it out)
    [network], [protocol] as in a transfer scenario (one training per method and condition, k = 0)

Records are grouped by operating *condition*: the file's ``condition`` when given, else by
tacho speed (``conditions_of``: within 5 %, a test record with the history of nearest speed).
Each condition has its own history: standardisation
(eq. 2.112), the alignment of records that start at different tacho marks, the methods'
calibration and thresholds. A condition with test records but no history is refused.

Units scored: every revolution (``revolution``) and the TSA of consecutive blocks of
``b`` revolutions (``record<b>``). The threshold of a method and unit is fixed on the
method's scores of the history's units of that kind (record-level history units: TSAs of
sliding windows), for a unit of a *new* record: ``threshold = "records"`` (default) the
``1 - false_alarm`` predictive quantile of a one-way random-effects model, record effect plus
within-record spread (``record_effects``); ``"pooled"`` the quantile of a Gumbel law fitted by
its quartiles to the pooled units (blind to take-to-take variation). With ``seeds`` > 1 every
network is trained that many times (repetitions 0 …); the method's score is the median over
its members of each member's score standardised by its own history model, thresholded alike.

Output: results.jsonl (one record per condition x source x method: the history and test scores,
thresholds under both rules, the history model; an ensemble's members one record per seed besides),
scores.csv (file, unit, index, method, score, decision), summary.json, table.md/table.csv
(AUC, detection and false-alarm rates per condition, unit and method; below them what each learned
method learned of the simulator: the ROC AUC of its scores of the source's held-out revolutions,
beside the bound of that source (source_bound: the likelihood ratio that knows its noise-free
fault shapes), and its training time) and report.html; with
pinion_sync, shafts.csv (file, unit, index, the shaft each test unit's localised damage is put on,
or "nothing", and each shaft's strength) and its counts per label in table.md.
"""

from __future__ import annotations

import csv
import io
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from ..confined import Confined
from ..data.cache import load_or_build
from ..data.chain import Chain
from ..data.recordings import cut_recording
from ..data.spec import POINTS, DatasetSpec
from ..data.textzip import align_to
from ..errors import GearlabInputError, shown
from ..events import Event, UnitProgress
from ..learn import protocol as chapter5  # train_method looked up at call time (a test spies on it)
from ..learn.bounds import bayes_scores
from ..learn.config import Calibration, check_length
from ..learn.history import gumbel_quantile
from ..learn.protocol import Method, Protocol, StateStore, each_draw, fault_score, shared_state
from ..learn.schedule import two_phases
from ..params import did_you_mean
from ..parts import scoring, training
from ..parts.measured import ROLES, Target, TargetFile, target_spec
from ..parts.training import CALIBRATION, METHOD_KEYS, NETWORK, TRAINING, check_training
from ..registry import get_registry
from ..runs import RunDir
from ..scenario import Key, Scenario, Table, in_range, location, one_of
from ..settings import shrunk
from ..signals import Standardiser
from ..signals.indicators import (
    DEFAULT_INDICATORS,
    INDICATORS,
    band_limited,
    difference_signal,
    fm4,
    na4,
    na4_reference,
    pinion_sync,
    shaft_parts,
    shaft_strengths,
    sync_shares,
    tooth_energy,
    tooth_reference,
    tooth_sync,
    window_gram,
    window_reference,
)
from . import record_effects
from .common import DATASET_TABLE, class_sizes, device_of, executor_for, no_compare, simulated_spec, sized

SOURCE_SPEEDS = ("records", "source")
INPUTS = ("difference", "revolution")
# Sliding TSA windows of the history: a new window every block/HISTORY_STRIDES revolutions.
HISTORY_STRIDES = 10
# Fewest history units of a kind that a threshold may be fitted to (by their quartiles).
MIN_HISTORY_UNITS = 8
# Records without a 'condition' whose tacho speeds lie within this fraction share a history.
SPEED_GROUP = 0.05
THRESHOLDS = ("records", "pooled")
# How a network's history scores are made: "all" -- trained on every history record and scoring them
# (in-sample); "crossed" -- one training per history record left out, which scores it (a new record's
# scores, as the test records' are)
HISTORY_FITS = ("all", "crossed")
CORRECTED_HISTORY = ("revolution", "tsa")
MAX_SEEDS = 20
MAX_DRAWS = 64

TABLES = {
    "source": Table(DATASET_TABLE.keys, required=True),
    "corrected": Table(
        {
            "effects": Key(list, [], doc="effects added to the [source]'s: the corrected simulator (none: plain only)"),
            "label": Key(str, "corrected", doc="the corrected source's name in the method rows"),
            "tsa": Key(
                int,
                0,
                in_range(0, 1000),
                "a corrected sample is the TSA of this many simulated revolutions, each with its own "
                "noise (the revolutions of a record-level unit); 0: one revolution",
            ),
            "draws": Key(
                int,
                1,
                in_range(1, MAX_DRAWS),
                "noise draws of each corrected sample; a network trains on one of them at random per "
                "batch row, so it cannot learn the noise of one draw by heart (docs/real_data.md)",
            ),
            "history_units": Key(
                str,
                "revolution",
                one_of(*CORRECTED_HISTORY),
                "what the corrected source's methods see of the history in training: 'revolution' (the "
                "history revolutions, as the plain source's) or 'tsa' (the history's TSAs of `tsa` "
                "revolutions, sliding as its units are: the target at the corrected sample's averaging)",
            ),
        }
    ),
    "target": Table(
        {
            "vibration": Key((int, str), doc="vibration column: 0-based index or header name"),
            "tacho": Key((int, str), doc="tacho column: 0-based index or header name"),
            "pulses_per_rev": Key(int, 1, in_range(1, 10_000), "tacho pulses per input-shaft revolution"),
            "sensitivity": Key(
                (int, float, str), None, doc="sensor sensitivity, e.g. '10 mV/g' (a number: V per m/s²)"
            ),
            "gain": Key((int, float, str), None, doc="volts per file unit (integer counts; WAV: at full scale)"),
            "fs": Key((int, float, str), None, doc="sampling rate, e.g. '66666.67 Hz', when a file carries none"),
            "transient": Key(str, "none", doc="'stats' drops a start-up transient, 'none' keeps every revolution"),
            "positive": Key(str, "fault", doc="the label of records with the fault to detect; every other is negative"),
            "files": Key(list, doc="[{file, role = 'history' | 'test', label, condition (optional)}, ...]"),
        },
        required=True,
    ),
    "network": NETWORK,
    "methods": Table(METHOD_KEYS, array=True),
    "classical": Table(
        {
            "indicators": Key(
                list, list(DEFAULT_INDICATORS), doc=f"classical indicators of the TSA: {', '.join(INDICATORS)}"
            ),
            "mesh_orders": Key(
                list,
                [],
                doc="mesh orders of the TSA's shaft (default: the source pinion's teeth); the first is the "
                "tooth count of the gear on that shaft (the localised indicators' windows)",
            ),
            "shaft_orders": Key(int, 2, in_range(0, 100), "low shaft orders removed with the mesh harmonics"),
            "sidebands": Key(int, 1, in_range(0, 100), "sidebands either side of each mesh harmonic (FM4)"),
            "slow_shafts": Key(
                list,
                [],
                doc="periods, in whole input revolutions, of the other shafts whose localised damage "
                "tooth_sync is to tell from the input pinion's (a shaft turning q times slower, q whole, "
                "brings a tooth back to one input angle every q revolutions; the PHM rig: [3, 5])",
            ),
            "shafts": Key(
                dict,
                {},
                doc="the other shafts a localised fault may turn with, {name = period in whole input "
                "revolutions} (the PHM rig: {idler = 3, output = 5}): pinion_sync calls a pinion fault "
                "only for localised content of the input TSA that no tooth of these shafts explains (what "
                "each shaft's TSA holds beyond the input TSA's copies under a smooth modulation of its turn)",
            ),
        }
    ),
    "detection": Table(
        {
            "blocks": Key(list, [10, 30], doc="revolutions per record-level TSA unit"),
            "false_alarm": Key(float, 0.01, in_range(1e-6, 0.5), "share of healthy history units above the threshold"),
            "input": Key(
                str,
                "difference",
                doc="what the learned methods see: 'difference' (revolution or TSA less its "
                "shaft and mesh orders, as FM4's) or 'revolution' (as it is)",
            ),
            "points": Key(
                int,
                POINTS,
                in_range(64, POINTS),
                "samples per revolution the learned methods see: the order spectrum of what they see cut "
                f"below points / 2 ({POINTS}, the records' grid: all of it)",
            ),
            "threshold": Key(
                str,
                "records",
                doc="'records': predictive quantile for a new record's unit (record effect + within-record "
                "spread, one-way random effects); 'pooled': Gumbel quantile of the pooled history units",
            ),
            "history_fit": Key(
                str,
                "all",
                one_of(*HISTORY_FITS),
                "how a network's history scores are made: 'all' (trained on every history record, "
                "which it then scores) or 'crossed' (one training per history record left out of its "
                "training rows; that record's units are scored by it, the test units by all of them)",
            ),
            "seeds": Key(
                int,
                1,
                in_range(1, MAX_SEEDS),
                "trainings per network method and condition; more than 1: the median of their "
                "history-standardised scores",
            ),
            "source_speed": Key(
                str,
                "records",
                doc="'records': the source simulated at each condition's history speed "
                "(to 1 Hz); 'source': at the [source]'s own speed",
            ),
        }
    ),
    "protocol": Table({**TRAINING, **CALIBRATION}),
}
OVERRIDES: tuple[str, ...] = ()  # no key is set from the command line


# --- building the scenario ---------------------------------------------------------------


def methods_of(entries: list[dict], where: str) -> tuple[Method, ...]:
    """The [[methods]]; none listed: every registered adapter that learns without target labels
    (source-trained, domain-adaptation and detector methods), in the registry's order."""
    registry = get_registry()
    if not entries:
        entries = [
            {"adapter": name, "supervised": False, "params": {}}
            for name in registry.names("adapter")
            if registry.get("adapter", name).train_on != "target"
            and "unsupervised" in registry.get("adapter", name).supervision
        ]
    out = []
    for i, entry in enumerate(entries):
        at = location(where, "methods", index=i)
        m = training.method(entry, at)
        if m.supervised:
            raise GearlabInputError(f"{at} key 'supervised': the measured target has no labels a method may use")
        if registry.get("adapter", m.adapter).train_on == "target":
            raise GearlabInputError(
                f"{at} key 'adapter': '{m.adapter}' trains on labelled target data; the measured history has none"
            )
        if m in out:
            raise GearlabInputError(f"{at}: {m.label} is listed twice")
        out.append(m)
    return tuple(out)


def build(scenario: Scenario) -> dict:
    t = scenario.tables
    path = scenario.path
    source = simulated_spec(t["source"], location(path, "source"), scenario.base)
    corrected = corrected_spec(t, location(path, "corrected"), scenario.base, source)
    sizes = class_sizes(source, location(path, "source"))
    if not sizes["healthy"] or sum(sizes.values()) == sizes["healthy"]:
        raise GearlabInputError(
            f"{location(path, 'source')}: the source needs healthy and faulty revolutions (has {sizes})"
        )
    _, pair, _ = source.check_model(location(path, "source"))
    target = target_spec(t["target"], location(path, "target"), scenario.base)
    c = t["classical"]
    for name in c["indicators"]:
        if name not in INDICATORS:
            raise GearlabInputError(
                f"{location(path, 'classical', 'indicators')}: unknown indicator "
                f"{shown(name)}{did_you_mean(str(name), INDICATORS)}; known: {', '.join(INDICATORS)}"
            )
    orders = c["mesh_orders"] or [pair.Z1]
    if not all(isinstance(o, int) and not isinstance(o, bool) and 1 <= o <= 1000 for o in orders):
        raise GearlabInputError(
            f"{location(path, 'classical', 'mesh_orders')}: expected whole orders 1 … 1000, got {shown(orders)}"
        )
    slow = c["slow_shafts"]
    if not all(isinstance(q, int) and not isinstance(q, bool) and 2 <= q <= 1000 for q in slow):
        raise GearlabInputError(
            f"{location(path, 'classical', 'slow_shafts')}: expected whole numbers of input revolutions "
            f"2 … 1000 (a shaft turning q times slower than the input), got {shown(slow)}"
        )
    shafts = c["shafts"]
    if not all(isinstance(q, int) and not isinstance(q, bool) and 2 <= q <= 1000 for q in shafts.values()):
        raise GearlabInputError(
            f"{location(path, 'classical', 'shafts')}: expected {{name = whole number of input revolutions "
            f"2 … 1000 a turn}} (a shaft turning q times slower than the input), got {shown(shafts)}"
        )
    if "input" in shafts or "nothing" in shafts:
        raise GearlabInputError(
            f"{location(path, 'classical', 'shafts')}: 'input' and 'nothing' are taken (the input shaft and "
            f"no shaft); name the other shafts, e.g. {{idler = 3, output = 5}}"
        )
    blocks = t["detection"]["blocks"]
    if not all(isinstance(b, int) and not isinstance(b, bool) and 2 <= b <= 10_000 for b in blocks) or len(
        set(blocks)
    ) != len(blocks):
        raise GearlabInputError(
            f"{location(path, 'detection', 'blocks')}: expected distinct whole numbers of "
            f"revolutions >= 2, got {shown(blocks)}"
        )
    check_training(t, path)
    p = t["protocol"]
    protocol = Protocol(
        methods=methods_of(t["methods"], str(path)),
        network=t["network"]["name"],
        dropout=t["network"]["dropout"],
        ks=(0,),
        repetitions=1,
        **{key: p[key] for key in TRAINING},
        device=device_of(scenario),
        calibration=Calibration(**{key: p[key] for key in CALIBRATION}),
    )
    protocol.calibration.check(str(path))
    points = t["detection"]["points"]
    try:  # a network that cannot take that many samples is refused now, not in the middle of a run
        check_length(protocol.network, points)
    except GearlabInputError as e:
        raise GearlabInputError(f"{location(path, 'detection', 'points')}: {points} is too few: {e}") from None
    if p["batch"] > p["target_train"]:
        raise GearlabInputError(
            f"{location(path, 'protocol', 'batch')}: {p['batch']} is larger than target_train = {p['target_train']}"
        )
    n = sum(sizes.values())  # the source's samples, known from its spec: refused now, not after simulating
    if n - max(1, round(protocol.val_fraction * n)) < p["batch"]:
        raise GearlabInputError(
            f"{location(path, 'protocol', 'batch')}: {p['batch']} is larger than the source training set "
            f"({n - max(1, round(protocol.val_fraction * n))} of the {n} samples of '{source.name}')"
        )
    if t["detection"]["source_speed"] not in SOURCE_SPEEDS:
        raise GearlabInputError(
            f"{location(path, 'detection', 'source_speed')}: expected one of "
            f"{', '.join(SOURCE_SPEEDS)}, got {shown(t['detection']['source_speed'])}"
        )
    if t["detection"]["threshold"] not in THRESHOLDS:
        raise GearlabInputError(
            f"{location(path, 'detection', 'threshold')}: expected one of {', '.join(THRESHOLDS)}, got "
            f"{shown(t['detection']['threshold'])}{did_you_mean(str(t['detection']['threshold']), THRESHOLDS)}"
        )
    if t["detection"]["input"] not in INPUTS:
        raise GearlabInputError(
            f"{location(path, 'detection', 'input')}: expected one of {', '.join(INPUTS)}, got "
            f"{shown(t['detection']['input'])}"
        )
    return {
        "source": source,
        "corrected": corrected,
        "corrected_label": t["corrected"]["label"],
        # the corrected source's history training rows: TSAs of its `tsa` revolutions, or revolutions
        "corrected_history": t["corrected"]["tsa"] if t["corrected"]["history_units"] == "tsa" else 0,
        "corrected_draws": t["corrected"]["draws"],
        "target": target,
        "protocol": protocol,
        "source_speed": t["detection"]["source_speed"],
        "input": t["detection"]["input"],
        "points": points,
        "classical": {
            "indicators": tuple(c["indicators"]),
            "mesh_orders": tuple(orders),
            "shaft_orders": c["shaft_orders"],
            "sidebands": c["sidebands"],
            "slow_shafts": tuple(slow),
            "shafts": tuple(shafts.items()),
        },
        "blocks": tuple(blocks),
        "false_alarm": t["detection"]["false_alarm"],
        "threshold": t["detection"]["threshold"],
        "seeds": t["detection"]["seeds"],
        "history_fit": t["detection"]["history_fit"],
    }


def corrected_spec(t: dict, where: str, base: Path, source: DatasetSpec) -> DatasetSpec | None:
    """The [source] with the [corrected] effects after its own (None: no effects given)."""
    extra = t["corrected"]["effects"]
    if not extra:
        return None
    label = t["corrected"]["label"]
    if not label or not all(ch.isalnum() or ch in "-_" for ch in label):
        raise GearlabInputError(
            f"{where} key 'label': expected a short name of letters, digits, - or _, got {shown(label)}"
        )
    entry = {**t["source"], "effects": list(t["source"].get("effects") or []) + list(extra)}
    if t["corrected"]["tsa"]:  # noise drawn on every revolution, then averaged as a record unit is
        entry.update(tsa=True, revolutions=t["corrected"]["tsa"])
    spec = simulated_spec(entry, where, base)
    # draws: every sample D times, each with its own seed (the builder's duplicates; D healthy
    # samples for each one), in runs of D rows that source_split folds into (n, D, L)
    draws = t["corrected"]["draws"]
    spec = spec.with_(duplicates=spec.duplicates * draws, healthy=spec.healthy * draws)
    # a name of its own for the reports and conditions.json (the cache key hashes the spec anyway)
    name = f"{source.name}+{label}"
    return spec.with_(name=name, domain=name)


def describe(scenario: Scenario) -> str:
    spec = scenario.spec
    files = spec["target"].files
    n_hist = sum(f.role == "history" for f in files)
    names = [m.adapter for m in spec["protocol"].methods] + list(spec["classical"]["indicators"])
    if spec.get("corrected") is not None:
        extra = ", ".join(name for name, _ in spec["corrected"].effects[len(spec["source"].effects) :])
        names += [f"{m.adapter} ({spec['corrected_label']}: + {extra})" for m in spec["protocol"].methods]
    return (
        f"{sized(spec['source'])} -> {len(files)} measured records ({n_hist} history, {len(files) - n_hist} "
        f"test); methods: {', '.join(names)}; units: revolution, " + ", ".join(f"record{b}" for b in spec["blocks"])
    )


def quick(scenario: Scenario) -> None:
    """Smoke run: short training."""
    p = scenario.spec["protocol"]
    scenario.spec["protocol"] = shrunk(p, prime_epochs=20, baseline_epochs=30, min_epochs=30, max_epochs=40)


# --- the records -------------------------------------------------------------------------


def conditions_of(files: list[TargetFile], speeds: dict[str, float]) -> dict[str, str]:
    """{file path: condition}: the file's own 'condition', else its speed group. History records
    without one are grouped by tacho speed (a group spans SPEED_GROUP of its slowest record's
    speed; named by its median to 1 Hz); a test record joins the group of nearest speed, or one
    of its own (which has no history) when none lies within SPEED_GROUP of it."""
    out = {f.path: f.condition for f in files if f.condition}
    groups: list[list[float]] = []
    for v in sorted(speeds[f.path] for f in files if not f.condition and f.role == "history"):
        if groups and v <= groups[-1][0] * (1 + SPEED_GROUP):
            groups[-1].append(v)
        else:
            groups.append([v])
    centres = [float(np.median(g)) for g in groups]
    for f in files:
        if f.condition:
            continue
        v = speeds[f.path]
        near = min(range(len(centres)), key=lambda i: abs(centres[i] - v)) if centres else None
        if near is not None and abs(centres[near] - v) <= SPEED_GROUP * centres[near]:
            v = centres[near]
        out[f.path] = f"{v:.0f} Hz"
    return out


def tsa_units(revs: np.ndarray, block: int, stride: int | None = None) -> np.ndarray:
    """TSAs of *block* consecutive revolutions: non-overlapping blocks (stride = block), or sliding
    windows moved by *stride* revolutions."""
    stride = stride or block
    starts = range(0, revs.shape[0] - block + 1, stride)
    if not len(starts):
        return np.empty((0, revs.shape[1]), dtype=revs.dtype)
    return np.stack([revs[s : s + block].mean(axis=0) for s in starts]).astype(revs.dtype)


def _window(unit: str) -> tuple[int, int]:
    """(revolutions per unit, stride of the history's sliding windows) of a unit kind."""
    if unit == "revolution":
        return 1, 1
    b = int(unit.removeprefix("record"))
    return b, max(1, b // HISTORY_STRIDES)


def longest_tsa(units) -> str | None:
    """The record-level unit kind of the most revolutions among *units* ("record30" of
    "revolution", "record10", "record30"); None when there is none."""
    records = [u for u in dict.fromkeys(units) if u != "revolution"]
    return max(records, key=lambda u: _window(u)[0]) if records else None


def unit_sets(revs: np.ndarray, blocks, history: bool) -> dict[str, np.ndarray]:
    """{unit name: rows} of one record."""
    out = {"revolution": revs}
    for b in blocks:
        out[f"record{b}"] = tsa_units(revs, b, max(1, b // HISTORY_STRIDES) if history else None)
    return out


def read_target(target: Target, blocks, on_event, where: str = "[target] key 'files'") -> dict[str, dict]:
    """{condition: {"history": [(file, revolutions)], "test": [...], "speeds": {...}}}: every record
    read, standardised against its condition's history and aligned to its first history record.
    Only the records' signals are used here (no label)."""
    conditions: dict[str, dict] = {}
    on_event(Event("stage", stage="records", total=len(target.files), message="measured records"))
    records = {}
    for i, f in enumerate(target.files):
        records[f.path] = target.read(f)
        on_event(Event("advance", stage="records", done=i + 1, total=len(target.files)))
    speeds = {p: r.speed_hz for p, r in records.items()}
    named = conditions_of(list(target.files), speeds)
    for f in target.files:
        cond = conditions.setdefault(named[f.path], {"history": [], "test": [], "speeds": {}})
        cond[f.role].append((f, records[f.path].revolutions))
        cond["speeds"][f.path] = speeds[f.path]
    for name, cond in conditions.items():
        if not cond["history"]:
            files = ", ".join(f.path for f, _ in cond["test"])
            raise GearlabInputError(
                f"{where}: condition '{name}' ({files}) has no history record; "
                "each condition needs its own healthy history (give 'condition' to group files)"
            )
        # The highest order every history record holds, where the acquisition's anti-alias filter
        # leaves data (as the gap kind compares).
        cond["max_order"] = min(
            Chain(fs=records[f.path].fs, speed=speeds[f.path]).max_order for f, _ in cond["history"]
        )
        standardiser = Standardiser.fit(np.concatenate([r for _, r in cond["history"]]))
        reference = standardiser.apply(cond["history"][0][1]).mean(axis=0)
        cond["standardiser"], cond["reference"] = standardiser, reference  # kept for gearlab score
        cond["shifts"] = {}
        for role in ROLES:
            aligned = []
            for f, revs in cond[role]:
                shift, revs = align_to(reference, standardiser.apply(revs), target.pulses_per_rev)
                cond["shifts"][f.path] = shift
                aligned.append((f, revs))
            cond[role] = aligned
        per_record = [unit_sets(r, blocks, True) for _, r in cond["history"]]
        cond["history_units"] = {u: np.concatenate([s[u] for s in per_record]) for u in per_record[0]}
        # which history units come from which record (in order), and how many are independent:
        # the threshold models the record-to-record variation (record_effects)
        cond["history_records"] = {
            u: [(len(s[u]), record_effects.independent_units(len(s[u]), *_window(u))) for s in per_record]
            for u in per_record[0]
        }
        for u, X in cond["history_units"].items():
            if len(X) < MIN_HISTORY_UNITS:  # a threshold is fitted to their quartiles
                longest = max(len(r) for _, r in cond["history"])
                raise GearlabInputError(
                    f"{where}: the history of condition '{name}' gives {len(X)} '{u}' units "
                    f"(its longest record has {longest} revolutions); expected at least "
                    f"{MIN_HISTORY_UNITS}: longer records, or shorter [detection] blocks"
                )
        cond["test_units"] = {f.path: unit_sets(r, blocks, False) for f, r in cond["test"]}
    return conditions


# --- the units of work -------------------------------------------------------------------


def _to_lists(scores: dict) -> dict:
    return {k: (_to_lists(v) if isinstance(v, dict) else [float(s) for s in v]) for k, v in scores.items()}


def is_detector(method: Method) -> bool:
    """A method with no network: a model built from the training arrays (matched_filter, likelihood_ratio)."""
    return get_registry().get("adapter", method.adapter).train_on == "detector"


def seeds_of(method: Method, seeds: int) -> tuple:
    """The seeds a method is trained with: (None,) for one training (repetition 0, the record
    named after the method) and for a detector (no network, nothing random); else 0 … seeds-1,
    each a member of the method's ensemble."""
    if seeds == 1 or is_detector(method):
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


def train_unit(task: tuple) -> dict:
    """One method at one condition (one seed of it), in this process or a worker: trained on the
    source and the history's training revolutions, then its scores of the history units (for the
    threshold) and, only now, of the test units."""
    import torch

    from ..learn.training import pick_device  # here, not at the top: start-up time

    (
        protocol,
        method,
        variant,
        condition,
        seed,
        fold,
        (Xs, ys, Xv, yv),
        train,
        history_units,
        test_units,
        states,
        rule,
    ) = task
    started = time.perf_counter()
    torch.set_num_threads(1)
    device = pick_device(protocol.device)
    unit = unit_name(condition, method, seed, variant, fold)
    point = aligned_to_a_point(protocol, method, Xs, ys)
    # Against a single point the domain discrepancy falls by a few per cent every 25 epochs for as
    # long as the training lasts: the stopping rule's "it has
    # stopped moving" never holds, and no epoch after the ramp is nearer convergence than the
    # ramp's end. Such a training ends there, at the first epoch its kept model may come from.
    trained = replace(protocol, max_epochs=protocol.min_epochs) if point else protocol
    with UnitProgress(states.root, unit) as progress:

        def report(epoch: int, history) -> None:
            progress(f"epoch {epoch + 1}")

        model, history, _ = chapter5.train_method(
            trained,
            method,
            (Xs, ys),
            (Xv[:, 0] if Xv.ndim == 3 else Xv, yv),  # one draw decides when to stop: an epoch's cost
            (train, np.zeros(len(train), dtype=np.int64)),
            seed or 0,  # the repetition: its own torch seed and draws
            0,
            StateStore(states),
            device,
            report,
        )
    # what a network learned of the simulator, from training data only: its scores of the source's
    # held-out revolutions, every draw of them (0.5: it does not tell the simulated fault from
    # healthy). A detector is built in the target's frame (the history's reference, the path to
    # it), where a source revolution means nothing.
    held_out = None if is_detector(method) else fault_score(model, Xv.reshape(-1, Xv.shape[-1]), device)
    y_held = np.repeat(yv, len(held_out) // len(yv)) if held_out is not None else yv
    # the model is fixed: the history's units fix the thresholds, then the test units are scored
    hist = {u: fault_score(model, X, device) for u, X in history_units.items()}
    fixed = rule.decide(hist)
    test = {path: {u: fault_score(model, X, device) for u, X in units.items()} for path, units in test_units.items()}
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
        "history_scores": _to_lists(hist),
        **fixed,
        "test_scores": _to_lists(test),
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
    if get_registry().get("adapter", method.adapter).train_on != "joint" or protocol.calibration.source_noise != "off":
        return False
    rows = Xs[np.asarray(ys) == 0] if protocol.calibration.alignment == "healthy" else Xs
    rows = np.asarray(rows).reshape(-1, rows.shape[-1])  # draws, if any, are rows too
    return len(rows) > 0 and float(np.ptp(rows, axis=0).max()) <= 1e-6 * float(np.abs(rows).max())


@dataclass(frozen=True)
class Rule:
    """How a threshold is fixed from the history's unit scores alone ([detection] threshold and
    false_alarm), with the history's record structure: {unit: [(units, independent units) per
    history record, in the order of the concatenated scores]}."""

    how: str
    false_alarm: float
    records: dict

    def groups(self, u: str, scores) -> list[np.ndarray]:
        """The history's *scores* of unit kind *u*, one array per history record."""
        counts = [n for n, _ in self.records[u]]
        return np.split(np.asarray(scores, dtype=np.float64), np.cumsum(counts)[:-1])

    def model(self, u: str, scores, keep=None) -> record_effects.RecordEffects:
        """The random-effects model (record effect + within-record spread) of the history's *scores*
        of unit kind *u*, over the records *keep* (default: all)."""
        groups = self.groups(u, scores)
        keep = range(len(groups)) if keep is None else keep
        return record_effects.fit(
            [groups[i] for i in keep],
            1.0 - self.false_alarm,
            [self.records[u][i][1] for i in keep],
            [record_effects.overlap_dof(self.records[u][i][0], *_window(u)) for i in keep],
        )

    def models(self, history_scores: dict) -> dict[str, record_effects.RecordEffects]:
        """{unit: the random-effects model of its scores}."""
        return {u: self.model(u, s) for u, s in history_scores.items()}

    def decide(self, history_scores: dict) -> dict:
        """The record's "thresholds" (by this rule), the history models and both rules' thresholds
        (so a run shows what the other rule would have called)."""
        models = self.models(history_scores)
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
        "history_scores": _to_lists(hist),
        **rule.decide(hist),
        "test_scores": _to_lists(test),
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
        "history_scores": _to_lists(hist),
        **rule.decide(hist),
        "test_scores": _to_lists(test),
        **trained_together(folds),
    }


def method_name(m: Method, variant: str = "") -> str:
    return m.adapter + "".join(f", {k}={v}" for k, v in m.shown) + (f" ({variant})" if variant else "")


def classical_record(name: str, condition: str, cond: dict, classical: dict, rule: Rule) -> dict:
    """A classical indicator's scores: computed on the TSA units, its reference (NA4's variance,
    tooth_energy's, tooth_sync's and pinion_sync's windows) from the history's units of the same kind;
    tooth_sync and pinion_sync read each unit's own revolutions (their pairs), not only their TSA.
    pinion_sync's record also names, per test unit, the shaft its localised damage turns with
    (shaft_attribution)."""
    orders, shaft, sidebands = classical["mesh_orders"], classical["shaft_orders"], classical["sidebands"]
    history = cond["history_units"]
    # the history's units of each kind, one array per history record (in the order of cond["history"])
    per_record = {
        u: np.split(X, np.cumsum([n for n, _ in cond["history_records"][u]])[:-1]) for u, X in history.items()
    }
    periods = [q for _, q in classical["shafts"]]
    # tooth_sync: each unit's synchronous window shares from its own revolutions, {path: {unit: shares}};
    # pinion_sync: each unit's parts per shaft (shaft_parts), flattened to (units, shafts x windows)
    shares = {}
    if name in ("tooth_sync", "pinion_sync"):
        for role in ROLES:
            for f, revs in cond[role]:
                shares[f.path] = {}
                gram = window_gram(revs, orders[0], orders, shaft, sidebands)  # one per record, every unit kind
                for u in history:
                    block, stride = _window(u)[0], _window(u)[1] if role == "history" else _window(u)[0]
                    if name == "tooth_sync":
                        shares[f.path][u] = sync_shares(
                            revs, block, stride, orders[0], orders, classical["slow_shafts"], shaft, sidebands, gram
                        )
                    else:
                        parts = shaft_parts(revs, block, stride, orders[0], orders, periods, shaft, sidebands, gram)
                        shares[f.path][u] = parts.reshape(len(parts), -1)
    # the localised indicators' within-record spread: that of independent units, from sliding windows
    dofs = {u: [record_effects.overlap_dof(len(X), *_window(u)) for X in groups] for u, groups in per_record.items()}
    reference = {}
    if name == "na4":  # the denominator: the mean residual variance of the history's units
        reference = {u: na4_reference(X, orders, shaft) for u, X in history.items()}
    elif name == "tooth_energy":  # per tooth window: the records' mean and within-record spread
        reference = {
            u: tooth_reference(groups, orders[0], orders, shaft, sidebands, dofs[u]) for u, groups in per_record.items()
        }
    elif name in ("tooth_sync", "pinion_sync"):
        reference = {u: window_reference([shares[f.path][u] for f, _ in cond["history"]], dofs[u]) for u in history}

    def parts(path: str, u: str) -> np.ndarray:  # pinion_sync: (units, 1 + shafts, windows)
        return shares[path][u].reshape(-1, 1 + len(periods), orders[0])

    def strengths(path: str, u: str) -> np.ndarray:  # pinion_sync: (units, 1 + shafts)
        return shaft_strengths(parts(path, u), periods, reference[u])

    def score(X: np.ndarray, u: str, path: str) -> np.ndarray:
        if name == "fm4":
            return fm4(X, orders, shaft, sidebands)
        if name == "tooth_energy":
            return tooth_energy(X, orders, reference[u], shaft, sidebands)
        if name == "tooth_sync":  # the units' own revolutions (X is their TSA)
            return tooth_sync(shares[path][u], reference[u])
        if name == "pinion_sync":
            return pinion_sync(parts(path, u), periods, reference[u])
        return na4(X, orders, reference[u], shaft)

    hist = {
        u: np.concatenate([score(X, u, f.path) for (f, _), X in zip(cond["history"], groups)])
        for u, groups in per_record.items()
    }
    if name == "pinion_sync":
        # the input TSA's localised content that no slow shaft's tooth explains is held to the threshold
        # of the input TSA's localised content (the input strength) in the healthy history: what a new
        # healthy record's own would pass 1 % of the time, whatever a slow shaft explains of it; and
        # above 0
        fixed = rule.decide(
            {u: np.concatenate([strengths(f.path, u)[:, 0] for f, _ in cond["history"]]) for u in history}
        )
    else:
        fixed = rule.decide(hist)  # fixed before any test unit is scored
    extra = {}
    if name == "pinion_sync":
        fixed["thresholds"] = {u: max(t, 0.0) for u, t in fixed["thresholds"].items()}
        fixed["thresholds_by_rule"] = {
            how: {u: max(t, 0.0) for u, t in by.items()} for how, by in fixed["thresholds_by_rule"].items()
        }
    test = {p: {u: score(X, u, p) for u, X in units.items()} for p, units in cond["test_units"].items()}
    if name == "pinion_sync":
        extra["shafts"] = shaft_attribution(
            ("input", *(n for n, _ in classical["shafts"])),
            {u: np.concatenate([strengths(f.path, u) for f, _ in cond["history"]]) for u in history},
            {f.path: {u: strengths(f.path, u) for u in history} for f, _ in cond["test"]},
            rule,
            (test, fixed["thresholds"]),
        )
    return {
        "unit": f"{condition}/{name}",
        "condition": condition,
        "method": name,
        "adapter": None,
        "history_scores": _to_lists(hist),
        **fixed,
        "test_scores": _to_lists(test),
        **extra,
    }


def shaft_attribution(names: tuple, history: dict, test: dict, rule: Rule, pinion: tuple) -> dict:
    """Which shaft each test unit's localised damage turns with. A unit whose pinion fault is called
    (*pinion* = (pinion_sync's test scores {path: {unit: scores}}, its thresholds): the input TSA holds
    localised content that no slow shaft's tooth explains) is put on the input shaft, whatever else is
    there. Otherwise: a tooth on any shaft whose period is a whole number of input revolutions leaves an
    image in the input TSA (1/q of its size), so a unit has localised damage when the input shaft's
    strength (indicators.shaft_strengths) lies above its threshold — fixed by *rule* on the history's
    input strengths, as any score's — and it is put on the largest of pinion_sync's score (the input's
    own) and the slow shafts' strengths; else "nothing" (a bearing's impulses, noise). *history*:
    {unit: (history units, shafts)}, *test*: {path: {unit: (units, shafts)}}."""
    thresholds = {u: rule.decide({u: h[:, 0]})["thresholds"][u] for u, h in history.items()}
    scores, called_above = pinion

    def named(s: np.ndarray, own: list, u: str) -> list[str]:  # a shaft the unit is too short to see is none
        out = []
        for row, p in zip(np.where(np.isnan(s), -np.inf, s), own):
            if p > called_above[u]:  # a called pinion fault is the input shaft's, whatever else is there
                out.append(names[0])
            elif row[0] <= thresholds[u]:
                out.append("nothing")
            else:
                out.append(names[int(np.argmax([p, *row[1:]]))])
        return out

    return {
        "names": list(names),
        "thresholds": thresholds,
        "named": {p: {u: named(s, scores[p][u], u) for u, s in units.items()} for p, units in test.items()},
        "strengths": {p: {u: s.tolist() for u, s in units.items()} for p, units in test.items()},
    }


def learned_input(spec: dict, max_order: int | None = None):
    """What the learned methods see of a revolution or TSA (source and target alike): as it is,
    or its difference signal (shaft orders, mesh harmonics and their sidebands removed, as for
    FM4), which leaves what one tooth adds and drops what every tooth and each build share; at
    [detection] points per revolution (band_limited: a network's step costs in proportion), and
    no order above *max_order*: the condition's records hold none there (read_target), while a
    simulated revolution, and the sensor noise added to it, reach order POINTS / 2."""
    points = spec["points"]
    if spec["input"] == "revolution":
        return lambda X: band_limited(X, points, max_order)
    c = spec["classical"]
    return lambda X: band_limited(
        difference_signal(X, c["mesh_orders"], c["shaft_orders"], c["sidebands"]).astype(np.float32),
        points,
        max_order,
    )


def source_for(source: DatasetSpec, cond: dict, how: str) -> DatasetSpec:
    """The source simulated at the condition's speed (the median of its history records' tacho
    speeds, to 1 Hz), or as given."""
    if how == "source":
        return source
    speed = float(round(np.median([cond["speeds"][f.path] for f, _ in cond["history"]])))
    return source.with_(speed_hz=speed, name=f"{source.name}@{speed:g}Hz", domain=f"{source.name}@{speed:g}Hz")


def history_training_rows(cond: dict, protocol: Protocol, condition: str, tsa: int = 0) -> np.ndarray:
    """The history revolutions a network trains on: target_train of them at random (seeded); with
    *tsa* > 1 the history's TSAs of *tsa* revolutions instead (sliding as its history units are)."""
    if tsa > 1:
        revs = np.concatenate([tsa_units(r, tsa, max(1, tsa // HISTORY_STRIDES)) for _, r in cond["history"]])
    else:
        revs = np.concatenate([r for _, r in cond["history"]])
    rng = np.random.default_rng([protocol.seed, sum(map(ord, condition))])
    take = rng.permutation(len(revs))[: protocol.target_train]
    return revs[np.sort(take)]


def folds_of(history_fit: str, cond: dict, condition: str, path) -> tuple:
    """The history records left out one at a time (history_fit = "crossed"), or (None,): one
    training on them all."""
    if history_fit == "all":
        return (None,)
    if len(cond["history"]) < 2:
        files = ", ".join(f.path for f, _ in cond["history"])
        raise GearlabInputError(
            f"{location(path, 'detection', 'history_fit')}: 'crossed' leaves out one history record at a "
            f"time and needs at least two per condition; condition '{condition}' has one ({files}); "
            "expected 'all' or another history record"
        )
    return tuple(range(len(cond["history"])))


def trained_on(cond: dict, fold: int | None) -> dict:
    """The condition as a training sees it: its history without record *fold* (history_fit =
    "crossed"), or whole."""
    if fold is None:
        return cond
    return {**cond, "history": [h for i, h in enumerate(cond["history"]) if i != fold]}


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


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    spec = scenario.spec
    protocol: Protocol = spec["protocol"]
    with executor_for(scenario) as executor:
        conditions = read_target(spec["target"], spec["blocks"], on_event, f"{scenario.path}: [target] key 'files'")
        folds = {c: folds_of(spec["history_fit"], cond, c, scenario.path) for c, cond in conditions.items()}
        for c, cond in conditions.items():
            band = f"no shaft order above {cond['max_order']} (the records' band)"
            on_event(Event("log", message=f"{c}: the learned methods see {band}"))
        # the sources: "" the [source], and the corrected simulator when [corrected] gives effects
        variants = {"": spec["source"]}
        if spec.get("corrected") is not None:
            variants[spec["corrected_label"]] = spec["corrected"]
        specs = {
            (c, v): source_for(source, cond, spec["source_speed"])
            for c, cond in conditions.items()
            for v, source in variants.items()
        }
        for c, cond in conditions.items():  # before any work: every training has a batch of history rows
            for k in folds[c]:
                for v in variants:
                    n = len(
                        history_training_rows(trained_on(cond, k), protocol, c, spec["corrected_history"] if v else 0)
                    )
                    if n < protocol.batch:
                        left = "" if k is None else f" with history record {cond['history'][k][0].path} left out"
                        raise GearlabInputError(
                            f"{scenario.path}: [protocol] key 'batch': {protocol.batch} is larger than the {n} "
                            f"history rows condition '{c}' trains on{left}; expected a smaller batch"
                        )
        for c, cond in conditions.items():
            cond["source"] = specs[(c, "")].name
            cond["sources"] = {v or "source": specs[(c, v)].name for v in variants}
        built = list(dict.fromkeys(specs.values()))
        draws = {s: spec["corrected_draws"] if v else 1 for (_, v), s in specs.items()}  # per sample
        on_event(Event("stage", stage="datasets", total=len(built), message="source datasets"))
        sources = {}
        for i, s in enumerate(built):
            sources[s], _ = load_or_build(s, executor, on_event)
            on_event(Event("advance", stage="datasets", done=i + 1, total=len(built)))
            n = len(sources[s].X) // draws[s]
            if n - max(1, round(protocol.val_fraction * n)) < protocol.batch:
                raise GearlabInputError(
                    f"{scenario.path}: [protocol] key 'batch': {protocol.batch} is larger than "
                    f"the source training set of '{s.name}'"
                )
        on_event(Event("log", message="the sources' bounds: their noise-free twins and likelihood ratios"))
        bounds = {key: source_bound(s, sources[s], protocol, draws[s], executor, on_event) for key, s in specs.items()}
        records = {r["unit"]: r for r in run.records()}
        rules = {
            c: Rule(spec["threshold"], spec["false_alarm"], cond["history_records"]) for c, cond in conditions.items()
        }
        for name, cond in conditions.items():
            for indicator in spec["classical"]["indicators"]:
                if f"{name}/{indicator}" not in records:
                    run.append(classical_record(indicator, name, cond, spec["classical"], rules[name]))
        shown = {c: learned_input(spec, cond["max_order"]) for c, cond in conditions.items()}
        splits = {
            (c, v): tuple(
                a if a.ndim == 1 else each_draw(shown[c], a)
                for a in source_split(sources[specs[(c, v)]], protocol, draws[specs[(c, v)]])
            )
            for c, v in specs
        }
        # the units every training of a condition scores, as the learned methods see them (made once)
        units_seen = {
            c: (
                {u: shown[c](X) for u, X in cond["history_units"].items()},
                {p: {u: shown[c](X) for u, X in units.items()} for p, units in cond["test_units"].items()},
            )
            for c, cond in conditions.items()
        }
        members = {
            (c, v, m): seeds_of(m, spec["seeds"]) for c in conditions for v in variants for m in protocol.methods
        }
        todo = [(c, v, m, seed, k) for (c, v, m), seeds in members.items() for seed in seeds for k in folds[c]]
        pending = [(c, v, m, seed, k) for c, v, m, seed, k in todo if unit_name(c, m, seed, v, k) not in records]
        # one folder of shared states (primings, source models) per condition and source
        folders = {(c, v): f"condition{i}" + (f"-{v}" if v else "") for i, c in enumerate(conditions) for v in variants}

        def state_file(unit: tuple) -> Path | None:
            c, v, m, seed, _ = unit
            state = shared_state(m, seed or 0, 0, protocol)
            return None if state is None else run.file("states", folders[(c, v)], f"{state}.pt")

        phases = two_phases(pending, state_file)
        on_event(Event("stage", stage="runs", total=len(todo), message=f"{len(todo)} trainings"))
        finished = len(todo) - len(pending)

        def record_done(_: int, record: dict) -> None:
            nonlocal finished
            run.append(record)
            records[record["unit"]] = record
            finished += 1
            on_event(Event("log", message=f"{record['unit']} trained"))
            on_event(Event("advance", stage="runs", done=finished, total=len(todo)))

        for phase in phases:
            tasks = []
            for c, v, m, seed, k in phase:
                cond = conditions[c]
                states = run.file("states", folders[(c, v)])
                tasks.append(
                    (
                        protocol,
                        m,
                        v,
                        c,
                        seed,
                        k,
                        splits[(c, v)],
                        shown[c](
                            history_training_rows(
                                trained_on(cond, k), protocol, c, spec["corrected_history"] if v else 0
                            )
                        ),
                        *units_seen[c],
                        states,
                        rules[c],
                    )
                )
            executor.map(train_unit, tasks, on_done=record_done, gpu=protocol.device != "cpu")
        for (c, v, m), seeds in members.items():
            for seed in seeds if folds[c] != (None,) else ():  # a training's folds make its record
                name = unit_name(c, m, seed, v)
                if name not in records:
                    group = [records[unit_name(c, m, seed, v, k)] for k in folds[c]]
                    records[name] = crossed_record(name, group, rules[c])
                    run.append(records[name])
            if seeds != (None,) and unit_name(c, m, None, v) not in records:
                group = [records[unit_name(c, m, s, v)] for s in seeds]
                run.append(ensemble_record(unit_name(c, m, None, v), group, rules[c]))
        run.write_json(
            "conditions.json",
            {
                c: {
                    "history": [f.path for f, _ in v["history"]],
                    "test": [f.path for f, _ in v["test"]],
                    "speeds_hz": v["speeds"],
                    "start_marks": v["shifts"],
                    "max_order": v["max_order"],  # the records' band: no higher order reaches a learned method
                    "source": v["source"],
                    "sources": v["sources"],
                    # what the best detector of each source's held-out samples reaches (source_bound)
                    "source_bound": {w or "source": bounds[(c, w)] for w in variants},
                }
                for c, v in conditions.items()
            },
        )
        store_scoring(run, spec, conditions)
        summarise(scenario, run)


# --- figures -----------------------------------------------------------------------------


def auc(negatives: np.ndarray, positives: np.ndarray) -> float | None:
    """ROC AUC = P(score of a positive > score of a negative), ties counted half (Mann-Whitney).
    None when a side is empty or holds a score that is not a finite number: a NaN compares
    false with everything, so it would read as AUC 0 — the chips ranked last — when the method
    in fact gave no ranking at all (a detector whose scores were NaN read so)."""
    if not len(negatives) or not len(positives):
        return None
    n, p = np.asarray(negatives, dtype=np.float64)[:, None], np.asarray(positives, dtype=np.float64)[None, :]
    if not (np.isfinite(n).all() and np.isfinite(p).all()):
        return None
    return float(np.mean((p > n) + 0.5 * (p == n)))


def summarise(scenario: Scenario, run: RunDir) -> None:
    spec = scenario.spec
    target: Target = spec["target"]
    labels = {f.path: f.label for f in target.files}
    everything = run.records()
    by_unit = {r["unit"]: r for r in everything}
    # an ensemble's members (one training each) are kept in results.jsonl and shown only as the
    # spread of their AUCs beside the ensemble's
    records = [r for r in everything if r.get("seed") is None and r.get("fold") is None]
    thresholds = {r["unit"]: r["thresholds"] for r in records}
    # scores.csv: every test unit's score and decision
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["file", "unit", "index", "method", "score", "decision"])
    for r in sorted(records, key=lambda r: r["unit"]):  # not in the order the trainings finished
        for path, units in r["test_scores"].items():
            for u, scores in units.items():
                thr = thresholds[r["unit"]][u]
                for i, s in enumerate(scores):
                    w.writerow([path, u, i, r["method"], repr(float(s)), int(s > thr)])
    run.write_text("scores.csv", buf.getvalue())
    attributed = [r for r in records if "shafts" in r]
    if attributed:
        run.write_text("shafts.csv", shafts_csv(attributed))

    # the labels come in only here, to score what was decided
    def split(r: dict, u: str) -> tuple[np.ndarray, np.ndarray]:
        neg = [r["test_scores"][p][u] for p in r["test_scores"] if labels[p] != target.positive]
        pos = [r["test_scores"][p][u] for p in r["test_scores"] if labels[p] == target.positive]
        return np.concatenate(neg or [np.empty(0)]), np.concatenate(pos or [np.empty(0)])

    rows = []
    for r in records:
        for u in r["history_scores"]:
            thr = thresholds[r["unit"]][u]
            neg, pos = split(r, u)
            # scores that are not numbers (a broken method) are counted and shown, never ranked
            broken = int(np.sum(~np.isfinite(np.concatenate([neg, pos, np.asarray(r["history_scores"][u])]))))
            other = {
                rule: (
                    100.0 * float(np.mean(pos > t[u])) if len(pos) else None,
                    100.0 * float(np.mean(neg > t[u])) if len(neg) else None,
                )
                for rule, t in r.get("thresholds_by_rule", {}).items()
            }
            by_label = {}
            for p, units in r["test_scores"].items():
                by_label.setdefault(labels[p], []).extend(units[u])
            rows.append(
                {
                    "condition": r["condition"],
                    "unit": u,
                    "method": r["method"],
                    "auc": auc(neg, pos),
                    "detection": 100.0 * float(np.mean(pos > thr)) if len(pos) else None,
                    "false_alarm": 100.0 * float(np.mean(neg > thr)) if len(neg) else None,
                    "n_positive": int(len(pos)),
                    "n_negative": int(len(neg)),
                    "non_finite": broken,
                    "threshold": thr,
                    "called_by_label": {k: 100.0 * float(np.mean(np.asarray(v) > thr)) for k, v in by_label.items()},
                    # detection and false alarms (%) at each threshold rule's threshold
                    "by_rule": {rule: {"detection": d, "false_alarm": f} for rule, (d, f) in other.items()},
                    "member_auc": [auc(*split(by_unit[m], u)) for m in r.get("members", [])],
                }
            )
    order = {c: i for i, c in enumerate(dict.fromkeys(r["condition"] for r in records))}
    variants = [""] + ([spec["corrected_label"]] if spec.get("corrected") is not None else [])
    methods = [method_name(m, v) for v in variants for m in spec["protocol"].methods]
    methods += list(spec["classical"]["indicators"])

    def rank(method: str) -> int:
        return methods.index(method) if method in methods else len(methods)

    rows.sort(
        key=lambda r: (
            order[r["condition"]],
            rank(r["method"]),
            r["unit"] != "revolution",
            r["unit"],
        )
    )
    summary = {
        "kind": "detection",
        "scenario": scenario.name,
        "source": asdict(spec["source"]),
        "target": {**asdict(target), "files": [asdict(f) for f in target.files]},
        "protocol": {k: v for k, v in asdict(spec["protocol"]).items() if k != "methods"},
        "methods": list(dict.fromkeys(r["method"] for r in records)),
        "false_alarm_asked": spec["false_alarm"],
        "rows": rows,
        # pinion_sync's attribution per label (shafts_md), shown by the report as table.md shows it
        "shafts_md": shafts_md(attributed, labels),
    }
    conditions = run.read_json("conditions.json")
    bound = {c: v.get("source_bound", {}) for c, v in (conditions or {}).items()}
    summary["learned"] = [
        {
            "condition": r["condition"],
            "method": r["method"],
            "source_auc": r["source_auc"],
            "source_bound": bound.get(r["condition"], {}).get(r.get("source", "source")),
            "part_source_auc": r.get("part_source_auc", []),
            "source_units": r["source_units"],
            "aligned_to_a_point": r.get("aligned_to_a_point", False),
            "seconds": r["seconds"],
        }
        for r in sorted(records, key=lambda r: (order[r["condition"]], rank(r["method"])))
        if "source_units" in r
    ]
    if conditions is not None:
        summary["conditions"] = conditions
    run.write_json("summary.json", summary)
    run.write_text(
        "table.md", table_md(rows) + "\n" + labels_md(rows) + summary["shafts_md"] + learned_md(summary["learned"])
    )
    run.write_text("table.csv", table_csv(rows))


def _cell(x, fmt="{:.2f}") -> str:
    return "–" if x is None else fmt.format(x)


def _spread(aucs) -> str:
    """An ensemble's member AUCs as their range."""
    aucs = [a for a in aucs or [] if a is not None]
    return f" ({min(aucs):.2f}–{max(aucs):.2f})" if aucs else ""


def table_md(rows: list[dict]) -> str:
    """One table per condition: a row per method; AUC (an ensemble's: with the range of its
    members' AUCs), detection and false alarms (% of the test's positive and negative units
    called at the history's threshold) per unit."""
    units = list(dict.fromkeys(r["unit"] for r in rows))
    out = []
    for c in dict.fromkeys(r["condition"] for r in rows):
        cells = {(r["method"], r["unit"]): r for r in rows if r["condition"] == c}
        first = next(r for r in rows if r["condition"] == c)
        out.append(f"| {c}: method | " + " | ".join(f"{u} AUC | det % | FA %" for u in units) + " |")
        out.append("|---|" + "---|---|---|" * len(units))
        for m in dict.fromkeys(r["method"] for r in rows if r["condition"] == c):
            parts = []
            for u in units:
                r = cells.get((m, u))
                parts.append(
                    "| | "
                    if r is None
                    else f"{_cell(r['auc'], '{:.3f}')}{_spread(r.get('member_auc'))} | "
                    f"{_cell(r['detection'], '{:.0f}')} | {_cell(r['false_alarm'], '{:.0f}')}"
                )
            out.append(f"| {m} | " + " | ".join(parts) + " |")
        out.append(
            "| units (pos / neg) | "
            + " | ".join(
                f"{cells[(first['method'], u)]['n_positive']} / {cells[(first['method'], u)]['n_negative']} | |"
                if (first["method"], u) in cells
                else "| |"
                for u in units
            )
            + " |"
        )
        broken = {m: 0 for m in dict.fromkeys(r["method"] for r in rows if r["condition"] == c)}
        for r in rows:
            if r["condition"] == c:
                broken[r["method"]] += r.get("non_finite", 0)
        if any(broken.values()):
            out.append(
                "Scores that are not numbers (no AUC, '–'): " + ", ".join(f"{m} {n}" for m, n in broken.items() if n)
            )
        out.append("")
    return "\n".join(out)


def labels_md(rows: list[dict]) -> str:
    """Called units (%) per test label at the history's threshold, for the longest TSA: is other
    damage (a negative label) taken for the fault?"""
    unit = longest_tsa(r["unit"] for r in rows)
    if unit is None:
        return ""
    picked = [r for r in rows if r["unit"] == unit]
    labels = list(dict.fromkeys(k for r in picked for k in r["called_by_label"]))
    out = [
        f"| {unit}: condition | method | " + " | ".join(f"called % '{k}'" for k in labels) + " |",
        "|---|---|" + "---|" * len(labels),
    ]
    for r in picked:
        out.append(
            f"| {r['condition']} | {r['method']} | "
            + " | ".join(_cell(r["called_by_label"].get(k), "{:.0f}") for k in labels)
            + " |"
        )
    return "\n".join(out) + "\n"


def learned_md(learned: list[dict]) -> str:
    """What each method that learns from the simulator learned of it: the ROC AUC of a network's
    scores of the source's held-out revolutions (an ensemble's: the median over its members, with
    their range; a detector's "–": it is built in the target's frame), and the training time, all
    of its trainings together, and whether its domain loss aligned the history with a single point
    (aligned_to_a_point). From training data only: a row near 0.5 cannot tell the simulated fault
    from healthy, so its calls on the records are not what the simulator taught it."""
    if not learned:
        return ""
    out = [
        "\nWhat each method learned of the simulator (ROC AUC of a network's scores of the source's held-out "
        "revolutions, 0.5 = chance; a detector, built on the history, has none; the bound: the likelihood "
        "ratio that knows the source's noise-free fault shapes and noise law, – for a noise-free source; "
        "training time, all seeds; history aligned with: a point when the source's samples its domain loss "
        "aligns the history with are one input, a noise-free healthy revolution)\n",
        "| condition | method | source AUC | bound | training (s) | history aligned with |",
        "|---|---|---|---|---|---|",
    ]
    for r in learned:
        point = "a point" if r.get("aligned_to_a_point") else ""
        out.append(
            f"| {r['condition']} | {r['method']} | {_cell(r['source_auc'])}{_spread(r['part_source_auc'])} | "
            f"{_cell(r.get('source_bound'))} | {r['seconds']:.0f} | {point} |"
        )
    return "\n".join(out) + "\n"


def shafts_csv(records: list[dict]) -> str:
    """One row per test unit of each pinion_sync record: the shaft its localised damage is put on
    ("nothing": no shaft above its threshold) and every shaft's strength."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    names = list(dict.fromkeys(n for r in records for n in r["shafts"]["names"]))
    w.writerow(["condition", "file", "unit", "index", "shaft", *(f"strength_{n}" for n in names)])
    for r in records:
        a = r["shafts"]
        for path, units in a["named"].items():
            for u, named in units.items():
                for i, (shaft, strength) in enumerate(zip(named, a["strengths"][path][u])):
                    values = dict(zip(a["names"], strength))
                    w.writerow(
                        [r["condition"], path, u, i, shaft, *(repr(float(values.get(n, np.nan))) for n in names)]
                    )
    return buf.getvalue()


def shafts_md(records: list[dict], labels: dict) -> str:
    """pinion_sync's attribution per condition and test label, for the longest TSA: the share (%) of
    the label's units put on each shaft."""
    if not records:
        return ""
    unit = longest_tsa(records[0]["shafts"]["thresholds"])
    if unit is None:
        return ""
    names = list(dict.fromkeys(n for r in records for n in r["shafts"]["names"])) + ["nothing"]
    out = [
        f"\nWhich shaft (pinion_sync, {unit}: % of each label's units put on each shaft)\n",
        "| condition | label | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for r in records:
        by_label: dict[str, list[str]] = {}
        for path, units_named in r["shafts"]["named"].items():
            by_label.setdefault(labels[path], []).extend(units_named[unit])
        for label, named in by_label.items():
            out.append(
                f"| {r['condition']} | {label} | "
                + " | ".join(f"{100.0 * named.count(n) / len(named):.0f}" for n in names)
                + " |"
            )
    return "\n".join(out) + "\n"


def table_csv(rows: list[dict]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(
        ["condition", "unit", "method", "auc", "detection", "false_alarm", "n_positive", "n_negative", "threshold"]
    )
    for r in rows:
        w.writerow(
            [
                r["condition"],
                r["unit"],
                r["method"],
                *(("" if r[k] is None else f"{r[k]:.4f}") for k in ("auc", "detection", "false_alarm")),
                r["n_positive"],
                r["n_negative"],
                f"{r['threshold']:.6g}",
            ]
        )
    return buf.getvalue()


def summary_lines(run: RunDir) -> list[str]:
    summary = run.read_json("summary.json")
    return [
        f"ROC AUC, detection and false alarms at the history's threshold ({100 * summary['false_alarm_asked']:g} % "
        "false alarms asked):",
        table_md(summary["rows"]).rstrip(),
        labels_md(summary["rows"]).rstrip(),
        *([summary["shafts_md"].strip()] if summary.get("shafts_md") else []),
        *([learned_md(summary["learned"]).strip()] if summary.get("learned") else []),
    ]


def records_table(scenario: Scenario, records: list[dict]) -> str:
    return "| unit | method |\n|---|---|\n" + "".join(f"| {r['condition']} | {r['method']} |\n" for r in records)


def charts(scenario: Scenario, run: RunDir) -> list:
    """The scoring history (`gearlab score`) as a trend per condition and method."""
    return score_trends(run)


# --- day-to-day scoring (gearlab score; gearlab.parts.scoring) --------------------------------


def store_scoring(run: RunDir, spec: dict, conditions: dict) -> None:
    """What `gearlab score` needs of the finished run: the target's keys, the units and threshold
    rule, and per condition its speed, standardiser, alignment reference and history revolutions
    (the thresholds and classical references are made from them as the run made them)."""
    target: Target = spec["target"]
    out = {
        "target": {
            k: getattr(target, k)
            for k in ("vibration", "tacho", "pulses_per_rev", "sensitivity", "gain", "fs", "transient")
        },
        "blocks": list(spec["blocks"]),
        "threshold": spec["threshold"],
        "false_alarm": spec["false_alarm"],
        "points": spec["points"],
        "input": spec["input"],
        "classical": {k: list(v) if isinstance(v, tuple) else v for k, v in spec["classical"].items()},
        "conditions": {},
    }
    for i, (name, cond) in enumerate(conditions.items()):
        history = np.concatenate([r for _, r in cond["history"]])
        file = f"condition{i}.npz"
        scoring.save_arrays(
            run.file("scoring", file),
            standardiser=np.array([cond["standardiser"].mean, cond["standardiser"].std]),
            reference=cond["reference"],
            history=history.astype(np.float32),
        )
        out["conditions"][name] = {
            "file": file,
            "speed_hz": float(np.median([cond["speeds"][f.path] for f, _ in cond["history"]])),
            "max_order": cond["max_order"],
            "history": [[f.path, len(r)] for f, r in cond["history"]],
        }
    run.write_json(scoring.SCORING_FILE, out)


def _scoring_condition(run: RunDir, meta: dict, name: str, records: list[tuple[TargetFile, np.ndarray]]) -> dict:
    """A condition as read_target makes it, from the stored history and the new *records*
    (standardised and aligned as the run's records were)."""
    c = meta["conditions"][name]
    arrays = scoring.load_arrays(run.file("scoring", c["file"]))
    standardiser = Standardiser(*(float(v) for v in arrays["standardiser"]))
    parts = np.split(arrays["history"], np.cumsum([n for _, n in c["history"]])[:-1])
    history = [(TargetFile(path, path, "history", "", name), revs) for (path, _), revs in zip(c["history"], parts)]
    ppr = meta["target"]["pulses_per_rev"]
    test = [(f, align_to(arrays["reference"], standardiser.apply(revs), ppr)[1]) for f, revs in records]
    blocks = meta["blocks"]
    per_record = [unit_sets(r, blocks, True) for _, r in history]
    return {
        "history": history,
        "test": test,
        "max_order": c["max_order"],
        "history_units": {u: np.concatenate([s[u] for s in per_record]) for u in per_record[0]},
        "history_records": {
            u: [(len(s[u]), record_effects.independent_units(len(s[u]), *_window(u))) for s in per_record]
            for u in per_record[0]
        },
        "test_units": {f.path: unit_sets(r, blocks, False) for f, r in test},
    }


def _condition_of(meta: dict, path: str, speed: float, asked: str | None) -> str:
    names = list(meta["conditions"])
    if asked is not None:
        if asked not in names:
            raise GearlabInputError(
                f"--condition '{asked}'{did_you_mean(asked, names)}: not a condition of the run; "
                f"known: {', '.join(names)}"
            )
        return asked
    near = min(names, key=lambda c: abs(meta["conditions"][c]["speed_hz"] - speed))
    centre = meta["conditions"][near]["speed_hz"]
    if abs(speed - centre) > SPEED_GROUP * centre:
        known = ", ".join(f"'{c}' ({meta['conditions'][c]['speed_hz']:.2f} Hz)" for c in names)
        raise GearlabInputError(
            f"{path}: runs at {speed:.2f} Hz, more than {SPEED_GROUP:.0%} from every condition's history ({known}); "
            "expected a record of a trained condition, or --condition NAME"
        )
    return near


def _learned_scores(run: RunDir, record: dict, seen: dict, rule: Rule, by_unit: dict) -> dict:
    """{path: {unit: scores}} of a learned method's record (one training, an ensemble of seeds, or
    crossed folds) on the units *seen* ({path: {unit: X}} as the method sees them)."""
    models = scoring.MODELS

    def raw(unit: str) -> dict:
        model = scoring.load_model(run.file(*models), unit)
        return {p: {u: fault_score(model, X, "cpu") for u, X in units.items()} for p, units in seen.items()}

    if "members" in record:  # an ensemble: the median of its members' history-standardised scores
        members = [by_unit[m] for m in record["members"]]
        parts = []
        for m in members:
            scored, ms = raw(m["unit"]), rule.models(m["history_scores"])
            parts.append({p: {u: ms[u].standardised(s) for u, s in units.items()} for p, units in scored.items()})
        return {p: {u: np.median([q[p][u] for q in parts], axis=0) for u in seen[p]} for p in seen}
    if "folds" in record:  # crossed: the mean over the folds, each standardised by its training's records
        parts = []
        for k, name in enumerate(record["folds"]):
            fold = by_unit[name]
            keep = [i for i in range(len(record["folds"])) if i != k]
            scored = raw(name)
            models = {u: rule.model(u, fold["history_scores"][u], keep=keep) for u in fold["history_scores"]}
            parts.append({p: {u: models[u].standardised(s) for u, s in units.items()} for p, units in scored.items()})
        return {p: {u: np.mean([q[p][u] for q in parts], axis=0) for u in seen[p]} for p in seen}
    return raw(record["unit"])


def score(run: RunDir, files, condition: str | None = None, on_event=lambda e: None) -> list[dict]:
    """New recordings scored by a finished run's trained methods at its thresholds, nothing trained
    again: one row per file, method and unit kind (its units' scores, how many are called, the
    threshold and the record's decision: the majority of its units called), appended to the run's
    scoring history."""
    meta = run.read_json(scoring.SCORING_FILE)
    if meta is None:
        raise GearlabInputError(
            f"{run.path}: no {scoring.SCORING_FILE}: not a finished detection run (or one from before gearlab "
            "score kept its models); expected a finished run: run the scenario again"
        )
    keys = meta["target"]
    cut = {}
    for i, file in enumerate(files):
        rec = cut_recording(str(file), **keys)
        name = _condition_of(meta, str(file), rec.speed_hz, condition)
        cut.setdefault(name, []).append((TargetFile(str(file), str(file), "test", "", name), rec.revolutions))
        on_event(Event("advance", stage="records", done=i + 1, total=len(files)))
    by_unit = {r["unit"]: r for r in run.records()}
    shown_spec = {"points": meta["points"], "input": meta["input"], "classical": meta["classical"]}
    classical = {**meta["classical"], "shafts": tuple(tuple(x) for x in meta["classical"]["shafts"])}
    rows = []
    for name, records in cut.items():
        cond = _scoring_condition(run, meta, name, records)
        rule = Rule(meta["threshold"], meta["false_alarm"], cond["history_records"])
        shown = learned_input(shown_spec, cond["max_order"])
        seen = {p: {u: shown(X) for u, X in units.items()} for p, units in cond["test_units"].items()}
        for r in by_unit.values():
            if r["condition"] != name or r.get("seed") is not None or r.get("fold") is not None:
                continue
            if r["adapter"] is None:
                made = classical_record(r["method"], name, cond, classical, rule)
                scores, thresholds = made["test_scores"], made["thresholds"]
            else:
                scores, thresholds = _learned_scores(run, r, seen, rule, by_unit), r["thresholds"]
            for f, _ in records:
                for u, s in scores[f.path].items():
                    s = np.asarray(s, dtype=np.float64)
                    called = int(np.sum(s > thresholds[u]))
                    rows.append(
                        {
                            "file": f.path,
                            "condition": name,
                            "method": r["method"],
                            "unit": u,
                            "units": int(s.size),
                            "called": called,
                            "threshold": float(thresholds[u]),
                            "rule": meta["threshold"],
                            "median_score": float(np.median(s)) if s.size else None,
                            "decision": "fault" if s.size and called > s.size / 2 else "healthy",
                            "scores": [float(x) for x in s],
                        }
                    )
    scoring.append_history(run, rows)
    trends = score_trends(run)
    if trends:
        from ..plots import score_trend  # here, not at the top: start-up time (matplotlib)

        score_trend(trends, run.file("figures", "score_trend.png"))
    return rows


def score_trends(run: RunDir) -> list:
    """Per condition and method: the median score of each scored record's longest TSA units, in the
    order they were scored, beside the threshold (gearlab.parts.scoring's history)."""
    from ..charts import Chart, Curve

    rows = scoring.read_history(run)
    unit = longest_tsa(r["unit"] for r in rows) or "revolution"
    out = []
    for c in dict.fromkeys(r["condition"] for r in rows):
        picked = [r for r in rows if r["condition"] == c and r["unit"] == unit and r["median_score"] is not None]
        curves = []
        for m in dict.fromkeys(r["method"] for r in picked):
            mine = [r for r in picked if r["method"] == m]
            x = list(range(1, len(mine) + 1))
            curves.append(Curve(m, x, [r["median_score"] - r["threshold"] for r in mine]))
        if curves:
            out.append(
                Chart(
                    f"{c}: scored records, {unit} (median score less the threshold: above 0 is called)",
                    "record scored (in order)",
                    "score - threshold",
                    tuple(curves),
                )
            )
    return out


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """Per condition, the rows meeting the goal and what the learned rows learned (kinds.detection_verdict)."""
    from .detection_verdict import detection_lines  # read only for a verdict

    return detection_lines(summary, longest_tsa(r["unit"] for r in summary.get("rows") or []))


def verdict_table(summary: dict) -> str | None:
    return None  # table.md's per-condition tables say it all


compare_table = no_compare  # each detection run's own tables, lettered
