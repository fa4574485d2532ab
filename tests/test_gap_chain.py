"""The measurement chain (gearlab.data.chain) and the diagnosis's reuse of its sampled rows."""

import math

import numpy as np
import pytest

from gearlab.data.chain import Chain, measure, sampled, tracked
from gearlab.data.spec import dataset_preset
from gearlab.gap import diagnose as d
from gearlab.gap import identify, scoring
from gearlab.gap import search as gap_search
from gearlab.signals.indicators import band_limited

SOURCE = dataset_preset("B-6-ch5").with_(healthy=6)


def test_sampled_rows_are_the_fourier_series_at_the_record_times():
    """Each row is its own revolution's Fourier series below the record's Nyquist order, read at
    the sample times u = (k - 1 - frac) / per_rev + offset (revolutions), whatever the start."""
    rng = np.random.default_rng(3)
    P = 256
    X = rng.normal(size=(3, P))
    chain = Chain(fs=40.0 * 97.3, speed=40.0, fractions=(0.1, 0.77, 0.5))
    offset = 0.9
    x, u = sampled(X, chain, offset)
    max_order = math.ceil(chain.nyquist_order) - 1
    m = np.arange(max_order + 1)
    for i, frac in enumerate(sorted(chain.fractions)):  # as many rows as fractions: each once
        np.testing.assert_allclose(u[i], (np.arange(u.shape[1]) - 1.0 - frac) / chain.samples_per_rev)
        F = np.fft.rfft(X[i])[: max_order + 1] / P
        F[1:] *= 2.0
        angles = u[i] + offset / (2 * np.pi)
        direct = np.real(np.exp(2j * np.pi * np.outer(angles, m)) @ F)
        np.testing.assert_allclose(x[i], direct, atol=1e-12 * np.abs(direct).max())
    # measure = sampled, then the importer's order tracking (here with no noise and no step)
    np.testing.assert_array_equal(measure(X, chain, None, offset), tracked(x, u, chain, None, P))


def test_the_rows_before_the_noise_are_reused_and_give_the_same_rows():
    """A search re-fits the sensor noise at every point: the deterministic rows, sampled at the
    record's times, are made once per source set, and the rows made again are identical."""
    clean = scoring.source_rows(SOURCE.with_(healthy=1, noise=None))[0]
    chain = Chain(fs=40.0 * 2000.5, speed=40.0, fractions=(0.25, 0.5, 0.75), step=1e-3, reference=clean)
    noise = d.get_registry().get("effect", "sensor_noise")
    scoring._sampled.clear()
    first = scoring.source_rows(SOURCE.with_(effects=(noise.spec({"snr_db": 10.0}),)), 0, chain)
    assert len(scoring._sampled) == 1
    again = scoring.source_rows(SOURCE.with_(effects=(noise.spec({"snr_db": 10.0}),)), 0, chain)
    other = scoring.source_rows(SOURCE.with_(effects=(noise.spec({"snr_db": 3.0}),)), 0, chain)
    assert len(scoring._sampled) == 1  # another noise level: the same deterministic rows
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)
    scoring._sampled.clear()
    fresh = scoring.source_rows(SOURCE.with_(effects=(noise.spec({"snr_db": 3.0}),)), 0, chain)
    np.testing.assert_array_equal(fresh, other)
    # the cached samples are shared: nobody may change them in place
    ((x, _),) = scoring._sampled.values()
    with pytest.raises(ValueError):
        x[0, 0] = 1.0


def test_the_order_bands_end_at_the_records_passband():
    """Above a record's passband both sets hold only floating-point rounding (-290 dB): the bands
    end at the highest order compared, and a change of the arithmetic at 1e-14 no longer moves
    the gap (it moved a null target's from 1.4 to 2.5, p 0.30 to 0.04)."""
    from gearlab.gap.stats import gap_report
    from gearlab.gap.views import BandPlan

    plan = BandPlan.make(4096, (25, 30), highest=792)
    assert plan.nyquist == 792 and plan.harmonics * 25 + plan.sidebands < plan.floor_start
    orders = np.concatenate([o for bands in plan.bands().values() for _, o in bands])
    assert orders.max() == 792
    assert BandPlan.make(4096, (25, 30), highest=5000) == BandPlan.make(4096, (25, 30), highest=2048)
    with pytest.raises(Exception, match="passband"):
        BandPlan.make(4096, (25, 30), highest=20)

    rng = np.random.default_rng(1)
    clean = scoring.source_rows(SOURCE.with_(healthy=1, noise=None))[0]
    source = band_limited(clean + rng.normal(0, 0.03 * clean.std(), (40, 4096)), max_order=700)
    target = band_limited(clean + rng.normal(0, 0.03 * clean.std(), (40, 4096)), max_order=700)
    nudged = band_limited(source * (1 + 1e-13), max_order=700)
    gaps = [
        gap_report(X, target, (25, 30), bootstrap=0, permutations=50, max_order=700)["total"]["gap"]
        for X in (source, nudged)
    ]
    assert gaps[1] == pytest.approx(gaps[0], rel=1e-6)


class _FilterLike:
    """A search space like sensor_lowpass's: a corner frequency (log) and an order of 1-8 poles."""

    def space(self):
        return [
            {"name": "f_c", "low": 100.0, "high": 1e5, "default": 5e3, "integer": False, "log": True},
            {"name": "order", "low": 1, "high": 8, "default": 4, "integer": True, "log": False},
        ]


def _filter_score(params):
    # a narrow valley whose best corner moves with the order, the true order (3) best: about the
    # scores of the 3-pole low-pass target (1e4 at 2 % off the corner, 3e4-1e5 at the next orders)
    corner = 6400.0 * 1.15 ** (params["order"] - 3)
    return 2e7 * math.log(params["f_c"] / corner) ** 2 + 3e4 * abs(params["order"] - 3)


@pytest.mark.parametrize("profiled", [True, False])
def test_an_ordinal_parameter_is_profiled_not_left_where_the_design_found_it(profiled, monkeypatch):
    """Nelder-Mead on a rounded coordinate stays at the order of the best design point; the
    profile fits the corner at every order (a 3-pole low-pass came back as 5 poles at 7.6 kHz)."""
    if not profiled:
        monkeypatch.setattr(gap_search, "ORDINAL_VALUES", 0)
    space = d.Space(_FilterLike())
    found = []
    for seed in range(8):
        history = gap_search._fit_search(space, _filter_score, 64, seed)
        best = min(history, key=lambda h: h["score"])
        found.append((best["params"]["order"], best["params"]["f_c"]))
    right = [order == 3 and abs(f_c / 6400.0 - 1) < 0.01 for order, f_c in found]
    if profiled:
        assert all(right), found
    else:  # what the profile is for: without it, the search misses on some seeds
        assert not all(right), found


def test_a_local_refit_starts_small_and_converges():
    """A re-fit from fitted values (no design) starts from a small simplex: from 0.6 % off it gets
    to the optimum within the backfitting's evaluations (with the design's 0.35-wide simplex it
    stayed 0.6 % off, and a second effect was accepted for the residual)."""
    space = d.Space(_FilterLike())
    start = {"f_c": 6400.0 * 1.006, "order": 3}
    history = gap_search._fit_search(space, _filter_score, 32, 0, start=start)
    best = min(history, key=lambda h: h["score"])
    assert best["params"]["f_c"] == pytest.approx(6400.0, rel=5e-4)


def test_the_rows_take_the_targets_start_fractions_at_even_quantiles():
    """The importer's interpolation loss depends on where a revolution starts between samples, so
    the source's rows take the target's start fractions as they are distributed over its record.
    Near a whole number of samples per revolution they drift slowly: the first 40 of 79 covered half
    the range (a null target "significant" at p 0.002 on every seed, the TSA residual 0.5 dB high in
    every sector); at 1614.25 samples per revolution they take 4 values in turn, and every other one
    of them saw only 2."""

    def taken(fractions, rows):
        chain = Chain(fs=40.0 * 300.5, speed=40.0, fractions=tuple(fractions))
        _, u = sampled(np.zeros((rows, 64)), chain)
        return -1.0 - u[:, 0] * chain.samples_per_rev  # u of sample 0 is (-1 - frac) / per_rev

    drifting = [(k * 0.9875) % 1.0 for k in range(79)]
    got = taken(drifting, 40)
    assert got.min() < 0.05 and got.max() > 0.95 and len(np.unique(np.round(got, 6))) == 40
    quarters = [0.25 * (k % 4) for k in range(79)]
    got = np.round(taken(quarters, 40), 9)
    assert {v: int(np.sum(got == v)) for v in (0.0, 0.25, 0.5, 0.75)} == {0.0: 10, 0.25: 10, 0.5: 10, 0.75: 10}
    whole = [0.25 * (k % 4) for k in range(80)]  # more rows than fractions: each value as often
    np.testing.assert_allclose(np.sort(taken(whole, 200)), np.repeat([0, 0.25, 0.5, 0.75], 50), atol=1e-9)


def test_a_whole_number_found_alone_within_the_noise_is_determined():
    """A filter's order: the orders next to the best were evaluated and are worse beyond the score's
    noise; nothing lies between, so its interval is the one order (extended to its neighbours it
    read [2, 4] and "not identifiable" for an order found exactly)."""
    space = d.Space(_FilterLike())
    history = [
        {"params": {"f_c": 6400.0 * 1.15 ** (n - 3), "order": n}, "score": _filter_score({"f_c": 6400.0, "order": n})}
        for n in range(1, 9)
    ]
    best = min(history, key=lambda h: h["score"])
    intervals = identify._intervals(space, history, best, noise=10.0)
    assert intervals["order"] == [3.0, 3.0] and identify.determined(space, intervals)["order"]["determined"]
    wide = identify._intervals(space, history, best, noise=1e9)  # every order within the noise
    assert wide["order"] == [1.0, 8.0] and not identify.determined(space, wide)["order"]["determined"]


@pytest.mark.parametrize("consecutive", [True, False])
def test_consecutive_rows_carry_a_tone_from_one_revolution_into_the_next(consecutive):
    """A measured record's revolutions follow one another: a tone that is not shaft-synchronous runs
    on across them. With consecutive=True the source's rows are made so (its line in the record read
    end to end is as narrow as one bin); made one revolution at a time, each row starts the tone at
    its own phase and the line spreads (a 37.3 Hz tone at 40 Hz was fitted at 55 Hz so)."""
    from gearlab.effects import effect_spec

    speed = 40.0
    chain = Chain(fs=speed * 1700.25, speed=speed, fractions=(0.0, 0.25, 0.5, 0.75))
    spec = SOURCE.with_(healthy=16, noise=None, effects=(effect_spec("interference_tone", frequency=37.3, ratio=1.0),))
    plain = scoring.source_rows(SOURCE.with_(healthy=16, noise=None), 0, chain, consecutive)
    residual = (scoring.source_rows(spec, 0, chain, consecutive) - plain).reshape(-1)  # the tone alone, end to end
    power = np.abs(np.fft.rfft(residual)) ** 2
    line = round(37.3 / speed * 16)  # the record's bins are 1/16 order apart
    near = power[line - 1 : line + 2].sum() / power.sum()
    if consecutive:
        assert near > 0.9, near
    else:
        assert near < 0.7, near


def test_consecutive_rows_are_read_through_their_neighbours_not_wrapped_onto_themselves():
    """Read one revolution at a time, a row's Fourier series wraps its end onto its start; a tone that
    runs on across rows jumps there, and the jump rang in every row with the tone's phase (images at
    k +- the tone's order, 11 dB under a 1.25-order tone). With record=True each row is read through
    itself and its two neighbours: at the record's sample times it is the tone itself."""
    P, n, order = 512, 8, 0.31
    chain = Chain(fs=40.0 * 201.37, speed=40.0, fractions=(0.2, 0.6))
    theta = np.arange(n * P) / P  # revolutions, the record end to end
    X = np.sin(2 * np.pi * order * theta + 0.4).reshape(n, P)
    x, u = sampled(X, chain, 0.0, record=True)
    assert x.shape[0] == n - 2  # the first and last rows are neighbours only
    frac = np.sort(chain.fractions)[((np.arange(n - 2) + 0.5) * 2 / (n - 2)).astype(int)]
    for i in range(n - 2):
        np.testing.assert_allclose(u[i], (np.arange(u.shape[1]) - 1.0 - frac[i]) / chain.samples_per_rev)
        truth = np.sin(2 * np.pi * order * (i + 1 + u[i]) + 0.4)  # row i + 1 of the record
        # what is left: the three-revolution series' own wrap, a revolution away (2.5e-4 at P = 512)
        assert np.max(np.abs(x[i] - truth)) < 1e-3
    one, _ = sampled(X[1:-1], chain, 0.0)  # each row alone: wrapped onto itself
    assert np.max(np.abs(one - np.sin(2 * np.pi * order * (np.arange(1, n - 1)[:, None] + u) + 0.4))) > 0.1


def test_the_search_scores_a_sub_order_tone_by_the_records_lines(tmp_path):
    """One revolution sees a 7.3 Hz tone at 40 Hz (0.18 orders) as a slow drift: the per-revolution
    score barely tells its frequency 3 % off from the truth. With consecutive rows the score adds the
    record's fractional lines (gearlab.gap.views.record_view, blocks of 10 revolutions): 3 % off then
    scores far above the truth, which stays near 0 (bias-corrected)."""
    from gearlab.effects import effect_spec
    from gearlab.kinds.gap_benchmark import trials as bench

    source = SOURCE.with_(faults=(), healthy=40, noise=bench.BASE_NOISE)  # the default search's rows
    truth = {"frequency": 7.29, "ratio": 0.22}
    trial = bench.Trial(
        0,
        "suborder",
        (effect_spec("interference_tone", **truth),),
        None,
        ("interference_tone", "sensor_noise"),
        7,
        bench.Acquisition(0.45, 1.0, "npz"),
    )
    rows, chain, max_order = bench.import_target(bench.write_target(trial, source, tmp_path, 80))
    settings = d.Settings(candidates=trial.candidates, max_order=max_order, healthy=40)
    target, chain, R, settings, pair, search, _ = d._prepared(source, rows, settings, chain)
    assert R.consecutive

    def scores(consecutive: bool) -> list[float]:
        scorer = d.Scorer(target, pair, settings.max_order, consecutive)
        tones = [{**truth, "frequency": truth["frequency"] * k} for k in (1.0, 1.03)]
        return [scorer.score(R(search.with_(effects=(effect_spec("interference_tone", **t),)))) for t in tones]

    (right, off), (plain_right, plain_off) = scores(True), scores(False)
    assert plain_off - plain_right < 20.0  # per revolution: 3 % off within the score's noise
    assert abs(right - plain_right) < 20.0 and off - right > 100.0
