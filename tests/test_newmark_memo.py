"""Simulator's memo (issue 42): a gap search makes a simulator per parameter set it tries and runs
hundreds at one speed, so the time base (t, the nominal shaft angle, its phase, the tacho), the TVMS
table indices and each gear pair's TVMS builder are made once per process. A reused simulator must
give the floats of one made with nothing kept, whatever ran on it before."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.dynamics import newmark
from gearlab.dynamics.newmark import Simulator
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry


def _floats(sim) -> list[np.ndarray]:
    return [sim.t, sim.tacho, sim.tvms, *sim.channels.values(), *sim.state]


def _same(a, b) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(_floats(a), _floats(b), strict=True))


@pytest.mark.parametrize("model, preset", [("six_dof", "meng2020"), ("two_stage", "phm09")])
def test_a_reused_simulator_gives_a_fresh_one_s_floats(model, preset, monkeypatch):
    registry = get_registry()
    reused = Simulator(registry.get("model", model), preset)
    pinion = place_fault(registry, reused.pair, "crack", 3, step=10)
    wheel = place_fault(registry, reused.pair, "crack", 5, step=8, gear="wheel")
    first = reused.run((), duration=0.02)
    for x in _floats(first):  # a caller editing its result in place leaves the memo alone
        x[:] = 1.0
    # the same steps at another speed (another angle, another table period), another fault's table, a
    # wheel fault (the shaft-angle path), another length: none may reuse a stale series
    calls = [
        dict(faults=()),
        dict(faults=(pinion,)),
        dict(faults=(pinion,), speed_hz=17.3),
        dict(faults=(), speed_hz=23.0),
        dict(faults=(wheel,)),
        dict(faults=(wheel,), speed_hz=23.0),
        dict(faults=(), duration=0.015),
    ]
    for call in calls:
        call = {"duration": 0.02, **call}
        with monkeypatch.context() as m:  # nothing kept: a new memo and new TVMS builders
            m.setattr(newmark, "_MEMO", {})
            m.setattr(newmark, "_STIFFNESS", {})
            fresh = Simulator(registry.get("model", model), preset).run(**call)
        assert _same(reused.run(**call), fresh), call


def test_the_time_base_and_table_index_are_made_once():
    sim = Simulator(get_registry().get("model", "six_dof"), "meng2020")
    sim.run(duration=0.01)
    t, shaft, phase, tacho = sim._time_base(2000, 30.0)
    assert all(a is b for a, b in zip((t, shaft, phase, tacho), sim._time_base(2000, 30.0)))
    assert not t.flags.writeable and sim._index(2001, 100) is sim._index(2001, 100)
    assert sim._time_base(2000, 31.0)[1] is not shaft and np.array_equal(sim._time_base(2000, 31.0)[0], t)


def test_a_gear_pair_s_tvms_builder_is_shared_and_another_pair_gets_its_own():
    registry = get_registry()
    a, b = (Simulator(registry.get("model", "six_dof"), "meng2020") for _ in range(2))
    two = Simulator(registry.get("model", "two_stage"), "phm09")
    assert a.stiffness is b.stiffness and two.stiffness is not a.stiffness
    assert two.stiffness.pair == two.pair and two.mesh_models[0].pair == two.meshes[0].pair


def test_a_shorter_run_s_time_base_is_the_start_of_the_longest_one_s():
    # builder.steady_response runs 8, 32, 128 then 512 revolutions: one time base and one table index
    # are kept, the shorter runs' their first entries (at 200 kHz the four overflowed the memo's
    # budget together and were made again at every run of a gap search)
    sim = Simulator(get_registry().get("model", "six_dof"), "meng2020")
    short = sim._time_base(2000, 30.0)
    longest = sim._time_base(8000, 30.0)
    again = sim._time_base(2000, 30.0)
    for s, long_ in zip(again, longest, strict=True):
        assert np.shares_memory(s, long_) and np.array_equal(s, long_[:2001])
    assert all(np.array_equal(a, b) for a, b in zip(short, again, strict=True))
    index = sim._index(8001, 100)
    assert np.shares_memory(sim._index(2001, 100), index)
