"""Simulated rig records (gearlab.data.simulated): the builder's steady response read at the logger's
instants, a tacho the importers read back exactly, damage on any gear named by its words, and one
line for a bad placement."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.data.builder import _simulator, angle_samples, steady_revolution, whole_steps_rate
from gearlab.data.recordings import read_recording
from gearlab.data.simulated import simulated_record
from gearlab.errors import GearlabInputError
from gearlab.signals import angle_from_pulses, resample_revolutions

SPEED = 35.0


@pytest.fixture(scope="module")
def healthy():
    return simulated_record(speed_hz=SPEED, revolutions=6, seed=4)


def test_a_healthy_record_is_the_builders_steady_revolution_at_the_loggers_rate(healthy):
    rec = healthy
    assert rec.fs == pytest.approx(66666.67) and rec.period == 1 and rec.faults == ()
    assert rec.vibration.size == int(np.ceil(6 * rec.fs / SPEED))
    assert 0.0 <= rec.angle[0] < 2 * np.pi and rec.angle[-1] > 2 * np.pi * 6
    sim = _simulator("two_stage", "phm09", whole_steps_rate(rec.fs, SPEED, 32))
    reference = angle_samples(steady_revolution(sim, [], SPEED, 20.0, "casing_x"), 1024)
    revolutions = resample_revolutions(rec.vibration, rec.angle, 1024)
    assert len(revolutions) == 5
    rms = np.sqrt(np.mean(reference**2))
    # order tracking of the record at its own (66 666.67 Hz) rate gives the simulated revolution back
    assert np.max(np.abs(revolutions - reference)) < 0.02 * rms
    assert np.max(np.abs(revolutions[1:] - revolutions[:-1])) < 0.02 * rms


def test_the_tacho_gives_the_shaft_angle_back(healthy):
    rec = healthy
    read = angle_from_pulses(rec.tacho, rec.fs)  # 0 at the first rising edge
    first_turn = np.ceil(rec.angle[0] / (2 * np.pi)) * 2 * np.pi
    inside = (rec.angle > first_turn) & (rec.angle < rec.angle[-1] - 2 * np.pi)
    np.testing.assert_allclose(read[inside] + first_turn, rec.angle[inside], atol=1e-9)


def test_the_csv_is_read_as_a_recording(healthy, tmp_path):
    path = healthy.write_csv(tmp_path / "r.csv")
    got = read_recording(path, "acc_ms2", "tacho_V")
    assert got.fs == pytest.approx(healthy.fs, rel=1e-6)
    np.testing.assert_allclose(got.signal, healthy.vibration, rtol=1e-8, atol=1e-9)
    in_volts = healthy.write_csv(tmp_path / "v.csv", sensitivity=0.01)
    volts = read_recording(in_volts, "acc_V", "tacho_V", sensitivity=0.01)
    np.testing.assert_allclose(volts.signal, healthy.vibration, rtol=1e-7, atol=1e-8)


@pytest.mark.parametrize(
    "gear, label, period", [("idler gear", "chip@wheel:5", 3), ("output gear", "chip@s2-wheel:5", 5)]
)
def test_damage_on_a_slower_shaft_repeats_once_per_turn_of_that_shaft(gear, label, period):
    rec = simulated_record(
        [{"name": "chip", "gear": gear, "tooth": 5, "step": 20}], speed_hz=SPEED, revolutions=2 * period + 1, seed=2
    )
    assert rec.faults == (label,) and rec.gears == (gear,) and rec.period == period
    revs = resample_revolutions(rec.vibration, rec.angle, 2048)
    rms = np.sqrt(np.mean(revs**2))
    # the same input revolution one period later, but not one input turn later
    assert np.max(np.abs(revs[period:] - revs[:-period])) < 0.02 * rms
    assert np.max(np.abs(revs[1:] - revs[:-1])) > 0.05 * rms


def test_noise_at_0_db_doubles_the_power():
    clean = simulated_record(speed_hz=SPEED, revolutions=3, seed=5)
    noisy = simulated_record(speed_hz=SPEED, revolutions=3, seed=5, snr_db=0.0, noise_kind="laplace")
    noise = noisy.vibration - clean.vibration
    assert np.sqrt(np.mean(noise**2)) == pytest.approx(np.sqrt(np.mean(clean.vibration**2)), rel=1e-9)


@pytest.mark.parametrize(
    "fault, message",
    [
        ({"name": "chip", "gear": "outptu gear", "step": 20}, r"faults #1 key 'gear': unknown gear 'outptu gear'"),
        ({"name": "chip", "gear": "wheel", "stage": 3, "step": 20}, r"faults #1 key 'stage': expected a stage"),
        ({"name": "chip", "gear": "output gear", "stage": 1, "step": 20}, r"key 'stage': 1 contradicts gear"),
        ({"name": "chip", "gear": "output gear", "tooth": 81, "step": 20}, r"wheel tooth number in 1\.\.80, got 81"),
        ({"name": "chip", "tooth": 3}, r"faults #1: give a ladder 'step'"),
        ({"name": "chip", "teeth": 3, "step": 20}, r"faults #1: unknown key 'teeth'"),
    ],
)
def test_a_bad_placement_is_one_line(fault, message):
    with pytest.raises(GearlabInputError, match=message) as err:
        simulated_record([fault], speed_hz=SPEED, revolutions=1)
    assert "\n" not in str(err.value)


def test_a_gearbox_description_is_simulated_as_its_source_would_be(healthy, tmp_path):
    # the built-in description of the PHM 2009 rig is the two_stage model's preset: the same record
    described = simulated_record(gearbox="phm09", speed_hz=SPEED, revolutions=6, seed=4)
    assert described.channel == healthy.channel == "casing_x" and described.load_nm == 20.0
    np.testing.assert_array_equal(described.vibration, healthy.vibration)
    # a user's one-stage description: its model (ten_dof, the housing), its sensor's channel and its
    # operating point; integrated at sim_fs, read at the logger's fs, the mesh lines where z1 puts them
    path = tmp_path / "rig.toml"
    one = stage(23, 71, width="15 mm", bores=("15 mm", "20 mm"))
    path.write_text(description(one, name="r", speed="20 Hz", load="9 N*m", near="input", direction="y"))
    rec = simulated_record(gearbox=str(path), revolutions=20, seed=1, fs=10_000.0, sim_fs=120e3)
    assert (rec.speed_hz, rec.load_nm, rec.channel, rec.fs) == (20.0, 9.0, "casing_y", 10_000.0)
    revs = resample_revolutions(rec.vibration, rec.angle, 512)
    amp = np.abs(np.fft.rfft(revs.mean(axis=0)))
    strongest = np.argsort(amp)[-3:]
    assert all(k % 23 == 0 for k in strongest), strongest
    with pytest.raises(GearlabInputError, match="give a 'gearbox' description or a 'preset', not both"):
        simulated_record(gearbox=str(path), preset="phm09", revolutions=1)
    with pytest.raises(GearlabInputError, match="nothere.toml"):
        simulated_record(gearbox=str(tmp_path / "nothere.toml"), revolutions=1)
