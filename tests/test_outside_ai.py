"""Outside user AI (issue 39 leftovers): what outside users of the previous stop found left to do."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.errors import GearlabInputError
from gearlab.gearbox import load_gearbox
from gearlab.inspect import InspectOptions
from gearlab.inspect_history import localisation

FS, SPEED = 2048.0, 31.0


def _take(path, seconds: float = 1.5, seed: int = 0) -> str:
    """A 1.5 s take of a 23/59 + 19/67 box at 31 Hz as .npz (m/s²): both meshes modulated by their shafts,
    white noise, a tacho once per input turn."""
    t = np.arange(int(seconds * FS)) / FS
    theta = 2 * np.pi * SPEED * t + seed
    mid = theta * 23 / 59
    x = (1 + 0.2 * np.cos(theta)) * np.cos(23 * theta) + (1 + 0.2 * np.cos(mid)) * 0.6 * np.cos(19 * mid + 0.4)
    x = x + np.random.default_rng(seed).normal(0, 0.05, t.size)
    tacho = np.where(theta % (2 * np.pi) < 0.4, 5.0, 0.0)
    np.savez(path, acc=x, tach=tacho, fs=FS)
    return str(path)


def test_inspect_history_on_short_takes_says_why_not_instead_of_failing(tmp_path):
    # AF's 1.5 s takes of a 23/59 + 19/67 box at 31 Hz (46 input turns, 5.1 output turns each): plain inspect read
    # them, --history exited 2 'error: 22 input revolutions hold 1 complete turns of the output shaft; expected at
    # least 2' (the history's units are half takes under 4 takes). Too few output turns for the which-gear check
    # is said in one phrase, the take itself stays inspected
    (tmp_path / "box.toml").write_text(
        description(stage(23, 59), stage(19, 67, module="3 mm"), speed="31 Hz", near="input", tacho="input")
    )
    box = load_gearbox(tmp_path / "box.toml")
    history = [_take(tmp_path / f"h{i}.npz", seed=i) for i in (1, 2, 3)]
    loc = localisation(_take(tmp_path / "r.npz", seed=7), history, box, InspectOptions("acc", "tach"))
    assert loc["named"] is None and loc["shafts"] == [], loc
    assert loc["summary"].startswith("not localised: the history's takes: too short for the which-gear check: 4.97"), (
        loc["summary"]
    )
    assert "output-shaft turns (45 input revolutions), it needs 8" in loc["summary"], loc["summary"]
    assert loc["call"].startswith("not read against the history:"), loc["call"]
    assert "\n" not in loc["call"]
    # takes of 8.2 output turns are read, the output shaft's evidence with the others'
    history = [_take(tmp_path / f"l{i}.npz", seconds=2.4, seed=i) for i in (1, 2, 3)]
    loc = localisation(_take(tmp_path / "lr.npz", seconds=2.4, seed=7), history, box, InspectOptions("acc", "tach"))
    assert [s["shaft"] for s in loc["shafts"]] and "output" in [s["shaft"] for s in loc["shafts"]], loc["summary"]


def test_a_detection_run_s_table_md_opens_with_its_verdict(cli, tmp_path, no_figures):
    # docs/your_gearbox.md step 6: 'report.html and table.md of the run directory ... open with the verdict: which
    # methods meet the goal'. table.md opened with the first condition's AUC table; the verdict was in report.html,
    # the terminal and the TUI only. report.html says it once (its own Verdict section), not again over a table
    from detection_scenario import scenario, shared_run

    from gearlab.report import build_report
    from gearlab.verdict import verdict_lines

    out = shared_run(scenario(tmp_path, methods=("matched_filter",)), tmp_path / "runs")
    said = verdict_lines(out)
    intro = next(i for i, x in enumerate(said) if x.startswith("At record"))  # after the per-take lines
    assert said and "goal met by" in said[intro + 1], said
    table = (out / "table.md").read_text()
    head, rest = table.split("\n\n", 1)
    assert head.splitlines() == [f"Verdict: {said[0]}", *(f"- {line}" for line in said[1:])], head
    assert rest.startswith("Condition "), rest[:80]
    html = build_report(out)
    assert html.count(said[intro + 1].split(":")[0] + ": goal met by") == 1, "the verdict twice in report.html"


@pytest.mark.parametrize(
    "where, name, value",
    [
        ("attribute", "fs_kHz", 25.6),
        ("attribute", "SampleRate_kHz", 25.6),
        ("dataset", "sampling_rate_hz", 25600.0),
        ("dataset", "fs_Hz", 25600.0),
        ("attribute", "dt_us", 1e6 / 25600),
    ],
)
def test_an_hdf5_rate_named_with_its_unit_is_read_at_validate_and_run(tmp_path, where, name, value):
    # an HDF5 file whose rate attribute is 'fs_kHz' (25.6): 'no sampling rate'. A rate's (or interval's) unit in its
    # field's name is read by the rule a CSV preamble's 'Sampling Rate (kHz): 25.6' is read by
    import h5py

    from gearlab.data.recordings import check_recording, read_header, read_recording

    path = tmp_path / "take.h5"
    x = np.random.default_rng(0).standard_normal(2560)
    with h5py.File(path, "w") as f:
        f["acc"] = x
        if where == "attribute":
            f.attrs[name] = value
        else:
            f[name] = value
    assert read_header(path).stated[0] == pytest.approx(25600.0), read_header(path).stated
    check_recording(path, "s.toml: [target]", {"vibration": "acc"})  # validate: no 'no sampling rate'
    rec = read_recording(path, "acc", None)
    assert rec.fs == pytest.approx(25600.0) and rec.signal.size == 2560
    # a name whose unit is no rate's is no rate field (nor a time): still 'no sampling rate'
    with h5py.File(path, "w") as f:
        f["acc"] = x
        f.attrs["fs_mm"] = 25.6
    with pytest.raises(GearlabInputError, match="no sampling rate"):
        read_recording(path, "acc", None)


def test_an_npz_rate_named_with_its_unit_is_read(tmp_path):
    from gearlab.data.recordings import read_recording

    path = tmp_path / "take.npz"
    np.savez(path, acc=np.random.default_rng(0).standard_normal(2560), SampleRate_kHz=25.6)
    assert read_recording(path, "acc", None).fs == pytest.approx(25600.0)


def test_a_run_up_without_a_tacho_read_at_one_speed_says_so(tmp_path):
    # 14 -> 19 Hz over 12 s without its tacho, at the declared 16 Hz: a detection run and gearlab score cut a run-up
    # to its revolutions at the history's speed only where the angle gives each one's speed (a tacho's, or the mesh
    # phase followed); read at one speed it was scored whole (191 'revolutions'), unsaid. Its spectra show it
    from test_outside_n import runup
    from textrecords import FS

    from gearlab.data.recordings import cut_recording
    from gearlab.signals.checks import VARIES_WORDS

    runup(tmp_path / "up.zip", 14.0, 19.0, 12.0)
    rec = cut_recording(str(tmp_path / "up.zip"), vibration=0, fs=FS, speed_hz=16.0)
    whole = "(a run-up or coast-down?): read whole at one speed: no tacho shows its speed revolution by revolution"
    assert rec.angle_source.startswith("nominal speed 16 Hz; its spectrum's lines move +3"), rec.angle_source
    assert rec.angle_source.endswith(whole) and VARIES_WORDS not in rec.angle_source, rec.angle_source
    # with its tacho: each revolution's speed, cut in band as before (no such words); a steady take: none
    tacho = cut_recording(str(tmp_path / "up.zip"), vibration=0, tacho=2, pulses_per_rev=10, fs=FS)
    assert VARIES_WORDS in tacho.angle_source and whole not in tacho.angle_source, tacho.angle_source
    runup(tmp_path / "steady.zip", 16.0, 16.0, 8.0)
    steady = cut_recording(str(tmp_path / "steady.zip"), vibration=0, fs=FS, speed_hz=16.0)
    assert steady.angle_source == "nominal speed 16 Hz", steady.angle_source


def test_a_detection_run_warns_of_a_run_up_test_take_it_reads_whole_without_a_tacho(tmp_path):
    from detection_scenario import scenario
    from test_outside_n import runup
    from textrecords import PULSES

    from gearlab.kinds.detection_records import read_target
    from gearlab.notebook import load_scenario

    (tmp_path / "data").mkdir()
    runup(tmp_path / "data" / "up.zip", 14.0, 19.0, 12.0)
    files = [("h1", "history", "healthy", 0.0), ("h2", "history", "healthy", 0.0), ("up", "test", "healthy", 0.0)]
    path = scenario(tmp_path, files=files, methods=("matched_filter",))
    path.write_text(path.read_text().replace(f'tacho = "2"\npulses_per_rev = {PULSES}\n', 'speed = "16 Hz"\n'))
    spec = load_scenario(path).spec
    ((_, cond),) = read_target(spec.target, spec.detection.blocks, lambda e: None, "here").items()
    (warning,) = [w for w in cond["warnings"] if w.startswith("../data/up.zip")]
    assert warning.endswith("read whole at one speed: no tacho shows its speed revolution by revolution"), warning
