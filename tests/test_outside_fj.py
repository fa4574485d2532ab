"""An outside user's gearboxes (issue 39, "How it will be checked"): a three-stage 23/70 + 27/62 + 31/65 reducer
with an input tacho recorded to MATLAB files (v5 and v7.3), and a two-stage 21/86 + 25/92 reducer without a tacho
logged in volts to CSV, its takes one after another in one file. The records are small stand-ins written here with
numpy (mesh harmonics, run-out sidebands, noise), not simulated by gearlab."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

G = 9.80665


def _box(stages, speed: float, seconds: float, fs: float, seed: int) -> np.ndarray:
    """Acceleration (m/s²) of a spur train *stages* [(z_pinion, z_wheel), ...] at *speed* Hz on its input: three
    harmonics of each mesh, amplitude-modulated once a turn by both its shafts, each shaft's run-out, noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    angle = [2 * np.pi * speed * t]
    for zp, zw in stages:
        angle.append(angle[-1] * zp / zw)
    acc = sum(0.4 * np.cos(a + s) for s, a in enumerate(angle))
    for k, (zp, _) in enumerate(stages):
        am = 1 + 0.1 * np.cos(angle[k]) + 0.08 * np.cos(angle[k + 1] + k)
        acc = acc + sum((3.0 - k) * h * am * np.cos((i + 1) * zp * angle[k] + k) for i, h in enumerate((1, 0.5, 0.25)))
    return acc + 0.3 * rng.standard_normal(t.size)


def _log(path: Path, takes: list[tuple[float, int]], fs: float = 6400.0) -> Path:
    """A CSV of the 21/86 + 25/92 box's takes (speed in Hz, seed) one after another in volts at 100 mV/g, a column
    'segment' marking each take, the time restarting at each; no tacho."""
    rows = []
    for k, (speed, seed) in enumerate(takes, start=1):
        vib = _box([(21, 86), (25, 92)], speed, 3.0, fs, seed) / G * 0.1
        rows.append(np.c_[np.arange(vib.size) / fs, vib, np.full(vib.size, k)])
    np.savetxt(path, np.vstack(rows), delimiter=",", header="time_s,acc_V,segment", comments="", fmt="%.7g")
    return path


def test_a_take_of_a_log_is_read_from_its_one_channel_its_take_column_no_vibration(tmp_path, cli):
    # 'gearlab inspect log.csv --takes segment' as the guide writes it: 'which channel is the vibration? the file has
    # acc_V, segment; expected --vibration NAME', where segment is the column --takes names, not a channel
    log = _log(tmp_path / "log.csv", [(30.0, 1), (29.5, 2)])
    given = ["--sensitivity", "100 mV/g", "--speed", "30 Hz"]
    code, out, err = cli("inspect", log, "--takes", "segment", *given, "--json")
    rows = json.loads(out) if code == 0 else []
    assert [r["take"] for r in rows] == [f"{log}[segment={k}]" for k in (1, 2)], err
    assert not any(r.get("problem") for r in rows), rows
    code, out, err = cli("inspect", f"{log}[segment=2]", *given)
    assert code == 0 and "vibration 'acc_V'" in out, out + err
