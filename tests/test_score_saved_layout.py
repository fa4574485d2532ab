"""`gearlab score` of a detection run whose saved arrays an older gearlab wrote on another layout than today's: its
history revolutions and the localisation's grid at other points a revolution (an older signals.POINTS), its
localisation layout of other orders (an older layout rule), its non-synchronous blocks of other bins (an older BLOCK).
A grid of other points is read as saved: the take put on the history revolutions' grid (the methods' models and
references were made there), the localisation's saved grid put on today's (its powers are per order); both exact at
every order read (signals.regrid). What cannot be re-binned is said in each score row, in one line, with what differs
and that running the detection again refreshes the history; never a traceback, and every method's row scored."""

from __future__ import annotations

import json

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import signals, text, write_zip

from gearlab.kinds.detection_saved import saved_histories
from gearlab.kinds.detection_which_gear import UNDETERMINED
from gearlab.signals import POINTS
from gearlab.signals import envelope_sync as E
from gearlab.signals import nonsync as NS
from gearlab.signals.regrid import at_points

OLDER_POINTS = 2048  # an older gearlab's records, half today's signals.POINTS
OLDER_ENVELOPE = 128  # ... and its envelope's (signals.envelope_sync.POINTS 256)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, module_cache):
    """The tiny detection run (two 40-turn history takes), its learned method seeing 2048 points a revolution (as
    one run by an older gearlab whose records held 2048 saw them: a network's input is the width it was trained at),
    a healthy and a chipped 40-turn take."""
    folder = tmp_path_factory.mktemp("layout")
    made = scenario(folder, methods=("matched_filter",), detection=f"points = {OLDER_POINTS}")
    run = shared_run(made, folder / "runs")
    takes = []
    for name, chip, seed in (("healthy", 0.0, 21), ("chipped", 4.0, 22)):
        vib, tacho = signals(revolutions=40, seed=seed, chip=chip, phase=0.3)
        takes.append(write_zip(folder / f"{name}.zip", text(vib, tacho)))
    return run, takes


@pytest.fixture
def saved(tiny):
    """The run's scoring folder as made, put back after the test edits it."""
    run, _ = tiny
    kept = {p: p.read_bytes() for p in (run / "scoring").glob("*.npz")}
    yield run
    for p, data in kept.items():
        p.write_bytes(data)


def _rows(cli, run, takes) -> list[dict]:
    code, out, err = cli("score", run, *takes, "--json")
    assert code == 0, err
    return json.loads(out)


@pytest.fixture(scope="module")
def today(tiny):
    """Each take's rows as the run scores them unedited: (file, method, unit) -> row."""
    from gearlab.kinds.detection_scoring import score
    from gearlab.runs import RunDir

    run, takes = tiny
    return {(r["file"], r["method"], r["unit"]): r for r in score(RunDir(run), [str(t) for t in takes])}


def _load(path) -> dict:
    with np.load(path) as f:
        return {k: f[k] for k in f.files}


def _save(path, arrays: dict) -> None:
    with path.open("wb") as f:
        np.savez(f, **arrays)


def _localisation(run):
    (cond,) = json.loads((run / "localisation.json").read_text())["conditions"].values()
    return run / "scoring" / cond["state"]


def _table(run):
    from gearlab.gearbox import order_table
    from gearlab.gearbox.simulation import gearbox_of

    return order_table(gearbox_of(json.loads((run / "localisation.json").read_text())["preset"]))


def _same_scores(rows: list[dict], today: dict, fault: str = "fault") -> None:
    """Every method's row of every take scored, as the unedited run scores it (its units called alike; a
    watched-gear fault decided *fault*)."""
    assert {(r["file"], r["method"], r["unit"]) for r in rows} == set(today)
    for r in rows:
        was = today[(r["file"], r["method"], r["unit"])]
        decision = fault if was["decision"] == "fault" else was["decision"]
        assert r["decision"] == decision and r["called"] == was["called"], (r, was)
    assert {r["decision"] for r in today.values()} >= {"healthy", "fault"}, today  # both takes' decisions seen


def test_a_history_saved_at_other_points_a_revolution_is_read_on_its_grid(cli, saved, tiny, today, quiet):
    # an older gearlab cut records to 2048 points a revolution: its history revolutions, their alignment reference
    # and the localisation's layouts (averages 2048, envelope 128) on that grid
    run, takes = tiny
    cond = run / "scoring" / "condition0.npz"
    arrays = _load(cond)
    history = at_points(arrays["history"], OLDER_POINTS).astype(np.float32)
    reference = at_points(arrays["reference"][None, :], OLDER_POINTS)[0]
    _save(cond, {**arrays, "history": history, "reference": reference})
    state = _load(_localisation(run))
    bands = [f"envelope{i}_" for i in range(1, len(state["envelope_bands"]))]  # the envelope's other bands too
    for prefix, points in (("", OLDER_POINTS), ("envelope_", OLDER_ENVELOPE), *((b, OLDER_ENVELOPE) for b in bands)):
        args = json.loads(str(state[f"{prefix}args"])) | {"points": points}
        state[f"{prefix}args"] = np.array(json.dumps(args))
        if state[f"{prefix}reference"].size:
            state[f"{prefix}reference"] = at_points(state[f"{prefix}reference"][None, :], points)[0]
    _save(_localisation(run), state)
    hist, _, why, unread = saved_histories(_load(_localisation(run)), _table(run))
    assert (hist.layout.points, hist.envelope.layout.points, why, unread) == (POINTS, E.POINTS, "", "")
    assert {h.layout.points for h in hist.envelope.histories[:]} == {E.POINTS}

    rows = _rows(cli, run, takes)
    _same_scores(rows, today)
    for r in rows:
        was = today[(r["file"], r["method"], r["unit"])]
        # the learned method's within 5e-4; FM4's and NA4's, moments of 2048 samples a revolution rather than 4096,
        # and their thresholds within 0.4 %: as a run made at 2048 points reads them
        assert r["median_score"] == pytest.approx(was["median_score"], rel=1e-2), (r, was)
        assert r["threshold"] == pytest.approx(was["threshold"], rel=1e-2), (r, was)
        assert (r["localised"], r["call"], r["evidence"]) == (was["localised"], was["call"], was["evidence"])


def test_a_localisation_history_of_other_orders_is_said_in_every_row(cli, saved, tiny, today, quiet):
    # an older layout rule kept 5 fewer orders: which orders they were is not saved, nothing to re-bin
    run, takes = tiny
    state = _load(_localisation(run))
    orders = state["power"].size
    for k in ("power", "line", "between", "unit_noise", "excess"):
        state[k] = state[k][:-5]
    _save(_localisation(run), state)

    rows = _rows(cli, run, takes)
    why = (
        f"the run's saved localisation history is not read (a saved localisation history holds {orders - 5} orders, "
        f"the gearbox's layout {orders}: saved for another gearbox description, or by a gearlab of another layout "
        "rule); running the detection again refreshes the history"
    )
    _same_scores(rows, today, fault=f"{UNDETERMINED}: {why}")  # a flag on it a fault of no gear named
    assert all(r["evidence"] == f"not read: {why}" and r["localised"] is None for r in rows), rows


def test_an_envelope_history_of_other_orders_leaves_the_averages_call_and_says_so(cli, saved, tiny, today, quiet):
    run, takes = tiny
    state = _load(_localisation(run))
    orders = state["envelope_power"].size
    for k in ("power", "line", "between", "unit_noise", "excess"):
        state[f"envelope_{k}"] = state[f"envelope_{k}"][:-3]
    _save(_localisation(run), state)

    rows = _rows(cli, run, takes)
    _same_scores(rows, today)
    said = (
        f"; the run's saved envelope history is not read (a saved localisation history holds {orders - 3} orders, "
        f"the gearbox's layout {orders}: saved for another gearbox description, or by a gearlab of another layout "
        "rule); running the detection again refreshes the history"
    )
    for r in rows:
        was = today[(r["file"], r["method"], r["unit"])]
        assert r["evidence"] == was["evidence"] + said and r["localised"] == was["localised"], (r, was)


def test_non_synchronous_blocks_of_other_bins_are_said_in_every_row(cli, saved, tiny, today, quiet):
    # an older BLOCK of 8 revolutions: bins of 1/8 order, every other one of today's
    run, takes = tiny
    state = _load(_localisation(run))
    state["nonsync_blocks"] = state["nonsync_blocks"][:, ::2]
    bins = state["nonsync_blocks"].shape[1]
    _save(_localisation(run), state)

    rows = _rows(cli, run, takes)
    _same_scores(rows, today)
    said = (
        f"non-synchronous check not read: its saved history holds {bins} bins a block, this gearlab reads {NS.BINS} "
        f"from {NS.LOW:g} to {NS.HIGH:g} input orders in blocks of {NS.BLOCK} revolutions; running the detection "
        "again refreshes the history"
    )
    for r in rows:
        assert r["nonsync"] == {"note": said, "changed": False} and r["evidence"].endswith(said), r["evidence"]


def test_a_band_limited_record_put_on_another_grid_is_the_one_sampled_there():
    # the orders read below half the coarser grid: every sample the same to rounding, up or down
    rng = np.random.default_rng(7)
    count = 12
    orders = rng.choice(np.arange(1, count * 1000), 200, replace=False) / count  # whole cycles, under 1024 orders
    amp, phase = rng.normal(size=orders.size), rng.uniform(0, 2 * np.pi, orders.size)

    def sampled(points: int) -> np.ndarray:
        theta = 2 * np.pi * np.arange(count * points) / points
        return sum(a * np.cos(o * theta + p) for a, o, p in zip(amp, orders, phase)).reshape(count, points)

    fine, coarse = sampled(4096), sampled(2048)
    scale = np.abs(fine).max()
    assert np.abs(at_points(fine, 2048) - coarse).max() < 1e-9 * scale
    assert np.abs(at_points(coarse, 4096) - fine).max() < 1e-9 * scale
    assert at_points(fine, 4096) is fine
