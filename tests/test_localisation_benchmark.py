"""benchmarks/localisation.py goes on past a trial gearlab refuses (a random train's history too short for the
which-gear check) and says which trial and why, instead of stopping the whole run; --history-loads reaches every
trial."""

import importlib.util
from pathlib import Path

import pytest

from gearlab.errors import GearlabInputError

PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "localisation.py"


def _benchmark():
    spec = importlib.util.spec_from_file_location("localisation_benchmark", PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_refused_trial_is_counted_and_the_run_goes_on(monkeypatch, capsys):
    B = _benchmark()

    def refuse(args, made):
        if args[2] == 1:
            raise GearlabInputError("history: 3 revolutions, the which-gear check needs 8")
        return []

    monkeypatch.setattr(B, "_trial", refuse)
    assert B.trial(("random", 7, 1, "simulated", [], None)) == [
        {"refused": "history: 3 revolutions, the which-gear check needs 8", "trial": 1}
    ]
    B.main(["--trials", "3", "--seed", "7", "--box", "random"])
    out = capsys.readouterr().out
    assert "trial 1 refused by gearlab: history: 3 revolutions, the which-gear check needs 8" in out
    assert "trial 0 refused" not in out and "trial 2 refused" not in out


def test_the_history_s_loads_reach_every_trial_and_a_single_load_is_refused(monkeypatch, capsys):
    B = _benchmark()
    seen = []
    monkeypatch.setattr(B, "_trial", lambda args, made: seen.append(args[5]) or [])
    B.main(["--trials", "2", "--seed", "7", "--box", "random", "--history-loads", "1,2"])
    assert seen == [(1.0, 2.0), (1.0, 2.0)]
    assert "history at 1, 2 times the drawn load" in capsys.readouterr().out
    with pytest.raises(SystemExit) as refused:
        B.main(["--trials", "1", "--box", "random", "--history-loads", "1"])
    assert refused.value.code == 2 and "expected two or more positive multiples" in capsys.readouterr().err
