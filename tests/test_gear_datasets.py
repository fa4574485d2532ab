"""Datasets with faults on any gear (gearlab.data.placement): class keys that say the gear, the rows
of a slower shaft's period, and the scenario's `faults` in both forms with one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.data.builder import SimTask, build_dataset, operating_point, simulate_unit, whole_steps_rate
from gearlab.data.placement import canonical_faults, shaft_names
from gearlab.data.spec import POINTS, dataset_preset
from gearlab.errors import GearlabInputError
from gearlab.physics.presets import gear_pair

ON_EVERY_GEAR = (("chip", (20,)), ("chip@wheel", (20,)), ("chip@s2-pinion", (20,)), ("chip@s2-wheel", (20,)))


@pytest.fixture(scope="module")
def rig():
    spec = dataset_preset("phm09-30").with_(faults=ON_EVERY_GEAR, teeth=(2, 40), healthy=1)
    with pytest.raises(GearlabInputError, match=r"tooth 40 is outside 1\.\.32"):
        spec.check_model()  # the input pinion has 32 teeth
    spec = spec.with_(faults=ON_EVERY_GEAR[1:])
    return spec, build_dataset(spec)


def test_the_classes_say_which_gear(rig):
    spec, data = rig
    assert spec.class_names == ("healthy", "chip@wheel", "chip@s2-pinion", "chip@s2-wheel")
    classes = spec.fault_classes()
    assert [(c.name, c.stage, c.gear) for c in classes.values()] == [
        ("chip", 1, "wheel"),
        ("chip", 2, "pinion"),
        ("chip", 2, "wheel"),
    ]
    assert [c.pair.Z2 if c.gear == "wheel" else c.pair.Z1 for c in classes.values()] == [96, 48, 80]
    assert data.X.shape == (1 + 3 * 2, POINTS)
    assert list(data.label) == [0, 1, 1, 2, 2, 3, 3] and list(data.tooth) == [0, 2, 40, 2, 40, 2, 40]
    # a sample's revolution is the one its damaged tooth meshes in: it differs from the healthy one
    healthy = data.X[0]
    for row in data.X[1:]:
        assert np.sqrt(np.mean((row - healthy) ** 2)) > 1e-3 * np.sqrt(np.mean(healthy**2))


def test_a_sample_averages_the_gears_turns_not_one_revolution(rig):
    """J consecutive input revolutions of a fault on the 80T output gear: the damage is in one of every
    5, so the input-shaft TSA of J = 5 is the mean of the period's 5 revolutions, the first of which
    (the row of J = 1) carries the damaged tooth's mesh."""
    spec, data = rig
    one = spec.with_(faults=(("chip@s2-wheel", (20,)),), teeth=(2,))
    averaged = build_dataset(one.with_(revolutions=5, tsa=True))
    speed, load = operating_point(one)
    fs = whole_steps_rate(one.fs, speed, 32)
    task = SimTask(one.model, one.preset, fs, speed, load, one.channel, "chip@s2-wheel", 20, (2,), (), 2)
    period = simulate_unit(tuple(task))[0].reshape(-1, POINTS)
    assert period.shape == (5, POINTS)
    mean, std = averaged.reference
    np.testing.assert_allclose(averaged.X[1], (period.mean(axis=0) - mean) / std, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(data.X[5], (period[0] - mean) / std, rtol=1e-5, atol=1e-5)
    change_one = data.X[5] - data.X[0]
    change_tsa = averaged.X[1] - averaged.X[0]
    assert np.sqrt(np.mean(change_tsa**2)) < 0.5 * np.sqrt(np.mean(change_one**2))


def test_the_scenario_forms_give_the_same_keys():
    shafts = shaft_names("phm09", 2)
    assert shafts == ("input", "idler", "output")
    table = canonical_faults({"chip": [20], "chip@output gear": [20], "crack@s1-wheel": [12]}, shafts, "[[datasets]]")
    listed = canonical_faults(
        [
            {"name": "chip", "steps": [20]},
            {"name": "chip", "gear": "wheel", "stage": 2, "steps": [20]},
            {"name": "crack", "gear": "idler gear", "steps": [12]},
        ],
        shafts,
        "[[datasets]]",
    )
    assert table == listed == (("chip", (20,)), ("chip@s2-wheel", (20,)), ("crack@wheel", (12,)))
    # the description's default names serve too
    assert canonical_faults({"chip@intermediate pinion": [1]}, shafts, "x") == (("chip@s2-pinion", (1,)),)


SCENARIO = '[scenario]\nname = "g"\nkind = "dataset"\n\n[[datasets]]\npreset = "phm09-30"\nhealthy = 1\n'


@pytest.mark.parametrize(
    "faults, message",
    [
        ('[{ name = "chip", gear = "outpt gear", steps = [20] }]', "key 'gear': unknown gear 'outpt gear'"),
        (
            '[{ name = "chip", gear = "wheel", stage = 3, steps = [20] }]',
            "key 'stage': expected a stage number in 1..2",
        ),
        ('[{ name = "chip", gear = "wheel", stage = 2 }]', "#1: missing 'steps'"),
        ('{ "chip@s3-wheel" = [20] }', "fault 'chip@s3-wheel' key 'stage': expected a stage number in 1..2"),
        (
            '[{ name = "chip", gear = "wheel", steps = [20] }, { name = "chip", gear = "idler gear", steps = [1] }]',
            "fault 'chip@idler gear' is listed twice",
        ),
        ('[{ name = "chip", wheel = 3, steps = [20] }]', "unknown key 'wheel'"),
        ('"chip"', "key 'faults'"),
    ],
)
def test_bad_placements_are_refused_at_validate(cli, write_scenario, faults, message):
    code, _, err = cli("validate", write_scenario(SCENARIO + f"faults = {faults}\n"))
    assert code == 2 and message in err, err
    assert len(err.strip().splitlines()) == 1


def test_a_dataset_of_faults_on_every_gear_validates(cli, write_scenario):
    faults = '[{ name = "chip", steps = [20] }, { name = "chip", gear = "output gear", steps = [20] }]'
    code, out, err = cli("validate", write_scenario(SCENARIO + f"faults = {faults}\nteeth = [3]\n"))
    assert code == 0, err


def test_the_period_of_damage_on_each_gear_and_the_bound_on_it():
    import math

    from gearlab.data.placement import MAX_PERIOD, train_period
    from gearlab.physics.geometry import GearPair

    rig = (gear_pair("phm09_stage1"), gear_pair("phm09_stage2"))
    assert [train_period(rig, s, g) for s, g in ((1, "pinion"), (1, "wheel"), (2, "pinion"), (2, "wheel"))] == [
        1,
        3,
        3,
        5,
    ]
    common = dict(module=2e-3, face_width=20e-3, pressure_angle=math.radians(20), E=200e9, nu=0.3, hub_radius=8e-3)
    coprime = (GearPair(Z1=21, Z2=53, **common), GearPair(Z1=29, Z2=61, **common))
    # stage 2 meshes 609/53 times per input turn; its wheel turns 609/3233 times
    assert [train_period(coprime, s, g) for s, g in ((1, "pinion"), (1, "wheel"), (2, "wheel"))] == [53, 53, 3233]
    assert train_period(coprime, 2, "wheel") > MAX_PERIOD  # past it: a stretch (tests/test_long_period_trains.py)


@pytest.mark.parametrize(
    ("gear", "shafts", "suggested"),
    [("input wheel", ("input", "output"), "output gear"), ("outpt wheel", ("input", "idler", "output"), "output gear")],
)
def test_an_unknown_gear_s_suggestion_is_a_name_the_error_lists(gear, shafts, suggested):
    # 'input wheel' of a one-stage train was told "did you mean 'output wheel'?; known: ..., output gear": an alias
    # understood but not listed, so the user could not tell whether the suggestion was a name at all
    from gearlab.data.placement import resolve_gear
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError) as caught:
        resolve_gear(gear, None, shafts, "[source] key 'faults'")
    line = str(caught.value)
    assert f"(did you mean '{suggested}'?)" in line, line
    assert suggested in line.split("; known: ")[1].split(", "), line
