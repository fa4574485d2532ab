"""A long train's stretch (builder.steady_stretch) is run from lead_revolutions before it, not from
t = 0 (issue 39/42: outside box R's gap profile, a casing on soft mounts: 506 settle turns before its
128, 8.6 M steps a point). Simulator.run(start=...) reads every series at its own absolute step, so
the stretch is the same steady turns as the run from the start's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.data import builder
from gearlab.dynamics.newmark import Simulator
from gearlab.gearbox.simulation import reference
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry

# hunting-tooth pairs (2773 input turns to repeat): a stretch, as outside box R's 38/87 + 49/93 + 69/91
HUNTING = description(
    stage(19, 47), stage(23, 59, module="2.5 mm"), stage(29, 71, module="3 mm"), name="h", speed="15 Hz", load="60 N*m"
)
# R's casing as its gap profile fitted it: 10 kg on soft mounts, lightly damped in y (a 1.6 1/s bounce)
SOFT = {"mf": 10.34, "k_xf": 3.383e5, "k_yf": 1.8135e6, "c_xf": 146.9, "c_yf": 74.6}


def _series(sim) -> list[np.ndarray]:
    return [sim.t, sim.tacho, sim.tvms]


@pytest.mark.parametrize("fault", [None, "wheel"])
@pytest.mark.parametrize("fs", [40e3, builder.whole_steps_rate(40e3, 30.0, 32)])  # interpolated, whole steps
def test_a_run_started_later_reads_every_series_at_its_own_step(fault, fs):
    registry = get_registry()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        sim = Simulator(registry.get("model", "two_stage"), "phm09", fs=fs)
    faults = () if fault is None else (place_fault(registry, sim.pair, "crack", 5, step=8, gear="wheel"),)
    start = 3 * round(fs / 30.0) + 17
    whole = sim.run(faults, 30.0, duration=8 / 30.0)
    later = sim.run(faults, 30.0, duration=4 / 30.0, start=start)
    for a, b in zip(_series(whole), _series(later), strict=True):
        assert len(b) < len(a) - start and np.array_equal(a[start : start + len(b)], b)
    per_rev = fs / 30.0
    k = sim._mesh_series(0, 2 * np.pi * 30.0 * whole.t, per_rev)
    k_later = sim._mesh_series(0, 2 * np.pi * 30.0 * later.t, per_rev, start=start)
    assert np.array_equal(k[start : start + len(later.t)], k_later)


def test_a_lightly_damped_casing_s_stretch_is_the_long_run_s_in_a_fraction_of_its_steps(tmp_path, monkeypatch):
    (tmp_path / "h.toml").write_text(HUNTING)
    casing = get_registry().get("effect", "casing_path")
    fs = builder.whole_steps_rate(10_000, 15.0, 19)
    task = builder.SimTask(
        "three_stage",
        reference(str(tmp_path / "h.toml")),
        fs,
        15.0,
        60.0,
        "pinion_x",
        None,
        None,
        (1,),
        (casing.spec(SOFT),),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        sim = builder._unit_simulator(task)
    channel, per_rev, turns = "casing_x", round(fs / 15.0), 32
    settle = builder.settle_revolutions(sim, 15.0)
    assert settle > 200  # the box bouncing on its mounts: 1.8 and 3.5 1/s
    long = sim.run((), 15.0, 60.0, duration=(settle + turns) / 15.0, channels=[channel]).channels[channel]
    long = long[settle * per_rev : (settle + turns) * per_rev + 1]

    asked = []
    run, tail = Simulator.run, Simulator.tail

    def counted_run(self, *args, duration=0.4, **kw):
        asked.append(int(round(duration * self.fs)))
        return run(self, *args, duration=duration, **kw)

    def counted_tail(self, faults, speed_hz, load_nm, channel, duration, *args, **kw):
        asked.append(int(round(duration * self.fs)))  # a tail integrates every step from its start
        return tail(self, faults, speed_hz, load_nm, channel, duration, *args, **kw)

    monkeypatch.setattr(Simulator, "run", counted_run)
    monkeypatch.setattr(Simulator, "tail", counted_tail)
    x, _, at = builder.steady_stretch(sim, (), 15.0, 60.0, channel, (), turns)
    assert at == settle  # the same turns of the meshes' cycle
    assert np.abs(x - long).max() < 1e-7 * np.abs(long).max()
    assert asked == [(builder.lead_revolutions(sim, 15.0) + turns) * per_rev]
    assert asked[0] < (settle + turns) * per_rev / 2.5


def test_the_lead_is_the_full_settle_for_a_mode_that_is_all_mesh():
    # a one-stage model on rigid bearings: its slowest mode is the mesh's, the lead its whole settle
    sim = Simulator(get_registry().get("model", "six_dof"), "meng2020")
    decay, share = builder._modes(sim)
    slowest = np.argmin(decay)
    assert share[slowest] > 0.01
    assert builder.lead_revolutions(sim, 30.0) <= builder.settle_revolutions(sim, 30.0)


def test_consecutive_gap_rows_of_a_long_train_simulate_the_turns_they_read(tmp_path, monkeypatch):
    # a measured target's consecutive rows read healthy + 2 turns of the stretch (measured_rows); the
    # other 106 of the 128 it simulated set only the noise's reference RMS (R: -0.005 dB apart)
    from test_long_period_trains import _n_train_spec

    from gearlab.data import placement
    from gearlab.data.chain import Chain
    from gearlab.gap import scoring

    spec = _n_train_spec(tmp_path, healthy=20, seed=7)
    monkeypatch.setattr(placement, "MAX_PERIOD", 10)
    chain = Chain(fs=40.0 * 300.5, speed=40.0, fractions=(0.0, 0.25, 0.5), offset=0.0)
    asked = []
    original = builder.steady_stretch

    def counted(sim, faults, speed, load, channel, effects, revolutions):
        asked.append(revolutions)
        return original(sim, faults, speed, load, channel, effects, revolutions)

    monkeypatch.setattr(builder, "steady_stretch", counted)
    rows = scoring.source_rows(spec, 0, chain, True)
    assert asked == [22]
    fs = builder.whole_steps_rate(spec.fs, 40.0, 19)
    task = builder.SimTask(spec.model, spec.preset, fs, 40.0, 60.0, spec.channel, None, None, (1,), (), 1, 128)
    longer = builder.simulate_unit(tuple(task))[0]
    rms = float(np.sqrt(np.mean(longer[: 22 * 4096] ** 2)))
    truth = scoring.measured_rows(spec.with_(seed=8), longer, 40.0, rms, chain, 19, True)
    assert np.abs(rows - truth).max() < 1e-6 * np.abs(truth).max()
