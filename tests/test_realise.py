"""The one realisation of simulated revolutions (gearlab.data.realise): signal effects in the chain's
order, then the dataset's noise after every one of them, then the TSA; seeds that depend on the row
alone (not on the worker or chunk); and the builder and a simulated record realised by it with the
documented seeds. Also why a ``sensor_noise`` with a seed (the dataset's noise) and one without are
kept apart: the same noise, at another place and from other seeds."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.data.builder import SimTask, build_dataset, simulate_unit
from gearlab.data.realise import EFFECT_STREAM, REFERENCE_ROW, Seeds, parts, realise, row_seed
from gearlab.data.simulated import simulated_record
from gearlab.data.spec import POINTS, NoiseSpec, dataset_preset
from gearlab.effects import EffectChain, effect_spec
from gearlab.signals import tsa

SPEED = 40.0
FS = POINTS * SPEED
NOISE = NoiseSpec("gaussian", 0.0, 3)


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def clean():
    """The healthy steady revolution of Dataset B's six-DOF model (the builder's simulation unit)."""
    return simulate_unit(SimTask("six_dof", "meng2020", 200e3, SPEED, 20.0, "pinion_y", None, None, (1,)))[0]


def chain(*specs) -> EffectChain:
    return EffectChain.load(specs)


def high_band_share(x: np.ndarray) -> float:
    """The share of the power of rows *x* above order 1000 (40 kHz at 40 Hz, far above a 2 kHz low-pass)."""
    power = np.abs(np.fft.rfft(x, axis=-1)) ** 2
    return float(power[..., 1000:].sum() / power.sum())


def test_the_datasets_noise_comes_after_every_effect_and_a_noise_effect_at_its_place(clean):
    """A low-pass listed after sensor_noise filters that noise; the dataset's noise is added after the
    low-pass, white: its power above the corner stays what the noise put there."""
    record = np.broadcast_to(clean, (4, POINTS))
    lowpass = effect_spec("sensor_lowpass", f_c=2000.0)
    seeds = Seeds([1, 2, EFFECT_STREAM], [1, 2])
    here = {"fs": FS, "speed_hz": SPEED, "reference_rms": float(np.sqrt(np.mean(clean**2)))}
    filtered = realise(record, chain(lowpass), None, seeds, **here)
    dataset_noise = realise(record, chain(lowpass), NOISE, seeds, **here) - filtered
    noise_first = chain(effect_spec("sensor_noise", kind="gaussian", snr_db=0.0), lowpass)
    effect = realise(record, noise_first, None, seeds, **here)
    effect_noise = effect - filtered
    # white noise has half its power above order 1000; the effect's has been filtered away there
    assert 0.45 < high_band_share(dataset_noise) < 0.55
    assert high_band_share(effect_noise) < 1e-3  # the record's row edges leave ~1e-4
    # the dataset's noise: exactly its SNR on each realised row (eq. 4.1-4.5), after the low-pass
    snr = 10 * np.log10(np.mean(filtered**2, axis=1) / np.mean(dataset_noise**2, axis=1))
    np.testing.assert_allclose(snr, 0.0, atol=1e-9)


def test_rows_of_their_own_depend_on_their_seeds_alone_and_a_record_runs_on(clean):
    """Seeds per row: each row realised alone, in any grouping (a chunk, a worker), is the same row.
    One Seeds: the rows are one record, a tone that is no whole order runs on from row to row."""
    rows = np.broadcast_to(clean, (6, POINTS))
    tone = chain(effect_spec("interference_tone", frequency=37.3, ratio=0.5), effect_spec("sensor_noise", snr_db=6.0))
    seeds = [Seeds.of_row([0, 3, i]) for i in range(6)]
    here = {"fs": FS, "speed_hz": SPEED, "reference_rms": 1.0}
    together = realise(rows, tone, NOISE, seeds, **here)
    assert not np.array_equal(together[0], together[1])  # fresh draws on every row
    for lo, hi in ((0, 2), (2, 5), (5, 6)):
        np.testing.assert_array_equal(realise(rows[lo:hi], tone, NOISE, seeds[lo:hi], **here), together[lo:hi])
    np.testing.assert_array_equal(realise(rows, tone, NOISE, seeds, average=True, **here), tsa(together))
    # one record: row 1 continues row 0, and the tone alone (order 5/6: 5 bins of the 6-row record)
    # read end to end is one line; rows of their own each start it at their own phase
    only_tone = chain(effect_spec("interference_tone", frequency=SPEED * 5 / 6, ratio=0.5))

    def at_its_line(x):
        power = np.abs(np.fft.rfft((x - rows).reshape(-1))) ** 2
        return power[5] / power.sum()

    assert at_its_line(realise(rows, only_tone, None, seeds[0], **here)) > 0.999
    assert at_its_line(realise(rows, only_tone, None, seeds, **here)) < 0.9


def test_the_builders_rows_and_reference_are_the_realisation_with_the_documented_seeds(clean):
    """Row i of a dataset is the TSA of its J revolutions realised with Seeds.of_row([seed, noise seed, i]);
    its healthy reference fits 64 revolutions realised with row REFERENCE_ROW's seeds."""
    effects = (effect_spec("interference_tone", frequency=37.3, ratio=0.5), effect_spec("sensor_noise", snr_db=6.0))
    spec = dataset_preset("B-6-ch5").with_(
        faults=(), healthy=3, revolutions=4, tsa=True, noise=NoiseSpec("laplace", 3.0, 5), seed=2, effects=effects
    )
    ds = build_dataset(spec)  # B-6-ch5: the six-DOF model at 40 Hz, 20 N m, 200 kHz (the fixture's)
    here = {"fs": FS, "speed_hz": SPEED, "reference_rms": float(np.sqrt(np.mean(clean**2)))}
    signal = chain(*effects)
    reference = realise(
        np.broadcast_to(clean, (64, POINTS)), signal, spec.noise, Seeds.of_row(row_seed(spec, REFERENCE_ROW)), **here
    )
    assert row_seed(spec, 1) == [2, 5, 1]
    mean, std = float(np.mean(reference)), float(np.std(reference))
    np.testing.assert_allclose(ds.reference, (mean, std), rtol=1e-12)
    for i in range(3):
        revolutions = np.broadcast_to(clean, (4, POINTS))
        row = realise(revolutions, signal, spec.noise, Seeds.of_row(row_seed(spec, i)), average=True, **here)
        np.testing.assert_array_equal(ds.X[i], ((row - ds.reference[0]) / ds.reference[1]).astype(np.float32))


def test_a_simulated_record_is_realised_with_its_seeds():
    """simulated_record(seed=s): its clean record realised with Seeds([s, 1], [s, 2])."""
    effects = [{"name": "sensor_noise", "snr_db": 10.0}, {"name": "sensor_lowpass", "f_c": 5000.0}]
    plain = simulated_record(speed_hz=30.0, revolutions=2, seed=4)
    rec = simulated_record(speed_hz=30.0, revolutions=2, seed=4, snr_db=5.0, noise_kind="laplace", effects=effects)
    signal = chain(effect_spec("sensor_noise", snr_db=10.0), effect_spec("sensor_lowpass", f_c=5000.0))
    # neither effect reads reference_rms: any value gives the record's
    noise, seeds = NoiseSpec("laplace", 5.0), Seeds([4, 1], [4, 2])
    expected = realise(plain.vibration[None], signal, noise, seeds, fs=plain.fs, speed_hz=30.0, reference_rms=1.0)[0]
    np.testing.assert_array_equal(rec.vibration, expected)


def test_parts_split_the_signal_effects_in_their_order():
    full = chain(
        effect_spec("sensor_noise", snr_db=3.0),
        effect_spec("drive_inertias"),
        effect_spec("sensor_lowpass", f_c=5000.0),
        effect_spec("sensor_offset", offset=0.1),
    )
    shaping, noisy = parts(full)
    assert [e.name for e, _ in shaping.items] == ["sensor_lowpass", "sensor_offset"]
    assert [e.name for e, _ in noisy.items] == ["sensor_noise"]


def test_the_datasets_noise_and_sensor_noise_are_the_same_noise_from_other_seeds():
    """A ``sensor_noise`` (gaussian, 6 dB) with a seed (the dataset's noise) and one without put noise of
    exactly the same SNR on every revolution (one add_noise), but from other generators: the two are
    kept apart (kinds.common.effects_and_noise) so that every noisy dataset keeps its draws."""
    base = dataset_preset("B-6-ch5").with_(faults=(), healthy=3, seed=1)
    clean = build_dataset(base)
    declared = build_dataset(base.with_(noise=NoiseSpec("gaussian", 6.0, 0)))
    effect = build_dataset(base.with_(effects=(effect_spec("sensor_noise", kind="gaussian", snr_db=6.0),)))

    def residual_snr(ds):
        s = clean.X.astype(np.float64) * clean.reference[1] + clean.reference[0]
        x = ds.X.astype(np.float64) * ds.reference[1] + ds.reference[0]
        return 10 * np.log10(np.mean(s**2, axis=1) / np.mean((x - s) ** 2, axis=1))

    np.testing.assert_allclose(residual_snr(declared), 6.0, atol=1e-3)
    np.testing.assert_allclose(residual_snr(effect), 6.0, atol=1e-3)
    assert not np.allclose(declared.X, effect.X)
