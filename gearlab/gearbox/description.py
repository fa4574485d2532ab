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
from collections.abc import Callable, Mapping
from dataclasses import MISSING, dataclass, field
from pathlib import Path

from ..errors import GearlabInputError, did_you_mean, shown
from ..files import toml_tables
from ..settings import DEG, MM, declared, setting
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
# Each table's keys are a settings dataclass (gearlab.settings): SI unit, default, bounds, doc and
# the unit shown to people; a field without a default is required, NaN is optional with no default
# (the code derives the value). Every key a table knows is declared, its text keys too: the reader's
# "unknown key" lists and docs/settings.md (DOC_TABLES, gearlab.settings_doc) come from here.
# FITTED names the gap-diagnosis effect (plugins/effects) that may fit a value from measured data.

_NAN = math.nan
# An input shaft's speed: up to 1 kHz (60,000 rpm) in every table; a bare number (read in Hz) up to 100 Hz
# (6,000 rpm), above which it is more likely meant in rpm ('speed = 900' read as 900 Hz passed silently)
MAX_SPEED_HZ, BARE_SPEED_HZ = 1e3, 100.0


@dataclass(frozen=True)
class GearboxKeys:
    """The [gearbox] table's keys."""

    name: str = setting(str, "", doc="the gearbox's name (default: the file's name without .toml)")
    description: str = setting(str, "", doc="a line saying what it is")


DEDENDUM_DOC = "dedendum coefficient h_f* (h_f = h_f* m; clearance c* = h_f* - h_a*; per gear: default the stage's)"


@dataclass(frozen=True, kw_only=True)
class StageKeys:
    """A [[stages]] table's keys."""

    module: float = setting(float, low=1e-4, high=0.1, **MM, doc="module m (ISO 21771 m_n)")
    pressure_angle: float = setting(
        float, math.radians(20), low=math.radians(10), high=math.radians(35), **DEG, doc="pressure angle α"
    )
    face_width: float = setting(float, low=1e-4, high=1.0, **MM, doc="face width b (common to both gears)")
    centre_distance: float = setting(
        float, _NAN, low=1e-4, high=10.0, **MM, doc="centre distance a (optional; checked against z, m, x)"
    )
    addendum: float = setting(
        float, 1.0, low=0.5, high=1.5, doc="addendum coefficient h_a* (h_a = h_a* m; per gear: default the stage's)"
    )
    dedendum: float = setting(float, 1.25, low=0.75, high=2.0, doc=DEDENDUM_DOC)
    tool_tip_radius: float = setting(
        float, 0.2, low=0.0, high=0.5, doc="tip radius coefficient ρ_fP* of the generating rack"
    )
    name: str = setting(str, "", doc="the gear pair's name (default: the gearbox's)")
    pinion: dict = setting(dict, doc="gear 1, the driver on shaft k: [stages.pinion] below")
    wheel: dict = setting(dict, doc="gear 2, driven, on shaft k + 1: [stages.wheel] below")


BORE_DOC = "bore diameter d_bore (the hub radius of the stiffness model is d_bore/2)"


@dataclass(frozen=True, kw_only=True)
class GearKeys:
    """A stage's pinion or wheel table's keys (and PER_GEAR, the stage's keys a gear may set)."""

    z: int = setting(int, low=6, high=10_000, doc="number of teeth z")
    x: float = setting(float, 0.0, low=-1.0, high=2.0, doc="profile shift coefficient x")
    bore: float = setting(float, low=1e-4, high=10.0, **MM, doc=BORE_DOC)
    face_width: float = setting(
        float, _NAN, low=1e-4, high=1.0, **MM, doc="face width of this gear (default: the stage's)"
    )
    tip_diameter: float = setting(
        float, _NAN, low=1e-4, high=20.0, **MM, doc="tip diameter d_a (default d + 2 m (h_a* + x))"
    )
    material: str = setting((str, dict), "steel", doc="a [materials] name, or an inline table {E, nu, density}")


PER_GEAR = ("addendum", "dedendum")  # stage keys a gear may set for itself


@dataclass(frozen=True, kw_only=True)
class MaterialKeys:
    """A [materials] entry's keys."""

    E: float = setting(float, low=1e8, high=1e13, unit="Pa", display_unit="GPa", doc="Young's modulus E")
    nu: float = setting(float, low=0.0, high=0.4999, doc="Poisson's ratio ν")
    density: float = setting(float, 7850.0, low=100.0, high=30_000.0, unit="kg/m^3", doc="density ρ")


STEEL = {"E": 200e9, "nu": 0.3, "density": 7850.0}  # the thesis's steel (Tables 2.3, 2.4)


@dataclass(frozen=True)
class DynamicsKeys:
    """[dynamics]: the lumped-model parameters (thesis Tables 2.3/2.4, eq. 2.96-2.107), one value for the gearbox."""

    motor_inertia: float = setting(
        float, 0.0043, low=1e-7, high=1e3, unit="kg*m^2", doc="I11, the motor's rotor (Table 2.4)"
    )
    load_inertia: float = setting(
        float, 0.0045, low=1e-7, high=1e3, unit="kg*m^2", doc="I22, the load's rotor (Table 2.4)"
    )
    coupling_stiffness: float = setting(
        float, 1e4, low=1.0, high=1e9, unit="N*m/rad", doc="k_c, torsional stiffness of each coupling"
    )
    coupling_damping: float = setting(
        float, 10.0, low=0.0, high=1e6, unit="N*m*s/rad", doc="c_c, torsional damping of each coupling"
    )
    bearing_stiffness: float = setting(
        float, 1e8, low=1e5, high=1e11, unit="N/m", doc="k_b, radial stiffness of each shaft's bearings"
    )
    bearing_damping: float = setting(
        float, 2e3, low=0.0, high=1e7, unit="N*s/m", doc="c_b, radial damping of each shaft's bearings"
    )
    casing_mass: float = setting(float, 10.0, low=0.1, high=1e5, unit="kg", doc="m_f, the casing block")
    mounting_stiffness_x: float = setting(
        float, 2e8, low=1e5, high=1e11, unit="N/m", doc="k_xf, the casing's mounts along x"
    )
    mounting_stiffness_y: float = setting(
        float, 2e8, low=1e5, high=1e11, unit="N/m", doc="k_yf, the casing's mounts along y"
    )
    mounting_damping_x: float = setting(
        float, 2e3, low=0.0, high=1e7, unit="N*s/m", doc="c_xf, the casing's mounts along x"
    )
    mounting_damping_y: float = setting(
        float, 2e3, low=0.0, high=1e7, unit="N*s/m", doc="c_yf, the casing's mounts along y"
    )
    mesh_damping_ratio: float = setting(float, 0.07, low=0.0, high=0.5, doc="ζ of eq. 2.107, the mesh damping ratio")


LOAD_LEVEL_DOC = "factor on the output torque, the [operation] load or a scenario's 'load' (a gap run's load_level fit)"


SPEED_DOC = "input-shaft speed in (0, 1 kHz]: '25 Hz', '1500 rpm', '157.08 rad/s' (a bare number: Hz, up to 100)"


@dataclass(frozen=True)
class OperationKeys:
    """The [operation] table's keys (load_level: what a gap-diagnosis effect may fit)."""

    speed: float = setting(float, _NAN, high=MAX_SPEED_HZ, unit="Hz", doc=SPEED_DOC)
    load: float = setting(float, _NAN, low=0.0, high=1e7, unit="N*m", doc="output torque (default: a scenario's load)")
    load_level: float = setting(float, 1.0, low=0.01, high=100.0, doc=LOAD_LEVEL_DOC)


MASS_DOC = "mass of the shaft's block (its gears and the shaft; default: solid discs)"
INERTIA_DOC = "polar moment of inertia of the block (default: solid discs)"


@dataclass(frozen=True)
class ShaftKeys:
    """A [shafts] entry's keys."""

    name: str = setting(str, "", doc="the shaft's name (default: input, intermediate, output)")
    mass: float = setting(float, _NAN, low=1e-4, high=1e5, unit="kg", doc=MASS_DOC)
    inertia: float = setting(float, _NAN, low=1e-9, high=1e4, unit="kg*m^2", doc=INERTIA_DOC)


SENSOR_DIRECTIONS = ("x", "y", "radial", "axial")


@dataclass(frozen=True)
class SensorKeys:
    """The [sensor] table's keys."""

    near: str = setting(str, "", doc="the shaft whose bearing the accelerometer sits nearest (default: the input)")
    direction: str = setting(str, "y", choices=SENSOR_DIRECTIONS, doc="the accelerometer's direction")
    tacho: str = setting(str, "", doc="the shaft the tacho reads (default: the input)")
    pulses_per_rev: int = setting(int, 1, low=1, high=10_000, doc="tacho pulses per revolution")


GEARBOX_KEYS, STAGE_KEYS, GEAR_KEYS, MATERIAL_KEYS, DYNAMICS, OPERATION_KEYS, SHAFT_KEYS, SENSOR_KEYS = (
    declared(c)
    for c in (GearboxKeys, StageKeys, GearKeys, MaterialKeys, DynamicsKeys, OperationKeys, ShaftKeys, SensorKeys)
)
GEAR_TABLE = {**GEAR_KEYS, **{k: STAGE_KEYS[k] for k in PER_GEAR}}  # what a pinion or wheel table knows
LOAD_LEVEL = "load_level"
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
OPERATION_FITTED = {LOAD_LEVEL: "load_level"}  # [operation] keys a gap-diagnosis effect may fit
# The tables as docs/settings.md lists them (gearlab.settings_doc): (table, its keys, key -> the effect fitting it)
DOC_TABLES = (
    ("[gearbox]", GEARBOX_KEYS, {}),
    ("[operation]", OPERATION_KEYS, {}),  # load_level says what fits it
    ("[materials.NAME]", MATERIAL_KEYS, {}),
    ("[[stages]]", STAGE_KEYS, {}),
    ("[stages.pinion], [stages.wheel]", GEAR_KEYS, {}),  # and PER_GEAR, the stage's rows say
    ("[[shafts]]", SHAFT_KEYS, {}),
    ("[sensor]", SENSOR_KEYS, {}),
    ("[dynamics]", DYNAMICS, FITTED),
)


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
    if -MAX_SPEED_HZ <= value < 0 and isinstance(given, str):  # a box running backwards: its speed's size
        size = re.sub(r"^\s*-\s*", "", given)
        raise GearlabInputError(
            f"{where}: expected an input-shaft speed's size, e.g. '25 Hz', got {given!r}: a box turning either "
            f"direction is read alike (its tacho's pulses, its orders): write {size!r}"
        )
    if not 0 < value <= MAX_SPEED_HZ:
        raise GearlabInputError(
            f"{where}: expected an input-shaft speed up to 1 kHz, e.g. '25 Hz', got {value:g}{bare_speed(given)}"
            f"{_rpm_as_hz(given, value)}"
        )
    if bare_speed(given) and value > BARE_SPEED_HZ:  # '900' meant in rpm: 54,000 rpm as read
        raise GearlabInputError(
            f"{where}: a bare number is in Hz, and {value:g} Hz ({60 * value:,.0f} rpm) is no usual input-shaft "
            f"speed; expected the unit, e.g. '{value:g} rpm' ({value / 60:.4g} Hz) or '{value:g} Hz'"
        )
    return value


def bare_speed(value) -> str:
    """What an out-of-bounds speed's message adds when the speed was a bare number (read as Hz:
    '2100' meant in rpm is 2100 turns a second)."""
    bare = isinstance(value, (int, float)) and not isinstance(value, bool)
    if isinstance(value, str):
        bare = re.fullmatch(r"\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*", value) is not None
    return " (a bare number is in Hz; expected a speed with its unit, e.g. '35 Hz' or '2100 rpm')" if bare else ""


def _rpm_as_hz(given, value: float) -> str:
    """What an out-of-bounds speed's message adds when it was written in Hz: a motor's plate gives rpm,
    and '1470 Hz' copied from it is 1470 rpm, 24.5 Hz."""
    if not (isinstance(given, str) and re.search(r"\d\s*(Hz|hz|1/s)\s*$", given)) or value / 60 > MAX_SPEED_HZ:
        return ""
    return f" (as {given.strip()!r}: rpm meant? '{value:g} rpm' is {value / 60:.4g} Hz)"


def _module_of_pitch(value, where: str) -> str:
    """A diametral pitch P (teeth per inch of pitch diameter) is a module m = 25.4 mm / P: the one to write."""
    try:  # a bare number is teeth per inch, as a US drawing gives it
        per_m = to_si(value, "1/m", where) if isinstance(value, str) else float(value) / 0.0254
        written = f"module = '{1e3 / per_m:.4g} mm' (25.4 mm / P)" if per_m > 0 else ""
    except (GearlabInputError, TypeError, ValueError):
        written = ""
    return f"a diametral pitch P is written as a module: {written or 'module = 25.4 mm / P'}"


def _not_yet(kind: str) -> Callable[[object, str], str]:
    said = f"{kind} stages are not described yet (spur stages in series only: docs/your_gearbox.md, 'What you "
    said += "cannot do yet'); expected a spur stage's keys"
    return lambda value, where: said


def _idler_stages(data: Mapping) -> str:
    """How an idler is written: two [[stages]] sharing its tooth count (39/45 then 45/61), in the stage's numbers."""
    z = {k: data[k].get("z", k) if isinstance(data.get(k), Mapping) else k for k in ("pinion", "idler", "wheel")}
    return (
        f"an idler is written as two [[stages]] sharing its teeth: pinion {z['pinion']} / wheel {z['idler']}, then "
        f"pinion {z['idler']} / wheel {z['wheel']} ({z['pinion']}/{z['idler']} + {z['idler']}/{z['wheel']}; "
        "docs/your_gearbox.md, 'What you cannot do yet')"
    )


# Keys a gear engineer writes for a stage that gearlab takes in another form (a US diametral pitch) or does not
# simulate yet: named as such, where 'unknown key' offered a neighbour by spelling ('helix_angle': pressure_angle?)
OTHER_GEARING: dict[str, Callable[[object, str], str]] = {
    "diametral_pitch": _module_of_pitch,
    **dict.fromkeys(("helix_angle", "beta", "helix", "hand", "normal_module"), _not_yet("helical")),
    **dict.fromkeys(("planets", "sun", "ring", "planet", "carrier"), _not_yet("planetary")),
}


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
            if key in OTHER_GEARING:  # a gear engineer's key for what gearlab reads otherwise, or not yet
                raise GearlabInputError(f"{self.where(key)}: {OTHER_GEARING[key](self.data[key], self.where(key))}")
            if key not in keys:
                raise GearlabInputError(
                    f"{self.where(key)}: unknown key{did_you_mean(str(key), keys)}; known keys: {', '.join(keys)}"
                )

    def param(self, keys: Mapping, name: str, default: float | None = None) -> float | None:
        """The value of key *name* of *keys* (a table's declared keys) in SI, checked against its
        bounds; *default* (or the declared one) when absent, None when absent with no default (a
        required key, or an optional one declared NaN, and none given)."""
        p, declared_default = keys[name]
        if name not in self.data:
            value = declared_default if default is None else default
            if value is MISSING or (isinstance(value, float) and math.isnan(value)):
                return None
            return value
        where = self.where(name)
        raw = self.data[name]
        if p.integer:
            if isinstance(raw, bool) or not isinstance(raw, int):
                # TOML reads 31.0 as a decimal, though its writer meant a whole number: say how to write it
                written = f": write {name} = {raw:.0f}" if isinstance(raw, float) and raw.is_integer() else ""
                raise GearlabInputError(f"{where}: expected a whole number, got {shown(raw)}{written}")
            value = raw
        else:
            value = to_si(raw, p.unit, where)
        if not p.low <= value <= p.high:
            # a bare number is SI ('module = 2.5' is 2.5 m, 'pressure_angle = 20' is 20 rad): say so
            # ... and so is a number in quotes ('module = "2.5"' read "'2.5' is outside [0.1 mm, 100 mm]")
            bare = p.unit and _unitless(raw) and p.show(p.low) != f"{p.low:g} {p.unit}"
            said = f" (a bare number is in {p.unit}; expected e.g. '{raw} {p.display_unit}')" if bare else ""
            if not bare and p.unit == "rad" and p.low <= (n := math.degrees(value)) <= p.high:  # radians as degrees
                said = f" ({n:.4g} rad is {math.degrees(n):.3g} deg: radians written as degrees? expected the degrees)"
            raise GearlabInputError(f"{where}: {shown(raw)} is outside [{p.show(p.low)}, {p.show(p.high)}]{said}")
        return value

    def required(self, keys: Mapping, name: str, default: float | None = None) -> float:
        value = self.param(keys, name, default)
        if value is None:
            p = keys[name][0]
            raise GearlabInputError(
                f"{self.where(name)}: missing; expected {p.doc}" + (f" in {p.display_unit}" if p.display_unit else "")
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
    head.known(GEARBOX_KEYS)
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
    op.known(OPERATION_KEYS)
    speed = speed_hz(op.data["speed"], op.where("speed")) if "speed" in op.data else None
    load = op.param(OPERATION_KEYS, "load")

    sensor = _sensor(data.get("sensor", {}), source, shafts)
    dyn = _Table(data.get("dynamics", {}), source, "[dynamics]")
    dyn.known(DYNAMICS)
    dynamics = {name: dyn.param(DYNAMICS, name) for name in DYNAMICS}

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
        tuple(dyn.data) + ((LOAD_LEVEL,) if LOAD_LEVEL in op.data else ()),
        op.param(OPERATION_KEYS, LOAD_LEVEL),
    )
    check_geometry(box)
    return box


def _materials(data, source: str) -> dict[str, Material]:
    table = _Table(data, source, "[materials]")
    out = {"steel": Material("steel", **STEEL)}
    for key, value in table.data.items():
        t = _Table(value, source, f"[materials.{key}]")
        t.known(MATERIAL_KEYS)
        E, nu, density = (t.required(MATERIAL_KEYS, name) for name in MATERIAL_KEYS)
        out[str(key)] = Material(str(key), E, nu, density)
    return out


def _stage(data: Mapping, i: int, source: str, materials: dict[str, Material]) -> Stage:
    t = _Table(data, source, f"[[stages]] #{i + 1}")
    if "idler" in data:  # a gear between pinion and wheel: its two meshes are two stages that share its teeth
        raise GearlabInputError(f"{t.where('idler')}: {_idler_stages(data)}")
    t.known(STAGE_KEYS)
    name = t.text("name", "")
    numbers = [key for key, (p, _) in STAGE_KEYS.items() if p.types in (int, float)]
    module, alpha, width, a, ha, hf, rho = (t.param(STAGE_KEYS, key) for key in numbers)
    module = t.required(STAGE_KEYS, "module")
    width = t.required(STAGE_KEYS, "face_width")
    if hf <= ha:
        raise GearlabInputError(
            f"{t.where('dedendum')}: h_f* = {hf:g} must exceed the addendum coefficient h_a* = {ha:g} "
            "(the tip clearance c* = h_f* - h_a* is positive)"
        )
    gears = [_gear(t.sub(role), role, width, materials, hf - ha) for role in ("pinion", "wheel")]
    return Stage(i + 1, name, module, alpha, width, ha, hf, rho, a, *gears, where=t.where())


def _gear(t: _Table, role: str, stage_width: float, materials: dict[str, Material], clearance: float) -> GearSpec:
    t.known(GEAR_TABLE)
    z = int(t.required(GEAR_KEYS, "z"))
    x = t.param(GEAR_KEYS, "x")
    bore = t.required(GEAR_KEYS, "bore")
    width = t.param(GEAR_KEYS, "face_width", stage_width)
    tip = t.param(GEAR_KEYS, "tip_diameter")
    ha, hf = (t.param(STAGE_KEYS, name) if name in t.data else None for name in PER_GEAR)
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
        m.known(MATERIAL_KEYS)
        mat = Material(f"{t.name}.material", *(m.required(MATERIAL_KEYS, name) for name in MATERIAL_KEYS))
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
        t.known(SHAFT_KEYS)
        name = t.text("name", names[i])
        if not name or name in out:
            raise GearlabInputError(f"{t.where('name')}: expected a distinct non-empty shaft name, got {shown(name)}")
        out.append(name)
        mass.append(t.param(SHAFT_KEYS, "mass"))
        inertia.append(t.param(SHAFT_KEYS, "inertia"))
    return tuple(out), tuple(mass), tuple(inertia)


def _sensor(data, source: str, shafts: tuple[str, ...]) -> Sensor:
    t = _Table(data, source, "[sensor]")
    t.known(SENSOR_KEYS)
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
    ppr = t.param(SENSOR_KEYS, "pulses_per_rev")
    return Sensor(values["near"], direction, values["tacho"], int(ppr))


def _unitless(raw) -> bool:
    """Whether *raw* (a key's value) is a number without a unit: a TOML number, or a text of one alone."""
    if not isinstance(raw, str):
        return True
    try:
        float(raw.strip())
    except ValueError:
        return False
    return True
