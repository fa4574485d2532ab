"""`gearlab inspect TAKE --history H`: the take's acquisition options (--vibration, --fs, --sensitivity, --gain,
--unit) read the history files too, the same chain being the normal case; a history file that states its own unit
or rate against them is refused in one line naming it and the --history-key that reads it, never read another way
unsaid (a history in g read with the take's --sensitivity was shown 'not m/s²' and compared as such)."""

from __future__ import annotations

import json

import h5py
import numpy as np

G = 9.80665
FS, SPEED, SECONDS = 10_000.0, 25.0, 4.0
SENSITIVITY = 0.1 / G  # V per m/s² (100 mV/g)


def _acc(seed: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(int(FS * SECONDS)) / FS
    theta = 2 * np.pi * SPEED * t
    rng = np.random.default_rng(seed)
    acc = 5.0 * np.sin(16 * theta) + 2.0 * np.sin(32 * theta + 0.3) + rng.normal(0.0, 0.5, t.size)  # m/s²
    return acc, ((SPEED * t) % 1.0 < 0.1).astype(float)


def _h5(path, seed: int, scale: float, unit: str | None, fs: float | None = FS):
    acc, tacho = _acc(seed)
    with h5py.File(path, "w") as f:
        ds = f.create_dataset("acc", data=acc * scale)
        if unit is not None:
            ds.attrs["units"] = unit
        f.create_dataset("tacho", data=tacho)
        if fs is not None:
            f.attrs["fs"] = fs
    return path


def test_a_history_file_s_own_unit_against_the_take_s_sensitivity_is_refused_naming_its_key(tmp_path, cli):
    take = _h5(tmp_path / "take.h5", 1, SENSITIVITY, None)  # volts, read with --sensitivity
    history = [_h5(tmp_path / f"h{k}.h5", 1 + k, 1 / G, "g") for k in (1, 2)]  # in g, as the file says
    given = ["inspect", take, "--gearbox", "luo2019", "--vibration", "acc", "--tacho", "tacho"]
    given += ["--sensitivity", "100 mV/g", "--history", history[0], "--history", history[1]]
    code, out, err = cli(*given)
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, (out, err)
    assert "h1.h5" in line and "file's unit 'g'" in line and "--history-key 'h1.h5:sensitivity='" in line, line
    code, out, err = cli(*given, "--history-key", "sensitivity=", "--json")
    assert code == 0, err
    level = json.loads(out)["localisation"]["level"]
    assert abs(level - 1.0) < 0.05, level  # both in m/s²: the same level


def test_a_history_file_s_own_rate_against_the_take_s_fs_is_refused_naming_its_key(tmp_path, cli):
    take = _h5(tmp_path / "take.h5", 1, 1.0, "m/s^2", fs=None)  # no rate in the file: --fs
    history = [_h5(tmp_path / f"h{k}.h5", 1 + k, 1.0, "m/s^2", fs=FS / 2) for k in (1, 2)]  # its own rate, another
    given = ["inspect", take, "--gearbox", "luo2019", "--vibration", "acc", "--tacho", "tacho", "--fs", "10 kHz"]
    code, out, err = cli(*given, "--history", history[0], "--history", history[1])
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, (out, err)
    assert "h1.h5" in line and "5000 Hz" in line and "--history-key 'h1.h5:fs='" in line, line


def test_the_take_s_options_read_a_history_of_the_same_chain(tmp_path, cli):
    take = _h5(tmp_path / "take.h5", 1, SENSITIVITY, None)
    history = [_h5(tmp_path / f"h{k}.h5", 1 + k, SENSITIVITY, None) for k in (1, 2)]
    given = ["inspect", take, "--gearbox", "luo2019", "--vibration", "acc", "--tacho", "tacho", "--json"]
    code, out, err = cli(*given, "--sensitivity", "100 mV/g", "--history", history[0], "--history", history[1])
    assert code == 0, err
    assert abs(json.loads(out)["localisation"]["level"] - 1.0) < 0.05, out[-400:]
