"""Outside-user check of issue 39, round 16 (helper DF): recordings made outside gearlab (numpy, here; the round's own
boxes were a 26/101 + 31/78 reducer with an input tacho, in m/s² and in volts at 5 mV/(m/s²), and a 35/78 + 41/90 +
47/104 one without a tacho), read as docs/your_gearbox.md says. What a logger does to a take: a DC-coupled input's
offset, an ICP sensor settling, a dropout, clipping: said wherever a take is read, and the baseline taken out."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import FS, PULSES, signals, text, write_zip

from gearlab.parts import scoring
from gearlab.runs import RunDir


@pytest.fixture(scope="module")
def finished(tmp_path_factory, module_cache):
    """The tiny detection run (tests/detection_scenario: 16 Hz, 10 mV/g, the matched filter beside FM4 and NA4)."""
    folder = tmp_path_factory.mktemp("df")
    path = scenario(folder, methods=("matched_filter",))
    return shared_run(path, folder / "runs"), folder


def _take(path, change=None, seed=11, chip=0.0):
    """A 40-revolution take of the tiny run's records (m/s² written as volts at 10 mV/g), *change*d."""
    vib, tacho = signals(revolutions=40, seed=seed, phase=0.3, chip=chip)
    if change is not None:
        vib = change(vib, np.arange(vib.size) / FS)
    return write_zip(path, text(vib, tacho))


def _decisions(stdout: str) -> dict:
    return {(r["method"], r["unit"]): (r["decision"], r["median_score"]) for r in json.loads(stdout)}


BIAS = 11.5 / (0.01 / 9.80665)  # an ICP sensor's 11.5 V bias, logged DC-coupled, in m/s² at 10 mV/g


@pytest.mark.parametrize(
    "change, said",
    [
        (lambda x, t: x + BIAS, "the baseline sits at 1.128e+04 m/s²"),
        (lambda x, t: x + 40.0 * np.exp(-t / 0.8), "drifts by"),
    ],
)
def test_a_baseline_off_zero_or_drifting_is_taken_out_and_said(cli, finished, quiet, change, said):
    # DF: a healthy take logged DC-coupled (2.1 V over 5 mV/(m/s²)) was called a fault by the matched filter
    # (+4.48 over its threshold) and the likelihood ratio (+1850), unsaid; an ICP sensor settling (0.4 V decaying over
    # 0.8 s) by every method, its level '6.5 x its history's (another load or gain?)'. Both now score as the take
    # without them, and say what was taken out
    out, folder = finished
    clean = _take(folder / "clean.zip")
    code, stdout, err = cli("score", out, clean, "--json")
    assert code == 0, err
    before = _decisions(stdout)
    changed = _take(folder / "changed.zip", change)
    code, stdout, err = cli("score", out, changed, "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    assert {k: v[0] for k, v in _decisions(stdout).items()} == {k: v[0] for k, v in before.items()}
    for key, (_, median) in _decisions(stdout).items():
        assert median == pytest.approx(before[key][1], rel=0.02, abs=0.02), key
    assert all(any(said in f and "taken out" in f for f in r["flaws"]) for r in rows), rows[0]["flaws"]
    code, stdout, err = cli("score", out, changed)
    assert code == 0 and said in " ".join(stdout.split()), stdout


def test_a_dropout_and_a_clipped_take_are_scored_with_a_line_that_says_so(cli, finished, quiet):
    # DF: 0.3 s of zeros in a 2 s take (a logger's lost packets) was scored 'healthy' by every method with a line
    # saying its lines did not fit the gearbox (stage 2 read as a 26.9-tooth pinion, 31 described), the dropout unsaid;
    # a take clipped at the logger's +-5 V was read by inspect with a note, scored without one
    out, folder = finished

    def dropout(x, t):
        return np.where((t > 0.9) & (t < 1.2), 0.0, x)

    def clipped(x, t):
        return np.clip(x, -4.0, 4.0)  # the chip's rings over the range

    clip = _take(folder / "clip.zip", clipped, chip=8.0)
    code, stdout, err = cli("score", out, _take(folder / "gap.zip", dropout), clip)
    assert code == 0, err
    words = " ".join(stdout.split())
    assert "warning: a dropout: 2458 samples (0.3 s) flat at 0 m/s² from 0.9 s" in words, words
    assert "samples flat at 4 m/s² (clipped at the logger's or sensor's range?)" in words, words
    history = scoring.read_history(RunDir.open(out))
    assert any("a dropout" in f for r in history if r["file"].endswith("gap.zip") for f in r["flaws"])


def test_inspect_reads_a_take_as_score_does_without_its_baseline(tmp_path):
    # inspect gave the RMS of a drifting take (20.4 m/s² of a 3.0 m/s² vibration) and said nothing of the drift
    from test_inspect import described

    from gearlab.inspect import InspectOptions, inspect_record

    vib, tacho = signals(revolutions=40, seed=3)
    t = np.arange(vib.size) / FS
    np.savez(tmp_path / "a.npz", acc=vib + 30.0 + 40.0 * np.exp(-t / 0.8), tacho=tacho, fs=FS)
    np.savez(tmp_path / "b.npz", acc=vib, tacho=tacho, fs=FS)
    box = described((32, 96), speed="16 Hz")
    got = {
        n: inspect_record(str(tmp_path / f"{n}.npz"), box, InspectOptions("acc", "tacho", pulses_per_rev=PULSES))
        for n in "ab"
    }
    assert got["a"]["rms"] == pytest.approx(got["b"]["rms"], rel=0.01)
    assert got["b"]["flaws"] == [] and len(got["a"]["flaws"]) == 1 and "drifts by" in got["a"]["flaws"][0]


def test_a_take_scored_again_or_renamed_is_one_take_of_the_history(cli, finished, quiet, tmp_path):
    # DF: `gearlab score RUN take.csv` twice, then the same file renamed week2.csv: the history held it three times
    # and the trend drew three points ('records: 1 test_chip.csv, 2 test_chip.csv, 3 renamed_week2.csv')
    import shutil

    from gearlab.kinds.detection_scoring import score_trends

    out, folder = finished
    run = tmp_path / "run"
    shutil.copytree(out, run)  # a run directory copied elsewhere scores as the original
    (run / "scoring" / "history.jsonl").unlink(missing_ok=True)  # the other tests' takes
    take = _take(folder / "week1.zip", seed=21)
    renamed = folder / "week2.zip"
    shutil.copyfile(take, renamed)
    other = _take(folder / "week3.zip", seed=22)
    said = []
    for files in ((take,), (take,), (renamed, other), (other, other)):
        code, stdout, err = cli("score", run, *files)
        assert code == 0, err
        said.append(" ".join(stdout.split()))
    assert "not added" not in said[0]
    assert "scored before, at " in said[1] and f"as {take}: not added to the history again" in said[1], said[1]
    assert f"as {take}: not added to the history again" in said[2], said[2]
    assert f"as {other}: not added to the history again" in said[3], said[3]
    history = scoring.read_history(RunDir.open(run))
    assert {h["file"] for h in history} == {str(take), str(other)}
    assert len(history) == 2 * len([h for h in history if h["file"] == str(take)])
    (chart,) = score_trends(RunDir.open(run))
    assert "records: 1 week1.zip, 2 week3.zip;" in chart.title, chart.title
    assert (
        not (out / "scoring" / "history.jsonl").exists()
        or str(take) not in (out / "scoring" / "history.jsonl").read_text()
    )


def test_the_which_gear_table_says_a_take_too_short_for_the_check_was_not_read():
    # DF: 2 s takes of a 26/101 + 31/78 box at 28.5 Hz (5.7 output turns, the check needs 8): the detection run's
    # table said 'localised on: nothing' beside its chipped takes (its localisation.json: 'too short for the
    # which-gear check'), read as 'no change on any gear'
    from gearlab.kinds.detection_which_gear import records_md

    short = "too short for the which-gear check: 5.73 output-shaft turns (56 input revolutions), it needs 8"
    loc = {
        "watched": ["input pinion 26T (stage 1)"],
        "records": {
            "rec/test_chip.csv": {
                "call": "watched-gear fault (not localised)",
                "condition": "28.5 Hz",
                "method": "",
                "named": None,
                "named_shaft": None,
                "nonsync": {"changed": False, "note": short.replace("which-gear", "non-synchronous")},
                "shafts": [],
                "summary": f"not localised: {short}",
            }
        },
    }
    row = records_md(loc, {"rec/test_chip.csv": "fault"}, {"rec/test_chip.csv"}).splitlines()[-1]
    assert f"| fault | not read: {short} |" in row and "nothing" not in row, row


@pytest.mark.parametrize("top, leak", [(477.71, 24.09), (399.18, 25.90)])
def test_a_strong_change_s_leak_into_a_shaft_whose_harmonics_lie_beside_its_own_is_not_other_damage(top, leak):
    # DF: a 35/78 + 41/90 + 47/104 box at 45 Hz without a tacho, 8 s takes, an impulse once per turn of the 104T output
    # gear: inspect --history named the output gear (z 478 and 399, threshold 2.81) and also the intermediate 1 shaft
    # (z 24.1 and 25.9: 5.0 and 6.5 % of the named z). That shaft turns 4.93 times an output turn: its 14th and 15th
    # harmonics lie within a bin of the impulse comb's 69th and 74th (8 s: bins of 0.0028 input orders), and its TSA
    # passes them. A take damaged on the output gear alone was called damaged on the 41T pinion too, a fault of a
    # scenario watching it; damage on two gears of different shafts stands at 57-71 % of the named z (CV's 106/127:
    # 594 of 1039; a pinion chip with a chip on its wheel: 66 of 93)
    from gearlab.data.which_gear import named_gears
    from gearlab.inspect_history import call_of

    def shaft(name, gear, z):
        return {"shaft": name, "gear": gear, "gears": [gear], "z": z, "threshold": 2.81, "flagged": z > 2.81}

    found = {"named": "output gear 104T (stage 3)", "named_shaft": "output", "summary": ""}
    found["shafts"] = [
        shaft("output", "output gear 104T (stage 3)", top),
        shaft("intermediate 1", "intermediate 1 pinion 41T (stage 2)", leak),
    ]
    assert named_gears(found) == "output gear 104T (stage 3)"
    assert call_of(found, {}) == "localised change: output gear 104T (stage 3)"
    found["shafts"][1]["z"] = 0.57 * top  # damage of its own on that shaft: named as before
    assert named_gears(found) == "output gear 104T (stage 3); intermediate 1 pinion 41T (stage 2)"


def test_a_take_sampled_too_slowly_for_its_history_s_band_is_refused_in_one_line(cli, finished, quiet):
    # DF: a healthy take at 10 kHz scored by a run whose history was at 25.6 kHz (bands of 158 and 404 input orders):
    # the matched filter +0.0002 and the likelihood ratio +0.026 over their record30 thresholds, 1 of 2 units called,
    # unsaid (the same take at 25.6 kHz: -0.007 and -10.5); a detection run with such a test take scored it alike
    out, folder = finished
    vib, tacho = signals(revolutions=40, seed=11, phase=0.3)
    slow = write_zip(folder / "slow.zip", text(vib[::2], tacho[::2]))  # 4096 Hz: band 102 of the history's 205 orders
    code, stdout, err = cli("score", out, slow, "--key", f"fs={FS / 2} Hz")
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1 and not stdout, err
    assert f"{slow}: sampled at 4.096 kHz, its band ends at input order " in line, line
    assert "below the " in line and "its condition's history is read to" in line, line
    code, _, err = cli("score", out, _take(folder / "fast_enough.zip"))
    assert code == 0, err


def test_the_gap_diagnosis_says_what_the_acquisition_did_to_its_history(tmp_path):
    # DF: a history take logged DC-coupled (an ICP sensor's bias) was read by the gap diagnosis without a word; its
    # notes now say it, as a detection run's warnings and gearlab score do
    from dataclasses import asdict

    from gearlab.kinds.gap import target_of
    from gearlab.kinds.gap_inputs import TargetEntry, read_history

    files = []
    for i in range(2):
        vib, tacho = signals(revolutions=40, seed=30 + i)
        np.savez(tmp_path / f"h{i}.npz", acc_ms2=vib + 25.0 * i, tacho=tacho, fs=FS)
        files.append({"file": f"h{i}.npz", "role": "history", "label": "healthy"})
    entry = {
        **asdict(TargetEntry()),
        "vibration": "acc_ms2",
        "tacho": "tacho",
        "pulses_per_rev": PULSES,
        "files": files,
    }
    notes = read_history(target_of(entry, "s.toml: [target]", tmp_path), lambda e: None)[2]
    said = [n for n in notes if "baseline" in n]
    assert len(said) == 1 and said[0].startswith("h1.npz: the baseline sits at 25 m/s²"), notes


def test_a_run_scores_after_its_project_folder_moved_or_its_description_changed(tmp_path):
    # DF: a detection run of a description (26/101 + 31/78, '[source] gearbox = "boxa.toml"'), its project folder
    # moved: `gearlab score RUN take.csv` stopped with '/old/folder/boxa.toml: no such gearbox description'. The run
    # keeps the description it simulated (scoring/gearbox.toml) and reads it where the file it names is gone or changed
    import shutil

    from gearboxes import description, stage

    from gearlab.errors import GearlabInputError
    from gearlab.gearbox.simulation import gearbox_of, reference
    from gearlab.kinds.detection_which_gear import KEPT, localisation_of

    (tmp_path / "proj").mkdir()
    box = tmp_path / "proj" / "boxa.toml"
    box.write_text(description(stage(26, 101), stage(31, 78), name="boxa", speed="28.5 Hz"))
    ref = reference(str(box))
    run = tmp_path / "run"
    (run / "scoring").mkdir(parents=True)
    (run / "scenario.toml").write_text("")
    (run / "localisation.json").write_text(json.dumps({"preset": ref, "events": {"preset": ref, "effects": []}}))
    (run / Path(*KEPT)).write_bytes(box.read_bytes())
    assert localisation_of(RunDir.open(run))["preset"] == ref  # where it was: as it was
    shutil.move(tmp_path / "proj", tmp_path / "moved")
    with pytest.raises(GearlabInputError, match="no such gearbox description"):
        gearbox_of(ref)
    for gone in ("moved", "edited"):
        if gone == "edited":  # put back, then edited after the run
            shutil.move(tmp_path / "moved", tmp_path / "proj")
            box.write_text(box.read_text().replace("28.5 Hz", "30 Hz"))
        meta = localisation_of(RunDir.open(run))
        assert meta["preset"] != ref and meta["preset"] == meta["events"]["preset"], meta
        assert [(s.pinion.z, s.wheel.z) for s in gearbox_of(meta["preset"]).stages] == [(26, 101), (31, 78)]


@pytest.mark.parametrize("fmt", ["h5", "mat"])
def test_a_rate_field_inside_a_group_is_no_channel(tmp_path, fmt):
    # DF: an HDF5 group (and a MATLAB v7.3 struct: its fields a group's datasets) of 'acc' and 'fs': inspect without
    # --vibration said 'which channel is the vibration? the file has take/acc, take/fs', and listed it as a channel
    import h5py

    from gearlab.inspect import InspectOptions, inspect_record

    vib, _ = signals(revolutions=40, seed=5)
    path = tmp_path / f"take.{fmt}"
    with h5py.File(path, "w", userblock_size=512 if fmt == "mat" else 0) as h:
        group = h.create_group("take")
        for name, values in (("acc", vib), ("fs", np.array([[FS]]))):
            group.create_dataset(name, data=values.reshape(-1, 1))
            group[name].attrs["MATLAB_class"] = np.bytes_("double")
    if fmt == "mat":  # MATLAB's 128-byte text header in the user block
        with path.open("r+b") as f:
            f.write(b"MATLAB 7.3 MAT-file, HDF5 schema 1.00 .".ljust(116) + bytes(8) + b"\x00\x02IM")
    got = inspect_record(str(path), None, InspectOptions(speed_hz=16.0))
    assert got["vibration"] == "take/acc" and got["channels"] == ["take/acc"] and got["fs_hz"] == FS


def test_a_flagged_take_too_short_for_the_which_gear_check_is_a_fault_of_no_gear(cli, finished, quiet, tmp_path):
    # DP: a 2 s take with damage on another gear than the watched one was called a fault at record30 and reported as
    # the watched gear's, while the which-gear check could not read so short a take: its gear is said undetermined
    out, _ = finished
    vib, tacho = signals(revolutions=10, seed=12, phase=0.3, chip=4.0)  # 9 whole turns: 7.5 output turns, 10 needed
    short = write_zip(tmp_path / "short.zip", text(vib, tacho))
    code, stdout, err = cli("score", out, short, "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    said = "fault, gear not determined: 7.5 turns of the output shaft, 10 needed"
    assert {r["call"] for r in rows} == {said}, rows
    called = [r for r in rows if r["called"] > r["units"] / 2]
    assert called and {r["decision"] for r in called} == {said}, rows
    history = scoring.read_history(RunDir(Path(out)))
    assert {r["decision"] for r in history if r["file"] == str(short) and r["called"] > r["units"] / 2} == {said}
    code, stdout, err = cli("score", out, short)
    assert code == 0 and "which gear: not determined (not localised: too short for the which-gear check" in stdout
    assert "│ fault, gear not " in stdout, stdout
