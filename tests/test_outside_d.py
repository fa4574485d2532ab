"""An outside user's later steps (issue 39, "How it will be checked"): box P, a 19/44 reducer with a 1-mark input
tacho (int16 WAV with a gain, HDF5 in a group, volts at 10.2 mV/(m/s^2)), and box Q, a 27/61 + 18/49 reducer
without one (headerless TSV, npz), each with next weeks' takes at 28 and 41 Hz scored by `gearlab score`. The
rows here are small stand-ins written by hand, not scored or simulated by gearlab."""

from __future__ import annotations

import numpy as np


def _scored(file: str, method: str, margin: float, threshold: float = 1.0) -> dict:
    """One row of a run's scoring history (gearlab.parts.scoring) as `gearlab score` appends it."""
    return {
        "file": file,
        "condition": "28 Hz",
        "method": method,
        "unit": "record30",
        "median_score": threshold + margin,
        "threshold": threshold,
        "decision": "fault" if margin > 0 else "healthy",
    }


def test_the_score_trend_names_each_take_and_shows_every_method_s_crossing(monkeypatch):
    # box P's next weeks at 28 Hz: the trend (report and TUI) drew the points at x 1.0, 1.2, ... 2.0 with no
    # take named anywhere, and a likelihood ratio's margin of 601 flattened a matched filter's -0.007 -> +0.09
    # (healthy, then called) onto the zero line
    from gearlab.kinds import detection_scoring

    rows = [
        _scored("rec/P_week1_28.wav", "likelihood_ratio", -63.5),
        _scored("rec/P_week1_28.wav", "matched_filter", -0.007, 0.1),
        _scored("rec/P_week3_28.wav", "likelihood_ratio", 601.0),
        _scored("rec/P_week3_28.wav", "matched_filter", 0.092, 0.1),
    ]
    monkeypatch.setattr(detection_scoring.scoring, "read_history", lambda run: rows)
    monkeypatch.setattr(detection_scoring.scoring, "read_skipped", lambda run: [])  # no take refused
    (trend,) = detection_scoring.score_trends(None)
    assert "records: 1 P_week1_28.wav, 2 P_week3_28.wav" in trend.title, trend.title
    assert list(trend.xticks) == [1, 2]  # whole records, not 1.2, 1.4, ...
    mf = next(c for c in trend.curves if c.label == "matched_filter")
    assert mf.y[0] < 0 < mf.y[1] and max(abs(v) for v in mf.y) == 1.0  # the crossing, at its own scale
    assert "matched_filter 0.092" in trend.title and "likelihood_ratio 601" in trend.title  # the scale said


def _box_q(path, speed=41.0, fs=8192.0, seconds=6.0, seed=1601):
    """Box Q, 27/61 + 18/49 without a tacho: each mesh's harmonics 1-3 modulated by both its shafts, the
    speed wobbling 0.2 %, white noise (m/s^2)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    theta = 2 * np.pi * np.cumsum(speed * (1 + 0.002 * np.sin(2 * np.pi * 0.31 * t))) / fs
    inter, out = theta * 27 / 61, theta * 27 / 61 * 18 / 49
    h = np.arange(1, 4)[:, None]
    stage1 = 4.0 * (1 + 0.2 * np.cos(theta + 0.4) + 0.12 * np.cos(inter + 2.0)) * (np.cos(h * 27 * theta) / h).sum(0)
    stage2 = 3.0 * (1 + 0.2 * np.cos(inter) + 0.12 * np.cos(out + 1.0)) * (np.sin(h * 18 * inter) / h).sum(0)
    np.savez(path, acc=stage1 + stage2 + rng.normal(0, 0.5, t.size), fs=fs)


def test_a_take_at_another_speed_than_described_is_told_its_speed_not_a_pinion_count(tmp_path):
    # box Q's 41 Hz take, inspected with the description's [operation] speed = "28 Hz" and no --speed: 'the mesh
    # at 652.4 Hz is a 22-tooth pinion's at 29.65 Hz, a 23-tooth ... or a 24-tooth ...: the speed or a tooth
    # count differs' (652.4 Hz: stage 2's 2nd harmonic at 41 Hz), where every described mesh has its lines
    from test_inspect import described

    from gearlab.inspect import InspectOptions, inspect_record

    _box_q(tmp_path / "q41.npz")
    box = described((27, 61), (18, 49), speed="28 Hz")
    verdict = inspect_record(str(tmp_path / "q41.npz"), box, InspectOptions("acc"))["verdict"]
    assert "tooth pinion's at" not in verdict, verdict
    said = verdict.split("every described mesh has its lines at ")[1]
    assert abs(float(said.split(" Hz")[0]) / 41.0 - 1) < 0.005, verdict  # within the ±1 % a declared speed refines
    assert "--speed '" in said, verdict
    # at the speed it names, the description matches
    right = inspect_record(str(tmp_path / "q41.npz"), box, InspectOptions("acc", speed_hz=float(said.split(" Hz")[0])))
    assert right["verdict"] == "the description 'box' matches this recording", right["verdict"]
