"""A pulse tacho on the right shaft read with another count of marks a turn than it gives (issue 39): `gearlab
inspect` says 'the tacho gives 2 pulse(s) per revolution, not 1? (--pulses-per-rev 2, key 'pulses_per_rev' ...)'
(gearlab.inspect_tacho.marks_words), but the gap diagnosis said only 'the tacho gives 2 x the pulses per revolution
it was read with? [target] pulses_per_rev': neither the count the records show nor the one they were read with,
where the scenario knows it (the history's pulses_per_rev, Chain.pulses_per_rev). The gap, and a detection run's
check of its history, now say it in inspect's words, with the key and its value in [target] (a run has no
inspect options). The takes: a 27/73 box at 25 Hz with
a tacho on its input shaft, CSV records made with numpy (tests/test_tacho_misread_output.py's maker)."""

from __future__ import annotations

import pytest
from test_tacho_misread_output import _box, _files, _gap_run, _options, _record

from gearlab.gearbox import load_gearbox
from gearlab.inspect import inspect_record

TARGET = '[target]\nvibration = "acc_V"\ntacho = "tacho_V"\nsensitivity = "100 mV/g"\nfiles = [\n'
HISTORY = (("h1", "history", "healthy"), ("h2", "history", "healthy"))


def _takes(tmp_path, marks: int, read: int, names=("h1", "h2")) -> None:
    """box.toml (its [sensor] tacho on the input, read with *read* marks a turn) and takes of a tacho of *marks*."""
    _box(tmp_path / "box.toml", 27, 73)
    if read != 1:  # [sensor] is the description's last table
        with open(tmp_path / "box.toml", "a") as f:
            f.write(f"pulses_per_rev = {read}\n")
    for i, name in enumerate(names):
        _record(tmp_path / f"{name}.csv", 27, 73, "input", marks, seconds=3.0, seed=30 + i)


def _said(marks: int, read: int, run: bool = True) -> str:
    """inspect_tacho.marks_words: in a run (which has no inspect options), the key and its value in [target]."""
    said = f"the tacho gives {marks} pulse(s) per revolution, not {read}? "
    inspect = f"(--pulses-per-rev {marks}, key 'pulses_per_rev'"
    return said + (f"([target] pulses_per_rev = {marks})" if run else inspect)


@pytest.mark.parametrize(
    ("marks", "read", "measured"), [(2, 1, 13.5), (1, 3, 81.0)], ids=["2-read-as-1", "1-read-as-3"]
)
def test_the_gap_names_the_pulse_count_and_its_key_as_inspect_does(tmp_path, cli, marks, read, measured):
    _takes(tmp_path, marks, read)
    verdict = _gap_run(tmp_path, cli, "box.toml", TARGET + _files(*HISTORY))["verdict"]
    assert verdict.startswith(f"structure differs: mesh order {measured} measured, 27 expected"), verdict
    # the count the records show, the one read, and the key with its value in [target]
    assert verdict.endswith(_said(marks, read) + ")"), verdict
    assert "x the pulses" not in verdict and "of the pulses" not in verdict, verdict
    # inspect of one of the takes says the same sentence
    report = inspect_record(str(tmp_path / "h1.csv"), load_gearbox(tmp_path / "box.toml"), _options())
    assert _said(marks, read, run=False) + " in a scenario)" in report["verdict"], report["verdict"]


def test_a_detection_run_s_history_check_names_the_pulse_count_and_its_key(tmp_path, cli):
    """The detection kind's check of its history against the description (the gap's structure_line) says the same."""
    _takes(tmp_path, 2, 1, names=("h1", "h2", "t1", "t2"))
    rows = (*HISTORY, ("t1", "test", "healthy"), ("t2", "test", "fault"))
    path = tmp_path / "detect.toml"
    path.write_text(
        '[scenario]\nname = "pc_det"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "chip@input pinion" = [18] }\nhealthy = 8\n[protocol]\nbatch = 8\n'
        + TARGET + _files(*rows) + '[[methods]]\nadapter = "matched_filter"\n'
    )  # fmt: skip
    code, out, err = cli("run", path, "--out", tmp_path / "runs", "--quick")
    assert code == 2, out + err
    (line,) = [x for x in err.strip().splitlines() if x.startswith("error:")]
    assert "[source] key 'gearbox': the history of condition" in line, line
    assert "mesh order 13.5 measured, 27 expected" in line, line
    assert _said(2, 1) + ");" in line, line
