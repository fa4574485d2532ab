"""A tacho's marks a turn typed a factor off (issue 39, an outside user's 60-mark output encoder given as
pulses_per_rev = 6 in the description's [sensor]): every record read at 10 x the described speed, cut into 10 x
the revolutions, each of too few samples for the mesh. A detection run read those revolutions of the units' shaft
for minutes and never reached its structure check; the gap run named "[target] key 'fs'" (the sampling rate).
Both now stop at the first record's read with one line naming the description's file, [sensor] key
'pulses_per_rev' and the count that brings the speed back. The takes: tests/test_inspect_tacho_misread.py's
19/47 + 29/71 reducer (numpy, no simulator), a 60-mark tacho on the output shaft, 2 s each."""

from __future__ import annotations

from gearboxes import description, stage
from test_inspect_tacho_misread import STAGES, _record

FILES = (("h1", "history", "healthy"), ("h2", "history", "healthy"), ("t1", "test", "healthy"), ("t2", "test", "fault"))
SAID = "box.toml: [sensor] key 'pulses_per_rev': the tacho reads the shaft at"
MARKS = "the tacho gives 60 pulse(s) per revolution, not 6? ([sensor] pulses_per_rev = 60)"


def _takes(tmp_path, given: int, names=FILES) -> str:
    """box.toml (its [sensor]: a tacho on the output shaft of *given* marks a turn) and 60-mark takes; the 'files'."""
    text = description(
        stage(*STAGES[0]), stage(*STAGES[1], module="3 mm"), name="bi", speed="2400 rpm", load="80 N*m", tacho="output"
    )
    (tmp_path / "box.toml").write_text(text + f"pulses_per_rev = {given}\n")
    for i, (name, _, _) in enumerate(names):
        _record(tmp_path / f"{name}.npz", tacho_shaft=2, marks=60, seed=20 + i, seconds=2.0)
    return ",\n".join(f'{{ file = "{n}.npz", role = "{r}", label = "{lab}" }}' for n, r, lab in names)


def _error(out: str, err: str) -> str:
    (line,) = [x for x in err.strip().splitlines() if x.startswith("error:")]
    return line


def test_a_detection_run_names_the_description_s_marks_before_reading_the_units(tmp_path, cli):
    files = _takes(tmp_path, 6)
    path = tmp_path / "detect.toml"
    path.write_text(
        '[scenario]\nname = "bi"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "chip@intermediate gear" = [18] }\nhealthy = 8\n'
        f'[target]\nvibration = "acc_ms2"\ntacho = "tach"\nfiles = [\n{files},\n]\n'
        '[[methods]]\nadapter = "matched_filter"\n'
    )
    code, out, err = cli("run", path, "--out", tmp_path / "runs", "--quick")
    assert code == 2, out[-2000:] + err[-2000:]
    line = _error(out, err)
    assert SAID in line and MARKS in line, line
    assert "at 404.2 Hz, 10.1 x the described 40 Hz" in line, line  # its input 1 % over 40 Hz
    assert "units" not in out and "simulations" not in out, out[-2000:]  # stopped at the read


def test_the_gap_run_names_the_description_s_marks_not_target_s(tmp_path, cli):
    files = _takes(tmp_path, 6, FILES[:2])
    path = tmp_path / "gap.toml"
    path.write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n'
        f'[target]\nvibration = "acc_ms2"\ntacho = "tach"\nfiles = [\n{files},\n]\n[accuracy]\nenabled = false\n'
    )
    code, out, err = cli("run", path, "--out", tmp_path / "runs", "--quick")
    assert code == 2, out[-2000:] + err[-2000:]
    line = _error(out, err)
    assert SAID in line and MARKS in line, line
    assert "[target]" not in line and "key 'fs'" not in line, line


def test_a_right_count_or_another_speed_with_samples_enough_is_read():
    """The refusal at the read needs both: a speed a whole count of marks off the described, and too few samples a
    revolution for the first mesh (19 teeth and 3 sidebands: 45). A right count reads the described speed; a shaft
    run at half its described speed has twice the samples; a count typed 10 x over (360 for 36) reads a tenth of the
    speed with 10 x the samples, left to the structure check, which reads the mesh lines."""
    import pytest

    from gearlab.errors import GearlabInputError
    from gearlab.parts.measured import refuse_marks

    at = ("box.toml: [sensor] key 'pulses_per_rev'", "[sensor]")
    refuse_marks(12800.0, 40.4, (40.0, 19, ()), 60, *at)  # the count right, 1 % over the described
    refuse_marks(12800.0, 20.0, (40.0, 19, ()), 60, *at)  # half the speed: 640 samples a turn
    refuse_marks(12800.0, 4.0, (40.0, 19, ()), 360, *at)  # 3200 a turn
    with pytest.raises(GearlabInputError, match=r"not 6\? \(\[sensor\] pulses_per_rev = 60\)"):
        refuse_marks(12800.0, 400.0, (40.0, 19, ()), 6, *at)  # 32 a turn, 10 x the described
    # a speed 12.34 x the described, one mark a turn: 12 marks typed as 1, unless the description has two shafts
    # turning 12.34 : 1 (a tacho on the input read as on the output: the structure check names its shaft)
    with pytest.raises(GearlabInputError, match=r"not 1\? \(\[sensor\] pulses_per_rev = 12\)"):
        refuse_marks(12800.0, 493.6, (40.0, 19, ()), 1, *at)
    refuse_marks(12800.0, 493.6, (40.0, 19, (12.34, 1 / 12.34)), 1, *at)
    # the nearer explanation wins: 10.00 x is 10 marks typed as 1 beside two shafts turning 1 : 10.02
    with pytest.raises(GearlabInputError, match=r"not 1\? \(\[sensor\] pulses_per_rev = 10\)"):
        refuse_marks(12800.0, 400.0, (40.0, 19, (10.02, 1 / 10.02)), 1, *at)
