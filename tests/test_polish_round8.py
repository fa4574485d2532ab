"""Outside-user round 8's small items (issue 39): a condition named by its measured speed, not the
nominal one; the records' alignment told alike in the log and the table where a tacho reads another
shaft; a headerless text record's time column recognised in the 'no sampling rate' error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gearlab.errors import GearlabInputError


def _files(*paths: str, role: str = "history"):
    from gearlab.parts.measured import TargetFile

    return [TargetFile(p, p, role, "healthy", "") for p in paths]


def test_a_condition_is_named_by_its_measured_speed_not_the_nominal_one():
    """A 1500 rpm (25 Hz) motor slipping to 1476 rpm: its records run at 24.6 Hz (the mesh lines' speed),
    and the condition -- the name of the log's lines, table.md's rows and the report's -- says so;
    before: '25 Hz'. Speeds within 0.5 % of a whole Hz keep that name ('30 Hz' for 29.997)."""
    from gearlab.kinds.detection_records import conditions_of

    files = _files("h1.wav", "h2.wav") + _files("t.wav", role="test")
    named = conditions_of(files, {"h1.wav": 24.6, "h2.wav": 24.6, "t.wav": 24.61})
    assert set(named.values()) == {"24.6 Hz"}, named
    files = _files("a.csv", "b.csv") + _files("c.csv", role="test")
    assert set(conditions_of(files, {"a.csv": 29.997, "b.csv": 30.006, "c.csv": 29.999}).values()) == {"30 Hz"}
    # a slow shaft's few Hz: 8.33 Hz is not '8 Hz'
    assert set(conditions_of(_files("s.csv"), {"s.csv": 8.333}).values()) == {"8.3 Hz"}


def test_a_tacho_on_another_shaft_is_said_alike_in_the_log_and_the_table():
    """A tacho on the intermediate shaft (2 marks a turn), units of that shaft's revolutions aligned by
    correlation: the log said '(no tacho)' and table.md '3215 marks' for the same turn in samples."""
    from gearlab.gearbox.orders import TachoShaft
    from gearlab.kinds.detection_records import unaligned_why
    from gearlab.kinds.detection_tables import records_md
    from gearlab.parts.measured import Target

    keys = dict(vibration="1", pulses_per_rev=2, sensitivity=None, fs=None, transient="none", positive="fault")
    shaft = TachoShaft("intermediate", 15, 46)
    why = unaligned_why(Target(tacho="2", files=(), tacho_shaft=shaft, **keys), "intermediate")
    assert "no tacho" not in why and why.startswith("tacho '2' on the intermediate shaft, 2 marks per turn"), why
    assert unaligned_why(Target(tacho=None, files=(), **keys), "input") == "no tacho"
    cond = {
        "history": ["h.csv"],
        "test": ["t.csv"],
        "speeds_hz": {"h.csv": 29.997, "t.csv": 29.999},
        "speed_from": {p: "tacho '2' (2 pulses per revolution) on the intermediate shaft" for p in ("h.csv", "t.csv")},
        "start_marks": {"h.csv": 3215, "t.csv": 3304},
        "tacho": True,
        "unit_shaft": "intermediate",
    }
    table = records_md({"30 Hz": cond})
    assert "| 3215 samples |" in table and "| 3304 samples |" in table and " marks |" not in table, table
    assert "not by its marks" in table
    # units of the input shaft keep the tacho's marks
    assert "| 3215 marks |" in records_md({"30 Hz": {**cond, "unit_shaft": "input"}})


def _headerless(path: Path, time_column: bool, fs: float = 20_000.0, n: int = 4000) -> Path:
    t = np.arange(n) / fs
    x = np.sin(2 * np.pi * 300 * t) + 0.1 * np.random.default_rng(3).standard_normal(n)
    first = t if time_column else 0.5 * np.cos(2 * np.pi * 40 * t)
    path.write_text("".join(f"{a:.6f};{b:.6f};{0.0:.2f}\n" for a, b in zip(first, x)))
    return path


def test_a_headerless_time_column_is_named_in_the_no_sampling_rate_error(tmp_path):
    """A headerless ';' CSV whose column 0 is time: 'no sampling rate' said only '(--fs / fs = ...)';
    now, at validate time (the scenario's table and key) and when read (gearlab inspect), that column 0
    rises by a constant step as a time column does, and the rate to give."""
    from gearlab.data.recordings import check_recording, read_recording

    path = _headerless(tmp_path / "r.csv", time_column=True)
    with pytest.raises(GearlabInputError) as err:
        check_recording(path, "s.toml: [target]", {"vibration": "1"})
    line = str(err.value)
    assert line.startswith("s.toml: [target] key 'fs': missing;") and str(path) in line, line
    assert "column 0 rises by a constant 5e-05 a row, as a time column in seconds does" in line, line
    assert "fs = '20 kHz'" in line and "\n" not in line, line
    with pytest.raises(GearlabInputError, match=r"no sampling rate.*column 0 rises.*fs = '20 kHz' \(--fs '20 kHz'\)"):
        read_recording(path, "1")
    # column 0 a signal: no such guess, the error as before
    other = _headerless(tmp_path / "s.csv", time_column=False)
    with pytest.raises(GearlabInputError) as err:
        check_recording(other, "s.toml: [target]", {"vibration": "1"})
    assert "column 0" not in str(err.value) and str(err.value).endswith("expected the rate, e.g. fs = '51.2 kHz'")
    with pytest.raises(GearlabInputError, match=r"none was given \(--fs / fs = \.\.\.\)$"):
        read_recording(other, "1")
    assert read_recording(path, "1", fs=20_000.0).fs == 20_000.0  # given, it reads as ever
