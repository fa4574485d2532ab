"""Detection on a user's own gearbox (issue 39, outside round 11): the simulations a two-stage box's
watched gear costs, and the units of a slower shaft free of the input shaft's own content."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from gearboxes import description, stage

from gearlab.engine import load_scenario
from gearlab.kinds.common import class_sizes
from gearlab.kinds.detection_records import UnitShaft


def _user_box(tmp_path, source_extra: str = "", stages=((23, 37), (29, 43)), watched=""):
    """A detection scenario on a described box without a tacho (speed from the description), its
    watched gear the last stage's pinion, on two small CSV records the test writes."""
    box = description(*(stage(z1, z2) for z1, z2 in stages), name="u", speed="900 rpm", load="50 N*m")
    (tmp_path / "u.toml").write_text(box)
    fs, n = 8000.0, 4000
    x = np.sin(np.arange(n) * 0.37)
    for name in ("h.csv", "t.csv"):
        (tmp_path / name).write_text("time_s,acc\n" + "".join(f"{i / fs:.6f},{a:.5f}\n" for i, a in enumerate(x)))
    watched = watched or ("intermediate pinion" if len(stages) == 2 else "output gear")
    (tmp_path / "s.toml").write_text(
        '[scenario]\nname = "s"\nkind = "detection"\n[source]\ngearbox = "u.toml"\n'
        f'faults = {{ "chip@{watched}" = [16, 18, 20] }}\nhealthy = 48\n{source_extra}'
        '[target]\nvibration = "acc"\nfiles = [\n'
        '  { file = "h.csv", role = "history", label = "healthy" },\n'
        '  { file = "t.csv", role = "test", label = "fault" },\n]\n'
    )
    return load_scenario(tmp_path / "s.toml").spec.source


def test_a_two_stage_box_s_watched_pinion_is_simulated_on_a_few_teeth_not_on_every_one(tmp_path):
    # 29 teeth x 3 sizes were 88 simulations, each its own (the two-stage model breaks the tooth-shift
    # symmetry); every tooth's damage lies at one place of its row (data.builder), so six teeth spread
    # around the gear, each sample as many times as the 29 teeth gave, make the same source rows
    source = _user_box(tmp_path)
    assert source.teeth == (1, 5, 10, 15, 20, 25)
    sizes = class_sizes(source)
    assert sizes["healthy"] == 48 and sum(sizes.values()) - 48 == 3 * 6 * 5  # 90 fault rows, as 87 were


def test_teeth_or_duplicates_the_user_wrote_a_wheel_and_a_one_stage_box_keep_every_tooth(tmp_path):
    assert _user_box(tmp_path, "teeth = [1, 2, 3]\n").teeth == (1, 2, 3)
    assert _user_box(tmp_path, "duplicates = 2\n").teeth is None
    assert _user_box(tmp_path, stages=((23, 47),)).teeth is None  # one simulation a size serves every tooth
    # a wheel's rows hold each tooth's damage at its own angle: every tooth is a shape of its own
    assert _user_box(tmp_path, watched="intermediate gear").teeth is None
    assert _user_box(tmp_path, watched="output gear").teeth is None


def test_a_slower_shaft_s_units_keep_its_own_content_and_lose_the_input_s(tmp_path):
    # a 54/107 reducer's output shaft (outside box K): the input's second order falls at 1.981 output
    # orders, which a TSA of 30 output turns keeps at 0.57 of a cycle of drift
    points, turns = 1024, 150
    theta = np.arange(turns * points) / points  # input turns
    out = theta * 54 / 107  # output turns
    own = np.sin(2 * np.pi * 54 * theta) + 3.0 * np.exp(-0.5 * (((out % 1.0) - 0.3) / 0.004) ** 2)  # mesh + chip
    interferer = 0.8 * np.sin(2 * np.pi * 2 * theta + 0.4) + 0.3 * np.sin(2 * np.pi * 53 * theta)
    shaft = UnitShaft("output", Fraction(54, 107), "output gear")
    units = shaft.revolutions((own + interferer).reshape(turns, points))
    clean = shaft.revolutions(own.reshape(turns, points))
    block, truth = units[:30].mean(axis=0), clean[:30].mean(axis=0)
    assert np.sqrt(np.mean((block - truth) ** 2)) < 0.05 * np.sqrt(np.mean(interferer**2))
    assert abs(block.max() - truth.max()) < 0.05 * truth.max()  # the chip kept
