"""Issue 39: a slow box (a 45/119 + 28/123 conveyor at 45 rpm) steps at the simulator's 200 kHz whatever its speed:
269,000 steps an input turn, and damage on its intermediate pinion repeats every 119 turns. Its first steadiness
look is cut from 8 periods (952 turns, 256 M steps: not one of 85 simulations in 10 minutes) to the 3 its settle
needs, and the run's first line says the cost before it starts; a fast box is simulated as before."""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import pytest
from gearboxes import description, stage
from test_slow_swing_speed import BOX

from gearlab.data import builder
from gearlab.data.slow_box import FIRST_LOOK, SLOW_STEPS, first_blocks, next_blocks
from gearlab.dynamics.newmark import Simulator
from gearlab.gearbox.simulation import reference
from gearlab.kinds.common import dataset_spec, sized


def _never() -> int:
    raise AssertionError("a fast box's settle is not asked")


def test_a_fast_box_first_looks_as_before_and_a_slow_one_as_its_settle_needs():
    assert first_blocks(6667, 5, 5, _never) == FIRST_LOOK  # the PHM 2009 rig's output gear at 30 Hz
    assert first_blocks(6667, 1, 16, _never) == 3  # a later mesh's cycle, as before
    assert first_blocks(269190, 119, 119, lambda: 23) == 3  # the conveyor's intermediate pinion at 0.743 Hz
    assert first_blocks(269190, 119, 119, lambda: 400) == 6  # a settle of 400 turns: 4 periods, then the two compared
    assert first_blocks(SLOW_STEPS // (FIRST_LOOK * 100), 100, 100, _never) == FIRST_LOOK  # at the budget: as before


def test_a_look_that_was_not_steady_is_followed_by_one_past_the_settle():
    assert next_blocks(8, 1, 1, _never, 256) == 32  # a train whose cycle is its damage's period: 4 x, as before
    assert next_blocks(3, 1, 3, lambda: 15, 12) == 7  # a later mesh's 3-turn cycle, a 15-turn settle: 5 and the two
    assert next_blocks(3, 1, 3, lambda: 200, 12) == 12  # never past the most, the look it went on to before
    assert next_blocks(3, 1, 16, lambda: 10, 12) == 4  # a settle within the first look: one cycle more
    assert next_blocks(7, 1, 3, _never, 12) == 12  # after that, the most


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


def test_a_short_later_mesh_cycle_is_integrated_once_past_its_settle(tmp_path, monkeypatch):
    """The 21/63 + 18/54 + 15/45 box (issue 42: a gap run simulates it at each evaluation): its third mesh repeats
    every 3 input turns, its start-up dies away in 15. The first look of 3 cycles is not steady; the next went to 12
    cycles (36 turns integrated), now to 7 (21), whose last cycle is the 36-turn run's to 1e-9 of its peak (the
    check's: 1e-6)."""
    box = description(
        stage(21, 63, bores=("20 mm", "25 mm")),
        stage(18, 54, "2.5 mm", "25 mm", ("25 mm", "30 mm")),
        stage(15, 45, "3 mm", "30 mm", ("30 mm", "40 mm")),
        name="three",
        speed="30 Hz",
        load="40 N*m",
        near="input",
        direction="x",
    )
    (tmp_path / "three.toml").write_text(box)
    per_rev = 21 * 318  # builder.whole_steps_rate(200 kHz): whole steps a tooth pitch
    sim = builder._simulator("three_stage", reference(str(tmp_path / "three.toml")), per_rev * 30.0)
    assert builder.mesh_cycle(sim) == 3 and builder.settle_revolutions(sim, 30.0) == 15
    steps, newmark = [], Simulator._newmark  # the steps each integration call takes (k(t) holds its start's too)
    monkeypatch.setattr(Simulator, "_newmark", lambda sim, k, *a: steps.append(len(k) - 1) or newmark(sim, k, *a))
    x, _ = builder.steady_response(sim, [], 30.0, 40.0, "casing_x", whole_cycle=True)
    assert sum(steps) == 21 * per_rev  # before: 36 turns
    monkeypatch.setattr(Simulator, "_newmark", newmark)
    old = sim.tail([], 30.0, 40.0, "casing_x", 36 / 30.0, 33 * per_rev).x[: 3 * per_rev]
    assert len(x) == 3 * per_rev and np.max(np.abs(x - old)) < 1e-9 * np.max(np.abs(old))
