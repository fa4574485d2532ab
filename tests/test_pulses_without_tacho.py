"""`pulses_per_rev` belongs to a tacho (issue 39 item 2): given where no tacho is read -- a [[datasets]]
file, `gearlab inspect --pulses-per-rev` -- it was accepted and did nothing; now it is one line naming the
key, exit 2 at validate, and the line names a channel of the file that looks like a tacho (gearlab takes
none without being told)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

FS, SPEED = 10_000.0, 25.0


def _record(tmp_path: Path, with_tacho: bool) -> Path:
    t = np.arange(int(2 * FS)) / FS
    theta = 2 * np.pi * SPEED * t
    arrays = {"acc": np.sin(20 * theta) + 0.01 * np.random.default_rng(0).standard_normal(t.size), "fs": FS}
    if with_tacho:
        arrays["tacho_V"] = np.where(theta % (2 * np.pi) < 0.4, 5.0, 0.0)
    np.savez(tmp_path / "r.npz", **arrays)
    return tmp_path / "r.npz"


@pytest.mark.parametrize("with_tacho", [False, True], ids=["no tacho channel", "a tacho channel not named"])
def test_a_dataset_s_pulses_per_rev_without_a_tacho_is_one_line(tmp_path, cli, with_tacho):
    _record(tmp_path, with_tacho)
    path = tmp_path / "s.toml"
    path.write_text(
        '[scenario]\nname = "d"\nkind = "dataset"\n[[datasets]]\nfile = "r.npz"\nvibration = "acc"\n'
        'speed = "25 Hz"\npulses_per_rev = 4\ntransient = "none"\n'
    )
    code, _, err = cli("validate", path)
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, err
    assert "[[datasets]] #1 key 'pulses_per_rev'" in line and "no 'tacho'" in line, line
    assert ("tacho = 'tacho_V'" in line) == with_tacho, line


def test_a_target_s_pulses_per_rev_names_the_file_s_tacho_channel(tmp_path, cli):
    _record(tmp_path, True)
    path = tmp_path / "g.toml"
    path.write_text(
        '[scenario]\nname = "u"\nkind = "gap"\n[source]\npreset = "B-6-ch5"\n[target]\nvibration = "acc"\n'
        'speed = "25 Hz"\npulses_per_rev = 4\nfiles = [{ file = "r.npz", role = "history", label = "healthy" }]\n'
        "[accuracy]\nenabled = false\n"
    )
    code, _, err = cli("validate", path)
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, err
    assert "[target] key 'pulses_per_rev'" in line and "tacho = 'tacho_V'" in line, line


def test_inspect_s_pulses_per_rev_without_tacho_is_one_line(tmp_path, cli):
    path = _record(tmp_path, True)
    code, _, err = cli("inspect", path, "--vibration", "acc", "--speed", "25 Hz", "--pulses-per-rev", "4")
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, err
    assert "--pulses-per-rev" in line and "--tacho tacho_V" in line, line
