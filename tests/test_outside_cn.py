"""Outside user CN (issue 39 leftovers): a two-stage box's records made with numpy, not gearlab's simulator."""

from __future__ import annotations

import numpy as np
from gearboxes import description, stage

FS, SPEED = 8000.0, 25.0  # the 19/62 + 23/87 box's takes: rate (Hz), input speed (Hz)
MESH_2 = 23 * 19 / 62  # the second mesh, in input orders


def _take(path, seed: int, seconds: float = 3.0) -> str:
    """A take of a 19/62 + 23/87 box at 25 Hz as .npz (m/s²): each mesh modulated by its pinion's shaft, the
    first with its 2nd harmonic, white noise, a tacho once per INPUT turn."""
    t = np.arange(int(seconds * FS)) / FS
    theta = 2 * np.pi * SPEED * t + 0.3 * seed
    mid = theta * 19 / 62
    x = (1 + 0.2 * np.cos(theta)) * np.cos(19 * theta) + 0.5 * np.cos(38 * theta + 0.3)
    x = x + (1 + 0.2 * np.cos(mid)) * 0.8 * np.cos(23 * mid + 0.4)
    x = x + np.random.default_rng(seed).normal(0, 0.05, t.size)
    np.savez(path, acc=x, tach=np.where(theta % (2 * np.pi) < 0.4, 5.0, 0.0), fs=FS)
    return str(path)


def test_an_input_tacho_read_as_the_output_is_named_by_a_detection_run(tmp_path, cli):
    # [target] tacho_shaft = "output" on takes whose tacho marks the input: every order reads 1/12.34 of its own,
    # the meshes at 1.54, 3.08 and 0.57, none over order 5.5. The structure check counted its lines over 5.5 (a pinion
    # has 6 teeth or more) before asking which shaft the tacho reads, found none and went on to the gears: 'stage 2
    # wheel: 19 teeth fit the recording'. inspect and the gap (there only through stray lines near order 60 at 48 kHz)
    # named the tacho's shaft; the detection run now says it in their words, before any training
    for name, seed in (("h1", 0), ("h2", 1), ("t1", 2)):
        _take(tmp_path / f"{name}.npz", seed)
    (tmp_path / "box.toml").write_text(
        description(stage(19, 62), stage(23, 87, module="3 mm"), name="box", speed="25 Hz", load="40 N*m")
    )
    files = ", ".join(
        f'{{ file = "{n}.npz", role = "{r}", label = "{lab}" }}'
        for n, r, lab in (("h1", "history", "healthy"), ("h2", "history", "healthy"), ("t1", "test", "fault"))
    )
    (tmp_path / "detect.toml").write_text(
        '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
        f'[target]\nvibration = "acc"\ntacho = "tach"\ntacho_shaft = "output"\nfiles = [{files}]\n'
        "[detection]\nblocks = [10]\n"
    )
    code, _, err = cli("run", tmp_path / "detect.toml", "--out", tmp_path / "runs")
    assert code == 2, err
    line = err.strip().splitlines()[-1]
    assert "the history of condition '309 Hz' differs from the [source]'s gearbox: mesh order 1.5 measured" in line
    said = "every order reads 1/12.34 x its own, as when a tacho on the input shaft is read as on the output"
    assert said in line and "give [target] tacho_shaft = 'input'" in line, line
    assert "teeth fit the recording" not in line, line
    # inspect reads the same take through the same check, in the same words
    code, out, err = cli(
        "inspect",
        tmp_path / "h1.npz",
        "--gearbox",
        tmp_path / "box.toml",
        "--vibration",
        "acc",
        "--tacho",
        "tach",
        "--tacho-shaft",
        "output",
    )
    assert code == 0, err
    assert said in " ".join(out.split()) and "--tacho-shaft input" in out, out
