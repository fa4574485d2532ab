"""The layering of gearlab, written down and enforced (docs/architecture.md).

Every module of the gearlab package is parsed (not imported); every ``import`` of a gearlab
module counts, at module level and inside functions alike (an import inside a function is
still a dependency: it only runs later). A module may import from its own layer and the
layers below it, never from a layer above, and the import graph has no cycle. Imports under
``if TYPE_CHECKING:`` are left out: they never run.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "gearlab"

# Bottom to top. A module belongs to the first entry that names it or a package holding it.
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    (
        "base",
        (
            "gearlab",
            "gearlab.errors",
            "gearlab.units",
            "gearlab.files",
            "gearlab.confined",
            "gearlab.events",
            "gearlab.charts",
            "gearlab.executors",
            "gearlab.memo",
        ),
    ),
    ("physics and signals", ("gearlab.physics", "gearlab.signals", "gearlab.gearbox")),
    ("dynamics", ("gearlab.dynamics",)),
    ("effect contract", ("gearlab.effect_contract",)),
    ("plugin registry", ("gearlab.registry",)),
    ("effect chain and learning", ("gearlab.effects", "gearlab.learn")),
    ("datasets", ("gearlab.data",)),
    (
        "gap diagnosis and recording inspection",
        ("gearlab.gap", "gearlab.inspect", "gearlab.inspect_axes", "gearlab.inspect_history", "gearlab.inspect_tacho"),
    ),
    ("scenario schema, run directory, figures", ("gearlab.scenario", "gearlab.runs", "gearlab.plots")),
    ("shared kind parts", ("gearlab.parts",)),
    ("scenario kinds", ("gearlab.kinds",)),
    ("verdict and report", ("gearlab.verdict", "gearlab.report", "gearlab.runinfo", "gearlab.inspect_report")),
    ("run engine", ("gearlab.engine",)),
    (
        "front-ends and the plugin API",
        (
            "gearlab.compare",
            "gearlab.tui",
            "gearlab.cli",
            "gearlab.cliconv",
            "gearlab.terminal",
            "gearlab.__main__",
            "gearlab.api",
            "gearlab.notebook",  # the notebook API, reached as gearlab.<name> (resolved on first use)
            "gearlab.settings_doc",
            "gearlab.inspect_takes",  # inspects each take through the notebook API
        ),
    ),
]


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def layer_of(module: str) -> int:
    best = None
    for index, (_, names) in enumerate(LAYERS):
        for name in names:
            if module == name or module.startswith(name + "."):
                if best is None or len(name) > best[1]:
                    best = (index, len(name))
    if best is None:
        raise AssertionError(f"{module} is in no layer of tests/test_architecture.py: add it to LAYERS")
    return best[0]


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    """ids of the import nodes under `if TYPE_CHECKING:` (never executed)."""
    skipped = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                skipped.update(id(n) for n in ast.walk(child))
    return skipped


def imports_of(module: str) -> list[tuple[str, int, bool]]:
    """(imported gearlab module, line, at module level) for every import in *module*."""
    path = MODULES[module]
    tree = ast.parse(path.read_text(), str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    skipped = _type_checking_nodes(tree)
    top = {id(n) for n in tree.body}
    found = []
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        targets = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            # `from pkg import sub` imports the submodule pkg.sub
            targets = [f"{source}.{a.name}" if f"{source}.{a.name}" in MODULES else source for a in node.names]
        for target in targets:
            while target and target not in MODULES and "." in target:  # `import gearlab.x.y` of a name
                target = target.rpartition(".")[0]
            if target in MODULES and target != module:
                found.append((target, node.lineno, id(node) in top))
    return found


@functools.cache
def graph() -> dict[str, list[tuple[str, int, bool]]]:
    """Every module's imports (imports_of), parsed on first use: at module level every pytest worker
    paid it at collection (1.4 s of CPU), the one that runs this file alone needs it."""
    return {module: imports_of(module) for module in MODULES}


def test_every_module_has_a_layer():
    for module in MODULES:
        layer_of(module)


def test_no_module_imports_from_a_layer_above_its_own():
    upward = [
        f"{MODULES[m].relative_to(PACKAGE.parent)}:{line}: {m} ({LAYERS[layer_of(m)][0]}) imports {t} "
        f"({LAYERS[layer_of(t)][0]})"
        for m, edges in graph().items()
        for t, line, _ in edges
        if layer_of(t) > layer_of(m)
    ]
    assert not upward, "upward imports:\n" + "\n".join(upward)


def test_the_import_graph_has_no_cycle():
    edges = {m: sorted({t for t, _, _ in e}) for m, e in graph().items()}
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        path.append(m)
        for t in edges[m]:
            if state.get(t) == 1:
                return path[path.index(t) :] + [t]
            if t not in state and (cycle := visit(t)):
                return cycle
        path.pop()
        state[m] = 2
        return None

    for m in sorted(edges):
        if m not in state and (cycle := visit(m)):
            pytest.fail("import cycle: " + " -> ".join(cycle))


def test_the_check_sees_function_level_imports_and_orders_the_layers():
    # the test itself: a function-level import is an edge, and the layers order them
    # (adapters import the torch losses inside their methods: start-up time)
    assert ("gearlab.learn.losses", True) not in {(t, top) for t, _, top in graph()["gearlab.learn.adapters"]}
    assert any(t == "gearlab.learn.losses" and not top for t, _, top in graph()["gearlab.learn.adapters"])
    assert layer_of("gearlab.dynamics.newmark") < layer_of("gearlab.effects") < layer_of("gearlab.engine")
    assert layer_of("gearlab.kinds.gap") == layer_of("gearlab.kinds")


def kind_of(module: str) -> str | None:
    """The registered scenario kind whose module (or package) holds *module*, or whose own helper
    module it is (gearlab.kinds.<kind>_*: detection_records is the detection kind's), the longest
    name winning (transfer_benchmark_draw is transfer_benchmark's, not transfer's); None: shared."""
    from gearlab.kinds import SCENARIO_KINDS

    if not module.startswith("gearlab.kinds."):
        return None
    top = module.split(".")[2]
    owners = [k.__name__ for k in SCENARIO_KINDS.values() if top == k.__name__.rpartition(".")[2]]
    owners += [k.__name__ for k in SCENARIO_KINDS.values() if top.startswith(k.__name__.rpartition(".")[2] + "_")]
    return max(owners, key=len, default=None)


def test_no_scenario_kind_imports_another():
    # what kinds share lives below them (gearlab.parts, gearlab.kinds.common); only the registry
    # (gearlab.kinds itself) names every kind
    crossing = [
        f"{MODULES[m].relative_to(PACKAGE.parent)}:{line}: {m} imports the kind {kind_of(t)}"
        for m, edges in graph().items()
        if m.startswith("gearlab.kinds.")
        for t, line, _ in edges
        if kind_of(t) is not None and kind_of(t) != kind_of(m)
    ]
    assert not crossing, "a scenario kind imports another:\n" + "\n".join(crossing)
    assert kind_of("gearlab.kinds.transfer") == "gearlab.kinds.transfer" and kind_of("gearlab.kinds.common") is None
    # a kind's helper modules are the kind's: the gap kind reading the detection kind's records is a crossing
    assert kind_of("gearlab.kinds.detection_records") == "gearlab.kinds.detection"
    assert kind_of("gearlab.kinds.transfer_benchmark_draw") == "gearlab.kinds.transfer_benchmark"
    assert kind_of("gearlab.kinds.gap_benchmark.trials") == "gearlab.kinds.gap_benchmark"
    assert kind_of("gearlab.kinds.record_effects") is None and kind_of("gearlab.kinds") is None


# No module is longer than this; the ones still over it, to be split (issue 38): the list only shrinks.
MAX_LINES = 800
TOO_LONG: set[str] = set()


def test_no_module_is_over_the_line_limit():
    lines = {m: len(p.read_text().splitlines()) for m, p in MODULES.items()}
    over = {m for m, n in lines.items() if n > MAX_LINES}
    assert over <= TOO_LONG, "over {MAX_LINES} lines: split them\n" + "\n".join(
        f"{MODULES[m].relative_to(PACKAGE.parent)}: {lines[m]}" for m in sorted(over - TOO_LONG)
    )
    done = {m for m in TOO_LONG if lines.get(m, 0) <= MAX_LINES}
    assert not done, f"within {MAX_LINES} lines now (or gone): take them off TOO_LONG: {sorted(done)}"


# The front-ends reach a kind through the kind contract (gearlab.kinds.contract) only: they never
# compare with a kind's name, key a table by it, or import a kind's module (issue 38).
FRONT_ENDS = ("gearlab.verdict", "gearlab.report", "gearlab.compare", "gearlab.cli", "gearlab.tui", "gearlab.plots")


def kind_names_in(module: str) -> list[str]:
    """Where *module* names a kind: a comparison with its name, a table keyed by it, its name as any
    other string (a message, an argument; docstrings aside), an import of the kind's modules."""
    from gearlab.kinds import SCENARIO_KINDS

    names = set(SCENARIO_KINDS)

    def named(node) -> bool:
        items = node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else [node]
        return any(isinstance(i, ast.Constant) and i.value in names for i in items)

    path = MODULES[module]
    tree = ast.parse(path.read_text())
    docstrings = {
        id(n.body[0].value)
        for n in ast.walk(tree)
        if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and n.body
        and isinstance(n.body[0], ast.Expr)
        and isinstance(n.body[0].value, ast.Constant)
    }
    found, seen = [], set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and any(named(n) for n in [node.left, *node.comparators]):
            found.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {ast.unparse(node)}")
            seen.update(id(n) for n in ast.walk(node))
        elif isinstance(node, ast.Dict) and any(k is not None and named(k) for k in node.keys):
            found.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: a table keyed by kind names")
            seen.update(id(n) for n in ast.walk(node))
    found += [
        f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: the kind name {node.value!r}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and named(node) and id(node) not in seen | docstrings
    ]
    found += sorted(
        {
            f"{path.relative_to(PACKAGE.parent)}:{line}: imports the kind {kind_of(t)}"
            for t, line, _ in graph()[module]
            if kind_of(t) is not None
        }
    )
    return found


def test_front_ends_do_not_switch_on_kind_names():
    fronts = [m for m in MODULES if any(m == f or m.startswith(f + ".") for f in FRONT_ENDS)]
    found = {m: kind_names_in(m) for m in fronts}
    assert not any(found.values()), "kind names in the front-ends (go through the kind contract):\n" + "\n".join(
        line for m in sorted(found) for line in found[m]
    )
    # the check sees them: the kinds' registry keys its table by their names and imports each one's module
    from gearlab.kinds import SCENARIO_KINDS

    registry = kind_names_in("gearlab.kinds")
    assert sum("a table keyed by kind names" in f for f in registry) == 1
    assert sum("imports the kind" in f for f in registry) == len(SCENARIO_KINDS)
    assert any(f.endswith("the kind name 'gap_benchmark'") for f in registry)  # GAP_COMMAND_KINDS: a plain string


def kind_owning(name: str, doc: str) -> str | None:
    """The kind a function belongs to by its *name* (a kind's name among its words: gap_figures) or
    its docstring *doc* (one of a kind's modules named, 'kind `gap`', 'the detection kind'), else None."""
    from gearlab.kinds import SCENARIO_KINDS

    words = name.strip("_").split("_")
    for kind in sorted(SCENARIO_KINDS, key=len, reverse=True):
        n = len(kind.split("_"))
        if any(words[i : i + n] == kind.split("_") for i in range(len(words))):
            return kind
    modules = [kind_of(f"gearlab.kinds.{m}") or "" for m in re.findall(r"kinds\.(\w+)", doc)]
    said = [a or b for a, b in re.findall(r"\bkind\W{0,2}(\w+)|(\w+)\W{0,2} kind\b", doc)]
    named = [m.rpartition(".")[2] for m in modules if m] + [k for k in said if k in SCENARIO_KINDS]
    return named[0] if named else None


def test_plots_holds_no_kinds_figures():
    """gearlab.plots holds the shared drawing (save, generic charts); each kind's own figures live on
    its side (gearlab.kinds.<kind>_figures), reached through the kind (issue 38)."""
    path = MODULES["gearlab.plots"]
    owned = [
        f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {node.name} is the {kind} kind's"
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, (ast.FunctionDef, ast.ClassDef))
        and (kind := kind_owning(node.name, ast.get_docstring(node) or ""))
    ]
    assert not owned, "a kind's figures in gearlab.plots (move them to the kind):\n" + "\n".join(owned)
    # the check sees them: by name, by a kind's module in the docstring, by 'kind `gap`'
    assert kind_owning("noise_study_figures", "") == "noise_study" and kind_owning("dataset_signals", "") == "dataset"
    assert kind_owning("score_trend", "The trends (gearlab.kinds.detection_scoring.score_trends)") == "detection"
    assert kind_owning("figures", "The gap diagnosis (kind `gap`): per-view gap") == "gap"
    assert kind_owning("chart_figure", "A gearlab.charts.Chart as a PNG") is None


def test_plugins_import_gearlab_only_through_the_public_api():
    root = PACKAGE.parent
    private = []
    # the plugin packages: the built-in ones and the out-of-tree example (examples/your_gearbox is a
    # user's script that makes recordings, not a plugin)
    for path in sorted([*(root / "plugins").rglob("*.py"), *(root / "examples" / "gearlab-wear").rglob("*.py")]):
        for node in ast.walk(ast.parse(path.read_text())):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom) and not node.level
                else []
            )
            private += [
                f"{path.relative_to(root)}:{node.lineno}: {n}"
                for n in names
                if (n == "gearlab" or n.startswith("gearlab.")) and n != "gearlab.api"
            ]
    assert not private, "plugins must import from gearlab.api only:\n" + "\n".join(private)


def test_every_scenario_kind_fulfils_the_kind_contract():
    import inspect
    import types

    from gearlab.kinds import SCENARIO_KINDS
    from gearlab.kinds.contract import ScenarioKind

    wanted = [name for name in ScenarioKind.__dict__ if not name.startswith("_")] + ["TABLES"]
    for name, module in SCENARIO_KINDS.items():
        assert isinstance(module, ScenarioKind), name
        for attr in wanted:
            if callable(getattr(ScenarioKind, attr, None)):
                want = list(inspect.signature(getattr(ScenarioKind, attr)).parameters)[1:]  # without self
                assert len(inspect.signature(getattr(module, attr)).parameters) == len(want), (name, attr)
    lacking = types.ModuleType("lacking")
    lacking.TABLES, lacking.build = {}, lambda scenario: None
    assert not isinstance(lacking, ScenarioKind)  # the check sees a missing function


# A development round (an outside user's round of recordings, an issue's n-th round of work) is the
# story of how a figure was found: it belongs to the commit messages, not to the code or the docs
# (issue 38). The gap diagnosis's own greedy rounds ('round 1', 'a second round of every candidate')
# are the method, and stay.
ROUND_STORY = re.compile(
    r"outside (?:box|round|user)\b|\bround \d\d+\b|\b(?:tenth|eleventh|twelfth|\w+teenth|\d+(?:st|nd|rd|th)) round\b",
    re.I,
)


def test_no_code_comment_or_doc_points_into_a_development_round():
    root = PACKAGE.parent
    files = [*PACKAGE.rglob("*.py"), *(root / "plugins").rglob("*.py"), *(root / "docs").glob("*.md")]
    hits = [
        f"{path.relative_to(root)}:{i}: {line.strip()}"
        for path in sorted(files)
        for i, line in enumerate(path.read_text().splitlines(), 1)
        if ROUND_STORY.search(line) or (path.suffix == ".md" and line.startswith("#") and " round" in line.lower())
    ]
    assert not hits, "a development round named (say what was found, at HEAD):\n" + "\n".join(hits)
    assert ROUND_STORY.search("Box S of outside round 12") and ROUND_STORY.search("Issue 19, sixteenth round")
    assert not ROUND_STORY.search("the first round's effect") and not ROUND_STORY.search("gap: round 1, fitting")


def calls_of(names: set[str]) -> dict[str, list[str]]:
    """{module or plugin file: ['line: name', ...]} of every call of a function or method named in
    *names*, in gearlab and the built-in plugins."""
    root = PACKAGE.parent
    found: dict[str, list[str]] = {}
    for path in sorted([*PACKAGE.rglob("*.py"), *(root / "plugins").rglob("*.py")]):
        for line, name in calls_in(path):
            if name in names:
                found.setdefault(str(path.relative_to(root)), []).append(f"{line}: {name}")
    return found


@functools.cache
def calls_in(path: Path) -> tuple[tuple[int, str | None], ...]:
    """(line, name) of every call in *path*, in ast.walk's order: parsed and walked once for the four
    calls_of of this file (each walked every module of the package and the plugins: 5 s of a one-core
    cProfile of the suite)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call):
            f = node.func
            found.append(
                (node.lineno, f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else None)
            )
    return tuple(found)


def test_one_realisation_of_a_simulated_signal():
    # the builder, the gap diagnosis, the gap benchmark and a simulated record all realise their rows
    # through gearlab.data.realise.realise (signal effects, then the dataset's noise); nothing else
    # applies a chain's signal effects or adds a noise (the chain's own loop and the sensor_noise
    # effect aside)
    found = calls_of({"apply_signal", "add_noise"})
    allowed = {"gearlab/data/realise.py", "gearlab/effects.py", "plugins/effects/sensor_noise.py"}
    assert set(found) <= allowed, {f: c for f, c in found.items() if f not in allowed}
    assert "gearlab/data/realise.py" in found
    users = set(calls_of({"realise"}))
    callers = ("data/builder.py", "data/simulated.py", "gap/scoring.py", "kinds/gap_benchmark/trials.py")
    assert {f"gearlab/{f}" for f in callers} <= users


def test_one_way_to_declare_a_setting():
    # a setting is a gearlab.settings.Setting, made by settings.setting as a settings dataclass's
    # field: a scenario table's key, a plugin's parameter (its params dataclass), a gearbox
    # description's key; a scenario table's Key is made from the dataclass (scenario.keys_of), never
    # written by hand, and no other spelling (the positional Param records of before) is left
    made = calls_of({"Key", "Setting"})
    assert {f: len(c) for f, c in made.items()} == {"gearlab/scenario.py": 1, "gearlab/settings.py": 1}, made
    root = PACKAGE.parent
    sources = [*PACKAGE.rglob("*.py"), *(root / "plugins").rglob("*.py"), *(root / "examples").rglob("*.py")]
    spelt = [str(p.relative_to(root)) for p in sources if re.search(r"\bParam\(", p.read_text())]
    assert not spelt, f"Param( in {spelt}: declare a plugin's parameters with gearlab.api.setting"


def test_benchmarks_holds_only_what_the_readme_names():
    root = PACKAGE.parent
    readme = (root / "README.md").read_text()
    unnamed = [p.name for p in sorted((root / "benchmarks").glob("*.py")) if f"benchmarks/{p.name}" not in readme]
    assert not unnamed, f"benchmarks/ files the README does not name (a research script leaves the tree): {unnamed}"


DOCS_LINES = 4000  # docs/ in all: each page answers a user's or a contributor's question (issue 38)


def test_the_docs_stay_within_their_line_budget():
    pages = sorted((PACKAGE.parent / "docs").glob("*.md"))
    lines = {p.name: len(p.read_text().splitlines()) for p in pages}
    assert pages and sum(lines.values()) <= DOCS_LINES, (
        f"docs/ is {sum(lines.values())} lines, over {DOCS_LINES}: say it in fewer "
        + str(sorted(lines.items(), key=lambda kv: -kv[1])[:5])
    )


def test_one_false_alarm_rate_and_one_threshold_rule_per_kind():
    # a kind's scenario sets the false-alarm rate and the threshold rule in one table each: a
    # detection scenario's [detection] (its [protocol] refuses them, naming where they moved), a
    # transfer scenario's [protocol] (issue 38 item 3: three false_alarm knobs and two threshold keys
    # in one scenario before)
    from gearlab.kinds import SCENARIO_KINDS

    for name, kind in SCENARIO_KINDS.items():
        for key in ("false_alarm", "threshold"):
            tables = [t for t, table in kind.TABLES.items() if key in table.keys]
            assert len(tables) <= 1, f"kind {name}: '{key}' in {tables}"
    assert "threshold" in (SCENARIO_KINDS["detection"].TABLES["protocol"].moved or {})


# build() fields still holding a scenario table as a plain dict, to be typed (issue 38 item 4): the list only
# shrinks (the gap benchmark's [search] settings were the last, typed since)
UNTYPED_SPEC_FIELDS: set[tuple[str, str]] = set()


def _plain_table(value) -> bool:
    """A dict holding plain values somewhere (a table as read), not only typed specs."""
    import dataclasses

    if not isinstance(value, dict):
        return False
    return any(_plain_table(v) if isinstance(v, dict) else not dataclasses.is_dataclass(v) for v in value.values())


def test_every_kinds_build_returns_typed_specs():
    # each shipped scenario's build() is a settings dataclass (the dataset kind: a list of them) whose
    # fields are typed: no table passed on as the dict it was read as
    import dataclasses

    from test_scenarios import SCENARIOS, skip_without_its_records

    from gearlab.engine import load_scenario
    from gearlab.kinds import SCENARIO_KINDS

    untyped, seen = set(), set()
    for path in SCENARIOS:
        try:
            skip_without_its_records(path)
        except pytest.skip.Exception:
            continue
        scenario = load_scenario(path)
        spec = SCENARIO_KINDS[scenario.kind].build(scenario)
        seen.add(scenario.kind)
        for item in spec if isinstance(spec, list) else [spec]:
            assert dataclasses.is_dataclass(item), f"{path.name}: build() returned {type(item).__name__}"
            fields = dataclasses.fields(item)
            untyped |= {(scenario.kind, f.name) for f in fields if _plain_table(getattr(item, f.name))}
    assert untyped <= UNTYPED_SPEC_FIELDS, f"build() passes tables on untyped: {sorted(untyped - UNTYPED_SPEC_FIELDS)}"
    assert not {(k, f) for k, f in UNTYPED_SPEC_FIELDS if k in seen} - untyped, "typed now: take off the list"
    assert seen >= set(SCENARIO_KINDS) - {"detection"}  # detection's only shipped scenario reads the PHM records
    # the check sees a plain table, and lets a table of specs (the noise study's datasets) pass
    typed = dataclasses.make_dataclass("Typed", [])()
    assert _plain_table({"a": {"b": 1}}) and not _plain_table({"noisy": {"gaussian": typed}})


def test_one_measured_file_reader():
    # a measured file's format is parsed in gearlab/data/readers/ alone, one reader a format, reached through
    # gearlab.data.recordings (issue 38 item 3: data/importers.py with readers/ and data/textzip.py were two paths)
    parsers = {"loadmat", "whosmat", "loadtxt", "genfromtxt", "ZipFile", "read_columns"}
    found = {f: {c.split(": ")[1] for c in calls} for f, calls in calls_of(parsers).items()}
    outside = {f: names for f, names in found.items() if not f.startswith("gearlab/data/readers/")}
    assert outside == {"gearlab/kinds/stiffness.py": {"loadtxt"}}, outside  # stiffness: its run's own CSVs
    assert {"gearlab/data/readers/text.py", "gearlab/data/readers/matlab.py"} <= set(found)
    h5 = [m for m, p in MODULES.items() if re.search(r"^\s*import h5py", p.read_text(), re.M)]
    assert all(m.startswith("gearlab.data.readers.") for m in h5) and h5, h5


def test_the_cli_and_the_tui_are_built_on_the_notebook_api():
    """Issue 38 item 5: `gearlab` and its TUI read scenarios, run them, resume them and read their
    runs through gearlab.notebook (the API of docs/api.md), not around it through the engine."""
    fronts = [m for m in MODULES if m.startswith(("gearlab.cli.", "gearlab.tui")) or m == "gearlab.cli"]
    around = [f"{m}:{line} imports {t}" for m in fronts for t, line, _ in graph()[m] if t == "gearlab.engine"]
    assert not around, "\n".join(around)
    used = {t for m in fronts for t, _, _ in graph()[m]}
    assert "gearlab.notebook" in used
