"""What a steady simulation holds (issue 39/42): a dataset's simulation worker held ~0.95 GB, the
integrator's whole time series (time base, angles, stiffness, response: ~73 bytes a step; 1144 turns
of a 143T wheel's cycle at 202 kHz, 0.64 GB) where the rows read the last block only and the steadiness
check the last two. Simulator.tail integrates in chunks and keeps the samples asked for: the same floats
as Simulator.run, continued or not, on one mesh or several, from a later start too."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from gearlab.data import builder
from gearlab.dynamics import newmark
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry


@pytest.fixture
def small_chunks(monkeypatch):
    """Chunks of 3 divergence checks (a run below spans several), nothing kept in the series memo."""
    monkeypatch.setattr(newmark, "CHUNK", 3 * newmark._CHECK_EVERY, raising=False)
    monkeypatch.setattr(newmark, "_MEMO_BYTES", 0)


@pytest.mark.parametrize("model, preset, gear", [("six_dof", "meng2020", "wheel"), ("two_stage", "phm09", "pinion")])
def test_a_tail_is_the_run_s_samples_float_for_float(model, preset, gear, small_chunks):
    sim = builder._simulator(model, preset, 66666.67 if preset == "phm09" else 200e3)
    fault = (place_fault(get_registry(), sim.pair, "chip", 3, step=16, gear=gear),)
    # whole table entries a step (200 kHz at 25 Hz: 8000 steps a turn) and interpolated ones (phm09 at 30 Hz)
    speed, load, channel = 25.0 if preset == "meng2020" else 30.0, 10.0, sim.model.channels[-1]
    for start in (0, 5 * newmark._CHECK_EVERY + 7):
        whole = sim.run(fault, speed, load, duration=0.1, channels=[channel], start=start).channels[channel]
        since = len(whole) - 4000
        tail = sim.tail(fault, speed, load, channel, 0.1, since, start=start)
        assert tail.steps == len(whole) - 1 and np.array_equal(tail.x, whole[since:])
        # continued from a shorter tail of the same call, that one's window partly inside the longer's
        short = sim.tail(fault, speed, load, channel, 0.06, 0, start=start)
        longer = sim.tail(fault, speed, load, channel, 0.1, 3000, after=short, start=start)
        assert np.array_equal(longer.x, whole[3000:])
        assert all(np.array_equal(a, b) for a, b in zip(longer.state, tail.state))


def test_a_slow_gear_s_steady_cycle_holds_its_last_blocks_not_the_run(small_chunks):
    """A chip on meng2020's 30T wheel (25/30: a period of 6 input turns) at 5 Hz runs 8 periods until
    the last two agree: the old loop held every series of the run, 73 blocks' bytes at once; now the
    two blocks the check reads, the block returned and a chunk's series: 6.0."""
    sim = builder._simulator("six_dof", "meng2020", 20e3, warn_step=False)
    fault = (place_fault(get_registry(), sim.pair, "chip", 1, step=16, gear="wheel"),)
    period = sim.period(fault)
    block = round(sim.fs / 5.0) * period * 8  # bytes of one block (a period of float64 samples)
    sim.run(fault, 5.0, 10.0, duration=0.01, channels=["gear_y"])  # the TVMS tables of this grid, made once
    tracemalloc.start()
    try:
        x, _ = builder.steady_response(sim, fault, 5.0, 10.0, "gear_y", whole_cycle=True)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(x) * 8 == block
    assert peak < 8 * block, f"{peak / block:.1f} blocks held at once"


def test_a_long_tail_keeps_its_first_chunk_s_series_alone(monkeypatch):
    """The series memo (bounded by _MEMO_BYTES) keeps the time base and table indices of a tail's first
    chunk, which the next run at that speed reads again; the later chunks' are made and dropped, not
    kept until the memo overflows (9 chunks of ~40 MB for a 143T wheel's cycle: 120 MB more a worker)."""
    monkeypatch.setattr(newmark, "CHUNK", 3 * newmark._CHECK_EVERY, raising=False)
    monkeypatch.setattr(newmark, "_MEMO", {})
    sim = builder._simulator("six_dof", "meng2020", 200e3)
    sim.tail((), 25.0, 10.0, "gear_y", 0.2, 0)  # 40,000 steps: 7 chunks
    starts = {key[-1] for key in newmark._MEMO if key[0] in ("t", "angle")}
    assert starts == {0}, sorted(starts)
