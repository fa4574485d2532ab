"""The corrected gearbox description of a gap run (docs/your_gearbox.md step 4): when the [source]
simulates a gearbox description and the diagnosis keeps effects that fit the description's own
[dynamics] values (description.FITTED: bearing_stiffness, drive_inertias, casing_path, mesh_damping),
the run directory gets gearbox_corrected.toml: the user's description with those values set
(gearlab.gearbox.corrected), each with a comment naming the effect, its fitted parameters and the run.

From the effects' parameters (plugins/effects): drive_inertias sets I11, I22, k_c, c_c
(motor_inertia, load_inertia, coupling_stiffness, coupling_damping); casing_path sets mf, k_xf,
k_yf, c_xf, c_yf (casing_mass, mounting_stiffness_x/_y, mounting_damping_x/_y); mesh_damping's zeta is
mesh_damping_ratio (its 'proportional' damping model, the simulator's; a 'constant' fit has no key);
bearing_stiffness multiplies k_b and c_b (bearing_stiffness, bearing_damping) by k_factor and c_factor;
load_level's factor multiplies [operation] load_level (description.OPERATION_FITTED: the torque the
source ran at, however given, times the factor).
A one-stage description that states a drive value and no housing one is simulated without the housing
(gearlab.gearbox.simulation.model_name): where that would drop the housing the source had, its
casing_mass is written too, unchanged.

The effects the corrected corrected_effects holds besides (sensor noise, a sensor's response, a tone,
...) are not part of the gearbox: a comment at the end lists them for the [corrected] effects. The
description's configuration is checked against the source's with the written effects (DOFs, channel,
damping model, every value to 1e-5): the file is written only when they agree.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

from ..data.spec import DatasetSpec
from ..effects import EffectChain, config_of
from ..errors import GearlabInputError
from ..gearbox.corrected import number, quantity, with_dynamics, with_table
from ..gearbox.derive import DYNAMICS_NAMES
from ..gearbox.description import (
    DYNAMICS,
    FITTED,
    LOAD_LEVEL,
    OPERATION_FITTED,
    OPERATION_KEYS,
    parse_gearbox,
    read_description,
)
from ..gearbox.simulation import channel, is_reference, label, model_name, preset_of, referenced
from ..registry import get_registry
from ..settings import resolve_params

FILE = "gearbox_corrected.toml"
FACTORS = {"k_b": "k_factor", "c_b": "c_factor"}  # bearing_stiffness: factors on the model's values
_BOUNDS = {name: p for name, (p, _) in DYNAMICS.items()}


def write_corrected(source: DatasetSpec, result: dict, run) -> str | None:
    """Write gearbox_corrected.toml into the *run* directory (gearlab.runs.RunDir: atomic, inside it)
    when the diagnosis *result* keeps an effect of the description's [dynamics]; returns what the run
    says of it: the file's name, why it is not written, or None (nothing to write)."""
    try:
        text, said = corrected_description(source, result, f"{run.path.parent.name}/{run.path.name}")
    except GearlabInputError as exc:  # a description edited in a form this cannot edit: the run stands
        return f"not written ({exc})"
    if text is not None:
        run.write_text(FILE, text)
    return said


def corrected_description(source: DatasetSpec, result: dict, run_name: str) -> tuple[str | None, str | None]:
    """(the text of gearbox_corrected.toml, what the run says of it), (None, None) where the source
    is no description or no kept effect fits one of its values."""
    effects = [(name, dict(params)) for name, params in result.get("corrected_effects") or []]
    fitted = set(FITTED.values()) | set(OPERATION_FITTED.values())
    if not is_reference(source.preset) or not any(name in fitted for name, _ in effects):
        return None, None
    box = referenced(source.preset)
    before = config_of(source.model, source.preset, source.channel).params
    mesh_model = config_of(source.model, source.preset, source.channel).mesh_damping
    values: dict[str, float] = {}
    comments: dict[str, str] = {}
    written, left = [], []
    operation: dict[str, str] = {}
    for name, params in effects:
        if name in OPERATION_FITTED.values():
            why = _operation(name, params, box, run_name, operation, comments)
            if why:
                left.append((name, params, why))
            else:
                written.append((name, tuple(sorted(params.items()))))
            continue
        keys = [key for key, effect in FITTED.items() if effect == name]
        why = _not_written(name, params, mesh_model)
        new = {} if why else _values(keys, params, before)
        out = [f"{k} = {number(new[k])}" for k in new if not _BOUNDS[k].low <= new[k] <= _BOUNDS[k].high]
        if keys and not why and out:
            why = f"{', '.join(out)} outside the description's bounds"
        if not keys or why:
            left.append((name, params, why))
            continue
        for key, value in new.items():
            symbol = DYNAMICS_NAMES[key]
            if value != before.get(symbol):
                values[key], comments[key] = value, f"gap run {run_name}: {name} {_fit(key, params, before)}"
        written.append((name, tuple(sorted(params.items()))))
    if not values and not operation:
        return None, None
    raw = read_description(box.source)
    old = raw.get("dynamics") if isinstance(raw.get("dynamics"), dict) else {}
    new_box = _parsed(box, values, old, comments)
    if model_name(new_box) != model_name(box) and "casing_mass" not in values and source.model == model_name(box):
        values["casing_mass"] = box.dynamics["casing_mass"]
        comments["casing_mass"] = f"as before, stated to keep the housing of model {model_name(box)}"
    tail = [f"# not part of the gearbox: give them in [corrected] effects (gap run {run_name}):"] if left else []
    tail += [
        f'#   {{ name = "{name}", '
        + ", ".join(f"{k} = {_toml(v)}" for k, v in params.items())
        + f" }}{f'  # {why}' if why else ''}"
        for name, params, why in left
    ]
    what = [table for table, given in (("[dynamics]", values), ("[operation] load_level", operation)) if given]
    head = [
        f"# {label(source.preset)} with the {' and '.join(what)} the gap diagnosis fitted "
        f"(gap run {run_name}: {result.get('verdict', '')})"
    ]
    text = with_table(Path(box.source).read_text(), "operation", operation, comments)
    text = with_dynamics(text, {k: quantity(k, v, old.get(k)) for k, v in values.items()}, comments, head, tail)
    new_box = parse_gearbox(tomllib.loads(text), box.source)
    problem = _differs(source, box, new_box, tuple(written))
    if problem:
        return None, (
            f"not written: model '{source.model}' of the corrected description would not simulate as the fit "
            f"did ({problem}); give the fitted effects as [corrected] effects"
        )
    return text, FILE


def _operation(name: str, params: dict, box, run_name: str, operation: dict, comments: dict) -> str:
    """Set the [operation] key the effect *name* fits (into *operation*, its comment into *comments*);
    '' when set, else why not."""
    key = next(k for k, effect in OPERATION_FITTED.items() if effect == name)
    factor = float(params["factor"])
    level = box.load_level * factor
    bounds = OPERATION_KEYS[LOAD_LEVEL][0]
    if not bounds.low <= level <= bounds.high:
        return f"{key} = {number(level)} outside the description's bounds"
    operation[key], torque = number(level), box.torque()
    at = "" if torque is None else f": {number(torque)} -> {number(torque * factor)} N*m at the [operation] load"
    was = "" if box.load_level == 1.0 else f" x {number(box.load_level)}"
    comments[key] = f"gap run {run_name}: {name} factor = {_shown(params['factor'])}{was}{at}"
    return ""


def _fit(key: str, params: dict, before: dict) -> str:
    """The fitted parameter a [dynamics] *key* follows: 'k_c = 500', 'k_factor = 0.41 x 1e8 N/m'."""
    symbol = DYNAMICS_NAMES[key]
    if symbol in params:
        return f"{symbol} = {_shown(params[symbol])}"
    factor = FACTORS[symbol]
    return f"{factor} = {_shown(params[factor])} x {number(before[symbol])} {_BOUNDS[key].unit}"


def _not_written(name: str, params: dict, mesh_model: str) -> str:
    if name == "mesh_damping" and params.get("model", mesh_model) != mesh_model:
        return f"its '{params['model']}' damping model has no description key (the simulator's: {mesh_model})"
    return ""


def _values(keys: list[str], params: dict, before: dict) -> dict[str, float]:
    out = {}
    for key in keys:
        symbol = DYNAMICS_NAMES[key]
        if symbol in params:
            out[key] = float(params[symbol])
        elif FACTORS.get(symbol) in params and symbol in before:
            out[key] = before[symbol] * float(params[FACTORS[symbol]])
    return out


def _parsed(box, values: dict, old: dict, comments: dict):
    text = with_dynamics(
        Path(box.source).read_text(), {k: quantity(k, v, old.get(k)) for k, v in values.items()}, comments
    )
    return parse_gearbox(tomllib.loads(text), box.source)


def _differs(source: DatasetSpec, box, new_box, written: tuple) -> str:
    """'' when the description *new_box* simulates as *source* (on *box*) with the *written*
    effects added, else what differs."""
    registry = get_registry()
    model = model_name(new_box) if source.model == model_name(box) else source.model
    plugin = registry.get("model", model)
    preset = preset_of(new_box, tuple(plugin.param_names()), plugin.stages, model)
    try:  # the channel the description put the sensor on, kept where the [source] named another
        described = channel(box, source.model, tuple(registry.get("model", source.model).channels))
    except GearlabInputError:
        described = None
    chan = channel(new_box, model, plugin.channels) if source.channel == described else None
    base = config_of(source.model, source.preset, source.channel)
    fitted = EffectChain.load(source.effects + written).model_config(base)
    own = EffectChain.load(source.effects).model_config(
        base.replace(
            dofs=tuple(plugin.dofs),
            input_dof=plugin.input_dof,
            load_dof=plugin.load_dof,
            channel=chan or source.channel,
            values=tuple(sorted(resolve_params(plugin.params, preset["params"], model).items())),
        )
    )
    factor = math.prod(float(dict(p)["factor"]) for name, p in written if name in OPERATION_FITTED.values())
    if not math.isclose(new_box.load_level, box.load_level * factor, rel_tol=1e-5):
        return f"load_level {new_box.load_level} against {box.load_level * factor}"
    for what in ("dofs", "input_dof", "load_dof", "channel", "mesh_damping"):
        if getattr(fitted, what) != getattr(own, what):
            return f"{what} {getattr(own, what)} against {getattr(fitted, what)}"
    a, b = fitted.params, own.params
    for key in sorted(set(a) | set(b)):
        if key not in a or key not in b or not math.isclose(a[key], b[key], rel_tol=1e-5):
            return f"{key} {b.get(key)} against {a.get(key)}"
    return ""


def _shown(value) -> str:
    return number(value) if isinstance(value, float) else str(value)


def _toml(value) -> str:
    return number(value) if isinstance(value, float) else f'"{value}"' if isinstance(value, str) else str(value)
