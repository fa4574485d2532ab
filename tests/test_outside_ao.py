"""A later stage's described mesh that is a subharmonic of an earlier mesh must not match on that mesh's lines
(issue 39, AM's fresh boxes). 36/84 + 27/69 at 35.16 Hz described with a 28-tooth stage-2 pinion puts stage 2 at
12.000 = 36 / 3: no line at 12 or 24, but 36, 72, 108 (stage 1's) are its 3rd, 6th, 9th harmonics, and inspect said
'matches' while the true mesh 11.571 and its harmonics stood 58-66 dB over the floor. 22/70 + 18/68 at 41.29 Hz
described with a 69-tooth first wheel: stage 2 at 5.739, whose 23rd harmonic is stage 1's 6th (132), its only
line: 'matches'."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage

FS, SECONDS = 25_600.0, 4.0
BOXES = {"am8": (((36, 84), (27, 69)), 35.158), "am9": (((22, 70), (18, 68)), 41.295)}


def text(teeth, speed: float) -> str:
    mods = (("2 mm", "20 mm", ("20 mm", "25 mm")), ("3 mm", "25 mm", ("30 mm", "40 mm")))
    stages = [stage(z1, z2, module=m, width=w, bores=b) for (z1, z2), (m, w, b) in zip(teeth, mods)]
    return description(*stages, name="ao", speed=f"{speed:.3f} Hz", load="30 N*m", near="input", tacho="input")


@pytest.fixture(scope="module", params=sorted(BOXES))
def take(request, tmp_path_factory):
    """The box simulated at 200 kHz, 0.2 s settled, resampled to 25.6 kHz, 30 dB noise (AM's generator)."""
    teeth, speed = BOXES[request.param]
    where = tmp_path_factory.mktemp("ao")
    return request.param, where, simulated_take(where, teeth, speed, seed=39)


def simulated_take(where, teeth, speed: float, seed: int, seconds: float = SECONDS) -> np.ndarray:
    """*teeth* at *speed* described in where/true.toml and simulated from it at 200 kHz, *seconds* after
    0.2 s settled, resampled to 25.6 kHz, 30 dB of noise (AM's generator; test_outside_aq/as take theirs here too)."""
    from scipy.signal import resample_poly

    import gearlab

    (where / "true.toml").write_text(text(teeth, speed))
    sim = gearlab.simulate_signals(gearbox=where / "true.toml", duration=seconds + 0.25, fs=200e3, speed=speed)
    acc = resample_poly(sim.channels["casing_x"][sim.t >= 0.2], 16, 125)[: int(seconds * FS)]
    return acc + np.random.default_rng(seed).standard_normal(acc.size) * acc.std() * 10 ** (-30 / 20)


def true_description_matches(take, boxes: dict, kind: str) -> None:
    """The take's own description matches, no later mesh read as outshone (test_outside_aq/as's boxes)."""
    name, where, acc = take
    teeth, speed = boxes[name]
    report = inspected(where, acc, speed, teeth, kind)
    assert report["matches"] is True, report["verdict"]
    assert not any("outshone" in s for s in report["check"]["stages"]), report["check"]["stages"]


def inspected(where, acc, speed: float, teeth, kind: str) -> dict:
    import gearlab

    (where / "gb.toml").write_text(text(teeth, speed))
    theta = 2 * np.pi * speed * (0.2 + np.arange(acc.size) / FS) + 3.7
    tacho = np.where(np.mod(theta, 2 * np.pi) < 0.2 * np.pi, 5.0, 0.0) if kind == "ttl" else 2.5 - 2.5 * np.cos(theta)
    np.savez(where / "take.npz", acc=acc, tacho=tacho, fs=FS)
    take = where / "take.npz"
    return gearlab.inspect_recording(take, where / "gb.toml", vibration="acc", tacho="tacho", unit="m/s^2")


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_the_true_description_still_matches(take, kind):
    name, where, acc = take
    teeth, speed = BOXES[name]
    report = inspected(where, acc, speed, teeth, kind)
    assert report["matches"] is True, report["verdict"]


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_a_subharmonic_of_the_first_mesh_is_no_match(take, kind):
    name, where, acc = take
    (a, b), (c, d) = BOXES[name][0]
    wrong = ((a, b), (c + 1, d)) if name == "am8" else ((a, b - 1), (c, d))
    report = inspected(where, acc, BOXES[name][1], wrong, kind)
    assert report["matches"] is False, report["verdict"]
    stage2 = report["check"]["stages"][1]
    # stage 2 read at its true mesh, not on stage 1's lines
    assert abs(stage2["measured_order"] - c * a / b) < 0.01, stage2


@pytest.mark.parametrize("first_wheel", [66, 65])
def test_the_gap_calls_a_missing_later_mesh_the_source_holds_strong(tmp_path, first_wheel):
    """29/66 + 22/95 at 37.81 Hz described with a 65-tooth first wheel: the target shows no line at the described
    stage-2 mesh 9.815 (it sits at 9.667), where the source's would stand 75 dB over the floor; the gap skipped it."""
    from gearboxes import described_pair
    from scipy.signal import resample_poly

    import gearlab
    from gearlab.gap.structure import later_stages
    from gearlab.signals import resample_revolutions

    speed, true, described = 37.813, ((29, 66), (22, 95)), ((29, first_wheel), (22, 95))

    def rows(teeth, target: bool) -> np.ndarray:
        (tmp_path / "s.toml").write_text(text(teeth, speed))
        sim = gearlab.simulate_signals(gearbox=tmp_path / "s.toml", duration=SECONDS + 0.25, fs=200e3, speed=speed)
        acc = resample_poly(sim.channels["casing_x"][sim.t >= 0.2], 16, 125)[: int(SECONDS * FS)]
        acc = acc + target * np.random.default_rng(39).standard_normal(acc.size) * acc.std() * 10 ** (-30 / 20)
        return resample_revolutions(acc, 2 * np.pi * speed * np.arange(acc.size) / FS, points=1024)

    got = later_stages(rows(true, True), rows(described, False), described_pair(*described), 400)
    if first_wheel == 66:
        assert got["line"] is None, got
    else:  # no line at 9.815: the mesh is looked for where the wheel a tooth or three off puts it (test_outside_ax)
        assert got["line"] and got["line"].startswith("stage 2: mesh order 9.667 measured, 9.815 expected"), got
        assert "a 66-tooth wheel on the intermediate shaft (66.00) puts it there, 65 said" in got["line"], got
