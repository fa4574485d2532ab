"""The gap's structure line without a source says what inspect says of the same take (issue 39, the lead's fresh box
128 of seeds 5240-5263, a development case now). A 21/92 + 30/63 box at 42.80 Hz described with a 91-tooth first
wheel puts stage 2 at 6.923, where the take has no line (the real mesh, 6.848, is a sideband's width off): inspect
said 'stage 2: no line at mesh order 6.923 (a 30-tooth pinion)', while the gap's later_stages, with no source to weigh
the mesh's level by, let a missing later mesh pass and its line read 'structure not fully checked: no sideband shows
the order of the intermediate shaft, so a wheel on it is checked only through a later stage's mesh order'. With no
source the gap has inspect's information, so it says inspect's line (gearlab.gap.structure_later)."""

from __future__ import annotations

import numpy as np
import pytest
from test_outside_ao import FS, inspected, simulated_take

TEETH, SPEED = ((21, 92), (30, 63)), 42.802
WRONG = ((21, 91), (30, 63))


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    """The box simulated at 200 kHz, 0.2 s settled, resampled to 25.6 kHz, 30 dB noise (test_outside_ao's)."""
    where = tmp_path_factory.mktemp("ax")
    return where, simulated_take(where, TEETH, SPEED, seed=5184, seconds=2.0)


def _line(acc, teeth, kind: str, record: dict) -> str | None:
    from gearboxes import described_pair

    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line
    from gearlab.signals import angle_from_pulses, resample_revolutions

    theta = 2 * np.pi * SPEED * (0.2 + np.arange(acc.size) / FS) + 3.7
    tacho = np.where(np.mod(theta, 2 * np.pi) < 0.2 * np.pi, 5.0, 0.0) if kind == "ttl" else 2.5 - 2.5 * np.cos(theta)
    rows = resample_revolutions(acc, angle_from_pulses(tacho, FS), points=1024)
    chain = Chain(fs=FS, speed=SPEED, tacho_shaft="input")
    return structure_line(rows, described_pair(*teeth), 400, chain, None, record)


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_a_first_wheel_one_short_is_called_out_by_the_gap_as_by_inspect(take, kind):
    where, acc = take
    report = inspected(where, acc, SPEED, WRONG, kind)
    assert report["matches"] is False and "stage 2: no line at mesh order 6.923" in report["verdict"], report["verdict"]
    record: dict = {}
    line = _line(acc, WRONG, kind, record)
    assert line is not None and line.startswith("stage 2: no line at mesh order 6.923"), (line, record)
    assert "unchecked" not in record, record


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_the_true_description_passes_the_gap_and_inspect(take, kind):
    where, acc = take
    assert inspected(where, acc, SPEED, TEETH, kind)["matches"] is True
    assert _line(acc, TEETH, kind, {}) is None
