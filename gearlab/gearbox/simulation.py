"""Simulating a gearbox description: the lumped model, its parameters, its sensor channel and its
operating point, and the preset a dataset spec names it by (docs/gearbox.md, "Simulating it").

A dataset spec names its model's parameters by a preset string. A description's is a reference,
``gearbox:NAME#HASH``: NAME a built-in description or a file's absolute path, HASH the first 12
hex digits of the file's SHA-256. So the spec (and the dataset cache key) changes when the file
does, a worker process reads the file itself, and a file edited after the spec was made is
refused rather than simulated in two versions.

The lumped model (thesis 2.3, 2.4.2; plugins/models), by what the description gives:

* one stage: ``ten_dof`` (pinion and wheel blocks, motor, load and the housing on its mounts)
  when [dynamics] gives a housing value (casing_mass, mounting_*) or no drive value either;
  ``eight_dof`` (no housing: the bearings grounded) when it gives the drive (motor_inertia,
  load_inertia, coupling_*) and no housing value;
* two stages: ``two_stage``, its second mesh the description's stage 2;
* three stages: ``three_stage`` (two_stage with a third mesh and a block on shaft 3).

A [source] may name another model with ``model`` (six_dof, say) of the same number of stages.
The values: each shaft's block from [[shafts]] (else its gears as solid discs), the rest from
[dynamics] (else the DYNAMICS defaults; FITTED names the gap-diagnosis effect that fits each).
The channel from [sensor]: on a model with a housing the accelerometer sits on it (casing_x,
casing_y: the lumped housing is one block, so 'near' picks nothing); without one, on the block
of the shaft it is near (input: pinion_, output of one stage: gear_, of a train: gear_ for shaft
2, shaft3_ for shaft 3 of three, output_ for the output). 'radial' is y, the axis nearest the line of action
(eq. 2.104: cos α of the mesh force); 'axial' is refused (the models have no axial DOF).
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Iterator, Mapping
from pathlib import Path

from ..errors import GearlabInputError
from .derive import DYNAMICS_NAMES, MODELS, gear_pairs, lumped_params, train_pair
from .description import FITTED, LOAD_LEVEL, OPERATION_FITTED, SHAFT_NAMES, Gearbox

PREFIX = "gearbox:"
HOUSING = ("casing_mass", "mounting_stiffness_x", "mounting_stiffness_y", "mounting_damping_x", "mounting_damping_y")
DRIVE = ("motor_inertia", "load_inertia", "coupling_stiffness", "coupling_damping")


def is_reference(preset: str) -> bool:
    return isinstance(preset, str) and preset.startswith(PREFIX)


def _file(spec: str) -> Path:
    from . import builtin_gearboxes

    builtin = builtin_gearboxes()
    return builtin[spec] if spec in builtin and not Path(spec).exists() else Path(spec)


def reference(spec: str) -> str:
    """The preset reference of a description: a built-in name or a file path (made absolute)."""
    path = _file(spec)
    name = spec if path != Path(spec) else str(path.resolve())
    return f"{PREFIX}{name}#{hashlib.sha256(path.read_bytes()).hexdigest()[:12]}"


@functools.lru_cache(maxsize=32)
def referenced(ref: str) -> Gearbox:
    """The description a reference names, checked to be the file it was made from."""
    from . import resolve_gearbox

    spec, _, digest = ref.removeprefix(PREFIX).rpartition("#")
    box = resolve_gearbox(spec)
    now = reference(spec).rpartition("#")[2]
    if now != digest:
        raise GearlabInputError(
            f"{spec}: the gearbox description changed since the dataset was specified (content {digest}, now "
            f"{now}); run the scenario again"
        )
    return box


def gearbox_of(source) -> Gearbox | None:
    """The gearbox description a simulated source (a DatasetSpec, or its preset string) simulates: a
    built-in one named by the preset, or a description it references; None: a model preset, no
    shafts to localise on."""
    from . import builtin_gearboxes, resolve_gearbox

    preset = source if isinstance(source, str) else source.preset
    if is_reference(preset):
        return referenced(preset)
    if preset in builtin_gearboxes():
        return resolve_gearbox(preset)
    return None


@functools.lru_cache(maxsize=64)
def shaft_names(preset: str, stages: int) -> tuple[str, ...]:
    """The shafts of a model preset, input first: its gearbox description's names when the preset
    is one (a built-in description or a gearbox reference), else the default names."""
    from . import builtin_gearboxes, resolve_gearbox

    box = None
    if is_reference(preset):
        box = referenced(preset)
    elif preset in builtin_gearboxes():
        box = resolve_gearbox(preset)
    if box is not None and len(box.shafts) == stages + 1:
        return tuple(box.shafts)
    return SHAFT_NAMES[stages] if stages in SHAFT_NAMES else tuple(f"shaft {i + 1}" for i in range(stages + 1))


def label(preset: str) -> str:
    """A preset as people read it: a description's name and file, else the preset name."""
    if not is_reference(preset):
        return preset
    return preset.removeprefix(PREFIX).rpartition("#")[0]


def model_name(box: Gearbox) -> str:
    """The lumped model a description implies (module doc)."""
    stages = len(box.stages)
    if stages > 1:
        return MODELS[stages]
    stated = set(box.stated)
    return "eight_dof" if stated & set(DRIVE) and not stated & set(HOUSING) else "ten_dof"


def channel(box: Gearbox, model: str, channels: tuple[str, ...]) -> str:
    """The channel of *model* (its *channels*) where the description's [sensor] sits (module doc)."""
    where = f"{box.source}: [sensor] key 'direction'"
    direction = {"x": "x", "y": "y", "radial": "y"}.get(box.sensor.direction)
    if direction is None:
        raise GearlabInputError(
            f"{where}: {box.sensor.direction!r}: the lumped models have no axial motion; expected x, y or radial "
            "(or give 'channel' in the [source])"
        )
    if f"casing_{direction}" in channels:
        return f"casing_{direction}"
    shaft = box.shafts.index(box.sensor.near)
    block = ("pinion", "gear", "output") if len(box.shafts) < 4 else ("pinion", "gear", "shaft3", "output")
    block = block[shaft] if shaft < len(block) else ""
    name = f"{block}_{direction}"
    if name not in channels:
        raise GearlabInputError(
            f"{box.source}: [sensor] key 'near': model '{model}' has no block on shaft {box.sensor.near!r}; its "
            f"channels: {', '.join(channels)} (give 'channel' in the [source])"
        )
    return name


def defaults(box: Gearbox, names: tuple[str, ...]) -> list[str]:
    """What the description leaves to defaults of a model taking the parameters *names*: its
    [dynamics] keys, '(fit: EFFECT)' where the gap diagnosis may fit one, and the shaft blocks it
    leaves to solid discs."""
    used = [key for key in box.dynamics if key not in box.stated and DYNAMICS_NAMES[key] in names]
    out = [f"{key}{f' (fit: {FITTED[key]})' if key in FITTED else ''}" for key in used]
    if LOAD_LEVEL not in box.stated:  # [operation] load_level: the gap's load_level effect fits it
        out.append(f"{LOAD_LEVEL} (fit: {OPERATION_FITTED[LOAD_LEVEL]})")
    discs = [name for name, m, j in zip(box.shafts, box.shaft_mass, box.shaft_inertia) if m is None or j is None]
    return out + ([f"the {', '.join(discs)} shaft blocks (solid discs)"] if discs else [])


def preset_of(box: Gearbox, names: tuple[str, ...], stages: int, model: str = "") -> dict:
    """A model preset ({"pair", "params", "speed_hz", "load_nm", "speeds_hz", "loads_nm"}) from
    *box* for a model of *stages* stages taking the parameters *names*."""
    if len(box.stages) != stages:
        raise GearlabInputError(
            f"{box.source}: [[stages]]: {len(box.stages)} stage(s), but model '{model}' simulates {stages} "
            f"(the description's model: {model_name(box)})"
        )
    _, params = lumped_params(box)
    pairs = gear_pairs(box)
    return {
        "pair": pairs[0] if stages == 1 else train_pair(*pairs),  # stage 1 carrying the next
        "params": {k: v for k, v in params.items() if k in names},
        "speed_hz": box.speed_hz,
        "load_nm": box.torque(),
        "speeds_hz": () if box.speed_hz is None else (box.speed_hz,),
        "loads_nm": () if box.load_nm is None else (box.torque(),),
    }


@functools.lru_cache(maxsize=32)
def preset_of_reference(ref: str, names: tuple[str, ...], stages: int, model: str = "") -> dict:
    """preset_of the description *ref* names (a reference: :func:`reference`)."""
    return preset_of(referenced(ref), names, stages, model)


class DescribedPresets(Mapping):
    """A model plugin's presets, each read from the built-in description of its name on first use
    (registering the plugins reads no file), with the plugin's *extra* keys (the operating points
    its datasets use) on top: the preset and the description are one thing."""

    def __init__(self, model, extra: Mapping[str, Mapping]):
        self._model, self._extra, self._read = model, dict(extra), {}

    def __getitem__(self, name: str) -> dict:
        if name not in self._extra:
            raise KeyError(name)
        if name not in self._read:
            from . import resolve_gearbox

            m = self._model
            self._read[name] = {
                **preset_of(resolve_gearbox(name), m.param_names(), m.stages, m.name),
                **self._extra[name],
            }
        return self._read[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._extra)

    def __len__(self) -> int:
        return len(self._extra)


def model_command(gearbox: str, model: str | None, preset: str | None, flag=lambda key: key) -> tuple[str, str]:
    """(model, preset) of a *gearbox* description: its model unless *model*, its reference as the
    preset. *flag* names a keyword in an error (the CLI passes its options: --preset, ...)."""
    if preset is not None:
        raise GearlabInputError(
            f"{flag('preset')} {preset}: the {flag('gearbox')} description gives the model's values; give one"
        )
    try:
        ref = reference(gearbox)
    except OSError as exc:
        raise GearlabInputError(
            f"{flag('gearbox')} {gearbox}: cannot read the description ({exc.strerror or exc})"
        ) from None
    return model or model_name(referenced(ref)), ref


def simulate_command(
    gearbox: str | None,
    model: str | None,
    preset: str | None,
    speed: float | None,
    load: float | None,
    flag=lambda key: key,
) -> tuple[str, str | None, float | None, float | None]:
    """(model, preset, speed, load) of a simulation: with a *gearbox*, the description simulated as a
    [source] gearbox is (its model unless *model*, its values, its [operation] speed and load unless
    *speed* and *load*; the load times its load_level); else *model* and *preset* as given. *flag*: as in
    model_command."""
    if gearbox is None:  # the model is checked where it is loaded (gearlab.notebook.simulator)
        return model, preset, speed, load
    model, ref = model_command(gearbox, model, preset, flag)
    box = referenced(ref)
    for key, value in (("speed", speed), ("load", load)):
        if value is None and getattr(box, f"{key}_hz" if key == "speed" else f"{key}_nm") is None:
            raise GearlabInputError(f"{box.source}: [operation] key '{key}': missing; expected it there or {flag(key)}")
    return model, ref, speed if speed is not None else box.speed_hz, box.torque(load)
