"""Scenario kind `detection`: a fault found in measured records without a single real fault label.

The source is a simulator with healthy and faulty revolutions; the target is a list of
measured text records, each with a *role*: ``history`` (the unlabelled healthy past a method
may learn from and fix its threshold on) or ``test`` (scored only). Every method is trained
and thresholded from the source and the history alone; the test records come in only once
the method's model and threshold are fixed, and their labels only when the figures are made.

    [source]              a dataset preset with overrides (as in [[datasets]]), healthy + faults
    [corrected]           effects (as in [[datasets]]) and gearbox (a description in place of the [source]'s)
                          that make the corrected simulator (what `gearlab gap` fitted), tsa (revolutions
                          averaged per sample), draws (noise draws of each sample, one at random per batch
                          row), history_units (what of the history its methods train on), label: every method
                          is trained on both sources, the corrected one's rows "<method> (<label>)"
    [target]              vibration, tacho (or without one: speed, or the [source]'s gearbox), pulses_per_rev,
                          sensitivity, fs, positive, files = [
                            { file, role = "history" | "test", label, condition, speed (optional) }, ...]
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
speed (``conditions_of``: within 5 %, a test record with the history of nearest speed): the
tacho's, or without one the declared speed or the one the description's mesh orders show
(recordings.shaft_angle; conditions.json and table.md say per record how it was found).
Each condition has its own history: standardisation
(eq. 2.112), the alignment of records that start at different tacho marks (without a tacho, at
any sample of the revolution), the methods' calibration and thresholds. A condition with test
records but no history is refused.

Units scored: every revolution (``revolution``) and the TSA of consecutive blocks of ``b``
revolutions (``record<b>``), of the shaft that carries the watched gear (the source's faulty
gear; detection_records.unit_shaft): the input shaft's, or a slower shaft's cut on its angle
(the input's times its turns per input turn), for the history, test and source alike. The
threshold of a method and unit is fixed on the method's scores of the history's units of that
kind (record-level history units: TSAs of sliding windows; of three or more history records, each
record's against the reference made without it, a detector's or a classical indicator's), for a unit of a *new* record:
``threshold = "records"`` (default) the ``1 - false_alarm`` predictive quantile (Student-t) of a one-way
random-effects model, record effect plus within-record spread (``record_effects``); ``"pooled"``
the quantile of a Gumbel law fitted by its quartiles to the pooled units (blind to take-to-take
variation). With ``seeds`` > 1 every network is trained that many times (repetitions 0 …); the
method's score is the median over its members of each member's score standardised by its own
history model, thresholded alike.

Output: results.jsonl (one record per condition x source x method: the history and test scores,
thresholds under both rules, the history model; an ensemble's members one record per seed besides),
scores.csv (file, unit, index, method, score, decision), summary.json, table.md/table.csv
(AUC, detection and false-alarm rates per condition, unit and method; below them what each learned
method learned of the simulator: the ROC AUC of its scores of the source's held-out revolutions,
beside the bound of that source (source_bound: the likelihood ratio that knows its noise-free
fault shapes), and its training time) and report.html; with
pinion_sync, shafts.csv (file, unit, index, the shaft each test unit's localised damage is put on,
or "nothing", and each shaft's strength) and its counts per label in table.md. When the source
simulates a gearbox description: localisation.json, the gear each test record's change is on and
what a flag on it is (a watched-gear fault, or other damage: kinds.detection_which_gear), in table.md.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ..data.cache import load_or_build
from ..data.readers.headers import validating
from ..data.spec import DatasetSpec
from ..errors import GearlabInputError, did_you_mean, shown
from ..events import Event, ignore_events
from ..executors import Aside, Shared
from ..gearbox.simulation import gearbox_of, label, referenced
from ..learn.config import Calibration, check_length
from ..learn.protocol import Method, Protocol, domain_adapting, each_draw, shared_state
from ..learn.schedule import longest_first, two_phases
from ..parts import training
from ..parts.measured import pattern_counts, target_spec
from ..parts.training import CALIBRATION, METHOD_KEYS, NETWORK, TRAINING, check_training
from ..registry import METHODS, get_registry
from ..runs import RunDir
from ..scenario import Scenario, Table, keys_of, location
from ..settings import shrunk, typed
from ..signals.indicators import INDICATORS
from .common import (
    DATASET_TABLE,
    class_sizes,
    device_of,
    executor_for,
    gearbox_name,
    no_title,
    simulated_spec,
    sized,
    with_source_gearbox,
)
from .detection_classical import classical_record
from .detection_figures import captions, drawing_in, roc_charts
from .detection_figures import draw as draw_figures
from .detection_records import (
    asynchronous_orders,
    check_structure,
    folds_of,
    history_training_rows,
    learned_input,
    longest_tsa,
    read_target,
    register_to_source,
    shaft_symmetry,
    short_takes,
    source_for,
    synchronous_input,
    tooth_gap,
    trained_on,
    turned_faults,
    unaligned_why,
    unit_mesh_orders,
    unit_shaft,
    watched_teeth,
)
from .detection_scoring import score as score  # the kind's `gearlab score` (engine.score_recordings)
from .detection_scoring import score_trends, store_scoring
from .detection_screen import screen_histories
from .detection_settings import (
    UNIT_THRESHOLD,
    Classical,
    Corrected,
    Detection,
    Spec,
    TargetRecords,
)
from .detection_tables import labels_md, learned_md, side_by_side, summarise, table_md
from .detection_units import (
    Rule,
    crossed_record,
    ensemble_record,
    healthy_twin,
    noise_effects,
    noise_free_twin,
    seeds_of,
    signature_rows,
    source_bound,
    source_split,
    train_unit,
    unit_name,
    without_each,
)
from .detection_which_gear import store_localisation

TABLES = {
    "source": Table(DATASET_TABLE.keys, required=True, moved=DATASET_TABLE.moved),
    "corrected": Table(keys_of(Corrected)),
    "target": Table(keys_of(TargetRecords), required=True),
    "network": NETWORK,
    "methods": Table(METHOD_KEYS, array=True),
    "classical": Table(keys_of(Classical)),
    "detection": Table(keys_of(Detection)),
    # One threshold rule and one false-alarm rate, [detection]'s (UNIT_THRESHOLD)
    "protocol": Table(
        {**TRAINING, **{k: v for k, v in CALIBRATION.items() if k not in UNIT_THRESHOLD}},
        moved={
            "threshold": "a detection scenario's one threshold rule is [detection] threshold "
            "('records' or 'pooled'): every method's threshold is fixed on the history's units",
            "false_alarm": "a detection scenario's one false-alarm rate is [detection] false_alarm: "
            "every method's threshold is fixed on the history's units",
        },
    ),
}
OVERRIDES: tuple[str, ...] = ()  # no key is set from the command line


# --- building the scenario ---------------------------------------------------------------


def trains_on_target(name: str) -> bool:
    """An adapter that trains on labelled target rows (target_only, finetune): the history has none."""
    registry = get_registry()
    return registry.kind_of(name) == "adapter" and registry.get("adapter", name).train_on == "target"


def methods_of(entries: list[dict], where: str) -> tuple[Method, ...]:
    """The [[methods]]; none listed: every registered adapter and detector that learns without
    target labels (source-trained, domain-adaptation and detector methods), in name order."""
    registry = get_registry()
    if not entries:
        entries = [
            {"adapter": name, "supervised": False, "params": {}}
            for name in registry.names(METHODS)
            if not trains_on_target(name) and "unsupervised" in registry.get(METHODS, name).supervision
        ]
    out = []
    for i, entry in enumerate(entries):
        at = location(where, "methods", index=i)
        m = training.method(entry, at, UNIT_THRESHOLD["false_alarm"], "[detection] false_alarm")
        if m.supervised:
            raise GearlabInputError(f"{at} key 'supervised': the measured target has no labels a method may use")
        if trains_on_target(m.adapter):
            raise GearlabInputError(
                f"{at} key 'adapter': '{m.adapter}' trains on labelled target data; the measured history has none"
            )
        if m in out:
            raise GearlabInputError(f"{at}: {m.label} is listed twice")
        out.append(m)
    return tuple(out)


def build(scenario: Scenario) -> Spec:
    t = scenario.tables
    path = scenario.path
    written = scenario.raw.get("source") or {}  # a user's box: its watched gear's teeth sized (watched_teeth)
    source = watched_teeth(simulated_spec(t["source"], location(path, "source"), scenario.base), written)
    cor = typed(Corrected, t["corrected"])
    corrected = corrected_spec(cor, t["source"], location(path, "corrected"), scenario.base, source)
    corrected = corrected if corrected is None else watched_teeth(corrected, written)
    sizes = class_sizes(source, location(path, "source"))
    if not sizes["healthy"] or sum(sizes.values()) == sizes["healthy"]:
        raise GearlabInputError(
            f"{location(path, 'source')}: the source needs healthy and faulty revolutions (has {sizes})"
        )
    _, pair, _ = source.check_model(location(path, "source"))
    entry = with_source_gearbox(t["target"], t["source"], location(path, "target"), scenario.base)
    if entry["gearbox"]:  # resolved and loaded now: a bad description fails validate
        entry = {**entry, "gearbox": gearbox_name(entry["gearbox"], location(path, "target", "gearbox"), scenario.base)}
    target = target_spec(entry, location(path, "target"), scenario.base, box=gearbox_of(source))
    c = typed(Classical, t["classical"])
    for name in c.indicators:
        if name not in INDICATORS:
            raise GearlabInputError(
                f"{location(path, 'classical', 'indicators')}: unknown indicator "
                f"{shown(name)}{did_you_mean(str(name), INDICATORS)}; known: {', '.join(INDICATORS)}"
            )
    orders = c.mesh_orders or unit_mesh_orders(source, unit_shaft(source))
    if not all(isinstance(o, int) and not isinstance(o, bool) and 1 <= o <= 1000 for o in orders):
        raise GearlabInputError(
            f"{location(path, 'classical', 'mesh_orders')}: expected whole orders 1 … 1000, got {shown(orders)}"
        )
    slow = c.slow_shafts
    if not all(isinstance(q, int) and not isinstance(q, bool) and 2 <= q <= 1000 for q in slow):
        raise GearlabInputError(
            f"{location(path, 'classical', 'slow_shafts')}: expected whole numbers of input revolutions "
            f"2 … 1000 (a shaft turning q times slower than the input), got {shown(slow)}"
        )
    shafts = c.shafts
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
    d = typed(Detection, t["detection"])
    blocks = d.blocks
    if not all(isinstance(b, int) and not isinstance(b, bool) and 2 <= b <= 10_000 for b in blocks) or len(
        set(blocks)
    ) != len(blocks):
        raise GearlabInputError(
            f"{location(path, 'detection', 'blocks')}: expected distinct whole numbers of "
            f"revolutions >= 2, got {shown(blocks)}"
        )
    short_takes(source, target, blocks, location(path, "target", "files"))  # a take its header says is short
    if validating():  # a history its tachos show too short: refused in the run's line (a run reads the takes whole)
        where = location(path, "target", "files")
        screen_histories(target, blocks, unit_shaft(source), where, lambda: _read(scenario, source, target, blocks))
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
        calibration=Calibration(**{key: p[key] for key in CALIBRATION if key in p}, **UNIT_THRESHOLD),
    )
    protocol.calibration.check(str(path))
    points = d.points
    try:  # a network that cannot take that many samples is refused now, not in the middle of a run
        check_length(protocol.network, points)
    except GearlabInputError as e:
        raise GearlabInputError(f"{location(path, 'detection', 'points')}: {points} is too few: {e}") from None
    if p["batch"] > p["target_train"]:
        raise GearlabInputError(
            f"{location(path, 'protocol', 'batch')}: {p['batch']} is larger than target_train = {p['target_train']}"
        )
    n = sum(sizes.values())  # the source's samples, known from its spec: refused now, not after simulating
    trained = n - max(1, round(protocol.val_fraction * n))
    if trained < p["batch"]:
        raise GearlabInputError(
            f"{location(path, 'protocol', 'batch')}: {p['batch']} is larger than the source training set "
            f"({trained} of the {n} samples of '{source.name}'); expected batch <= {trained}: a smaller [protocol] "
            "batch, or more simulated samples ([source] healthy, faults)"
        )
    return Spec(
        source=source,
        corrected=corrected,
        corrected_label=cor.label,
        corrected_history=cor.tsa if cor.history_units == "tsa" else 0,
        corrected_draws=cor.draws,
        target=target,
        protocol=protocol,
        classical=replace(
            c,
            indicators=tuple(c.indicators),
            mesh_orders=tuple(orders),
            slow_shafts=tuple(slow),
            shafts=tuple(shafts.items()),
        ),
        detection=replace(d, blocks=tuple(blocks)),
    )


def corrected_spec(
    cor: Corrected, source_entry: dict, where: str, base: Path, source: DatasetSpec
) -> DatasetSpec | None:
    """The [source] (its table *source_entry*, its spec *source*) with the [corrected] effects after
    its own and its gearbox description in place of the [source]'s (None: neither given)."""
    if not cor.effects and not cor.gearbox:
        return None
    label = cor.label
    if not label or not all(ch.isalnum() or ch in "-_" for ch in label):
        raise GearlabInputError(
            f"{where} key 'label': expected a short name of letters, digits, - or _, got {shown(label)}"
        )
    entry = {**source_entry, "effects": list(source_entry.get("effects") or []) + list(cor.effects)}
    if cor.gearbox:
        entry["gearbox"] = corrected_gearbox(cor.gearbox, source_entry, f"{where} key 'gearbox'", base, source)
    if cor.tsa:  # noise drawn on every revolution, then averaged as a record unit is
        entry.update(tsa=True, revolutions=cor.tsa)
    spec = simulated_spec(entry, where, base)
    # draws: every sample D times, each with its own seed (the builder's duplicates; D healthy
    # samples for each one), in runs of D rows that source_split folds into (n, D, L)
    draws = cor.draws
    spec = spec.with_(duplicates=spec.duplicates * draws, healthy=spec.healthy * draws)
    # a name of its own for the reports and conditions.json (the cache key hashes the spec anyway)
    name = f"{source.name}+{label}"
    return spec.with_(name=name, domain=name)


def corrected_gearbox(gearbox: str, source_entry: dict, where: str, base: Path, source: DatasetSpec) -> str:
    """The [corrected] gearbox description, checked to describe the [source]'s gears (a gap run's
    gearbox_corrected.toml of its description: the tooth counts the same, the values fitted)."""
    from ..gearbox import resolve_gearbox

    if not source_entry.get("gearbox"):
        raise GearlabInputError(
            f"{where}: the [source] simulates no gearbox description; the corrected one replaces its "
            "description (give [source] gearbox = ...)"
        )
    path = gearbox_name(gearbox, where, base)
    teeth = [(s.pinion.z, s.wheel.z) for s in resolve_gearbox(path).stages]
    plain = [(s.pinion.z, s.wheel.z) for s in referenced(source.preset).stages]
    if teeth != plain:
        raise GearlabInputError(
            f"{where}: {shown(gearbox)} has the tooth counts {teeth}, the [source]'s description {plain}; "
            "expected the same gears (a gap run's gearbox_corrected.toml of the [source]'s description)"
        )
    return path


def describe(scenario: Scenario) -> str:
    spec = scenario.spec
    files = spec.target.files
    n_hist = sum(f.role == "history" for f in files)
    matched = pattern_counts(files)
    names = [m.adapter for m in spec.protocol.methods] + list(spec.classical.indicators)
    if spec.corrected is not None:
        extra = [name for name, _ in spec.corrected.effects[len(spec.source.effects) :]]
        if spec.corrected.preset != spec.source.preset:  # its own gearbox description
            extra.insert(0, Path(label(spec.corrected.preset)).name)
        extra = ", ".join(extra)
        names += [f"{m.adapter} ({spec.corrected_label}: + {extra})" for m in spec.protocol.methods]
    return (
        f"{sized(spec.source)} -> {len(files)} measured records ({n_hist} history, {len(files) - n_hist} "
        f"test{'; ' * bool(matched)}{matched}); methods: {', '.join(names)}; units: revolution, "
        + ", ".join(f"record{b}" for b in spec.detection.blocks)
    )


def _source_said(scenario: Scenario) -> str:
    """The [source] key its gearbox is given by: 'gearbox' (a user's description, which the history is checked against
    before any work) or 'preset' (a built-in rig's)."""
    return "gearbox" if "gearbox" in (scenario.raw.get("source") or {}) else "preset"


def _read(scenario: Scenario, source: DatasetSpec, target, blocks) -> dict:
    """The measured takes read as a run reads them first (read_target, with a user's description checked against the
    history first), for a history the screen finds short (detection_screen): its refusal is the run's."""
    shaft, said = unit_shaft(source), _source_said(scenario)

    def structure(of: dict) -> str | None:
        return check_structure(source, target, of, scenario.where("source", said))

    continuous = bool(asynchronous_orders(source, shaft))
    first = structure if said == "gearbox" else None
    return read_target(target, blocks, ignore_events, scenario.where("target", "files"), shaft, continuous, None, first)


def quick(scenario: Scenario) -> None:
    """Smoke run: short training."""
    p = scenario.spec.protocol
    shorter = shrunk(p, prime_epochs=20, baseline_epochs=30, min_epochs=30, max_epochs=40)
    scenario.spec = replace(scenario.spec, protocol=shorter)


def unit_modules(scenario: Scenario) -> tuple[str, ...]:
    """The records' reader (a multi-file target is read on the pool), then the trainings' first imports."""
    return (
        "gearlab.parts.measured",
        "torch",
        "scipy.stats",
        "gearlab.learn.protocol",
        f"{__package__}.detection_units",
    )


def run(scenario: Scenario, run: RunDir, on_event) -> None:
    spec = scenario.spec
    protocol, d = spec.protocol, spec.detection
    with executor_for(scenario) as executor:
        # the units are revolutions of the watched gear's shaft (input: as ever)
        shaft = unit_shaft(spec.source)
        if shaft is not None:
            on_event(Event("log", message=f"units: revolutions and TSAs of {shaft.said()}"))
        if spec.source.teeth is not None and "teeth" not in (scenario.raw.get("source") or {}):
            teeth = ", ".join(map(str, spec.source.teeth))
            on_event(Event("log", message=f"the watched gear simulated on teeth {teeth} (watched_teeth)"))
        where, continuous = scenario.where("target", "files"), bool(asynchronous_orders(spec.source, shaft))
        # a description (the user's) the history contradicts ends the run, before any work (and before a history
        # too short for its units, read_target); a built-in preset's rig is told, checked aside while the pool
        # trains (4.4 s of phm09_chip's main thread with both workers idle)
        said = _source_said(scenario)

        def structure(of: dict | None = None) -> str | None:
            return check_structure(spec.source, spec.target, of or conditions, scenario.where("source", said))

        first = structure if said == "gearbox" else None
        conditions = read_target(spec.target, d.blocks, on_event, where, shaft, continuous, executor, first)
        if said == "gearbox" and (differs := structure()):
            raise GearlabInputError(differs)
        folds = {c: folds_of(d.history_fit, cond, c, scenario.path) for c, cond in conditions.items()}
        for c, cond in conditions.items():
            band = f"no shaft order above {cond['max_order']} (the records' band)"
            on_event(Event("log", message=f"{c}: the learned methods see {band}"))
        # the sources: "" the [source], and the corrected simulator when [corrected] gives effects
        variants = {"": spec.source}
        if spec.corrected is not None:
            variants[spec.corrected_label] = spec.corrected
        specs = {
            (c, v): source_for(source, cond, d.source_speed, shaft)
            for c, cond in conditions.items()
            for v, source in variants.items()
        }
        for c, cond in conditions.items():  # before any work: every training has a batch of history rows
            for k in folds[c]:
                for v in variants:
                    n = len(history_training_rows(trained_on(cond, k), protocol, c, spec.corrected_history if v else 0))
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
        draws = {s: spec.corrected_draws if v else 1 for (_, v), s in specs.items()}  # per sample
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
        for c, cond in conditions.items():
            # records whose angle starts where they do (no tacho, or a shaft the input tacho does not
            # mark): into the source's frame
            if not cond["unit_tacho"]:
                turn = register_to_source(cond, sources[specs[(c, "")]])
                why = unaligned_why(spec.target, cond["unit_shaft"])
                on_event(Event("log", message=f"{c}: turned by {turn} samples into the source's frame ({why})"))
        on_event(Event("log", message="the sources' bounds: their noise-free twins and likelihood ratios"))
        for s in built:  # the twins the bounds read, built by the pool now (the bounds are made aside)
            if len(noise_effects(s)) == 1:
                load_or_build(noise_free_twin(s, draws[s]), executor, on_event)
        records = {r["unit"]: r for r in run.records()}
        rules = {c: Rule(d.threshold, d.false_alarm, cond["history_records"]) for c, cond in conditions.items()}
        classical = [(i, c) for c in conditions for i in spec.classical.indicators if f"{c}/{i}" not in records]
        # what this process makes that no training waits for: made while the pool trains (Aside)
        aside = Aside(
            {
                "classical": lambda: [
                    classical_record(i, c, conditions[c], spec.classical, rules[c]) for i, c in classical
                ],
                "bounds": lambda: {
                    k: source_bound(s, sources[s], protocol, draws[s], None, ignore_events) for k, s in specs.items()
                },
                # which gear each test record's change is on, from the raw records (no score is made here)
                "localisation": lambda: store_localisation(run, spec.source, conditions, spec.corrected),
                "structure": structure if said == "preset" else lambda: None,
            }
        )

        def keep(r: dict) -> None:
            """*r* into results.jsonl, and its unit to the event stream (the TUI's live table and its count of
            finished units, which said 'finished: 0 unit(s)' of every detection run); its scores stay out."""
            run.append(r)
            on_event(Event("record", stage="runs", record={k: r[k] for k in ("unit", "condition", "method") if k in r}))

        held: list[dict] = []  # trainings' records that ended before the classical ones were appended
        in_order = [False]  # the classical records appended

        def append_in_order(record: dict | None = None, wait: bool = False) -> None:
            """results.jsonl in the order of a run that made them first (table.md's rows follow it)."""
            held.extend([record] if record is not None else [])
            if not in_order[0]:
                if not (wait or aside.ready("classical")):
                    return
                for r in aside.get("classical"):
                    keep(r)
                in_order[0] = True
            for r in held:
                keep(r)
            held.clear()

        later = asynchronous_orders(spec.source, shaft)  # a mesh of no whole order of the units' shaft: out
        shown = {
            c: synchronous_input(learned_input(d.input, d.points, spec.classical, cond["unit_max_order"]), later)
            for c, cond in conditions.items()
        }
        splits = {
            (c, v): tuple(
                a if a.ndim == 1 else each_draw(shown[c], a)
                for a in source_split(sources[specs[(c, v)]], protocol, draws[specs[(c, v)]])
            )
            for c, v in specs
        }
        detector_splits = dict(splits)
        # a source with sensor noise (the corrected one): its detectors' shapes from its noise-free twin
        quiet = {s: noise_free_twin(s, draws[s]) for s in built if noise_effects(s)}
        for c, v in specs:
            if (s := specs[(c, v)]) in quiet:
                Xs, ys, _, _ = source_split(load_or_build(quiet[s], executor, on_event)[0], protocol)
                detector_splits[(c, v)] = (shown[c](Xs), ys, *splits[(c, v)][2:])
        if later:  # the detectors' shapes: each fault row less its healthy twin (signature_rows)
            twins = {s: load_or_build(healthy_twin(quiet.get(s, s)), executor, on_event)[0] for s in built}
            for c, v in specs:
                s, (Xs, ys, Xv, yv) = specs[(c, v)], detector_splits[(c, v)]
                Ts = each_draw(shown[c], source_split(twins[s], protocol, 1 if s in quiet else draws[s])[0])
                detector_splits[(c, v)] = (signature_rows(Xs, ys, Ts), ys, Xv, yv)
        z, gap = tooth_gap(spec.source) if shaft is not None else (1, 1)
        if gap > 1:  # the detectors' shapes on every tooth of the watched gear, the frame's 1/g turns among them
            turns = f"the detectors' shapes turned by each pitch of the {z}T gear up to {gap - 1} (teeth not simulated)"
            on_event(Event("log", message=turns))
            for key, (Xs, ys, Xv, yv) in detector_splits.items():
                detector_splits[key] = (*turned_faults(Xs, ys, z, gap), Xv, yv)
        elif shaft is not None and (g := shaft_symmetry(spec.source, shaft)) > 1:
            # the detectors' shapes at every angle the turn into the source's frame may put the damage
            turns = f"the detectors' shapes turned by each 1/{g} of a turn of the {shaft.name} shaft"
            on_event(Event("log", message=turns))
            for key, (Xs, ys, Xv, yv) in detector_splits.items():
                detector_splits[key] = (*turned_faults(Xs, ys, g), Xv, yv)
        # the units every training of a condition scores, as the learned methods see them (made once)
        units_seen = {
            c: (
                Shared({u: shown[c](X) for u, X in cond["history_units"].items()}),
                Shared({p: {u: shown[c](X) for u, X in units.items()} for p, units in cond["test_units"].items()}),
            )
            for c, cond in conditions.items()
        }
        # what many trainings take goes to a local pool's workers once (executors.Shared), not in each unit
        shared_splits = {key: Shared(split) for key, split in splits.items()}
        shared_detector_splits = {key: Shared(split) for key, split in detector_splits.items()}
        rows: dict[tuple, Shared] = {}  # a condition's history rows a training takes, by fold and source

        def history_rows(c: str, k: int | None, v: str) -> Shared:
            if (c, k, v) not in rows:
                taken = trained_on(conditions[c], k), protocol, c, spec.corrected_history if v else 0
                rows[(c, k, v)] = Shared(shown[c](history_training_rows(*taken)))
            return rows[(c, k, v)]

        def left_out(c: str, v: str, m, k: int | None) -> tuple | None:
            """A detector made on all the history (k None): the history rows without each record in turn
            (without_each), on which the detector that scores that record is referenced (its median and noise
            level: detectors.referenced_on, detection_units.train_unit). A detector's reference is the
            history's median revolution, so a history record scores nearer it than a new one."""
            if not m.is_detector or k is not None:
                return None
            made = without_each(len(conditions[c]["history"]), lambda j: history_rows(c, j, v))
            return None if made is None else tuple(made)

        members = {(c, v, m): seeds_of(m, d.seeds) for c in conditions for v in variants for m in protocol.methods}
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
            append_in_order(record)
            records[record["unit"]] = record
            finished += 1
            on_event(Event("log", message=f"{record['unit']} trained"))
            on_event(Event("advance", stage="runs", done=finished, total=len(todo)))

        # the joint trainings first (a corrected source's draws before a plain one), then the
        # source-only and target trainings, the detectors last in their order (their records,
        # appended as they end, give the order of the report's rows)
        def cost(u: tuple) -> tuple:
            joint = domain_adapting(u[2].adapter)
            return joint, not u[2].is_detector, joint and bool(u[1])

        try:
            for phase in phases:
                tasks = []
                for c, v, m, seed, k in longest_first(phase, cost):
                    states = run.file("states", folders[(c, v)])
                    tasks.append(
                        (
                            protocol,
                            m,
                            v,
                            c,
                            seed,
                            k,
                            (shared_detector_splits if m.is_detector else shared_splits)[(c, v)],
                            history_rows(c, k, v),
                            *units_seen[c],
                            states,
                            rules[c],
                            bool(later),  # the detectors whiten their rows (gearlab.learn.whiten)
                            left_out(c, v, m, k),
                        )
                    )
                executor.map(train_unit, tasks, on_done=record_done, gpu=protocol.device != "cpu")
        except BaseException:  # what ended stays for --resume, where the order lets it
            append_in_order()
            raise
        append_in_order(wait=True)
        bounds = aside.get("bounds")
        for (c, v, m), seeds in members.items():
            for seed in seeds if folds[c] != (None,) else ():  # a training's folds make its record
                name = unit_name(c, m, seed, v)
                if name not in records:
                    group = [records[unit_name(c, m, seed, v, k)] for k in folds[c]]
                    records[name] = crossed_record(name, group, rules[c])
                    keep(records[name])
            if seeds != (None,) and unit_name(c, m, None, v) not in records:
                group = [records[unit_name(c, m, s, v)] for s in seeds]
                keep(ensemble_record(unit_name(c, m, None, v), group, rules[c]))
        aside.get("localisation")  # (localisation.json written aside)
        if differs := aside.get("structure"):
            on_event(Event("log", message=f"warning: {differs}"))
        aside.close()
        run.write_json(
            "conditions.json",
            {
                c: {
                    "history": [f.path for f, _ in v["history"]],
                    "test": [f.path for f, _ in v["test"]],
                    "speeds_hz": v["speeds"],
                    # how each record's speed (and shaft angle) was found: tacho, declared, mesh orders
                    "speed_from": v["speed_from"],
                    "warnings": v.get("warnings", []),  # a take off its history's level (level_warnings)
                    # each test take's level over its history's, the history's own spread (called_levels)
                    "level_ratio": v["level_ratio"],
                    "level_spread": v["level_spread"],
                    # each record's turn into register with the history: in tacho marks, or without a
                    # tacho in samples of the revolution (correlation; read_target)
                    "start_marks": v["shifts"],
                    "tacho": v["tacho"],
                    "unit_shaft": v["unit_shaft"],  # the shaft whose revolutions (and TSAs) are the units
                    "max_order": v["max_order"],  # the records' band: no higher order reaches a learned method
                    "source": v["source"],
                    "sources": v["sources"],
                    # what the best detector of each source's held-out samples reaches (source_bound)
                    "source_bound": {w or "source": bounds[(c, w)] for w in variants},
                    # each history record's units of each kind, in order (the figures split its scores)
                    "history_units": {u: [n for n, _ in counts] for u, counts in v["history_records"].items()},
                }
                for c, v in conditions.items()
            },
        )
        store_scoring(run, spec, conditions)
        summarise(scenario, run)
        with drawing_in(executor):  # the figures side by side in the run's pool
            draw_figures(run)


def summary_lines(run: RunDir) -> list[str]:
    summary = run.read_json("summary.json")
    conditions = summary.get("conditions") or {}
    return [
        f"ROC AUC, detection and false alarms at the history's threshold ({100 * summary['false_alarm_asked']:g} % "
        "false alarms asked):",
        table_md(summary["rows"]).rstrip(),
        labels_md(summary["rows"]).rstrip(),
        *([summary["shafts_md"].strip()] if summary.get("shafts_md") else []),
        *([summary["which_gear"]["md"].strip()] if summary.get("which_gear") else []),
        *([learned_md(summary["learned"]).strip()] if summary.get("learned") else []),
        *summary.get("warnings", []),
        # without a tacho, how each record's speed was found and what that changes (table.md has it always)
        *([summary["records_md"].strip()] if not all(c.get("tacho", True) for c in conditions.values()) else []),
    ]


def records_table(scenario: Scenario, records: list[dict]) -> str:
    return "| unit | method |\n|---|---|\n" + "".join(f"| {r['condition']} | {r['method']} |\n" for r in records)


def charts(scenario: Scenario, run: RunDir) -> list:
    """Each method's ROC per condition (kinds.detection_figures) and the scoring history (`gearlab score`)
    as a trend per condition and method."""
    summary = run.read_json("summary.json")
    return (roc_charts(summary, run.records()) if summary else []) + score_trends(run)


def verdict_lines(summary: dict, records: list[dict]) -> list[str]:
    """Per test take, what is wrong, where, how sure and what to do, and why the table's false alarms differ from
    the verdict's (kinds.detection_summary); then per condition, the rows meeting the goal and what the learned rows
    learned (kinds.detection_verdict)."""
    from .detection_summary import verdict  # read only for a verdict

    return verdict(summary, records)


def headline(run) -> str:
    """`gearlab runs`' headline: the run's first finding on its methods (detection_lines), not the summary's first
    take (verdict_lines opens with a line per take: a listing of runs names runs)."""
    from .detection_verdict import detection_lines

    summary = run.read_json("summary.json") or {}
    lines = detection_lines(summary, longest_tsa(r["unit"] for r in summary.get("rows") or []))
    return next((line for line in lines if not line.rstrip().endswith(":")), "")


def verdict_table(summary: dict) -> str | None:
    return None  # table.md's per-condition tables say it all


compare_table = side_by_side  # per condition, method and unit: each run's AUC and detected / false-alarm %
table_title = no_title  # table.md titles its tables


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    """The ROC, per condition the scores per record and in time order (kinds.detection_figures), then
    the trend of what `gearlab score` scored."""
    return {
        **captions(summary),
        "score_trend": (
            "",
            "gearlab score: per condition, each method's median score of each scored record's longest TSA "
            "units less its threshold, over the method's largest, in the order the records were scored (above 0: "
            "called; each panel's title names the records and each method's largest).",
        ),
    }
