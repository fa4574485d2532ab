"""A gearbox description (docs/gearbox.md): the TOML file a user writes once, read and checked.

A description names, in ISO 21771 terms, a series train of 1 to 3 spur stages. Stage k's
pinion (gear 1, the driver) sits on shaft k and drives its wheel (gear 2) on shaft k + 1;
shaft 1 is the input, the last shaft the output. Everything is read into SI floats; a bad
value is one line naming the file, the table and the key (GearlabInputError, exit 2).

    [gearbox]      name, description
    [operation]    speed (input shaft, "25 Hz" or "1500 rpm"), load (output torque),
                   load_level (a factor on the load, however given: what a gap diagnosis fits)
    [materials.X]  E, nu, density
    [[stages]]     module m, pressure_angle α, face_width b, centre_distance a (checked),
                   addendum h_a*, dedendum h_f*, tool_tip_radius ρ_fP*
      [stages.pinion] / [stages.wheel]   z, x (profile shift), bore, material, face_width,
                   addendum, dedendum (default: the stage's), tip_diameter d_a (a shortened tip)
    [[shafts]]     name, mass, inertia (input to output; the lumped block of each shaft)
    [sensor]       near (shaft), direction, tacho (shaft), pulses_per_rev
    [dynamics]     lumped-model parameters with documented defaults (DYNAMICS)

The geometry is checked (gearlab.gearbox.checks) as soon as it is read.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import GearlabInputError, shown
from ..files import toml_tables
from ..params import Param, did_you_mean
from ..units import to_si

MAX_STAGES = 3  # series trains of 1 to 3 spur meshes; helical and planetary stages come later
SHAFT_NAMES = {
    1: ("input", "output"),
    2: ("input", "intermediate", "output"),
    3: ("input", "intermediate 1", "intermediate 2", "output"),
}


def gear_name(stage: int, gear: str, shafts: tuple[str, ...]) -> str:
    """The words for a gear: "input pinion", "output gear", "idler gear", ..."""
    return f"{shafts[stage - 1]} pinion" if gear == "pinion" else f"{shafts[stage]} gear"


# --- declared keys ---------------------------------------------------------------------------
#
# Param carries name, SI unit, default, bounds, doc and the unit shown to people; FITTED names
# the gap-diagnosis effect (plugins/effects) that may fit a value from measured data.

_NAN = math.nan  # a required key's "default"

STAGE_KEYS = (
    Param("module", "m", _NAN, 1e-4, 0.1, "module m (ISO 21771 m_n)", "mm"),
    Param("pressure_angle", "rad", math.radians(20), math.radians(10), math.radians(35), "pressure angle α", "deg"),
    Param("face_width", "m", _NAN, 1e-4, 1.0, "face width b (common to both gears)", "mm"),
    Param("centre_distance", "m", _NAN, 1e-4, 10.0, "centre distance a (optional; checked against z, m, x)", "mm"),
    Param("addendum", "", 1.0, 0.5, 1.5, "addendum coefficient h_a* (h_a = h_a* m; per gear: default the stage's)"),
    Param(
        "dedendum",
        "",
        1.25,
        0.75,
        2.0,
        "dedendum coefficient h_f* (h_f = h_f* m; clearance c* = h_f* - h_a*; per gear: default the stage's)",
    ),
    Param("tool_tip_radius", "", 0.2, 0.0, 0.5, "tip radius coefficient ρ_fP* of the generating rack"),
)
GEAR_KEYS = (
    Param("z", "", _NAN, 6, 10_000, "number of teeth z", integer=True),
    Param("x", "", 0.0, -1.0, 2.0, "profile shift coefficient x"),
    Param(
        "bore", "m", _NAN, 1e-4, 10.0, "bore diameter d_bore (the hub radius of the stiffness model is d_bore/2)", "mm"
    ),
    Param("face_width", "m", _NAN, 1e-4, 1.0, "face width of this gear (default: the stage's)", "mm"),
    Param("tip_diameter", "m", _NAN, 1e-4, 20.0, "tip diameter d_a (default d + 2 m (h_a* + x))", "mm"),
)
PER_GEAR = ("addendum", "dedendum")  # stage keys a gear may set for itself (STAGE_KEYS' Params)
MATERIAL_KEYS = (
    Param("E", "Pa", _NAN, 1e8, 1e13, "Young's modulus E", "GPa"),
    Param("nu", "", _NAN, 0.0, 0.4999, "Poisson's ratio ν"),
    Param("density", "kg/m^3", 7850.0, 100.0, 30_000.0, "density ρ"),
)
STEEL = {"E": 200e9, "nu": 0.3, "density": 7850.0}  # the thesis's steel (Tables 2.3, 2.4)

# Lumped-model parameters (thesis Tables 2.3/2.4, eq. 2.96-2.107), one value for the gearbox.
DYNAMICS = (
    Param("motor_inertia", "kg*m^2", 0.0043, 1e-7, 1e3, "I11, the motor's rotor (Table 2.4)"),
    Param("load_inertia", "kg*m^2", 0.0045, 1e-7, 1e3, "I22, the load's rotor (Table 2.4)"),
    Param("coupling_stiffness", "N*m/rad", 1e4, 1.0, 1e9, "k_c, torsional stiffness of each coupling"),
    Param("coupling_damping", "N*m*s/rad", 10.0, 0.0, 1e6, "c_c, torsional damping of each coupling"),
    Param("bearing_stiffness", "N/m", 1e8, 1e5, 1e11, "k_b, radial stiffness of each shaft's bearings"),
    Param("bearing_damping", "N*s/m", 2e3, 0.0, 1e7, "c_b, radial damping of each shaft's bearings"),
    Param("casing_mass", "kg", 10.0, 0.1, 1e5, "m_f, the casing block"),
    Param("mounting_stiffness_x", "N/m", 2e8, 1e5, 1e11, "k_xf, the casing's mounts along x"),
    Param("mounting_stiffness_y", "N/m", 2e8, 1e5, 1e11, "k_yf, the casing's mounts along y"),
    Param("mounting_damping_x", "N*s/m", 2e3, 0.0, 1e7, "c_xf, the casing's mounts along x"),
    Param("mounting_damping_y", "N*s/m", 2e3, 0.0, 1e7, "c_yf, the casing's mounts along y"),
    Param("mesh_damping_ratio", "", 0.07, 0.0, 0.5, "ζ of eq. 2.107, the mesh damping ratio"),
)
FITTED = {
    "motor_inertia": "drive_inertias",
    "load_inertia": "drive_inertias",
    "coupling_stiffness": "drive_inertias",
    "coupling_damping": "drive_inertias",
    "bearing_stiffness": "bearing_stiffness",
    "bearing_damping": "bearing_stiffness",
    "casing_mass": "casing_path",
    "mounting_stiffness_x": "casing_path",
    "mounting_stiffness_y": "casing_path",
    "mounting_damping_x": "casing_path",
    "mounting_damping_y": "casing_path",
    "mesh_damping_ratio": "mesh_damping",
}
LOAD_LEVEL = Param(
    "load_level",
    "",
    1.0,
    0.01,
    100.0,
    "factor on the output torque, the [operation] load or a scenario's 'load' (a gap run's load_level fit)",
)
OPERATION_FITTED = {"load_level": "load_level"}  # [operation] keys a gap-diagnosis effect may fit
SHAFT_KEYS = (
    Param("mass", "kg", _NAN, 1e-4, 1e5, "mass of the shaft's block (its gears and the shaft; default: solid discs)"),
    Param("inertia", "kg*m^2", _NAN, 1e-9, 1e4, "polar moment of inertia of the block (default: solid discs)"),
)
SENSOR_DIRECTIONS = ("x", "y", "radial", "axial")


# --- the description -------------------------------------------------------------------------


@dataclass(frozen=True)
class Material:
    name: str
    E: float  # Pa
    nu: float
    density: float  # kg/m^3


@dataclass(frozen=True)
class GearSpec:
    """One gear as described: z teeth, profile shift x, bore diameter, material, face width (SI);
    its own addendum and dedendum coefficients and tip diameter where given (None: the stage's,
    and d_a = d + 2 m (h_a* + x); gearlab.gearbox.checks.gear_tip)."""

    z: int
    x: float
    bore: float
    face_width: float
    material: Material
    where: str  # file and table, for the messages of later checks
    addendum: float | None = None
    dedendum: float | None = None
    tip_diameter: float | None = None


@dataclass(frozen=True)
class Stage:
    index: int  # 1-based
    name: str  # "" when not given: the gear pair is named after the gearbox (derive.gear_pairs)
    module: float
    pressure_angle: float
    face_width: float
    addendum: float
    dedendum: float
    tool_tip_radius: float
    centre_distance: float | None
    pinion: GearSpec
    wheel: GearSpec
    where: str

    @property
    def ratio(self) -> float:
        """Gear ratio u = z2 / z1 (the wheel turns u times slower)."""
        return self.wheel.z / self.pinion.z


@dataclass(frozen=True)
class Sensor:
    near: str  # the shaft whose bearing the accelerometer sits nearest
    direction: str
    tacho: str  # the shaft the tacho reads
    pulses_per_rev: int


@dataclass(frozen=True)
class Gearbox:
    name: str
    description: str
    source: str  # the file (or "built-in NAME"); messages name it
    stages: tuple[Stage, ...]
    shafts: tuple[str, ...]  # input first
    shaft_mass: tuple[float | None, ...]  # kg, as described (None: from the gears, derive.lumped_params)
    shaft_inertia: tuple[float | None, ...]  # kg m^2, likewise
    speed_hz: float | None  # input-shaft speed, None when not stated
    load_nm: float | None  # output torque
    sensor: Sensor
    dynamics: dict[str, float] = field(default_factory=dict)
    stated: tuple[str, ...] = ()  # the [dynamics] keys (and [operation] load_level) the description gives
    load_level: float = 1.0  # [operation] load_level: the simulated torque is the load times it

    def torque(self, load: float | None = None) -> float | None:
        """The output torque simulated: *load* (a scenario's) or [operation] load, times load_level;
        None when neither is given."""
        load = self.load_nm if load is None else load
        return None if load is None else load * self.load_level

    def shaft_index(self, name: str, where: str) -> int:
        try:
            return self.shafts.index(name)
        except ValueError:
            raise GearlabInputError(
                f"{where}: unknown shaft {shown(name)}{did_you_mean(str(name), self.shafts)}; "
                f"the shafts are {', '.join(self.shafts)}"
            ) from None


# --- reading ---------------------------------------------------------------------------------


def speed_hz(value, where: str) -> float:
    """An input-shaft speed in revolutions per second: "25 Hz", "1500 rpm", "157.08 rad/s" or a number in Hz
    (up to BARE_SPEED_HZ).

    pint keeps the 2π of a revolution ("1500 rpm" is 157 rad/s, which it calls 157 Hz), so a
    speed written with an angle (rpm, rev/min, rad/s, deg/s) is converted to revolutions per
    second; a plain frequency (Hz, 1/s) is one revolution per cycle already.
    """
    given = value
    if isinstance(value, str) and any(u in value for u in ("rpm", "revolution", "turn", "rad", "deg")):
        value = to_si(value, "revolution/s", where)
    else:
        value = to_si(value, "Hz", where)
    if not 0 < value <= MAX_SPEED_HZ:
        raise GearlabInputError(
            f"{where}: expected an input-shaft speed up to 1 kHz, e.g. '25 Hz', got {value:g}{bare_speed(given)}"
        )
    if bare_speed(given) and value > BARE_SPEED_HZ:  # '900' meant in rpm: 54,000 rpm as read
        raise GearlabInputError(
            f"{where}: a bare number is in Hz, and {value:g} Hz ({60 * value:,.0f} rpm) is no usual input-shaft "
            f"speed; expected the unit, e.g. '{value:g} rpm' ({value / 60:.4g} Hz) or '{value:g} Hz'"
        )
    return value


# An input shaft's speed: up to 1 kHz (60,000 rpm) in every table; a bare number (read in Hz) up to 100 Hz
# (6,000 rpm), above which it is more likely meant in rpm ('speed = 900' read as 900 Hz passed silently)
MAX_SPEED_HZ, BARE_SPEED_HZ = 1e3, 100.0


def bare_speed(value) -> str:
    """What an out-of-bounds speed's message adds when the speed was a bare number (read as Hz:
    '2100' meant in rpm is 2100 turns a second)."""
    bare = isinstance(value, (int, float)) and not isinstance(value, bool)
    if isinstance(value, str):
        bare = re.fullmatch(r"\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*", value) is not None
    return " (a bare number is in Hz; expected a speed with its unit, e.g. '35 Hz' or '2100 rpm')" if bare else ""


class _Table:
    """One table of the description: typed, unit-aware reads, every message naming file, table and key."""

    def __init__(self, data, source: str, name: str):
        self.source, self.name = source, name
        if not isinstance(data, Mapping):
            raise GearlabInputError(f"{source}: {name}: expected a table, got {type(data).__name__} {shown(data)}")
        self.data = data

    def where(self, key: str | None = None) -> str:
        return f"{self.source}: {self.name}" + (f" key '{key}'" if key else "")

    def known(self, keys) -> None:
        keys = list(keys)
        for key in self.data:
            if key not in keys:
                raise GearlabInputError(
                    f"{self.where(key)}: unknown key{did_you_mean(str(key), keys)}; known keys: {', '.join(keys)}"
                )

    def param(self, p: Param, default: float | None = None) -> float | None:
        """The value of *p* in SI, checked against its bounds; *default* (or p.default) when absent,
        None when absent and optional (default NaN and none given)."""
        if p.name not in self.data:
            value = p.default if default is None else default
            if isinstance(value, float) and math.isnan(value):
                return None
            return value
        where = self.where(p.name)
        raw = self.data[p.name]
        if p.integer:
            if isinstance(raw, bool) or not isinstance(raw, int):
                raise GearlabInputError(f"{where}: expected a whole number, got {shown(raw)}")
            value = raw
        else:
            value = to_si(raw, p.unit, where)
        if not p.low <= value <= p.high:
            # a bare number is SI ('module = 2.5' is 2.5 m, 'pressure_angle = 20' is 20 rad): say so
            bare = p.unit and not isinstance(raw, str) and p.show(p.low) != f"{p.low:g} {p.unit}"
            said = f" (a bare number is in {p.unit}; expected e.g. '{raw} {p.display_unit}')" if bare else ""
            raise GearlabInputError(f"{where}: {shown(raw)} is outside [{p.show(p.low)}, {p.show(p.high)}]{said}")
        return value

    def required(self, p: Param, default: float | None = None) -> float:
        value = self.param(p, default)
        if value is None:
            raise GearlabInputError(
                f"{self.where(p.name)}: missing; expected {p.doc}" + (f" in {p.display_unit}" if p.display_unit else "")
            )
        return value

    def text(self, key: str, default: str) -> str:
        value = self.data.get(key, default)
        if not isinstance(value, str):
            raise GearlabInputError(f"{self.where(key)}: expected a string, got {type(value).__name__} {shown(value)}")
        return value

    def sub(self, key: str, required: bool = True) -> _Table | None:
        if key not in self.data:
            if required:
                raise GearlabInputError(f"{self.where()}: missing table '{key}'; expected {key} = {{ z = ..., ... }}")
            return None
        return _Table(self.data[key], self.source, f"{self.name}.{key}")


TABLES = ("gearbox", "operation", "materials", "stages", "shafts", "sensor", "dynamics")


def read_description(path: Path | str) -> dict:
    """The TOML of a description file, or one line on why it cannot be read."""
    path = Path(path)
    return toml_tables(
        path,
        path.read_bytes,
        "no such gearbox description (a .toml file, docs/gearbox.md)",
        "is a directory; expected a gearbox description .toml file",
    )


def load_gearbox(path: Path | str) -> Gearbox:
    """Read, check and return the description in *path* (geometry checked: gearlab.gearbox.checks)."""
    return parse_gearbox(read_description(path), str(path))


def parse_gearbox(data: Mapping, source: str) -> Gearbox:
    """A description from its TOML tables; *source* names it in messages (a file, or
    "scenario.toml: [gearbox]" for a table inside a scenario)."""
    from .checks import check_geometry

    for key in data:
        if key not in TABLES:
            raise GearlabInputError(
                f"{source}: unknown table [{key}]{did_you_mean(str(key), TABLES)}; known tables: {', '.join(TABLES)}"
            )
    head = _Table(data.get("gearbox", {}), source, "[gearbox]")
    head.known(("name", "description"))
    name = head.text("name", Path(source).stem if source.endswith(".toml") else "gearbox")
    description = head.text("description", "")

    materials = _materials(data.get("materials", {}), source)
    stages_data = data.get("stages")
    if not isinstance(stages_data, list) or not stages_data or not all(isinstance(s, Mapping) for s in stages_data):
        raise GearlabInputError(
            f"{source}: [[stages]]: expected 1 to {MAX_STAGES} stages as [[stages]] tables, got "
            f"{'none' if stages_data is None else shown(stages_data)}"
        )
    if len(stages_data) > MAX_STAGES:
        raise GearlabInputError(f"{source}: [[stages]]: {len(stages_data)} stages; expected 1 to {MAX_STAGES}")
    stages = tuple(_stage(s, i, source, materials) for i, s in enumerate(stages_data))
    shafts, shaft_mass, shaft_inertia = _shafts(data.get("shafts"), len(stages), source)

    op = _Table(data.get("operation", {}), source, "[operation]")
    op.known(("speed", "load", LOAD_LEVEL.name))
    speed = speed_hz(op.data["speed"], op.where("speed")) if "speed" in op.data else None
    load = None
    if "load" in op.data:
        load = to_si(op.data["load"], "N*m", op.where("load"))
        if not 0 <= load <= 1e7:
            raise GearlabInputError(f"{op.where('load')}: expected an output torque in [0, 1e7] N*m, got {load:g}")

    sensor = _sensor(data.get("sensor", {}), source, shafts)
    dyn = _Table(data.get("dynamics", {}), source, "[dynamics]")
    dyn.known(p.name for p in DYNAMICS)
    dynamics = {p.name: dyn.param(p) for p in DYNAMICS}

    box = Gearbox(
        name,
        description,
        source,
        stages,
        shafts,
        shaft_mass,
        shaft_inertia,
        speed,
        load,
        sensor,
        dynamics,
        tuple(dyn.data) + ((LOAD_LEVEL.name,) if LOAD_LEVEL.name in op.data else ()),
        op.param(LOAD_LEVEL),
    )
    check_geometry(box)
    return box


def _materials(data, source: str) -> dict[str, Material]:
    table = _Table(data, source, "[materials]")
    out = {"steel": Material("steel", **STEEL)}
    for key, value in table.data.items():
        t = _Table(value, source, f"[materials.{key}]")
        t.known(p.name for p in MATERIAL_KEYS)
        E, nu, density = (t.required(p) for p in MATERIAL_KEYS)
        out[str(key)] = Material(str(key), E, nu, density)
    return out


def _stage(data: Mapping, i: int, source: str, materials: dict[str, Material]) -> Stage:
    t = _Table(data, source, f"[[stages]] #{i + 1}")
    t.known([p.name for p in STAGE_KEYS] + ["name", "pinion", "wheel"])
    name = t.text("name", "")
    module, alpha, width, a, ha, hf, rho = (t.param(p) for p in STAGE_KEYS)
    module = t.required(STAGE_KEYS[0])
    width = t.required(STAGE_KEYS[2])
    if hf <= ha:
        raise GearlabInputError(
            f"{t.where('dedendum')}: h_f* = {hf:g} must exceed the addendum coefficient h_a* = {ha:g} "
            "(the tip clearance c* = h_f* - h_a* is positive)"
        )
    gears = [_gear(t.sub(role), role, width, materials, hf - ha) for role in ("pinion", "wheel")]
    return Stage(i + 1, name, module, alpha, width, ha, hf, rho, a, *gears, where=t.where())


def _gear(t: _Table, role: str, stage_width: float, materials: dict[str, Material], clearance: float) -> GearSpec:
    own = [p for p in STAGE_KEYS if p.name in PER_GEAR]
    t.known([p.name for p in GEAR_KEYS] + [p.name for p in own] + ["material"])
    z = int(t.required(GEAR_KEYS[0]))
    x = t.param(GEAR_KEYS[1])
    bore = t.required(GEAR_KEYS[2])
    width = t.param(GEAR_KEYS[3], stage_width)
    tip = t.param(GEAR_KEYS[4])
    ha, hf = (t.param(p) if p.name in t.data else None for p in own)
    if ha is not None and tip is not None:
        raise GearlabInputError(
            f"{t.where('tip_diameter')}: give the tip by 'addendum' or by 'tip_diameter', not both "
            f"(d_a = d + 2 m (h_a* + x))"
        )
    if hf is not None and hf <= clearance:
        raise GearlabInputError(
            f"{t.where('dedendum')}: h_f* = {hf:g} leaves no flank below the reference circle for the stage's tip "
            f"clearance c* = {clearance:g} (the generating rack's h_a = h_f* - c*); expected h_f* > {clearance:g}"
        )
    material = t.data.get("material", "steel")
    if isinstance(material, Mapping):
        m = _Table(material, t.source, f"{t.name}.material")
        m.known(p.name for p in MATERIAL_KEYS)
        mat = Material(f"{t.name}.material", *(m.required(p) for p in MATERIAL_KEYS))
    elif isinstance(material, str) and material in materials:
        mat = materials[material]
    else:
        raise GearlabInputError(
            f"{t.where('material')}: unknown material {shown(material)}"
            f"{did_you_mean(str(material), list(materials))}; known: {', '.join(materials)} "
            "(define others under [materials.NAME] with E, nu, density)"
        )
    return GearSpec(z, x, bore, width, mat, t.where(), ha, hf, tip)


def _shafts(data, stages: int, source: str) -> tuple[tuple[str, ...], tuple, tuple]:
    names = SHAFT_NAMES[stages]
    if data is None:
        return names, (None,) * len(names), (None,) * len(names)
    if not isinstance(data, list) or len(data) != stages + 1:
        raise GearlabInputError(
            f"{source}: [[shafts]]: expected {stages + 1} shafts for {stages} stage(s), input to output "
            f"(default names: {', '.join(names)}), got {shown(data)}"
        )
    out, mass, inertia = [], [], []
    for i, item in enumerate(data):
        t = _Table(item, source, f"[[shafts]] #{i + 1}")
        t.known(["name"] + [p.name for p in SHAFT_KEYS])
        name = t.text("name", names[i])
        if not name or name in out:
            raise GearlabInputError(f"{t.where('name')}: expected a distinct non-empty shaft name, got {shown(name)}")
        out.append(name)
        mass.append(t.param(SHAFT_KEYS[0]))
        inertia.append(t.param(SHAFT_KEYS[1]))
    return tuple(out), tuple(mass), tuple(inertia)


def _sensor(data, source: str, shafts: tuple[str, ...]) -> Sensor:
    t = _Table(data, source, "[sensor]")
    t.known(("near", "direction", "tacho", "pulses_per_rev"))
    values = {}
    for key in ("near", "tacho"):
        name = t.text(key, shafts[0])
        if name not in shafts:
            raise GearlabInputError(
                f"{t.where(key)}: unknown shaft {shown(name)}{did_you_mean(name, shafts)}; "
                f"the shafts are {', '.join(shafts)}"
            )
        values[key] = name
    direction = t.text("direction", "y")
    if direction not in SENSOR_DIRECTIONS:
        raise GearlabInputError(
            f"{t.where('direction')}: {shown(direction)} is not one of {', '.join(SENSOR_DIRECTIONS)}"
        )
    ppr = t.param(Param("pulses_per_rev", "", 1, 1, 10_000, "tacho pulses per revolution", integer=True))
    return Sensor(values["near"], direction, values["tacho"], int(ppr))
