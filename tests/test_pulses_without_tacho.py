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


def _refused(cli, *args) -> str:
    code, _, err = cli(*args)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    return err.strip()


DATASET = '[[datasets]]\nfile = "r.npz"\nvibration = "acc"\nspeed = "25 Hz"\npulses_per_rev = 4\ntransient = "none"\n'
TARGET = '[source]\npreset = "B-6-ch5"\n[target]\nvibration = "acc"\nspeed = "25 Hz"\npulses_per_rev = 4\n'
TARGET += 'files = [{ file = "r.npz", role = "history", label = "healthy" }]\n[accuracy]\nenabled = false\n'


@pytest.mark.parametrize(
    ("kind", "body", "key", "with_tacho"),
    [
        ("dataset", DATASET, "[[datasets]] #1 key 'pulses_per_rev'", False),
        ("dataset", DATASET, "[[datasets]] #1 key 'pulses_per_rev'", True),
        ("gap", TARGET, "[target] key 'pulses_per_rev'", True),
    ],
    ids=["dataset, no tacho channel", "dataset, a tacho channel not named", "gap target"],
)
def test_pulses_per_rev_without_a_tacho_is_one_line(tmp_path, cli, kind, body, key, with_tacho):
    _record(tmp_path, with_tacho)
    path = tmp_path / "s.toml"
    path.write_text(f'[scenario]\nname = "d"\nkind = "{kind}"\n{body}')
    line = _refused(cli, "validate", path)
    assert f"{key}: belongs to a tacho; no 'tacho' is given" in line, line
    assert ("tacho = 'tacho_V'" in line) == with_tacho, line


def test_inspect_s_pulses_per_rev_without_tacho_is_one_line(tmp_path, cli):
    path = _record(tmp_path, True)
    line = _refused(cli, "inspect", path, "--vibration", "acc", "--speed", "25 Hz", "--pulses-per-rev", "4")
    assert "--pulses-per-rev" in line and "--tacho tacho_V" in line, line
