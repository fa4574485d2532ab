"""The template detectors' shapes on a train whose later mesh is no whole input order (issue 39): a
fault sample's later mesh at its own phase of the cycle is no part of a template, and every
whole-order train keeps its templates' bits."""

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.data.builder import _simulator, build_dataset, mesh_cycle, simulate_unit
from gearlab.data.realise import first_revolution
from gearlab.data.spec import POINTS, DatasetSpec
from gearlab.gearbox import resolve_gearbox
from gearlab.gearbox.simulation import channel, model_name, reference
from gearlab.learn.detectors import _shapes, asynchronous
from gearlab.learn.path import fit_path
from gearlab.registry import get_registry

# 19/47 then 23/71: the later mesh at 19 x 23/47 = 9.298 input orders, between a revolution's orders 9 and 10
BOX = description(
    stage(19, 47, bores=("20 mm", "25 mm")),
    stage(23, 71, "2.5 mm", "25 mm", ("25 mm", "35 mm")),
    name="reducer",
    speed="35 Hz",
    load="15 N*m",
    near="input",
    direction="x",
)


@pytest.mark.filterwarnings("ignore:.*fewer than 10 steps")
def test_a_chips_templates_hold_no_later_mesh(tmp_path):
    path = tmp_path / "reducer.toml"
    path.write_text(BOX)
    box = resolve_gearbox(str(path))
    model = model_name(box)
    ch = channel(box, model, tuple(get_registry().get("model", model).channels))
    spec = DatasetSpec(
        name="reducer", model=model, preset=reference(str(path)), channel=ch, speed_hz=35.0, load_nm=15.0, fs=40e3
    )
    spec = spec.with_(healthy=48, faults=(("chip", (20,)),), teeth=(1, 5, 9, 13))
    data = build_dataset(spec)
    X, y = data.X.astype(np.float64), data.fault.astype(int)
    # the synchronous response of each chip sample: its row less the clean healthy revolution of the
    # cycle its record starts at (realise.first_revolution), standardised as the rows are
    sim = _simulator(spec.model, spec.preset, data.meta["fs_hz"])
    cycle = mesh_cycle(sim)
    assert cycle == 47
    unit = (spec.model, spec.preset, data.meta["fs_hz"], 35.0, 15.0, spec.channel, None, None, (1,))
    healthy = (simulate_unit(unit)[0].reshape(cycle, POINTS) - data.reference[0]) / data.reference[1]
    faults = np.flatnonzero(y == 1)
    same_phase = healthy[[first_revolution(spec.seed, i, cycle) for i in faults]]
    chip = X[faults] - same_phase
    # the target: the source's own healthy rows, so that the path is the gain 1 and the templates
    # are the shapes as made in the source
    _, _, _, shapes = _shapes("test", X, y, X[y == 0], None, "gain")
    median = np.median(X[y == 0], axis=0)
    later = [9, 10]  # the revolution's orders around the later mesh
    raw = np.abs(np.fft.rfft(same_phase - median, axis=1)[:, later]) ** 2  # what the raw fault rows carry
    left = np.abs(np.fft.rfft(shapes - chip, axis=1)[:, later]) ** 2  # what the templates carry but the chip
    # Before the templates were made synchronous a template was the raw row less the median, so it
    # carried the later mesh whole (left = raw). Now its least-squares fit by the healthy rows' spread
    # (the mesh at 27 of the cycle's 47 phases, the fault rows' among them) is gone but for the
    # directions weaker than the gate's 4 median energies: measured 9 and 4 % of the energy at orders
    # 9 and 10 (0.7 % over the whole revolution); a quarter (half the amplitude) leaves a margin.
    assert left.sum() <= 0.25 * raw.sum()
    assert np.sum((shapes - chip) ** 2) <= 0.05 * np.sum((same_phase - median) ** 2)
    # the chip's own response survives: most of each template is it
    assert np.sum(chip * shapes) >= 0.5 * np.sum(chip**2)


def test_whole_order_spread_keeps_the_templates():
    # a whole-order train's healthy rows: one revolution and white noise (none of it is a direction)
    rng = np.random.default_rng(3)
    clean = np.sin(2 * np.pi * 16 * np.arange(POINTS) / POINTS)
    noisy = clean + 0.5 * rng.standard_normal((48, POINTS))
    assert len(asynchronous(noisy - np.median(noisy, axis=0))) == 0
    assert len(asynchronous(np.zeros((48, POINTS)))) == 0
    # and the shapes are the plain difference through the path, bit for bit
    X = np.vstack([np.tile(clean, (8, 1)), np.tile(clean, (4, 1)) + 0.1 * rng.standard_normal((4, POINTS))])
    y = np.r_[np.zeros(8, int), np.ones(4, int)]
    target = clean + 0.3 * rng.standard_normal((12, POINTS))
    _, _, _, shapes = _shapes("test", X, y, target, None, "gain")
    source_healthy, _, through = fit_path(X, y, target, "gain")
    assert np.array_equal(shapes, through(X[y == 1] - source_healthy))
