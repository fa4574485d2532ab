"""Dataset specifications and the presets of the thesis (2.4.3, Table 4.1, Tables 5.1, 5.2).

A dataset is a set of one-revolution samples (4096 points in the input-shaft angle) from
one model, preset, operating point and channel, with faults over their ladders on every
pinion tooth, healthy samples, optional noise and TSA. The spec is all that defines it:
its canonical JSON, hashed with the physics version, is the cache key.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace

from .. import PHYSICS_VERSION
from ..effects import EffectChain, check_effect_specs, config_of
from ..errors import GearlabInputError, did_you_mean
from ..physics.faults import LADDER_STEPS
from ..registry import get_registry
from ..settings import MAX_SEED, setting
from ..signals import NOISE_KINDS, SNR_DB_RANGE
from .placement import fault_classes

POINTS = 4096  # samples per revolution (thesis 2.4)
FAULTS = ("crack", "chip", "spall", "pit")


@dataclass(frozen=True)
class NoiseSpec:
    """A dataset's measurement noise, drawn from its own seed after every effect: what a scenario's
    ``effects = [{name = "sensor_noise", kind = "laplace", snr_db = 0, seed = 1}]`` declares (a
    sensor_noise with a seed; gearlab.kinds.common.effects_and_noise, checked by settings.from_inline)."""

    kind: str = setting(str, choices=NOISE_KINDS, doc="noise distribution (thesis 4.1)")
    snr_db: float = setting(
        float,
        unit="dB",
        low=SNR_DB_RANGE[0],
        high=SNR_DB_RANGE[1],
        doc="signal-to-noise ratio: noise RMS = signal RMS x 10^(-SNR/20)",
    )
    seed: int = setting(int, 0, low=0, high=MAX_SEED, doc="seed of the noise draws")


@dataclass(frozen=True)
class DatasetSpec:
    name: str
    model: str
    preset: str
    channel: str
    speed_hz: float | None = None  # None: the preset's operating point
    load_nm: float | None = None
    # (class key, ladder steps): the fault plugin's name on the input pinion, "NAME@GEAR" on another gear
    # (gearlab.data.placement.fault_key: chip@wheel, chip@s2-wheel), which the class name then says
    faults: tuple[tuple[str, tuple[int, ...]], ...] = ()
    teeth: tuple[int, ...] | None = None  # None: every tooth of the faulted gear
    duplicates: int = 1
    healthy: int = 0
    revolutions: int = 1  # J noisy revolutions per sample: TSA averages them, else the first is kept
    noise: NoiseSpec | None = None
    tsa: bool = False
    seed: int = 0
    fs: float = 200e3
    domain: str = ""
    # Unmodelled effects (gearlab.effects; the gap diagnosis, docs/gap.md): ((name, ((param, SI value), ...)), ...),
    # each resolved and sorted by gearlab.effects.effect_spec; applied model -> excitation -> signal.
    effects: tuple[tuple[str, tuple[tuple[str, object], ...]], ...] = ()
    # Every fault sample made healthy at the same point (its cycle revolution, tooth turn, effects and
    # noise draws): the dataset's healthy twin, whose row i a fault row i differs from by the fault
    # alone (builder.build_dataset; the detectors' templates on a train of a long cycle)
    healthy_twin: bool = False
    # (p, q): every row is a revolution (or TSA) of the shaft turning p/q times per input turn, not
    # of the input shaft (builder.noisy_rows; the detection kind's units of a watched gear on a
    # slower shaft: detection_records.unit_shaft); (): the input shaft
    unit_shaft: tuple[int, ...] = ()

    def canonical(self) -> dict:
        d = asdict(self)
        d.pop("name")  # a label, not part of what the data are
        d.pop("domain")
        if not self.effects:
            d.pop("effects")  # so every dataset without effects keeps the key it had before effects existed
        if not self.healthy_twin:
            d.pop("healthy_twin")  # likewise for every dataset that is no twin
        if not self.unit_shaft:
            d.pop("unit_shaft")  # likewise for every dataset of input-shaft rows
        else:  # 3: fault rows start anywhere in the cycle, input orders out, the cut read cubic 2 x denser
            d["shaft_rows"] = 3
        return d

    def key(self) -> str:
        text = json.dumps({"spec": self.canonical(), "physics": PHYSICS_VERSION}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:24]

    def with_(self, **changes) -> DatasetSpec:
        return replace(self, **changes)

    @property
    def class_names(self) -> tuple[str, ...]:
        return ("healthy",) + tuple(name for name, _ in self.faults)

    def check(self, where: str = "") -> None:
        where = where or f"dataset '{self.name}'"
        for name, steps in self.faults:
            for s in steps:
                if isinstance(s, bool) or not isinstance(s, int) or not 1 <= s <= LADDER_STEPS:
                    raise GearlabInputError(
                        f"{where} key 'faults': fault '{name}' step {s!r} is outside 1..{LADDER_STEPS}"
                    )
        for label, value, low in (
            ("duplicates", self.duplicates, 1),
            ("healthy", self.healthy, 0),
            ("revolutions", self.revolutions, 1),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise GearlabInputError(f"{where}: '{label}' must be a whole number >= {low}, got {value!r}")
        if self.noise is not None and self.noise.kind not in NOISE_KINDS:
            raise GearlabInputError(
                f"{where}: unknown noise kind '{self.noise.kind}'{did_you_mean(self.noise.kind, NOISE_KINDS)}; "
                f"known: {', '.join(NOISE_KINDS)}"
            )
        if self.tsa and self.revolutions < 2:
            raise GearlabInputError(f"{where}: TSA needs revolutions >= 2, got {self.revolutions}")
        if not self.faults and not self.healthy:
            raise GearlabInputError(f"{where}: the dataset has no samples (no faults and healthy = 0)")
        check_effect_specs(self.effects, f"{where}: effects")

    def check_model(self, where: str = ""):
        """What needs the registry: the model, its preset and channel, the fault names, the
        teeth (1..Z1 of the preset's pinion) and the effects with their parameters and the
        configuration they make. Returns (model plugin, gear pair, teeth)."""
        where = where or f"dataset '{self.name}'"
        registry = get_registry()
        model = registry.get("model", self.model, where)
        pair, _ = model.resolve(self.preset, where=where)
        if self.channel not in model.channels:
            raise GearlabInputError(
                f"{where}: model '{self.model}' has no channel '{self.channel}'; "
                f"its channels: {', '.join(model.channels)}"
            )
        if self.effects:
            self.model_config(where)  # effect names, parameters and what they do to the model
        teeth = tuple(range(1, pair.Z1 + 1)) if self.teeth is None else self.teeth
        classes = fault_classes(model, self.preset, self.faults, self.teeth, where)  # gears and their teeth
        if not classes or any((c.stage, c.gear) == (1, "pinion") for c in classes.values()):
            for n in teeth:
                if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= pair.Z1:
                    raise GearlabInputError(f"{where} key 'teeth': tooth {n!r} is outside 1..{pair.Z1}")
        for c in classes.values():
            for name, _, _ in c.parts:
                registry.get("fault", name, f"{where} key 'faults'")  # (a scenario's '[source]: unknown fault')
        return model, pair, teeth

    def fault_classes(self, where: str = ""):
        """Each fault class resolved on the model: its plugin, gear (stage, pinion or wheel) and teeth
        (gearlab.data.placement.FaultClass), by class key."""
        where = where or f"dataset '{self.name}'"
        model = get_registry().get("model", self.model, where)
        return fault_classes(model, self.preset, self.faults, self.teeth, where)

    def effect_chain(self, where: str = ""):
        """The dataset's effects, loaded and ordered by level (gearlab.effects.EffectChain)."""
        return EffectChain.load(self.effects, f"{where or f'dataset {self.name!r}'}: effects")

    def model_config(self, where: str = ""):
        """The simulator configuration after the model-level effects (gearlab.dynamics.config.ModelConfig)."""
        where = where or f"dataset '{self.name}'"
        source = config_of(self.model, self.preset, self.channel, where)
        return self.effect_chain(where).model_config(source, where)


def _ladders(steps: Mapping[str, tuple[int, ...]]) -> tuple[tuple[str, tuple[int, ...]], ...]:
    return tuple((name, tuple(steps[name])) for name in FAULTS)


ALL_STEPS = tuple(range(1, LADDER_STEPS + 1))
# Chapter 5 keeps the three top intensities, and for cracks three middle ones (5.4.1). The
# text says "the 10th to 13th", four steps, but Tables 5.1/5.2 count three per tooth
# (48 = 3 x 16, 75 = 3 x 25); we take 11-13 (docs/learning.md).
CH5_STEPS = {"crack": (11, 12, 13), "chip": (18, 19, 20), "spall": (18, 19, 20), "pit": (18, 19, 20)}

_A = dict(model="ten_dof", preset="luo2019", speed_hz=25.2, load_nm=7.0)
_B = dict(preset="meng2020", speed_hz=40.0, load_nm=20.0, channel="pinion_y")


def _chapter2(name, **kw) -> DatasetSpec:
    # Every fault at every intensity on every tooth once, and as many healthy samples.
    spec = DatasetSpec(name=name, faults=_ladders({f: ALL_STEPS for f in FAULTS}), domain=name, **kw)
    return spec


def _presets() -> dict[str, DatasetSpec]:
    out = {
        "A-pinion": _chapter2("A-pinion", channel="pinion_x", **_A),
        "A-casing": _chapter2("A-casing", channel="casing_x", **_A),
        "B-6": _chapter2("B-6", model="six_dof", **_B),
        "B-8": _chapter2("B-8", model="eight_dof", **_B),
    }
    for name in list(out):
        z1 = 16 if name.startswith("A") else 25
        out[name] = out[name].with_(healthy=len(FAULTS) * LADDER_STEPS * z1)
    # Chapter 4 (Table 4.1): 4 faults x 20 intensities x 16 teeth x 5 duplicates + 6400 healthy,
    # SNR 1 (0 dB), J = 60; the noisy set keeps the first revolution, the TSA set averages all 60.
    for kind in NOISE_KINDS:
        base = out["A-casing"].with_(duplicates=5, healthy=6400, revolutions=60, noise=NoiseSpec(kind, 0.0, 0))
        out[f"A-casing_noise-{kind}"] = base.with_(name=f"A-casing_noise-{kind}", domain=f"A-casing_noise-{kind}")
        out[f"A-casing_TSA-{kind}"] = base.with_(name=f"A-casing_TSA-{kind}", domain=f"A-casing_TSA-{kind}", tsa=True)
    # Chapter 5 (Tables 5.1, 5.2): one sample per fault, intensity and tooth; a healthy sample per
    # fault sample plus a quarter more (240 = 192 + 48, 375 = 300 + 75).
    for name, healthy in (("A-pinion", 240), ("A-casing", 240), ("B-6", 375), ("B-8", 375)):
        out[f"{name}-ch5"] = out[name].with_(
            name=f"{name}-ch5", domain=f"{name}-ch5", faults=_ladders(CH5_STEPS), healthy=healthy
        )
    # The PHM 2009 spur rig (docs/real_data.md): the two-stage model, sensor on the casing, at the
    # records' nominal speeds and their sampling rate (66 666.67 Hz, rounded up to whole steps per
    # tooth pitch), so a simulated revolution has the bandwidth of a measured one after order tracking.
    # Healthy, and a chip on a 32T tooth (Tian 2004's ladder on this pair: depth b = 1.07 mm, half
    # a module; steps 12-20 take its width across the face from 58 % to all of it).
    for speed in (30, 40):
        name = f"phm09-{speed}"
        out[name] = DatasetSpec(
            name=name,
            model="two_stage",
            preset="phm09",
            channel="casing_x",
            speed_hz=float(speed),
            load_nm=20.0,
            faults=(("chip", PHM09_CHIP_STEPS),),
            healthy=160,
            fs=PHM09_FS,
            domain=name,
        )
    return out


PHM09_FS = 66666.67  # Hz, the records' sampling rate (data README)
PHM09_CHIP_STEPS = (12, 14, 16, 18, 20)

DATASET_PRESETS: dict[str, DatasetSpec] = _presets()


def dataset_preset(name: str, where: str = "") -> DatasetSpec:
    try:
        return DATASET_PRESETS[name]
    except KeyError:
        prefix = f"{where}: " if where else ""
        raise GearlabInputError(
            f"{prefix}unknown dataset preset '{name}'{did_you_mean(name, list(DATASET_PRESETS))}; "
            f"known: {', '.join(DATASET_PRESETS)}"
        ) from None


@dataclass
class Dataset:
    """float32 samples (n, 4096) and per-sample labels, with the spec that made them."""

    spec: DatasetSpec
    X: object  # np.ndarray (n, POINTS) float32
    label: object  # class index into spec.class_names (0 = healthy)
    fault: object  # 1 = a fault class, 0 = healthy
    intensity: object  # ladder step (0 for healthy samples)
    tooth: object  # pinion tooth (0 for healthy samples)
    rfa: object
    revolution: object  # which noisy revolution was kept (-1 for a TSA sample)
    domain: object  # index into domains
    domains: tuple[str, ...] = ()
    reference: tuple[float, float] = (0.0, 1.0)  # mean and std of the healthy reference (eq. 2.112)
    meta: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.X)

    @property
    def key(self) -> str:
        return self.spec.key()
