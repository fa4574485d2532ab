"""A sideband family is read from the lines a shaft's own orders explain, not from the intermodulation of a
stage's two shafts (issue 39: inspect finds every stage's mesh order and calls out any tooth-count mismatch).
A mesh modulated by both its shafts carries lines at a o_p +- b o_w; a 22/68 + 18/70 box puts o_p - o_w (0.2403)
2.2 bins beside the output's 3rd sideband (0.2496) in 8 s, and the output's comb took it: 'the wheel on the output
shaft shows 71.4 teeth, 70 described' of the right description. Records written by hand
(tests/test_joint_mesh_speed._record), not simulated by gearlab."""

from __future__ import annotations

import pytest
from test_joint_mesh_speed import _inspect, _record

TRUE = ((22, 68), (18, 70))
LEVELS, HARMONICS = (0.6, 1.0), ((1.0, 0.5, 0.3), (0.4, 0.5, 1.0))


def _x(ramp=0.0):
    return _record(LEVELS, ramp=ramp, teeth=TRUE, f0=29.36, harmonics=HARMONICS, noise=0.05)


@pytest.mark.parametrize("ramp", [0.0, 0.02])
def test_the_right_description_matches_though_o_p_minus_o_w_lies_beside_the_wheel_s_3rd_sideband(tmp_path, ramp):
    report = _inspect(tmp_path, _x(ramp), TRUE, "29.4 Hz")
    assert report["matches"], report["verdict"]
    wheel = report["check"]["stages"][1]["z2_seen"]
    assert abs(wheel - 70) < 0.5


@pytest.mark.parametrize("said", [((22, 68), (18, 71)), ((22, 68), (18, 69)), ((22, 68), (17, 70))])
def test_a_count_one_off_is_called_out_or_said_unchecked(tmp_path, said):
    # a wheel's sidebands read 70.04 ± 0.97 teeth: 71 passed as 'matches', not called out nor said unchecked
    report = _inspect(tmp_path, _x(), said, "29.4 Hz")
    assert report["matches"] is False or "the tooth count of the wheel on the output shaft" in report["verdict"]
