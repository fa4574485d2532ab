"""An outside user's look (issue 39): four gearboxes no other test uses, their takes made here by plain numpy (each
mesh with 4 harmonics, amplitude- and phase-modulated by both of its shafts, shaft lines, a slow speed wander, noise;
no gearlab simulator), read as docs/your_gearbox.md says. A: two stages 23/59 + 19/71 at 1,750 rpm, no tacho, MATLAB
v5 in m/s^2. B: one stage 37/89 at 12 Hz, an int16 stereo WAV (vibration at 100 mV/g, full scale 5 V; a tacho of 2
marks a turn). C: two stages 29/53 + 21/88 at 45 Hz, HDF5 of two accelerometers in g and a tacho on the intermediate
shaft, one (N, 3) dataset whose attributes name its columns and units. D: one stage 41/43 at 30 Hz, a CSV in volts
at 10.2 mV/(m/s^2) whose time column is in ms. Beside them: a file's unit spelled out as NI's software writes it."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
import scipy.io
from gearboxes import description, inspected, read_as_described, stage, text_rows
from scipy.io import wavfile

G = 9.80665


def _take(stages, speed, fs, seconds, seed, gains=None):
    """(acceleration in m/s^2, each shaft's angle, the mean input speed in Hz) of a train of (pinion, wheel) *stages*
    at about *speed* Hz: each mesh's harmonics modulated by both of its shafts, shaft lines, a 0.4 Hz speed wander of
    0.3 %, white noise; *gains*: each stage's level at the sensor."""
    rng = np.random.default_rng(seed)
    n = int(fs * seconds)
    t = np.arange(n) / fs
    hz = speed * (1 + 0.003 * np.sin(2 * np.pi * 0.4 * t + rng.uniform(0, 2 * np.pi)))
    th = 2 * np.pi * np.cumsum(hz) / fs + rng.uniform(0, 2 * np.pi)
    shafts = [th * np.prod([zp / zw for zp, zw in stages[:k]]) for k in range(len(stages) + 1)]
    a = sum(0.3 * np.cos(s + k) for k, s in enumerate(shafts))
    for i, (zp, _) in enumerate(stages):
        am = 1 + 0.25 * np.cos(shafts[i] + 0.3) + 0.2 * np.cos(shafts[i + 1] + 1.2)
        pm = 0.3 * np.sin(shafts[i] + 2.0) + 0.25 * np.sin(shafts[i + 1] + 0.7)
        level = (gains or [1.0 / (1 + 0.6 * j) for j in range(len(stages))])[i]
        for h, amp in ((1, 3.0), (2, 1.8), (3, 1.0), (4, 0.6)):
            a = a + level * amp * am * np.cos(h * (zp * shafts[i] + pm) + h)
    return a + rng.normal(0, 0.3, n), shafts, float(np.mean(hz))


def _pulses(angle, marks=1):
    return np.where(np.mod(angle * marks / (2 * np.pi), 1.0) < 0.15, 4.0, 0.0)


A = ((23, 59), (19, 71))
BOX_A = description(
    stage(23, 59, module="2.5 mm", width="25 mm", bores=("25 mm", "40 mm")),
    stage(19, 71, module="3 mm", width="30 mm", bores=("35 mm", "50 mm")),
    name="boxA",
    speed="1750 rpm",
    load="120 N*m",
    near="input",
)


@pytest.fixture(scope="module")
def box_a(tmp_path_factory):
    where = tmp_path_factory.mktemp("r37_a")
    a, _, hz = _take(A, 1750 / 60, 6400.0, 12.0, seed=1)
    scipy.io.savemat(where / "take.mat", {"acc": a[:, None], "fs": 6400.0, "acc_unit": "m/s^2"}, format="5")
    (where / "boxA.toml").write_text(BOX_A)
    (where / "boxA_72.toml").write_text(BOX_A.replace("z = 71", "z = 72"))
    (where / "boxA_18.toml").write_text(BOX_A.replace("z = 19", "z = 18"))
    return where, hz


def test_a_two_stage_mat_in_m_s2_without_a_tacho_reads_its_speed_and_meshes(cli, box_a):
    where, hz = box_a
    report = inspected(cli, where / "take.mat", "--gearbox", where / "boxA.toml")
    read_as_described(report, hz, [23, 23 * 19 / 59])


@pytest.mark.parametrize(
    "toml, said",
    [
        ("boxA_72.toml", "the wheel on the output shaft shows 71.0"),
        ("boxA_18.toml", "a 19-tooth pinion on the intermediate shaft? described 18"),
    ],
)
def test_a_later_stage_count_one_off_is_named(cli, box_a, toml, said):
    where, _ = box_a
    code, out, err = cli("inspect", where / "take.mat", "--gearbox", where / toml)
    assert code == 0, err
    assert said in " ".join(out.split()), out[-1500:]


BOX_B = description(
    stage(37, 89, module="2 mm", bores=("30 mm", "50 mm")),
    name="boxB",
    speed="12 Hz",
    load="300 N*m",
    near="input",
    tacho="input",
    marks=2,
)
B_KEYS = ("--vibration", "0", "--tacho", "1", "--gain", "5 V", "--sensitivity", "100 mV/g")


@pytest.fixture(scope="module")
def box_b(tmp_path_factory):
    where = tmp_path_factory.mktemp("r37_b")
    a, shafts, hz = _take(((37, 89),), 12.0, 8000.0, 4.0, seed=2)
    volts = a / G * 0.1  # 100 mV/g
    counts = np.stack([volts, _pulses(shafts[0], 2)], axis=1) / 5.0 * 32767  # full scale 5 V
    wavfile.write(where / "take.wav", 8000, np.round(counts).astype(np.int16))
    (where / "boxB.toml").write_text(BOX_B)
    (where / "boxB_one_mark.toml").write_text(BOX_B.replace("pulses_per_rev = 2\n", ""))
    return where, hz


def test_b_int16_stereo_wav_at_its_full_scale_reads_speed_and_mesh_by_two_marks(cli, box_b):
    where, hz = box_b
    report = inspected(cli, where / "take.wav", "--gearbox", where / "boxB.toml", *B_KEYS)
    read_as_described(report, hz, [37])
    code, out, err = cli("inspect", where / "take.wav", "--gearbox", where / "boxB.toml", *B_KEYS)
    assert "m/s² = value x 490.332, 50 g a file unit (5 V / 100 mV/g)" in out, out[:600]


def test_b_two_marks_a_turn_left_out_of_the_description_are_named(cli, box_b):
    where, _ = box_b
    code, out, err = cli("inspect", where / "take.wav", "--gearbox", where / "boxB_one_mark.toml", *B_KEYS)
    assert code == 0, err
    assert "the tacho gives 2 pulse(s) per revolution, not 1?" in " ".join(out.split()), out[-1500:]


C = ((29, 53), (21, 88))
BOX_C = description(
    stage(29, 53, module="2 mm", width="18 mm", bores=("20 mm", "30 mm")),
    stage(21, 88, module="2.5 mm", width="24 mm", bores=("30 mm", "45 mm")),
    name="boxC",
    speed="45 Hz",
    load="60 N*m",
    near="input",
    tacho="intermediate",
)


@pytest.fixture(scope="module")
def box_c(tmp_path_factory):
    where = tmp_path_factory.mktemp("r37_c")
    near_in, shafts, hz = _take(C, 45.0, 12800.0, 6.0, seed=3, gains=[1.0, 0.4])
    near_out, _, _ = _take(C, 45.0, 12800.0, 6.0, seed=3, gains=[0.3, 1.0])
    with h5py.File(where / "take.h5", "w") as f:
        data = f.create_dataset("data", data=np.stack([near_in / G, near_out / G, _pulses(shafts[1])], axis=1))
        data.attrs["channel_names"] = ["acc_in", "acc_out", "tacho"]
        data.attrs["units"] = ["g", "g", "V"]
        f.attrs["fs"] = 12800.0
    (where / "boxC.toml").write_text(BOX_C)
    (where / "boxC_tacho_in.toml").write_text(BOX_C.replace('tacho = "intermediate"', 'tacho = "input"'))
    return where, hz


def test_c_hdf5_columns_named_by_attribute_read_in_g_with_a_tacho_on_the_intermediate_shaft(cli, box_c):
    where, hz = box_c
    keys = ("--gearbox", where / "boxC.toml", "--vibration", "acc_out", "--tacho", "tacho")
    read_as_described(inspected(cli, where / "take.h5", *keys), hz, [29, 29 * 21 / 53])
    code, out, err = cli("inspect", where / "take.h5", *keys)
    assert "values: m/s² = value x 9.80665 (channel 'acc_out' in g)" in out, out[:600]


def test_c_a_tacho_on_the_intermediate_shaft_described_on_the_input_is_named(cli, box_c):
    where, _ = box_c
    keys = ("--gearbox", where / "boxC_tacho_in.toml", "--vibration", "acc_in", "--tacho", "tacho")
    code, out, err = cli("inspect", where / "take.h5", *keys)
    assert code == 0, err
    assert "--tacho-shaft intermediate" in out, out[-1500:]


BOX_D = description(
    stage(41, 43, module="1.5 mm", width="15 mm"), name="boxD", speed="30 Hz", load="40 N*m", tacho="input"
)
D_KEYS = ("--vibration", "acc (V)", "--tacho", "tacho (V)", "--sensitivity", "10.2 mV/(m/s^2)")


@pytest.fixture(scope="module")
def box_d(tmp_path_factory):
    where = tmp_path_factory.mktemp("r37_d")
    a, shafts, hz = _take(((41, 43),), 30.0, 10000.0, 3.0, seed=4)
    ms = np.arange(a.size) / 10.0  # 10 kHz, in ms
    rows = text_rows("%.3f,%.6f,%.1f", ms, a * 0.0102, _pulses(shafts[0]))
    (where / "take.csv").write_text("t (ms),acc (V),tacho (V)\n" + rows)
    (where / "boxD.toml").write_text(BOX_D)
    (where / "boxD_42.toml").write_text(BOX_D.replace("z = 41", "z = 42"))
    return where, hz


def test_d_csv_whose_time_is_in_ms_reads_its_rate_and_a_near_unity_pair(cli, box_d):
    where, hz = box_d
    read_as_described(inspected(cli, where / "take.csv", "--gearbox", where / "boxD.toml", *D_KEYS), hz, [41])
    code, out, err = cli("inspect", where / "take.csv", "--gearbox", where / "boxD_42.toml", *D_KEYS)
    assert code == 0, err
    assert "at 10 kHz (time 't (ms)' (x 0.001 s))" in out, out[:600]
    assert "a 41-tooth pinion on the input shaft? described 42" in " ".join(out.split()), out[-1500:]


@pytest.mark.parametrize("unit, volts", [("Volts", 1.0), ("VOLT", 1.0), ("Millivolts", 1e-3)])
def test_a_file_unit_spelled_out_as_ni_writes_it_is_read_as_volts(tmp_path, cli, unit, volts):
    # a TDMS channel's unit_string in its HDF5 export, 'Volts' as NI's software writes it: 'values: unknown (the
    # file's unit 'Volts' is not read; no sensitivity or gain given: the values are taken as m/s²)', where 'V' and
    # 'volt' said the sensitivity was missing, and a 'unit' key of 'Volts' was read as volts
    from gearlab.data.recordings import read_recording
    from gearlab.errors import GearlabInputError

    a, _, _ = _take(((41, 43),), 30.0, 5000.0, 1.0, seed=5)
    with h5py.File(tmp_path / "ni.h5", "w") as f:
        f.create_dataset("acc", data=a * 0.0102).attrs["unit_string"] = unit
        f.attrs["fs"] = 5000.0
    with pytest.raises(GearlabInputError, match="key 'sensitivity': missing; channel 'acc' is in volts"):
        read_recording(tmp_path / "ni.h5", "acc")
    rec = read_recording(tmp_path / "ni.h5", "acc", sensitivity=0.0102)
    assert np.allclose(rec.signal, a * volts), np.std(rec.signal) / np.std(a)
    code, out, err = cli("inspect", tmp_path / "ni.h5", "--speed", "30 Hz")
    assert code == 0, err
    assert f"not m/s² (channel 'acc' is in volts ({unit}, as the file's unit '{unit}' says)" in out, out[:600]


def _csv_of_wav_take(path):
    a, shafts, _ = _take(((37, 89),), 12.0, 2000.0, 0.5, seed=6)
    t = np.arange(a.size) / 2000.0
    path.write_text("time_s,acc_V,tacho_V\n" + text_rows("%.7f,%.6f,%.3f", t, a / G * 0.1, _pulses(shafts[0], 2)))
    return path


def test_score_of_a_csv_on_a_wav_run_asks_for_its_channels_not_its_time_column(tmp_path):
    # B's run read WAVs with the [target]'s vibration '0' and tacho '1'; next week's take converted to a CSV with a
    # header (time_s, acc_V, tacho_V) held a column '0', its time: 'gearlab score' read it and stopped at "'0' is
    # B_next_week.csv's time or rate column 'time_s' (column 0 counts it); expected a signal channel", with no word
    # of --key, which the guide's step 7 and the line for a file without the channels give
    from types import SimpleNamespace

    from gearlab.errors import GearlabInputError
    from gearlab.kinds.detection_scoring import file_keys, remembered

    target = {"vibration": "0", "tacho": "1", "gain": "5 V", "sensitivity": "100 mV/g"}
    files = [SimpleNamespace(path=f"rec/B_{r}.wav", role=r, keys={}) for r in ("history1", "history2", "test")]
    meta = {"target": target, "file_keys": file_keys(files)}
    take = _csv_of_wav_take(tmp_path / "next.csv")
    with pytest.raises(GearlabInputError, match="--key vibration=NAME --key tacho=NAME") as refused:
        remembered(meta, str(take))
    assert "the run's no files'" not in str(refused.value), refused.value  # every file read with the [target]'s
    assert remembered(meta, str(take), {"vibration": "acc_V", "tacho": "tacho_V"})[0] == {}


def test_a_gain_given_every_file_on_a_file_in_volts_says_how_to_drop_it(tmp_path):
    # the same CSV scored with --key vibration=acc_V --key tacho=tacho_V: the run's gain = '5 V' (its WAVs' full
    # scale) refused on the volts column with 'expected no gain (an amplifier's gain goes in the sensitivity ...)',
    # no word of --key gain=, as the line for a file in m/s² says it
    from gearlab.data.recordings import read_recording
    from gearlab.errors import GearlabInputError

    take = _csv_of_wav_take(tmp_path / "next.csv")
    with pytest.raises(GearlabInputError, match='gain = "" in this file\'s entry; gearlab score: --key gain='):
        read_recording(take, "acc_V", "tacho_V", sensitivity=0.1 / G, gain=5.0)


def test_c_a_dataset_whose_columns_are_all_named_is_listed_by_those_names_alone(cli, box_c):
    # C's (N, 3) 'data' named acc_in, acc_out, tacho by its attribute was listed as a channel of its own ('which
    # channel is the vibration? the file has data, acc_in, acc_out, tacho'), and '--vibration data' was refused
    from gearlab.data.readers.headers import HEADERS

    where, _ = box_c
    code, out, err = cli("inspect", where / "take.h5", "--gearbox", where / "boxC.toml")
    assert code == 2 and "the file has acc_in, acc_out, tacho; expected --vibration NAME" in err, err
    header = HEADERS["HDF5"](where / "take.h5")
    assert header.channels == ["acc_in", "acc_out", "tacho"], header.channels  # validate's listing
    assert header.find("data[1]") and not header.find("data[3]")  # a column by its index is still read


@pytest.mark.parametrize("names", ["acc_in,acc_out,tacho", "acc_in; acc_out; tacho", b"acc_in, acc_out, tacho"])
def test_column_names_stored_as_one_separated_text_name_each_column(tmp_path, names):
    # channel_names written as ONE text "acc_in,acc_out,tacho" (a common export) was no list of 3: the file was read
    # as one channel 'data', with no word of 'data[1]'
    from gearlab.data.readers.headers import HEADERS
    from gearlab.data.recordings import read_recording

    a, shafts, _ = _take(C, 45.0, 12800.0, 0.5, seed=7)
    with h5py.File(tmp_path / "take.h5", "w") as f:
        data = f.create_dataset("data", data=np.stack([a / G, a / G / 2, _pulses(shafts[1])], axis=1))
        data.attrs["channel_names"] = names
        data.attrs["units"] = "g,g,V"
        f.attrs["fs"] = 12800.0
    rec = read_recording(tmp_path / "take.h5", "acc_out", "tacho")
    assert rec.channels == ["acc_in", "acc_out", "tacho"], rec.channels
    assert np.allclose(rec.signal, a / 2), rec.units  # in g, as its unit says: m/s²
    assert HEADERS["HDF5"](tmp_path / "take.h5").channels == ["acc_in", "acc_out", "tacho"]


GAP = '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "{box}"\n[target]\nvibration = "acc"\n'
GAP += 'files = [{{ file = "take.mat", role = "history", label = "healthy" }}]\n'


def test_validate_says_a_gap_history_too_short_for_the_orders_of_stage_1_s_wheel_shaft(cli, box_a):
    # A's gap run on 12 s takes ended with a note alone: 'orders of the intermediate shaft ... need 10 blocks of 59
    # consecutive revolutions per set (590 revolutions); got 0 blocks', nowhere said before recording
    where, _ = box_a
    (where / "gap.toml").write_text(GAP.format(box="boxA.toml"))
    code, out, err = cli("validate", where / "gap.toml")
    assert code == 0 and "OK" in out, err
    said = "the report's orders of the intermediate shaft (stage 1's 59-tooth wheel, 0.3898 input orders) need 590 "
    assert said in err and "record(s) hold ~350 (their headers' lengths at 29.17 Hz: 20.3 s in all needed)" in err
    (where / "boxA_29.toml").write_text(BOX_A.replace("z = 23", "z = 29").replace("z = 59", "z = 58"))
    (where / "gap.toml").write_text(GAP.format(box="boxA_29.toml"))
    code, out, err = cli("validate", where / "gap.toml")
    assert code == 0 and "consecutive input revolutions" not in err, err  # 29/58: blocks of 2, 20 revolutions
