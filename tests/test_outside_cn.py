"""Outside user CN (issue 39 leftovers): a two-stage box's records made with numpy, not gearlab's simulator."""

from __future__ import annotations

import numpy as np
import pytest
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


def _loaded(path, load: float, seed: int, strikes: float | None = None, turns: int = 400) -> str:
    """*turns* input turns of the 19/62 + 23/87 box at 25 Hz and *load* (1: the history's) as .npz: each mesh's
    harmonics 1-5 modulated by its stage's shafts, its level x *load*, its harmonics' fall-off (0.4 *load*) per
    harmonic (a heavier load fills the higher harmonics), white noise; *strikes*: a decaying 3 kHz ring struck so
    many times a turn, each interval slipping 1.5 % (a rolling element's)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(turns / SPEED * FS)) / FS
    theta = 2 * np.pi * SPEED * t + rng.uniform(0, 2 * np.pi)
    x, shaft = 0.05 * rng.standard_normal(t.size), [1.0, 19 / 62, 19 / 62 * 23 / 87]
    for k, mesh in enumerate((19.0, MESH_2)):
        mod = 1 + 0.2 * np.cos(shaft[k] * theta + 0.3) + 0.1 * np.cos(shaft[k + 1] * theta + 1.0)
        x += (
            0.6**k
            * load
            * mod
            * sum((0.4 * load) ** (h - 1) * np.cos(h * mesh * theta + 0.7 * h + k) for h in range(1, 6))
        )
    if strikes:
        ring = 0.5 * np.exp(-np.arange(40) / 8) * np.sin(2 * np.pi * 3000 / FS * np.arange(40))
        at = rng.uniform(0, FS / (SPEED * strikes))
        while at < t.size - ring.size:
            x[int(at) : int(at) + ring.size] += ring
            at += FS / (SPEED * strikes) * (1 + 0.015 * rng.standard_normal())
    np.savez(path, acc=x, tach=np.where(theta % (2 * np.pi) < 0.4, 5.0, 0.0), fs=FS)
    return str(path)


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    """The box's description, a light-load history of three takes, and takes to read against it."""
    where = tmp_path_factory.mktemp("loaded")
    (where / "box.toml").write_text(
        description(stage(19, 62), stage(23, 87, module="3 mm"), name="box", speed="25 Hz", load="40 N*m")
    )
    history = [_loaded(where / f"h{i}.npz", 1.0, seed=i) for i in (1, 2, 3)]
    return where / "box.toml", history, where


@pytest.mark.parametrize(
    "seed", [10, pytest.param(11, marks=pytest.mark.slow), pytest.param(12, marks=pytest.mark.slow)]
)
def test_a_healthy_take_at_a_heavier_load_is_no_bearing_damage(loaded, seed):
    # A healthy take at twice the load of a light-load history was 'other damage: non-synchronous (bearing-like)':
    # z 4.6-5.1 over 4.1, the strongest line at order 8.89 = M1 - 4 M2 + o_2 (M1 = 19, M2 = 7.048, o_2 = 0.306), a
    # beat of the two meshes' harmonics whose level follows the load (outside user CN: at 1.5 x, order 4.33). The
    # meshes' combinations are the gearbox's (signals.nonsync.synchronous_bins): now z 2.6-3.3 under 4.0, no change;
    # a bearing's 3.57 strikes a turn are still other damage at that order
    from gearlab.gearbox import load_gearbox
    from gearlab.inspect import InspectOptions
    from gearlab.inspect_history import localisation

    box, history, where = loaded
    options = InspectOptions("acc", "tach")
    loc = localisation(_loaded(where / f"heavy{seed}.npz", 2.0, seed), history, load_gearbox(box), options)
    ns = loc["nonsync"]
    assert not ns["changed"] and ns["z"] <= ns["threshold"], ns
    assert not loc["call"].startswith("other damage"), loc["call"]
    bearing = localisation(_loaded(where / f"b{seed}.npz", 1.0, seed, 3.57), history, load_gearbox(box), options)
    ns = bearing["nonsync"]
    assert ns["changed"] and ns["z"] > 2 * ns["threshold"] and abs(ns["order"] - 3.57) < 0.02, ns
    assert bearing["call"] == f"other damage: non-synchronous (bearing-like), at order {ns['order']:.2f}"
