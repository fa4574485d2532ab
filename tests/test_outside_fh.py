"""Outside user FH (issue 39, round 26): a 39/61 single-stage drive recorded by two accelerometers (one on the
gear's bearing, one on the motor's) beside a once-per-turn tacho, takes named by their date; its takes made here
with numpy (both shafts' lines, the mesh's harmonics modulated in amplitude and phase, noise). A user with an idler
between pinion and wheel writes it as a third gear of the stage."""

from __future__ import annotations

import functools
import json
import shutil

import numpy as np
import pytest
from detection_scenario import call_every_row, scenario, shared_run
from gearboxes import text_rows
from textrecords import signals, text, write_zip

BOX = (
    '[gearbox]\nname = "mill39"\n[operation]\nspeed = "30 Hz"\nload = "20 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    'pinion = { z = 39, bore = "25 mm" }\nwheel = { z = 61, bore = "30 mm" }\n'
    '[sensor]\nnear = "input"\ntacho = "input"\n'
)


def test_an_idler_written_in_a_stage_is_refused_with_the_two_stages_to_write(tmp_path, cli):
    # 'idler = { z = 45 }' beside pinion and wheel was 'unknown key (did you mean 'module'?)': no word of how an idler
    # is described (two stages sharing its tooth count, as the guide's last section says)
    idler = BOX.replace("wheel = {", 'idler = { z = 45, bore = "25 mm" }\nwheel = {')
    (tmp_path / "box.toml").write_text(idler)
    code, out, err = cli("validate", tmp_path / "box.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "box.toml: [[stages]] #1 key 'idler'" in line, err
    assert "did you mean" not in line and "two [[stages]]" in line, line
    assert "39/45" in line and "45/61" in line, line


def test_a_history_of_one_take_does_not_put_a_called_take_at_its_own_level_off_it():
    # one healthy take, the least a user has: its spread read 0, so a called take at 1.0 x its level (a sweeping take,
    # a 5 %-clipped one) read 'level 1 x its history's, its own takes within 0.0% of it: ... the call may be the
    # level's change', in the run's warnings and in every `gearlab score` row; a take 1.5 x off is still said
    from types import SimpleNamespace

    from gearlab.kinds.detection_level import called_level, level_line, run_levels

    revs = np.random.default_rng(1).normal(size=(30, 256))
    take = lambda name, k: (SimpleNamespace(path=name), k * revs)  # noqa: E731
    ratios, spread, _ = run_levels({"history": [take("h.csv", 1.0)], "test": [take("t.csv", 1.03), take("x", 1.5)]})
    assert called_level(True, [], ratios["t.csv"], spread) == "", (ratios, spread)
    assert level_line(ratios["x"]).startswith("level 1.5 x its history's")
    # two history takes 2 % apart: a called take 10 % off them is still said, as before
    ratios, spread, _ = run_levels({"history": [take("a", 1.0), take("b", 1.02)], "test": [take("t.csv", 1.1)]})
    assert called_level(True, [], ratios["t.csv"], spread).startswith("level 1.1 x its history's, its own takes")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, module_cache):
    """The tie's tiny run (detection_scenario.shared_run) and two takes of its box: one plain, one whose first 5 %
    surged 4 x, its mesh's peaks there flat at the ADC's range."""
    folder = tmp_path_factory.mktemp("tie")
    out = shared_run(scenario(folder, methods=("source_only",)), folder / "runs")
    takes = tmp_path_factory.mktemp("takes")
    vib, tacho = signals(revolutions=41, seed=11, phase=0.3)
    plain = write_zip(takes / "plain.zip", text(vib, tacho))
    surge = vib * np.where(np.arange(vib.size) < vib.size // 20, 4.0, 1.0)  # 5 % of the take at 4 x: the ADC's range
    top = 2.0 * float(np.max(np.abs(vib)))
    return out, plain, write_zip(takes / "clipped.zip", text(np.clip(surge, -top, top), tacho))


def _called(cli, tiny, monkeypatch, take) -> list[dict]:
    """The rows of *take* scored with every classical row's thresholds under its scores: called."""
    call_every_row(monkeypatch)
    mine = shutil.copytree(tiny[0], tiny[0].with_name(f"{tiny[0].name}-{take.stem}"), dirs_exist_ok=True)
    code, stdout, err = cli("score", mine, take, "--json")
    assert code == 0, err
    return json.loads(stdout)


def test_a_called_clipped_take_is_told_the_call_may_be_the_clipping(cli, tiny, monkeypatch):
    # a healthy 39/61 take clipped over 5 % of its samples (its mesh's peaks, modulated once a turn) was scored
    # 'input pinion 39T (stage 1), tooth 1 of 39' at z 18 over 2.6 by fm4 and likelihood_ratio; the clipping was a
    # warning line above, '3000 samples flat at 5.397 m/s² (clipped at the logger's or sensor's range?)', the call
    # not doubted
    rows = _called(cli, tiny, monkeypatch, tiny[2])
    assert any(r["decision"] != "healthy" for r in rows), rows[0]
    flaws = rows[0]["flaws"]  # each side clipped
    assert len(flaws) == 2 and all("clipped at the logger's or sensor's range" in f for f in flaws), flaws
    assert all("the call may be the clipping" in f for f in flaws), flaws
    assert all(r["flaws"] == flaws for r in rows)
    plain = _called(cli, tiny, monkeypatch, tiny[1])  # called too, not clipped: nothing said
    assert any(r["decision"] != "healthy" for r in plain) and plain[0]["flaws"] == [], plain[0]


def test_a_steady_mesh_clipped_over_5_percent_of_its_samples_is_said_clipped():
    # the 39/61 box's mesh, steady (no surge), its peaks clipped by the ADC over 5 % of the take, was read without a
    # word: its clipped value 1.1 robust deviations off the median, under the 3 asked (a tone's peaks lie near 1.4);
    # a quantised tone's peak, which repeats too, and a noisy one's stay unsaid
    from gearlab.signals.spikes import acquisition

    vib, _ = signals(revolutions=41, seed=11, phase=0.3)
    top = float(np.quantile(np.abs(vib), 0.95))
    _, flaws = acquisition(np.clip(vib, -top, top), 8192.0)
    assert len(flaws) == 2 and all("clipped at the logger's or sensor's range" in f for f in flaws), flaws
    assert acquisition(vib, 8192.0)[1] == ()
    tone = np.sin(2 * np.pi * 1170.0 * np.arange(60000) / 20000.0)
    quantised = np.round(0.1 * tone * 32767) / 32767 * 50.0  # int16 at a tenth of its range, in m/s²
    assert acquisition(quantised, 20000.0)[1] == ()
    noisy = np.round((0.1 * tone + 0.002 * np.random.default_rng(3).normal(size=tone.size)) * 32767) / 32767 * 50.0
    assert acquisition(noisy, 20000.0)[1] == ()


def test_a_run_s_verdict_doubts_a_call_on_a_clipped_take():
    # the 39/61 run's healthy take clipped over 5 % of its samples opened the verdict with 'damage on the input pinion
    # 39T (stage 1): z = 32.05 ..., tooth 1 of 39; called by 1 of 4 methods ... (fm4 +18.6 sd); look at that gear.',
    # the clipping a warning further down
    from gearlab.kinds.detection_summary import take_lines

    take = {
        "condition": "30 Hz", "named": "input pinion 39T (stage 1)",
        "call": "watched-gear fault: input pinion 39T (stage 1)",
        "summary": "input pinion 39T (stage 1): z = 32.05 (threshold 2.58), tooth 1 of 39",
        "nonsync": {"changed": False, "order": 0.73, "z": 4.4, "threshold": 5.9},
    }  # fmt: skip
    flat = "rec/clip.csv: 3000 samples flat at 5.397 m/s² (clipped at the logger's or sensor's range?)"
    summary = {"which_gear": {"records": {"rec/clip.csv": take}}, "conditions": {"30 Hz": {"warnings": [flat]}}}
    records = [
        {"condition": "30 Hz", "method": "fm4", "thresholds": {"record30": 1.0},
         "test_scores": {"rec/clip.csv": {"record30": [2.0, 3.0]}}},
    ]  # fmt: skip
    (line,) = take_lines(summary, records, "record30")
    assert line.startswith("take clip.csv: clipped (3000 samples flat at 5.397 m/s²): the call may be the clip"), line
    assert "record at a larger range" in line and "look at that gear" not in line, line
    (plain,) = take_lines({**summary, "conditions": {}}, records, "record30")  # not clipped: as before
    assert plain.startswith("take clip.csv: damage on the input pinion") and plain.endswith("look at that gear."), plain


def _sweep(path, seed: int, seconds: float = 3.0, f0: float = 30.0, sweep: float = 0.15) -> None:
    """A 39/61 take whose input speed sweeps linearly by *sweep* of *f0* over it, in volts at 100 mV/g (columns
    time_s, acc_gear_V, tacho_V): the mesh's harmonics modulated in amplitude and phase, both shafts' lines, noise."""
    path.write_text(_sweep_text(seed, seconds, f0, sweep))


@functools.cache
def _sweep_text(seed: int, seconds: float, f0: float, sweep: float) -> str:
    """_sweep's file, made once a process: the tests here and test_validate_screen write the same steady takes
    (seeds 1-3 and 7) into several folders."""
    rng = np.random.default_rng(seed)
    fs = 20000.0
    t = np.arange(int(seconds * fs)) / fs
    th = 2 * np.pi * np.cumsum(f0 * (1 + sweep * (t / seconds - 0.5))) / fs
    out = th * 39 / 61
    x = 0.3 * np.cos(th) + 0.2 * np.cos(out)
    for h, a in ((1, 1.0), (2, 0.5), (3, 0.25)):
        x = x + a * (1 + 0.2 * np.cos(th + 0.3) + 0.1 * np.cos(out + 1.0)) * np.cos(h * 39 * th + 0.1 * np.sin(th) + h)
    volts = 0.03 * (x + rng.normal(0, 0.15, t.size))
    tacho = np.where(np.mod(th, 2 * np.pi) < 0.3, 5.0, 0.0)
    return "time_s,acc_gear_V,tacho_V\n" + text_rows("%.6f,%.6f,%.1f", t, volts, tacho)


def _sweep_scenario(path) -> None:
    """A detection scenario at *path* of the box.toml beside it: h*.csv the history, test.csv a test take (_sweep's
    columns)."""
    path.write_text(
        '[scenario]\nname = "sweep"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
        '[target]\nvibration = "acc_gear_V"\ntacho = "tacho_V"\nsensitivity = "100 mV/g"\n'
        'files = [{ file = "h*.csv", role = "history", label = "healthy" },\n'
        '  { file = "test.csv", role = "test", label = "healthy" }]\n'
        '[[methods]]\nadapter = "matched_filter"\n'
    )


def test_a_sweeping_history_take_s_speed_is_said_as_the_run_read_it(tmp_path, cli):
    # three 3 s history takes sweeping 15 % about 30 Hz: each printed '30.771 Hz, from tacho ...; 27.9 Hz .. 32.09 Hz
    # over the take: a run-up or coast-down? its mean speed is its condition (steady records compare)', where 30.77 Hz
    # is the median of the 32 steady turns the run used, not the take's mean (30.0 Hz); the run then stops (3 record30
    # units of 8), before any simulation
    (tmp_path / "box.toml").write_text(BOX)
    for i in (1, 2, 3, 4):
        _sweep(tmp_path / (f"h{i}.csv" if i < 4 else "test.csv"), i)
    _sweep_scenario(tmp_path / "run.toml")
    code, out, err = cli("run", tmp_path / "run.toml", "--quick", "--out", tmp_path / "runs")
    said = [line for line in (out + err).splitlines() if line.startswith("h1.csv: ")]
    assert code == 2 and "expected at least 8" in err, err
    assert said and "its mean speed is its condition" not in said[0], said
    assert "revolutions at" in said[0] and "steady part" in said[0], said
    # the refusal says each take's steady part itself (validate's, below, comes before any log line)
    (line,) = [x for x in err.splitlines() if "expected at least 8" in x]
    assert "gives 3 'record30' units" in line and "steady parts used: h1.csv: 32 of 89 revolutions at " in line, line
    # validate refuses it in the same line (a text take's header gives no length: its tacho is read, not its
    # vibration); the same takes steady pass
    code, out, said = cli("validate", tmp_path / "run.toml")
    assert code == 2 and said.strip() == line, (said, line)
    for i in (1, 2, 3):
        _sweep(tmp_path / f"h{i}.csv", i, sweep=0.0)
    code, out, err = cli("validate", tmp_path / "run.toml")
    assert code == 0 and out.startswith("OK: "), err


def test_a_called_take_s_level_near_its_history_s_is_said_in_the_digits_that_tell_it_off():
    # two history takes 0.1 % apart: the 39/61 run's chipped take, 0.8 % louder, read 'level 1 x its history's, its
    # own takes within 0.1% of it: ... the call may be the level's change', a level as its history's said off it
    from gearlab.kinds.detection_level import called_level

    said = called_level(True, [], 1.008, 0.001)
    assert said.startswith("level 1.01 x its history's, its own takes within 0.1% of it"), said
    assert called_level(True, [], 0.83, 0.01).startswith("level 0.83 x its history's"), "as before"


def test_inspect_s_call_against_one_history_take_says_it_rests_on_that_take(tmp_path, cli):
    # a healthy 39/61 take against the one healthy take a user has read 'call: other damage: non-synchronous
    # (bearing-like), at order 9.63' (z 5.2 over 4.1; over two history takes its threshold is 5.9, and no take is
    # called), with nothing said of the one take, as a run's verdict says it ('one history take: ...')
    box = tmp_path / "box.toml"
    box.write_text(BOX)
    for i in (1, 2, 3):
        _sweep(tmp_path / f"h{i}.csv", i, sweep=0.0)
    _sweep(tmp_path / "take.csv", 7, sweep=0.0)
    text = tmp_path / "take.csv"
    rows = text.read_text().splitlines()
    bumped = [rows[0]] + [
        f"{t},{float(v) + (0.05 if float(k) > 1 else 0.0):.6f},{k}" for t, v, k in (r.split(",") for r in rows[1:])
    ]  # a bump while the tacho is high: once a turn, at one angle (a localised change on the input shaft)
    text.write_text("\n".join(bumped) + "\n")
    keys = ("--gearbox", box, "--vibration", "acc_gear_V", "--tacho", "tacho_V", "--sensitivity", "100 mV/g")
    code, out, err = cli("inspect", text, *keys, "--json", "--history", tmp_path / "h1.csv")
    call = json.loads(out)["localisation"]["call"] if code == 0 else err
    assert not call.startswith("no change") and "of one history take" in call, call
    code, out, err = cli(
        "inspect", text, *keys, "--json", "--history", tmp_path / "h1.csv", "--history", tmp_path / "h2.csv"
    )
    call = json.loads(out)["localisation"]["call"] if code == 0 else err
    assert not call.startswith("no change") and "of one history take" not in call, call


def test_healthy_takes_against_one_history_take_are_not_called_non_synchronous(tmp_path, cli):
    # the least history a user has, one healthy take: its threshold the bare Gaussian floor (4.1), no records' spread
    # read, where the take's mean carries the blocks' noise as the new take's does; of five healthy takes 2 were
    # called 'other damage: non-synchronous (bearing-like)' (z 6.5 at order 3.37, 4.5 at 7.11), each with 'of one
    # history take' beside it. The threshold of one take's blocks alone: 7.6
    (tmp_path / "box.toml").write_text(BOX)
    keys = ("--gearbox", tmp_path / "box.toml", "--vibration", "acc_gear_V", "--tacho", "tacho_V")
    _sweep(tmp_path / "h1.csv", 1, sweep=0.0)
    for seed in (4, 5, 6, 7, 8):
        _sweep(tmp_path / "take.csv", seed, sweep=0.0)
        code, out, err = cli("inspect", tmp_path / "take.csv", *keys, "--json", "--history", tmp_path / "h1.csv")
        assert code == 0, err
        found = json.loads(out)["localisation"]
        assert found["call"].startswith("no change"), (seed, found["call"], found["nonsync"]["z"])


def test_score_against_a_run_of_one_history_take_says_its_thresholds_rest_on_it(tmp_path, cli, tiny):
    # a run of one history take says so in its verdict ('<condition>: one history take: ...'); `gearlab score` of a
    # new take against it said nothing, in its rows or its printout, its thresholds that one take's all the same
    files = [("h1", "history", "healthy", 0.0), ("h3", "test", "healthy", 0.0), ("f1", "test", "fault", 4.0)]
    run = shared_run(scenario(tmp_path, files=files, methods=("source_only",)), tmp_path / "runs")
    take = tmp_path / "data" / "h3.zip"
    code, out, err = cli("score", run, take, "--json")
    assert code == 0, err
    rows = json.loads(out)
    said = {r["history"] for r in rows}
    assert len(said) == 1 and "one history take" in next(iter(said)) and "add two or more" in next(iter(said)), said
    code, out, err = cli("score", run, take)
    assert code == 0 and "warning: " + next(iter(said)) in " ".join(out.split()), out
    mine = shutil.copytree(tiny[0], tmp_path / "tiny")  # its own copy: scoring appends to a run's history
    code, out, err = cli("score", mine, tiny[1], "--json")  # two history takes: nothing said
    assert code == 0 and all(r["history"] is None for r in json.loads(out)), err
