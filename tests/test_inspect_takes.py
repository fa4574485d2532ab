"""`gearlab inspect FILE --takes KEY` (issue 39): a logger's file of several takes at a glance, a row per take (its
name, duration, speed and how it was read, the mesh orders found against --gearbox, its level, whether it looks like
the other takes; with --history the call inspect --history makes of one take)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from gearboxes import description, stage
from textrecords import FS, PULSES, SENSITIVITY, SPEED, TEETH, signals

SECONDS = 2.5  # each take's length
OPTIONS = ["--vibration", "acc", "--tacho", "tacho", "--sensitivity", "10 mV/g"]


def _log(path: Path, takes: list[tuple[float, int, float]]) -> Path:
    """A CSV of takes (chip, seed, speed in Hz) one after another, marked by a column 'segment', the time restarting
    at each: the accelerometer in V and a tacho of PULSES marks a turn (tests/textrecords.py)."""
    rows = []
    for k, (chip, seed, speed) in enumerate(takes, start=1):
        vib, tacho = signals(revolutions=int(SECONDS * speed), chip=chip, seed=seed, phase=0.7 * seed, speed=speed)
        rows += zip([k] * vib.size, np.arange(vib.size) / FS, vib * SENSITIVITY, tacho)
    path.write_text("segment,time_s,acc,tacho\n" + "".join(f"{k},{t:.7f},{v:.7e},{p:.2f}\n" for k, t, v, p in rows))
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """The log of 3 takes (the 3rd at 1.25 x the speed), one of 3 whose 2nd has a chipped pinion tooth, a history
    file of 2 healthy takes and the description: one stage, TEETH/64, its tacho PULSES marks a turn."""
    where = tmp_path_factory.mktemp("takes")
    _log(where / "log.csv", [(0.0, 1, SPEED), (0.0, 2, SPEED), (0.0, 3, 1.25 * SPEED)])
    _log(where / "chip.csv", [(0.0, 1, SPEED), (4.0, 2, SPEED), (0.0, 3, SPEED)])
    _log(where / "hist.csv", [(0.0, 4, SPEED), (0.0, 5, SPEED)])
    box = description(stage(TEETH, 64), name="rig", speed=f"{SPEED} Hz", tacho="input", marks=PULSES)
    (where / "box.toml").write_text(box)
    return where


def test_a_row_per_take_the_take_at_another_speed_said(folder, cli, monkeypatch):
    log = folder / "log.csv"
    code, out, err = cli("inspect", log, "--takes", "segment", "--gearbox", folder / "box.toml", *OPTIONS, "--json")
    rows = json.loads(out) if code == 0 else []
    assert [r["take"] for r in rows] == [f"{log}[segment={k}]" for k in (1, 2, 3)], err
    assert [round(r["speed_hz"], 2) for r in rows] == [SPEED, SPEED, 1.25 * SPEED]
    assert all(r["duration_s"] == pytest.approx(SECONDS, abs=0.01) for r in rows)
    assert all(r["speed_source"].startswith("tacho 'tacho'") for r in rows)
    # the mesh order is an order: found on each take, at either speed
    found = [[s["measured_order"] for s in r["mesh"]] for r in rows]
    assert all(r["matches"] for r in rows) and found == [[pytest.approx(TEETH, abs=0.01)]] * 3, found
    assert [r["like_others"] for r in rows[:2]] == ["yes", "yes"]
    assert rows[2]["like_others"] == f"speed +25.0 % off the takes' median {SPEED:g} Hz", rows[2]
    # in the terminal: one table, a row per take (named as the file is given)
    monkeypatch.chdir(folder)
    code, out, err = cli("inspect", "log.csv", "--takes", "segment", "--gearbox", "box.toml", *OPTIONS)
    starts = [line.split()[1] for line in out.splitlines() if line.startswith("│ log.csv")]  # a row's first line
    assert code == 0 and starts == [f"log.csv[segment={k}]" for k in (1, 2, 3)], (out, err)
    assert out.count("+25.0 %") == 1 and out.index("+25.0 %") > out.index("log.csv[segment=3]"), out


def test_with_a_history_each_take_gets_the_call_inspect_makes_of_one(folder, cli):
    history = ["--history", folder / "hist.csv", "--history-key", "takes=segment"]
    args = ["inspect", folder / "chip.csv", "--takes", "segment", "--gearbox", folder / "box.toml", *OPTIONS, *history]
    code, out, err = cli(*args, "--json")
    calls = [r["call"] for r in json.loads(out)] if code == 0 else err
    assert calls[1] == f"localised change: input pinion {TEETH}T (stage 1)", calls
    assert all(c.startswith("no change against the history") for c in calls[::2]), calls
    # the same call as inspect gives the take alone
    code, out, err = cli("inspect", f"{folder / 'chip.csv'}[segment=2]", *args[4:], "--json")
    assert code == 0 and json.loads(out)["localisation"]["call"] == calls[1], err


def test_a_column_the_file_does_not_have_is_one_line_naming_the_file_and_the_key(folder, cli):
    code, out, err = cli("inspect", folder / "log.csv", "--takes", "segmnt", *OPTIONS)
    line = err.strip()
    assert code == 2 and "\n" not in line and not out, err
    assert line.startswith("error: --takes: ") and "log.csv has no column 'segmnt'" in line, line
    assert "did you mean 'segment'" in line, line


def test_a_take_that_cannot_be_read_is_named_with_why_the_others_shown(folder, cli):
    head, *rows = (folder / "log.csv").read_text().splitlines(keepends=True)
    second = [r for r in rows if r.startswith("2,")][:300]  # take 2 cut to 300 samples, under a turn
    (folder / "short.csv").write_text(head + "".join(r for r in rows if r[0] == "1" or r[0] == "3" or r in second))
    marks = ["--pulses-per-rev", str(PULSES)]
    code, out, err = cli("inspect", folder / "short.csv", "--takes", "segment", *OPTIONS, *marks, "--json")
    got = json.loads(out)
    assert code == 2 and [r["take"][-3:] for r in got] == ["=1]", "=2]", "=3]"], err
    assert "not one complete revolution" in got[1]["problem"] and "problem" not in got[0] | got[2], got
    said = f"error: not read: {folder / 'short.csv'}[segment=2] (why: in the table); the other takes shown"
    assert err.strip() == said, err
