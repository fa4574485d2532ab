"""Issue 39, outside users' leftovers (helper AE): a history take that starts with a run-up (a real recording often
does) is used on its steady part, said as a test take's cut is (a)."""

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
    assert f"{D.VARIES_WORDS}; {words}" in warning and warning.endswith("(steady part)"), warning
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
