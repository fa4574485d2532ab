"""Outside user FC (issue 39, round 25): a 38/103 reducer at 29 Hz, its takes made here with numpy (each shaft's lines,
the mesh's harmonics modulated in amplitude and phase by both shafts, noise, a once-per-turn tacho), a chipped pinion
tooth (a burst and a ring once a turn) and a bearing's outer race (strikes at 3.62 input orders, slipping 1 %, ringing
at 4.6 kHz), read as docs/your_gearbox.md says: a box with a gear fault and a bearing fault at once."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.inspect import InspectOptions

FS = 12800.0
Z = (38, 103)
BOX = (
    '[gearbox]\nname = "reducerFC"\n[operation]\nspeed = "29 Hz"\nload = "40 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\npinion = { z = 38, bore = "25 mm" }\n'
    'wheel = { z = 103, bore = "40 mm" }\n[sensor]\nnear = "input"\ntacho = "input"\n'
)


def _ring(hz: float, decay: float, seconds: float) -> np.ndarray:
    k = np.arange(int(seconds * FS)) / FS
    return np.exp(-decay * k) * np.sin(2 * np.pi * hz * k)


def _take(seed: int, seconds: float = 4.0, chip: float = 0.0, wheel: bool = False, bearing: float = 0.0, load=1.0):
    """(time s, m/s², tacho V) of the 38/103 box at 29 Hz; *chip*: a tooth's burst and ring once a turn of the pinion
    (of the wheel, *wheel*); *bearing*: outer-race strikes at 3.62 input orders, each interval slipping 1 %; *load*:
    the mesh's lines' factor."""
    rng = np.random.default_rng(seed)
    n = int(seconds * FS)
    t = np.arange(n) / FS
    a_in = 2 * np.pi * 29.0 * t + rng.uniform(0, 6)
    a_out = a_in * Z[0] / Z[1]
    x = 0.5 * np.cos(a_in + 0.3) + 0.3 * np.cos(2 * a_in + 1.0) + 0.4 * np.cos(a_out + 0.7)
    am = 1 + 0.08 * np.cos(a_in + 0.2) + 0.06 * np.cos(a_out + 1.1)
    pm = 0.05 * np.sin(a_in + 0.4) + 0.04 * np.sin(a_out)
    for h, amp in ((1, 3.0), (2, 1.2), (3, 0.5)):
        x += load * amp * am * np.cos(h * (Z[0] * a_in + pm) + 0.5 * h)
    if chip:
        a, z = (a_out, Z[1]) if wheel else (a_in, Z[0])
        at = np.mod(a - 2 * np.pi * 7 / z + np.pi, 2 * np.pi) - np.pi
        x += chip * np.exp(-0.5 * (at * z / (1.4 * np.pi)) ** 2) * np.cos(Z[0] * a_in + 0.5)
        ring = _ring(3100.0, 900.0, 0.004)
        for i in np.flatnonzero(np.diff(np.floor((a - 2 * np.pi * 7 / z) / (2 * np.pi))) > 0):
            x[i : i + ring.size] += 4 * chip * ring[: n - i]
    if bearing:
        ring, at = _ring(4600.0, 1500.0, 0.003), rng.uniform(0, 0.01)
        while at < seconds:
            i = int(at * FS)
            x[i : i + ring.size] += bearing * ring[: n - i]
            at += (1 + 0.01 * rng.standard_normal()) / (3.62 * 29.0)
    x += rng.normal(0, 0.2, n)
    return t, x, np.where(np.mod(a_in, 2 * np.pi) < 0.3, 5.0, 0.0)


@pytest.fixture(scope="module")
def takes(tmp_path_factory):
    from gearlab.gearbox import load_gearbox

    folder = tmp_path_factory.mktemp("fc")
    (folder / "box.toml").write_text(BOX)
    made = {
        **{f"history{k}": {"seed": k} for k in (1, 2, 3)},
        "chip_bearing": {"seed": 12, "chip": 1.0, "bearing": 2.5},
        "wheel_chip": {"seed": 30, "chip": 3.0, "wheel": True},
        "bearing": {"seed": 13, "bearing": 2.5},
        "heavier": {"seed": 20, "load": 1.5},
    }
    for name, kw in made.items():
        t, x, tacho = _take(**kw)
        np.savetxt(
            folder / f"{name}.csv",
            np.column_stack([t, x, tacho]),
            delimiter=",",
            header="time_s,acc_ms2,tacho_V",
            comments="",
            fmt="%.8g",
        )
    return folder, load_gearbox(folder / "box.toml")


def _inspected(takes, name: str) -> dict:
    from gearlab.inspect_history import localisation

    folder, box = takes
    history = [str(folder / f"history{k}.csv") for k in (1, 2, 3)]
    return localisation(str(folder / f"{name}.csv"), history, box, InspectOptions("acc_ms2", tacho="tacho_V"))


def test_a_bearing_s_strikes_beside_a_chipped_pinion_are_named_beside_it(takes):
    # a chipped 38T pinion and an outer race striking at 3.62 input orders in one take: inspect's call read
    # 'localised change: input pinion 38T (stage 1)' alone, the run's 'watched-gear fault: input pinion 38T (stage 1)',
    # while the non-synchronous line stood at z 20.2 over its threshold of 4.47: the bearing went unsaid
    from gearlab.kinds.detection_which_gear import call_of, is_also_other

    got = _inspected(takes, "chip_bearing")
    assert got["named"] == "input pinion 38T (stage 1)" and got["nonsync"]["changed"], got["nonsync"]
    ns = got["nonsync"]  # the strikes' line, no product of the pinion's shaft (nonsync.products)
    assert ns["order"] == pytest.approx(3.62, abs=0.04) and "input" not in ns["shafts"], ns
    assert got["call"] == (
        "localised change: input pinion 38T (stage 1); also other damage: non-synchronous (bearing-like), at order "
        f"{got['nonsync']['order']:.2f}"
    ), got["call"]
    run = call_of(got, ["input pinion 38T (stage 1)"], got["nonsync"], 29.0)
    assert run.startswith("watched-gear fault: input pinion 38T (stage 1); also other damage: non-synchronous"), run
    assert is_also_other(run), run
    alone = _inspected(takes, "bearing")  # the bearing alone: no gear named, other damage
    assert alone["named"] is None and alone["call"].startswith("other damage: non-synchronous (bearing-like)"), alone


def test_a_wheel_chip_s_leak_at_a_whole_output_order_is_no_bearing(takes):
    # the 103T wheel's chip over 4 s (41 output turns) leaks past the residual's removed bins: its line, at a whole
    # output order, passes the non-synchronous threshold; it is the wheel's own, not a bearing beside it
    got = _inspected(takes, "wheel_chip")
    assert got["named"] == "output gear 103T (stage 1)", got["summary"]
    ns = got["nonsync"]  # z 5.1 over 4.42 at 1.842, the 5th output order (1.845)
    assert ns["changed"] and "output" in ns["shafts"], ns
    assert abs(ns["order"] - round(ns["order"] * 103 / 38) * 38 / 103) < 0.5 / 16, ns
    assert got["call"] == "localised change: output gear 103T (stage 1)", got["call"]


def test_a_daq_s_raw_binary_samples_are_refused_naming_the_side_header_and_the_npz_to_write(tmp_path, takes, cli):
    # a DAQ's float32 .bin beside its .json header, and an int16 big-endian .dat beside a .txt: the .bin read
    # "unknown file type '.bin'; supported: ...", the .dat "cannot read ... as text: 'utf-8' codec can't decode byte
    # 0xff in position 0: invalid start byte", neither naming the header beside it nor a way to read the samples
    from gearlab.errors import GearlabInputError
    from gearlab.inspect import inspect_record

    folder, box = takes
    t, x, tacho = _take(1, seconds=1.0)
    np.column_stack([x, tacho]).astype("<f4").tofile(tmp_path / "daq.bin")
    (tmp_path / "daq.json").write_text('{"fs": 12800, "channels": ["acc", "tacho"]}')
    np.round(np.column_stack([x, tacho]) / 0.01).astype(">i2").tofile(tmp_path / "daq2.dat")
    (tmp_path / "daq2.txt").write_text("sample_rate=12800\nchannels=acc,tacho\nscale=0.01 per count\n")
    for name, side in (("daq.bin", "daq.json"), ("daq2.dat", "daq2.txt")):
        with pytest.raises(GearlabInputError) as err:
            inspect_record(str(tmp_path / name), box, InspectOptions("acc", tacho="tacho"))
        text = str(err.value)
        assert "raw binary samples" in text and f"'{side}' beside it" in text and "\n" not in text, text
        assert f"numpy.fromfile('{name}'" in text and "numpy.savez(" in text and "fs=RATE" in text, text
    scenario = tmp_path / "gap.toml"
    (tmp_path / "box.toml").write_text(BOX)
    scenario.write_text(
        '[scenario]\nname = "raw"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n'
        '[target]\nvibration = "acc"\ntacho = "tacho"\n'
        'files = [{ file = "daq2.dat", role = "history", label = "healthy" }]\n'
        '[diagnosis]\ncandidates = ["sensor_noise"]\n[accuracy]\nenabled = false\n'
    )
    code, _, err = cli("validate", str(scenario))
    line = err.strip().splitlines()[-1]
    assert code == 2 and "[target] key 'file'" in line and "raw binary samples" in line, (code, err)
    # the recipe the line gives reads: the samples with their rate
    y = np.fromfile(tmp_path / "daq2.dat", dtype=">i2").reshape(-1, 2) * 0.01
    np.savez(tmp_path / "daq2.npz", acc=y[:, 0], tacho=y[:, 1], fs=FS)
    got = inspect_record(str(tmp_path / "daq2.npz"), box, InspectOptions("acc", tacho="tacho", unit="m/s^2"))
    assert got["fs_hz"] == FS and got["speed"]["mean_hz"] == pytest.approx(29.0, rel=0.005), got["speed"]


def test_a_take_at_another_load_than_its_history_s_says_its_level_beside_the_call(takes):
    # a healthy take at 1.5 x the one-load history's mesh level: a run and score warn 'level 1.5 x its history's
    # (another load or gain?)'; inspect --history said nothing of it, its call whatever the which-gear z gave
    got = _inspected(takes, "heavier")
    assert got["level"] == pytest.approx(1.5, rel=0.1), got["level"]
    assert got["call"].endswith(
        f"; the take's level {got['level']:.2g} x its history's (another load or gain?): a history at that load "
        "compares like with like"
    ), got["call"]
    same = _inspected(takes, "bearing")  # within LEVEL_OFF of its history's: nothing said
    assert "level" not in same["call"] and same["level"] == pytest.approx(1.0, abs=0.2), same


def test_the_verdict_s_which_gear_line_names_a_bearing_s_takes_and_the_one_beside_a_gear():
    # the 38/103 run's verdict listed the outer race's take (z 24.1 over 4.5, 'other damage: non-synchronous
    # (bearing-like), at order 3.62' in its table) among 'nothing localised' with the healthy takes, and said nothing
    # of the bearing beside the chipped pinion's take
    from gearlab.kinds.detection_verdict import which_gear_line

    pinion, ns = "input pinion 38T (stage 1)", "non-synchronous (bearing-like), at order 3.62"
    records = {
        "rec/chip.csv": {"named": pinion, "call": f"watched-gear fault: {pinion}"},
        "rec/chip_bearing.csv": {"named": pinion, "call": f"watched-gear fault: {pinion}; also other damage: {ns}"},
        "rec/bearing.csv": {"named": None, "call": f"other damage: {ns}"},
        "rec/healthy.csv": {"named": None, "call": "not flagged (no method's units over its threshold)"},
    }
    summary = {
        "which_gear": {"watched": [pinion], "records": {f: r | {"condition": "29 Hz"} for f, r in records.items()}}
    }
    assert which_gear_line(summary, "29 Hz") == (
        f"29 Hz, which gear each test take's change lies on: {pinion}, watched: 2 (chip.csv, chip_bearing.csv); "
        "a non-synchronous (bearing-like) line: 1 (bearing.csv); nothing localised: 1 (healthy.csv); beside a gear's "
        "change, a non-synchronous (bearing-like) line: 1 (chip_bearing.csv)."
    )
