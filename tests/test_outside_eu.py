"""Outside user EU (issue 39, round 23): a 37/113 drive at 27 Hz, its takes made here with numpy (each shaft's lines,
the mesh's harmonics modulated in amplitude and phase by both shafts, noise, a once-per-turn tacho), written as
commercial DAQ software exports them: Simcenter Testlab's MAT struct (x_values.increment, y_values.values), NI
TDMS channels copied to HDF5 (a 'wf_increment' and a 'unit_string' attribute per channel)."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.inspect import InspectOptions, inspect_record

FS = 25600.0
ZP, ZW = 37, 113
BOX = (
    '[gearbox]\nname = "driveEU"\n[operation]\nspeed = "27 Hz"\nload = "30 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "18 mm"\npinion = { z = 37, bore = "25 mm" }\n'
    'wheel = { z = 113, bore = "40 mm" }\n[sensor]\nnear = "input"\ntacho = "input"\n'
)


def _take(seconds: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(m/s², tacho V): 27 Hz swinging 0.2 %; both shafts' orders 1-2, the mesh's harmonics 1-3 modulated, noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    th = 2 * np.pi * np.cumsum(27.0 * (1 + 0.002 * np.sin(2 * np.pi * 0.37 * t))) / FS + rng.uniform(0, 6)
    wheel = th * ZP / ZW
    x = sum(0.15 * np.cos(k * a + 0.5 * k) for a in (th, wheel) for k in (1, 2))
    for h, amp in ((1, 3.0), (2, 1.1), (3, 0.4)):
        am = 1 + 0.05 * np.cos(th + 0.3 * h) + 0.04 * np.cos(wheel + 0.8 * h)
        x = x + amp * am * np.cos(h * (ZP * th + 0.03 * np.cos(th) + 0.02 * np.cos(wheel)))
    x = x + rng.normal(0, 0.06 * np.std(x), t.size)
    return x, np.where(np.mod(th, 2 * np.pi) < 0.3, 5.0, 0.0)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    from gearlab.gearbox import load_gearbox

    path = tmp_path_factory.mktemp("drive") / "box.toml"
    path.write_text(BOX)
    return load_gearbox(path)


def _matched(got: dict) -> None:
    assert got["fs_hz"] == pytest.approx(FS, rel=1e-6), got["fs_source"]
    assert got["speed"]["mean_hz"] == pytest.approx(27.0, rel=0.005)
    assert "matches" in got["verdict"], got["verdict"]


def test_a_simcenter_testlab_struct_s_x_values_increment_gives_the_rate(tmp_path, box):
    # Testlab's 'Save as MATLAB' writes each channel as a struct: x_values (start_value, increment,
    # number_of_values), y_values (values, unit) and function_record; was 'no sampling rate: the file has no
    # 'fs'/time and none was given'
    from scipy.io import savemat

    acc, tacho = _take(2.0, 1)
    x_values = {"start_value": 0.0, "increment": 1 / FS, "number_of_values": float(acc.size), "unit": "s"}
    savemat(
        tmp_path / "testlab.mat",
        {
            "Signal_1": {"x_values": x_values, "y_values": {"values": acc, "unit": "m/s^2"}, "function_record": {}},
            "Signal_2": {"x_values": x_values, "y_values": {"values": tacho, "unit": "V"}, "function_record": {}},
        },
    )
    got = inspect_record(
        str(tmp_path / "testlab.mat"), box, InspectOptions("Signal_1.y_values.values", tacho="Signal_2.y_values.values")
    )
    assert "increment" in got["fs_source"], got["fs_source"]
    _matched(got)


def test_a_testlab_struct_named_as_the_channel_names_the_field_of_its_numbers(tmp_path, box):
    # --vibration Signal_1 (the channel's name in Testlab) said 'is not numeric (stored as object); expected an array
    # of numbers', the field to give ('Signal_1.y_values.values') unsaid
    from scipy.io import savemat

    from gearlab.errors import GearlabInputError

    acc, tacho = _take(0.5, 5)
    x_values = {"start_value": 0.0, "increment": 1 / FS, "number_of_values": float(acc.size)}
    savemat(tmp_path / "t.mat", {"Signal_1": {"x_values": x_values, "y_values": {"values": acc, "unit": "g"}}})
    with pytest.raises(GearlabInputError) as err:
        inspect_record(str(tmp_path / "t.mat"), box, InspectOptions("Signal_1"))
    text = str(err.value)
    assert "'Signal_1' is not numeric: a struct" in text and "Signal_1.y_values.values" in text, text


def test_tdms_channels_in_hdf5_give_their_rate_by_wf_increment_and_their_unit_by_unit_string(tmp_path, box):
    # NI's TDMS properties, kept by a TDMS-to-HDF5 copy as each channel's attributes: 'wf_increment' (s) and
    # 'unit_string'; the rate was 'no sampling rate', and given by hand, a channel in g was taken as m/s² (9.8 x low)
    import h5py

    acc, tacho = _take(2.0, 2)
    with h5py.File(tmp_path / "tdms.h5", "w") as f:
        group = f.create_group("Measurement")
        for name, data, unit in (("acc", acc / 9.80665, "g"), ("tacho", tacho, "V")):
            ds = group.create_dataset(name, data=data)
            ds.attrs.update({"wf_increment": 1 / FS, "wf_start_offset": 0.0, "unit_string": unit})
    got = inspect_record(str(tmp_path / "tdms.h5"), box, InspectOptions("acc", tacho="tacho"))
    assert "wf_increment" in got["fs_source"], got["fs_source"]
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.01), got["units"]
    _matched(got)


def test_dewesoft_like_mat_channels_with_their_own_rate_or_time_variables_are_read_and_validated(tmp_path, box, cli):
    # a DAQ's MAT export of each channel as a variable beside its own: 'Data1_time_ACC' for 'Data1_ACC' (Dewesoft's
    # names), 'TACHO_fs' for 'TACHO' (its counter at half the rate); both were 'no sampling rate', and
    # validate 'key 'fs': missing; ... carries no sampling rate'
    from scipy.io import savemat

    acc, tacho = _take(2.0, 3)
    t = np.arange(acc.size) / FS
    savemat(tmp_path / "dewe.mat", {"Data1_ACC": acc, "Data1_time_ACC": t, "Data1_TACHO": tacho, "Data1_time_TACHO": t})
    savemat(tmp_path / "own.mat", {"ACC": acc, "ACC_fs": FS, "TACHO": tacho[::2], "TACHO_fs": FS / 2})
    got = inspect_record(str(tmp_path / "dewe.mat"), box, InspectOptions("Data1_ACC", tacho="Data1_TACHO"))
    assert "Data1_time_ACC" in got["fs_source"], got["fs_source"]
    _matched(got)
    got = inspect_record(str(tmp_path / "own.mat"), box, InspectOptions("ACC", tacho="TACHO"))
    assert "'ACC_fs'" in got["fs_source"] and "held from 12800 Hz" in got["fs_source"], got["fs_source"]
    _matched(got)
    (tmp_path / "box.toml").write_text(BOX)
    for name, vib, tach in (("dewe", "Data1_ACC", "Data1_TACHO"), ("own", "ACC", "TACHO")):
        (tmp_path / "gap.toml").write_text(
            '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n[target]\n'
            f'vibration = "{vib}"\ntacho = "{tach}"\n'
            f'files = [{{ file = "{name}.mat", role = "history", label = "healthy" }}]\n'
            '[diagnosis]\ncandidates = ["sensor_noise"]\n[accuracy]\nenabled = false\n'
        )
        code, out, err = cli("validate", tmp_path / "gap.toml")
        assert code == 0 and "1 measured history record" in out, out + err


def test_an_amplifier_s_gain_given_as_gain_on_a_channel_in_volts_is_refused_in_one_line(tmp_path, box, cli):
    # 10 mV/g through an amplifier at x10, written as the sensor sheet and the amplifier's dial say (gain = "10"):
    # the gain is volts per file unit, so the level came out 100 x too high ('100 g a file unit (10 V / 10 mV/g)'),
    # unsaid; the guide's way, sensitivity = '100 mV/g', reads it right
    acc, tacho = _take(2.0, 4)
    t = np.arange(acc.size) / FS
    path = tmp_path / "amp.csv"
    np.savetxt(path, np.c_[t, acc / 9.80665 * 0.1, tacho], delimiter=",", header="time_s,acc_V,tacho_V", comments="")
    (tmp_path / "box.toml").write_text(BOX)
    args = ("inspect", path, "--gearbox", tmp_path / "box.toml", "--vibration", "acc_V", "--tacho", "tacho_V")
    code, out, err = cli(*args, "--sensitivity", "10 mV/g", "--gain", "10")  # inspect looks, and says so in line 1
    assert "not m/s² (expected no gain" in out.splitlines()[0] and "'1 V/g'" in out.splitlines()[0], out + err
    got = inspect_record(str(path), box, InspectOptions("acc_V", tacho="tacho_V", sensitivity=0.1 / 9.80665))
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.01), got["units"]
    (tmp_path / "gap.toml").write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n[target]\nvibration = "acc_V"\n'
        'tacho = "tacho_V"\nsensitivity = "10 mV/g"\ngain = "10"\n'
        'files = [{ file = "amp.csv", role = "history", label = "healthy" }]\n[accuracy]\nenabled = false\n'
    )
    code, out, err = cli("validate", tmp_path / "gap.toml")
    assert code == 2 and "[target] key 'gain'" in err and "volts already" in err, out + err


def test_a_take_3_db_under_its_history_names_the_template_methods_that_call_it_and_the_remedy():
    # a 34/87 + 26/61 + 38/91 box's healthy takes after the sensor was re-mounted, 3 dB lower: gearlab score's
    # matched_filter called both 'fault' at record30 (2/2 units, median over threshold +0.006 and +0.003; which gear:
    # nothing) while the line said 'NA4, a size, reads it as a change' (NA4 stayed healthy) and gave no remedy
    from gearlab.kinds.detection_level import level_line

    line = level_line(10 ** (-3 / 20))
    assert line.startswith("level 0.71 x its history's (another load or gain?)"), line
    assert "matched_filter" in line and "likelihood_ratio" in line and "re-mounted: record a new history" in line, line


def _localised(watched: float) -> dict:
    """A detection summary (its record30 fm4 row and which-gear call) whose fault takes were all called at the
    history's threshold, *watched* % of them on the watched gear, the rest on another (other damage)."""
    row = {"condition": "40 Hz", "unit": "record30", "method": "fm4", "auc": 1.0, "detection": 100.0}
    row |= {"false_alarm": 0.0, "n_positive": 4, "n_negative": 4, "history_model": {"records": 3}}
    call = {"condition": "40 Hz", "method": "fm4", "unit": "record30", "auc": 1.0}
    call |= {"units": {"fault": 4, "healthy": 2}, "judged": {"fault": 4 * watched // 100, "healthy": 2}}
    call |= {"watched": {"fault": watched, "healthy": 0.0}, "other": {"fault": 100.0 - watched, "healthy": 0.0}}
    return {"rows": [row], "which_gear": {"calls": [call]}, "target": {"positive": "fault"}}


def test_a_verdict_says_the_fault_takes_were_called_on_another_gear_not_that_the_threshold_failed():
    # a 34/87 + 26/61 + 38/91 box watching its 26T intermediate pinion: both fault takes called by every method at
    # the history's threshold (called % 'fault' 100, 'healthy' 0), their change named on the 87T gear of the same
    # shaft, so 0 % detected; the verdict said '(the threshold, not the method, fails): fm4 (AUC 1.00, 0 / 0 %)'
    from gearlab.kinds.detection_verdict import detection_lines

    text = " ".join(detection_lines(_localised(0.0), "record30"))
    assert "lies on another gear than the watched one as other damage" in text and "fm4 (AUC 1.00, 0 / 0 %)" in text, (
        text
    )
    assert "the threshold, not the method, fails" not in text, text


def test_compare_counts_detections_as_each_run_s_verdict_does():
    # the same box before and after two takes with damage on the watched pinion's own mesh were added: the verdicts
    # said fm4 '0 / 0 %' and '50 / 0 %' at record30, gearlab compare '1.000 (100 / 0)' for both, a +0.000 change
    from gearlab.kinds.detection_tables import side_by_side

    title, table = side_by_side([("A", None, None, _localised(0.0)), ("B", None, None, _localised(50.0))])
    row = next(line for line in table.splitlines() if "record30" in line)
    assert "1.000 (0 / 0)" in row and "1.000 (50 / 0)" in row, table
    assert "other damage" in title, title


def test_a_corrected_method_that_scores_as_its_plain_twin_is_said():
    # the 3-stage box's run with [corrected] effects = sensor_noise (20 dB): 'matched_filter (corrected)' and
    # 'likelihood_ratio (corrected)' scored all 414 test units as the plain rows to the last bit, in every table and
    # in gearlab compare, unsaid: does detection use the corrected simulator? (it does; noise changes no template)
    from gearlab.kinds.detection_tables import unchanged_by_correction

    scores = {"f.csv": {"record30": [1.0, 2.0]}}
    records = [
        {"condition": "40 Hz", "method": m, "test_scores": scores}
        for m in ("matched_filter", "matched_filter (corrected)", "fm4")
    ]
    records.append({"condition": "40 Hz", "method": "dann (corrected)", "test_scores": {"f.csv": {"record30": [3.0]}}})
    records.append({"condition": "40 Hz", "method": "dann", "test_scores": scores})
    (line,) = unchanged_by_correction(records)
    assert line.startswith("40 Hz: matched_filter (corrected) scored every test unit as matched_filter"), line


def test_a_negative_sensitivity_is_refused_with_its_magnitude_to_give(tmp_path):
    # a charge amplifier's inverting output written as the calibration sheet says ('-100 mV/g'): the refusal named
    # no way on for a sign that is the sheet's
    from gearlab.data.textzip import parse_sensitivity
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError) as err:
        parse_sensitivity("-100 mV/g", "[target] key 'sensitivity'")
    assert "give its magnitude" in str(err.value) and "[target] key 'sensitivity'" in str(err.value), str(err.value)
    assert parse_sensitivity("100 mV/g", "x") == pytest.approx(0.1 / 9.80665)
