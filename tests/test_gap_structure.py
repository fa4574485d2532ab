"""Structure before effects (gearlab/gap/structure.py, issue 39 item 4): a tooth count, a speed or a
pure scale factor that differs between the source and the target ends the diagnosis with one line
saying what differs, before any effect is searched; two nulls written outside gearlab (an int16 WAV
without its gain, a 200 kHz record with its noise added at that rate) invent no gap; the run's
log line and its report say the same verdict, and every parameter row says which fit it is."""

import warnings

import numpy as np
import pytest
from gearboxes import described_pair

import gearlab.kinds.gap_benchmark.trials as bench
from gearlab.data.builder import build_dataset
from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.effects import effect_spec
from gearlab.gap.diagnose import Settings, diagnose
from gearlab.gap.structure import later_combs, later_stages, level_line, mesh_check, speed_line
from gearlab.gap.views import healthy_rows
from gearlab.kinds.gap import ranking_md, verdict_text
from gearlab.kinds.gap_verdict import gap_lines

SOURCE = dataset_preset("B-6-ch5").with_(faults=(), healthy=24, noise=NoiseSpec("gaussian", 30.0, 1))
FAST = dict(healthy=24, bootstrap=20, permutations=99, budget=4, seed=0, max_effects=1)
CANDIDATES = ("sensor_noise", "sensor_bandwidth")
SPEED = 40.0  # B-6-ch5's


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        yield


@pytest.fixture(scope="module")
def clean():
    """The source's noise-free revolutions (41: a record of 40 and a bit)."""
    return healthy_rows(build_dataset(SOURCE.with_(noise=None, healthy=41)))


def retoothed(rows: np.ndarray, z_from: int, z_to: int) -> np.ndarray:
    """Revolutions of a z_to-tooth pinion made from a z_from-tooth one: the line at order h z_from + j
    (a mesh harmonic and its sidebands) moved to h z_to + j, up to order 1000 (above, the moved
    lines would crowd in on one another near the Nyquist order)."""
    F = np.fft.rfft(rows, axis=1)
    G = np.zeros_like(F)
    G[:, 0] = F[:, 0]
    for k in range(1, 1001):
        h = round(k / z_from)
        moved = h * z_to + k - h * z_from
        if 0 < moved < G.shape[1]:
            G[:, moved] += F[:, k]
    return np.fft.irfft(G, n=rows.shape[1], axis=1)


def written(folder, rows: np.ndarray, per_rev: int, snr_db: float, speed: float = SPEED, fmt: str = "npz"):
    """Revolutions (n, 4096) written as a record would be outside gearlab: Fourier-resampled to
    *per_rev* samples per revolution at *speed*, white noise at *snr_db* added at that rate, a
    once-per-revolution pulse tacho; float npz, or an int16 WAV (full-scale fractions) with no gain
    or calibration beside it. Returns (rows, chain, max_order) as the importer reads them."""
    n, points = rows.shape
    F = np.fft.rfft(rows.reshape(-1))
    total = n * per_rev
    G = np.zeros(total // 2 + 1, complex)
    k = min(F.size, G.size)
    G[:k] = F[:k] * total / (n * points)
    x = np.fft.irfft(G, n=total)
    rng = np.random.default_rng(7)
    x = x + rng.standard_normal(x.size) * np.sqrt(np.mean(x**2) * 10 ** (-snr_db / 10))
    tacho = ((np.arange(total) % per_rev) < per_rev // 2).astype(float)
    folder.mkdir(exist_ok=True)
    if fmt == "wav":
        from scipy.io import wavfile

        counts = np.round(x / (4 * np.abs(x).max()) * 32767).astype(np.int16)
        path = folder / "target.wav"
        wavfile.write(path, int(round(per_rev * speed)), np.stack([counts, (tacho * 16000).astype(np.int16)], 1))
    else:
        path = folder / "target.npz"
        record = {bench.VIBRATION: x, bench.TACHO: tacho, bench.LABEL: np.array("healthy")}
        np.savez(path, **record, fs=np.array(per_rev * speed))
    return bench.import_target(path)


def diagnosed(rows, chain=None, max_order=0):
    settings = Settings(candidates=CANDIDATES, max_order=max_order, **FAST)
    return diagnose(SOURCE, rows, settings, chain=chain)


# --- the tooth count ----------------------------------------------------------------------------------


def test_the_mesh_order_is_read_off_the_lines_of_the_target(clean):
    # B-6-ch5's strongest lines are mesh harmonics 4-15 (250 first), its mesh order's own line weak
    assert not mesh_check(clean, 25, 30)["differs"]
    for z in (20, 24, 26):
        found = mesh_check(retoothed(clean, 25, z), 25, 30)
        assert found["differs"] and found["measured"] == pytest.approx(z, abs=1e-3)
    # ... and a source of 50 teeth is told from a 25-tooth target (its odd harmonics are off that comb)
    assert mesh_check(clean, 50, 60)["measured"] == pytest.approx(25, abs=1e-3)
    # a strong interference tone is one line, no other gear: no difference
    toned = healthy_rows(
        build_dataset(SOURCE.with_(effects=(effect_spec("interference_tone", frequency=333.3, ratio=0.5),)))
    )
    assert not mesh_check(toned, 25, 30)["differs"]


def test_a_simulated_target_of_another_tooth_count_ends_in_one_line():
    target = dataset_preset("A-pinion-ch5").with_(faults=(), healthy=24, noise=NoiseSpec("laplace", 0.0, 1))
    result = diagnosed(healthy_rows(build_dataset(target)))
    assert result["verdict"] == "structure differs" and result["effects"] == [] and result["rounds"] == []
    assert result["difference"].startswith(
        "mesh order 16.0 measured, 25 expected: the source simulates a 25-tooth pinion"
    )
    assert verdict_text(result) == f"structure differs: {result['difference']}"


def test_a_measured_file_of_a_20_tooth_pinion_ends_in_one_line(clean, tmp_path, monkeypatch):
    rows, chain, max_order = written(tmp_path / "z20", retoothed(clean, 25, 20), 4099, 30.0)
    assert chain is not None

    def simulated(*args, **kwargs):
        raise AssertionError("the source was simulated")

    # the first stage's teeth are read off the record and the description: the source, another gearbox, is not
    # simulated, for its rows nor for the tacho offset, and no gap is measured
    monkeypatch.setattr("gearlab.gap.scoring.source_rows", simulated)
    monkeypatch.setattr("gearlab.gap.conclusion._clean_revolution", simulated)
    result = diagnosed(rows, chain, max_order)
    assert result["verdict"] == "structure differs" and result["effects"] == []
    assert result["difference"] == (
        "mesh order 20.0 measured, 25 expected: the source simulates a 25-tooth pinion (the target's shows 20 teeth)"
    )
    assert result["before"] is result["after"] is result["gap_before"] is result["significant_before"] is None
    assert result["chain"]["offset_deg"] is None and result["chain"]["speed_hz"] == pytest.approx(40.0)
    summary = {"gap_before": None, "views": {}, "verdict": verdict_text(result)}
    assert gap_lines(summary) == [
        f"Structure differs: {result['difference']}; no effect was searched, no gap measured."
    ]


def test_a_record_at_another_speed_ends_in_one_line(clean, tmp_path):
    rows, chain, max_order = written(tmp_path / "slow", clean, 4099, 30.0, speed=30.0)
    result = diagnosed(rows, chain, max_order)
    assert result["verdict"] == "structure differs" and result["effects"] == []
    assert result["difference"].startswith("speed 30 Hz measured, 40 Hz expected: the source simulates 40 Hz")


def train_rows(stages, seed: int, n: int = 40, points: int = 4096, later: float = 0.3) -> np.ndarray:
    """Revolutions of a train of *stages* ((z1, z2), ...): each mesh's harmonics 1-3, a later
    stage's *later* of the first's, modulated by both of its shafts (sidebands), white noise."""
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * np.arange(n * points) / points
    x, o = np.zeros(theta.size), 1.0
    for k, (z1, z2) in enumerate(stages):
        mod = 1 + 0.2 * np.cos(o * theta) + 0.1 * np.cos(o * z1 / z2 * theta + 1.0)
        for h in (1, 2, 3):
            x += later**k / h * mod * np.cos(h * o * z1 * theta + rng.uniform(0, 6))
        o *= z1 / z2
    return (x + rng.normal(0, 0.05, x.size)).reshape(n, points)


def test_a_later_stage_of_another_tooth_count_ends_in_one_line():
    record = train_rows([(24, 60), (35, 83)], seed=1)
    # the source of the right counts reads as the record does; its mesh 2 at 14 (= 24/60 x 35)
    right = later_stages(record, train_rows([(24, 60), (35, 83)], seed=2), described_pair((24, 60), (35, 83)))
    assert right["line"] is None and right["stages"][0]["target"] == pytest.approx(14.0, abs=1e-3)
    # a 33-tooth second pinion described: its mesh at 13.2, the record's at 14 (two sidebands of the
    # 0.4-order shaft off 13.2, so no comb of the source's tells them apart: its own reading does)
    wrong = later_stages(record, train_rows([(24, 60), (33, 83)], seed=2), described_pair((24, 60), (33, 83)))
    assert wrong["line"].startswith(
        "stage 2: mesh order 14 measured, 13.2 expected: the source simulates a 33-tooth pinion on the "
        "intermediate shaft turning at order 0.4 (the target's mesh is 35.0 such teeth"
    )
    assert later_stages(record, record, described_pair((24, 60))) == {"stages": [], "line": None}


def test_a_second_mesh_as_strong_as_the_first_is_the_sources_own_and_one_tooth_off_is_told():
    # a reducer's second mesh (14) as strong as its first (24): no other pinion, once the source's
    # later stages are its comb too (the first stage's comb alone held 24 x 35/60 = 14's harmonics off it)
    record = train_rows([(24, 60), (35, 83)], seed=3, later=0.9)
    later = later_combs(described_pair((24, 60), (35, 83)))
    assert later == ((14.0, (0.4, pytest.approx(14 / 83))),)
    assert mesh_check(record, 24, 60)["differs"]
    assert not mesh_check(record, 24, 60, later=later)["differs"]
    # a 25-tooth source: the record's 24, 48, 72 sit on its sidebands 25 - 1, 50 - 2, 75 - 3, and no
    # line on its mesh harmonics
    wrong = mesh_check(record, 25, 60, later=later_combs(described_pair((25, 60), (35, 83))))
    assert wrong["on_mesh"] < 0.25 and wrong["differs"] and wrong["measured"] == pytest.approx(24, abs=1e-2)


def test_a_speed_found_from_the_mesh_lines_names_the_tooth_count_it_trades_with():
    # no tacho: only speed x teeth is measured, so a 19-tooth pinion at 28 Hz reads as 20 teeth at 26.6 Hz
    assert speed_line(26.6, 28.0, 20) == (
        "speed 26.6 Hz found from the mesh lines (no tacho), 28 Hz expected: the record's mesh at 532 Hz is a "
        "20-tooth pinion's at 26.6 Hz or a 19-tooth pinion's at 28 Hz: ambiguous (the input shaft's own lines tell "
        "neither): declare the records' speed ([target] speed) or give a tacho, and the diagnosis names what differs"
    )
    assert speed_line(27.0, 28.0, 20).startswith("speed 27 Hz found from the mesh lines (no tacho), 28 Hz expected")
    assert speed_line(27.9, 28.0, 20) is None
    assert speed_line(26.6, 28.0).startswith("speed 26.6 Hz measured, 28 Hz expected")


# --- the level ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("factor", [2.0, 0.25])
def test_a_pure_scale_factor_is_reported_as_such_not_fitted(factor):
    rows = healthy_rows(build_dataset(SOURCE.with_(seed=77, noise=NoiseSpec("gaussian", 30.0, 9))))
    assert diagnosed(rows)["verdict"] == "no significant gap"
    result = diagnosed(rows * factor)
    assert result["verdict"] == "level differs" and result["effects"] == [] and result["rounds"] == []
    assert result["structure"]["level"]["factor"] == pytest.approx(factor, rel=0.02)
    shown = "2" if factor > 1 else "4"
    assert result["difference"].startswith(f"level/units differ by a factor of ~{shown}: give sensitivity and gain")


def test_null_an_int16_wav_without_its_gain_is_a_scale_factor(clean, tmp_path):
    """The source written as an int16 WAV (full-scale fractions), no sensitivity, no gain: the
    values are the source / ~5800, which is said, not fitted as a casing of 333 kg."""
    rows, chain, max_order = written(tmp_path / "wav", clean, 5123, 30.0, fmt="wav")
    assert chain is not None and chain.step > 0
    result = diagnosed(rows, chain, max_order)
    assert result["verdict"] == "level differs" and result["effects"] == []
    c = result["structure"]["level"]["factor"]
    assert 1e-4 < c < 1e-3
    assert result["difference"] == level_line(c) and "give sensitivity and gain" in result["difference"]


def test_null_a_200_khz_record_with_its_noise_shows_no_gap(clean, tmp_path):
    """Noise added at 200 kHz (5000 samples per revolution, above the 4096 points of a revolution):
    the importer's order tracking interpolates it, and the source's noise goes the same way."""
    rows, chain, max_order = written(tmp_path / "fast", clean, 5000, 30.0)
    assert chain is not None and chain.fs == pytest.approx(200e3)
    assert diagnosed(rows, chain, max_order)["verdict"] == "no significant gap"


# --- one verdict, every row's fit named ------------------------------------------------------------------


def test_the_report_says_the_verdict_the_run_printed():
    base = {
        "gap_before": 100.0,
        "gap_after": 0.1,
        "p_before": 0.002,
        "p_after": 0.01,
        "shrink": 0.999,
        "significant_before": True,
        "significant_after": True,
        "unexplained": True,
        "views": {"mesh": {"share_before": 1.0}},
        "ranking": [{"name": "sensor_lowpass", "share_removed": 1.0, "params": {"order": 5, "f_c": 550.0}}],
        "effects": [{"name": "sensor_lowpass", "share_removed": 0.9998, "round": 1, "params": {"order": 8}}],
    }
    result = {"verdict": "partly explained", "unexplained": True, "explained_share": 0.9998}
    summary = {**base, "verdict": verdict_text(result)}
    lines = gap_lines(summary)
    assert summary["verdict"] == "partly explained (100 % of the gap)"
    assert lines[1].endswith("; PARTLY EXPLAINED (100 % OF THE GAP).") and "UNEXPLAINED" not in lines[1]
    assert "sensor_lowpass (final fit: order = 8;" in lines[1]
    structural = {**base, "effects": [], "verdict": "structure differs: mesh order 20.0 measured, 25 expected"}
    assert gap_lines(structural)[-1] == (
        "Structure differs: mesh order 20.0 measured, 25 expected; no effect was searched."
    )
    table = ranking_md(base["ranking"], base["effects"])
    assert "| parameters (round-1 fit) |" in table and "accepted (final fit)" in table
    assert "| order = 5, f_c = 550 |" in table and "round 1, 100.0 %; order = 8 |" in table


def test_records_whose_speed_the_mesh_lines_gave_are_told_a_whole_tooth_off(clean):
    # Outside user (issue 39): a 14/39 mixer's HDF5 takes without a tacho, described with 15 teeth: the
    # speed found from the mesh lines was 42 Hz (630 Hz / 15), the source set to it, and revolutions cut
    # at 42 Hz showed mesh order 15: 'unexplained', the tooth count unsaid. Here a 24-tooth pinion's
    # record at 40 Hz described with 25 teeth reads at 38.4 Hz.
    from gearlab.data.chain import Chain
    from gearlab.gap.structure import traded_teeth

    chain = Chain(fs=4096 * 38.4, speed=38.4, speed_from_mesh=True, described_speed=SPEED)
    settings = Settings(candidates=CANDIDATES, **FAST)
    result = diagnose(SOURCE.with_(speed_hz=38.4), clean, settings, chain=chain)
    assert result["verdict"] == "structure differs" and result["effects"] == []
    assert result["difference"].startswith(
        "speed 38.4 Hz found from the mesh lines (no tacho), 40 Hz expected: the record's mesh at 960 Hz is a "
        "25-tooth pinion's at 38.4 Hz or a 24-tooth pinion's at 40 Hz"
    )
    # a motor's slip off its nameplate, no whole tooth's share, is no structure
    assert traded_teeth(39.0, 40.0, 25) is None and traded_teeth(38.4, 40.0, 25) == 24
