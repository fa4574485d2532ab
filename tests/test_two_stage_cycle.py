"""A two-stage train whose later mesh is no whole input order (issue 39): the simulated source's rows
hold the later mesh at the phases a recording shows, and every whole-order train keeps its bits."""

import math

import numpy as np
import pytest
from gearboxes import REDUCER, description, stage

from gearlab.data.builder import (
    _simulator,
    build_dataset,
    mesh_cycle,
    noisy_rows,
    row_tasks,
    simulate_unit,
    steady_response,
    whole_steps_rate,
)
from gearlab.data.cache import entry_key
from gearlab.data.realise import first_revolution
from gearlab.data.spec import DATASET_PRESETS, POINTS, DatasetSpec, NoiseSpec, dataset_preset
from gearlab.gearbox import resolve_gearbox
from gearlab.gearbox.simulation import channel, model_name, reference
from gearlab.registry import get_registry

# 19/47 then 23/71: the later mesh at 19 x 23/47 = 9.2979 input orders, repeating after 47 turns
BOX = description(
    stage(19, 47, bores=("20 mm", "25 mm")),
    stage(23, 71, "2.5 mm", "25 mm", ("25 mm", "35 mm")),
    name="reducer",
    speed="35 Hz",
    **REDUCER,
)
ROWS = 48


@pytest.fixture(scope="module")
def reducer(tmp_path_factory):
    path = tmp_path_factory.mktemp("reducer") / "reducer.toml"
    path.write_text(BOX)
    box = resolve_gearbox(str(path))
    model = model_name(box)
    ch = channel(box, model, tuple(get_registry().get("model", model).channels))
    # 40 kHz: coarse for the train's highest mode (a warning), enough for orders below 40
    spec = DatasetSpec(
        name="reducer", model=model, preset=reference(str(path)), channel=ch, speed_hz=35.0, load_nm=15.0, fs=40e3
    )
    return spec.with_(healthy=ROWS)


def _ratio(spectra: np.ndarray, k: int) -> float:
    """|mean of the rows' order-k line| / mean of its magnitudes: 1 for a line at one phase in
    every row, near 0 for one whose phase turns from row to row."""
    return float(abs(spectra[:, k].mean()) / abs(spectra[:, k]).mean())


@pytest.mark.filterwarnings("ignore:.*fewer than 10 steps")
def test_the_rows_hold_the_later_mesh_at_the_phases_a_recording_shows(reducer):
    data = build_dataset(reducer)
    X = data.X.astype(np.float64) * data.reference[1] + data.reference[0]  # physical units
    sim = _simulator(reducer.model, reducer.preset, data.meta["fs_hz"])
    cycle = mesh_cycle(sim)
    assert cycle == 47
    # the recording: the steady time signal over its whole cycle, cut at the tacho into revolutions
    x, _ = steady_response(sim, [], 35.0, 15.0, reducer.channel, whole_cycle=True)
    revs = x.reshape(cycle, -1)
    S = np.fft.rfft(X, axis=1) / POINTS
    R = np.fft.rfft(revs, axis=1) / revs.shape[1]
    # The later mesh (9.298 orders) lies between orders 9 and 10 of a revolution. Over the whole cycle
    # its phase takes 47 equally spaced values, so a recording's TSA removes it (ratio ~0). The rows
    # draw their revolutions independently: the mean of N unit phasors of uniform phase has
    # E|m|^2 = 1/N and P(|m| > 3/sqrt(N)) = exp(-9), so the rows' mean keeps at most that share
    # over what the recording's keeps. One revolution at one phase in every row (the source before
    # issue 39) keeps 1.
    bound = 3 / math.sqrt(ROWS)
    for k in (9, 10):
        assert _ratio(S, k) <= _ratio(R, k) + bound, k
        # each raw row holds the line at a recording's level: the mean magnitude of N of the cycle's
        # revolutions is within 4 standard errors of the whole cycle's
        spread = abs(R[:, k]).std() / abs(R[:, k]).mean()
        assert abs(abs(S[:, k]).mean() / abs(R[:, k]).mean() - 1) <= 4 * spread / math.sqrt(ROWS) + 0.01, k
    # the first mesh (order 19, whole) survives the average as it does in the recording's TSA
    assert abs(_ratio(S, 19) - _ratio(R, 19)) <= bound
    # the rows are J consecutive revolutions of the cycle from a drawn one: their starts spread over it
    starts = {first_revolution(reducer.seed, i, cycle) for i in range(ROWS)}
    assert len(starts) > ROWS // 2


def test_the_cache_key_changes_for_a_non_whole_train_only(reducer):
    assert entry_key(reducer) != reducer.key()
    assert all(entry_key(spec) == spec.key() for spec in DATASET_PRESETS.values())


def test_a_record_starts_a_whole_number_of_its_gears_periods_in():
    assert first_revolution(0, 5, 3, 3) == 0  # one period: no draw
    assert first_revolution(0, 5, 1) == 0
    drawn = [first_revolution(4, i, 59 * 3, 3) for i in range(200)]
    assert all(s % 3 == 0 and 0 <= s < 177 for s in drawn) and len(set(drawn)) > 30
    assert drawn == [first_revolution(4, i, 59 * 3, 3) for i in range(200)]  # seeded


def test_whole_order_trains_keep_their_rows():
    # The PHM 2009 rig (32/96 then 48/80: the later mesh at order 16) repeats every revolution: the
    # whole cycle is the period it always returned, each record starts at revolution 0 with no draw,
    # so every array is the one made before the rows were drawn over a cycle.
    spec = dataset_preset("phm09-30").with_(teeth=(1, 7), healthy=3, faults=(("chip@wheel", (20,)),))
    spec = spec.with_(noise=NoiseSpec("gaussian", 0.0, 3), tsa=True, revolutions=5)
    _, pair, _ = spec.check_model()
    fs = whole_steps_rate(spec.fs, 30.0, pair.Z1)
    sim = _simulator(spec.model, spec.preset, fs)
    assert mesh_cycle(sim) == 1
    one, _ = steady_response(sim, [], 30.0, 20.0, spec.channel)
    whole, _ = steady_response(sim, [], 30.0, 20.0, spec.channel, whole_cycle=True)
    assert np.array_equal(one, whole)
    healthy = simulate_unit(("two_stage", "phm09", fs, 30.0, 20.0, spec.channel, None, None, (1, 2)))
    assert healthy.shape == (2, POINTS)
    idler = simulate_unit(("two_stage", "phm09", fs, 30.0, 20.0, spec.channel, "chip@wheel", 20, (1,)))
    assert idler.shape == (1, 3 * POINTS)  # its gear's period, as before
    data = build_dataset(spec)
    rows = {0: healthy[0], 1: idler[0]}
    clean = lambda idx: [rows[int(data.label[i])] for i in idx]  # noqa: E731
    tasks = row_tasks(spec, len(data.X), clean, data.reference, 30.0, 1.0, lambda i: 3 if data.label[i] else 1)
    assert all(s == 0 for task in tasks for s in task.starts)
    # the rows made without starts (every record from revolution 0) are the rows made with them
    for task in tasks:
        assert np.array_equal(noisy_rows(tuple(task)), noisy_rows(tuple(task._replace(starts=()))))
