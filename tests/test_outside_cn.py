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


# The takes localisation reads whole (its history's shaft averages the most of a call's CPU): 186 turns, three
# periods of the meshes, tell the load's beat from a bearing as 400 did, in 3.3 + 1.3 s of CPU against 11.6 + 3.3 s
LOCALISED_TURNS = 186


@pytest.mark.parametrize(
    "seed", [10, pytest.param(11, marks=pytest.mark.slow), pytest.param(12, marks=pytest.mark.slow)]
)
def test_a_healthy_take_at_a_heavier_load_is_no_bearing_damage(loaded, seed):
    # A healthy take at twice the load of a light-load history was 'other damage: non-synchronous (bearing-like)':
    # z 4.6-5.1 over 4.1, the strongest line at order 8.89 = M1 - 4 M2 + o_2 (M1 = 19, M2 = 7.048, o_2 = 0.306), a
    # beat of the two meshes' harmonics whose level follows the load (outside user CN: at 1.5 x, order 4.33). The
    # meshes' combinations are the gearbox's (signals.nonsync.synchronous_bins) and the takes read in whole periods
    # of the meshes (nonsync.read_turns): at 400 turns z 2.8-3.5 under 4.8, at LOCALISED_TURNS 2.3-3.3 under 4.6, no
    # change (read_turns undone: 5.7-6.7 at 8.91 over 4.3; both undone: 5.7-6.7 over 4.3); a bearing's 3.57 strikes a
    # turn are still other damage at that order (z 18-19)
    from gearlab.gearbox import load_gearbox
    from gearlab.inspect import InspectOptions
    from gearlab.inspect_history import localisation

    box, _, where = loaded
    n = LOCALISED_TURNS
    history = [_loaded(where / f"h{i}_{n}.npz", 1.0, seed=i, turns=n) for i in (1, 2, 3)]
    options = InspectOptions("acc", "tach")
    loc = localisation(_loaded(where / f"heavy{seed}.npz", 2.0, seed, turns=n), history, load_gearbox(box), options)
    ns = loc["nonsync"]
    assert not ns["changed"] and ns["z"] <= ns["threshold"], ns
    assert not loc["call"].startswith("other damage"), loc["call"]
    take = _loaded(where / f"b{seed}.npz", 1.0, seed, 3.57, turns=n)
    bearing = localisation(take, history, load_gearbox(box), options)
    ns = bearing["nonsync"]
    assert ns["changed"] and ns["z"] > 2 * ns["threshold"] and abs(ns["order"] - 3.57) < 0.02, ns
    assert bearing["call"] == f"other damage: non-synchronous (bearing-like), at order {ns['order']:.2f}"


@pytest.mark.parametrize("turns", [240, 300, *(pytest.param(n, marks=pytest.mark.slow) for n in (200, 350, 500))])
def test_a_healthy_takes_verdict_does_not_hinge_on_its_length(loaded, turns):
    # The heavy take of 200-500 turns against the same 400-turn history, as localisation reads it (nonsync_lines):
    # read whole, its second mesh (437/62 input orders) fell between bins at 240 and 300 turns (0.61, 0.52 off) and
    # the record's ends left it in the residual; its envelope's beats read z 4.3 at 240, 5.1-6.2 at 300 (seeds 10-12,
    # threshold 4.0), 'bearing-like', against 1.6-3.3 at 200, 350, 400, 500. Read in pieces of whole periods of the
    # meshes (nonsync.read_turns) each mesh is removed whole: z 2.3-3.5 at every length (threshold 4.8); the bearing's
    # strikes still read many times the threshold, at 3.57
    from gearlab.gearbox import load_gearbox
    from gearlab.gearbox.orders import order_table
    from gearlab.inspect import InspectOptions
    from gearlab.inspect_history import input_revolutions, nonsync_lines

    box, history, where = loaded
    box, options = load_gearbox(box), InspectOptions("acc", "tach")
    past, table = [input_revolutions(h, box, options)[0] for h in history], order_table(box)
    heavy = input_revolutions(_loaded(where / f"heavy{turns}.npz", 2.0, 11, turns=turns), box, options)[0]
    ns = nonsync_lines(heavy, past, table, 25.0)
    assert not ns["changed"] and ns["z"] <= ns["threshold"], ns
    bearing = input_revolutions(_loaded(where / f"b{turns}.npz", 1.0, 11, 3.57, turns=turns), box, options)[0]
    ns = nonsync_lines(bearing, past, table, 25.0)
    assert ns["changed"] and ns["z"] > 2 * ns["threshold"] and abs(ns["order"] - 3.57) < 0.02, ns


def _tipped(path, seed: int, tip: float = 0.0) -> None:
    """An 8 s take of the 19/62 + 23/87 box at 25 Hz (10 kHz) as .npz, a tacho once per input turn; *tip*: the
    share of the first mesh lost while tooth 30 of the 62T intermediate gear meshes (a broken tip)."""
    rng = np.random.default_rng(seed)
    fs = 10000.0
    t = np.arange(int(8 * fs)) / fs
    theta = 2 * np.pi * SPEED * t + rng.uniform(0, 2 * np.pi)
    mid = theta * 19 / 62
    at = (mid % (2 * np.pi)) / (2 * np.pi) * 62  # the 62T gear's teeth passed
    amp = (1 + 0.2 * np.cos(theta) + 0.1 * np.cos(mid + 1.0)) * (1 - tip * np.exp(-0.5 * ((at - 30) / 0.6) ** 2))
    x = amp * (np.cos(19 * theta) + 0.4 * np.cos(38 * theta + 0.3) + 0.2 * np.cos(57 * theta + 0.9))
    x += 0.6 * (1 + 0.2 * np.cos(mid) + 0.1 * np.cos(mid * 23 / 87)) * (np.cos(23 * mid + 0.4) + 0.3 * np.cos(46 * mid))
    x += rng.normal(0, 0.1, t.size)
    np.savez(path, acc=x, tach=np.where(theta % (2 * np.pi) < 0.4, 5.0, 0.0), fs=fs)


def _tip_scenario(folder, rows) -> None:
    """box.toml (the 19/62 + 23/87 box) and detect.toml watching its 62T intermediate gear for broken tips, simulated
    on teeth 1 and 31 alone (the guide's way to a short run), read against *rows* (name, role, label, tip)."""
    (folder / "box.toml").write_text(
        description(stage(19, 62), stage(23, 87, module="3 mm"), speed="25 Hz", load="40 N*m", tacho="input")
    )
    files = ", ".join(f'{{ file = "{n}.npz", role = "{r}", label = "{lab}" }}' for n, r, lab, _ in rows)
    (folder / "detect.toml").write_text(
        '[scenario]\nname = "tip"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "broken_tip@intermediate gear" = [10, 20] }\nteeth = [1, 31]\n'
        f'[target]\nvibration = "acc"\ntacho = "tach"\nfiles = [{files}]\n[[methods]]\nadapter = "matched_filter"\n'
    )


def test_the_detectors_shapes_reach_the_teeth_not_simulated(tmp_path):
    # teeth 1 and 31 of the 62T gear: the widest gap is 32 pitches, so each fault row is turned by 1 ... 31 pitches
    # (every tooth reached from one simulated, whichever way the teeth are counted); every tooth: none
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import tooth_gap, turned_faults

    _tip_scenario(tmp_path, [("h", "history", "healthy", 0.0), ("t", "test", "fault", 0.5)])
    _tipped(tmp_path / "h.npz", 0)
    _tipped(tmp_path / "t.npz", 1, 0.5)
    source = load_scenario(tmp_path / "detect.toml").spec.source
    assert tooth_gap(source) == (62, 32) and tooth_gap(source.with_(teeth=None)) == (62, 1)
    assert tooth_gap(source.with_(teeth=(1, 11, 21, 31, 41, 51)))[1] == 12
    X = np.zeros((2, 8 * 62), dtype=np.float32)
    X[1, 3] = 1.0  # a fault row
    Xt, yt = turned_faults(X, np.array([0, 1]), 62, 4)
    assert list(yt) == [0, 1, 1, 1, 1] and [int(np.argmax(r)) for r in Xt[1:]] == [3, 11, 19, 27]


@pytest.mark.slow
def test_a_broken_tip_on_a_tooth_not_simulated_is_found_by_the_matched_filter(tmp_path, gearlab, no_figures):
    # five broken-tip takes on the 62T intermediate gear, the source simulating teeth 1 and 31 alone (the guide's
    # way to a short run): each tooth's damage strikes at its own angle of the shaft's turn, and matched_filter's
    # shapes held two angles: 0 % of the takes' record30 units called (AUC 0.69), fm4 and na4 100 %. The shapes
    # turned by the pitches between the teeth simulated (detection_records.tooth_gap) reach every tooth
    import json
    import re

    rows = [("h0", "history", "healthy", 0.0), ("h1", "history", "healthy", 0.0), ("h2", "history", "healthy", 0.0)]
    rows += [(f"ok{i}", "test", "healthy", 0.0) for i in range(5)] + [
        (f"tip{i}", "test", "fault", 0.5) for i in range(5)
    ]
    for k, (name, _, _, tip) in enumerate(rows):
        _tipped(tmp_path / f"{name}.npz", k, tip)
    _tip_scenario(tmp_path, rows)
    code, out = gearlab(tmp_path, "run", "detect.toml", "--quick")
    assert code == 0, out
    assert "the detectors' shapes turned by each pitch of the 62T gear up to 31" in out, out
    run = tmp_path / re.findall(r"^run directory: (.+)$", out, re.M)[-1].strip()
    summary = json.loads((run / "summary.json").read_text())
    r = next(r for r in summary["rows"] if r["method"] == "matched_filter" and r["unit"] == "record30")
    assert r["auc"] >= 0.95 and r["detection"] >= 90 and r["false_alarm"] <= 10, r
