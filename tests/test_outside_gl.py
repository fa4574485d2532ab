"""An outside user's look (issue 39, "How it will be checked"): a three-stage 22/71 + 27/86 + 34/107 reducer at
60 Hz, the accelerometer (100 mV/g) on the output bearing and an encoder of 60 pulses a turn on the output shaft,
recorded by a DAQ as MATLAB files (`Channel_1_Data` in volts, `Channel_3_Data` the encoder, `Sample_Rate`). The
recordings are made here, small, by plain numpy (mesh harmonics with sidebands, no gearlab simulator)."""

from __future__ import annotations

import numpy as np
import scipy.io
from gearboxes import description, stage

FS, F_IN, G = 10000.0, 60.0, 9.80665
Z = ((22, 71), (27, 86), (34, 107))
BOX = description(
    stage(22, 71, module="2 mm", width="20 mm", bores=("25 mm", "40 mm")),
    stage(27, 86, module="3 mm", width="30 mm", bores=("40 mm", "55 mm")),
    stage(34, 107, module="4 mm", width="40 mm", bores=("55 mm", "80 mm")),
    name="box3",
    speed="3600 rpm",
    load="800 N*m",
    near="output",
    tacho="output",
    marks=60,
)
DAQ = ("--vibration", "Channel_1_Data", "--tacho", "Channel_3_Data", "--sensitivity", "100 mV/g")


def _take(path, seconds=4.0, seed=1, gain=1.0):
    """A .mat take: each stage's mesh (3 harmonics, both shafts' sidebands, the last stage strongest at the sensor),
    noise, in volts at 100 mV/g (x *gain*), and the 60-mark encoder on the output shaft as a 0/5 V square wave."""
    rng = np.random.default_rng(seed)
    n = int(FS * seconds)
    th_in = 2 * np.pi * F_IN * np.arange(n) / FS + rng.uniform(0, 2 * np.pi)
    turns = np.cumprod([1.0] + [zp / zw for zp, zw in Z])
    th = [th_in * k for k in turns]
    a = sum(0.2 * np.cos(th[k] + k) for k in range(4))  # each shaft's run-out
    for s, (zp, _) in enumerate(Z):
        am = 1 + 0.08 * np.cos(th[s]) + 0.06 * np.cos(th[s + 1] + 1.1)
        a = a + sum((0.75 + 0.75 * s) * ah * am * np.cos(h * zp * th[s] + s) for h, ah in ((1, 1), (2, 0.45), (3, 0.2)))
    a = a + rng.normal(0, 0.3, n)
    tacho = np.where(np.sin(60 * th[3]) > 0, 5.0, 0.0)
    data = {"Channel_1_Data": (a / G * 0.1 * gain)[:, None], "Channel_3_Data": tacho[:, None]}
    scipy.io.savemat(path, data | {"Sample_Rate": np.array([[FS]])})
    return path


def _inspect(cli, tmp_path, take, *extra):
    (tmp_path / "box3.toml").write_text(BOX)
    return cli("inspect", take, "--gearbox", tmp_path / "box3.toml", *DAQ, *extra)


def test_an_encoder_read_with_a_tenth_of_its_marks_is_named(cli, tmp_path):
    """The encoder's 60 marks a turn typed as 6: every order reads a tenth of its own (mesh 2.2 for 22) and the
    speed 10 x the described. inspect said only 'stage 1: no line at mesh order 22 (a 22-tooth pinion)' for every
    stage, as if the gears differed; it tried counts of marks up to 8 alone."""
    code, out, err = _inspect(cli, tmp_path, _take(tmp_path / "t.mat"), "--pulses-per-rev", "6")
    assert code == 0, err
    assert "the tacho gives 60 pulse(s) per revolution, not 6?" in out, out[-3000:]
    assert "no line at mesh order 22" not in out


def test_a_face_width_in_inches_by_mistake_is_refused(cli, tmp_path):
    """'30 in' typed for the 30 mm face of stage 2 (762 mm on a 27-tooth pinion of 81 mm): validate said OK, and the
    simulator would have meshed a 25 x stiffer stage. Refused in one line naming the stage, key and what is
    expected; a face of 1.2 in (30.5 mm) is a face width, accepted."""
    path = tmp_path / "box3.toml"
    path.write_text(BOX.replace('face_width = "30 mm"', 'face_width = "30 in"'))
    code, out, err = cli("validate", path)
    assert code == 2, out
    assert err.count("\n") == 1 and "[[stages]] #2 key 'face_width': 762 mm" in err, err
    assert "81 mm" in err and "expected" in err
    path.write_text(BOX.replace('face_width = "30 mm"', 'face_width = "1.2 in"'))
    code, out, err = cli("validate", path)
    assert code == 0, err


def test_a_history_read_by_a_60_mark_output_encoder_is_aligned_at_any_of_its_605880_marks(tmp_path):
    """An input angle read off this box's 60-mark output encoder is known to 1/605880 of a turn (TachoShaft.marks):
    a detection run's structure check aligned each history take to the first by trying every mark in a Python loop
    (data.textzip.align_to), minutes a take before any simulation. Every mark is tried at once now; the mark found
    is the one the take was turned by."""
    from gearlab.data.textzip import align_to
    from gearlab.gearbox import load_gearbox
    from gearlab.gearbox.orders import TachoShaft

    (tmp_path / "box3.toml").write_text(BOX)
    marks = TachoShaft.of(load_gearbox(tmp_path / "box3.toml"), "output", "[sensor]").marks(60)
    assert marks == 605880
    rng = np.random.default_rng(3)
    spectrum = np.fft.rfft(rng.normal(size=1024))
    spectrum[-1] = 0.0  # band-limited: a shift of a fraction of a point is exact
    reference, k = np.fft.irfft(spectrum, n=1024), np.arange(513)
    for m0 in (0, 1, 302940, 605879, 123457):
        late = np.fft.irfft(np.fft.rfft(reference) * np.exp(-2j * np.pi * k * m0 / marks), n=1024)
        m, turned = align_to(reference, np.stack([late, late]), marks)
        assert m == m0
        assert np.allclose(turned, reference, atol=1e-9)


def test_a_gap_run_whose_encoder_marks_are_typed_a_factor_off_names_pulses_per_rev_not_fs(cli, tmp_path):
    """[target] pulses_per_rev = 6 for the 60-mark encoder: the gap run read the shaft at 600 Hz and stopped with
    "[target] key 'fs': sampling rate too low for the mesh harmonics", sending the user to the sampling rate. The
    speed read 10 x the described names the marks."""
    _take(tmp_path / "h1.mat", seconds=2.0)
    (tmp_path / "box3.toml").write_text(BOX)
    files = '[{ file = "h1.mat", role = "history", label = "healthy" }]'
    (tmp_path / "gap.toml").write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "box3.toml"\n[target]\n'
        'vibration = "Channel_1_Data"\ntacho = "Channel_3_Data"\nsensitivity = "100 mV/g"\npulses_per_rev = 6\n'
        f"files = {files}\n[accuracy]\nenabled = false\n"
    )
    code, out, err = cli("run", tmp_path / "gap.toml", "--quick")
    assert code == 2, out[-2000:]
    line = err.strip().splitlines()[-1]
    assert "[target] key 'pulses_per_rev'" in line and "60 pulse(s) per revolution, not 6?" in line, line
    assert "key 'fs'" not in line
