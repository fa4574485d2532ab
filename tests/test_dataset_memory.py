"""What a dataset's build holds at once (issue 39/42).

An outside user's one-stage 105/143 box with a chip on the 143T output gear died of MemoryError under
a 6 GB cap while its source dataset was built (max RSS 6.13 GB without the cap): the damage repeats
every 143 input turns, so each of the wheel's 143 teeth had a row of 143 x 4096 float64 (4.8 MB),
0.69 GB a fault step, held in the main process for every step at once and pickled a second time into
the pool's tasks. A cycle's rows are now its time samples and each row's turn (gearlab.data.rows),
made in the task that adds the row's noise.
"""

from __future__ import annotations

import pickle
import tracemalloc

import numpy as np
import pytest
from gearboxes import description, stage, two_file_detection

from gearlab.data import builder
from gearlab.data.rows import Row, TurnedRows, entries, made
from gearlab.data.spec import POINTS, NoiseSpec
from gearlab.executors import LocalExecutor

Z1, Z2 = 19, 31  # coprime: damage on the wheel repeats every 31 input turns

SCENARIO = two_file_detection("memory", 'faults = { "chip@output gear" = [16, 20] }\nhealthy = 4\n')


@pytest.fixture
def spec(tmp_path, monkeypatch):
    """The source of a chip on every tooth of a 31T output gear (2 steps: 62 rows of 31 turns), at a
    low integration rate (20 kHz) so that the rows, not the simulation, are what there is to hold."""
    from gearlab.engine import load_scenario

    box = description(stage(Z1, Z2), name="m", speed="25 Hz", load="10 N*m", near="input", direction="radial")
    (tmp_path / "box.toml").write_text(box)
    for name in ("a.csv", "b.csv"):  # not read: the source alone is built
        (tmp_path / name).write_text("t,acc,tacho\n0,0,0\n")
    (tmp_path / "s.toml").write_text(SCENARIO)
    monkeypatch.setattr(builder, "_SIMULATED", builder.OrderedDict())  # simulated afresh
    return load_scenario(str(tmp_path / "s.toml")).spec.source.with_(fs=20e3)


ROW = Z2 * POINTS * 8  # bytes of one clean row of the wheel's cycle

# a low integration rate for a small memory test: the model warns that its highest mode is undersampled
pytestmark = pytest.mark.filterwarnings("ignore:.*fewer than 10 steps per period")


def test_a_slow_gears_rows_are_not_all_held_at_once(spec):
    """The main process, its pool simulating and adding noise, holds under 12 clean rows' bytes at once
    while it builds 66 samples, 62 of them a row of 31 turns: 7.2 rows (before: 95.8 rows, 93 MiB: every
    fault step's rows, and the tasks' pickled copies of them)."""
    with LocalExecutor(2) as pool:
        tracemalloc.start()
        try:
            data = builder.build_dataset(spec, pool)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    assert len(data.X) == 4 + 2 * Z2
    assert peak < 12 * ROW, f"{peak / 2**20:.1f} MiB held at once: {peak / ROW:.1f} rows"


def test_turned_rows_are_the_stacked_rows_and_travel_as_their_cycle(spec):
    """A unit's rows made when read are, float for float, the rows a caller of simulate_unit gets; what
    travels between processes is the cycle's time samples (31 turns at 817 steps, 0.2 MB), not the
    rows of the 31 teeth (31.5 MB)."""
    fs = builder.whole_steps_rate(spec.fs, 25.0, Z1)
    teeth = tuple(range(1, Z2 + 1))
    task = builder.SimTask(spec.model, spec.preset, fs, 25.0, 10.0, spec.channel, "chip@wheel", 20, teeth)
    stacked = builder.simulate_unit(tuple(task))
    lazy = builder.simulate_unit(tuple(task._replace(lazy=True)))
    assert isinstance(lazy, TurnedRows) and stacked.shape == (Z2, Z2 * POINTS)
    rows = pickle.loads(pickle.dumps(entries(lazy)))  # as a task carries them: the cycle once
    assert all(isinstance(r, Row) and r.size == Z2 * POINTS for r in rows)
    assert all(np.array_equal(made(r), want) for r, want in zip(rows, stacked))
    assert len(pickle.dumps(entries(lazy))) < 1.1 * lazy.nbytes < 0.02 * stacked.nbytes


def test_a_chunks_rows_made_from_a_cycle_are_its_rows(spec, monkeypatch):
    """Noise, a TSA of 3 turns and duplicates on the rows made in the task: the dataset of the rows
    made when read is the one of the stacked rows (the same arrays, bytes for bytes)."""
    noisy = spec.with_(teeth=(1, 2, 31), duplicates=2, noise=NoiseSpec("gaussian", 5.0, 3), tsa=True, revolutions=3)
    lazy = builder.build_dataset(noisy)
    real = builder.simulate_unit
    monkeypatch.setattr(builder, "_SIMULATED", builder.OrderedDict())
    monkeypatch.setattr(builder, "simulate_unit", lambda task: real(builder.SimTask(*task)._replace(lazy=False)))
    stacked = builder.build_dataset(noisy)
    assert np.array_equal(lazy.X, stacked.X) and lazy.reference == stacked.reference


@pytest.mark.slow
def test_ray_tasks_make_the_rows_of_a_cycle_as_this_process_does(spec, monkeypatch):
    """The rows made when read travel to Ray's tasks and back as they do to the local pool's."""
    pytest.importorskip("ray")
    from gearlab import executors

    spec = spec.with_(teeth=(1, 2, 31), noise=NoiseSpec("gaussian", 5.0, 3))
    here = builder.build_dataset(spec)
    monkeypatch.setattr(builder, "_SIMULATED", builder.OrderedDict())
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    try:
        there = builder.build_dataset(spec, executors.RayExecutor(None, 2))
    finally:
        executors._close_session()
    assert np.array_equal(here.X, there.X) and here.reference == there.reference
