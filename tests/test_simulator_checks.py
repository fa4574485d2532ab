"""One check of what a simulation is asked for (gearlab.notebook.simulator, simulate_command): from
Python its errors name the keywords, from the command line the options, and the CLI keeps no check
of its own."""

import pytest

import gearlab
import gearlab.cli
from gearlab.errors import GearlabInputError


@pytest.mark.parametrize(
    "call, says",
    [
        (lambda: gearlab.simulate_signals(), "give model NAME (and preset) or gearbox DESCRIPTION"),
        (lambda: gearlab.simulate_signals("three_stage"), "model three_stage: no built-in preset; give gearbox"),
        (lambda: gearlab.simulate_signals(gearbox="phm09", preset="x"), "preset x: the gearbox description"),
        (lambda: gearlab.simulate_signals(gearbox="no/such.toml"), "gearbox no/such.toml: cannot read"),
    ],
)
def test_from_python_the_errors_name_the_keywords(call, says):
    with pytest.raises(GearlabInputError) as caught:
        call()
    assert says in str(caught.value) and "--" not in str(caught.value), caught.value


@pytest.mark.parametrize(
    "args, says",
    [
        (["simulate", "--out", "x.npz"], "give --model NAME (and --preset) or --gearbox DESCRIPTION"),
        (["modes"], "give --model NAME (and --preset) or --gearbox DESCRIPTION"),
        (["modes", "--model", "three_stage"], "--model three_stage: no built-in preset; give --gearbox DESCRIPTION"),
        (["modes", "--gearbox", "phm09", "--preset", "x"], "--preset x: the --gearbox description"),
        (["simulate", "--out", "x.npz", "--gearbox", "phm09", "--preset", "x"], "--preset x: the --gearbox"),
    ],
)
def test_from_the_command_line_the_same_checks_name_the_options(cli, tmp_path, monkeypatch, args, says):
    monkeypatch.chdir(tmp_path)
    code, _, err = cli(*args)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and says in lines[0], err


def test_the_cli_keeps_no_simulator_check_of_its_own():
    import importlib
    import pkgutil

    modules = [importlib.import_module(f"gearlab.cli.{m.name}") for m in pkgutil.iter_modules(gearlab.cli.__path__)]
    assert "gearlab.cli.tools" in {m.__name__ for m in modules}  # modes and simulate
    assert not [m.__name__ for m in [gearlab.cli, *modules] if hasattr(m, "_simulator")]
