"""The plugin registry: pluggy hookspecs, entry-point loading, lookup by name.

Every plugin, built-in or third-party, is a module named in the ``gearlab`` entry-point
group that implements one or more of the hooks below, each returning plugin objects:

    [project.entry-points.gearlab]
    wear = "gearlab_wear.plugin"

    # gearlab_wear/plugin.py
    from gearlab.api import hookimpl

    @hookimpl
    def gearlab_faults():
        return [Wear()]

A plugin that fails to import, breaks a contract or reuses a name is reported with its
package name (``gearlab plugins`` shows it) and left out; the rest keep working.
"""

from __future__ import annotations

import functools
import importlib.metadata
import re
from collections.abc import Iterable
from dataclasses import dataclass, field

import pluggy

from .effect_contract import hook_problem
from .errors import UnknownPluginError, did_you_mean
from .settings import describe_params, params_problem
from .units import display

PROJECT = "gearlab"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


class HookSpecs:
    @hookspec
    def gearlab_faults(self) -> list:
        """Fault plugins (gearlab.physics.faults.Fault): change the tooth section, give an RFA and a ladder."""

    @hookspec
    def gearlab_models(self) -> list:
        """Dynamic models: DOFs, constant M/K/C, projection vector, forces, channels, presets."""

    @hookspec
    def gearlab_adapters(self) -> list:
        """Domain-adaptation methods: extra modules, domain loss on latent features, lambda schedule."""

    @hookspec
    def gearlab_detectors(self) -> list:
        """Detectors: no network; fitted on the source's fault shapes and the target's healthy history."""

    @hookspec
    def gearlab_effects(self) -> list:
        """Unmodelled effects for the sim-to-real gap diagnosis, with bounded parameters and a level."""


KINDS = {
    "fault": "gearlab_faults",
    "model": "gearlab_models",
    "adapter": "gearlab_adapters",
    "detector": "gearlab_detectors",
    "effect": "gearlab_effects",
}
# The kinds a scenario's methods name (`[[methods]] adapter = ...`, a `methods` list): one namespace,
# so that one lookup finds a method whatever its kind
METHODS = ("adapter", "detector")

# What each kind of plugin object must provide, beyond `name` and `params`.
REQUIRED = {
    "fault": ("apply", "ladder_endpoints", "rfa", "resolve", "ladder"),
    "model": ("assemble", "resolve", "preset"),
    "adapter": (),
    "detector": ("fit", "resolve"),
    # and a level, a breaks_symmetry flag and the hook of its level (gearlab.effect_contract.hook_problem);
    # subclasses of gearlab.effect_contract.Effect have all but the hook
    "effect": ("resolve", "spec", "space", "check_config"),
}
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class PluginProblem:
    package: str
    plugin: str
    message: str

    def __str__(self) -> str:
        return f"package '{self.package}', plugin '{self.plugin}': {self.message}"


@dataclass
class Registry:
    plugins: dict[str, dict[str, object]] = field(default_factory=lambda: {kind: {} for kind in KINDS})
    packages: dict[tuple[str, str], str] = field(default_factory=dict)
    problems: list[PluginProblem] = field(default_factory=list)

    def names(self, kind: str | tuple[str, ...]) -> list[str]:
        """The names of one kind, or of several (METHODS) in one sorted list."""
        kinds = (kind,) if isinstance(kind, str) else kind
        return sorted(name for k in kinds for name in self.plugins[k])

    def kind_of(self, name: str, kinds: tuple[str, ...] = METHODS) -> str | None:
        """Which of *kinds* registers *name* (None: none does); names are unique across METHODS."""
        return next((k for k in kinds if name in self.plugins[k]), None)

    def get(self, kind: str | tuple[str, ...], name: str, where: str = ""):
        """The plugin *name* of *kind*, or of whichever of several kinds holds it (METHODS)."""
        kinds = (kind,) if isinstance(kind, str) else kind
        found = self.kind_of(name, kinds)
        if found is not None:
            return self.plugins[found][name]
        prefix = f"{where}: " if where else ""
        known = "; ".join(f"known {k}s: {', '.join(self.names(k)) or 'none'}" for k in kinds)
        raise UnknownPluginError(f"{prefix}unknown {kinds[0]} '{name}'{did_you_mean(name, self.names(kinds))}; {known}")

    def add(self, kind: str, obj, package: str, plugin: str) -> None:
        problem = _contract_problem(kind, obj)
        if problem:
            self.problems.append(PluginProblem(package, plugin, problem))
            return
        name = obj.name
        taken = self.kind_of(name, METHODS if kind in METHODS else (kind,))
        if taken is not None:
            first = f"package '{self.packages[(taken, name)]}'"
            owner = first if taken == kind else f"the {taken} of {first}"  # a method's name is one lookup
            self.problems.append(
                PluginProblem(package, plugin, f"{kind} name '{name}' is already registered by {owner}; ignored")
            )
            return
        self.plugins[kind][name] = obj
        self.packages[(kind, name)] = package

    def describe(self) -> list[dict]:
        rows = []
        for kind in KINDS:
            for name in self.names(kind):
                obj = self.plugins[kind][name]
                info = obj.describe() if hasattr(obj, "describe") else {}
                row = {
                    "kind": kind,
                    "name": name,
                    "package": self.packages[(kind, name)],
                    "doc": info.get("doc", getattr(obj, "doc", "")),
                    "params": info.get("params", describe_params(obj.params)),
                }
                if kind == "effect":  # where it acts, and whether the builder may use the tooth shift
                    row["level"] = getattr(obj, "level", "")
                    row["breaks_symmetry"] = bool(getattr(obj, "breaks_symmetry", False))
                    row["options"] = info.get("options", {k: list(v) for k, v in getattr(obj, "options", {}).items()})
                rows.append(row)
        return rows


def _contract_problem(kind: str, obj) -> str:
    name = getattr(obj, "name", None)
    if not isinstance(name, str) or not _NAME.match(name):
        return f"{kind} plugin {obj!r} has no valid name (expected lower-case letters, digits and '_')"
    problem = params_problem(getattr(obj, "params", None))
    if problem:
        return f"{kind} '{name}': {problem}"
    missing = [attr for attr in REQUIRED[kind] if not callable(getattr(obj, attr, None))]
    if missing:
        return f"{kind} '{name}' lacks {', '.join(missing)}"
    if kind == "effect":
        return hook_problem(obj)
    return ""


def _package(entry_point, names: dict[int, str]) -> str:
    """The distribution that declares *entry_point*, its name read once per distribution into
    *names*: each read parses its METADATA file (48 built-in plugins: 0.1 s of validate, issue 42)."""
    dist = getattr(entry_point, "dist", None)
    if dist is None:
        return entry_point.value.split(".")[0]
    if id(dist) not in names:  # the entry point holds its distribution: the id stays its own
        names[id(dist)] = dist.name
    return names[id(dist)]


def load_registry(entry_points: Iterable | None = None) -> Registry:
    """Load every plugin of the ``gearlab`` entry-point group into a fresh registry.

    gearlab's own entry points load first, so a third party cannot shadow a built-in name.
    """
    if entry_points is None:
        entry_points = importlib.metadata.entry_points(group=PROJECT)
    manager = pluggy.PluginManager(PROJECT)
    manager.add_hookspecs(HookSpecs)
    registry = Registry()
    names: dict[int, str] = {}
    ordered = sorted(
        ((_package(ep, names), ep) for ep in entry_points), key=lambda p: (p[0] != PROJECT, p[0], p[1].name)
    )
    loaded = {}
    for package, ep in ordered:
        try:
            module = ep.load()
            manager.register(module, name=f"{package}:{ep.name}")
        except Exception as exc:  # a broken third-party plugin must not take the rest down
            registry.problems.append(PluginProblem(package, ep.name, f"failed to load: {type(exc).__name__}: {exc}"))
            continue
        loaded[f"{package}:{ep.name}"] = (package, ep.name)
    for kind, hook in KINDS.items():
        for impl in getattr(manager.hook, hook).get_hookimpls():  # registration order
            package, plugin = loaded[impl.plugin_name]
            try:
                objects = list(impl.function())
            except Exception as exc:
                registry.problems.append(PluginProblem(package, plugin, f"{hook}() raised {type(exc).__name__}: {exc}"))
                continue
            for obj in objects:
                registry.add(kind, obj, package, plugin)
    return registry


@functools.cache
def get_registry() -> Registry:
    return load_registry()


def param_text(param: dict) -> str:
    """One parameter of ``Registry.describe()`` as 'name [unit] = default  (low .. high)', in its display unit."""

    def show(value):
        return display(value, param["unit"], param["display_unit"]).split(" ")[0]

    return (
        f"{param['name']} [{param['display_unit'] or '-'}] = {show(param['default'])}  "
        f"({show(param['low'])} .. {show(param['high'])})"
    )


def kind_text(row: dict) -> str:
    """The kind of a ``Registry.describe()`` row; an effect's level and symmetry with it."""
    if row["kind"] != "effect":
        return row["kind"]
    return f"effect ({row['level']}{', breaks tooth-shift symmetry' if row.get('breaks_symmetry') else ''})"


def params_text(row: dict) -> str:
    """A row's parameters (one per line, see param_text) and its text options ('kind: a | b')."""
    lines = [param_text(p) for p in row["params"]]
    lines += [f"{name}: {' | '.join(choices)}" for name, choices in (row.get("options") or {}).items()]
    return "\n".join(lines)
