"""An outside user's fourth look (issue 39, "How it will be checked"; helper H): a 31/73 box driven from its 73T
wheel and a 25/52 + 16/81 box with a 4-mark tacho on its intermediate shaft, recorded as csv with ';' and decimal
commas, int24 WAV in volts, HDF5 and npz in g. The recordings are made here, small, by plain numpy."""

from __future__ import annotations

import json

import numpy as np
import pytest
from gearboxes import description, stage
from which_gear_takes import box_b_description, box_b_take

BOX_B = box_b_description()


def test_score_key_empty_drops_the_run_s_gain_and_sensitivity(tmp_path):
    # a run whose [target] read int24 WAVs in volts (gain = "5 V", sensitivity 100 mV/g) scores a next-week npz in
    # g: `--key gain=` was refused ('expected KEY=VALUE ... did you mean gain'), and `--key unit=g` alone with
    # 'expected no gain': no way to drop the run's gain, as a [target] files entry's gain = "" does
    from gearlab.kinds.detection_scoring import reading_keys

    np.savez(tmp_path / "week1.npz", acc_top=np.zeros(512, "f4"), tacho=np.zeros(512, "f4"), fs=10240.0)
    target = {"fs": None, "gain": 5.0, "gearbox": None, "pulses_per_rev": 4, "sensitivity": 0.0102, "speed_hz": None}
    target |= {"tacho": "2", "tacho_shaft": {"a": 25, "b": 52, "name": "intermediate"}, "transient": "none"}
    meta = {"target": target | {"unit": None, "vibration": "0"}, "conditions": {"25 Hz": {"speed_hz": 25.0}}}
    meta["file_keys"] = {"formats": {".wav": {}}, "sets": {".wav": [{}]}, "tests": {}}
    given = {"vibration": "acc_top", "tacho": "tacho", "gain": "", "sensitivity": "", "unit": "g"}
    keys = reading_keys(meta, None, given, str(tmp_path / "week1.npz"))
    assert keys["gain"] is None and keys["sensitivity"] is None and keys["unit"] == "g", keys
    # a channel still needs a name
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError, match="--key vibration="):
        reading_keys(meta, None, given | {"vibration": ""}, str(tmp_path / "week1.npz"))


def test_a_four_mark_tacho_s_own_shaft_counts_its_teeth_up_to_quarter_turns(
    cli, tmp_path, monkeypatch, synchronous_only
):
    # box B's 52T crack, tacho (4 marks a turn) on the intermediate shaft: inspect --history said 'tooth 4 of 52 (in
    # this take only: the tooth is not fixed across takes; this shaft's angle relative to the tacho is not known)'
    # and read 3.55 and 30.55 pitches in two takes (the take's turn to the first history take's not added back). Now
    # counted from the mark, the same tooth up to 13-tooth steps (52 / 4), and said so
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    (tmp_path / "boxB.toml").write_text(BOX_B)
    history = [box_b_take(tmp_path / f"h{seed}.npz", seed, seconds=4.0) for seed in (51, 52, 53)]
    pitches = []
    for seed in (54, 56):
        take = box_b_take(tmp_path / f"c{seed}.npz", seed, seconds=4.0, crack=1.0)
        args = ["inspect", take, "--gearbox", tmp_path / "boxB.toml", "--vibration", "acc_top", "--tacho", "tacho"]
        code, stdout, err = cli(*args, "--unit", "g", *[a for h in history for a in ("--history", h)], "--json")
        assert code == 0, err
        shaft = json.loads(stdout)["localisation"]["shafts"][0]
        assert shaft["shaft"] == "intermediate" and shaft["flagged"], shaft
        tooth = shaft["tooth"]["intermediate gear 52T (stage 1)"]
        assert tooth.get("mark") and tooth["step"] == 13, tooth
        pitches.append(tooth["pitches"])
    steps = (pitches[1] - pitches[0]) / 13
    assert abs(steps - round(steps)) < 0.1, pitches  # the crack sits at 2 rad: 16.55 pitches from a mark
    assert abs(((pitches[0] - 16.55) / 13) - round((pitches[0] - 16.55) / 13)) < 0.1, pitches
    code, stdout, err = cli(*args, "--unit", "g", *[a for h in history for a in ("--history", h)])
    assert "-tooth steps between takes: its marks are alike" in stdout, stdout[-1500:]
    assert "angle relative to the tacho is not known" not in stdout


def _run_up_csv(path, f0, f1, seconds=6.0, fs=12800.0):
    """A 31/73 box driven from its 73T wheel, its speed rising f0 -> f1 over the take: ';' separated, decimal commas,
    a jittery time column, two accelerometers in g and a 1-mark tacho on the input (73T) shaft."""
    rng = np.random.default_rng(3)
    t = np.arange(int(fs * seconds)) / fs
    th = 2 * np.pi * np.cumsum(f0 + (f1 - f0) * t / seconds) / fs
    x = np.cos(73 * th + 0.2 * np.cos(th)) + 0.3 * np.cos(146 * th) + rng.normal(0, 0.05, t.size)
    rows = np.column_stack(
        [t + rng.normal(0, 0.03 / fs, t.size), x, 0.5 * x, np.where(th / 2 / np.pi % 1 < 0.06, 5, 0)]
    )
    text = ("%.7f;%.5f;%.5f;%.1f\n" * len(rows) % tuple(rows.ravel().tolist())).replace(".", ",")  # in one operation
    path.write_text("Zeit [s];Beschl. 1 [g];Beschl. 2 [g];Tacho [V]\n" + text)
    return path


def test_a_run_up_is_said_a_run_up_not_only_its_mean_speed(tmp_path):
    # a run-up 20 -> 35 Hz with a tacho: a detection run printed 'rec/A_runup.csv: 27.499 Hz, from tacho ...', then
    # "condition '27.5 Hz' has no history record", gearlab score 'runs at 27.50 Hz, more than 5% from every
    # condition': nothing said that the take's speed ran from 20 to 35 Hz (inspect's tacho line alone did)
    from gearlab.data.recordings import cut_recording

    keys = {"vibration": "Beschl. 1 [g]", "tacho": "Tacho [V]"}
    up = cut_recording(str(_run_up_csv(tmp_path / "runup.csv", 20.0, 35.0)), **keys)
    assert up.speed_hz == pytest.approx(27.5, rel=0.01)
    assert "20." in up.angle_source and "over the take: a run-up:" in up.angle_source, up.angle_source
    steady = cut_recording(str(_run_up_csv(tmp_path / "steady.csv", 20.0, 20.4)), **keys)  # a motor's 2 %: steady
    assert "run-up" not in steady.angle_source, steady.angle_source


BOX_A = description(stage(73, 31, bores=("30 mm", "20 mm")), name="boxA", speed="20 Hz", near="input", tacho="input")


def test_inspect_without_a_tacho_says_a_run_up_is_one(cli, tmp_path):
    # the run-up 20 -> 35 Hz inspected without its tacho: 'note: no line within ±1% of a mesh frequency at this speed
    # (the lines fit 0.3794 Hz (27.39 Hz as 1×M1))', a speed of 0.38 Hz; nothing said of its speed's course
    (tmp_path / "boxA.toml").write_text(BOX_A)
    args = ("--gearbox", tmp_path / "boxA.toml", "--vibration", "Beschl. 1 [g]")
    code, stdout, err = cli("inspect", _run_up_csv(tmp_path / "runup.csv", 20.0, 35.0), *args)
    assert code == 0, err
    said = " ".join(stdout.split())
    assert "its speed varies (a run-up or coast-down?): give its tacho (--tacho)" in said, said[-1500:]
    assert "lines move +69 %" in said and "0.3794 Hz" not in said, said[-1500:]
    code, stdout, err = cli("inspect", _run_up_csv(tmp_path / "steady.csv", 20.0, 20.2), *args)
    assert code == 0 and "run-up" not in stdout and "matches this recording" in " ".join(stdout.split()), stdout


def _wav24(path, x, fs, full_scale=5.0):
    """x (volts, one channel) as a 24-bit integer WAV of *full_scale* volts: what is over it is clipped."""
    import wave

    q = np.clip(np.round(x / full_scale * (2**23 - 1)), -(2**23), 2**23 - 1).astype("<i4")
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1), w.setsampwidth(3), w.setframerate(int(fs))
        w.writeframes(q.view(np.uint8).reshape(-1, 4)[:, :3].tobytes())
    return path


def test_inspect_says_a_channel_clipped_at_its_range(cli, tmp_path):
    # an int24 WAV in volts (100 mV/g, full scale 5 V) with a knock over its range: 4 samples at full scale, read
    # by inspect without a word
    (tmp_path / "boxB.toml").write_text(BOX_B)
    x = np.load(box_b_take(tmp_path / "b.npz", 7, seconds=3.0))["acc_top"].astype(float) * 0.1  # g -> V
    args = ("--gearbox", tmp_path / "boxB.toml", "--gain", "5 V", "--sensitivity", "100 mV/g", "--speed", "25 Hz")
    code, stdout, err = cli("inspect", _wav24(tmp_path / "clean.wav", x, 10240.0), *args)
    assert code == 0 and "clipped" not in stdout, err + stdout
    x[5000:5004] += 6.0
    code, stdout, err = cli("inspect", _wav24(tmp_path / "knock.wav", x, 10240.0), *args, "--json")
    assert code == 0, err
    assert json.loads(stdout)["flaws"] == ["4 samples flat at 490.3 m/s² (clipped at the logger's or sensor's range?)"]
    code, stdout, err = cli("inspect", tmp_path / "knock.wav", *args, "--report", tmp_path / "report")
    assert code == 0 and "4 samples flat at 490.3 m/s²" in (tmp_path / "report" / "report.html").read_text(), err


def test_a_test_take_at_another_load_is_said_so_beside_na4(tmp_path):
    # the 31/73 box's healthy takes at 1.6 x the load of the history: NA4 (a size) called 50 % of the healthy
    # record30 units, and nothing said why; the run now says each such take's level against its history's
    from types import SimpleNamespace

    from gearlab.kinds.detection_level import level_warnings

    rng = np.random.default_rng(5)

    def take(name, level):
        return SimpleNamespace(path=name), level * rng.normal(0, 1, (40, 256))

    cond = {
        "history": [take(f"h{i}.csv", 1.0) for i in range(3)],
        "test": [take("same.csv", 1.05), take("load2.csv", 1.6)],
    }
    lines = level_warnings(cond)
    assert len(lines) == 1 and lines[0].startswith("load2.csv: level 1.6 x its history's (another load or gain?)"), (
        lines
    )
    cond["test"] = [take("quiet.csv", 0.6)]
    assert level_warnings(cond)[0].startswith("quiet.csv: level 0."), level_warnings(cond)
    # a history of two loads (the 25/52 + 16/81 box's, 1 and 1.5 x): NA4's threshold 259, the chip's 20-100 uncalled
    cond = {"history": [take("h1.csv", 1.0), take("h2.csv", 1.0), take("h3.csv", 1.0), take("h4.csv", 1.5)], "test": []}
    (said,) = level_warnings(cond)
    assert said.startswith("the history's levels span 0.99 .. 1.5 x their median (two loads or gains?): NA4"), said
    # gearlab score said nothing either (NA4: 'fault' on the healthy take): its row holds the line, printed per file
    from gearlab.kinds.detection_level import level_line
    from gearlab.terminal import score_tables

    row = {"file": "load2.csv", "speed_hz": 20.0, "speed_from": "tacho", "condition": "20 Hz", "rule": "records"}
    row |= {"level": level_line(1.6), "method": "na4", "unit": "record30", "units": 12, "called": 12}
    row |= {"median_score": 16.9, "threshold": 1.0, "decision": "fault"}
    said = [str(t) for t in score_tables([row], "run")]
    assert any(t.startswith("level 1.6 x its history's (another load or gain?)") for t in said), said
    assert level_line(1.1) == ""


def test_a_few_samples_clipped_at_the_range_are_bridged_as_a_spike_is(tmp_path):
    # the 25/52 + 16/81 history's third take held a knock over its int24 WAV's 5 V (4 samples flat at full scale):
    # left whole (a lone sample only was bridged), its units' fm4 126 set the record10 threshold at 40.4 (3.77
    # without), and the 16T chip's takes (fm4 10.4, healthy 3) went uncalled by fm4 and na4
    from gearlab.data.recordings import cut_recording
    from gearlab.gearbox.orders import TachoShaft
    from gearlab.signals.spikes import without_spikes

    take = dict(np.load(box_b_take(tmp_path / "h.npz", 3, seconds=6.0)))
    take["acc_top"][20000:20004] = 50.0  # g: a logger's range
    np.savez(tmp_path / "knock.npz", **take)
    shaft = TachoShaft(name="intermediate", a=25, b=52)
    rec = cut_recording(
        str(tmp_path / "knock.npz"), vibration="acc_top", tacho="tacho", pulses_per_rev=4, tacho_shaft=shaft
    )
    bridged = without_spikes(rec.revolutions, rec.fs, rec.speed_hz)
    assert np.abs(rec.revolutions).max() > 40 and np.abs(bridged).max() < 5, np.abs(bridged).max()
    # a burst at one angle of a shaft every turn is the gearbox's: left whole
    take["acc_top"][20000:20004] = take["acc_top"][20000:20004] * 0 + take["acc_top"][:4]
    t = np.arange(take["acc_top"].size) / float(take["fs"])
    take["acc_top"] = take["acc_top"] + 40.0 * ((25.0 * t) % 1 < 1 / 409.6)
    np.savez(tmp_path / "tooth.npz", **take)
    rec = cut_recording(
        str(tmp_path / "tooth.npz"), vibration="acc_top", tacho="tacho", pulses_per_rev=4, tacho_shaft=shaft
    )
    assert np.array_equal(without_spikes(rec.revolutions, rec.fs, rec.speed_hz), rec.revolutions)
