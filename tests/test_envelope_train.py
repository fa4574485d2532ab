"""Which gear in the envelope, on the PHM 2009 rig's train (tests/eccentric_idler.py, numpy takes at 40 Hz, two
healthy history takes): an eccentric 48T idler pinion, whose mesh the 80T gear's own small modulation also follows,
leaves products of the two shafts' lines in the record less every shaft's average, and their envelope read the
output shaft over its threshold (data.which_gear named 'output gear 80T' on every such take of development seeds
11-14 at 40 Hz, z 28.8-34.5 over 3.99). Those lines repeat with the train (signals.envelope_train): the flag is set
aside, no gear named, while a tooth strike whose ring's phase wanders is still named on its gear."""

from __future__ import annotations

import numpy as np
import pytest
from eccentric_idler import BOX, take
from jittered_strikes import Strike

from gearlab.data import which_gear as W
from gearlab.gearbox import order_table, resolve_gearbox
from gearlab.signals import envelope_sync as E
from gearlab.signals import envelope_train as TR
from gearlab.signals import localise as L


@pytest.fixture(scope="module")
def rig():
    table = order_table(resolve_gearbox(BOX))
    return table, W.history_of([W.Take(*take(seed)) for seed in (1, 2)], table)


def test_an_eccentric_idler_pinion_is_not_named_on_the_output_gear_in_the_envelope(rig):
    table, hist = rig
    t = W.Take(*take(11, eccentric=0.8))
    first = t.first % int(table.train_period)
    # the averages name nothing (the eccentricity's lines are the second mesh's first sidebands, left out with it)
    assert L.localise(t.revolutions, hist, table, first).named is None
    seen = E.localise(t.revolutions, hist.envelope, table, first)
    assert seen.named_shaft == "output", seen.summary()  # the train's products, read in the envelope
    found = W.which_gear(t, hist, table, None)
    assert found["named"] is None and found.get("seen") != "envelope", found["summary"]
    assert TR.SET_ASIDE in found["summary"] and "output z" in found["summary"], found["summary"]


@pytest.mark.parametrize(
    ("strike", "gear"),
    [
        (Strike("output", 0.7, 1.0), "output gear 80T (stage 2)"),
        (Strike("input", 0.3, 0.5), "input pinion 32T (stage 1)"),
    ],
)
def test_a_strike_whose_ring_wanders_is_still_named_on_the_rig(rig, strike, gear):
    table, hist = rig
    t = W.Take(*take(11, strike=strike))
    found = W.which_gear(t, hist, table, None)
    assert found["named"] == gear and found["seen"] == "envelope", found["summary"]
    assert TR.SET_ASIDE not in found["summary"], found["summary"]


def test_the_train_s_average_takes_out_the_lines_the_train_repeats_and_keeps_the_rest(rig):
    table, _ = rig
    period, points = int(table.train_period), 64
    rng = np.random.default_rng(5)
    turns = np.arange(8 * period * points) / points  # input turns
    line = np.cos(2 * np.pi * turns * (16 + 1 / 3 + 1 / 5))  # an order of neither shaft, repeated every 15 turns
    noise = rng.standard_normal(turns.size)
    rest = TR.less_train((line + noise).reshape(-1, points), table)
    assert rest.shape == (8 * period, points)
    held = noise.reshape(8, -1)
    assert np.allclose(rest.reshape(-1), (held - held.mean(axis=0)).reshape(-1))  # the line gone, the noise kept
    assert TR.less_train(np.zeros((TR.MIN_PERIODS * period - 1, points)), table) is None  # too few to tell apart
