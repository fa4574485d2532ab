"""An outside user's look (issue 39): two gearboxes no other test uses, their takes made here by plain numpy (mesh
lines with both shafts' sidebands, shaft harmonics, noise, a tooth's strike once a turn; no gearlab simulator).
A: one stage 23/79 at ~35 Hz, a logger's CSV: 6 lines of preamble (a channel units line among them) above the header
'Time (ms),Accel X (g),Accel Y (g),Tacho (V)', the speed drifting +-3 %. B: two stages 17/51 + 29/58 at 12 Hz in
HDF5 (/run1/acc, units and fs attributes), the history at 25.6 kHz, the takes at 51.2 kHz."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import inspected, read_as_described

G = 9.80665
PREAMBLE_A = (
    "Device: VibLogger VL-4 SN 20413\nDate: 2026-11-30 09:12:44\nSample rate: 20480 Hz\nChannels: 3\n"
    "Units: ms, g, g, V\nOperator: plant B line 2\nTime (ms),Accel X (g),Accel Y (g),Tacho (V)\n"
)


def test_a_logger_s_channel_units_line_in_its_preamble_is_no_header(tmp_path):
    # 'Units: ms, g, g, V' above the header has the table's commas: it was read as the header ('column 'g' appears
    # twice in the header'), the file refused
    from gearlab.data.recordings import read_channels

    t = np.arange(2048) / 20480.0
    rows = "".join(f"{1000 * s:.4f},{0.1:.6f},{np.sin(500 * s):.6f},0.05\n" for s in t)
    path = tmp_path / "log.csv"
    path.write_text(PREAMBLE_A + rows)
    found, fs = read_channels(path, ["Accel Y (g)"])
    assert fs == pytest.approx(20480.0)
    assert found["Accel Y (g)"] == pytest.approx(np.sin(500 * t), abs=1e-5)


@pytest.mark.parametrize("name, sep", [("log.csv", ","), ("log.txt", "\t")])
def test_a_preamble_s_units_line_gives_each_column_its_unit_at_validate_and_in_a_run(tmp_path, cli, name, sep):
    # columns named with no unit, the preamble's line alone says AccY is in g: validate's header reading and a run's
    # reading must both know it (a sensitivity given for volts refused), in a CSV and a tab-separated text alike
    from gearboxes import description, stage

    from gearlab.data.recordings import read_contents

    t = np.arange(4096) / 20480.0
    rows = "".join(sep.join((f"{s:.7f}", "0.1", f"{np.sin(5000 * s):.6f}", "0.05")) + "\n" for s in t)
    path = tmp_path / name
    table = sep.join(("Units: s", "V", "g", "V")) + "\n" + sep.join(("Time", "AccX", "AccY", "Tacho")) + "\n"
    path.write_text("Device: VL-4\nSample rate: 20480 Hz\n" + table + rows)
    assert read_contents(path, ["AccY"])[0].units["AccY"] == "g"
    (tmp_path / "box.toml").write_text(description(stage(23, 79), speed="35 Hz", load="40 N*m"))
    scenario = (
        '[scenario]\nname = "s"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n[target]\nvibration = "AccY"\n'
        f'speed = "35 Hz"\nsensitivity = "100 mV/g"\nfile = "{name}"\n'
    )
    (tmp_path / "s.toml").write_text(scenario)
    code, out, err = cli("validate", tmp_path / "s.toml")
    assert code == 2 and "key 'sensitivity'" in err and "acceleration already (g" in err, (out, err)


def _box(zs, f0, fs, seconds, seed, fault=None, drift=0.03):
    """A box's acceleration (m/s^2) and input angle at a speed drifting slowly by *drift* over the take: each stage's
    mesh (3 harmonics, its two shafts' sidebands), each shaft's harmonics, noise; *fault* = shaft index: a tooth's
    strike once a turn of that shaft (a 3.1 kHz ring) and its mesh's dip over about one tooth."""
    rng = np.random.default_rng(seed)
    n = int(fs * seconds)
    t = np.arange(n) / fs
    f = f0 * (1 + drift * np.sin(2 * np.pi * t / (1.3 * seconds) + rng.uniform(0, 2 * np.pi)))
    th = 2 * np.pi * np.cumsum(f) / fs + rng.uniform(0, 2 * np.pi)
    shafts = [th * np.prod([zp / zw for zp, zw in zs[:k]]) for k in range(len(zs) + 1)]
    a = sum(0.25 / h * np.cos(h * s + 3 * k + h) for k, s in enumerate(shafts) for h in (1, 2, 3))
    for s, (zp, _) in enumerate(zs):
        am = 1 + 0.12 * np.cos(shafts[s] + 0.4) + 0.08 * np.cos(shafts[s + 1] + 2.1)
        mesh = sum(c * np.cos(h * zp * shafts[s] + s + h) for h, c in ((1, 1), (2, 0.4), (3, 0.15)))
        a = a + 3.0 / (1 + s) * am * mesh
    if fault is not None:
        stage = min(fault, len(zs) - 1)
        z = zs[stage][0] if fault == stage else zs[stage][1]
        off = np.angle(np.exp(1j * (shafts[fault] - 1.0)))
        a = a - 3.0 / (1 + stage) * np.exp(-0.5 * (off / (np.pi / z)) ** 2) * np.cos(zs[stage][0] * shafts[stage])
        ring = np.zeros(n)
        ring[np.flatnonzero(np.diff(np.mod(shafts[fault] - 1.0, 2 * np.pi)) < 0) + 1] = 1.0
        kernel = np.exp(-t[: int(0.006 * fs)] / 0.0015) * np.sin(2 * np.pi * 3100 * t[: int(0.006 * fs)])
        a = a + 6.0 * np.convolve(ring, kernel)[:n]
    return a + rng.normal(0, 0.4, n), th, f.mean()


def _csv_a(path, seed, seconds=3.0, fault=None):
    """Box A's take as its logger writes it: the preamble, time in ms, Accel X and Y in g, a once-a-turn tacho."""
    fs = 20480
    ay, th, mean = _box(((23, 79),), 35.0, fs, seconds, seed, fault)
    ax = 0.5 * ay[::-1]
    tacho = np.where(np.mod(th, 2 * np.pi) < 0.2, 5.0, 0.05)
    table = np.column_stack([1000 * np.arange(ay.size) / fs, ax / G, ay / G, tacho])
    with open(path, "w") as out:
        out.write(PREAMBLE_A)
        np.savetxt(out, table, fmt=["%.4f", "%.6f", "%.6f", "%.3f"], delimiter=",")
    return mean


def _h5_b(path, seed, fs, seconds=4.0, fault=None):
    """Box B's take: /run1/acc in m/s^2 with its 'units' and 'fs' attributes, /run1/tacho beside it."""
    import h5py

    a, th, mean = _box(((17, 51), (29, 58)), 12.0, fs, seconds, seed, fault, drift=0.01)
    with h5py.File(path, "w") as h5:
        acc = h5.create_dataset("run1/acc", data=a.astype(np.float32))
        acc.attrs["units"], acc.attrs["fs"] = "m/s^2", float(fs)
        tacho = h5.create_dataset("run1/tacho", data=np.where(np.mod(th, 2 * np.pi) < 0.2, 5.0, 0.05))
        tacho.attrs["fs"] = float(fs)
    return mean


A_KEYS = ("--vibration", "Accel Y (g)", "--tacho", "Tacho (V)")
B_KEYS = ("--vibration", "run1/acc", "--tacho", "run1/tacho")


def _write_boxes(where):
    from gearboxes import description, stage

    box_a = description(stage(23, 79, "2.5 mm", "25 mm"), name="boxA", speed="35 Hz", load="40 N*m", tacho="input")
    (where / "boxA.toml").write_text(box_a)
    (where / "boxA24.toml").write_text(box_a.replace("z = 23,", "z = 24,"))
    stages = stage(17, 51, "3 mm", "30 mm"), stage(29, 58, "4 mm", "40 mm")
    (where / "boxB.toml").write_text(description(*stages, name="boxB", speed="12 Hz", load="300 N*m", tacho="input"))


@pytest.fixture(scope="module")
def takes(tmp_path_factory):
    """A's three takes (a history, a healthy and a chipped pinion's); B's history at 25.6 kHz, its takes at 51.2 kHz
    (a healthy one and one whose output gear is chipped): their mean speeds by name."""
    where = tmp_path_factory.mktemp("hk")
    _write_boxes(where)
    a_takes = ("a_hist.csv", 1, None), ("a_healthy.csv", 2, None), ("a_pinion.csv", 3, 0), ("a_wheel.csv", 4, 1)
    b_takes = ("b_hist1.h5", 11, 25600, None), ("b_hist2.h5", 12, 25600, None), ("b_out.h5", 13, 51200, 2)
    speeds = {name: _csv_a(where / name, seed, fault=fault) for name, seed, fault in a_takes}
    speeds |= {name: _h5_b(where / name, seed, fs, fault=fault) for name, seed, fs, fault in b_takes}
    return where, speeds


def test_a_logger_csv_gives_its_speed_and_mesh_order_from_the_accelerometer_asked(cli, takes):
    where, speeds = takes
    code, out, err = cli("inspect", where / "a_hist.csv", "--gearbox", where / "boxA.toml")
    assert code == 2 and "the file has Accel X (g), Accel Y (g), Tacho (V); expected --vibration NAME" in err, err
    report = inspected(cli, where / "a_hist.csv", "--gearbox", where / "boxA.toml", *A_KEYS)
    read_as_described(report, speeds["a_hist.csv"], [23])


def test_a_wrong_tooth_count_is_called_out(cli, takes):
    where, _ = takes
    code, out, err = cli("inspect", where / "a_hist.csv", "--gearbox", where / "boxA24.toml", *A_KEYS)
    assert code == 0, err
    assert "a 23-tooth pinion on the input shaft? described 24" in out, out[-2000:]


@pytest.mark.parametrize(
    "take, call",
    [("a_healthy.csv", "no change"), ("a_pinion.csv", "input pinion 23T"), ("a_wheel.csv", "output gear 79T")],
)
def test_a_take_against_its_history_names_the_damaged_gear_or_none(cli, takes, take, call):
    where, _ = takes
    history = ("--history", where / "a_hist.csv")
    code, out, err = cli("inspect", where / take, "--gearbox", where / "boxA.toml", *A_KEYS, *history)
    assert code == 0, err
    (line,) = [line for line in out.splitlines() if line.startswith("call: ")]
    assert call in line, out[-1500:]


def test_b_takes_at_twice_their_history_s_rate_read_both_stages_and_the_output_gear(cli, takes):
    where, speeds = takes
    box = ("--gearbox", where / "boxB.toml")
    report = inspected(cli, where / "b_out.h5", *box, *B_KEYS)
    assert abs(report["speed"]["mean_hz"] / speeds["b_out.h5"] - 1) < 0.005, report["speed"]
    orders = [s["measured_order"] for s in report["check"]["stages"]]
    assert orders == pytest.approx([17, 29 / 3], abs=0.05), report["check"]["stages"]
    history = ("--history", where / "b_hist1.h5", "--history", where / "b_hist2.h5")
    code, out, err = cli("inspect", where / "b_out.h5", *box, *B_KEYS, *history)
    assert code == 0, err
    assert "call: localised change: output gear 58T (stage 2)" in out, out[-1500:]


SCENARIO = """[scenario]
name = "s"
kind = "detection"
[source]
gearbox = "{box}"
faults = {{ chip = [20] }}
[target]
vibration = "{vibration}"
tacho = "{tacho}"
files = [
  {{ file = "{history}", role = "history", label = "healthy" }},
  {{ file = "{test}", role = "test", label = "fault" }},
]
"""
A = dict(box="boxA.toml", vibration="Accel Y (g)", tacho="Tacho (V)", history="a_hist.csv", test="a_pinion.csv")
B = dict(box="boxB.toml", vibration="run1/acc", tacho="run1/tacho", history="b_hist*.h5", test="b_out.h5")


@pytest.mark.parametrize(
    "keys, change, said",
    [
        (A, ("Accel Y", "Accel Z"), ("a_hist.csv has no channel 'Accel Z (g)'", "key 'vibration'")),
        (A, ("a_pinion.csv", "a_gone.csv"), ("a_gone.csv: no such file", "key 'file'")),
        (A, ("[target]\n", '[target]\nunit = "m/s^2"\n'), ("a_hist.csv, which is in g (as its name", "key 'unit'")),
        (B, ("run1/acc", "run2/acc"), ("b_hist1.h5 has no channel 'run2/acc'", "key 'vibration'")),
        (B, ("[target]\n", '[target]\nunit = "g"\n'), ("b_hist1.h5, which is in m/s^2", "key 'unit'")),
    ],
    ids=["A column", "A missing file", "A unit", "B group path", "B unit"],
)
def test_bad_input_is_one_line_naming_file_and_key_at_validate(cli, takes, keys, change, said):
    where, _ = takes
    text = SCENARIO.format(**keys)
    (where / "ok.toml").write_text(text)
    code, out, err = cli("validate", where / "ok.toml")
    assert code == 0, err
    (where / "bad.toml").write_text(text.replace(*change))
    code, out, err = cli("validate", where / "bad.toml")
    assert code == 2 and err.count("\n") == 1 and "bad.toml" in err, (out, err)
    assert all(s in err for s in said), err
