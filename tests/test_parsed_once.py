"""A measured file is parsed once while it is unchanged (data.readers.parsed): a logger's file of several takes, read
once per take, and a record that inspect, score and a run read again. A file written anew is read anew, one changed
this instant is not kept (its time stamp may not change with its next write), and no caller can change another's
arrays (they are read-only)."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from gearlab.data import readers
from gearlab.data.recordings import read_contents


@pytest.fixture
def parses(monkeypatch):
    """The files the CSV reader parsed, in order."""
    seen, real = [], readers.READERS["CSV"]

    def counted(path, names):
        seen.append(path.name)
        return real(path, names)

    monkeypatch.setattr(readers, "_kept", type(readers._kept)())  # nothing kept from other tests
    monkeypatch.setitem(readers.READERS, "CSV", counted)
    return seen


def _csv(path, rows, age_s=60.0):
    """A CSV of three takes under 'take', its last change *age_s* ago (negative: in the future)."""
    x = np.arange(rows, dtype=float)
    path.write_text("take,acc\n" + "".join(f"{1 + 3 * i // rows},{v:.1f}\n" for i, v in enumerate(x)))
    stamp = time.time() - age_s
    os.utime(path, (stamp, stamp))
    return path


def test_the_takes_of_a_file_are_parsed_once_and_their_rows_kept_apart(tmp_path, parses):
    log = _csv(tmp_path / "log.csv", 30)
    got = [read_contents(f"{log}[take={k}]", ["acc"])[0].found["acc"] for k in (1, 2, 3)]
    assert parses == ["log.csv"]
    assert [a.tolist() for a in got] == [list(range(0, 10)), list(range(10, 20)), list(range(20, 30))]
    whole, _ = read_contents(log, ["acc"])
    assert parses == ["log.csv"] * 2 and whole.found["acc"].size == 30  # other channels asked for: read again


def test_a_file_written_anew_is_read_anew(tmp_path, parses):
    log = _csv(tmp_path / "log.csv", 30)
    assert read_contents(log, ["acc"])[0].found["acc"].size == 30
    _csv(log, 60)  # another size
    assert read_contents(log, ["acc"])[0].found["acc"].size == 60
    log.write_text(log.read_text().replace("59.0", "99.0"))  # the same size, written now
    stamp = time.time() - 30
    os.utime(log, (stamp, stamp))
    assert read_contents(log, ["acc"])[0].found["acc"][-1] == 99.0
    assert parses == ["log.csv"] * 3


def test_a_file_changed_this_instant_is_not_kept(tmp_path, parses):
    log = _csv(tmp_path / "log.csv", 30, age_s=-5.0)  # its stamp ahead of the clock: as just written
    for _ in range(2):
        read_contents(log, ["acc"])
    assert parses == ["log.csv"] * 2


def test_no_caller_changes_what_another_reads(tmp_path, parses):
    log = _csv(tmp_path / "log.csv", 30)
    first, _ = read_contents(log, ["acc"])
    with pytest.raises(ValueError, match="read-only"):
        first.found["acc"][0] = 5.0
    first.found["acc"] = np.zeros(3)
    first.warnings.append("a caller's own note")
    again, _ = read_contents(log, ["acc"])
    assert parses == ["log.csv"] and again.found["acc"][:3].tolist() == [0.0, 1.0, 2.0]
    assert "a caller's own note" not in again.warnings


def test_only_the_last_few_files_are_kept(tmp_path, parses):
    logs = [_csv(tmp_path / f"log{i}.csv", 30) for i in range(readers.KEPT_FILES + 1)]
    for log in logs + logs[:1]:
        read_contents(log, ["acc"])
    assert parses == [log.name for log in logs] + ["log0.csv"]  # the first, kept longest ago, gone
