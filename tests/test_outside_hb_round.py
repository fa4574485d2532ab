"""An outside user's look (issue 39): two gearboxes no other test uses, their recordings made here by plain numpy
(mesh lines with shaft sidebands, shaft harmonics, noise; no gearlab simulator). A: one stage 17/53 at 18 Hz, an
accelerometer in volts (10.2 mV/(m/s^2)) and a once-a-turn tacho, logged as a semicolon CSV with decimal commas.
B: two stages 19/67 + 23/71 at 40 Hz, no tacho, in m/s^2 as MATLAB v5 and .npz files whose unit is a text entry."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
from gearboxes import description, inspected, read_as_described, stage

FS_A, F_A, SENSITIVITY_A = 6400.0, 18.07, "10.2 mV/(m/s^2)"
BOX_A = description(
    stage(17, 53, module="3 mm", bores=("25 mm", "30 mm")), name="box17", speed="18 Hz", load="40 N*m", tacho="input"
)
A_KEYS = ("--vibration", "acc [V]", "--tacho", "key [V]", "--sensitivity", SENSITIVITY_A)
FS_B, F_B = 5000.0, 40.0
BOX_B = description(
    stage(19, 67, module="2.5 mm", bores=("25 mm", "30 mm")),
    stage(23, 71, module="3 mm", width="25 mm", bores=("30 mm", "40 mm")),
    name="box2s",
    speed="40 Hz",
    load="60 N*m",
    near="input",
)


def _accel(z, speed, fs, seconds, seed, level=1.0):
    """A box's acceleration (m/s^2) and input-shaft angle: each stage's mesh (3 harmonics, both shafts' sidebands),
    run-out, noise, all x *level* (a load)."""
    rng = np.random.default_rng(seed)
    n = int(fs * seconds)
    th = 2 * np.pi * speed * np.arange(n) / fs + rng.uniform(0, 2 * np.pi)
    shafts = [th * np.prod([zp / zw for zp, zw in z[:k]]) for k in range(len(z) + 1)]
    a = sum(0.5 * np.cos(s + k) for k, s in enumerate(shafts))
    for s, (zp, _) in enumerate(z):
        am = 1 + 0.08 * np.cos(shafts[s]) + 0.06 * np.cos(shafts[s + 1] + 1.1)
        a = a + sum(4 / (1 + s) * ah * am * np.cos(h * zp * shafts[s] + s) for h, ah in ((1, 1), (2, 0.4), (3, 0.2)))
    return level * (a + rng.normal(0, 0.6, n)), th


def _accel_b(seconds=1.0, seed=1, level=1.0):
    return _accel(((19, 67), (23, 71)), F_B, FS_B, seconds, seed, level)[0]


def _csv_a(path, seed):
    """Box A's take as its logger writes it: semicolon-separated, decimal commas, volts at 10.2 mV/(m/s^2) and a
    once-a-turn tacho pulse."""
    a, th = _accel(((17, 53),), F_A, FS_A, 2.0, seed)
    key = np.where(np.mod(th, 2 * np.pi) < 0.15, 4.8, 0.05)
    rows = (f"{i / FS_A:.6f};{v:.6f};{k:.2f}".replace(".", ",") for i, (v, k) in enumerate(zip(a * 0.0102, key)))
    path.write_text("t [s];acc [V];key [V]\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def box_a(tmp_path_factory):
    where = tmp_path_factory.mktemp("hb_a")
    (where / "box17.toml").write_text(BOX_A)
    (where / "box18.toml").write_text(BOX_A.replace("z = 17", "z = 18"))
    return where, _csv_a(where / "take.csv", seed=1)


def test_a_semicolon_csv_with_decimal_commas_reads_its_mesh_and_speed(cli, box_a):
    """Box A as the guide's step 2 inspects it: mesh order 17 found within 0.05, the tacho's speed within 0.5 %."""
    where, take = box_a
    read_as_described(inspected(cli, take, "--gearbox", where / "box17.toml", *A_KEYS), F_A, [17])


def test_a_wrong_pinion_count_is_called_out(cli, box_a):
    where, take = box_a
    code, out, err = cli("inspect", take, "--gearbox", where / "box18.toml", *A_KEYS)
    assert code == 0, err
    assert "a 17-tooth pinion on the input shaft? described 18" in out, out[-2000:]


def _scenario(tmp_path, history, test, extra=""):
    (tmp_path / "box2s.toml").write_text(BOX_B)
    path = tmp_path / "detect.toml"
    path.write_text(
        '[scenario]\nname = "b"\nkind = "detection"\n[source]\ngearbox = "box2s.toml"\nfaults = { chip = [16] }\n'
        f'[target]\nspeed = "40 Hz"\n{extra}files = [{{ file = "{history}", role = "history", label = "healthy" }}, '
        f'{{ file = "{test}", role = "test", label = "fault" }}]\n[[methods]]\nadapter = "matched_filter"\n'
    )
    return path


def test_a_mat_files_unit_text_is_no_channel_and_its_unit_is_checked_at_validate(cli, tmp_path):
    """A MATLAB v5 take of box B with `acc`, `fs` and the text `acc_unit` (as the guide's step 0 reads a unit):
    validate counted `acc_unit` a second signal channel and asked for 'vibration', which inspect and the run do not;
    and a velocity's `acc_unit = 'mm/s'` passed validate where the same .npz is refused. Both read as inspect reads."""
    a = _accel_b()
    scipy.io.savemat(tmp_path / "h.mat", {"acc": a[:, None], "fs": FS_B, "acc_unit": "m/s^2"}, format="5")
    scipy.io.savemat(tmp_path / "t.mat", {"acc": a[:, None], "fs": FS_B, "acc_unit": "m/s^2"}, format="5")
    code, out, err = cli("validate", _scenario(tmp_path, "h.mat", "t.mat"))
    assert code == 0, err
    scipy.io.savemat(tmp_path / "v.mat", {"acc": a[:, None], "fs": FS_B, "acc_unit": "mm/s"}, format="5")
    code, out, err = cli("validate", _scenario(tmp_path, "h.mat", "v.mat"))
    assert code == 2, out
    assert err.count("\n") == 1 and "key 'vibration'" in err and "v.mat" in err and "velocity in mm/s" in err, err
    # a struct's 'units' field (MATLAB's struct('acc', x, 'fs', 5000, 'units', 'mm/s')) as well
    for name, unit in (("good.mat", "m/s^2"), ("struct.mat", "mm/s")):
        scipy.io.savemat(tmp_path / name, {"rec": {"acc": a[:, None], "fs": FS_B, "units": unit}}, format="5")
    code, out, err = cli("validate", _scenario(tmp_path, "good.mat", "struct.mat", 'vibration = "rec/acc"\n'))
    assert code == 2 and "struct.mat" in err and "velocity in mm/s" in err, (out, err)


@pytest.fixture(scope="module")
def box_b(tmp_path_factory):
    """Box B's healthy history at load 1.0 (a .mat and an .npz, 2.5 s: 9 turns of the output shaft) and its takes:
    healthy at 1.2 x the level (the level measure's limit is 1.25 x)."""
    where = tmp_path_factory.mktemp("hb_b")
    (where / "box2s.toml").write_text(BOX_B)
    mat = {"acc": _accel_b(2.5, seed=11)[:, None], "fs": FS_B, "acc_unit": "m/s^2"}
    scipy.io.savemat(where / "h1.mat", mat, format="5")
    np.savez(where / "h2.npz", acc=_accel_b(2.5, seed=12), fs=FS_B, unit="m/s^2")
    np.savez(where / "loaded.npz", acc=_accel_b(2.5, seed=13, level=1.2), fs=FS_B, unit="m/s^2")
    return where


def _call_b(cli, where, take):
    import json

    history = ("--history", where / "h1.mat", "--history", where / "h2.npz")
    code, out, err = cli("inspect", where / take, "--gearbox", where / "box2s.toml", *history, "--json")
    assert code == 0, err
    return json.loads(out)["localisation"]["call"]


def test_a_healthy_take_at_1_2_x_its_history_level_is_no_change(cli, box_b):
    call = _call_b(cli, box_b, "loaded.npz")
    assert call.startswith("no change against the history"), call
    assert "level" not in call, call


def test_a_run_s_verdict_says_the_level_of_a_take_called_on_no_gear():
    # box B's healthy take at 1.2 x its one-load history's level (under the 1.25 x of a level change) was called by
    # NA4 and the template methods on no gear: the verdict said 'the watched gear's fault by the run's rule; look at
    # the watched gear.' and the level only among the warnings under the tables (gearlab score says it first)
    from gearlab.kinds.detection_summary import take_lines

    take = {
        "condition": "40 Hz", "named": [], "call": "watched-gear fault: input pinion 19T (stage 1)",
        "summary": "nothing localised (largest: input z = 1.04, threshold 2.71)",
        "nonsync": {"changed": False, "order": 1.2, "z": 2.0, "threshold": 4.3},
    }  # fmt: skip
    level = {"level_ratio": {"rec/loaded.npz": 1.2016}, "level_spread": 3.6e-5, "warnings": []}
    summary = {"which_gear": {"records": {"rec/loaded.npz": take}}, "conditions": {"40 Hz": level}}
    records = [
        {"condition": "40 Hz", "method": m, "thresholds": {"record30": 1.0},
         "test_scores": {"rec/loaded.npz": {"record30": [2.0, 3.0]}}}
        for m in ("na4", "matched_filter")
    ]  # fmt: skip
    (line,) = take_lines(summary, records, "record30")
    assert "the watched gear's fault by the run's rule; its level 1.2 x its history's" in line, line
    assert line.endswith("or record a history at this take's load (or gain)."), line
    level["level_ratio"]["rec/loaded.npz"] = 1.0
    (plain,) = take_lines(summary, records, "record30")  # at the history's level: as before
    assert plain.endswith("by the run's rule; look at the watched gear."), plain
