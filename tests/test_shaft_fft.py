"""The shaft averages' transforms (signals.shaft.shaft_averages: a record's spectrum and its reading 4 x
denser, for each shaft) are taken once per piece of record: a history's left-out check reads each record
in the blocks that are already its units (localise.history), not a second time, and a take read again
(a detection's stored localisation, then its score) is its content kept (localise.content). Against the
computation it replaced, kept here as the reference (content(record, block) for each record left out,
read afresh): the same thresholds and left-out z, bit for bit, with one shaft_averages per unit and per
whole record."""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

import numpy as np
import pytest

from gearlab.gearbox import order_table, resolve_gearbox
from gearlab.signals import localise as L

BOX = Path(__file__).resolve().parents[1] / "examples" / "gearboxes" / "reducer_21_63_24_56.toml"


@pytest.fixture(autouse=True)
def nothing_kept(monkeypatch):
    monkeypatch.setattr(L, "_READ", OrderedDict())


def reference_left_out_z(records, firsts, hist, table) -> np.ndarray:
    """history()'s left-out z as it was computed: each record's content read in blocks again."""
    L._READ.clear()
    lay, block = hist.layout, hist.block
    units = [L._units(r, f, lay, block) for r, f in zip(records, firsts)]
    z = []
    for i, r in enumerate(records):
        rest = [u for j, us in enumerate(units) if j != i for u in us]
        level, sd = L.shaft_levels(L.content(r, lay, firsts[i], block), L.spread(rest, ~lay.carrier), lay)
        z.append(level / sd)
    return np.array(z).reshape(-1, len(lay.shafts))


def counted(monkeypatch) -> list[int]:
    """The size of each record shaft_averages reads, from now on."""
    calls, real = [], L.shaft_averages

    def spy(y, *args):
        calls.append(y.size)
        return real(y, *args)

    monkeypatch.setattr(L, "shaft_averages", spy)
    return calls


def takes(*lengths: int) -> list[np.ndarray]:
    rng = np.random.default_rng(4)
    u = np.arange(512) / 512
    return [rng.standard_normal((R, 512)) + np.cos(2 * np.pi * 21 * u) for R in lengths]


def test_a_history_reads_each_block_once_and_decides_as_before(monkeypatch):
    table = order_table(resolve_gearbox(BOX))
    records, firsts = takes(40, 44, 50), [0, 3, 5]
    calls = counted(monkeypatch)
    hist = L.history(records, table, first_revolutions=firsts)
    assert hist.layout.mode == "shafts" and hist.block == 20
    units = sum(r.shape[0] // 20 for r in records)  # 2 + 2 + 2 blocks, no record read whole: its levels read no mean
    assert sorted(calls) == [20 * 512] * units  # was 6 + 3 + 6 again, then 6 + 3
    np.testing.assert_array_equal(hist.left_out_z, reference_left_out_z(records, firsts, hist, table))
    assert np.all(hist.thresholds >= np.nanmax(hist.left_out_z, axis=0))


def test_a_take_read_again_is_not_read_twice_and_a_changed_one_is(monkeypatch):
    table = order_table(resolve_gearbox(BOX))
    hist = L.history(takes(40, 44, 50), table)
    (take,) = takes(46)
    calls = counted(monkeypatch)
    first = L.localise(take, hist, table, first_revolution=2)
    read = len(calls)
    assert read == 3  # the take whole and its two blocks of 20
    again = L.localise(take.copy(), hist, table, first_revolution=2)
    assert len(calls) == read and [e.z for e in again.ranking] == [e.z for e in first.ranking]
    L.localise(take, hist, table, first_revolution=3)  # another first revolution: another tooth index
    assert len(calls) == 2 * read
    take[7, 100] += 1e-9
    L.localise(take, hist, table, first_revolution=2)
    assert len(calls) == 3 * read - 1  # the take whole and its first block; the second, unchanged, kept
