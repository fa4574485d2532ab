"""A sideband comb is read from the lines a shaft's own orders explain, not from another stage's shafts mixed
around that stage's harmonics (issue 39: inspect finds every stage's mesh order and calls out any tooth-count
mismatch). A 19/48 + 25/94 + 17/48 box puts stage 2's 2 M2 + o1 + o2 (20.293: its 2nd harmonic's sideband of
the shaft it shares with stage 1 and of its own wheel's shaft) at M1 + 1.293; the input pinion's comb took it and
the right description read 'the pinion on the input shaft shows 14.7 teeth, 19 described'. Records written by hand
(tests/test_joint_mesh_speed._record), not simulated by gearlab."""

from __future__ import annotations

import numpy as np
import pytest
from test_joint_mesh_speed import _inspect, _record

TRUE = ((19, 48), (25, 94), (17, 48))
F0 = 44.24
LEVELS = (0.65, 0.72, 0.66)
HARMONICS = ((0.58, 0.3, 0.45), (0.79, 0.93, 0.91), (0.96, 0.22, 0.79))


def _x(ramp=0.0):
    return _record(LEVELS, ramp=ramp, teeth=TRUE, f0=F0, harmonics=HARMONICS, noise=0.05)


def test_stage_2_s_mixed_sideband_lies_beside_the_input_comb_s_first():
    # the case is the one named: 2 M2 + o1 + o2 within 2 bins (8 s, 354 turns) of M1 + its 1.293 reading
    o1 = 19 / 48
    o2 = o1 * 25 / 94
    assert abs(2 * 25 * o1 + o1 + o2 - (19 + 1.293)) < 2 / 354


@pytest.mark.parametrize("ramp", [0.0, 0.02])
def test_the_right_description_matches_though_another_stage_s_mixed_sideband_lies_in_the_input_comb(tmp_path, ramp):
    report = _inspect(tmp_path, _x(ramp), TRUE, "44.5 Hz")
    assert report["matches"], report["verdict"]
    stages = report["check"]["stages"]
    assert np.allclose([s["measured_order"] for s in stages], [19, 19 * 25 / 48, 19 * 25 * 17 / 48 / 94], atol=0.05)
    assert "pinion on the input shaft" not in report["verdict"], report["verdict"]


@pytest.mark.parametrize("said", [((18, 48), (25, 94), (17, 48)), ((20, 48), (25, 94), (17, 48))])
def test_an_input_pinion_one_tooth_off_is_still_called_out(tmp_path, said):
    report = _inspect(tmp_path, _x(), said, "44.5 Hz")
    assert report["matches"] is False, report["verdict"]
