"""A tacho read on the wrong shaft or with the wrong marks per turn (issue 39, an outside user's 19/47 +
29/71 reducer): every order then reads f times its own, and inspect said so, but the rows read at that
speed came after it as further differences: 'a 115-tooth pinion on the input shaft? described 19' beside
'the tacho reads the output shaft?', 'the wheel on the output shaft shows 98.0 teeth' beside 'the tacho
gives 2 pulse(s) per revolution, not 1?'. The tacho's line is now the only one: the rest follows from it. Both
together (its 1-mark output tacho read as the input's 2) read every order 12.11 x its own: 'a 230-tooth pinion on
the input shaft?'; now the shaft and the marks."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.gearbox import load_gearbox
from gearlab.inspect import InspectOptions, inspect_record

STAGES = ((19, 47), (29, 71))


def _record(path, tacho_shaft: int, marks: int, speed=40.0, fs=12800.0, seconds=6.0, seed=3):
    """A 19/47 + 29/71 reducer's housing acceleration (m/s²): each stage's first three mesh harmonics,
    amplitude- and phase-modulated at its two shafts' orders (the sidebands that tell the shafts), the
    input drifting 1.5 %, noise; and a square-wave tacho of *marks* per turn of shaft *tacho_shaft*.
    The path, and the input's mean speed (Hz)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    f = speed * (1 + 0.015 * np.sin(2 * np.pi * t / (2.3 * seconds)))
    angles = [2 * np.pi * np.cumsum(f) / fs]
    for z1, z2 in STAGES:
        angles.append(angles[-1] * z1 / z2)
    acc = rng.normal(0, 0.2, t.size)
    for k, (z1, _) in enumerate(STAGES):
        am = 1 + 0.15 * np.cos(angles[k]) + 0.1 * np.cos(angles[k + 1])
        pm = 0.2 * np.cos(angles[k]) + 0.1 * np.sin(angles[k + 1])
        for h, a in ((1, 2.0), (2, 0.8), (3, 0.35)):
            acc += a * am * np.cos(h * (z1 * angles[k] + pm) + rng.uniform(0, 2 * np.pi))
    tacho = np.where(np.mod(marks * angles[tacho_shaft], 2 * np.pi) < np.pi, 5.0, 0.0)
    np.savez(path, acc_ms2=acc, tach=tacho, fs=fs)
    return path, float(f.mean())


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    path = tmp_path_factory.mktemp("box") / "reducer.toml"
    text = description(stage(*STAGES[0]), stage(*STAGES[1], module="3 mm"), name="reducer", speed="2400 rpm")
    path.write_text(text + '[sensor]\ntacho = "input"\n')
    return load_gearbox(path)


@pytest.mark.parametrize(
    ("tacho_shaft", "marks", "wrong", "right", "said", "not_said"),
    [
        # an output tacho read as the input's: not also 'a 115-tooth pinion on the input shaft?'
        (
            2,
            1,
            {},
            {"tacho_shaft": "output"},
            "the tacho reads the output shaft? --tacho-shaft output",
            "-tooth pinion",
        ),
        # a 2-mark tacho read as 1: not also 'the wheel on the output shaft shows 98.0 teeth'
        (
            0,
            2,
            {"pulses_per_rev": 1},
            {"pulses_per_rev": 2},
            "the tacho gives 2 pulse(s) per revolution, not 1?",
            "teeth (mesh order",
        ),
    ],
    ids=["shaft", "marks"],
)
def test_a_tacho_misread_one_way_is_told_alone(tmp_path, box, tacho_shaft, marks, wrong, right, said, not_said):
    rec, mean_hz = _record(tmp_path / "take.npz", tacho_shaft=tacho_shaft, marks=marks)
    report = inspect_record(str(rec), box, InspectOptions("acc_ms2", "tach", **wrong))
    assert report["matches"] is False
    assert report["check"]["differences"] == [report["verdict"].split("differs: ", 1)[1]], report["verdict"]
    assert said in report["verdict"] and not_said not in report["verdict"], report["verdict"]
    read = inspect_record(str(rec), box, InspectOptions("acc_ms2", "tach", **right))
    assert read["matches"], read["verdict"]
    assert read["speed"]["mean_hz"] == pytest.approx(mean_hz, rel=0.005)


def test_an_output_tacho_of_one_mark_read_as_the_input_s_two_is_told_both(tmp_path, box):
    rec, mean_hz = _record(tmp_path / "out.npz", tacho_shaft=2, marks=1)
    report = inspect_record(str(rec), box, InspectOptions("acc_ms2", "tach", pulses_per_rev=2))
    assert report["matches"] is False
    said = "with 1 pulse(s) per revolution, not 2? (--tacho-shaft output --pulses-per-rev 1"
    assert said in report["verdict"] and ";" not in report["verdict"], report["verdict"]
    assert "every order reads 12.11 x its own" in report["verdict"], report["verdict"]
    right = inspect_record(str(rec), box, InspectOptions("acc_ms2", "tach", pulses_per_rev=1, tacho_shaft="output"))
    assert right["matches"], right["verdict"]
    assert right["speed"]["mean_hz"] == pytest.approx(mean_hz, rel=0.005)
