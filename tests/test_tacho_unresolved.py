"""A tacho whose pulses the sampling cannot resolve is named so in one line (signals.angle._unresolved): a train at
or over half the sampling rate reads folded down (a 120-mark wheel at 25 Hz, 3 kHz at 5 kHz, was read as 16.7 Hz,
'another operating point', unsaid), and pulses narrower than a sample are seen one in five (read as missed marks or
a wheel with a gap); a once-a-turn pulse one sample wide, every one seen, and 60 marks at 3.3 samples a pulse read."""

from __future__ import annotations

import numpy as np
import pytest

FS, SECONDS = 5000.0, 4.0
T = np.arange(int(FS * SECONDS)) / FS


def _take(tmp_path, speed: float, marks: int, width_s: float | None):
    theta = 2 * np.pi * speed * T
    acc = np.sin(16 * theta) + 0.3 * np.sin(32 * theta) + 0.1 * np.random.default_rng(7).standard_normal(T.size)
    phase = (marks * speed * T) % 1.0
    tacho = phase < (0.5 if width_s is None else width_s * marks * speed)
    path = tmp_path / "take.npz"
    np.savez(path, acc=acc, tacho=tacho.astype(float), fs=FS)
    return path


CASES = [  # (speed Hz, marks a turn, pulse width s (None: half a pulse), words of the refusal or None)
    (25.0, 120, None, "pulses come every 2.5 samples (2 kHz) with a level one sample long: pulses at or over half"),
    (24.3, 1, 0.04e-3, "pulses last a sample or less and 79% of them fall between samples, unseen: pulses narrower"),
    (24.3, 1, 0.3e-3, None),  # 1.5 samples wide: every pulse seen
    (25.0, 60, None, None),  # 3.3 samples a pulse: read
]


@pytest.mark.parametrize(("speed", "marks", "width", "said"), CASES, ids=["aliased", "narrow", "one wide", "60"])
def test_a_tacho_faster_than_its_sampling_is_named_so(tmp_path, cli, speed, marks, width, said):
    path = _take(tmp_path, speed, marks, width)
    given = ["inspect", path, "--gearbox", "luo2019", "--vibration", "acc", "--tacho", "tacho"]
    code, out, err = cli(*given, "--pulses-per-rev", str(marks))
    if said is None:
        assert code == 0 and f"speed {speed:g} Hz" in out, (out, err)
        return
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, (out, err)
    assert f"tacho 'tacho' (read as {marks} pulse(s) per revolution): pulse train: " in line and said in line, line
