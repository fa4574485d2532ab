"""Outside user GT (issue 39): a one-stage 31/94 mixer reducer and a two-stage 21/62 + 35/88 fan drive, neither with a
tacho, recorded in m/s² (HDF5 datasets in a group with `fs` and `units` attributes; float and 24-bit WAV), made here
with numpy: each stage's mesh harmonics modulated by both its shafts (sidebands), each shaft's run-out, noise. What a
user types wrong: a speed in rpm written as Hz, a tooth count written as a decimal."""

from __future__ import annotations

BOX = (
    '[gearbox]\nname = "mill"\n[operation]\nspeed = "1470 rpm"\nload = "120 N*m"\n'
    '[[stages]]\nmodule = "2.5 mm"\nface_width = "25 mm"\n'
    'pinion = { z = 31, bore = "30 mm" }\nwheel = { z = 94, bore = "45 mm" }\n'
    '[sensor]\nnear = "output"\n'
)


def test_a_speed_in_rpm_written_as_hz_is_refused_with_the_rpm_it_likely_is(tmp_path, cli):
    # '1470 Hz' (the motor's plate says 1470 rpm) read 'expected an input-shaft speed up to 1 kHz, e.g. '25 Hz', got
    # 1470': the unit the user wrote dropped, no word that 1470 rpm is 24.5 Hz
    (tmp_path / "box.toml").write_text(BOX.replace('"1470 rpm"', '"1470 Hz"'))
    code, out, err = cli("validate", tmp_path / "box.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "box.toml: [operation] key 'speed'" in line, err
    assert "'1470 Hz'" in line and "'1470 rpm'" in line and "24.5 Hz" in line, line


def test_a_tooth_count_written_as_a_decimal_says_how_to_write_it(tmp_path, cli):
    # 'z = 31.0' read 'expected a whole number, got 31.0': 31.0 is a whole number to its writer
    (tmp_path / "box.toml").write_text(BOX.replace("z = 31,", "z = 31.0,"))
    code, out, err = cli("validate", tmp_path / "box.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "[[stages]] #1.pinion key 'z'" in line, err
    assert "z = 31" in line and "31.0" in line, line


def test_a_unit_key_in_capitals_names_the_symbol_it_is_not(cli, tmp_path):
    # '--unit G' (as a DAQ's channel list writes it) read "'G' is not one of m/s^2, m/s², g, V, mV, nor another
    # acceleration or voltage unit (e.g. 'mg', 'mm/s²')", no 'did you mean', though 'gs' and "g's" got one
    import numpy as np
    from scipy.io import wavfile

    wavfile.write(tmp_path / "take.wav", 8192, np.zeros(8192, np.float32))
    code, out, err = cli("inspect", tmp_path / "take.wav", "--speed", "25 Hz", "--unit", "G")
    line = err.strip()
    assert code == 2 and "\n" not in line and "--unit: 'G' is not one of" in line, err
    assert "did you mean 'g'?" in line, line


def test_a_two_channel_wav_with_no_channel_named_asks_for_its_index(cli, tmp_path):
    # a stereo WAV of two accelerometers read "which channel is the vibration? the file has 0, 1; expected
    # --vibration NAME": a WAV's channels have no names, only their 0-based index (as validate says it)
    import numpy as np
    from scipy.io import wavfile

    wavfile.write(tmp_path / "two.wav", 8192, np.zeros((8192, 2), np.float32))
    code, out, err = cli("inspect", tmp_path / "two.wav", "--speed", "25 Hz")
    line = err.strip()
    assert code == 2 and "\n" not in line and "the file has 0, 1" in line, err
    assert "--vibration INDEX (0-based: 0, 1)" in line, line
