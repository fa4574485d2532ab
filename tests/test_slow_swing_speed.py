"""Issue 39: a slow conveyor reducer (45/119 + 28/123 at 0.7425 Hz, no tacho) whose speed swings 0.2 % at
0.05 Hz, below its output shaft's 0.064 Hz. Its mesh phase followed at the speed keeps the swing (the low-pass
sits under the slowest shaft's rate); followed at twice the speed, in a band twice as wide, it loses it, and the
lines read at that angle fit 0.7425 Hz. A run's reader (cut_recording) cut the take at 1.485 Hz, its source empty,
where `gearlab inspect` read 0.7425 Hz: both read the speed the lines fit."""

from __future__ import annotations

import numpy as np

from gearlab.data.recordings import cut_recording
from gearlab.gearbox.description import load_gearbox
from gearlab.inspect import InspectOptions, inspect_record

FS = 1024.0
SPEED = 0.7425  # Hz, the input shaft's mean (45 rpm described: 1 % under)
COUNTS = ((45, 119), (28, 123))

BOX = """[gearbox]
name = "conveyor"

[operation]
speed = "45 rpm"

[[stages]]
module = "4 mm"
face_width = "60 mm"
pinion = { z = 45, bore = "50 mm" }
wheel = { z = 119, bore = "90 mm" }

[[stages]]
module = "8 mm"
face_width = "100 mm"
pinion = { z = 28, bore = "90 mm" }
wheel = { z = 123, bore = "160 mm" }

[sensor]
near = "intermediate"
direction = "radial"
"""


def _take(path) -> None:
    """100 s: each mesh's harmonics 1-3, amplitude-modulated by both its shafts; each pinion shaft's
    lines 1 and 2; noise 24 dB under;
    the input's speed swinging 0.2 % at 0.05 Hz."""
    rng = np.random.default_rng(39)
    t = np.arange(int(100 * FS)) / FS
    swing, rate = 0.002, 0.05
    theta = 2 * np.pi * SPEED * t + swing * SPEED / rate * (1 - np.cos(2 * np.pi * rate * t))
    x, o = np.zeros(t.size), 1.0
    for level, (z1, z2) in zip((1.0, 0.7), COUNTS):
        mod = 1 + 0.05 * np.cos(o * theta + 1.0) + 0.04 * np.cos(o * z1 / z2 * theta + 2.0)
        for h, a in ((1, 1.0), (2, 0.45), (3, 0.18)):
            x += level * a * mod * np.cos(h * o * z1 * theta + rng.uniform(0, 6))
        for h in (1, 2):
            x += 0.1 * np.cos(h * o * theta + rng.uniform(0, 6))
        o *= z1 / z2
    x += rng.standard_normal(t.size) * np.std(x) * 10 ** (-24 / 20)
    np.savez(path, acc=x.astype(np.float32), fs=FS, unit="m/s^2")


def test_a_slow_swinging_take_is_cut_at_the_speed_inspect_reads(tmp_path):
    (tmp_path / "conveyor.toml").write_text(BOX)
    box = load_gearbox(tmp_path / "conveyor.toml")
    _take(tmp_path / "take.npz")
    cut = cut_recording(tmp_path / "take.npz", vibration="acc", gearbox=box)
    assert abs(cut.speed_hz / SPEED - 1) < 0.002, cut.angle_source
    assert "from the mesh lines" in cut.angle_source and "(;" not in cut.angle_source
    seen = inspect_record(str(tmp_path / "take.npz"), box, InspectOptions("acc"))["speed"]
    assert abs(seen["mean_hz"] / cut.speed_hz - 1) < 0.002
