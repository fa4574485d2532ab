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


def _records(tmp_path, spikes: bool, chip: float = 0.0):
    """The conditions read_target makes of a one-stage box's two CSV takes the test writes (no tacho,
    900 rpm declared: 15 Hz at 8 kHz, 60 input turns), each with 4 single saturated samples when
    *spikes*, and a *chip*-high pulse every input turn when given."""
    from gearlab.kinds.detection_records import read_target

    box = description(stage(23, 47), name="u", speed="900 rpm", load="50 N*m")
    tmp_path.mkdir()
    (tmp_path / "u.toml").write_text(box)
    fs, n = 8000.0, 32000
    theta = np.arange(n) * 15.0 / fs
    for k, name in enumerate(("h.csv", "t.csv")):
        rng = np.random.default_rng(k)
        x = np.sin(2 * np.pi * 23 * theta) + 0.3 * rng.standard_normal(n)
        x += chip * np.exp(-0.5 * (((theta % 1.0) - 0.4) / 0.002) ** 2)
        if spikes:  # the sensor saturating: a sample at full scale, ~19 robust deviations out
            x[rng.choice(np.arange(1000, n - 1000), 4, replace=False)] = 20.0 * rng.choice([-1.0, 1.0], 4)
        (tmp_path / name).write_text("time_s,acc\n" + "".join(f"{i / fs:.6f},{a:.5f}\n" for i, a in enumerate(x)))
    (tmp_path / "s.toml").write_text(
        '[scenario]\nname = "s"\nkind = "detection"\n[source]\ngearbox = "u.toml"\n'
        'faults = { "chip@output gear" = [16, 18, 20] }\nhealthy = 48\n'
        '[target]\nvibration = "acc"\nfiles = [\n'
        '  { file = "h.csv", role = "history", label = "healthy" },\n'
        '  { file = "t.csv", role = "test", label = "fault" },\n]\n'
    )
    target = load_scenario(tmp_path / "s.toml").spec.target
    return next(iter(read_target(target, (10,), lambda e: None).values()))


def test_a_sensor_s_isolated_spikes_do_not_set_the_history_s_units(tmp_path):
    # outside box S (round 12): 4 saturated samples a take at 25-28 robust deviations set the history's
    # thresholds (fm4 record30 582 against the chipped take's 104-159): 0-33 % of the chip's units found
    clean, spiked = _records(tmp_path / "c", False), _records(tmp_path / "s", True)
    for unit in ("revolution", "record10"):
        a, b = clean["history_units"][unit], spiked["history_units"][unit]
        assert a.shape == b.shape
        # each unit's worst point: as the clean take's, within half its spread
        assert np.abs(b).max() < np.abs(a).max() + 0.5 * a.std()
        kurt = lambda X: (((X - X.mean(1, keepdims=True)) ** 4).mean(1) / X.var(1) ** 2).max()  # noqa: E731
        assert kurt(b) < 1.2 * kurt(a)


def test_a_change_that_comes_back_every_turn_is_not_bridged(tmp_path):
    # a tooth's pulse as high as the spikes but once a turn is the gearbox's: left whole
    from gearlab.signals.spikes import without_spikes

    revs = 0.3 * np.random.default_rng(3).standard_normal((60, 1024))
    revs[:, 400] += 12.0
    assert np.array_equal(without_spikes(revs, 8000.0, 15.0), revs)
    once = revs.copy()
    once[:, 400] -= 12.0
    once[17, 700] = 12.0  # once in 60 turns: a sensor's
    assert np.abs(without_spikes(once, 8000.0, 15.0)).max() < 2.0
    thrice = once.copy()
    thrice[40, 701], thrice[52, 700] = 12.0, 12.0  # three times at one angle of the shaft: a tooth's, however rare
    assert np.array_equal(without_spikes(thrice, 8000.0, 15.0), thrice)
    thrice[52, 700], thrice[52, 200] = 0.0, 12.0  # two at one angle by chance, one at another: a sensor's
    assert np.abs(without_spikes(thrice, 8000.0, 15.0)).max() < 2.0
    rings = once.copy()
    rings[17, 696:705] = 12.0 * np.cos(np.arange(-4, 5) * 0.6)  # a knock ringing through the mounting
    assert np.array_equal(without_spikes(rings, 8000.0, 15.0), rings)
