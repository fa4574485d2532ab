"""A first wheel described a tooth short, no tacho (issue 39 outside check, a 21/65 + 34/91 reducer at a
declared 29.3 Hz described with 64 teeth): the speed was read 1.5 % slow from stage 2's mesh, which the wrong
wheel moves, because the first mesh's lower wheel sideband (M1 less the intermediate shaft) was taken for
a carrier whose 'sidebands' confirmed a 21-tooth pinion at that speed."""

from __future__ import annotations

import numpy as np
from test_inspect import described, synthesise

from gearlab.inspect import InspectOptions, inspect_record

TRAIN = ((21, 65), (34, 91))


def test_a_wrong_first_wheel_keeps_the_speed_and_is_named(tmp_path):
    x, _, fs = synthesise(TRAIN, speed=29.3, fs=8192.0, revs=300)
    path = tmp_path / "rec.npz"
    np.savez(path, acc=x, fs=fs)
    options = InspectOptions(vibration="acc")
    right = inspect_record(str(path), described(*TRAIN, speed="29.3 Hz"), options)
    assert right["matches"], right["verdict"]
    wrong = inspect_record(str(path), described((21, 64), (34, 91), speed="29.3 Hz"), options)
    assert abs(wrong["speed"]["mean_hz"] / 29.3 - 1) < 0.005, wrong["speed"]
    assert "the wheel on the intermediate shaft shows 65.0" in wrong["verdict"], wrong["verdict"]
