"""Which gear on a three-stage box (signals.localise, per-shaft TSAs): the later stages' meshes, at no
whole input order, scatter the input shaft's turns far more than they stay in its average. Read as the
noise of the input's mean they hid an input-pinion fault (outside round 9's R, 38/87 + 49/93 + 69/91 at
15 Hz: input z 1.7 against its threshold 2.8, nothing localised; inspect, detection and score alike).
The records are written here, not simulated by gearlab: each stage's mesh harmonics amplitude-modulated
at its shafts' orders, a damaged tooth lifting its mesh for about a pitch, white noise, a wobbling speed,
cut on a tacho of the input."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, mesh_train, stage

TEETH = ((37, 86), (47, 91), (67, 89))  # tooth counts no other test uses
FS, SPEED, SECONDS = 12_800.0, 15.0, 8.0


def revolutions(fault, seed, slip):
    """The take's input revolutions (the data.which_gear.Take): *fault* (stage, "pinion" | "wheel",
    tooth) or None."""
    from gearlab.data.which_gear import Take
    from gearlab.signals import cut_revolutions

    rng = np.random.default_rng(seed)
    t = np.arange(int(SECONDS * FS)) / FS
    f = SPEED * (1 - slip) * (1 + 0.002 * np.sin(2 * np.pi * 0.4 * t + seed))
    theta = 2 * np.pi * np.cumsum(f) / FS
    x = mesh_train(
        theta, TEETH, rng, fault, noise=0.25, level=4.0, bump=0.6, width=0.6, second=0.45, third=0.2, phase=0.7
    )
    cut = cut_revolutions(x, FS, tacho=np.angle(np.exp(1j * theta)), transient="none")
    return Take(cut.revolutions, 0, float(cut.speed_hz), FS)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    from gearlab.data import which_gear as W
    from gearlab.gearbox import order_table, resolve_gearbox

    path = tmp_path_factory.mktemp("three") / "three.toml"
    path.write_text(description(*(stage(*z) for z in TEETH), name="three", speed="15 Hz", near="input"))
    table = order_table(resolve_gearbox(str(path)))
    hist = W.history_of([revolutions(None, seed, slip) for seed, slip in ((1, 0.012), (2, 0.016), (3, 0.010))], table)
    assert hist.layout.mode == "shafts"
    return table, hist


def test_an_input_pinion_fault_behind_two_later_meshes_is_named(box):
    from gearlab.data import which_gear as W

    table, hist = box
    found = W.which_gear(revolutions((0, "pinion", 9), 5, 0.015), hist, table, None)
    ev = {s["shaft"]: s for s in found["shafts"]}
    assert found["named"] == "input pinion 37T (stage 1)", found["summary"]
    # the fault stands well clear of the threshold (before: input z 2.84 against 2.81, on the edge)
    assert ev["input"]["z"] > 3 * ev["input"]["threshold"], found["summary"]
    assert abs(ev["input"]["tooth"]["input pinion 37T (stage 1)"]["tooth"] - 9) <= 1, found["summary"]
    assert not any(s["flagged"] for s in found["shafts"] if s["shaft"] != "input"), found["summary"]


def test_a_healthy_take_of_the_three_stages_localises_nothing(box):
    from gearlab.data import which_gear as W

    table, hist = box
    found = W.which_gear(revolutions(None, 4, 0.014), hist, table, None)
    assert found["named"] is None, found["summary"]
