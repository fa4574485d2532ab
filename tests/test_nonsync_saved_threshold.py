"""`gearlab score` reads a run's saved non-synchronous history (signals.nonsync.NonSyncHistory.state) against today's
threshold: remade from the saved envelope blocks of its takes, one take or several, whatever threshold an older
gearlab saved beside them; where the blocks cannot give it, the saved one is kept and every score row says so."""

from __future__ import annotations

import json
from statistics import NormalDist

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import signals, text, write_zip

from gearlab.signals import nonsync as NS


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, module_cache):
    """The tiny detection run (tests/detection_scenario: two 40-turn history takes) and a healthy 40-turn take."""
    folder = tmp_path_factory.mktemp("saved")
    run = shared_run(scenario(folder, methods=("matched_filter",)), folder / "runs")
    vib, tacho = signals(revolutions=40, seed=21, phase=0.3)
    return run, write_zip(folder / "take.zip", text(vib, tacho))


def _state(run) -> tuple:
    meta = json.loads((run / "localisation.json").read_text())
    (cond,) = meta["conditions"].values()
    path = run / "scoring" / cond["state"]
    with np.load(path) as f:
        return path, {k: f[k] for k in f.files}, cond["nonsync_threshold"]


def _save(path, arrays: dict) -> None:
    with path.open("wb") as f:
        np.savez(f, **arrays)


def _nonsync(cli, run, take) -> list[dict]:
    code, out, err = cli("score", run, take, "--json")
    assert code == 0, err
    return json.loads(out)


def test_a_several_take_history_saved_with_an_older_threshold_is_scored_with_today_s(cli, tiny, quiet):
    run, take = tiny
    path, arrays, today = _state(run)
    assert len(arrays["nonsync_sizes"]) == 2 and today is not None, arrays["nonsync_sizes"]
    old = _older(run, arrays)
    assert old < today - 0.3, (old, today)
    _save(path, {**arrays, "nonsync_threshold": np.array(old)})
    rows = _nonsync(cli, run, take)
    got = {r["nonsync"]["threshold"] for r in rows}
    assert len(got) == 1 and got.pop() == pytest.approx(today, rel=1e-9), (rows[0]["nonsync"], today)
    assert "older gearlab" not in rows[0]["evidence"], rows[0]["evidence"]


def test_a_saved_threshold_the_saved_blocks_cannot_remake_is_kept_and_said(cli, tiny, quiet):
    # blocks not told apart by take: the several takes' rule (each take left out against the others) cannot be read
    # from them; the saved threshold is kept, and said to be an older gearlab's
    run, take = tiny
    path, arrays, today = _state(run)
    old = _older(run, arrays)
    pooled = {k: v for k, v in arrays.items() if k != "nonsync_sizes"} | {"nonsync_threshold": np.array(old)}
    _save(path, pooled)
    rows = _nonsync(cli, run, take)
    got = {r["nonsync"]["threshold"] for r in rows}
    assert len(got) == 1 and got.pop() == pytest.approx(old, rel=1e-9), (rows[0]["nonsync"], old)
    said = {r["evidence"] for r in rows}
    assert all("older gearlab" in s and "running the detection again refreshes it" in s for s in said), said


def _older(run, arrays: dict) -> float:
    """The Gaussian quantile at the false alarm shared over the bins searched: where an older gearlab's threshold
    started from (its z in sds of the take's mean alone)."""
    from gearlab.gearbox import order_table
    from gearlab.gearbox.simulation import gearbox_of

    table = order_table(gearbox_of(json.loads((run / "localisation.json").read_text())["preset"]))
    bins = int((~NS.synchronous_bins(table, arrays["nonsync_blocks"].shape[1])).sum())
    return NormalDist().inv_cdf(1.0 - NS.FALSE_ALARM / bins)
