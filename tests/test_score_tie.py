"""`gearlab score`'s per-record decision at a tie (issue 39): a user's record of 2 units, 1 called, read `healthy`
while docs/your_gearbox.md spoke of 'most called' and 'none called' only. The rule: over half its units called, a
fault; half (a tie) or fewer, healthy; the printout gives the count of how many ('called' 2/4). The thresholds of the
classical rows are set here on the scored record's own scores so that exactly half, then one more, are over."""

import json
import shutil

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import record

from gearlab.kinds import detection_scoring
from gearlab.kinds.detection_which_gear import is_other


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    """The tiny detection run and the record to score, made once for the module: both tests score the same
    record against the same run, with other thresholds (_over)."""
    folder = tmp_path_factory.mktemp("tie")
    out = shared_run(scenario(folder, methods=("source_only",)), folder / "runs")
    # 41 turns: 40 units of a revolution, 8 of 5, 4 of 10, each count even (a tie can be)
    return out, record(folder / "new.zip", revolutions=41, chip=0.0, seed=11, phase=0.3)


@pytest.fixture
def finished(made, request):
    """The module's run as this test's own (a copy beside it: `gearlab score` adds its scoring/ history to the
    run it scores), and the record to score."""
    out, new = made
    return shutil.copytree(out, out.with_name(f"{out.name}-{request.node.name[:40]}")), new


def _over(monkeypatch, over_half: int):
    """Every classical row's thresholds put under the scored record's scores so that half its units, plus
    *over_half*, are over them (its scores all distinct)."""
    real = detection_scoring.classical_record

    def made(*args, **kwargs):
        out = real(*args, **kwargs)
        for units in out["test_scores"].values():
            for u, s in units.items():
                s = np.sort(np.asarray(s, dtype=np.float64))
                k = s.size // 2 + over_half  # the k largest over the threshold
                out["thresholds"][u] = float((s[-k - 1] + s[-k]) / 2)
        return out

    monkeypatch.setattr(detection_scoring, "classical_record", made)


def _rows(cli, out, new):
    code, stdout, err = cli("score", out, new, "--json")
    assert code == 0, err
    # the classical rows, the record's change on no other gear (its call: the watched gear's, or none)
    rows = [r for r in json.loads(stdout) if r["method"] in ("fm4", "na4") and not is_other(r["call"])]
    code, printed, err = cli("score", out, new)
    assert code == 0, err
    return rows, printed


def test_half_the_units_called_is_healthy_and_the_printout_says_how_many(cli, finished, monkeypatch):
    out, new = finished
    _over(monkeypatch, 0)
    rows, printed = _rows(cli, out, new)
    units = {r["unit"]: r["units"] for r in rows}
    assert units == {"revolution": 40, "record5": 8, "record10": 4}, units
    for r in rows:
        assert (r["called"] * 2, r["decision"]) == (r["units"], "healthy"), r
    # the table gives called / units beside the decision: 2 of 4, 'healthy'
    assert any(line.split()[1:] == ["record10", "2/4", line.split()[3], "healthy"] for line in _cells(printed)), printed


def test_one_more_than_half_called_is_a_fault(cli, finished, monkeypatch):
    out, new = finished
    _over(monkeypatch, 1)
    rows, printed = _rows(cli, out, new)
    for r in rows:
        assert (r["called"], r["decision"]) == (r["units"] // 2 + 1, "fault"), r
    assert any(line.split()[1:3] == ["record10", "3/4"] and line.split()[-1] == "fault" for line in _cells(printed))


def _cells(printed: str) -> list[str]:
    """The score table's rows, their box-drawing bars dropped."""
    return [" ".join(line.replace("│", " ").split()) for line in printed.splitlines() if "│" in line]


def test_the_guide_states_the_rule_these_tests_hold():
    from pathlib import Path

    guide = " ".join((Path(__file__).parents[1] / "docs" / "your_gearbox.md").read_text().split())
    said = "decision (over half its units called: `fault`, or `other damage: <gear>` on a gear not watched, "
    assert said in guide and "; half or fewer, a tie such as `1/2` too: `healthy`" in guide.split(said)[1][:300]
