"""Issue 39: without a tacho, a motor's speed swinging at about 1 Hz smears each mesh over FM sidebands 1 Hz
apart, which a comb at a fifth of the speed explains as well as the true one. Both speeds, their mesh phase
followed, read themselves again; the true one's phase gathers the mesh into its line (gearbox.speed.gathered)."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.gearbox.description import load_gearbox
from gearlab.inspect import InspectOptions, inspect_record

FS = 25600.0
SPEED = 41.70  # Hz, the input shaft's mean
COUNTS = ((39, 110), (38, 101))

BOX = """[gearbox]
name = "swing"

[[stages]]
module = "2.5 mm"
face_width = "25 mm"
pinion = {{ z = {0}, bore = "41 mm" }}
wheel = {{ z = {1}, bore = "81 mm" }}

[[stages]]
module = "3 mm"
face_width = "27 mm"
pinion = {{ z = {2}, bore = "48 mm" }}
wheel = {{ z = {3}, bore = "89 mm" }}

[sensor]
near = "input"
direction = "x"
"""


def _record(path, swing: float, rate: float) -> None:
    """benchmarks/your_gearbox.py's synthetic maker, fixed: each mesh's harmonics 1-4, amplitude-modulated by
    both its shafts, the later mesh 1.4 times the first's; shaft lines; noise 26 dB under; no tacho. The input's
    speed swings by *swing* of its mean at *rate* Hz (a motor's)."""
    rng = np.random.default_rng(1725)
    n = int(6.86 * FS)
    t = np.arange(n) / FS
    theta = 2 * np.pi * SPEED * t + swing * SPEED / rate * (1 - np.cos(2 * np.pi * rate * t))
    x, o, orders = np.zeros(n), 1.0, [1.0]
    for level, (z1, z2) in zip((1.0, 1.4), COUNTS):
        mod = 1 + 0.2 * np.cos(o * theta + 1.0) + 0.15 * np.cos(o * z1 / z2 * theta + 2.0)
        for h in range(1, 5):
            x += level / h * mod * np.cos(h * o * z1 * theta + rng.uniform(0, 6))
        o *= z1 / z2
        orders.append(o)
    for q in orders:
        x += 0.1 * np.cos(q * theta + rng.uniform(0, 6))
    x += rng.standard_normal(n) * np.std(x) * 10 ** (-26 / 20)
    np.savez(path, acc=x, fs=FS)


@pytest.mark.parametrize("swing, rate", [(0.003, 0.95), (0.0, 0.5)])
def test_a_swinging_speed_is_found_at_its_mean_not_refused_as_ambiguous(tmp_path, swing, rate):
    (tmp_path / "box.toml").write_text(BOX.format(*COUNTS[0], *COUNTS[1]))
    _record(tmp_path / "rec.npz", swing, rate)
    report = inspect_record(tmp_path / "rec.npz", load_gearbox(tmp_path / "box.toml"), InspectOptions(vibration="acc"))
    assert report["speed"]["mean_hz"] == pytest.approx(SPEED, rel=0.005), report["speed"]
    assert report["matches"] is True, report
