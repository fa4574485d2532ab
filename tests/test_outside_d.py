"""An outside user's later steps (issue 39, "How it will be checked"): box P, a 19/44 reducer with a 1-mark input
tacho (int16 WAV with a gain, HDF5 in a group, volts at 10.2 mV/(m/s^2)), and box Q, a 27/61 + 18/49 reducer
without one (headerless TSV, npz), each with next weeks' takes at 28 and 41 Hz scored by `gearlab score`. The
rows here are small stand-ins written by hand, not scored or simulated by gearlab."""

from __future__ import annotations


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
    (trend,) = detection_scoring.score_trends(None)
    assert "records: 1 P_week1_28.wav, 2 P_week3_28.wav" in trend.title, trend.title
    assert list(trend.xticks) == [1, 2]  # whole records, not 1.2, 1.4, ...
    mf = next(c for c in trend.curves if c.label == "matched_filter")
    assert mf.y[0] < 0 < mf.y[1] and max(abs(v) for v in mf.y) == 1.0  # the crossing, at its own scale
    assert "matched_filter 0.092" in trend.title and "likelihood_ratio 601" in trend.title  # the scale said
