"""A take read without a tacho is localised on the revolutions clear of its ends, where the angle followed on a mesh
harmonic's phase has not settled (gearbox.speed.settling: half a period of the follower's low-pass cutoff), alike
where a detection run or `gearlab score` cuts it (data.recordings.cut_recording, which_gear.Take.of) and where
`gearlab inspect --history` does (inspect_history.input_revolutions): the follower's error there, shared by every
order of a take, set a short history's mean off and healthy takes over their thresholds."""

from __future__ import annotations

import numpy as np
from test_followed_revolutions import _record
from test_inspect import described

from gearlab.data.recordings import cut_recording, read_recording
from gearlab.data.which_gear import Take
from gearlab.gearbox.speed import settling
from gearlab.inspect import InspectOptions
from gearlab.inspect_history import input_revolutions
from gearlab.signals.checks import settled, turn_times


def test_settled_keeps_the_revolutions_clear_of_either_end():
    fs = 1000.0
    angle = 2 * np.pi * 10.0 * np.arange(5000) / fs  # 10 Hz for 5 s: 49 complete revolutions, 0.1 s each
    assert settled(angle, fs, 0.0) == slice(0, 49)
    # revolution r spans r / 10 .. (r + 1) / 10 s: from 0.3 s on, and ending by 4.999 - 0.25 s
    assert settled(angle, fs, 0.25) == slice(3, 47)
    assert settled(angle, fs, 2.0) == slice(0, 49)  # 9 of 49 left: the take kept whole
    assert settled(angle, fs, 0.25, need=44) == slice(3, 47)  # 44 left: as many as the which-gear check needs
    assert settled(angle, fs, 0.25, need=45) == slice(0, 49)  # one short of them: the take read whole, ends in


def test_a_take_without_a_tacho_is_localised_on_its_settled_revolutions_in_every_reading(tmp_path):
    stages = ((26, 37),)
    path, box = _record(tmp_path, stages), described(*stages)
    true = cut_recording(path, vibration="acc", tacho="angle")  # the take's true angle
    cut = cut_recording(path, vibration="acc", gearbox=box)
    assert cut.angle_source.startswith("speed followed on the mesh phase"), cut.angle_source
    assert true.settled == slice(0, true.revolutions.shape[0])  # a tacho's angle: every revolution localised
    ends = settling(box, cut.speed_hz)
    assert 0.06 < ends < 0.07  # 0.5 / (0.45 x the 26/37 output's 16.9 Hz)
    rec = read_recording(path, "acc", "angle")
    at = turn_times(np.unwrap(rec.tacho), rec.fs)  # the true revolutions' starts (s): their angle's zero is the cut's
    last = (rec.tacho.size - 1) / rec.fs
    kept = [r for r in range(at.size - 1) if at[r] >= ends and at[r + 1] <= last - ends]
    # every revolution cut (a detection run's units), those clear of the follower's ends localised
    assert cut.revolutions.shape[0] == true.revolutions.shape[0] > len(kept) + 2
    assert cut.settled == slice(kept[0], kept[-1] + 1)
    take = Take.of(cut)
    assert take.first == kept[0] and take.speeds.size == len(kept)
    assert np.array_equal(take.revolutions, cut.revolutions[kept])
    # inspect --history cuts the take alike
    revs, first, *_ = input_revolutions(path, box, InspectOptions(vibration="acc"))
    assert first == take.first and np.allclose(revs, take.revolutions, rtol=0, atol=1e-9)
