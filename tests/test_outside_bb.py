"""A later pinion one tooth over, its described mesh half the first one, is called out by inspect and by the gap's
structure line without a source (issue 39; the lead's fresh box 147 of seeds 5264-5287, a development case now). A
16/52 + 25/61 box at 23.53 Hz described with a 26-tooth stage-2 pinion puts stage 2 at 16 / 52 x 26 = 8.000, whose
2nd, 4th, 6th harmonics are stage 1's 16, 32, 48; the real mesh, 7.692, is one intermediate-shaft order lower. Its
odd harmonics (8, 24, 40) held no line, yet the stage was read at 8 on the real mesh's 26th harmonic (200 = 25 x 8):
'matches' (inspect, both tachos) and no line from the gap. A mesh described at such a fraction is evidenced only by
its own first harmonics (gearlab.gearbox.shared_harmonics); without them the count search reads 7.692."""

from __future__ import annotations

import pytest
from test_outside_ao import FS, inspected, simulated_take
from test_outside_ax import gap_line

TEETH, SPEED = ((16, 52), (25, 61)), 23.527
OVER = ((16, 52), (26, 61))


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    """The box simulated at 200 kHz, 0.2 s settled, resampled to 25.6 kHz, 30 dB noise (test_outside_ao's)."""
    where = tmp_path_factory.mktemp("bb")
    return where, simulated_take(where, TEETH, SPEED, seed=5267, seconds=2.0)


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_a_later_pinion_one_over_at_half_the_first_mesh_is_called_out(take, kind):
    where, acc = take
    report = inspected(where, acc, SPEED, OVER, kind)
    assert report["matches"] is False, report["verdict"]
    assert "stage 2: mesh order 7.692 measured, 8 expected" in report["verdict"], report["verdict"]
    line = gap_line(acc, FS, SPEED, OVER, kind, {})
    assert line is not None and "25 teeth fit the recording, 26 described" in line, line


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_the_true_description_still_matches(take, kind):
    where, acc = take
    assert inspected(where, acc, SPEED, TEETH, kind)["matches"] is True
    assert gap_line(acc, FS, SPEED, TEETH, kind, {}) is None


def test_a_fraction_with_its_own_first_harmonics_is_not_borrowed():
    # 8 = 16 / 2 with a line at 24 (its 3rd, its own) is evidenced; with lines only on 16's harmonics and at its 25th
    # (200) it is not; 7.692, on no harmonic of 16, keeps the rule that every line of it must be another's
    import numpy as np

    from gearlab.gearbox.match import harmonics
    from gearlab.gearbox.shared_harmonics import borrowed
    from gearlab.gearbox.speed import Lines

    def lines(*at):
        x = np.array(at, dtype=float)
        return Lines(x, np.ones_like(x), np.full_like(x, 40.0))

    shared = harmonics([16.0], 0.01)
    assert borrowed(lines(16, 32, 48, 200), 8.0, 0.01, shared)
    assert not borrowed(lines(16, 24, 32, 48), 8.0, 0.01, shared)
    assert not borrowed(lines(16, 32, 200), 7.692, 0.01, shared)
