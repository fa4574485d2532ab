"""An outside user's later steps, second look (issue 39, "How it will be checked"; helper D's box Q, a 27/61 + 18/49
reducer without a tacho, and box P's next weeks scored by `gearlab score`): what D left. The recordings are made
here, small, not D's."""

from __future__ import annotations

import json

import numpy as np
from detection_scenario import run, scenario
from gearboxes import description, stage
from textrecords import record


def test_score_prints_the_files_in_the_order_given_not_grouped_by_condition(cli, tmp_path, monkeypatch, no_figures):
    # box P's weeks, given as week1 (28 Hz), week2 (41 Hz), week3 (28 Hz): printed week1, week3, week2
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "data").mkdir()
    files = []
    for i, (speed, role, label, chip) in enumerate(
        [(16.0, "history", "healthy", 0), (16.0, "history", "healthy", 0), (16.0, "test", "fault", 4.0)]
        + [(20.0, "history", "healthy", 0), (20.0, "history", "healthy", 0), (20.0, "test", "fault", 4.0)]
    ):
        name = f"r{i}"
        record(tmp_path / "data" / f"{name}.zip", revolutions=40, chip=chip, seed=i, phase=0.7 * i, speed=speed)
        files.append((name, role, label, chip))
    out = run(cli, scenario(tmp_path, files=files, methods=("source_only",)), tmp_path / "runs")
    weeks = []
    for week, speed in ((1, 16.0), (2, 20.0), (3, 16.0), (4, 20.0)):
        weeks.append(record(tmp_path / f"week{week}.zip", revolutions=40, seed=20 + week, speed=speed))
    code, stdout, err = cli("score", out, *weeks, "--json")
    assert code == 0, err
    order = list(dict.fromkeys(r["file"].rsplit("/", 1)[-1] for r in json.loads(stdout)))
    assert order == ["week1.zip", "week2.zip", "week3.zip", "week4.zip"], order
    code, stdout, err = cli("score", out, *weeks)
    assert code == 0, err
    said = [stdout.index(f"week{w}.zip: ") for w in (1, 2, 3, 4)]
    assert said == sorted(said), said


def test_the_report_s_score_trend_has_whole_number_ticks(tmp_path, monkeypatch):
    # box P's two weeks at 28 Hz: the report's PNG ticked its x axis at 1.0, 1.2, ... 2.0 (the TUI's: 1, 2);
    # a history more than 20 records long has no ticks given: whole numbers still
    from gearlab import plots
    from gearlab.charts import Chart, Curve
    from gearlab.kinds.detection_figures import score_trend

    drawn = []
    monkeypatch.setattr(plots, "save", lambda fig, path, **kw: drawn.append(fig) or path)
    two = Chart("28 Hz", "record", "score less threshold", (Curve("fm4", [1, 2], [-0.5, 0.4]),), xticks=[1, 2])
    long = Chart("41 Hz", "record", "score less threshold", (Curve("fm4", [1, 2.0, 3], [0.1, -0.2, 0.3]),))
    score_trend([two, long], tmp_path / "trend.png")
    (fig,) = drawn
    for ax in fig.axes:
        ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
        assert ticks and all(float(t).is_integer() for t in ticks), ticks
        assert any(list(line.get_ydata()) == [0.0, 0.0] for line in ax.get_lines())  # the zero line: called above


def _box_q_take(path, seed: int, speed: float = 28.0, fs: float = 8192.0, seconds: float = 10.0):
    """Box Q, 27/61 + 18/49, healthy, without a tacho, as helper D's outside lab wrote it: each mesh's harmonics
    1-3 amplitude- and phase-modulated by both its shafts, the speed wobbling 0.2 %, a structural mode at 3.6 kHz,
    white noise (m/s^2)."""
    from scipy.signal import lfilter

    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    turns = 2 * np.pi * np.cumsum(speed * (1 + 0.002 * np.sin(2 * np.pi * 0.31 * t + rng.uniform(0, 6)))) / fs
    shafts = [turns + rng.uniform(0, 2 * np.pi)]
    shafts += [shafts[0] * 27 / 61, shafts[0] * 27 / 61 * 18 / 49]

    def mesh(pinion, teeth, a, b):
        am = 1 + 0.2 * np.cos(a + 0.4) + 0.12 * np.cos(b + 2.0)
        fm = 0.06 * np.sin(a) + 0.05 * np.sin(b + 0.9)
        return sum(
            w * am * np.cos(k * (teeth * pinion + fm) + rng.uniform(0, 6)) for k, w in ((1, 1.0), (2, 0.5), (3, 0.25))
        )

    x = 4.0 * mesh(shafts[0], 27, shafts[0], shafts[1]) + 3.0 * mesh(shafts[1], 18, shafts[1], shafts[2])
    x += 0.4 * np.cos(shafts[0]) + 0.3 * np.cos(shafts[1] + 2)
    r = np.exp(-0.03 * 2 * np.pi * 3600 / fs)
    x += 0.8 * lfilter([1 - r], [1, -2 * r * np.cos(2 * np.pi * 3600 / fs), r * r], x)
    np.savez(path, acc=x + rng.normal(0, 0.5, t.size), fs=fs)
    return path


BOX_Q = description(
    stage(27, 61, width="18 mm", bores=("20 mm", "25 mm")),
    stage(18, 49, module="3 mm", width="25 mm", bores=("25 mm", "35 mm")),
    name="boxQ",
    speed="28 Hz",
    near="output",
    direction="x",
)


def test_a_healthy_take_of_a_two_stage_box_read_whole_is_not_called_bearing_like(cli, tmp_path, monkeypatch):
    # box Q's healthy takes at 28 Hz (D's detection run) read z 6.5, 7.1, 6.8 against 4.1, 'other damage:
    # non-synchronous (bearing-like), at order 3.54' (M1 - 3 M2 + the intermediate shaft's 0.443: two meshes'
    # lines leak past the bins removed, its grand period, 2989 turns, being no take's, and beat, moved by a shaft order)
    from gearlab.data import which_gear as W

    # Only the non-synchronous reading is asserted: the synchronous localisation beside it (the history's
    # per-shaft averages and the take's, read twice) was 70 % of this test's CPU and is left out; its
    # result, nothing named, is what the call reads then too. The files, their reading and the
    # non-synchronous history and call are inspect's own.
    monkeypatch.setattr(W, "history_of", lambda *args, **kwargs: None)
    monkeypatch.setattr(W, "which_gear", lambda *args, **kw: {"named": None})
    (tmp_path / "boxQ.toml").write_text(BOX_Q)
    takes = [_box_q_take(tmp_path / f"q{seed}.npz", seed) for seed in (1, 2, 3, 4, 5)]
    history = [a for h in takes[:3] for a in ("--history", h)]
    found = []
    for take in takes[3:]:
        code, stdout, err = cli(
            "inspect", take, "--gearbox", tmp_path / "boxQ.toml", "--speed", "28 Hz", *history, "--json"
        )
        assert code == 0, err
        found.append(json.loads(stdout)["localisation"]["nonsync"])
    # the history's own takes, read each against the others, raised the threshold to 5.6 (the Bonferroni floor over
    # its bins: 4.05) on those lines, deaf to a weaker bearing; the takes read z 3.1-3.5 at 2.8-3.6
    said = [(round(ns["z"], 2), round(ns["threshold"], 2)) for ns in found]
    assert not any(ns["changed"] for ns in found) and all(ns["threshold"] < 4.5 for ns in found), said


def test_a_bearing_striking_at_two_meshes_combination_is_named_at_its_own_order(cli, tmp_path, monkeypatch):
    # box Q's healthy takes (above) with a bearing's strikes added at 3.541 a turn, M1 - 3 M2 + o_2 of its two
    # meshes: with the meshes' combinations left out of the search, its own line was, and it was named at its
    # harmonic 7.08; the takes are read in whole periods of the meshes (read_turns), where no beat stands there
    from gearlab.data import which_gear as W

    monkeypatch.setattr(W, "history_of", lambda *args, **kwargs: None)  # as above: the non-synchronous call alone
    monkeypatch.setattr(W, "which_gear", lambda *args, **kw: {"named": None})
    (tmp_path / "boxQ.toml").write_text(BOX_Q)
    history = [a for seed in (1, 2, 3) for a in ("--history", _box_q_take(tmp_path / f"q{seed}.npz", seed))]
    order = 27 - 3 * 27 * 18 / 61 + 27 / 61
    take = np.load(_box_q_take(tmp_path / "q4.npz", 4))
    x, fs = take["acc"].copy(), float(take["fs"])
    rng = np.random.default_rng(9)
    t = np.arange(int(0.004 * fs)) / fs
    ring = np.exp(-0.05 * 2 * np.pi * 2500 * t) * np.sin(2 * np.pi * 2500 * t) * 0.6 * x.std()  # 2.5 kHz, 5 %
    period = 1 / (order * 28.0)
    at = rng.uniform(0, period)
    while at < x.size / fs - t[-1]:  # each interval slips 1.5 % (a rolling element's)
        i = int(at * fs)
        x[i : i + t.size] += ring
        at += period * (1 + 0.015 * rng.standard_normal())
    np.savez(tmp_path / "bearing.npz", acc=x, fs=fs)
    code, stdout, err = cli(
        "inspect", tmp_path / "bearing.npz", "--gearbox", tmp_path / "boxQ.toml", "--speed", "28 Hz", *history, "--json"
    )
    assert code == 0, err
    ns = json.loads(stdout)["localisation"]["nonsync"]
    assert ns["changed"] and abs(ns["order"] - order) < 0.05, ns  # (read to 1/16 order, then refined)
