"""Which gear on a rig with damage on two shafts (tests/eccentric_idler.py at 40 Hz): a chipped 32T input pinion
beside an eccentric 48T idler pinion whose transmission error swings the second mesh's phase once per idler turn.

What the localiser can say depends on the history (docs/real_data.md, "Which gear"). Against healthy takes alone the
eccentric pinion's sidebands of the second mesh (idler-exclusive orders) give the idler a level its shared orders do
not hold, and the band's least squares (signals.evidence.shaft_levels: input = shared orders less the idler's and the
output's levels) takes it off the input: the chip's z goes far below zero and the idler alone is named. With another
eccentric build in the history the two builds' difference sets the idler's threshold (tens of times the floor): the
idler is not flagged, the chip is named, and its z is lower by what the eccentricity still takes off."""

from __future__ import annotations

import pytest
from eccentric_idler import BOX, take

from gearlab.data import which_gear as W
from gearlab.gearbox import order_table, resolve_gearbox
from gearlab.signals import localise as L

SEED = 350  # development seed
DAMAGED = {"eccentric": 0.5, "runout": 1.0, "chip": (0.37, 0.4)}  # the chipped pinion beside the eccentric idler


@pytest.fixture(scope="module")
def rig():
    table = order_table(resolve_gearbox(BOX))
    return table, W.Take(*take(SEED, **DAMAGED)), W.Take(*take(SEED + 100))


def _shafts(found: dict) -> dict:
    return {s["shaft"]: s for s in found["shafts"]}


def test_against_healthy_takes_the_eccentric_idler_s_level_hides_the_chip(rig):
    table, damaged, healthy = rig
    hist = W.history_of([healthy, W.Take(*take(SEED + 300))], table)
    found = W.which_gear(damaged, hist, table, None)
    shafts = _shafts(found)
    assert found["named_shaft"] == "idler", found["summary"]
    assert shafts["input"]["z"] < 0 < shafts["idler"]["z"] - 100, found["summary"]  # taken off the input
    alone = W.which_gear(W.Take(*take(SEED, chip=DAMAGED["chip"])), hist, table, None)
    assert alone["named_shaft"] == "input", alone["summary"]  # the same chip without the eccentric idler


def test_with_another_eccentric_build_in_the_history_the_chip_is_named(rig):
    table, damaged, healthy = rig
    build = W.Take(*take(SEED + 200, eccentric=0.3, phase=0.5, runout=0.6))  # another build: another size and angle
    hist = W.history_of([healthy, build], table)
    found = W.which_gear(damaged, hist, table, None)
    shafts = _shafts(found)
    assert found["named"] == "input pinion 32T (stage 1)", found["summary"]
    assert not shafts["idler"]["flagged"], found["summary"]
    assert shafts["idler"]["threshold"] > 10 * L.threshold_floor(3), found["summary"]  # the builds' difference
