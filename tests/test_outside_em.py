"""Outside user EM (issue 39, round 21): a 29/139 pump drive at 30 Hz, its takes made here with numpy (each shaft's
lines, the mesh's harmonics modulated in amplitude and phase by both shafts, noise, a once-per-turn tacho), written
as engineers' tools write them: Excel's serial days as the time column, units of acceleration in a channel's name
that are not m/s² or g ('acc [mm/s²]', 'a (in/s^2)')."""

from __future__ import annotations

import re

import numpy as np
import pytest

from gearlab.inspect import InspectOptions, inspect_record

FS = 25600.0
STAGES = ((29, 139),)
BOX = (
    '[gearbox]\nname = "pumpA"\n[operation]\nspeed = "30 Hz"\nload = "40 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\npinion = { z = 29, bore = "25 mm" }\n'
    'wheel = { z = 139, bore = "40 mm" }\n[sensor]\nnear = "input"\ntacho = "input"\n'
)


def _shaft(seconds: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(t in s, the input shaft's angle in rad): 30 Hz swinging 0.2 %, from any angle."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    f = 30.0 * (1 + 0.002 * np.sin(2 * np.pi * 0.31 * t + rng.uniform(0, 6)))
    return t, 2 * np.pi * np.cumsum(f) / FS + rng.uniform(0, 6)


def _take(th: np.ndarray, seed: int) -> np.ndarray:
    """m/s²: both shafts' orders 1-2, the mesh's harmonics 1-3 modulated in amplitude and phase, noise 24 dB down."""
    rng = np.random.default_rng(seed + 7)
    zp, zw = STAGES[0]
    wheel = th * zp / zw
    x = sum(0.2 * np.cos(k * a + 0.7 * k) for a in (th, wheel) for k in (1, 2))
    for h, amp in ((1, 3.0), (2, 1.2), (3, 0.4)):
        am = 1 + 0.06 * np.cos(th + 0.3 * h) + 0.04 * np.cos(wheel + 0.8 * h)
        x = x + amp * am * np.cos(h * (zp * th + 0.03 * np.cos(th + 0.2) + 0.02 * np.cos(wheel)))
    return x + rng.normal(0, 0.06 * np.std(x), th.size)


def _tacho(th: np.ndarray) -> np.ndarray:
    return np.where(np.mod(th, 2 * np.pi) < 0.3, 5.0, 0.0)


def _csv(path, header: str, *columns, formats: tuple[str, ...]) -> None:
    rows = (",".join(f % v for f, v in zip(formats, row)) for row in zip(*columns))
    path.write_text(header + "\n" + "\n".join(rows) + "\n")


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    from gearlab.gearbox import load_gearbox

    path = tmp_path_factory.mktemp("pump") / "box.toml"
    path.write_text(BOX)
    return load_gearbox(path)


def test_a_time_column_of_excel_serial_days_gives_the_rate(tmp_path, box, cli):
    # Excel's CSV of a 'Time' column in its General format: serial days since 1899-12-30 to 15 digits
    # (46357.4166666667 is 2026-12-01 10:00): read as seconds, '76800 samples at 2.212e+06 kHz, 3.472e-05 s' and
    # 'speed 155513594 rpm (2592 kHz) measured ... +8639544 %', exit 0
    t, th = _shaft(2.0, 1)
    acc = _take(th, 1)
    path = tmp_path / "excel.csv"
    _csv(
        path, "Time,acc_ms2,tacho_V", 46357.0 + 10 / 24 + t / 86400, acc, _tacho(th), formats=("%.10f", "%.6f", "%.1f")
    )
    got = inspect_record(str(path), box, InspectOptions("acc_ms2", tacho="tacho_V"))
    assert got["fs_hz"] == pytest.approx(FS, rel=1e-4)
    assert "Excel serial days" in got["fs_source"], got["fs_source"]
    assert got["speed"]["mean_hz"] == pytest.approx(30.0, rel=0.005)
    assert "matches" in got["verdict"], got["verdict"]
    # validate reads the rate off the header's first rows alike: '25.6 kHz given, but excel.csv says 2.212e+06 kHz'
    _gap_scenario(tmp_path, "'excel.csv'", extra='fs = "25.6 kHz"\n')
    code, out, err = cli("validate", tmp_path / "gap.toml")
    assert code == 0, err


@pytest.mark.parametrize(("name", "per_ms2"), [("acc [mm/s²]", 1000.0), ("a (in/s^2)", 1 / 0.0254)])
def test_an_acceleration_unit_in_brackets_in_a_channel_s_name_scales_its_values(tmp_path, box, name, per_ms2):
    # a channel named 'acc [mm/s²]' (or 'a (in/s^2)', an American logger's) was 'values: unknown (no sensitivity
    # or gain given: the values are taken as m/s²)': the level 1000 x (39 x) too high, unsaid
    t, th = _shaft(2.0, 2)
    acc = _take(th, 2)
    path = tmp_path / "take.csv"
    _csv(path, f"time_s,{name},tacho_V", t, acc * per_ms2, _tacho(th), formats=("%.8f", "%.5f", "%.1f"))
    got = inspect_record(str(path), box, InspectOptions(name, tacho="tacho_V"))
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.01), got["units"]
    assert got["units"].startswith("m/s² = value x"), got["units"]


def test_inspect_names_a_speed_channel_in_hz_given_as_the_tacho(tmp_path, box):
    # a logger's analog speed channel ('speed_Hz', 30 Hz swinging 0.2 %) given as --tacho: inspect said 'pulse train
    # has 1 rising edge(s) in 51200 samples ... at least 2 once-per-revolution pulses are needed', as though the
    # pulses were too few (a run said 'a speed channel?')
    from gearlab.errors import GearlabInputError

    t, th = _shaft(2.0, 3)
    path = tmp_path / "speed.csv"
    speed = 30.0 * (1 + 0.002 * np.sin(2 * np.pi * 0.31 * t))
    _csv(path, "time_s,acc_ms2,speed_Hz", t, _take(th, 3), speed, formats=("%.8f", "%.5f", "%.4f"))
    with pytest.raises(GearlabInputError) as err:
        inspect_record(str(path), box, InspectOptions("acc_ms2", tacho="speed_Hz"))
    text = str(err.value)
    assert "a speed channel?" in text and "speed_Hz" in text and "\n" not in text, text
    assert re.search(r"'30\.0\d Hz'", text), text  # the speed to give, in the unit a channel named '_Hz' is in


def _gap_scenario(folder, file: str, extra: str = "") -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "box.toml").write_text(BOX)
    (folder / "gap.toml").write_text(
        '[scenario]\nname = "pump_gap"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n[target]\n'
        f'vibration = "acc_ms2"\ntacho = "tacho_V"\n{extra}'
        f'files = [{{ file = {file}, role = "history", label = "healthy" }}]\n'
        '[diagnosis]\ncandidates = ["sensor_noise"]\n[accuracy]\nenabled = false\n'
    )


def test_a_windows_user_s_backslashes_in_a_scenario_in_another_folder_than_its_data_name_its_files(tmp_path, cli):
    # a scenario written on Windows beside its data's folder ('..\daten\Prüfstand Verlauf ?.csv', a literal TOML
    # string, non-ASCII and blanks in the names): "'..\\daten\\Prüfstand Verlauf ?.csv' matches no file", exit 2
    t, th = _shaft(1.0, 4)
    (tmp_path / "daten").mkdir()
    for i in (1, 2):
        _csv(
            tmp_path / "daten" / f"Prüfstand Verlauf {i}.csv",
            "time_s,acc_ms2,tacho_V",
            t,
            _take(th, i),
            _tacho(th),
            formats=("%.8f", "%.5f", "%.1f"),
        )
    _gap_scenario(tmp_path / "szenarien", r"'..\daten\Prüfstand Verlauf ?.csv'")
    code, out, err = cli("validate", tmp_path / "szenarien" / "gap.toml")
    assert code == 0 and "2 measured history records" in out, out + err
    _gap_scenario(tmp_path / "szenarien", r"'..\daten\Prüfstand Verlauf 1.csv'")  # one file, no pattern
    code, out, err = cli("validate", tmp_path / "szenarien" / "gap.toml")
    assert code == 0 and "1 measured history record" in out, out + err
    # a drive's path is none on this machine: one line naming the scenario, its table and key
    _gap_scenario(tmp_path / "szenarien", r"'D:\Messungen\Verlauf 1.csv'")
    code, out, err = cli("validate", tmp_path / "szenarien" / "gap.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "gap.toml" in line and "[target]" in line and "Windows drive" in line, err


@pytest.mark.parametrize(
    ("name", "side", "said"),
    [
        ("take.csv", ("take.json", '{"device": "NI 9234", "channels": 2, "sample_rate": 25600}'), "take.json states"),
        ("take.csv", ("take.yaml", "logger: DT9837\nSampleRate_kHz: 25.6\n"), "take.yaml states"),
        ("pump_25k6Hz.csv", None, None),
        ("pump 25600 Hz.csv", None, "its name says"),
    ],
)
def test_a_rate_a_logger_s_side_file_or_the_take_s_name_states_is_named_where_the_file_has_none(
    tmp_path, box, name, side, said
):
    # no time column, the rate only beside the take (a logger's take.json or take.yaml) or in its name: 'no sampling
    # rate: the file has no 'fs'/time and none was given (--fs / fs = ...)', the rate the user had at hand unsaid
    from gearlab.errors import GearlabInputError

    _, th = _shaft(1.0, 5)
    _csv(tmp_path / name, "acc_ms2,tacho_V", _take(th, 5), _tacho(th), formats=("%.5f", "%.1f"))
    if side:
        (tmp_path / side[0]).write_text(side[1])
    with pytest.raises(GearlabInputError) as err:
        inspect_record(str(tmp_path / name), box, InspectOptions("acc_ms2", tacho="tacho_V"))
    text = str(err.value)
    assert "no sampling rate" in text and "\n" not in text, text
    if said is None:  # '25k6' is no number this reads: no rate guessed
        assert "its name says" not in text, text
    else:
        assert said in text and "--fs '25.6 kHz'" in text, text


def test_a_run_of_one_history_take_and_test_takes_too_short_for_its_longest_tsa_says_what_to_record(
    cli, tmp_path, no_figures
):
    # a 29/139 box's one 2 s history take and 1 s test takes (29 input turns; record30 needs 30): the verdict read
    # '30 Hz: no test take: its history's thresholds serve gearlab score.' beside a record10 AUC of 1.00 of two test
    # takes, and nothing of its thresholds resting on one take. Here the tiny run (blocks 5 and 10), test takes of 8
    # turns
    from detection_scenario import scenario
    from textrecords import record

    files = [("h1", "history", "healthy", 0.0), ("s1", "test", "healthy", 0.0), ("s2", "test", "fault", 4.0)]
    (tmp_path / "data").mkdir()
    for i, (name, _, _, chip) in enumerate(files[1:]):
        record(tmp_path / "data" / f"{name}.zip", revolutions=8, chip=chip, seed=20 + i, phase=0.3 * i)
    path = scenario(tmp_path, files=files, methods=("matched_filter",))
    code, out, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 0, err
    assert "no test take" not in out, out
    # no record10 unit of a test take: its 'called %' table said 'nan', numpy's 'Mean of empty slice' as a warning
    assert "empty slice" not in err and not re.search(r"\bnan\b", out), err
    (line,) = [s for s in out.splitlines() if "too short for record10" in s]
    assert "judged at record5" in line and "goal met by" in line, line
    # the which-gear check's 'too short' says the length to record in seconds too (1 s takes said '6.05 turns ... it
    # needs 8' alone); 8 turns at 16 Hz and 10 marks a turn here: a fraction of a second
    assert re.search(r"it needs \d+ \(a take of [\d.]+ s or more\)", out), out
    (alone,) = [s for s in out.splitlines() if "one history take" in s]
    assert "add two or more healthy takes" in alone, alone
    # `gearlab compare` of such runs stopped on 'internal error: TypeError: unsupported format string passed to
    # NoneType.__format__' (record10 has no AUC here)
    run_dir = out.strip().splitlines()[-1].split(": ", 1)[1]
    code, out, err = cli("compare", run_dir, run_dir)
    assert code == 0 and "– (– / –)" in out, out + err


def test_a_charge_accelerometer_s_sensitivity_is_refused_naming_the_amplifier_s_gain_it_needs(tmp_path, cli):
    # a charge accelerometer's data sheet value, sensitivity = "10 pC/g": 'has the wrong dimension; expected a
    # quantity in V*s^2/m', which says nothing of the charge amplifier between sensor and logger
    t, th = _shaft(1.0, 6)
    _csv(tmp_path / "take.csv", "time_s,acc_ms2,tacho_V", t, _take(th, 6), _tacho(th), formats=("%.8f", "%.5f", "%.1f"))
    _gap_scenario(tmp_path, "'take.csv'", extra='sensitivity = "10 pC/g"\n')
    code, _, err = cli("validate", tmp_path / "gap.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "gap.toml" in line and "[target]" in line and "sensitivity" in line, err
    assert "charge amplifier's gain" in line and "'100 mV/g'" in line, line


def test_a_unit_key_takes_any_acceleration_unit_and_names_a_velocity_as_such(tmp_path, cli, box):
    # a headerless logger export in mg: unit = "mg" (or "mm/s²") was refused, "'mg' is not one of m/s^2, m/s², g, V,
    # mV (did you mean 'g'?)", though a channel named 'acc [mg]' is read; unit = "mm/s" got "(did you mean 'm/s²'?)"
    t, th = _shaft(1.0, 7)
    acc = _take(th, 7)
    path = tmp_path / "take.csv"
    _csv(path, "time_s,acc,tacho_V", t, acc / 9.80665 * 1000, _tacho(th), formats=("%.8f", "%.4f", "%.1f"))
    got = inspect_record(str(path), box, InspectOptions("acc", tacho="tacho_V", unit="mg"))
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.01), got["units"]
    _gap_scenario(tmp_path, "'take.csv'", extra='unit = "mm/s"\n')
    (tmp_path / "gap.toml").write_text((tmp_path / "gap.toml").read_text().replace('"acc_ms2"', '"acc"'))
    code, _, err = cli("validate", tmp_path / "gap.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "[target] key 'unit'" in line and "is a velocity" in line, err


@pytest.mark.parametrize(
    ("stamp", "sep"),
    [("%Y-%m-%dT%H:%M:%S.%fZ", ","), ("%Y-%m-%dT%H:%M:%S.%f+01:00", ","), ("%Y-%m-%d %H:%M:%S,%f", ";")],
)
def test_clock_times_with_a_zone_or_a_decimal_comma_give_the_rate_without_numpy_s_warning(tmp_path, box, stamp, sep):
    # a logger's UTC stamps ('...T10:00:00.000039Z', '+01:00') read with 'warning: no explicit representation of
    # timezones available for np.datetime64'; a German logger's decimal comma ('10:00:00,000039', ';' between
    # columns) was 'must hold times in seconds or ISO 8601 clock times'
    import datetime
    import warnings

    t, th = _shaft(1.0, 8)
    start = datetime.datetime(2026, 12, 1, 10)
    stamps = [(start + datetime.timedelta(microseconds=round(s * 1e6))).strftime(stamp) for s in t]
    rows = (f"{s}{sep}{a:.5f}{sep}{k:.1f}" for s, a, k in zip(stamps, _take(th, 8), _tacho(th)))
    path = tmp_path / "take.csv"
    path.write_text(
        f"timestamp{sep}acc_ms2{sep}tacho_V\n" + "\n".join(r.replace(".", ",") if sep == ";" else r for r in rows)
    )
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        got = inspect_record(str(path), box, InspectOptions("acc_ms2", tacho="tacho_V"))
    assert got["fs_hz"] == pytest.approx(FS, rel=1e-4), got["fs_source"]
    assert not [w for w in said if "timezones" in str(w.message)], [str(w.message) for w in said]


def test_clock_times_stamped_coarser_than_a_sampling_period_take_the_rate_given(tmp_path, box):
    # a logger's clock stamped to the millisecond at 25.6 kHz ('10:00:00.000', 26 rows each): 'does not increase
    # between samples 0 and 1 (0 -> 0 s); expected increasing times in seconds', no rate said, and --fs refused alike
    import datetime

    from gearlab.errors import GearlabInputError

    t, th = _shaft(1.0, 9)
    start = datetime.datetime(2026, 12, 1, 10)
    stamps = [
        (start + datetime.timedelta(microseconds=round(s * 1e6))).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3] for s in t
    ]
    path = tmp_path / "take.csv"
    _csv(path, "timestamp,acc_ms2,tacho_V", stamps, _take(th, 9), _tacho(th), formats=("%s", "%.5f", "%.1f"))
    with pytest.raises(GearlabInputError) as err:
        inspect_record(str(path), box, InspectOptions("acc_ms2", tacho="tacho_V"))
    text = str(err.value)
    assert "written coarser than a sampling period" in text and "fs = '25.6" in text and "\n" not in text, text
    # the rate given is taken, checked against the stamps (a given fs was refused by the same line)
    got = inspect_record(str(path), box, InspectOptions("acc_ms2", tacho="tacho_V", fs=FS))
    assert got["fs_hz"] == FS and got["speed"]["mean_hz"] == pytest.approx(30.0, rel=0.005), got["fs_source"]
    with pytest.raises(GearlabInputError, match="disagrees with time 'timestamp'"):
        inspect_record(str(path), box, InspectOptions("acc_ms2", tacho="tacho_V", fs=24000.0))
