"""`gearlab score` of a take the run itself scored gives the scores the run gave it.

Two conditions at one speed (two loads grouped by hand); a light-load take whose level lies nearer the heavy
load's history than its own. The run scored it in 'light', as the scenario said; score put it in the condition
of nearest level, 'heavy', other references and thresholds: on synthetic rig records (DQ's ten conditions at
35 Hz, issue 39) likelihood_ratio's record10 median score less threshold -3.90 in the run, -6.23 from score.
A take the run read (its content, whatever its name now) is scored in the run's condition for it, its learned
methods on one torch thread as the run's (on several, a detector's float32 sums came out 2e-8 to 4e-6 off).
"""

import json
import shutil

import numpy as np
import pytest
from detection_scenario import run_in_module, scenario
from textrecords import scaled_record

import gearlab

LOUD = 1.6  # the heavy load's level over the light one's
ODD = 1.35  # a light-load take's: nearer the heavy load's history level than its own (log 0.30 against 0.17)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("own")
    (folder / "data").mkdir()
    files = (
        ("l1", "history", 1, 1.0, "light"),
        ("l2", "history", 2, 1.0, "light"),
        ("l3", "test", 3, ODD, "light"),
        ("h1", "history", 4, LOUD, "heavy"),
        ("h2", "history", 5, LOUD, "heavy"),
        ("h3", "test", 6, LOUD, "heavy"),
    )
    for name, _, seed, scale, _ in files:
        scaled_record(folder / "data" / f"{name}.zip", seed, scale)
    path = scenario(
        folder, files=[(n, r, "healthy", 0.0) for n, r, *_ in files], methods=("matched_filter", "likelihood_ratio")
    )
    text_ = path.read_text()
    for name, *_, cond in files:  # each file's condition, by hand
        text_ = text_.replace(f'"../data/{name}.zip",', f'"../data/{name}.zip", condition = "{cond}",')
    path.write_text(text_)
    return folder, run_in_module(path, folder / "runs", figures=False)


def _run_scores(out) -> dict:
    """{(file name, method, unit): (condition, the run's scores of the take's units)}."""
    found = {}
    for line in (out / "results.jsonl").read_text().splitlines():
        r = json.loads(line)
        if r.get("seed") is None and r.get("fold") is None and "test_scores" in r:
            for path, units in r["test_scores"].items():
                for unit, s in units.items():
                    found[(path.rsplit("/", 1)[-1], r["method"], unit)] = (r["condition"], np.asarray(s))
    return found


@pytest.fixture
def threads():
    """torch on several threads, as a fresh `gearlab score` process is (the in-process run left it on one)."""
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(4)
    yield
    torch.set_num_threads(before)


def test_a_take_of_the_run_is_scored_as_the_run_scored_it(cli, made, threads):
    folder, out = made
    ran = _run_scores(out)
    assert {"matched_filter", "likelihood_ratio", "fm4"} <= {m for _, m, _ in ran}
    renamed = folder / "l3_again.zip"  # its content, not its name, makes it the run's take
    shutil.copy(folder / "data" / "l3.zip", renamed)
    for file in (folder / "data" / "l3.zip", renamed):
        rows = gearlab.score_recordings(out, [file, folder / "data" / "l1.zip"])  # l1: a history take
        assert {r["condition"] for r in rows} == {"light"}, {r["condition"] for r in rows}
        said = {r["file"].rsplit("/", 1)[-1]: r["condition_by"] for r in rows}
        assert said[file.name] == "the run's own take: its condition in the run", said
        assert said["l1.zip"].startswith("the run's own history take: its condition in the run; in the references")
        for r in (r for r in rows if r["file"] == str(file)):
            cond, s = ran[("l3.zip", r["method"], r["unit"])]
            assert cond == "light"
            # bit for bit, a detector's float32 sums too (torch on one thread as the run's: one_thread)
            assert np.array_equal(r["scores"], s), (r["method"], r["unit"], np.abs(np.subtract(r["scores"], s)).max())
    code, printed, err = cli("score", out, folder / "data" / "l3.zip")
    assert code == 0, err
    assert "condition light (the run's own take: its condition in the run)" in printed, printed
    # a condition asked is kept, the take then scored against that condition's history
    code, stdout, err = cli("score", out, folder / "data" / "l3.zip", "--condition", "heavy", "--json")
    assert code == 0, err
    assert {r["condition"] for r in json.loads(stdout)} == {"heavy"}
