"""The Python API for notebooks and scripts (docs/api.md): each function is one step a user takes,
named as the docs name it, and reachable as ``gearlab.<name>`` (resolved on first use, so
``import gearlab`` stays instant). Keys are those of a scenario file (docs/settings.md): what a
notebook says, a scenario can say too, and is checked with the same one-line errors.

    import gearlab
    data = gearlab.simulate("B-6-ch5", teeth=[1, 2], faults={"crack": [13]}, healthy=8)

Every function here is a thin layer over the library that the scenario kinds and the CLI use:
no second implementation of a step lives here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import GearlabInputError

if TYPE_CHECKING:  # the annotations only: the modules load on first use (start-up time)
    import numpy as np

    from .data.recordings import Recording
    from .data.spec import Dataset, DatasetSpec
    from .dynamics.newmark import Simulation
    from .gearbox import Gearbox
    from .runs import RunDir
    from .scenario import Scenario

__all__ = [
    "corrected_source",
    "detector_scores",
    "diagnose_gap",
    "fit_detector",
    "gearbox_orders",
    "import_recording",
    "inspect_recording",
    "load_gearbox",
    "load_scenario",
    "open_run",
    "read_recording",
    "run_scenario",
    "run_verdict",
    "score_detector",
    "score_recordings",
    "simulate",
    "simulate_signals",
    "validate_scenario",
]


# --- gearbox descriptions ----------------------------------------------------------------------


def load_gearbox(description: str | Path) -> Gearbox:
    """A gearbox description (docs/gearbox.md): a .toml file, or a built-in one's name (luo2019,
    meng2020, phm09), checked with ISO 21771 geometry.

    >>> box = gearlab.load_gearbox("phm09")
    >>> box.shafts, [(s.pinion.z, s.wheel.z) for s in box.stages]
    (('input', 'idler', 'output'), [(32, 96), (48, 80)])
    """
    from .gearbox import resolve_gearbox

    return resolve_gearbox(description)


def gearbox_orders(gearbox: Gearbox | str | Path, speed: float | str | None = None) -> dict:
    """The order table of a description: each shaft's order, each stage's mesh order and hunting
    tooth; in Hz too at *speed* (the input shaft's, e.g. ``"30 Hz"`` or ``"1800 rpm"``).

    >>> orders = gearlab.gearbox_orders("phm09", speed="30 Hz")
    >>> [(s["stage"], s["mesh_order"], s["mesh_hz"]) for s in orders["stages"]]
    [(1, 32.0, 960.0), (2, 16.0, 480.0)]
    """
    from .gearbox import order_table, speed_hz

    box = gearbox if hasattr(gearbox, "stages") else load_gearbox(gearbox)
    return order_table(box).describe(None if speed is None else speed_hz(speed, "speed"))


# --- datasets: simulated and imported ------------------------------------------------------------


def _dataset(where: str, entry: Mapping[str, Any]) -> Dataset:
    """A [[datasets]] entry checked as a scenario's is (kinds.common), built or read from the cache."""
    from .data.cache import load_or_build
    from .kinds.common import DATASET_TABLE, dataset_spec
    from .scenario import location, validate_table

    values = validate_table(where, "datasets", DATASET_TABLE, dict(entry))
    spec = dataset_spec(values, location(where, "datasets"), Path.cwd())
    return load_or_build(spec)[0]


def simulate(preset: str | DatasetSpec, **keys) -> Dataset:
    """A simulated dataset: a preset (``B-6-ch5``, ``A-pinion``, ...; docs/scenarios.md) with the keys
    of a scenario's ``[[datasets]]`` entry (docs/settings.md: ``teeth``, ``faults``, ``healthy``,
    ``speed``, ``effects``, the noise a ``sensor_noise`` among them, ...), or a DatasetSpec as it is.
    Built once, then read from the dataset cache (``GEARLAB_CACHE``). ``X`` holds one standardised
    revolution (4096 points) a row, ``label`` its class (0 healthy), ``fault`` 0/1.

    >>> data = gearlab.simulate("B-6-ch5", teeth=[1, 2], faults={"crack": [13]}, healthy=8)
    >>> data.X.shape, data.spec.class_names, int(data.fault.sum())
    ((10, 4096), ('healthy', 'crack'), 2)
    """
    from .data.spec import DatasetSpec

    if isinstance(preset, DatasetSpec):
        if keys:
            raise GearlabInputError(
                f"gearlab.simulate: a DatasetSpec is simulated as it is; got keys {', '.join(keys)} "
                "(use spec.with_(...), or give a preset name with the keys)"
            )
        from .data.cache import load_or_build

        return load_or_build(preset)[0]
    return _dataset("gearlab.simulate", {"preset": preset, **keys})


def simulate_signals(
    model: str | None = None,
    preset: str | None = None,
    *,
    gearbox: str | Path | None = None,
    speed: float | None = None,
    load: float | None = None,
    faults: Sequence[str] = (),
    duration: float = 0.4,
    fs: float = 200e3,
    flag=lambda key: key,
) -> Simulation:
    """One run of a dynamic model, as ``gearlab simulate`` makes it (docs/physics.md): Newmark
    integration from the static equilibrium at a fixed input *speed* (Hz) and *load* (N*m; both
    the preset's by default) for *duration* s at *fs* Hz. *model* and *preset* (default: the model's
    first), or a *gearbox* description (its model unless *model*, its values, speed and load);
    *faults*: ``KIND@TOOTH=STEP`` or ``KIND@TOOTH:NAME=VALUE,...`` as ``--fault`` takes them.
    Returns ``t``, ``tacho`` (the input-shaft angle), ``tvms`` (N/m) and ``channels`` (m/s²).
    *flag* names a keyword in an error (the CLI passes its options).

    >>> sim = gearlab.simulate_signals("six_dof", preset="meng2020", faults=["crack@1=20"], duration=0.05)
    >>> sorted(sim.channels), sim.t.size, sim.speed_hz, [f.label for f in sim.faults]
    (['gear_x', 'gear_y', 'pinion_x', 'pinion_y'], 10001, 40.0, ['crack@1'])
    """
    from .gearbox.simulation import simulate_command
    from .physics.faults import place_fault_option
    from .registry import get_registry

    model, preset, speed, load = simulate_command(
        None if gearbox is None else str(gearbox), model, preset, speed, load, flag
    )
    sim = simulator(model, preset, fs=fs, flag=flag)
    where = flag("fault")
    placed = [place_fault_option(get_registry(), sim.pair, text, f"{where} {text!r}") for text in faults]
    return sim.run(placed, speed, load, duration)


def simulator(
    model: str | None = None,
    preset: str | None = None,
    *,
    gearbox: str | Path | None = None,
    fs: float = 200e3,
    flag=lambda key: key,
):
    """The simulator (gearlab.dynamics.newmark.Simulator) of *model* and *preset* (default: the
    model's first) or of a *gearbox* description, with the checks of simulate_signals: what
    simulate_signals runs and ``gearlab modes`` reads the natural frequencies of. *flag*: as there."""
    from .dynamics.newmark import Simulator
    from .gearbox.simulation import model_command
    from .registry import get_registry

    if gearbox is not None:
        model, preset = model_command(str(gearbox), model, preset, flag)
    elif model is None:
        raise GearlabInputError(f"give {flag('model')} NAME (and {flag('preset')}) or {flag('gearbox')} DESCRIPTION")
    dynamic = get_registry().get("model", model, flag("model"))
    if preset is None and not dynamic.presets:  # three_stage: no built-in train of three stages
        raise GearlabInputError(f"{flag('model')} {model}: no built-in preset; give {flag('gearbox')} DESCRIPTION")
    return Simulator(dynamic, next(iter(dynamic.presets)) if preset is None else preset, fs)


def _si(value, unit: str, where: str) -> float | None:
    from .units import to_si

    return None if value is None else to_si(value, unit, where)


def _rate(value, where: str) -> float | None:
    from .units import rate_hz

    return None if value is None else rate_hz(value, where)


def read_recording(
    path: str | Path,
    vibration: str | int,
    tacho: str | int | None = None,
    *,
    fs: float | str | None = None,
    sensitivity: float | str | None = None,
    gain: float | str | None = None,
    unit: str | None = None,
) -> Recording:
    """One measured file as it is (docs/recordings.md: .csv, .txt, .zip, .npz, .h5, .wav, .mat): the
    vibration in m/s² (through *sensitivity*, e.g. ``"100 mV/g"``, and *gain*, volts per file unit, or without a
    sensitivity g per volt or per file unit, e.g. ``"50 g"``, a WAV's full scale;
    *unit*, ``"g"``, ``"m/s^2"``, ``"V"`` or ``"mV"``, where the channel's name and file say none),
    the tacho as stored and the sampling rate (the file's, or *fs*, e.g. ``"20 kHz"``).

    >>> import numpy as np
    >>> t = np.arange(20_000) / 20e3                           # 1 s at 20 kHz; the shaft at 25 Hz
    >>> acc = 0.1 * np.cos(2 * np.pi * 16 * 25 * t)            # a 16-tooth mesh, in volts
    >>> np.savez("rig.npz", acc=acc, tacho=(25 * t % 1 < 0.1).astype(float), fs=20e3)
    >>> rec = gearlab.read_recording("rig.npz", "acc", "tacho", sensitivity="100 mV/g")
    >>> rec.fs, rec.signal.size, round(float(rec.signal.max()), 3)   # 0.1 V at 100 mV/g: 1 g
    (20000.0, 20000, 9.807)
    """
    from .data.recordings import read_recording as read
    from .data.textzip import calibration

    chain = calibration({"sensitivity": sensitivity, "gain": gain}, lambda key: key)
    return read(path, vibration, tacho, fs=_rate(fs, "fs"), **chain, unit=_unit(unit, "unit"))


def _unit(value: str | None, where: str) -> str | None:
    """A 'unit' as a scenario's key takes it (recordings.UNITS), else a one-line error naming *where*."""
    from .data.channel_units import declared_unit

    return declared_unit(value, where)


def import_recording(path: str | Path, vibration: str | int, **keys) -> Dataset:
    """A measured file as a dataset of revolutions, as a scenario's ``[[datasets]]`` entry with
    ``file`` imports it (docs/real_data.md): cut at the tacho (``tacho``, ``pulses_per_rev``) or a
    ``speed``, resampled to 4096 points a revolution, standardised against its healthy class.
    Keys: those of ``[[datasets]]`` (docs/settings.md: ``tacho``, ``labels``, ``sensitivity``, ``fs``,
    ``transient``, ...). Without ``labels`` every revolution is unlabelled (label -1).

    >>> import numpy as np
    >>> t = np.arange(40_000) / 20e3                           # 2 s at 20 kHz; the shaft at 25 Hz
    >>> acc = np.sin(2 * np.pi * 16 * 25 * t) + 0.1 * np.random.default_rng(0).standard_normal(t.size)
    >>> np.savez("rig.npz", acc=acc, tacho=(25 * t % 1 < 0.1).astype(float), fs=20e3)
    >>> data = gearlab.import_recording("rig.npz", "acc", tacho="tacho", transient="none")
    >>> data.X.shape, set(data.label.tolist()), round(data.meta["speed_hz"], 4)  # a square tacho: edges ±0.5 sample
    ((48, 4096), {-1}, 25.0)
    """
    return _dataset("gearlab.import_recording", {"file": str(path), "vibration": vibration, **keys})


def inspect_options(
    *,
    vibration: str | None = None,
    tacho: str | None = None,
    tacho_kind: str = "auto",
    pulses_per_rev: int | None = None,
    tacho_shaft: str | None = None,
    speed: float | str | None = None,
    fs: float | str | None = None,
    sensitivity: float | str | None = None,
    gain: float | str | None = None,
    unit: str | None = None,
    flag=lambda key: key,
):
    """InspectOptions from the user's texts (inspect_recording's keywords, which `gearlab inspect`'s
    options are), checked once: a wrong value is one line naming *flag(key)* (the CLI passes
    '--pulses-per-rev' for 'pulses_per_rev')."""
    from .data.importers import TACHO_KINDS
    from .data.textzip import calibration, gain_quantity
    from .inspect import InspectOptions
    from .parts.measured import speed_of

    kind, ppr = tacho_kind, pulses_per_rev
    if kind not in TACHO_KINDS:
        raise GearlabInputError(f"{flag('tacho_kind')}: {kind!r} is not one of {', '.join(TACHO_KINDS)}")
    if ppr is not None and not 1 <= ppr <= 10_000:
        raise GearlabInputError(f"{flag('pulses_per_rev')}: expected 1 .. 10000, got {ppr}")
    rate = _rate(fs, flag("fs"))
    if rate is not None and not 0 < rate <= 1e7:
        raise GearlabInputError(f"{flag('fs')}: expected a sampling rate in (0, 10 MHz], got {fs!r}")
    if gain is not None and not gain_quantity(gain, flag("gain"))[0] > 0:
        raise GearlabInputError(f"{flag('gain')}: expected a positive number of volts per file unit, got {gain!r}")
    chain = calibration({"sensitivity": sensitivity, "gain": gain}, flag)
    return InspectOptions(
        vibration=vibration,
        tacho=tacho,
        tacho_kind=kind,
        pulses_per_rev=ppr,
        tacho_shaft=tacho_shaft,
        speed_hz=None if speed is None else speed_of(speed, flag("speed")),  # as [target] key 'speed'
        fs=rate,
        **chain,
        unit=_unit(unit, flag("unit")),
    )


def inspect_recording(
    path: str | Path,
    gearbox: Gearbox | str | Path | None = None,
    *,
    history: Sequence[str | Path] = (),
    history_keys: Mapping[str, Mapping[str, str]] | Sequence[str] | None = None,
    flag=lambda key: key,
    **options,
) -> dict:
    """What ``gearlab inspect`` shows of a recording, as a dict: rate, duration, channels, the speed
    (from the tacho, a declared *speed* or the mesh lines of *gearbox*), the order spectrum's lines
    and the TSA of each shaft; with a *gearbox*, whether the description matches (``matches``; None
    where the pinion's tooth count cannot be confirmed without a tacho or the speed; ``verdict``); with
    *history* (healthy records of the same gearbox) and a *gearbox*, which shaft and gear carry a
    localised change, else a non-synchronous one, and the call (``localisation``). The arrays (``spectrum``,
    each ``tsa``) are kept. *options*:
    ``vibration``, ``tacho``, ``tacho_kind`` (auto, angle, pulses), ``pulses_per_rev``, ``tacho_shaft``,
    ``speed``, ``fs``, ``sensitivity``, ``gain``, ``unit``, as inspect_options checks them; *flag* names
    a keyword in an error (the CLI passes its options). A history file is read with the same options but
    for *history_keys*: {"": {key: value}} for every history file, {file name: {key: value}} for one (a
    history logged in another format than the record, or in several, keeps each file's own channels), or
    the texts KEY=VALUE, FILE:KEY=VALUE of `gearlab inspect --history-key`.

    >>> import numpy as np
    >>> t = np.arange(40_000) / 20e3
    >>> acc = np.sin(2 * np.pi * 16 * 25 * t) * (1 + 0.2 * np.sin(2 * np.pi * 25 * t))
    >>> np.savez("rig.npz", acc=acc, tacho=(25 * t % 1 < 0.1).astype(float), fs=20e3)
    >>> report = gearlab.inspect_recording("rig.npz", "luo2019", vibration="acc", tacho="tacho")
    >>> report["revolutions"], round(report["lines"][0]["order"], 2), report["matches"]
    (48, 16.0, True)
    """
    from .inspect import inspect_record
    from .inspect_history import localisation

    checked = inspect_options(flag=flag, **options)
    box = None if gearbox is None else gearbox if hasattr(gearbox, "stages") else load_gearbox(gearbox)
    if box is not None and checked.tacho_shaft is not None:
        box.shaft_index(checked.tacho_shaft, flag("tacho_shaft"))
    if history and box is None:
        raise GearlabInputError(
            f"{flag('history')}: localising needs the gearbox's shafts and teeth; give {flag('gearbox')} too"
        )
    if history_keys and not isinstance(history_keys, Mapping):
        history_keys = parse_history_keys(history_keys, flag)
    if history_keys and not history:
        raise GearlabInputError(f"{flag('history_key')}: keys of {flag('history')} files; expected those files too")
    taken: list = []  # the take read and its speed followed once: --history's localisation cuts the same
    report = inspect_record(str(path), box, checked, kept=taken)
    if history:
        read = _history_options([str(h) for h in history], history_keys or {}, options, flag)
        report["localisation"] = localisation(str(path), read, box, checked, tuple(taken))
    return report


HISTORY_KEYS = ("vibration", "tacho", "tacho_kind", "pulses_per_rev", "tacho_shaft", "speed", "fs", "sensitivity")
HISTORY_KEYS += ("gain", "unit", "takes")  # takes: a history file's takes each a history record (data.takes)


def _history_options(history: list[str], keys: Mapping[str, Mapping[str, str]], options: dict, flag) -> list:
    """[(history file, InspectOptions)]: the record's *options* with *keys*' "" entry over them, then the
    entry of the file's name (as given or its base name); a key or file name *keys* names wrongly: one line."""
    names = {n for h in history for n in (h, Path(h).name)}
    for name, table in keys.items():
        where = flag("history_key") + (f" '{name}:...'" if name else "")
        if name and name not in names:
            listed = ", ".join(Path(h).name for h in history)
            raise GearlabInputError(f"{where}: '{name}' is not a --history file; expected one of: {listed}")
        for key in table:
            if key not in HISTORY_KEYS:
                raise GearlabInputError(
                    f"{where}: unknown key {key!r}; expected KEY=VALUE, KEY one of {', '.join(HISTORY_KEYS)}"
                )
    from .data.takes import take_paths

    out: list = []
    for h in history:
        own = {**keys.get("", {}), **keys.get(Path(h).name, {}), **keys.get(h, {})}
        column = own.pop("takes", "")
        names = take_paths(h, column, f"{flag('history_key')} takes") if column else [h]
        if not own:  # read as the record is
            out += names
            continue
        given = {**options, **own}
        if isinstance(given.get("pulses_per_rev"), str):
            text = given["pulses_per_rev"]
            if not text.strip().isdigit():
                raise GearlabInputError(
                    f"{flag('history_key')} '{h}': pulses_per_rev = {text!r}; expected a whole number"
                )
            given["pulses_per_rev"] = int(text)
        given = {k: (None if v == "" and k != "tacho_kind" else v) for k, v in given.items()}
        read = inspect_options(flag=lambda key, h=h: f"{flag('history_key')} '{Path(h).name}:{key}'", **given)
        out += [(name, read) for name in names]
    return out


def parse_history_keys(texts: Sequence[str], flag=lambda key: key) -> dict[str, dict[str, str]]:
    """`--history-key` texts, KEY=VALUE (every history file) or FILE:KEY=VALUE (that file), as
    inspect_recording's *history_keys*."""
    out: dict[str, dict[str, str]] = {}
    for text in texts:
        left, eq, value = text.partition("=")
        name, _, key = left.rpartition(":")
        if not eq or not key.strip():
            raise GearlabInputError(
                f"{flag('history_key')} {text!r}: expected KEY=VALUE or FILE:KEY=VALUE, e.g. vibration=acc_V"
            )
        out.setdefault(name.strip(), {})[key.strip()] = value.strip()
    return out


# --- the gap between a simulator and a target ------------------------------------------------------


def _source_spec(source) -> DatasetSpec:
    from .data.spec import DatasetSpec, dataset_preset

    spec = getattr(source, "spec", source)
    if isinstance(spec, str):
        spec = dataset_preset(spec, "gearlab.diagnose_gap: source")
    if not isinstance(spec, DatasetSpec):
        raise GearlabInputError(
            f"gearlab.diagnose_gap: the source must be a simulation (a preset name, a DatasetSpec or a "
            f"simulated dataset), got {type(source).__name__}"
        )
    return spec


def diagnose_gap(source: str | DatasetSpec | Dataset, target: Dataset, **settings) -> dict:
    """Which unmodelled effects make the *source* simulator into the *target* (docs/gap.md): the gap
    before, the effects fitted and accepted, the gap after and a ``verdict``. *source*: a preset
    name, a DatasetSpec or a simulated dataset (its spec: the simulator configuration; its faults
    play no part); *target*: a dataset, simulated or imported, whose healthy revolutions (all of an
    unlabelled record) are the only thing of it the diagnosis sees. *settings*: the ``[diagnosis]``
    keys (docs/settings.md: ``candidates``, ``budget``, ``max_effects``, ``healthy``, ...).

    >>> target = gearlab.simulate("B-6-ch5", teeth=[1], faults={"crack": [13]}, healthy=30,
    ...                           effects=[{"name": "sensor_noise", "kind": "laplace", "snr_db": 10, "seed": 1}])
    >>> result = gearlab.diagnose_gap("B-6-ch5", target, candidates=["sensor_noise"], budget=4,
    ...                               max_effects=1, healthy=20, bootstrap=20, permutations=50)
    >>> result["verdict"], [(e["name"], e["params"]["kind"]) for e in result["effects"]]
    ('explained', [('sensor_noise', 'laplace')])
    """
    from .errors import did_you_mean
    from .gap.diagnose import Settings, diagnose_dataset
    from .settings import declared

    known = list(declared(Settings))
    for name in settings:
        if name not in known:
            raise GearlabInputError(
                f"gearlab.diagnose_gap: unknown setting '{name}'{did_you_mean(name, known)}; known: {', '.join(known)}"
            )
    if isinstance(settings.get("candidates"), list):
        settings["candidates"] = tuple(settings["candidates"])
    return diagnose_dataset(_source_spec(source), target, Settings(**settings))


def corrected_source(source: str | DatasetSpec | Dataset, result: dict) -> DatasetSpec:
    """The *source* with the effects a diagnosis fitted (``diagnose_gap``'s result) added: the
    corrected simulator, to simulate (``gearlab.simulate(spec)``) or to train on.

    >>> spec = gearlab.corrected_source("B-6-ch5", {"corrected_effects": [["sensor_noise",
    ...                                 [["kind", "laplace"], ["snr_db", 10.0]]]]})
    >>> [name for name, _ in spec.effects]
    ['sensor_noise']
    """
    from .gap.diagnose import corrected_source as corrected

    return corrected(_source_spec(source), result)


# --- detectors ---------------------------------------------------------------------------------------


def _rows(data, where: str):
    import numpy as np

    X = np.asarray(getattr(data, "X", data), dtype=np.float32)
    if X.ndim != 2:
        raise GearlabInputError(f"{where}: expected revolutions (n, points) or a dataset, got shape {X.shape}")
    return X


def fit_detector(
    method: str,
    source: Dataset,
    target: Dataset | np.ndarray,
    target_labels: Sequence[int] | np.ndarray | None = None,
    **params,
):
    """A detector that trains no network (docs/learning.md: ``likelihood_ratio``, ``matched_filter``,
    or a plugin's), built from the simulated *source* (its revolutions and fault labels) and the
    target's training revolutions: a dataset or an array, all taken as the healthy history unless
    *target_labels* (0 healthy, 1 fault) say otherwise. *params*: the method's parameters
    (``false_alarm``, ``path``, ...; ``gearlab plugins`` lists them). Revolutions are given
    standardised, as datasets hold them.

    >>> source = gearlab.simulate("B-6-ch5", teeth=[1, 2, 3], faults={"crack": [13]}, healthy=9)
    >>> target = gearlab.simulate("B-8-ch5", teeth=[1, 2, 3], faults={"crack": [13]}, healthy=40,
    ...                           effects=[{"name": "sensor_noise", "kind": "laplace", "snr_db": 0, "seed": 1}])
    >>> history = target.X[target.fault == 0][:30]                # healthy revolutions, no labels used
    >>> detector = gearlab.fit_detector("likelihood_ratio", source, history, false_alarm=0.05)
    >>> type(detector).__name__
    'LikelihoodDetector'
    """
    import numpy as np

    from .registry import get_registry

    where = f"gearlab.fit_detector('{method}')"
    registry = get_registry()
    if registry.kind_of(method) == "adapter":
        raise GearlabInputError(
            f"{where}: '{method}' trains a network (an adapter); expected a detector "
            f"({', '.join(registry.names('detector'))}): run a scenario to train a network"
        )
    detector = registry.get("detector", method, where)
    if not hasattr(source, "fault"):
        raise GearlabInputError(f"{where}: the source must be a labelled dataset (gearlab.simulate)")
    Xs, ys = _rows(source, f"{where}: source"), np.asarray(source.fault)
    Xt = _rows(target, f"{where}: target")
    yt = None if target_labels is None else np.asarray(target_labels)
    if yt is not None and yt.shape != (len(Xt),):
        raise GearlabInputError(f"{where}: {len(yt)} target labels for {len(Xt)} target revolutions")
    return detector.fit((Xs, ys), (Xt, yt), detector.resolve(params, where))


def detector_scores(detector, revolutions: Dataset | np.ndarray) -> np.ndarray:
    """Each revolution's score less the detector's threshold: above 0, a fault is called.

    >>> source = gearlab.simulate("B-6-ch5", teeth=[1, 2, 3], faults={"crack": [13]}, healthy=9)
    >>> detector = gearlab.fit_detector("matched_filter", source, source.X[source.fault == 0])
    >>> scores = gearlab.detector_scores(detector, source.X)
    >>> bool((scores[source.fault == 1] > 0).all())               # the source's own faults
    True
    """
    import numpy as np
    import torch

    X = _rows(revolutions, "gearlab.detector_scores")
    with torch.no_grad():
        logits = detector(torch.as_tensor(X)).numpy()
    # a detector's logits are [0, score - threshold] (gearlab.learn.detector_contract: scored as a network's)
    return np.asarray(logits[:, 1] - logits[:, 0], dtype=np.float64)


def score_detector(
    detector, revolutions: Dataset | np.ndarray, fault: Sequence[int] | np.ndarray | None = None
) -> dict:
    """How a detector does on labelled revolutions (*fault*: 0 healthy, 1 fault; a dataset's own by
    default): ``auc`` (ROC area of its scores), ``detected`` (share of faults called) and
    ``false_alarms`` (share of healthy revolutions called), with the counts.

    >>> source = gearlab.simulate("B-6-ch5", teeth=[1, 2, 3], faults={"crack": [13]}, healthy=9)
    >>> detector = gearlab.fit_detector("matched_filter", source, source.X[source.fault == 0])
    >>> gearlab.score_detector(detector, source)["auc"]
    1.0
    """
    import numpy as np

    from .parts.roc import auc

    labels = getattr(revolutions, "fault", None) if fault is None else fault
    if labels is None:
        raise GearlabInputError("gearlab.score_detector: give the revolutions' fault labels (0 healthy, 1 fault)")
    y = np.asarray(labels)
    scores = detector_scores(detector, revolutions)
    if y.shape != scores.shape:
        raise GearlabInputError(f"gearlab.score_detector: {y.size} labels for {scores.size} revolutions")
    healthy, faulty = scores[y == 0], scores[y == 1]
    return {
        "auc": auc(healthy, faulty),
        "detected": float(np.mean(faulty > 0)) if faulty.size else None,
        "false_alarms": float(np.mean(healthy > 0)) if healthy.size else None,
        "healthy": int(healthy.size),
        "faults": int(faulty.size),
    }


# --- scenarios and runs ------------------------------------------------------------------------------


def load_scenario(path: str | Path | None = None, *, run: RunDir | str | Path | None = None) -> Scenario:
    """A scenario file read and checked as ``gearlab validate`` does (every table and key; plugin
    names; measured files' headers): its ``kind``, ``tables`` (defaults filled) and ``spec``; with
    *run* instead, the scenario that run ran (its command line's keys set, shrunk alike if --quick).

    >>> Path("one.toml").write_text('[scenario]\\nname = "one"\\nkind = "dataset"\\n'
    ...                             '[[datasets]]\\npreset = "B-6-ch5"\\nhealthy = 4\\n') and None
    >>> scenario = gearlab.load_scenario("one.toml")
    >>> scenario.kind, [spec.healthy for spec in scenario.spec]
    ('dataset', [4])
    """
    if run is not None:
        from .engine import scenario_of

        return scenario_of(open_run(run) if isinstance(run, (str, Path)) else run)
    if path is None:
        raise GearlabInputError("load_scenario: give a scenario file or run=")
    from .engine import load_scenario as load

    return load(path)


def validate_scenario(path: str | Path) -> str:
    """What ``gearlab validate`` (and the TUI's Validate) says of a scenario file or a gearbox description: its OK
    line, a mistake raised as its one-line GearlabInputError. Beyond load_scenario's checks, the measured files are
    read past their headers where that is cheap: a logger's footer is warned of, and a detection history whose
    takes' tachos show it too short for its units is refused in the run's own line.

    >>> Path("two.toml").write_text('[scenario]\\nname = "two"\\nkind = "dataset"\\n'
    ...                             '[[datasets]]\\npreset = "B-6-ch5"\\nhealthy = 4\\n') and None
    >>> gearlab.validate_scenario("two.toml")
    "OK: two.toml: scenario 'two' (kind dataset); ..."
    """
    from .data.readers.headers import footers_said
    from .gearbox import validated_description
    from .kinds import SCENARIO_KINDS

    if said := validated_description(Path(path)):  # a description alone was told 'missing table [scenario]'
        return said
    s = footers_said(lambda: load_scenario(path))
    return f"OK: {path}: scenario '{s.name}' (kind {s.kind}); {SCENARIO_KINDS[s.kind].describe(s)}"


def run_scenario(
    path: str | Path | None = None,
    *,
    resume: str | Path | None = None,
    quick: bool = False,
    out: str | Path | None = None,
    overrides: Mapping[str, Mapping[str, Any]] | None = None,
    on_event=None,
) -> RunDir:
    """Run a scenario file as ``gearlab run`` does, into a new run directory under *out* (default:
    its ``[output] dir``), or on in the run directory *resume* (its finished units kept); *quick*: the
    smoke-test sizes (``--quick``); *overrides*: ``{table: {key:
    value}}`` replacing keys of the file; *on_event*: a callback for the progress events. Returns the
    run directory: ``.path``, ``.summary()``, ``.records()``; ``run_verdict(run)``.

    >>> Path("one.toml").write_text('''
    ... [scenario]
    ... name = "one"
    ... kind = "dataset"
    ... [[datasets]]
    ... preset = "B-6-ch5"
    ... teeth = [1]
    ... faults = { crack = [13] }
    ... healthy = 4
    ... ''') and None
    >>> run = gearlab.run_scenario("one.toml", out="runs")
    >>> [(r["unit"], r["n"]) for r in run.records()]
    [('B-6-ch5', 5)]
    """
    from .engine import run_scenario as run
    from .events import ignore_events

    return run(path, resume=resume, quick=quick, out=out, overrides=overrides, on_event=on_event or ignore_events)


def open_run(path: str | Path) -> RunDir:
    """A run directory written before (``gearlab runs`` lists them), to read its ``summary()`` and
    ``records()``; refused when it holds a link or another account's entry."""
    from .runs import RunDir

    return RunDir.open(Path(path))


def run_verdict(run: RunDir | str | Path) -> list[str]:
    """The verdict of a finished run, as ``gearlab run`` ends with it and report.html opens with it
    ([] for kinds without one)."""
    from .verdict import verdict_lines

    return verdict_lines(run)


def score_recordings(
    run: RunDir | str | Path,
    files: Sequence[str | Path],
    condition: str | None = None,
    on_event=None,
    given: dict | None = None,
) -> list[dict]:
    """New recordings scored by a finished detection run's trained methods at its thresholds, nothing
    trained again, as ``gearlab score RUN_DIR FILE...`` does (docs/your_gearbox.md): the files are
    read with the run's ``[target]`` keys (*given*: the files' own, e.g. ``{"vibration": "vib"}``,
    as a ``files`` entry gives them), in the *condition* of nearest speed unless named. One row
    per file, method and unit: ``units``, ``called`` (over the threshold), ``median_score``,
    ``threshold``, ``decision``, and which gear the change lies on (``localised``, ``evidence``).
    The rows are appended to the run's scoring history, whose trend its report shows.

    >>> import numpy as np
    >>> t = np.arange(40_000) / 20e3                           # 2 s at 20 kHz; the shaft at 25 Hz
    >>> for i, name in enumerate(["h1", "h2", "ok", "chip", "today_ok", "today"]):
    ...     acc = 0.1 * np.sin(2 * np.pi * 400 * t) + 0.01 * np.random.default_rng(i).standard_normal(t.size)
    ...     acc += 0.05 * ("chip" in name or name == "today") * (25 * t % 1 < 0.02)  # a knock a turn
    ...     np.savez(f"{name}.npz", acc=acc, tacho=(25 * t % 1 < 0.1).astype(float), fs=20e3)
    >>> Path("watch.toml").write_text('''
    ... [scenario]
    ... name = "watch"
    ... kind = "detection"
    ... [source]
    ... gearbox = "luo2019"
    ... faults = { chip = [20] }
    ... teeth = [1, 2]
    ... healthy = 8
    ... [target]
    ... vibration = "acc"
    ... tacho = "tacho"
    ... sensitivity = "100 mV/g"
    ... files = [{ file = "h1.npz", role = "history", label = "healthy" },
    ...          { file = "h2.npz", role = "history", label = "healthy" },
    ...          { file = "ok.npz", role = "test", label = "healthy" },
    ...          { file = "chip.npz", role = "test", label = "fault" }]
    ... [[methods]]
    ... adapter = "matched_filter"
    ... [detection]
    ... blocks = [10]
    ... [protocol]
    ... batch = 8
    ... [execution]
    ... workers = 1
    ... ''') and None
    >>> run = gearlab.run_scenario("watch.toml", out="runs")
    >>> rows = gearlab.score_recordings(run, ["today_ok.npz", "today.npz"])
    >>> [(r["file"], r["decision"]) for r in rows if r["method"] == "fm4" and r["unit"] == "record10"]
    [('today_ok.npz', 'healthy'), ('today.npz', 'fault')]
    """
    from .engine import score_recordings as score
    from .events import ignore_events
    from .runs import RunDir

    run = run if isinstance(run, RunDir) else RunDir.open(Path(run))
    given = dict(given or {})
    column = given.pop("takes", None)  # a logger's file of several takes: each scored as a record of its own
    known = (run.read_json("scoring.json") or {}).get("takes", [])  # else as the run's files were split
    return score(run, takes(files, column, known), condition, on_event or ignore_events, given)


def takes(names: Sequence[str | Path], column: str | None = None, known: Sequence[str] = ()) -> list[Path]:
    """The takes *names* stand for, as a [target] 'files' entry reads them: a file, a folder's records (its
    files of a format gearlab reads, sorted by name) or a glob pattern's matches (files.matched); each file's
    takes under *column* (its 'takes' key, "log.csv[segment=3]"; None: under the first of *known* it has,
    data.takes.file_takes)."""
    from .data.recordings import FORMATS
    from .data.takes import file_takes
    from .files import matched

    if column or (column is None and known):  # "" (--key takes=): each file one take, as the run's were not
        return [Path(t) for file in takes(names) for t in file_takes(file, column, "--key takes", known)]

    out = []
    for name in map(Path, names):
        if name.is_dir():
            found = sorted(p for p in name.iterdir() if p.is_file() and p.suffix.lower() in FORMATS)
            if not found:
                raise GearlabInputError(f"{name}: a folder holding no measured record; expected {', '.join(FORMATS)}")
            out += found
        else:
            out += [Path(m) for m in matched(str(name), Path("."), f"gearlab score FILE {str(name)!r}")]
    return out
