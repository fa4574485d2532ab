"""Issue 39: a slow box (a 45/119 + 28/123 conveyor at 45 rpm) steps at the simulator's 200 kHz whatever its speed:
269,000 steps an input turn, and damage on its intermediate pinion repeats every 119 turns. Its first steadiness
look is cut from 8 periods (952 turns, 256 M steps: not one of 85 simulations in 10 minutes) to the 3 its settle
needs, and the run's first line says the cost before it starts; a fast box is simulated as before."""

from __future__ import annotations

from collections import defaultdict

import pytest
from test_slow_swing_speed import BOX

from gearlab.data import builder
from gearlab.data.slow_box import FIRST_LOOK, SLOW_STEPS, first_blocks
from gearlab.kinds.common import dataset_spec, sized


def _never() -> int:
    raise AssertionError("a fast box's settle is not asked")


def test_a_fast_box_first_looks_as_before_and_a_slow_one_as_its_settle_needs():
    assert first_blocks(6667, 5, 5, _never) == FIRST_LOOK  # the PHM 2009 rig's output gear at 30 Hz
    assert first_blocks(6667, 1, 16, _never) == 3  # a later mesh's cycle, as before
    assert first_blocks(269190, 119, 119, lambda: 23) == 3  # the conveyor's intermediate pinion at 0.743 Hz
    assert first_blocks(269190, 119, 119, lambda: 400) == 6  # a settle of 400 turns: 4 periods, then the two compared
    assert first_blocks(SLOW_STEPS // (FIRST_LOOK * 100), 100, 100, _never) == FIRST_LOOK  # at the budget: as before


class _Stop(Exception):
    pass


class _Grab:
    """An executor that keeps the tasks it is given and runs none."""

    def map(self, f, tasks, callback=None):
        self.tasks = list(tasks)
        raise _Stop


@pytest.mark.parametrize("faults, said", [({"chip@intermediate pinion": [16, 18, 20]}, True), ({}, False)])
def test_a_slow_box_s_run_says_its_cost_before_it_simulates(tmp_path, faults, said):
    (tmp_path / "conveyor.toml").write_text(BOX.replace('speed = "45 rpm"', 'speed = "45 rpm"\nload = "2 kN*m"'))
    entry = defaultdict(lambda: None, gearbox="conveyor.toml", faults=faults, healthy=48)
    spec = dataset_spec(entry, "[source]", tmp_path)
    lines: list[str] = []
    told = sized(spec)  # gearlab validate's words of the source, before any run
    with pytest.raises(_Stop):
        builder.build_dataset(spec, _Grab(), lambda e: lines.append(getattr(e, "message", "")))
    if not said:  # healthy alone: 3 periods of the meshes' 17-turn cycle, 13.7 M steps
        assert lines[0] == "conveyor: 1 simulations" and "slow" not in told, (lines, told)
        return
    assert lines[0].startswith(
        "conveyor: 85 simulations; a slow box: each up to 357 input turns at 200 kHz, 95 M steps"
    ), lines
    assert "for 85: fewer fault intensities or teeth, or more workers, cut it)" in lines[0]
    assert told.endswith(
        "a slow box: each up to 357 input turns at 200 kHz, 95 M steps, about 1 min on one core (fewer fault "
        "intensities or teeth, or more workers, cut it)"
    ), told
