"""A wheel's count off is called out though its true sideband lies on an intermodulation product of the described
order (issue 39: inspect calls out any tooth-count mismatch). A comb leaves out the lines that are products
a o_rival +- b o of a stage's two shafts (sideband_combs.mixed); judged with the described o, a count off moved
them onto the true sideband: a 29/42 mesh described with 44 teeth (benchmarks/your_gearbox.py seed 1724, #16)
put 2 - 2 x 29/44 1.1 bins from the output's 1st sideband, 29/42, the comb lost it and said 'the tooth count of its
44-tooth wheel is not checked'; so did a 35/117 + 21/41 box described with a 43-tooth last wheel (#12): o_p - o_p
21/43 lies on o_p 21/41. Alone, a 21/41 mesh described with 43 took the product 1 - 21/41 for the output's order
and said 'matches' (43.05 teeth). Records written by hand (tests/test_joint_mesh_speed._record), not simulated by
gearlab."""

from __future__ import annotations

import pytest
from test_joint_mesh_speed import _inspect, _record

# (true counts, the wheel 2 teeth more, speed Hz, seconds): input revolutions as the benchmark's takes
CASES = [((29, 42), 44, 23.16, 5.5), ((21, 41), 43, 43.92, 5.0)]


def _x(teeth, f0, seconds, ramp):
    return _record((1.0,), seconds=seconds, ramp=ramp, teeth=(teeth,), f0=f0, harmonics=((1.0, 0.5, 0.3),), noise=0.05)


def test_the_described_order_s_products_lie_on_the_true_first_sideband():
    # the cases are the ones named: 1.1 bins at the take's 126 input turns, an 8th of a bin at 219 turns
    assert abs((2 - 2 * 29 / 44) - 29 / 42) < 1.1 / 126
    assert abs((1 - 21 / 43) - 21 / 41) < 0.125 / 219


@pytest.mark.parametrize("ramp", [0.0, 0.02])
@pytest.mark.parametrize("teeth, said, f0, seconds", CASES)
def test_a_wheel_two_teeth_off_is_called_out_and_the_right_count_matches(tmp_path, teeth, said, f0, seconds, ramp):
    x = _x(teeth, f0, seconds, ramp)
    right = _inspect(tmp_path, x, (teeth,), f"{f0:.1f} Hz")
    assert right["matches"], right["verdict"]
    assert abs(right["check"]["stages"][0]["z2_seen"] - teeth[1]) < 0.1
    wrong = _inspect(tmp_path, x, ((teeth[0], said),), f"{f0:.1f} Hz")
    assert wrong["matches"] is False, wrong["verdict"]
    assert f"the wheel on the output shaft shows {teeth[1]}.0" in wrong["verdict"], wrong["verdict"]
    assert f"{said} described" in wrong["verdict"], wrong["verdict"]
