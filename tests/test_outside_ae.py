"""Issue 39, outside users' leftovers (helper AE): a history take that starts with a run-up (a real recording often
does) is used on its steady part, said as a test take's cut is (a); a scored take localised on a gear no method
watches, which no method called, is marked in the scoring history and its trend (b)."""

from __future__ import annotations

import numpy as np
import pytest
from detection_scenario import scenario
from textrecords import FS, PULSES, text, write_zip

from gearlab.errors import GearlabInputError
from gearlab.kinds import detection_scoring as D
from gearlab.kinds.detection_records import read_target

SPEED = 16.0  # Hz: the tiny scenario's history (textrecords)


def _ramp_then_steady(path, ramp: float, steady: float, start: float = 8.0) -> tuple[int, int]:
    """A take running up from *start* to SPEED over *ramp* s, then steady for *steady* s: textrecords' mesh tone
    (order 32) and noise, a chipped tooth's ring on every revolution of the run-up (its steady part healthy), the
    tacho's PULSES marks a turn. (whole turns in all, whole turns once steady)."""
    t = np.arange(int((ramp + steady) * FS)) / FS
    rate = (SPEED - start) / ramp
    theta = 0.4 + 2 * np.pi * np.where(t < ramp, start * t + 0.5 * rate * t**2, (start + SPEED) / 2 * ramp)
    theta += 2 * np.pi * np.where(t < ramp, 0.0, SPEED * (t - ramp))
    vib = np.sin(32 * theta) + 0.3 * np.sin(64 * theta + 0.4) + 0.2 * np.sin(theta)
    since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * SPEED)
    vib += np.where(t < ramp, 4.0 * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since), 0.0)
    vib += 0.3 * np.random.default_rng(3).standard_normal(t.size)
    tacho = np.where(np.mod(theta * PULSES / (2 * np.pi), 1.0) < 0.3, 5.0, 0.05)
    write_zip(path, text(vib, tacho))
    at_speed = (start + SPEED) / 2 * ramp  # turns when the run-up ends
    return int((theta[-1] - 0.4) / (2 * np.pi)), int((theta[-1] - 0.4) / (2 * np.pi) - at_speed)


def _spec(folder, steady: float):
    """The tiny detection scenario (tests/detection_scenario: 16 Hz takes, blocks 5 and 10) with a second history
    take that runs up for 1 s, then holds 16 Hz for *steady* s; its spec and (turns in all, turns steady)."""
    from gearlab.notebook import load_scenario

    (folder / "data").mkdir(exist_ok=True)
    turns = _ramp_then_steady(folder / "data" / "up.zip", 1.0, steady)
    files = [("h1", "history", "healthy", 0.0), ("up", "history", "healthy", 0.0), ("f1", "test", "fault", 4.0)]
    return load_scenario(scenario(folder, files=files, methods=("matched_filter",))).spec, turns


def test_a_history_take_that_runs_up_first_is_used_on_its_steady_part(tmp_path):
    # 8 -> 16 Hz over 1 s (12 turns, each with a chip's ring), then 2 s at 16 Hz: before, refused ('a history take
    # must run steady'); now its steady revolutions alone are the history's, said as a test take's cut is
    spec, (total, steady) = _spec(tmp_path, 2.0)
    events = []
    (name, cond), *others = read_target(spec.target, spec.detection.blocks, events.append, "here").items()
    assert not others and name == "16 Hz", (name, others)
    (f,) = [f for f, _ in cond["history"] if f.path.endswith("up.zip")]
    revs = dict(cond["history"])[f]
    assert steady <= len(revs) <= steady + 2 < total, (len(revs), steady, total)  # the run-up's last turn or so in band
    raw, first = cond["raw"][f.path]
    assert raw.shape == revs.shape and first >= total - steady - 2, (first, total, steady)
    assert cond["speeds"][f.path] == pytest.approx(SPEED, rel=0.005)
    words = f"used {len(revs)} of {total} revolutions at "
    how = cond["speed_from"][f.path]
    assert D.VARIES_WORDS in how and how.split("; ")[-1].startswith(words) and how.endswith(" Hz (steady part)"), how
    (warning,) = [w for w in cond["warnings"] if w.startswith(f.path)]
    assert f"{D.VARIES_WORDS} a run-up; {words}" in warning and warning.endswith("(steady part)"), warning
    # its units from the steady revolutions only: the run-up's rings (4 x the tone) are not among them
    h1 = dict(cond["history"])[[g for g, _ in cond["history"] if g.path.endswith("h1.zip")][0]]
    assert np.abs(revs).max() < 2 * np.abs(h1).max(), (np.abs(revs).max(), np.abs(h1).max())


def test_a_history_take_too_short_once_steady_is_still_refused_in_one_line(tmp_path):
    # 1 s of run-up, then 0.4 s (~6 turns) at 16 Hz: a record10 unit needs 10
    spec, _ = _spec(tmp_path, 0.4)
    with pytest.raises(GearlabInputError) as got:
        read_target(spec.target, spec.detection.blocks, lambda e: None, "det.toml: [target] key 'files'")
    line = str(got.value)
    assert len(line.splitlines()) == 1 and line.startswith("det.toml: [target] key 'files': ../data/up.zip (history; ")
    assert "a history take must run steady" in line and "a unit of every kind needs 10 revolutions" in line, line
    assert line.count("expected") == 1 and "expected a history take steady for 10 revolutions" in line, line


OUT = "other damage: output gear 74T (stage 2)"


def _row(file: str, method: str, margin: float, call: str | None = None) -> dict:
    """One row of a run's scoring history as `gearlab score` appends it: *margin* over a threshold of 1, and the
    take's which-gear *call* (most units over threshold on a take called on another gear: that other damage)."""
    decision = "healthy" if margin <= 0 else (call if call else "fault")
    row = {"file": file, "condition": "L1", "method": method, "unit": "record30", "median_score": 1.0 + margin}
    return row | {"threshold": 1.0, "decision": decision, "call": call}


def test_the_trend_marks_a_take_on_an_unwatched_gear_that_no_method_called(monkeypatch):
    # rec/nw_broken_out.h5: a 74T output gear's broken tooth (localised on it) under every method's threshold; the
    # terminal said so under its 'healthy' rows (2b4efd1), the history and the trend did not: a healthy point
    rows = [_row("week1.h5", m, -0.5) for m in ("fm4", "na4")]
    rows += [_row("nw_broken_out.h5", m, -0.2, OUT) for m in ("fm4", "na4")]
    rows += [_row("broken_called.h5", "fm4", 0.5, OUT), _row("broken_called.h5", "na4", -0.1, OUT)]
    note = f"{OUT}, on a gear this run does not watch; no method called it"
    assert D.unwatched(rows) == {"nw_broken_out.h5": note}  # what score keeps per take ('unwatched')
    monkeypatch.setattr(D.scoring, "read_history", lambda run: rows)
    monkeypatch.setattr(D.scoring, "read_skipped", lambda run: [])  # no take refused
    (trend,) = D.score_trends(None)
    assert f"; record 2: {note}" in trend.title and f"; record 3: {OUT}\n" in trend.title, trend.title
    assert "record 1:" not in trend.title, trend.title


def test_score_keeps_the_note_in_the_history_of_a_take_on_an_unwatched_gear(
    cli, tmp_path, module_cache, monkeypatch, no_figures
):
    # the tiny run (matched filter and the classical rows) scoring a healthy take whose localisation names the
    # 74T output gear (as test_followups_39 stands in for signals.localise): every decision 'healthy', the note kept
    from detection_scenario import shared_run
    from test_followups_39 import scenario
    from textrecords import record

    from gearlab.parts import scoring
    from gearlab.runs import RunDir

    out = shared_run(scenario(tmp_path, methods=("matched_filter",)), tmp_path / "runs")
    record(tmp_path / "quiet.zip", revolutions=40, chip=0.0, seed=11, phase=0.3)
    call = {"named": "output gear 74T (stage 2)", "summary": "", "call": OUT, "evidence": "output z 3.1/2.6"}
    monkeypatch.setattr(
        D, "localise_scored", lambda run_dir, records, turned=None: {p: call for r in records.values() for p, *_ in r}
    )
    code, _, err = cli("score", out, tmp_path / "quiet.zip", "--json")
    assert code == 0, err
    history = scoring.read_history(RunDir.open(out))
    assert history and all(h["decision"] == "healthy" for h in history), {h["decision"] for h in history}
    assert {h["unwatched"] for h in history} == {f"{OUT}, on a gear this run does not watch; no method called it"}
    (trend,) = D.score_trends(RunDir.open(out))
    assert f"record 1: {OUT}, on a gear this run does not watch" in trend.title, trend.title
