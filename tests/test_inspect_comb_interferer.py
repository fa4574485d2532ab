"""A right description must match where a line that is no order of the gearbox lies 1-3 bins beside a shaft's 2nd
sideband (issue 39, gearbox.sideband_combs.comb's fit). A synthetic 34/58 + 22/84 box at 49.29 Hz, 10 kHz, 307 turns
(benchmarks/your_gearbox.py, seed 1724 #0) carries the first mesh's 5th harmonic folded about the rate (order 32.875),
smeared by the speed's swing into lines 0.0195 apart; one of them, 2.6 bins off M1 - 2 o and as strong as the
intermediate shaft's first sidebands, joined that shaft's comb (the j^2-weighted fit drew the spacing to it until every
line sat within a bin): 'intermediate shaft: order 0.5832 measured (4 sideband(s) of M1), 0.5862 expected'."""

from __future__ import annotations

import re

import numpy as np
import pytest
from test_inspect import described

from gearlab.inspect import InspectOptions, inspect_record

SPEED, FS, REVS = 49.29, 10000.0, 307


def _record(path, stages, off_bins: float, level: float) -> None:
    """Each mesh amplitude-modulated by the first harmonic of both its shafts (first sidebands only, as the
    benchmark's synthetic maker), shaft lines, noise, a tacho; and a fixed-frequency line *off_bins* bins
    (1 / REVS orders each) below the first mesh's 2nd lower sideband of its wheel's shaft, *level* times a first
    sideband."""
    rng = np.random.default_rng(0)
    t = np.arange(int(REVS / SPEED * FS)) / FS
    theta = 2 * np.pi * SPEED * t
    orders = [1.0]
    for z1, z2 in stages:
        orders.append(orders[-1] * z1 / z2)
    x = rng.normal(0, 0.02, t.size)
    for k, (z1, _) in enumerate(stages):
        am = 1 + 0.15 * np.cos(orders[k] * theta + 0.3) + 0.15 * np.cos(orders[k + 1] * theta + 1.1)
        x += 0.7**k * am * np.cos(z1 * orders[k] * theta + rng.uniform(0, 6))
    for o in orders:
        x += 0.1 * np.cos(o * theta + rng.uniform(0, 6))
    beside = (stages[0][0] - 2 * orders[1] - off_bins / REVS) * SPEED  # Hz: no order of any shaft
    x += level * 0.075 * np.cos(2 * np.pi * beside * t + 0.7)
    tacho = np.where((theta % (2 * np.pi)) < 0.4, 5.0, 0.0)
    np.savez(path, acc=x, tacho=tacho, fs=FS)


@pytest.mark.parametrize("stages", [((34, 58),), ((34, 58), (22, 84))], ids=["one stage", "two stages"])
# 2.6 bins: the line leaves the comb (judged on the spacing the other lines read); 1.2 bins: within the bin a
# comb's line may sit off, it stays, and the spacing's tolerance covers the first sidebands' own reading
@pytest.mark.parametrize("off_bins", [1.2, 2.6])
def test_a_line_beside_a_2nd_sideband_leaves_the_right_wheel_matched(tmp_path, stages, off_bins):
    path = tmp_path / "rec.npz"
    _record(path, stages, off_bins, level=1.5)
    options = InspectOptions(vibration="acc", tacho="tacho")
    right = inspect_record(str(path), described(*stages), options)
    assert right["matches"] is True, right["verdict"]
    shaft = right["check"]["shafts"][1]
    assert shaft["matched"] is True, shaft
    assert abs(shaft["measured_order"] - 34 / 58) <= shaft["tolerance"] < 34 / 58 / 58 / 2, shaft
    # a wheel a tooth off is named, with the count the shaft's sidebands show
    for teeth in (57, 59):
        wrong = inspect_record(str(path), described((34, teeth), *stages[1:]), options)
        assert wrong["matches"] is False, wrong["verdict"]
        seen = re.search(r"the wheel on the \w+ shaft shows (\d+\.\d) ± (\d\.\d) teeth", wrong["verdict"])
        assert seen and abs(float(seen[1]) - 58) < 0.25 and float(seen[2]) < 0.5, wrong["verdict"]
