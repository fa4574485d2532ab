"""A take whose noise floor differs from its history's is no localised change: a quieter or noisier sensor moves the
noise alone, a sensor's gain the lines and the noise alike (signals.evidence.line_gain). The tiny detection run's
records (textrecords.signals: the input shaft's lines at orders 1, 32 and 64, noise of sd 0.3 m/s²) read on the
25/30 description of its source (meng2020), whose mesh harmonics carry no line: two lines off them, too few to
read their gain from, development seeds."""

from __future__ import annotations

import numpy as np
import pytest
import textrecords
from textrecords import FS, PULSES, signals

from gearlab.data import which_gear as W
from gearlab.gearbox import order_table
from gearlab.gearbox.simulation import gearbox_of
from gearlab.inspect import InspectOptions
from gearlab.inspect_history import input_revolutions

NOISE = 0.3  # textrecords.signals' default: the history's


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """(the box, its order table, a reader of a take made by signals' keywords, the history of two takes)."""
    folder = tmp_path_factory.mktemp("noise")
    box = gearbox_of("meng2020")
    table = order_table(box)

    def take(name: str, gain: float = 1.0, fs: float = FS, **kw) -> W.Take:
        with pytest.MonkeyPatch.context() as mp:  # signals samples at textrecords.FS
            mp.setattr(textrecords, "FS", fs)
            vib, tacho = signals(revolutions=40, **kw)
        np.savez(folder / f"{name}.npz", acc_ms2=gain * vib, tacho_V=tacho, fs=fs)
        options = InspectOptions("acc_ms2", tacho="tacho_V", pulses_per_rev=PULSES)
        revs, first, _, _, speed, rate, turns = input_revolutions(str(folder / f"{name}.npz"), box, options)
        return W.Take(revs, first, speed.mean_hz, rate, turns)

    hist = W.history_of([take(f"h{k}", seed=k, phase=0.7 * k) for k in (0, 1)], table, tacho="input", pulses=PULSES)
    return box, take, hist, table


def _found(tiny, name: str, seed: int, **kw) -> dict:
    box, take, hist, table = tiny
    return W.which_gear(take(name, seed=seed, phase=0.3 * seed, **kw), hist, table, W.events(box.source))


# noise at 0.5, 0.7 and 1.5 times the history's; a gain of 0.5 and 2; twice the rate (half the noise an order)
OTHER = [{"noise": k * NOISE} for k in (0.5, 0.7, 1.5)] + [{"gain": 0.5}, {"gain": 2.0}, {"fs": 2 * FS}]


@pytest.mark.parametrize("kw", OTHER)
def test_a_healthy_take_at_another_noise_floor_or_gain_is_localised_on_no_gear(tiny, kw):
    # the lines were expected at the history's times the take's noise floor's level: noise at 0.5, 0.7 and 1.5 times
    # the history's read the input shaft at z 36-38, 12-13 and -7 to -8 (threshold 2.58), a take at twice the rate (half
    # the noise an order) at 6.6-8.0, seeds 100-102; -0.6 to 0.5 so
    found = _found(tiny, f"healthy{sorted(kw.items())}", 101, **kw)
    assert found["named"] is None, found["summary"]
    assert all(abs(s["z"]) < s["threshold"] for s in found["shafts"]), found["summary"]


@pytest.mark.parametrize("noise", [NOISE, 0.7 * NOISE])
def test_a_chip_is_still_named_at_the_history_s_noise_and_a_quieter_one(tiny, noise):
    found = _found(tiny, f"chip{noise}", 101, chip=1.0, noise=noise)
    assert found["named"] is not None and found["named"].startswith("input"), found["summary"]
