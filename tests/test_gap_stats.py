"""Gap statistics (docs/gap_stats.md; gearlab/gap): the views, the per-view gap and its
shares, the two-sample tests, the input checks.

Synthetic revolutions are a spur-gear signature in the angle domain (4096 points per
revolution, a 25-tooth pinion: mesh harmonics at orders 25, 50, 75, 100) plus white noise;
each test changes one thing in the target and checks the numbers the report gives for it.
Real data: tiny healthy sets of Dataset B, built into a temporary cache."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gearlab.data.cache import load_or_build
from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.errors import GearlabInputError
from gearlab.gap.stats import MIN_REVOLUTIONS, gap_report
from gearlab.gap.views import (
    BandPlan,
    LatentBasis,
    gear_pair_of,
    healthy_rows,
    network_embed,
    order_power,
    order_views,
    tsa_residual_view,
    waveform_view,
)

P = 4096
Z1, Z2 = 25, 30  # meng2020, Dataset B
THETA = 2.0 * np.pi * np.arange(P) / P
MESH = (1.0, 0.5, 0.3, 0.2)  # amplitudes of the mesh harmonics 1x..4x
NOISE = 0.1  # white-noise standard deviation of every revolution
FAST = {"bootstrap": 100, "permutations": 200}  # enough for the assertions, quick


def gear(mesh=MESH, am: float = 0.0, impact: float = 0.0) -> np.ndarray:
    """One clean revolution: mesh harmonics, optionally amplitude-modulated at shaft order 1
    (eccentricity-like) and with a once-per-revolution impact (an impulsive signature)."""
    x = sum(a * np.cos(k * Z1 * THETA + 0.4 * k) for k, a in enumerate(mesh, start=1))
    x = x * (1.0 + am * np.cos(THETA))
    return x + impact * np.exp(-0.5 * ((np.arange(P) - 1000) / 4.0) ** 2)


def revolutions(n: int, seed: int, noise: float = NOISE, tone: float = 0.0, **signal) -> np.ndarray:
    """n revolutions of the clean signal with independent white noise; *tone*: the amplitude of
    a line at order 37.5 with a random phase per revolution (not locked to the shaft)."""
    rng = np.random.default_rng(seed)
    X = gear(**signal) + noise * rng.standard_normal((n, P))
    if tone:
        X += tone * np.cos(37.5 * THETA + rng.uniform(0.0, 2.0 * np.pi, (n, 1)))
    return X


def feature(report: dict, view: str, name: str) -> dict:
    v = report["views"][view]
    i = v["names"].index(name)
    return {"effect": v["effect"][i], **next((t for t in v["top"] if t["feature"] == name), {})}


def largest_view(report: dict) -> str:
    return max(report["views"], key=lambda name: report["views"][name]["share"])


# --- views ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "points, pair", [(4096, (25, 30)), (4096, (16, 48)), (1024, (25, 30)), (70, (25, 30)), (4095, (16, 48))]
)
def test_order_bands_cover_every_order_once(points, pair):
    # The five order views partition orders 1..P/2: each order in exactly one band, so the
    # band powers add up to the row's mean square less its DC.
    plan = BandPlan.make(points, pair)
    orders = np.concatenate([o for bands in plan.bands().values() for _, o in bands])
    assert np.array_equal(np.sort(orders), np.arange(1, points // 2 + 1))
    x = np.random.default_rng(0).standard_normal((3, points))
    power = order_power(x)
    assert np.allclose(power.sum(axis=1), np.mean(x * x, axis=1))  # Parseval
    total = sum((10 ** (v.features / 10)).sum(axis=1) for v in order_views(x, pair, plan))
    assert np.allclose(total, power[:, 1:].sum(axis=1))


def test_band_layout_for_dataset_b():
    plan = BandPlan.make(P, (Z1, Z2))
    bands = plan.bands()
    assert [name for name, _ in bands["shaft"]] == ["shaft 1x (order 1)", "shaft 2x (order 2)", "shaft 3x (order 3)"]
    assert bands["mesh"][1][0] == "mesh 2x (order 50)" and plan.harmonics == 61  # 61·25 + 3 < 1536 = 3/4 · 2048
    assert bands["sidebands"][0] == ("mesh 1x ±1 (orders 24, 26)", pytest.approx(np.array([24, 26])))
    assert bands["non_synchronous"][0][0] == "orders 4-21 (below mesh 1x)"
    assert bands["non_synchronous"][1][0] == "orders 29-46 (mesh 1x-2x)"
    assert bands["noise_floor"][0][1][0] == 1536 and len(bands["noise_floor"]) == 4


def test_order_views_read_a_line_at_its_level():
    # A line A·cos(50θ) carries A²/2: mesh 2x of the clean signal reads 10·log10(0.5²/2) dB.
    views = {v.name: v for v in order_views(gear()[None, :], (Z1, Z2))}
    mesh = views["mesh"]
    assert mesh.features[0, 1] == pytest.approx(10 * np.log10(0.5**2 / 2), abs=1e-9)
    assert mesh.features[0, 4] < -250  # no 5x line at all: the -300 dB floor, not -inf


def test_tsa_residual_leave_one_out_matches_new_rows():
    # A set's residual against its own mean would read (1 - 1/n) low: leave-one-out makes the
    # source's residual energy the same as that of new rows against the source's mean.
    source, target = revolutions(40, 1), revolutions(400, 2)
    own = tsa_residual_view(source, (Z1, Z2))
    new = tsa_residual_view(target, (Z1, Z2), reference=source.mean(axis=0))
    assert own.size == Z1 and own.names[0] == "sector 1 (0.0-14.4 deg)"
    # White noise of variance 0.01 per sample, less the 1/... share of the DC and mesh lines removed.
    assert np.mean(own.features) == pytest.approx(np.mean(new.features), abs=0.05)
    assert np.mean(new.features) == pytest.approx(10 * np.log10(NOISE**2), abs=0.2)


def test_waveform_statistics_of_known_signals():
    rng = np.random.default_rng(0)
    tone = np.sqrt(2.0) * np.cos(5 * THETA)
    gauss = rng.standard_normal(200_000)[None, :]
    w = waveform_view(np.stack([tone, 3.0 + 0 * tone]))
    names = dict(zip(w.names, w.features[0]))
    assert names["rms"] == pytest.approx(1.0) and names["crest_factor"] == pytest.approx(np.sqrt(2.0))
    assert names["kurtosis"] == pytest.approx(1.5) and names["skewness"] == pytest.approx(0.0, abs=1e-9)
    assert names["peak_to_peak"] == pytest.approx(2 * np.sqrt(2.0))
    assert dict(zip(w.names, w.features[1]))["mean"] == 3.0  # a constant row stays finite
    assert np.all(np.isfinite(w.features))
    assert dict(zip(w.names, waveform_view(gauss).features[0]))["kurtosis"] == pytest.approx(3.0, abs=0.05)


# --- no gap -----------------------------------------------------------------------------------------


def test_identical_distributions_show_no_gap():
    report = gap_report(revolutions(40, 1), revolutions(40, 2), (Z1, Z2), seed=0)
    assert abs(report["auc"] - 0.5) < 0.15
    assert report["p_value"] > 0.05 and not report["significant"]
    assert report["total"]["gap"] < 5  # vs thousands below; bias-corrected, so near 0
    assert any("no significant gap" in note for note in report["notes"])
    json.dumps(report, allow_nan=False)


def test_false_positive_rate_is_near_alpha():
    # 100 pairs of sets drawn from one distribution (smaller: 512 points, 16 teeth, 20 rows):
    # the permutation test must reject about 5 % of them at alpha = 0.05 — the residual's
    # leave-one-out average is what keeps it so (against a set's own full mean: ~45 %).
    small = 2.0 * np.pi * np.arange(512) / 512
    clean = np.cos(16 * small) + 0.5 * np.cos(32 * small + 1) + 0.2 * np.cos(small)
    rejections, aucs = 0, []
    for seed in range(100):
        rng = np.random.default_rng(seed)
        source = clean + 0.2 * rng.standard_normal((20, 512))
        target = clean + 0.2 * rng.standard_normal((20, 512))
        report = gap_report(source, target, (16, 48), seed=seed, bootstrap=0, permutations=200)
        rejections += report["significant"]
        aucs.append(report["auc"])
    assert 1 <= rejections <= 10  # Binomial(100, 0.05): outside this 1.7 % of the time
    assert abs(np.mean(aucs) - 0.5) < 0.03


# --- one effect at a time: where the gap lands ---------------------------------------------------


def test_non_synchronous_tone_lands_in_the_non_synchronous_view():
    tone = 0.03  # -27 dB below the signal: small, not locked to the shaft (order 37.5, random phase)
    report = gap_report(revolutions(40, 1), revolutions(40, 2, tone=tone), (Z1, Z2), **FAST)
    assert report["significant"] and report["auc"] > 0.9
    view = report["views"]["non_synchronous"]
    assert largest_view(report) == "non_synchronous"
    assert view["share"] > 0.7 and view["share_interval"][0] > 0.5
    top = view["top"][0]
    assert top["feature"] == "orders 29-46 (mesh 1x-2x)"
    # Noise in the band's 18 orders: 18 · 2σ²/P; the tone adds A²/2 (97 % of it within the band).
    noise = 18 * 2 * NOISE**2 / P
    expected = 10 * np.log10((noise + 0.97 * tone**2 / 2) / noise)
    assert top["delta"] == pytest.approx(expected, abs=0.7)
    assert report["top_features"][0]["feature"] == top["feature"]


def test_white_noise_raises_the_noise_floor_and_lowers_kurtosis_and_crest():
    # An impulsive healthy signature (a once-per-revolution impact): more broadband noise
    # raises every noise-floor band by 20·log10(0.3/0.1) = 9.54 dB and buries the impact,
    # so kurtosis and crest factor fall; RMS rises.
    source = revolutions(40, 1, impact=6.0)
    target = revolutions(40, 2, noise=0.3, impact=6.0)
    report = gap_report(source, target, (Z1, Z2), **FAST)
    assert report["significant"]
    floor = report["views"]["noise_floor"]
    assert len(floor["top"]) == 4
    for band in floor["top"]:
        assert band["delta"] == pytest.approx(20 * np.log10(3.0), abs=0.2)
        assert band["effect"] > 10
    waveform = report["views"]["waveform"]
    effects = dict(zip(waveform["names"], waveform["effect"]))
    assert effects["kurtosis"] < -3 and effects["crest_factor"] < -1 and effects["rms"] > 3
    # Broadband: the residual sectors all rise too, and the mesh lines (far above the noise) barely move.
    assert min(report["views"]["tsa_residual"]["effect"]) > 5
    assert report["views"]["mesh"]["share"] < 0.05


def test_shaft_order_modulation_shows_in_the_sidebands():
    # (1 + 0.05 cos θ) on the mesh signal — eccentricity-like — puts lines at k·Z1 ± 1 of
    # amplitude 0.025·a_k: the ±1 sidebands, not ±2 or ±3, and most of the gap.
    report = gap_report(revolutions(40, 1), revolutions(40, 2, am=0.05), (Z1, Z2), **FAST)
    assert report["significant"] and largest_view(report) == "sidebands"
    side = report["views"]["sidebands"]
    assert side["share"] > 0.6
    assert [t["feature"] for t in side["top"][:4]] == [
        f"mesh {k}x ±1 (orders {25 * k - 1}, {25 * k + 1})" for k in (1, 2, 3, 4)
    ]
    # Sideband pair power 2·(0.025)²/2 over the noise in two orders (4σ²/P); the noise-only
    # band's mean in dB is 1.17 dB below its level (log of a chi-square with 4 degrees of freedom).
    expected = 10 * np.log10((0.025**2 + 4 * NOISE**2 / P) / (4 * NOISE**2 / P)) + 1.17
    assert side["top"][0]["delta"] == pytest.approx(expected, abs=1.5)
    effects = dict(zip(side["names"], side["effect"]))
    assert abs(effects["mesh 1x ±2 (orders 23, 27)"]) < 1 and abs(effects["mesh 1x ±3 (orders 22, 28)"]) < 1
    # Where in the revolution: the modulation's deviation (0.05 cos θ · mesh) is largest near
    # 0° and 180°, and vanishes near 90° and 270°.
    residual = dict(zip(report["views"]["tsa_residual"]["names"], report["views"]["tsa_residual"]["effect"]))
    assert residual["sector 1 (0.0-14.4 deg)"] > residual["sector 7 (86.4-100.8 deg)"] + 1
    assert residual["sector 13 (172.8-187.2 deg)"] > residual["sector 19 (259.2-273.6 deg)"] + 1


def test_mesh_harmonic_amplitude_shows_in_the_mesh_bands():
    # Mesh 2x amplitude 0.5 -> 0.75: +20·log10(1.5) = 3.52 dB on that band, nothing elsewhere
    # in the spectrum; the waveform statistics move with it (RMS), the residual does not.
    target = revolutions(40, 2, mesh=(1.0, 0.75, 0.3, 0.2))
    report = gap_report(revolutions(40, 1), target, (Z1, Z2), **FAST)
    assert largest_view(report) == "mesh" and report["views"]["mesh"]["share"] > 0.6
    top = report["views"]["mesh"]["top"][0]
    assert top["feature"] == "mesh 2x (order 50)"
    assert top["delta"] == pytest.approx(20 * np.log10(1.5), abs=0.02)
    assert report["views"]["tsa_residual"]["share"] < 0.01
    for quiet in ("shaft", "sidebands", "non_synchronous", "noise_floor"):
        assert report["views"][quiet]["share"] < 0.01, quiet


def test_shares_add_up_and_intervals_hold_the_estimate():
    report = gap_report(revolutions(40, 1), revolutions(40, 2, am=0.05, tone=0.03), (Z1, Z2), **FAST)
    views = report["views"]
    assert sum(v["share"] for v in views.values()) == pytest.approx(1.0)
    assert sum(v["gap"] for v in views.values()) == pytest.approx(report["total"]["gap"])
    for name, v in views.items():
        lo, hi = v["share_interval"]
        assert 0.0 <= lo <= hi <= 1.0, name
        if v["share"] > 0.1:
            assert lo <= v["share"] <= hi, name
    lo, hi = report["total"]["interval"]
    assert lo <= report["total"]["gap"] <= hi
    assert report == gap_report(revolutions(40, 1), revolutions(40, 2, am=0.05, tone=0.03), (Z1, Z2), **FAST)


def test_output_shaft_orders_from_consecutive_revolutions():
    # A modulation locked to the output shaft (order Z1/Z2 = 0.833) in one long record cut into
    # consecutive revolutions: blocks of Z2/gcd = 6 revolutions resolve it on its own line.
    n, points = 120, 1024
    theta = 2.0 * np.pi * np.arange(n * points) / points

    def record(depth: float, seed: int) -> np.ndarray:
        mesh = np.cos(Z1 * theta) + 0.5 * np.cos(2 * Z1 * theta)
        noise = NOISE * np.random.default_rng(seed).standard_normal(n * points)
        return (mesh * (1.0 + depth * np.cos(Z1 / Z2 * theta)) + noise).reshape(n, points)

    report = gap_report(record(0.0, 1), record(0.05, 2), (Z1, Z2), consecutive=True, **FAST)
    out = report["output_shaft"]
    assert out["blocks"] == [20, 20] and out["revolutions_per_block"] == 6
    assert out["top"][0]["feature"] == "mesh ± output 1x (15 harmonics)" and out["top"][0]["effect"] > 5
    assert "share" not in out  # one row per block: outside the per-revolution shares
    # Without consecutive rows the same modulation leaks into the integer orders, and the report says so.
    plain = gap_report(record(0.0, 1), record(0.05, 2), (Z1, Z2), **FAST)
    assert "output_shaft" not in plain and any("orders of the output shaft" in note for note in plain["notes"])
    assert plain["significant"]
    json.dumps(report, allow_nan=False)
    # too few source rows for 10 blocks: the note says which set is short, and where its count is set
    short = gap_report(record(0.0, 1)[:40], record(0.05, 2), (Z1, Z2), consecutive=True, **FAST)
    said = "got 6 blocks (the source's 40: [diagnosis] healthy; the target's 120: its records together)"
    assert short["output_shaft"] is None and any(said in note for note in short["notes"]), short["notes"]


def test_noise_free_source_stays_finite_and_is_flagged():
    source = np.tile(gear(), (20, 1))  # a deterministic simulation: every revolution the same
    report = gap_report(source, revolutions(20, 2), (Z1, Z2), **FAST)
    assert any("all identical" in note for note in report["notes"])
    assert report["significant"]
    json.dumps(report, allow_nan=False)


# --- latent features ------------------------------------------------------------------------------


def test_latent_view_from_a_network_and_from_a_wide_layer():
    from gearlab.learn.networks import build_network

    source, target = revolutions(20, 1), revolutions(20, 2, am=0.2)
    report = gap_report(source, target, (Z1, Z2), embed=network_embed(build_network("fast", 2, seed=0)), **FAST)
    latent = report["views"]["latent"]
    assert latent["features"] == 64 and latent["names"][0] == "unit 1"  # the fast network's 64 units as they are
    # A layer wider than 64 units is compared on its 8 leading principal components (both sets pooled).
    wide = LatentBasis.fit(source, target)
    assert wide.components.shape == (8, P)
    report = gap_report(source, target, (Z1, Z2), embed=lambda X: X[:, ::8], **FAST)
    assert report["views"]["latent"]["names"][:2] == ["PC1", "PC2"]


# --- real simulated data (Dataset B, tiny) ----------------------------------------------------------


@pytest.fixture(scope="module")
def dataset_b(tmp_path_factory):
    import os

    before = os.environ.get("GEARLAB_CACHE")
    os.environ["GEARLAB_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    try:

        def healthy(name: str, noise_seed: int):
            spec = dataset_preset(name).with_(
                faults=(), teeth=(1,), healthy=40, noise=NoiseSpec("gaussian", 10.0, noise_seed)
            )
            return load_or_build(spec)[0]

        yield {"B-6": healthy("B-6-ch5", 1), "B-6 other noise": healthy("B-6-ch5", 2), "B-8": healthy("B-8-ch5", 1)}
    finally:
        if before is None:
            os.environ.pop("GEARLAB_CACHE", None)
        else:
            os.environ["GEARLAB_CACHE"] = before


def test_dataset_b_six_vs_eight_dof_is_a_significant_gap(dataset_b):
    six, eight = dataset_b["B-6"], dataset_b["B-8"]
    pair = gear_pair_of(six.spec)
    assert (pair.Z1, pair.Z2) == (Z1, Z2)
    report = gap_report(healthy_rows(six), healthy_rows(eight), pair, **FAST)
    assert report["significant"] and report["p_value"] < 0.01 and report["auc"] > 0.95
    # The motor and load inertias move the resonances: the mesh harmonics change level
    # (and in physical units the RMS with them).
    assert largest_view(report) in ("mesh", "waveform")
    assert report["views"]["mesh"]["share"] > 0.2
    assert max(abs(t["delta"]) for t in report["views"]["mesh"]["top"]) > 3  # dB


def test_dataset_b_six_dof_with_another_noise_seed_is_no_gap(dataset_b):
    six, again = dataset_b["B-6"], dataset_b["B-6 other noise"]
    report = gap_report(healthy_rows(six), healthy_rows(again), gear_pair_of(six.spec), **FAST)
    assert not report["significant"] and abs(report["auc"] - 0.5) < 0.2


# --- bad inputs ---------------------------------------------------------------------------------------


def _message(excinfo) -> str:
    text = str(excinfo.value)
    assert "\n" not in text  # one line, for the CLI
    return text


def test_no_healthy_data(dataset_b):
    with pytest.raises(GearlabInputError) as e:
        gap_report(np.empty((0, P)), revolutions(20, 1), (Z1, Z2))
    assert "no healthy source data" in _message(e)
    faulty = dataset_b["B-6"]
    faulty = type(faulty)(**{**faulty.__dict__, "label": np.ones_like(faulty.label)})
    with pytest.raises(GearlabInputError) as e:
        healthy_rows(faulty)
    assert "has no healthy revolutions" in _message(e)


def test_too_few_revolutions():
    with pytest.raises(GearlabInputError) as e:
        gap_report(revolutions(20, 1), revolutions(MIN_REVOLUTIONS - 1, 2), (Z1, Z2))
    assert f"too few healthy target revolutions for the gap statistics: {MIN_REVOLUTIONS - 1}" in _message(e)
    assert f"at least {MIN_REVOLUTIONS} per set" in _message(e)


def test_sample_length_mismatch():
    with pytest.raises(GearlabInputError) as e:
        gap_report(revolutions(20, 1), revolutions(20, 2)[:, ::2], (Z1, Z2))
    assert "sample length mismatch: source revolutions have 4096 samples, target revolutions 2048" in _message(e)


def test_too_few_points_per_revolution_for_the_mesh_harmonics():
    rows = np.random.default_rng(0).standard_normal((20, 50))
    with pytest.raises(GearlabInputError) as e:
        gap_report(rows, rows, (Z1, Z2))
    text = _message(e)
    assert "50 points per revolution are too few for a 25-tooth pinion" in text
    assert "P/2 = 25 must exceed the first mesh order 25 plus its 3 sidebands (28)" in text
    assert "at least 58 points per revolution" in text


@pytest.mark.parametrize(
    "bad, expected",
    [
        ({"source_X": np.full((20, P), np.nan)}, "contains NaN"),
        ({"source_X": np.zeros(P)}, "must be 2-D"),
        ({"pair": (25,)}, "gear pair must be"),
        ({"pair": (2, 30)}, "Z1 must be a whole number of teeth >= 3"),
        ({"pair": "nope"}, "unknown gear-pair preset 'nope'"),
        ({"bootstrap": -1}, "bootstrap must be a whole number >= 0"),
        ({"alpha": 1.5}, "alpha must lie strictly between 0 and 1"),
        ({"embed": lambda X: np.ones((3, 2))}, "embed(source rows) must return an (n, d) array for 20 rows"),
    ],
)
def test_bad_inputs_get_one_clear_line(bad, expected):
    args = {
        "source_X": revolutions(20, 1),
        "target_X": revolutions(20, 2),
        "pair": (Z1, Z2),
        "bootstrap": 0,
        "permutations": 20,
    }
    with pytest.raises(GearlabInputError) as e:
        gap_report(**{**args, **bad})
    assert expected in _message(e)
