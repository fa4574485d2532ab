"""The pluggy registry: built-in faults, entry-point loading, broken and clashing plugins."""

import dataclasses
import importlib.metadata
import types
from dataclasses import dataclass

import pytest

from gearlab.errors import GearlabInputError, UnknownPluginError
from gearlab.physics.faults import Fault
from gearlab.registry import get_registry, hookimpl, load_registry
from gearlab.settings import NoParams, declared, setting

BUILTIN_FAULTS = ["broken_tip", "chip", "crack", "pit", "spall"]


class FakeDist:
    def __init__(self, name):
        self.name = name


class FakeEntryPoint:
    """What load_registry needs from importlib.metadata.EntryPoint."""

    def __init__(self, name, package, module=None, error=None):
        self.name = name
        self.value = f"{package.replace('-', '_')}.{name}"
        self.dist = FakeDist(package)
        self._module, self._error = module, error
        self.loads = 0

    def load(self):
        self.loads += 1
        if self._error is not None:
            raise self._error
        return self._module


def plugin_module(name, *objects, hook="gearlab_faults"):
    module = types.ModuleType(name)

    def hook_function():
        return list(objects)

    hook_function.__name__ = hook
    setattr(module, hook, hookimpl(hook_function))
    return module


def builtin_entry_points():
    return [ep for ep in importlib.metadata.entry_points(group="gearlab") if ep.dist.name == "gearlab"]


@dataclass(frozen=True)
class WearParams:
    depth: float = setting(float, 0.0, low=0.0, high=1e-3, unit="m", display_unit="um", doc="wear depth")


class Wear(Fault):
    name = "wear"
    doc = "uniform wear"
    params = WearParams

    def apply(self, section, params, pair):
        h = section.h - params["depth"]  # both flanks worn: A and I follow h (eq. 2.18, 2.19)
        return section.replace(h=h, A=2 * h * section.L, I=2.0 / 3.0 * h**3 * section.L)

    def ladder_endpoints(self, pair):
        return {"depth": 0.0}, {"depth": 1e-4}


class FakeCrack(Wear):
    name = "crack"


class PlainParams(Wear):
    name = "plainparams"
    params = type("PlainParams", (), {"depth": 0.0})  # not a dataclass


@dataclass(frozen=True)
class UndeclaredParams:
    depth: float = 0.0  # a plain field, no setting()


class Undeclared(Wear):
    name = "undeclared"
    params = UndeclaredParams


class NotParams(Wear):
    name = "notparams"
    params = ("depth",)


class NoApply:
    name = "noapply"
    doc = ""
    params = NoParams

    def ladder_endpoints(self, pair):
        return {}, {}

    def rfa(self, params, pair):
        return 0.0

    def resolve(self, given, pair, where=""):
        return {}

    def ladder(self, pair, steps=20):
        return [{}] * steps


@dataclass(frozen=True)
class BadDefaultParams:
    depth: float = setting(float, 2.0, low=0.0, high=1e-3, unit="m", display_unit="um", doc="wear depth")


class BadDefault(Wear):
    name = "baddefault"
    params = BadDefaultParams


# --- the built-in registry -------------------------------------------------------------------


def test_builtin_faults_are_registered_by_gearlab():
    registry = get_registry()
    assert registry.problems == []
    assert registry.names("fault") == BUILTIN_FAULTS
    for name in BUILTIN_FAULTS:
        assert registry.packages[("fault", name)] == "gearlab"
        fault = registry.get("fault", name)
        assert fault.name == name
        assert dataclasses.is_dataclass(fault.params) and declared(fault.params)
    rows = [row for row in registry.describe() if row["kind"] == "fault"]
    assert [row["name"] for row in rows] == BUILTIN_FAULTS
    assert all(row["package"] == "gearlab" and row["params"] for row in rows)


def test_builtins_come_through_the_entry_point_group():
    """The core has no private path for its own plugins: loading only the entry points gives them."""
    registry = load_registry(builtin_entry_points())
    assert registry.problems == []
    assert registry.names("fault") == BUILTIN_FAULTS
    assert load_registry([]).names("fault") == []


def test_a_distribution_name_is_read_once_for_all_its_plugins():
    """Each read of a distribution's name parses its METADATA file: 48 reads of gearlab's were a
    tenth of `gearlab validate` (issue 42). One read per distribution, each plugin still its own."""

    class CountingDist:
        reads = 0

        @property
        def name(self):
            CountingDist.reads += 1
            return "acme-gears"

    shared = CountingDist()
    eps = [FakeEntryPoint(n, "acme-gears", plugin_module(n, type(n, (Wear,), {"name": n}))) for n in ("wa", "wb", "wc")]
    for ep in eps:
        ep.dist = shared
    registry = load_registry(eps)
    assert CountingDist.reads == 1
    assert registry.names("fault") == ["wa", "wb", "wc"] and registry.problems == []
    assert {registry.packages[("fault", n)] for n in ("wa", "wb", "wc")} == {"acme-gears"}


def test_unknown_plugin_name_suggests_and_lists():
    registry = get_registry()
    with pytest.raises(UnknownPluginError) as info:
        registry.get("fault", "crak")
    message = str(info.value)
    assert "did you mean 'crack'" in message
    assert "broken_tip, chip, crack, pit, spall" in message
    assert isinstance(info.value, GearlabInputError)  # the CLI turns it into exit code 2
    with pytest.raises(UnknownPluginError, match=r"scenario\.toml: unknown fault 'wer'"):
        registry.get("fault", "wer", where="scenario.toml")


# --- third-party plugins ---------------------------------------------------------------------


def test_third_party_fault_is_registered_with_its_package():
    ep = FakeEntryPoint("wear", "gearlab-wear", plugin_module("gearlab_wear.plugin", Wear()))
    registry = load_registry([*builtin_entry_points(), ep])
    assert registry.problems == []
    assert registry.names("fault") == sorted(BUILTIN_FAULTS + ["wear"])
    assert registry.packages[("fault", "wear")] == "gearlab-wear"
    assert ep.loads == 1


def test_plugin_that_fails_to_import_is_reported_and_the_rest_load():
    broken = FakeEntryPoint("broken", "broken-pkg", error=ImportError("No module named 'missing_dependency'"))
    wear = FakeEntryPoint("wear", "gearlab-wear", plugin_module("gearlab_wear.plugin2", Wear()))
    registry = load_registry([broken, *builtin_entry_points(), wear])
    assert registry.names("fault") == sorted(BUILTIN_FAULTS + ["wear"])
    assert len(registry.problems) == 1
    problem = registry.problems[0]
    assert problem.package == "broken-pkg"
    assert problem.plugin == "broken"
    assert "ImportError" in problem.message and "missing_dependency" in problem.message
    assert "broken-pkg" in str(problem)


def test_hook_that_raises_is_reported():
    module = types.ModuleType("raiser")

    @hookimpl
    def gearlab_faults():
        raise RuntimeError("boom")

    module.gearlab_faults = gearlab_faults
    registry = load_registry([*builtin_entry_points(), FakeEntryPoint("raiser", "raiser-pkg", module)])
    assert registry.names("fault") == BUILTIN_FAULTS
    assert [p.package for p in registry.problems] == ["raiser-pkg"]
    assert "RuntimeError: boom" in registry.problems[0].message


@pytest.mark.parametrize("evil_first", [True, False])
def test_duplicate_name_is_reported_and_the_builtin_kept(evil_first):
    evil = FakeEntryPoint("crack", "evil-pkg", plugin_module("evil.plugin", FakeCrack()))
    eps = [evil, *builtin_entry_points()] if evil_first else [*builtin_entry_points(), evil]
    registry = load_registry(eps)
    builtin = get_registry().get("fault", "crack")
    assert type(registry.get("fault", "crack")) is type(builtin)
    assert registry.packages[("fault", "crack")] == "gearlab"
    assert len(registry.problems) == 1
    text = str(registry.problems[0])
    assert "evil-pkg" in text and "'gearlab'" in text and "crack" in text


def test_duplicate_between_two_third_parties_keeps_the_first_by_package_name():
    a = FakeEntryPoint("wear", "aaa-wear", plugin_module("aaa.plugin", Wear()))
    b = FakeEntryPoint("wear", "bbb-wear", plugin_module("bbb.plugin", Wear()))
    registry = load_registry([b, a])
    assert registry.packages[("fault", "wear")] == "aaa-wear"
    assert len(registry.problems) == 1
    assert "bbb-wear" in str(registry.problems[0]) and "aaa-wear" in str(registry.problems[0])


def test_adapters_and_detectors_share_one_namespace_and_one_lookup():
    """A scenario's methods name adapters and detectors alike: a detector may not take an
    adapter's name, and one lookup finds either kind (or lists both)."""
    from gearlab.api import Detector
    from gearlab.registry import METHODS

    class Shadow(Detector):
        name = "mmd"

        def statistic(self, source, target, params=None):
            return None

    shadow = FakeEntryPoint("shadow", "shadow-pkg", plugin_module("s", Shadow(), hook="gearlab_detectors"))
    registry = load_registry([*builtin_entry_points(), shadow])
    assert registry.names("detector") == ["likelihood_ratio", "matched_filter"]
    assert registry.kind_of("mmd") == "adapter" and registry.kind_of("matched_filter") == "detector"
    (problem,) = registry.problems
    assert "detector name 'mmd' is already registered by the adapter of package 'gearlab'" in str(problem)
    assert registry.get(METHODS, "matched_filter").kind == "detector"
    assert registry.get(METHODS, "mmd").kind == "adapter"
    assert registry.names(METHODS) == sorted(registry.names("adapter") + registry.names("detector"))
    with pytest.raises(
        UnknownPluginError,
        match=r"w: unknown adapter 'matched_filtr' \(did you mean 'matched_filter'"
        r"\?\); known adapters: coral, .*; known detectors: likelihood_ratio, matched_filter$",
    ):
        registry.get(METHODS, "matched_filtr", "w")
    with pytest.raises(UnknownPluginError, match=r"unknown detector 'mmd'"):
        registry.get("detector", "mmd")


@pytest.mark.parametrize(
    "obj, message",
    [
        (PlainParams(), "params must be a dataclass of fields declared with gearlab.api.setting"),
        (NotParams(), "params must be a dataclass of fields declared with gearlab.api.setting"),
        (Undeclared(), "parameter 'depth' must be declared with setting(float or int"),
        (NoApply(), "lacks apply"),
        (BadDefault(), "default 2.0 lies outside its bounds"),
    ],
    ids=["plain-class-params", "str-params", "undeclared-field", "no-apply", "bad-default"],
)
def test_bad_schema_is_reported(obj, message):
    good = Wear()
    module = plugin_module("badschema.plugin", obj, good)
    registry = load_registry([*builtin_entry_points(), FakeEntryPoint("bad", "bad-schema-pkg", module)])
    assert obj.name not in registry.names("fault")
    assert "wear" in registry.names("fault")  # the same hook's valid object still registers
    assert len(registry.problems) == 1
    problem = registry.problems[0]
    assert problem.package == "bad-schema-pkg"
    assert message in problem.message
    assert obj.name in problem.message


@pytest.mark.parametrize("bad_name", ["Wear", "3d", "", None, "has space"])
def test_bad_plugin_name_is_reported(bad_name):
    class Named(Wear):
        name = bad_name

    registry = load_registry([FakeEntryPoint("named", "named-pkg", plugin_module("named.plugin", Named()))])
    assert registry.names("fault") == []
    assert len(registry.problems) == 1 and "no valid name" in registry.problems[0].message


def test_third_party_fault_runs_through_the_engine():
    """A new fault needs nothing but the Fault contract: it resolves, ladders and changes the TVMS."""
    from gearlab.physics.presets import gear_pair
    from gearlab.physics.stiffness import MeshStiffnessModel

    registry = load_registry([FakeEntryPoint("wear", "gearlab-wear", plugin_module("wear.engine", Wear()))])
    wear = registry.get("fault", "wear")
    pair = gear_pair("meng2020")
    params = wear.resolve({"depth": "50 um"}, pair)
    assert params["depth"] == pytest.approx(50e-6)
    assert len(wear.ladder(pair)) == 20 and wear.at_step(pair, 20)["depth"] == pytest.approx(1e-4)
    model = MeshStiffnessModel(pair)
    assert model.mesh_stiffness([wear.place(3, params, pair)]).mean < model.mesh_stiffness().mean
