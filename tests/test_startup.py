"""Start-up: checking a scenario, `--help` and the TUI's first screen load no torch, no numba
(the simulator's kernels), no scipy.stats or scipy.ndimage, sklearn or matplotlib (issue 42; docs/architecture.md:
the modules that need them import them inside the functions that train, simulate or draw), and no
pydantic (Typer's coercion of a path, text or flag: gearlab.cliconv); the TUI's first screen loads
no plotext, webbrowser or run comparison and fills no plugin table on its hidden tab.

Each case runs in a fresh interpreter and reads its sys.modules afterwards, so what the rest of
the suite imported does not hide an import."""

import json
import subprocess
import sys

import pytest
from conftest import ROOT

HEAVY = ("torch", "numba", "scipy.stats", "scipy.ndimage", "sklearn", "matplotlib", "pydantic")

CASES = {
    # the README's command: `gearlab validate scenarios/quick.toml`
    "validate": """
from gearlab.cli import main
sys.argv = ["gearlab", "validate", "scenarios/quick.toml"]
try:
    main()
except SystemExit as e:
    assert not e.code, e.code
""",
    # every shipped scenario checked and described, as the TUI's tree does (validate reads measured files too)
    "every scenario": """
from pathlib import Path
from gearlab.engine import load_scenario
from gearlab.kinds import SCENARIO_KINDS
# the PHM 2009 scenarios read ../shared/data/phm09 at load time: left out where a checkout has none
no_rig = not Path("../shared/data/phm09").is_dir()
for path in sorted(Path("scenarios").glob("*.toml")) + sorted(Path("tests/tui_scenarios").glob("*.toml")):
    if not (no_rig and path.name.startswith("phm09")):
        SCENARIO_KINDS[(s := load_scenario(path)).kind].describe(s)
""",
    "help": """
from gearlab.cli import main
sys.argv = ["gearlab", "--help"]
try:
    main()
except SystemExit as e:
    assert not e.code, e.code
""",
    # the TUI's first screen: the scenario tree filled and every file validated, the plugins tab too
    "tui": """
import asyncio
from pathlib import Path
from rich.syntax import Syntax
from gearlab.tui.app import GearlabApp

drawn = []  # the scenario's TOML is drawn once per width (two: the scroll bar comes), not per layout pass
_get_syntax = Syntax._get_syntax
Syntax._get_syntax = lambda self, console, opts: drawn.append(opts.max_width) or _get_syntax(self, console, opts)

async def first_screen():
    app = GearlabApp("scenarios")
    async with app.run_test() as pilot:
        await pilot.pause()
        for _ in range(6000):  # the marks, validated after the first frame (tui.checking): 5 min at most
            if all(e.checked for e in app.entries):
                break
            await pilot.pause(0.05)
        no_rig = not Path("../shared/data/phm09").is_dir()  # the PHM 2009 scenarios' records, where present
        bad = [e.path for e in app.entries if not e.ok and not (no_rig and Path(e.path).name.startswith("phm09"))]
        assert app.entries and not bad, bad
        assert not app.query_one("#plugin-table").row_count  # filled when its tab is first shown
        later = [m for m in ("plotext", "webbrowser", "gearlab.compare", "gearlab.terminal") if m in sys.modules]
        assert not later, later  # what only a chart, a report opened in a browser or a comparison needs
        assert len(drawn) == len(set(drawn)), drawn

asyncio.run(first_screen())
""",
}


# `gearlab validate --help`, `gearlab run --help`: a command's own options are coerced too
CASES["command help"] = CASES["help"].replace('"--help"', '"validate", "--help"')


@pytest.mark.parametrize("case", list(CASES))
def test_start_up_loads_no_heavy_module(case):
    code = (
        "import sys\n"
        + CASES[case]
        + f"\nprint(__import__('json').dumps([m for m in {HEAVY!r} if m in sys.modules]))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    assert json.loads(done.stdout.strip().splitlines()[-1]) == [], f"{case} imported them"


def test_plain_values_are_coerced_as_typer_coerces_them(tmp_path):
    """gearlab.cliconv takes a path, a text or a flag's bool as it is, Typer's Pydantic adapter
    left unbuilt; each gives what Typer's own coercion gives, errors included, for every
    parameter of every command, and any other value goes to Typer's coercion."""
    typer_coercion = pytest.importorskip("typer._coercion")
    from typer.main import get_command

    from gearlab.cli import app
    from gearlab.cliconv import _PlainFirst

    group = get_command(app)
    file = tmp_path / "a.toml"
    file.write_text("")
    values = ["scenarios/quick.toml", str(file), str(tmp_path), "no/such/file", "", "-", "x y", True, False, "3"]
    seen = set()
    for name, command in [("", group), *group.commands.items()]:
        ctx = command.context_class(command)
        for param in command.get_params(ctx):  # those Typer adds (--install-completion) included
            descriptor = getattr(param, "type_descriptor", None)
            if descriptor is None:
                continue
            plain = param.get_runtime_param()
            assert isinstance(plain, _PlainFirst), (name, param.name)
            full = typer_coercion.build_runtime_param(descriptor)
            for value in values:
                got, want = _outcome(plain, value, param, ctx), _outcome(full, value, param, ctx)
                assert got == want, (name, param.name, value, got, want)
            seen.add(getattr(descriptor.annotation, "__name__", str(descriptor.annotation)))
    assert {"Path", "str", "bool", "int"} <= seen, seen  # the plain types and one that goes to Typer


def _outcome(runtime, value, param, ctx):
    try:
        result = runtime.coerce(value, param=param, ctx=ctx)
        return ("ok", type(result).__name__, result)
    except Exception as exc:  # noqa: BLE001 - the error is the outcome compared
        return ("error", type(exc).__name__, str(exc))


def test_the_torch_free_network_settings_match_the_networks():
    """gearlab.learn.config knows the networks' names and shortest revolutions without torch:
    the same as building them."""
    from gearlab.errors import GearlabInputError
    from gearlab.learn.config import NETWORK_NAMES, check_length, shortest_length
    from gearlab.learn.networks import NETWORKS, build_network

    assert NETWORK_NAMES == tuple(NETWORKS)
    for name in NETWORK_NAMES:
        shortest = shortest_length(name)
        build_network(name, 2, length=shortest)
        check_length(name, shortest)
        if shortest > 1:
            with pytest.raises(GearlabInputError) as built:
                build_network(name, 2, length=shortest - 1)
            with pytest.raises(GearlabInputError) as checked:
                check_length(name, shortest - 1)
            assert str(checked.value) == str(built.value)


def test_validate_loads_only_its_own_kind():
    """The kinds' modules load on first use (0.2 s of validate without bytecode caches, issue 42):
    checking the transfer scenario quick.toml imports the transfer kind and no other."""
    code = (
        CASES["validate"]
        + "\nprint(__import__('json').dumps(sorted(m for m in sys.modules if m.startswith('gearlab.kinds.'))))\n"
    )
    done = subprocess.run([sys.executable, "-c", "import sys\n" + code], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    kinds = {
        "dataset",
        "detection",
        "gap",
        "gap_benchmark",
        "noise_study",
        "stiffness",
        "transfer",
        "transfer_benchmark",
    }
    loaded = {m.split(".")[2] for m in json.loads(done.stdout.strip().splitlines()[-1])}
    assert loaded & kinds == {"transfer"}, loaded
