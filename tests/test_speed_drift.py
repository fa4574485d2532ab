"""A take whose speed drifts (wanders a few % and returns) is said to drift, not to run up: 'a drift of ±3.0 %'
where a run-up's words say 'a run-up' (a monotone change of speed over the take). A tacho-read take of a slow ±3 %
drift was said '19.4 Hz .. 20.6 Hz over the take: a run-up or coast-down?' by a run and `gearlab score`, and 'the
mean of a run-up or coast-down' by inspect. The shape is read off the speed track (signals.checks.speed_shape):
the net change between its ends against the way it travels."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.gearbox.speed import nominal_line
from gearlab.signals.checks import VARIES_WORDS, revolution_speeds, speed_shape, speed_varies, varies_span

FS = 2000.0
SECONDS = 20.0


def _angle(kind: str, phase: float = 0.3) -> np.ndarray:
    """The shaft angle (rad) of a 20 Hz take over SECONDS: a ±3 % drift of 1.5 slow cycles starting at *phase*,
    a run-up or a coast-down across the same 19.4 .. 20.6 Hz."""
    u = np.arange(int(SECONDS * FS)) / (SECONDS * FS)
    speed = {
        "drift": 20.0 * (1 + 0.03 * np.sin(2 * np.pi * 1.5 * u + phase)),
        "run-up": 20.0 * (1 + 0.03 * (2 * u - 1)),
        "coast-down": 20.0 * (1 - 0.03 * (2 * u - 1)),
    }[kind]
    return 2 * np.pi * np.cumsum(speed) / FS


@pytest.mark.parametrize("phase", [0.3, np.pi / 2, np.pi, -np.pi / 2])
def test_a_slow_drift_is_said_a_drift_of_its_size(phase):
    said = speed_varies(_angle("drift", phase), FS)
    assert VARIES_WORDS in said and "run-up" not in said and "coast-down" not in said, said
    assert "a drift of ±3.0 %" in said, said
    # what a run's warning and score's line say before 'scored on N of M revolutions at ..' (detection_in_band)
    assert varies_span(said) == f"{said[2:].split(' over')[0]} {VARIES_WORDS} a drift of ±3.0 %", said


@pytest.mark.parametrize("kind", ["run-up", "coast-down"])
def test_a_monotone_change_is_said_a_run_up_or_a_coast_down(kind):
    said = speed_varies(_angle(kind), FS)
    assert f"{VARIES_WORDS} a {kind}" in said and "drift" not in said and "?" not in said, said


def test_the_shape_reads_a_run_up_that_then_holds_steady_as_a_run_up():
    # a take starting with 1 s of run-up, then steady: its change lies at one end, monotone
    speeds = np.r_[np.linspace(15.0, 20.0, 20), np.full(400, 20.0)]
    assert speed_shape(speeds) == "a run-up"


@pytest.mark.parametrize(("kind", "words"), [("drift", "a drift of ±3.0 %"), ("run-up", "a run-up")])
def test_inspect_s_nominal_line_says_the_same_shape(kind, words):
    speeds = revolution_speeds(_angle(kind), FS)
    line = nominal_line(float(np.mean(speeds)), 20.0, "[operation] speed", speeds)
    assert f"the mean of {words} (19.4" in line and "not a steady speed" in line, line


def test_a_wander_through_a_stop_is_said_a_stop_not_a_drift():
    speeds = np.r_[np.full(60, 24.0), np.linspace(24.0, 0.8, 5), np.linspace(0.8, 24.0, 5), np.full(60, 24.0)]
    assert speed_shape(speeds, stops=True) == "a stop and a restart"
    assert speed_shape(speeds[:65], stops=True) == "a coast-down"  # to a stop at its end: monotone
