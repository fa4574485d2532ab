"""A take at another load than its one-load history is no localised change: a load scales the mesh's response, its
harmonics and the sidebands about them alike, at every tooth (signals.evidence.mesh_gain). The 38/103 reducer of
outside user FC (tests/test_outside_fc: its mesh harmonics modulated by both shafts, times the load), three healthy
history takes at one load, development seeds."""

from __future__ import annotations

import numpy as np
import pytest
from test_outside_fc import BOX, FS, _take

from gearlab.data import which_gear as W
from gearlab.gearbox import load_gearbox, order_table
from gearlab.inspect import InspectOptions
from gearlab.inspect_history import input_revolutions


@pytest.fixture(scope="module")
def reducer(tmp_path_factory):
    """(the box, its order table, a reader of a take made by _take's keywords, the history of its takes 1-3)."""
    folder = tmp_path_factory.mktemp("load")
    (folder / "box.toml").write_text(BOX)
    box = load_gearbox(folder / "box.toml")
    table = order_table(box)

    def take(name: str, **kw) -> W.Take:
        _, x, tacho = _take(**kw)
        np.savez(folder / f"{name}.npz", acc_ms2=x, tacho_V=tacho, fs=FS)
        revs, first, _, _, speed, rate, turns = input_revolutions(
            str(folder / f"{name}.npz"), box, InspectOptions("acc_ms2", tacho="tacho_V")
        )
        return W.Take(revs, first, speed.mean_hz, rate, turns)

    hist = W.history_of([take(f"h{k}", seed=k) for k in (1, 2, 3)], table, tacho="input", pulses=1)
    return box, table, take, hist


def _found(reducer, name: str, **kw) -> dict:
    box, table, take, hist = reducer
    return W.which_gear(take(name, **kw), hist, table, W.events(box.source))


@pytest.mark.parametrize("load", [1.5, 2.0])
def test_a_healthy_take_at_a_heavier_load_is_localised_on_no_gear(reducer, load):
    # seed 106's healthy take read the input pinion at z 3.12 (1.5 x) and 3.54 (2 x) over 2.58: the second mesh
    # sidebands by the input shaft (36, 40, 116 orders), weak in the history and so off its lines, grew with the mesh
    # and were read against the history times the take's noise level alone; 2.19 and 1.82 so
    found = _found(reducer, f"heavy{load}", seed=106, load=load)
    assert found["named"] is None, found["summary"]


@pytest.mark.parametrize(
    ("load", "gear", "kw"), [(1.5, "input pinion", {"chip": 0.07}), (1.0, "output gear", {"chip": 0.2, "wheel": True})]
)
def test_a_weak_chip_is_still_named_at_the_history_s_load_and_a_heavier_one(reducer, load, gear, kw):
    found = _found(reducer, f"chip{load}{gear}", seed=101, load=load, **kw)
    assert found["named"] is not None and found["named"].startswith(gear), found["summary"]
