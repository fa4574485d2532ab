"""Outside-user check of issue 39 (helper CP): recordings made outside gearlab, read as docs/your_gearbox.md says
(small files written here, not simulated by gearlab)."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import box_s, box_s_detection, box_s_gap, box_s_take

from gearlab.data.textzip import calibration, gain_quantity, parse_sensitivity

G = 9.80665


@pytest.mark.parametrize(
    "written, si, unit",
    [
        ("5g", 5 * G, "m/s^2"),  # a float WAV's full scale as a data sheet writes it
        ("2.5g", 2.5 * G, "m/s^2"),
        ("10g/V", 10 * G, "m/s^2/V"),
        ("1 mg", 1e-3 * G, "m/s^2"),  # integer counts of a milli-g each
        ("1mg", 1e-3 * G, "m/s^2"),
    ],
)
def test_a_gain_in_g_without_a_space_or_in_milli_g_is_read_as_gravity(written, si, unit):
    # '--gain 5g' was refused ('cannot read '5g' as a gain') while '--sensitivity 1V/g' was read: the 'g' after a
    # digit was taken as the gram; '1 mg' (milligram) too, though the gain's own help names counts of '1 mg'
    number, kind = gain_quantity(written, "--gain")
    assert kind == unit and number == pytest.approx(si)
    assert calibration({"gain": written}, lambda k: f"--{k}")["sensitivity"] > 0


def test_a_sensitivity_in_g_without_a_space_is_read_and_kilograms_stay_refused():
    assert parse_sensitivity("100mV/g", "--sensitivity") == pytest.approx(0.1 / G)
    assert parse_sensitivity("0.1V/g", "--sensitivity") == pytest.approx(0.1 / G)
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError, match="--gain"):
        gain_quantity("5 kg", "--gain")


def _stepped_take(fs=51200.0, seconds=4.0, f0=50.02, step=1.04, seed=26):
    """A two-stage 100/116 + 108/114 box's take without a tacho (its three shafts' lines, mesh harmonics 1-3 with
    their shafts' AM/PM, noise at 20 dB), its input speed stepping by *step* over 0.2 s half-way: (signal, speed
    per sample)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    f = f0 * (1 + (step - 1) * np.clip((t - seconds / 2) / 0.2, 0, 1))
    rev = np.cumsum(f) / fs + rng.uniform(0, 1)
    ratios = [1.0, 100 / 116, 100 / 116 * 108 / 114]
    x = np.zeros(t.size)
    for k, r in enumerate(ratios):
        x += 0.05 * np.cos(2 * np.pi * r * rev + 0.3 * k) + 0.02 * np.cos(4 * np.pi * r * rev + 1.1 * k)
    for i, zp in enumerate((100, 108)):
        a_in, a_out = 2 * np.pi * ratios[i] * rev, 2 * np.pi * ratios[i + 1] * rev
        am = 1 + 0.12 * np.cos(a_in + 0.4) + 0.08 * np.cos(a_out + 1.3)
        pm = 0.15 * np.sin(a_in) + 0.1 * np.sin(a_out + 0.7)
        for h, (amp, phase) in enumerate([(1.0, 0.2), (0.45, 1.7), (0.2, 2.9)], start=1):
            x += amp / (1 + 0.3 * i) * am * np.cos(2 * np.pi * h * zp * ratios[i] * rev + h * pm + phase + i)
    x = 3.0 * x
    x += rng.normal(0, np.sqrt(np.mean(x**2) / 100), t.size)
    return x, f


def test_a_take_without_a_tacho_whose_speed_steps_4_percent_is_followed_without_slipping(tmp_path):
    # box C of CP (100/116 + 108/114 at 50 Hz, 51.2 kHz, no tacho), a 4 % step half-way: the mesh phase was followed
    # in a band centred on the description's 50 Hz, 2 % under the take's mean, and the step's far side left it:
    # cycles slipped (48.2 Hz read for 0.1 s where it was 50-52), the mean read 50.75 Hz for 50.97 and inspect said
    # 'the wheel on the output shaft shows 114.6 ± 0.5 teeth, 114 described' of a right description
    from gearlab.gearbox import load_gearbox
    from gearlab.gearbox.speed import follow_speed

    box_file = tmp_path / "box.toml"
    box_file.write_text(
        '[gearbox]\nname = "stepC"\n[operation]\nspeed = "3000 rpm"\nload = "15 N*m"\n'
        '[[stages]]\nmodule = "1.25 mm"\nface_width = "15 mm"\npinion = { z = 100, bore = "25 mm" }\n'
        'wheel = { z = 116, bore = "30 mm" }\n'
        '[[stages]]\nmodule = "1.5 mm"\nface_width = "18 mm"\npinion = { z = 108, bore = "30 mm" }\n'
        'wheel = { z = 114, bore = "35 mm" }\n[sensor]\nnear = "intermediate"\n'
    )
    x, f = _stepped_take()
    theta, mean, how, _ = follow_speed(x, 51200.0, load_gearbox(str(box_file)), None, "take")
    assert theta is not None and "followed" in how
    assert mean == pytest.approx(f.mean(), rel=0.002)
    speed = np.diff(theta) * 51200.0 / (2 * np.pi)
    per_tenth = speed[: speed.size // 5120 * 5120].reshape(-1, 5120).mean(axis=1)
    truth = f[: speed.size // 5120 * 5120].reshape(-1, 5120).mean(axis=1)
    assert np.max(np.abs(per_tenth / truth - 1)) < 0.005


@pytest.mark.parametrize("marks", [1, 2, 3, 4, 6, 8])
def test_a_square_tacho_of_several_marks_a_turn_sampled_at_the_vibrations_rate_is_read_without_its_edges_pattern(marks):
    # CP's box C: a TTL tacho of 2 marks a turn sampled at 51.2 kHz, the shaft at 49.97 Hz. Its edges, each off by up
    # to half a sample in a pattern repeating at 30.7 Hz, were smoothed for 1 mark a turn only: read raw (1.34 mrad
    # rms), they phase-modulated the 100-tooth mesh by 0.13 rad, and its sidebands 0.615 order apart were read as the
    # intermediate shaft: inspect said 'the wheel on the intermediate shaft shows 162.6 ± 0.5 teeth, 116 described'
    # of a right description, and a detection run stopped on its history. 3-8 marks read raw: 1.25-1.64 mrad, and
    # inspect read 144.4 (3 marks) and 162.7 (4, 8) teeth for the 116
    from gearlab.signals.angle import angle_from_pulses

    fs, f0 = 51200.0, 49.97
    t = np.arange(int(4 * fs)) / fs
    turns = f0 * t + 0.37
    pulses = 5.0 * (np.mod(turns * marks, 1.0) < 0.25)
    theta = angle_from_pulses(pulses, fs, marks=marks) / marks
    error = theta - 2 * np.pi * (turns - np.ceil(turns[0] * marks) / marks)
    error = error[5000:-5000] - error[5000:-5000].mean()
    assert np.sqrt(np.mean(error**2)) < 0.2e-3  # rad; raw edges: 1.34e-3 at 2 marks


@pytest.mark.parametrize("fs, f0", [(51200.0, 49.97), (25600.0, 35.3)])
def test_a_square_tacho_of_unequally_spaced_marks_keeps_their_spacing_when_smoothed(fs, f0):
    # a real wheel's 4 marks lie a few % off a quarter turn each: each mark's edges are smoothed apart, so the angle
    # read follows the exact edges' (1.54 / 1.83 mrad rms raw, 0.07 / 0.08 smoothed apart; all marks as one sequence
    # flattened the spacing: 1.85 / 2.31)
    from gearlab.signals.angle import angle_from_pulses

    marks, s = 4, np.arange(int(4 * fs))
    where = (np.arange(marks) + np.array([0.0, 0.04, -0.03, 0.02])) / marks  # turns
    turns = f0 * s / fs + 0.37
    pulses = 5.0 * np.any([np.mod(turns - w, 1.0) < 0.025 for w in where], axis=0)
    exact = np.sort([(w + k - 0.37) * fs / f0 for w in where for k in range(int(5 * f0))])
    exact = exact[(exact > 0) & (exact < s.size - 1)]
    reference = np.interp(s, exact, 2 * np.pi * np.arange(exact.size))  # the angle read through exact edges
    error = (angle_from_pulses(pulses, fs, marks=marks) - reference)[5000:-5000] / marks
    assert np.std(error) < 0.2e-3  # rad


def _volts_take(path, fs=8192.0, seconds=3.0):
    """A one-stage 20/47 box's take at 24.3 Hz, 0.7 g RMS, in volts at 100 mV/g, one headerless column."""
    rng = np.random.default_rng(7)
    t = np.arange(int(fs * seconds)) / fs
    np.savetxt(path, 0.1 * box_s_take(rng, t), fmt="%.6f")
    return path


def test_volts_read_as_millivolts_by_the_unit_key_are_called_out(tmp_path):
    # CP: a take in volts given unit = "mV" reads 1000 x too low (0.7 g -> 0.7 mg) and nothing said so, where the
    # take in millivolts read as volts is called 'too loud for a gearbox'
    from gearlab.data.recordings import read_recording

    take = _volts_take(tmp_path / "v.tsv")
    low = read_recording(take, "0", fs=8192.0, sensitivity=0.1 / G, unit="mV")
    assert low.units.endswith("too quiet for a gearbox: values in volts? unit = 'V'"), low.units
    right = read_recording(take, "0", fs=8192.0, sensitivity=0.1 / G, unit="V")
    assert "too quiet" not in right.units and "too loud" not in right.units, right.units


def test_inspect_calls_out_volts_given_as_millivolts(cli, tmp_path):
    import json

    from gearboxes import description, stage

    box = tmp_path / "s.toml"
    box.write_text(description(stage(20, 47, bores=("25 mm", "40 mm")), name="boxS", speed="24.3 Hz", near="input"))
    take = _volts_take(tmp_path / "v.tsv")
    args = ("--gearbox", box, "--vibration", "0", "--fs", "8192", "--sensitivity", "100 mV/g", "--json")
    code, out, err = cli("inspect", take, *args, "--unit", "mV")
    assert code == 0, err
    said = json.loads(out)["units"]
    assert "RMS 0.000" in said and "too quiet for a gearbox: values in volts? --unit V" in said, said
    code, out, err = cli("inspect", take, *args, "--unit", "V")
    assert code == 0 and "too quiet" not in json.loads(out)["units"], err


@pytest.mark.parametrize("written, read", [("volts", "V"), ("Volt", "V"), ("volt", "V"), ("millivolts", "mV")])
def test_the_unit_key_reads_volts_as_they_are_spelled(cli, tmp_path, written, read):
    # CP: unit = "volts" was refused ("'volts' is not one of m/s^2, m/s², g, V, mV") by every reader of the key
    from gearlab import read_recording

    take = _volts_take(tmp_path / "v.tsv")
    spelled = read_recording(take, 0, fs=8192.0, sensitivity="100 mV/g", unit=written)
    assert spelled.units == read_recording(take, 0, fs=8192.0, sensitivity="100 mV/g", unit=read).units
    target = f'vibration = "0"\nfs = "8192 Hz"\nunit = "{written}"\nsensitivity = "100 mV/g"\n'
    box_s_gap(tmp_path, "v.tsv", target)
    code, out, err = cli("validate", tmp_path / "gap.toml")
    assert code == 0, err
    code, out, err = cli(
        "inspect",
        take,
        "--vibration",
        "0",
        "--fs",
        "8192",
        "--speed",
        "24.3 Hz",
        "--unit",
        written,
        "--sensitivity",
        "100 mV/g",
        "--json",
    )
    assert code == 0, err


@pytest.mark.parametrize("written", ["volz", "G", "kV"])
def test_a_unit_key_of_no_known_spelling_stays_refused(written):
    from gearlab import read_recording
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError, match=f"unit: '{written}' is not one of m/s\\^2, m/s², g, V, mV"):
        read_recording("missing.tsv", 0, fs=8192.0, unit=written)


def test_score_words_a_wav_s_full_scale_as_inspect_does(cli, tmp_path):
    # CP: a float WAV's gain = "5g" (its full scale) was worded '5 g a file unit (the gain, a full scale)' by inspect
    # and '5 g a file unit (1 V / 200 mV/g)' by gearlab score, a volt the user never gave: the run's scoring.json kept
    # the gain as the number 1.0 and lost that it was a full scale
    import json

    from scipy.io import wavfile

    box_s(tmp_path)
    rng, fs = np.random.default_rng(5), 8192
    t = np.arange(fs * 4) / fs
    for name in ("h1.wav", "h2.wav", "h3.wav", "t.wav", "new.wav"):
        wavfile.write(tmp_path / name, fs, (box_s_take(rng, t) / 5.0).astype(np.float32))  # in g, 5 g full scale
    files = [("h1.wav", "history", ""), ("h2.wav", "history", ""), ("h3.wav", "history", ""), ("t.wav", "test", "")]
    box_s_detection(tmp_path, "fs", files, 'vibration = "0"\ngain = "5g"\n')
    code, out, err = cli("run", tmp_path / "d.toml", "--quick", "--out", tmp_path / "runs")
    assert code == 0, err[-1500:]
    (run,) = (tmp_path / "runs").glob("fs/*/")
    code, out, err = cli("inspect", tmp_path / "new.wav", "--gain", "5g", "--speed", "24.3 Hz", "--json")
    assert code == 0, err
    inspected = json.loads(out)["units"]
    assert inspected.endswith("5 g a file unit (the gain, a full scale)"), inspected
    code, out, err = cli("score", run, tmp_path / "new.wav", "--json")
    assert code == 0, err[-1500:]
    scored = json.dumps(json.loads(out), ensure_ascii=False)
    assert inspected in scored and "1 V /" not in scored, scored[-1500:]


def test_a_detection_run_warns_of_a_take_in_volts_given_as_millivolts(tmp_path, monkeypatch):
    # the warning a take in millivolts read as volts gets (test_outside_o), for the other way round: one history
    # take's entry says unit = "mV" of its volts. The run's reading of its takes (read_target, as detection.run calls
    # it) logs the warning; test_outside_o's run of the twin case follows such a warning into table.md, and a whole
    # `gearlab run --quick` here (its training and report) was 3-4 s of CPU more
    from gearlab.kinds.detection_records import read_target, unit_shaft
    from gearlab.notebook import load_scenario

    box_s(tmp_path)
    for name in ("h1.tsv", "h2.tsv", "v.tsv", "t.tsv"):
        _volts_take(tmp_path / name, seconds=4.0)
    files = [("h1.tsv", "history", ""), ("h2.tsv", "history", ""), ("v.tsv", "history", ', unit = "mV"')]
    target = 'vibration = 0\nfs = "8192 Hz"\nunit = "V"\nsensitivity = "100 mV/g"\n'
    box_s_detection(tmp_path, "v", [*files, ("t.tsv", "test", "")], target)
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    spec = load_scenario(tmp_path / "d.toml").spec
    events = []
    read_target(spec.target, spec.detection.blocks, events.append, shaft=unit_shaft(spec.source))
    said = "\n".join(e.message for e in events if e.kind == "log")
    assert "warning: v.tsv: RMS 0.000" in said and "too quiet for a gearbox: values in volts? unit = 'V'" in said
    assert "h1.tsv: RMS" not in said
