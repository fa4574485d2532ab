"""Outside user DY (issue 39, round 19): a maintenance engineer's gearboxes, their takes made here with numpy (each
shaft's lines, each mesh's harmonics modulated by both its shafts, a tooth's dip and ring once a turn of its shaft,
noise, a once-per-turn tacho), read as docs/your_gearbox.md says: a 41/109 conveyor drive whose input pinion cracks
week by week, a 42/63 (non-hunting) + 23/71 mixer drive recorded on its output bearing, and what loggers and
MATLAB write beside the numbers (a rate in a comment, a struct's units)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.io import savemat

from gearlab.data.recordings import read_channels
from gearlab.inspect import InspectOptions, inspect_record

G = 9.80665
FS = 20000.0


def _shaft(seconds: float, f0: float, seed: int) -> np.ndarray:
    """The input shaft's angle per sample (rad): *f0* swinging 0.2 %, starting at any turn and angle."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    f = f0 * (1 + 0.002 * np.sin(2 * np.pi * 0.29 * t + rng.uniform(0, 6)))
    return 2 * np.pi * (np.cumsum(f) / FS + rng.integers(0, 1000)) + rng.uniform(0, 6)


def _take(th: np.ndarray, stages, seed: int, crack: float = 0.0, hum: float = 0.0) -> np.ndarray:
    """m/s²: every shaft's orders 1-2, each mesh's harmonics 1-3 modulated by both its shafts; *crack* > 0: the input
    pinion's tooth at 1.3 rad dips its mesh and rings a 3.1 kHz mode once a turn; *hum*: 50 Hz mains and its
    harmonics 2 and 3 (pickup on the sensor's cable); noise 26 dB down."""
    rng = np.random.default_rng(seed + 7)
    turns = np.cumprod([1.0] + [p / w for p, w in stages])
    x = sum(0.3 * np.cos(k * th * r + 0.7 * k + i) for i, r in enumerate(turns) for k in (1, 2))
    for s, (zp, _) in enumerate(stages):
        a, b = th * turns[s], th * turns[s + 1]
        for h, amp in ((1, 3.0), (2, 1.4), (3, 0.6)):
            am = 1 + 0.08 * np.cos(a + 0.3 * h) + 0.06 * np.cos(b + 1.1 * h)
            x = x + amp * am * np.cos(h * (zp * a + 0.03 * np.cos(a + 0.7) + 0.02 * np.cos(b)) + 0.4 * h * s)
    if crack:
        d = np.angle(np.exp(1j * (th - 1.3)))  # from the cracked tooth, one turn of the input shaft
        x = x - crack * 3.0 * np.exp(-0.5 * (d / (0.6 * 2 * np.pi / stages[0][0])) ** 2) * np.cos(stages[0][0] * th)
        since = np.mod(th - 1.3, 2 * np.pi) / (2 * np.pi * np.gradient(th)[0] * FS / (2 * np.pi))
        x = x + crack * 4.0 * np.exp(-since * 1250.0) * np.sin(2 * np.pi * 3100.0 * since)
    t = np.arange(th.size) / FS
    x = x + hum * (np.sin(2 * np.pi * 50 * t) + 0.3 * np.sin(2 * np.pi * 100 * t) + 0.5 * np.sin(2 * np.pi * 150 * t))
    return x + rng.normal(0, 0.05 * np.std(x), th.size)


def _tacho(th: np.ndarray) -> np.ndarray:
    return np.where(np.mod(th, 2 * np.pi) < 0.3, 5.0, 0.0)


# --- what loggers and MATLAB write beside the numbers -------------------------------------------------------------


@pytest.mark.parametrize("line", ["# Sample rate: 20 kHz", "# Sample rate [kHz]: 20", "# Sampling rate = 20000 Hz"])
def test_a_rate_in_a_comment_line_is_read_as_a_preamble_s_is(tmp_path, line):
    # a logger's CSV opening '# Sample rate: 20 kHz' was refused 'no sampling rate: the file has no 'fs'/time',
    # the same line without its '#' read as 20 kHz ('# fs = 20000' alone was read: a one-word key)
    th = _shaft(0.5, 29.0, 1)
    path = tmp_path / "take.csv"
    rows = "\n".join(f"{v:.5g},{p:g}" for v, p in zip(_take(th, ((41, 109),), 1), _tacho(th)))
    path.write_text(f"{line}\nacc,tach\n{rows}\n")
    _, fs = read_channels(path, ["acc"])
    assert fs == pytest.approx(20000.0)


def test_a_matlab_struct_s_units_field_is_the_unit_of_its_data(tmp_path):
    # MATLAB's rec = struct('fs', 20000, 'data', [acc tacho], 'units', 'g'): its data were read as m/s² ('values:
    # unknown (no sensitivity or gain given: the values are taken as m/s²)'), 9.8 times too small, its 'units' a channel
    th = _shaft(1.0, 29.0, 2)
    acc = _take(th, ((41, 109),), 2)
    savemat(tmp_path / "take.mat", {"rec": {"fs": FS, "data": np.c_[acc / G, _tacho(th)], "units": "g"}})
    got = inspect_record(str(tmp_path / "take.mat"), None, InspectOptions("data[0]", tacho="data[1]"))
    assert "g" in got["units"] and "9.80665" in got["units"], got["units"]
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.02)
    assert got["channels"] == ["rec/data"], got["channels"]  # its units no channel, nor the struct itself


# --- what is no gear's fault: a mains hum --------------------------------------------------------------------------

CONVEYOR = ((41, 109),)  # the conveyor drive: a 41T input pinion at 29 Hz, its 109T wheel on the output shaft


@pytest.fixture(scope="module")
def conveyor(tmp_path_factory):
    """The conveyor drive's description and takes (npz in m/s², 3 s: 87 input and 32 output turns): three
    healthy days for the history, a healthy take with a 50 Hz mains hum (0.3 m/s² against a 3 m/s² mesh)."""
    from gearlab.gearbox import load_gearbox

    folder = tmp_path_factory.mktemp("conveyor")
    (folder / "box.toml").write_text(
        '[gearbox]\nname = "conveyor"\n[operation]\nspeed = "29 Hz"\nload = "40 N*m"\n[[stages]]\nmodule = "2 mm"\n'
        'face_width = "20 mm"\npinion = { z = 41, bore = "25 mm" }\nwheel = { z = 109, bore = "40 mm" }\n'
        '[sensor]\nnear = "input"\ntacho = "input"\n'
    )
    paths = {}
    for name, seed, hum in (("day1", 10, 0.0), ("day2", 11, 0.0), ("day3", 12, 0.0), ("hum", 14, 0.3)):
        th = _shaft(3.0, 29.0, seed)
        paths[name] = str(folder / f"{name}.npz")
        np.savez(paths[name], acc=_take(th, CONVEYOR, seed, hum=hum), tach=_tacho(th), fs=FS)
    return load_gearbox(folder / "box.toml"), paths


def test_a_mains_hum_is_called_no_gear_fault_not_bearing_damage(conveyor):
    # a healthy take with 50 Hz pickup (and its 2nd and 3rd harmonics) on the sensor's cable: inspect --history
    # listed 49.927 Hz as 'not a gear order (a fixed frequency such as mains, or a bearing's)', then called it
    # 'other damage: non-synchronous (bearing-like), at order 2.08', as did the detection run and gearlab score
    from gearlab.inspect_history import localisation

    box, paths = conveyor
    history = [paths["day1"], paths["day2"], paths["day3"]]
    found = localisation(paths["hum"], history, box, InspectOptions("acc", tacho="tach"))
    assert found["nonsync"]["changed"], found["nonsync"]
    # its speed swings 0.2 % and the history is at its speed: by its frequency alone a bearing's line there reads the
    # same, so it is not called hum outright (tests/test_hum_or_bearing.py: a sweep or another speed tells)
    untold = "other damage: non-synchronous (bearing-like) or mains hum, at order 1.72 (50.0 Hz, within 1 % of the 50"
    assert found["call"].startswith(untold) and "not told apart" in found["call"], found["call"]


def test_a_run_s_flag_on_a_hum_is_no_gear_s_and_a_bearing_s_line_stays_bearing_like():
    # the detection run's and gearlab score's call (kinds.detection_which_gear.call_of) of a take whose residual's
    # envelope line is the mains': not the watched gear's, counted as a flag on no watched gear, as a bearing's is
    from gearlab.kinds.detection_which_gear import call_of, is_other

    nothing = {"named": None, "shafts": []}
    line = {"changed": True, "order": 2.078, "locked": "time", "why": "at 60.1 Hz too in the history's take at 25 Hz"}
    hum = call_of(nothing, ["input pinion 41T (stage 1)"], line, 28.92)
    assert hum.startswith("not a gear fault: mains hum at 60.1 Hz (order 2.08"), hum
    assert is_other(hum)
    # on the mains harmonic, not told from a bearing's (a steady take, no history at another speed): other damage
    untold = call_of(nothing, ["input pinion 41T (stage 1)"], line | {"locked": "", "why": ""}, 28.92)
    assert untold.startswith("other damage: non-synchronous (bearing-like) or mains hum, at order 2.08"), untold
    assert is_other(untold)
    bearing = call_of(nothing, ["input pinion 41T (stage 1)"], {"changed": True, "order": 4.37}, 29.0)
    assert bearing == "other damage: non-synchronous (bearing-like), at order 4.37"


# --- weeks of takes: when the crack first crossed, on which gear and tooth -----------------------------------------


def _week(n: int, method: str, margin: float, decision: str | None = None) -> dict:
    """One row of the conveyor's scoring history (gearlab.parts.scoring) as `gearlab score` appends it: week *n*,
    the watched input pinion, its record30 units' median score *margin* over the threshold 1."""
    where = "input pinion 41T (stage 1)" if margin > -0.5 else None
    tooth = "; tooth 9 of 41 (counted from the tacho's mark on this shaft)" if where else ""
    return {
        "file": f"rec/week{n}.csv",
        "condition": "29 Hz",
        "method": method,
        "unit": "record30",
        "median_score": 1.0 + margin,
        "threshold": 1.0,
        "decision": decision or ("fault" if margin > 0 else "healthy"),
        "localised": where,
        "evidence": f"input z {20 * (margin + 1):.1f}/2.6{tooth}",
    }


WEEKS = [  # the crack grows: fm4 and the matched filter call it from week 4, the likelihood ratio from week 5
    *(_week(n, "fm4", m) for n, m in enumerate((-0.9, -0.8, -0.05, 0.3, 0.8, 1.5), 1)),
    *(_week(n, "matched_filter", m) for n, m in enumerate((-0.9, -0.7, -0.1, 0.2, 0.6, 1.2), 1)),
    *(_week(n, "likelihood_ratio", m) for n, m in enumerate((-0.9, -0.9, -0.6, -0.1, 0.5, 1.1), 1)),
    *(_week(n, "na4", -0.9) for n in range(1, 7)),
]


def test_the_score_trend_says_when_a_fault_was_first_called_on_which_gear_and_tooth(monkeypatch):
    # a maintenance engineer's weekly takes of a cracking pinion, scored one by one: the trend (report, TUI) drew
    # each method's margin over its threshold per take, and nothing said which take first crossed, by which methods,
    # or where: the gear and tooth were in each take's printout only
    from gearlab.kinds import detection_scoring
    from gearlab.kinds.detection_trend import first_called

    (line,) = first_called(WEEKS)
    assert line.startswith("29 Hz, record30: first called on take 4 (week4.csv) by fm4, matched_filter"), line
    assert "likelihood_ratio from take 5, na4 never" in line, line
    assert "input pinion 41T (stage 1), tooth 9 of 41" in line and "every take since" in line, line
    monkeypatch.setattr(detection_scoring.scoring, "read_history", lambda run: WEEKS)
    monkeypatch.setattr(detection_scoring.scoring, "read_skipped", lambda run: [])  # every take was scored
    (trend,) = detection_scoring.score_trends(None)
    assert line in trend.title, trend.title


def test_a_trend_with_no_take_called_says_so_and_a_call_that_lapsed_says_that():
    from gearlab.kinds.detection_trend import first_called

    quiet = [r | {"decision": "healthy", "median_score": 0.5} for r in WEEKS]
    assert first_called(quiet) == ["29 Hz, record30: no take called (6 scored)"]
    lapsed = [r | {"decision": "healthy"} if r["file"].endswith("week5.csv") else r for r in WEEKS]
    (line,) = first_called(lapsed)
    assert "not called again on take 5 (week5.csv)" in line, line


def test_the_report_says_under_the_trend_chart_when_it_first_crossed(tmp_path):
    # report.html showed the trend as a picture only: its text now follows the chart's caption
    from gearlab.report import build_report
    from gearlab.runs import RunDir

    (tmp_path / "figures").mkdir()
    (tmp_path / "figures" / "score_trend.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (tmp_path / "figures" / "score_trend.txt").write_text("29 Hz, record30: first called on take 4 (week4.csv)")
    page = build_report(RunDir(tmp_path))
    assert "29 Hz, record30: first called on take 4 (week4.csv).</figcaption>" in page


def test_gearlab_score_ends_with_the_trend_so_far(tmp_path):
    # `gearlab score RUN_DIR week4.csv` printed week 4's table alone: its last lines now say the trend of the takes
    # scored so far (the history it appended to)
    import json

    from gearlab.terminal import score_trend

    (tmp_path / "scenario.toml").write_text('[scenario]\nname = "conveyor_crack"\nkind = "detection"\n')
    (tmp_path / "scoring").mkdir()
    (tmp_path / "scoring" / "history.jsonl").write_text("".join(json.dumps(r) + "\n" for r in WEEKS))
    (line,) = [str(t) for t in score_trend(tmp_path)]
    assert line.startswith("trend: 29 Hz, record30: first called on take 4 (week4.csv) by fm4, matched_filter"), line


# --- a take of the wrong polarity ----------------------------------------------------------------------------------


def test_a_take_whose_synchronous_average_is_the_history_s_reversed_is_said_to_be():
    from gearlab.signals.checks import polarity_line

    rng = np.random.default_rng(3)
    th = np.linspace(0, 2 * np.pi, 512, endpoint=False)
    history = np.cos(41 * th) + 0.3 * np.cos(82 * th + 1)
    take = history + rng.normal(0, 0.5, (40, th.size))
    assert polarity_line(take, history) == ""
    said = polarity_line(-take, history)
    assert said.startswith("polarity reversed against its history's (their synchronous averages correlate -0.9"), said
    assert polarity_line(rng.normal(0, 1, (40, th.size)), history) == ""  # unlike it, not reversed


@pytest.fixture(scope="module")
def conveyor_run(conveyor, tmp_path_factory):
    """A detection run of the conveyor drive watching its input pinion (the matched filter alone): its three
    healthy days the history; a healthy take recorded with the sensor's leads swapped (the values negated) a test."""
    from detection_scenario import run_in_module

    box, paths = conveyor
    folder = Path(paths["day1"]).parent
    th = _shaft(3.0, 29.0, 15)
    np.savez(folder / "swapped.npz", acc=-_take(th, CONVEYOR, 15), tach=_tacho(th), fs=FS)
    (folder / "detect.toml").write_text(
        '[scenario]\nname = "conveyor_crack"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { crack = [20] }\nhealthy = 8\nteeth = [1, 21]\n[target]\nvibration = "acc"\ntacho = "tach"\n'
        'files = [\n  { file = "day*.npz", role = "history", label = "healthy" },\n'
        '  { file = "swapped.npz", role = "test", label = "healthy" },\n'
        '  { file = "hum.npz", role = "test", label = "healthy" },\n]\n[[methods]]\nadapter = "matched_filter"\n'
        "[protocol]\nbatch = 8\n[execution]\nworkers = 1\n"
    )
    return run_in_module(folder / "detect.toml", folder / "runs", cwd=folder, figures=False)


def test_a_run_warns_of_a_take_of_reversed_polarity(conveyor_run):
    # the swapped take: 1 of 3 record30 units called by the matched filter and the likelihood ratio, nothing said
    from gearlab.runs import RunDir

    warnings = RunDir.open(conveyor_run).read_json("summary.json")["warnings"]
    assert [w for w in warnings if w.startswith("warning: swapped.npz: polarity reversed")], warnings
    assert not [w for w in warnings if "hum.npz: polarity" in w], warnings


def test_gearlab_score_says_a_take_of_reversed_polarity(conveyor_run, conveyor):
    from gearlab.notebook import score_recordings

    folder = Path(conveyor[1]["day1"]).parent
    rows = score_recordings(conveyor_run, [folder / "swapped.npz", folder / "day2.npz"])
    level = {Path(r["file"]).name: r["level"] for r in rows}
    assert level["swapped.npz"].startswith("polarity reversed against its history's"), level
    assert level["day2.npz"] == "", level


@pytest.mark.parametrize("line", ["# units: g", "Units: g", "# unit = g"])
def test_a_logger_s_units_line_above_the_table_is_the_unit_of_its_values(tmp_path, line):
    # a CSV opening 'Sample rate: 20 kHz' and 'Units: g' was read as m/s² ('values: unknown ... taken as m/s²'),
    # 9.8 times too small, as an NPZ's text 'unit' or a MATLAB struct's 'units' is not
    th = _shaft(1.0, 29.0, 4)
    acc = _take(th, CONVEYOR, 4)
    path = tmp_path / "take.csv"
    rows = "\n".join(f"{v:.6g},{p:g}" for v, p in zip(acc / G, _tacho(th)))
    path.write_text(f"Sample rate: 20 kHz\n{line}\nacc,tach\n{rows}\n")
    got = inspect_record(str(path), None, InspectOptions("acc", tacho="tach"))
    assert "9.80665" in got["units"], got["units"]
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.02)


def test_a_later_method_first_calling_a_take_whose_level_alone_changed_says_so():
    # a take at 9.8 x its history's level (a file in m/s² read as g), nothing localised, was 'level changed' in its
    # own score row; the trend said 'likelihood_ratio from take 3' as if a fault were first called there
    from gearlab.kinds.detection_trend import first_called

    level = "level changed by a factor of 9.82 (sensor, gain or load changed?): record a new history"
    rows = [
        {"condition": "c", "unit": "revolution", "method": m, "file": f"w{i}.csv", "median_score": 0.0, "decision": d}
        for m, decisions in (
            ("fm4", ("healthy", "fault", "fault")),
            ("likelihood_ratio", ("healthy", "healthy", level)),
        )
        for i, d in enumerate(decisions, 1)
    ]
    (line,) = first_called(rows)
    assert (
        "first called on take 2 (w2.csv) by fm4 (likelihood_ratio from take 3 (level changed by a factor of 9.82))"
        in line
    ), line
    rows[-1]["decision"] = "fault"
    assert "(likelihood_ratio from take 3)" in first_called(rows)[0]
