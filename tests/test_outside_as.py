"""A later stage's described mesh read on a weak line whose real mesh, one count off, stands far stronger beside it
on the described mesh's own sidebands (issue 39, the lead's fresh boxes 64 and 67; gearlab.gearbox.outshone).
38/69 + 22/51 at 24.89 Hz described with a 23-tooth stage-2 pinion puts stage 2 at 12.667, the real 12.116's first
upper sideband (the intermediate shaft, 0.5507): the real mesh's harmonics 1-3 sit on the described one's sidebands
-1, -2, -3, and the described 3rd harmonic on stage 1's mesh (38), so inspect said 'matches'. 32/66 + 26/62 at
31.75 Hz described with a 65-tooth first wheel: stage 2 at 12.8, no line there, while the real 12.606 (its 2nd and
3rd harmonics 65 dB over the floor) fell within the tolerance of the output shaft's sidebands 1-3 of 12.8."""

from __future__ import annotations

import numpy as np
import pytest
from test_outside_ao import FS, inspected, text

SECONDS = 2.0
BOXES = {"f64": (((38, 69), (22, 51)), 24.892), "f67": (((32, 66), (26, 62)), 31.753)}


def wrong(name: str):
    (a, b), (c, d) = BOXES[name][0]
    return ((a, b), (c + 1, d)) if name == "f64" else ((a, b - 1), (c, d))


@pytest.fixture(scope="module", params=sorted(BOXES))
def take(request, tmp_path_factory):
    """The box simulated at 200 kHz, 0.2 s settled, resampled to 25.6 kHz, 30 dB noise (test_outside_ao's)."""
    from scipy.signal import resample_poly

    import gearlab

    teeth, speed = BOXES[request.param]
    where = tmp_path_factory.mktemp("as")
    (where / "true.toml").write_text(text(teeth, speed))
    sim = gearlab.simulate_signals(gearbox=where / "true.toml", duration=SECONDS + 0.25, fs=200e3, speed=speed)
    acc = resample_poly(sim.channels["casing_x"][sim.t >= 0.2], 16, 125)[: int(SECONDS * FS)]
    acc = acc + np.random.default_rng(5184).standard_normal(acc.size) * acc.std() * 10 ** (-30 / 20)
    return request.param, where, acc


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_the_true_description_matches(take, kind):
    name, where, acc = take
    teeth, speed = BOXES[name]
    report = inspected(where, acc, speed, teeth, kind)
    assert report["matches"] is True, report["verdict"]
    assert not any("outshone" in s for s in report["check"]["stages"]), report["check"]["stages"]


def test_a_count_whose_real_mesh_stands_on_the_described_sidebands_is_called_out(take):
    name, where, acc = take
    (a, b), (c, d) = BOXES[name][0]
    report = inspected(where, acc, BOXES[name][1], wrong(name), "ttl")
    assert report["matches"] is False, report["verdict"]
    stage2 = report["check"]["stages"][1]
    assert abs(stage2["outshone"]["order"] - c * a / b) < 0.01 and stage2["outshone"]["db"] > 15, stage2
    gear, described = (f"a {c}-tooth pinion", c + 1) if name == "f64" else (f"a {b}-tooth wheel", b - 1)
    said = f"that is the mesh: {gear} on the intermediate shaft puts it there, {described} described"
    assert said in report["verdict"], report["verdict"]


def test_the_gap_structure_line_says_it_too(take):
    from gearboxes import described_pair

    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line
    from gearlab.signals import angle_from_pulses, resample_revolutions

    name, where, acc = take
    (a, b), (c, d) = BOXES[name][0]
    speed = BOXES[name][1]
    theta = 2 * np.pi * speed * (0.2 + np.arange(acc.size) / FS) + 3.7
    tacho = np.where(np.mod(theta, 2 * np.pi) < 0.2 * np.pi, 5.0, 0.0)
    rows = resample_revolutions(acc, angle_from_pulses(tacho, FS), points=1024)
    chain = Chain(fs=FS, speed=speed, tacho_shaft="input")
    assert structure_line(rows, described_pair(*BOXES[name][0]), 400, chain, None, {}) is None
    line = structure_line(rows, described_pair(*wrong(name)), 400, chain, None, {})
    assert line is not None and f"stand at {c * a / b:.4g}" in line, line
