"""Gearboxes and recordings made outside the project, run as a user would (issue 39, "How it will be
checked"): the findings of such a run, each fixed and kept fixed here on small generated inputs."""

import numpy as np
from gearboxes import described_pair

from gearlab.gap.structure import later_stages


def _train(stages, theta: np.ndarray, rng) -> np.ndarray:
    """A train of *stages* ((z1, z2), ...) at shaft angle *theta*: each mesh's harmonics 1-3, a later
    stage at 0.3 of the one before, amplitude-modulated by both of its shafts, white noise."""
    x, o = np.zeros(theta.size), 1.0
    for k, (z1, z2) in enumerate(stages):
        mod = 1 + 0.2 * np.cos(o * theta) + 0.1 * np.cos(o * z1 / z2 * theta + 1.0)
        for h in (1, 2, 3):
            x += 0.3**k / h * mod * np.cos(h * o * z1 * theta + 0.7 * h + k)
        o *= z1 / z2
    return x + rng.normal(0, 0.05, x.size)


def test_a_later_mesh_of_no_whole_order_is_read_against_the_description():
    # A 17/59 + 26/83 fan reducer (mesh 2 at 17 x 26/59 = 7.4915 orders) written as an int16 WAV
    # without a tacho: the gap diagnosis of its right description ended 'structure differs: stage 2:
    # mesh order 7.492 measured, 7.492 expected', because the source's revolutions (one steady
    # period each, the later mesh at one phase) laid end to end read stage 2 at 2.64.
    points, rng = 4096, np.random.default_rng(0)
    theta = 2 * np.pi * np.arange(60 * points) / points
    record = _train([(17, 59), (26, 83)], theta, rng).reshape(60, points)
    one = _train([(17, 59), (26, 83)], theta[:points], rng)
    source = np.tile(one, (20, 1)) + rng.normal(0, 0.05, (20, points))
    right = later_stages(record, source, described_pair((17, 59), (26, 83)))
    assert right["line"] is None
    assert abs(right["stages"][0]["target"] - 17 * 26 / 59) < 0.01
    # a 24-tooth second pinion described (mesh 2 at 6.915) is still called out, naming stage 2
    wrong = later_stages(record, source, described_pair((17, 59), (24, 83)))
    assert wrong["line"].startswith(
        "stage 2: mesh order 7.492 measured, 6.915 expected: the source simulates a 24-tooth pinion"
    )
