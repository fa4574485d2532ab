"""The signal pipeline (gearlab.signals): behaviour and numbers, thesis 2.4.3 and 4.1."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import kurtosis

from gearlab.errors import GearlabInputError
from gearlab.signals import (
    NOISE_KINDS,
    Standardiser,
    StandardiserAccumulator,
    add_noise,
    angle_from_pulses,
    angle_from_speed,
    check_signal,
    cut_revolutions,
    order_spectrum,
    resample_revolutions,
    revolution_starts,
    spectrum,
    steady_start,
    steady_start_stats,
    tsa,
    unwrap_tacho,
)

FS = 200e3
SPEED = 25.2  # Hz, Dataset A
P = 4096
TWO_PI = 2 * np.pi


def wrap(theta):
    """Angle wrapped into [-π, π), as the simulator's tacho."""
    return (theta + np.pi) % TWO_PI - np.pi


def grid(points=P):
    return TWO_PI * np.arange(points) / points


def varying_speed_angle(duration=0.5, f0=20.0, f1=30.0):
    """θ(t) = 2π ∫ f dt with f rising linearly from f0 to f1 over the record."""
    t = np.arange(int(duration * FS)) / FS
    return TWO_PI * (f0 * t + 0.5 * (f1 - f0) / duration * t**2)


# --- angle sources ----------------------------------------------------------------------


def test_unwrap_tacho_is_numpys_unwrap_bit_for_bit():
    # its corrections summed only at the wraps: the same values as np.unwrap's over every sample, boundary jumps of
    # exactly ±π included (np.unwrap keeps +π where the step rose)
    rng = np.random.default_rng(3)
    for trial in range(60):
        theta = np.cumsum(rng.uniform(-0.5, 2.5, int(rng.integers(2, 3000))) * (0.1, 1.0, 3.5)[trial % 3])
        tacho = wrap(theta)
        if trial % 4 == 0:
            tacho[rng.integers(0, tacho.size, 3)] = np.pi
        for x in (tacho, -tacho, np.round(tacho, 1)):
            assert np.array_equal(unwrap_tacho(x), np.unwrap(x))
    edge = np.array([0.0, np.pi, 0.0, -np.pi, np.pi, -np.pi])
    assert np.array_equal(unwrap_tacho(edge), np.unwrap(edge))
    assert np.array_equal(unwrap_tacho(np.array([0.5])), [0.5])


def test_unwrap_tacho_recovers_the_continuous_angle():
    theta = angle_from_speed(40_000, FS, SPEED, phase=0.3)
    assert np.allclose(unwrap_tacho(wrap(theta)), theta, atol=1e-9)


def test_angle_from_speed_is_linear_in_time():
    theta = angle_from_speed(5, 1000.0, 10.0, phase=1.0)
    assert np.allclose(theta, 1.0 + TWO_PI * 10.0 * np.arange(5) / 1000.0)


def test_pulses_reproduce_the_true_angle_between_first_and_last_pulse():
    theta = angle_from_speed(int(0.4 * FS), FS, SPEED, phase=1.0)
    pulses = np.where(np.mod(theta, TWO_PI) < np.pi, 5.0, 0.0)  # rising edge at θ ≡ 0 (mod 2π)
    est = angle_from_pulses(pulses, FS)
    inside = (theta >= TWO_PI) & (theta <= np.floor(theta[-1] / TWO_PI) * TWO_PI)
    err = est - (theta - TWO_PI)  # the first pulse is at true θ = 2π, estimated θ = 0
    assert np.max(np.abs(err[inside])) < 1e-3
    # extrapolation outside keeps the neighbouring revolution's speed
    assert np.max(np.abs(err)) < 2e-3


def test_pulses_with_noise_and_a_short_duty_cycle_count_each_pulse_once():
    rng = np.random.default_rng(1)
    theta = angle_from_speed(int(0.3 * FS), FS, SPEED)
    # a 10 % duty key-phasor with slow (RC-like) edges and noise that crosses the mid-level repeatedly
    clean = (np.mod(theta, TWO_PI) < 0.1 * TWO_PI).astype(float)
    kernel = np.ones(40) / 40
    v = np.convolve(clean, kernel, mode="same") + 0.03 * rng.standard_normal(theta.size)
    mid = 0.5 * (v.min() + v.max())
    assert np.count_nonzero((v[:-1] < mid) & (v[1:] >= mid)) > 7  # a naive edge count overcounts
    est = angle_from_pulses(v, FS)
    inside = (theta >= TWO_PI) & (theta <= np.floor(theta[-1] / TWO_PI) * TWO_PI)
    # 7 edges at θ = 2π … 14π found once each; noise jitters their timing by about a sample
    assert np.max(np.abs(est - (theta - TWO_PI))[inside]) < 5e-3


# --- revolution cutting and angular resampling ------------------------------------------


@pytest.mark.parametrize("k", [1, 7, 25])
def test_integer_order_at_constant_speed_gives_identical_revolutions(k):
    theta = angle_from_speed(int(0.3 * FS), FS, SPEED, phase=-2.0)
    revs = resample_revolutions(np.sin(k * theta), theta)
    assert revs.shape == (int((theta[-1] - 0.0) // TWO_PI), P)
    assert np.max(np.abs(revs - np.sin(k * grid()))) < 1e-4


def test_revolutions_are_cut_at_the_tacho_zero_crossings():
    theta = angle_from_speed(int(0.2 * FS), FS, SPEED, phase=-0.5)
    starts = revolution_starts(unwrap_tacho(wrap(theta)))
    expected = (TWO_PI * np.arange(len(starts)) + 0.5) / (TWO_PI * SPEED) * FS
    assert np.allclose(starts, expected, atol=1e-6)
    assert len(starts) == int(theta[-1] // TWO_PI) + 1  # k = 0 … floor(θ_end / 2π)


def test_varying_speed_still_yields_the_pure_order():
    theta = varying_speed_angle()
    revs = resample_revolutions(np.sin(7 * theta) + 0.5 * np.cos(16 * theta), theta)
    assert revs.shape[0] >= 10
    assert np.max(np.abs(revs - (np.sin(7 * grid()) + 0.5 * np.cos(16 * grid())))) < 1e-3


def bump(theta, where=1.0, kappa=20.0):
    """A smooth, 2π-periodic, localised feature: the response to one damaged tooth."""
    return np.exp(kappa * (np.cos(theta - where) - 1.0)) + 0.2 * np.sin(3 * theta)


@pytest.mark.parametrize("n", [2, 5, 16, 25])
def test_offset_realises_the_tooth_shift_exactly(n):
    z1 = 25  # 4096/25 = 163.84 angle samples per tooth: not a whole number of samples
    theta = angle_from_speed(int(0.3 * FS), FS, SPEED)
    shift = (n - 1) * TWO_PI / z1
    offset = -shift
    tooth1 = resample_revolutions(bump(theta), theta, offset=offset)
    # direct evaluation of the tooth-1 response on the shifted angle grid
    assert np.max(np.abs(tooth1 - bump(offset + grid()))) < 1e-4
    # ... which is the response to the same fault on tooth n, cut at the zero crossings
    tooth_n = resample_revolutions(bump(theta - shift), theta)
    m = min(len(tooth1), len(tooth_n))
    assert np.max(np.abs(tooth1[:m] - tooth_n[:m])) < 1e-4


def test_first_and_count_select_revolutions():
    theta = angle_from_speed(int(0.3 * FS), FS, SPEED)
    x = np.sin(theta) + theta / 100  # a drift makes revolutions distinguishable
    allrevs = resample_revolutions(x, theta, points=256)
    some = resample_revolutions(x, theta, points=256, first=2, count=3)
    assert np.array_equal(some, allrevs[2:5])
    with pytest.raises(GearlabInputError, match="holds 7 complete revolutions"):
        resample_revolutions(x, theta, points=256, first=5, count=3)


# --- transient detection ----------------------------------------------------------------


def periodic_record(duration=1.0, k=5):
    theta = angle_from_speed(int(duration * FS), FS, SPEED)
    t = np.arange(theta.size) / FS
    return t, theta, np.sin(k * theta)


@pytest.mark.parametrize("tau", [0.01, 0.02, 0.04])
def test_steady_start_finds_the_end_of_a_decaying_transient(tau):
    rtol = 1e-3
    t, theta, steady = periodic_record()
    revs = resample_revolutions(steady + np.exp(-t / tau), theta)
    rms = np.sqrt(np.mean(steady**2))
    t_settled = tau * np.log(1.0 / (rtol * rms))  # where exp(−t/τ) falls below rtol·RMS
    expected = int(np.ceil(t_settled * SPEED))  # first revolution starting after it
    assert abs(steady_start(revs, rtol) - expected) <= 1


def test_steady_start_is_zero_for_a_periodic_signal():
    _, theta, x = periodic_record(0.4, k=25)
    assert steady_start(resample_revolutions(x, theta)) == 0


def test_steady_start_raises_on_a_growing_signal():
    t, theta, x = periodic_record(0.4)
    with pytest.raises(GearlabInputError, match="never settles"):
        steady_start(resample_revolutions((1 + 3 * t) * x, theta))


def test_steady_start_stats_on_noisy_data():
    rng = np.random.default_rng(3)
    tau = 0.02
    t, theta, steady = periodic_record(1.0)
    envelope = 1 + 2 * np.exp(-t / tau)
    revs = add_noise(resample_revolutions(envelope * steady, theta), 20.0, "gaussian", rng)
    # the per-revolution RMS ≈ the envelope's RMS; steady within 5 % once 2·e^(−t/τ) averages below ~0.05
    rev_t = np.arange(len(revs)) / SPEED
    rev_env = np.array([np.sqrt(np.mean(envelope[(t >= a) & (t < a + 1 / SPEED)] ** 2)) for a in rev_t])
    expected = int(np.flatnonzero(np.abs(rev_env - 1) > 0.05)[-1]) + 1
    assert abs(steady_start_stats(revs, 0.05) - expected) <= 1
    assert steady_start_stats(add_noise(resample_revolutions(steady, theta), 0.0, "gaussian", rng)) == 0
    with pytest.raises(GearlabInputError, match="never settles"):
        steady_start_stats(resample_revolutions((1 + 3 * t) * steady, theta))


def test_cut_revolutions_from_tacho_pulses_and_speed_agree():
    t, theta, steady = periodic_record(0.6, k=16)
    x = steady + np.exp(-t / 0.02)
    by_tacho = cut_revolutions(x, FS, tacho=wrap(theta))
    assert by_tacho.first_steady == steady_start(resample_revolutions(x, theta))
    assert by_tacho.complete == 15 and abs(by_tacho.speed_hz - SPEED) < 1e-9
    assert np.max(np.abs(by_tacho.revolutions - np.sin(16 * grid()))) < 1e-3
    by_speed = cut_revolutions(x, FS, speed_hz=SPEED)
    assert np.allclose(by_speed.revolutions, by_tacho.revolutions)
    pulses = np.where(np.mod(theta, TWO_PI) < np.pi, 1.0, 0.0)
    by_pulses = cut_revolutions(x, FS, pulses=pulses, transient="none")
    # the pulse angle starts at the first pulse (true θ = 2π): revolution r is true revolution r+1
    assert np.max(np.abs(by_pulses.revolutions[-3:] - by_tacho.revolutions[-3:])) < 0.05


# --- standardisation (eq. 2.112 / 4.6) ---------------------------------------------------


def test_standardiser_fit_gives_zero_mean_unit_std_on_the_reference():
    ref = 3.0 + 0.2 * np.random.default_rng(0).standard_normal((20, P))
    st = Standardiser.fit(ref)
    z = st.apply(ref)
    assert z.dtype == np.float32
    assert abs(z.astype(np.float64).mean()) < 1e-6 and abs(z.astype(np.float64).std() - 1) < 1e-6


def test_streaming_accumulator_matches_fit_on_the_concatenation():
    rng = np.random.default_rng(1)
    blocks = [1e4 + rng.standard_normal(rng.integers(1, 3000)) * rng.uniform(0.1, 5) for _ in range(37)]
    acc = StandardiserAccumulator()
    for b in blocks:
        acc.add(b)
    streamed, direct = acc.result(), Standardiser.fit(np.concatenate(blocks))
    assert abs(streamed.mean - direct.mean) <= 1e-12 * abs(direct.mean)
    assert abs(streamed.std - direct.std) <= 1e-12 * direct.std


# --- noise (eq. 4.1–4.5) and TSA (eq. 4.7) ----------------------------------------------


@pytest.mark.parametrize("kind", NOISE_KINDS)
@pytest.mark.parametrize("snr_db", [0.0, 10.0, -5.0])
def test_every_row_gets_exactly_the_requested_noise_rms(kind, snr_db):
    rng = np.random.default_rng(7)
    x = np.sin(5 * grid())[None, :] * rng.uniform(0.5, 3.0, (12, 1)) + 0.1
    noisy = add_noise(x, snr_db, kind, rng)
    rms = lambda a: np.sqrt(np.mean(a**2, axis=-1))  # noqa: E731
    required = rms(x) * 10 ** (-snr_db / 20)
    assert np.allclose(rms(noisy - x), required, rtol=1e-9, atol=0)


def test_student_t_is_far_more_impulsive_than_gaussian():
    x = np.tile(np.sin(grid()), (20, 1))
    excess = {kind: kurtosis((add_noise(x, 0.0, kind, np.random.default_rng(0)) - x).ravel()) for kind in NOISE_KINDS}
    assert abs(excess["gaussian"]) < 0.2
    assert 2.0 < excess["laplace"] < 4.5
    assert excess["student_t"] > 10 * max(excess["laplace"], 1.0)


def test_noise_is_deterministic_given_the_seed():
    x = np.tile(np.sin(grid()), (3, 1))
    a = add_noise(x, 0.0, "laplace", np.random.default_rng(42))
    b = add_noise(x, 0.0, "laplace", np.random.default_rng(42))
    c = add_noise(x, 0.0, "laplace", np.random.default_rng(43))
    assert np.array_equal(a, b) and not np.allclose(a, c)


@pytest.mark.parametrize("kind", NOISE_KINDS)
def test_noise_drawn_again_is_the_draw_and_leaves_the_generator_where_the_draw_does(kind, monkeypatch):
    """A generator in a state seen before gets the standard noise drawn then (kept, signals.noise._DRAWN):
    the same values as a fresh draw, and the generator left where that draw leaves it, so its next draws
    are as before; another state (the same seed, used first) draws afresh."""
    from gearlab.signals import noise

    x = np.tile(np.sin(grid()), (3, 1)) * [[1.0], [2.0], [0.5]]
    monkeypatch.setattr(noise, "_DRAWN", noise.OrderedDict())
    monkeypatch.setattr(noise, "_drawn_size", [0])  # the bytes kept: of the empty store, not of earlier tests'
    first, again, used = (np.random.default_rng([7, 1]) for _ in range(3))
    used.uniform()
    drawn = [add_noise(x, 3.0, kind, g) for g in (first, again, used)]
    assert len(noise._DRAWN) == 2  # the second generator's draw was the first's
    fresh = np.random.default_rng([7, 1])
    standard = noise._STANDARD_NOISE[kind](fresh, x.shape)
    assert np.array_equal(drawn[1], x + noise._rms(x) * 10 ** (-3.0 / 20) / noise._rms(standard) * standard)
    assert np.array_equal(drawn[0], drawn[1]) and not np.allclose(drawn[2], drawn[1])
    after = [g.standard_normal(5) for g in (first, again, fresh)]
    assert np.array_equal(after[0], after[2]) and np.array_equal(after[1], after[2])


@pytest.mark.parametrize("j", [4, 16, 60])
def test_tsa_lowers_the_noise_rms_as_one_over_root_j(j):
    clean = np.tile(np.sin(25 * grid()) + 0.3 * np.cos(3 * grid()), (j, 1))
    noisy = add_noise(clean, 0.0, "gaussian", np.random.default_rng(j))
    noise_rms = np.sqrt(np.mean(clean[0] ** 2))  # 0 dB: noise RMS = signal RMS
    residual = tsa(noisy) - clean[0]
    assert abs(np.sqrt(np.mean(residual**2)) / (noise_rms / np.sqrt(j)) - 1) < 0.15


def test_tsa_averages_over_the_revolution_axis_of_a_batch():
    batch = np.random.default_rng(0).standard_normal((3, 5, 8))
    assert np.allclose(tsa(batch), batch.mean(axis=1))
    assert tsa(batch, axis=0).shape == (5, 8)


# --- spectra ----------------------------------------------------------------------------


def test_spectrum_peak_has_the_sine_amplitude():
    t = np.arange(20_000) / FS
    f, amp = spectrum(2.0 * np.sin(TWO_PI * 1000.0 * t + 0.3), FS)
    k = np.argmax(amp)
    assert f[k] == pytest.approx(1000.0)
    assert amp[k] == pytest.approx(2.0, rel=0.02)
    # between bins the Hann window loses at most its scalloping (−1.42 dB)
    f2, amp2 = spectrum(2.0 * np.sin(TWO_PI * 1005.0 * t), FS)
    assert 2.0 * 10 ** (-1.43 / 20) < amp2.max() <= 2.0 and abs(f2[np.argmax(amp2)] - 1005) <= 5


def test_order_spectrum_peaks_at_the_shaft_order():
    orders, amp = order_spectrum(0.7 * np.sin(25 * grid()) + 0.1)
    assert orders[np.argmax(amp)] == 25 and amp.max() == pytest.approx(0.7)
    assert amp[0] == pytest.approx(0.1)
    four_revs = np.sin(2.5 * TWO_PI * np.arange(4 * P) / P)  # order 2.5 over 4 concatenated revolutions
    o, a = order_spectrum(four_revs, per_revolution=P)
    assert o[np.argmax(a)] == pytest.approx(2.5)


@pytest.mark.parametrize("n", [1009 * 8, 1013 * 6 + 0, 2 * 1009, 3 * 1009, 1009 * 1013, 16 * 1031 * 3])
def test_a_length_with_a_large_prime_factor_is_transformed_split_and_alike(n, monkeypatch):
    """signals.spectra._rfft takes a 1-D length with a prime factor of SPLIT_PRIME or more through signals.fft's
    four-step rfft (numpy's generic radix-r pass costs n r); the spectrum is numpy's own to rounding, odd lengths and a
    prime row count too."""
    from gearlab.signals import spectra

    x = np.random.default_rng(n).standard_normal(n)
    want = np.fft.rfft(x)
    split = []
    real = spectra.rfft
    monkeypatch.setattr(spectra, "rfft", lambda y: split.append(y.size) or real(y))
    got = spectra._rfft(x)
    assert split == [n]
    assert got.shape == want.shape and np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))
    # a smooth length, a prime one (numpy's chirp) and a 2-D block stay numpy's own
    smooth, prime = np.random.default_rng(0).standard_normal(4096 * 3), np.random.default_rng(1).standard_normal(4793)
    for y in (smooth, prime, x[: 2 * (n // 2)].reshape(2, -1)):
        assert np.array_equal(spectra._rfft(y), np.fft.rfft(y, axis=-1))
    assert len(split) == 1


# --- bad input: one clear line with the key fact ----------------------------------------


def test_nan_in_the_signal_is_located():
    x = np.zeros(100)
    x[17] = np.nan
    with pytest.raises(GearlabInputError, match="NaN at sample 17"):
        check_signal(x)
    theta = angle_from_speed(100, FS, SPEED)
    with pytest.raises(GearlabInputError, match="signal contains NaN at sample 17"):
        resample_revolutions(x, theta)


@pytest.mark.parametrize(
    "bad, fact",
    [
        (np.zeros((2, 3)), "must be 1-D"),
        (np.array([]), "empty"),
        (np.array([1.0, np.inf]), "inf at sample 1"),
        (np.array(["a"]), "real numbers"),
    ],
)
def test_check_signal_rejects(bad, fact):
    with pytest.raises(GearlabInputError, match=fact):
        check_signal(bad)


def test_too_short_for_one_revolution():
    x = np.ones(1200)
    with pytest.raises(
        GearlabInputError, match=r"1200 samples, fewer than one revolution \(7937 at 25.2 Hz and 200 kHz\)"
    ):
        cut_revolutions(x, FS, speed_hz=SPEED)
    with pytest.raises(GearlabInputError, match="not one complete revolution"):
        resample_revolutions(x, angle_from_speed(1200, FS, SPEED))


def test_tacho_that_never_crosses_zero():
    theta = 0.1 + np.linspace(0.0, 2.5, 3000)  # less than a turn, all within (0, 2π)
    with pytest.raises(GearlabInputError, match="never crosses 0 rad"):
        revolution_starts(unwrap_tacho(wrap(theta)))
    with pytest.raises(GearlabInputError, match="fewer than one revolution"):
        cut_revolutions(np.sin(theta), 1000.0, tacho=wrap(theta), transient="none")
    with pytest.raises(GearlabInputError, match="does not increase between samples 0 and 1"):
        revolution_starts(np.zeros(10))


def test_tacho_in_degrees_is_refused():
    with pytest.raises(GearlabInputError, match="more than one turn"):
        unwrap_tacho(np.rad2deg(wrap(angle_from_speed(20_000, FS, SPEED))))


def test_unknown_noise_kind_lists_the_known_ones():
    with pytest.raises(GearlabInputError, match="unknown noise kind 'pink'; known: gaussian, laplace, student_t"):
        add_noise(np.ones((2, 8)), 0.0, "pink", np.random.default_rng(0))
    with pytest.raises(GearlabInputError, match="numpy.random.Generator"):
        add_noise(np.ones((2, 8)), 0.0, "gaussian", 42)


def test_zero_variance_reference():
    with pytest.raises(GearlabInputError, match="zero variance"):
        Standardiser.fit(np.full((3, 100), 0.1))
    with pytest.raises(GearlabInputError, match="zero variance"):
        StandardiserAccumulator().add(np.full(10, 0.1)).add(np.full(7, 0.1)).result()
    with pytest.raises(GearlabInputError, match="no reference values"):
        StandardiserAccumulator().result()


def test_fewer_than_two_pulses():
    theta = angle_from_speed(12_000, FS, SPEED, phase=0.5)  # 0.5 … 10 rad: one rising edge (2π)
    pulses = np.where(np.mod(theta, TWO_PI) < np.pi, 1.0, 0.0)
    with pytest.raises(GearlabInputError, match="1 rising edge"):
        angle_from_pulses(pulses, FS)
    with pytest.raises(GearlabInputError, match="constant"):
        angle_from_pulses(np.ones(500), FS)


def test_mismatched_lengths_and_sources():
    theta = angle_from_speed(20_000, FS, SPEED)
    with pytest.raises(GearlabInputError, match="signal has 19999 samples but the angle has 20000"):
        resample_revolutions(np.zeros(19_999), theta)
    with pytest.raises(GearlabInputError, match="exactly one of tacho, pulses or speed_hz"):
        cut_revolutions(np.zeros(20_000), FS, tacho=wrap(theta), speed_hz=SPEED)
    with pytest.raises(GearlabInputError, match="at least 2 are needed"):
        steady_start(np.zeros((1, 8)))


def test_band_limiting_keeps_the_orders_asked_for_and_nothing_else():
    """band_limited: orders up to max_order kept exactly, none above; with points, the rows at
    that many angles, as the full band-limited row sampled there; nothing to cut, the rows as
    they are."""
    from gearlab.signals.indicators import band_limited

    theta = 2 * np.pi * np.arange(4096) / 4096
    x = np.stack([np.cos(3 * theta) + 0.5 * np.sin(700 * theta + k) + 0.2 * np.cos(1500 * theta) for k in range(3)])
    low = band_limited(x, max_order=1000)
    assert np.allclose(low, x - 0.2 * np.cos(1500 * theta))
    assert np.allclose(band_limited(x, max_order=600), np.cos(3 * theta))
    short = band_limited(x, 1024, max_order=600)
    assert short.shape == (3, 1024) and np.allclose(short, np.cos(3 * theta[::4]))
    assert np.allclose(band_limited(x, 2048), low[..., ::2])  # orders below 1024: order 1500 goes
    assert band_limited(x) is x and band_limited(x, 4096, max_order=2048) is x and band_limited(x, 8192) is x
