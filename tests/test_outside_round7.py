"""Outside-user check of issue 39 (a spur gearbox and recordings made outside the project, described
as a user would from docs/your_gearbox.md): the mistakes a user makes give one line naming file, table
and key, exit 2, and what the recordings contradict is called out by every kind."""

from __future__ import annotations

import re

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.errors import GearlabInputError
from gearlab.gearbox import load_gearbox
from gearlab.notebook import inspect_options
from gearlab.parts.measured import speed_of


def test_a_bare_speed_meant_in_rpm_is_refused_in_every_table_with_its_unit_asked(tmp_path, cli):
    # '[operation] speed = 900' (a 4-pole motor's 900 rpm) was read as 900 Hz, 54,000 rpm, and passed:
    # the [operation] bound was 100 kHz, the [target]'s 1 kHz. A bare number is in Hz up to 100 Hz
    # (6,000 rpm); above it the unit is asked for; with a unit, every table takes up to 1 kHz.
    box = tmp_path / "box.toml"
    text = description(stage(23, 61, module="3 mm"), name="s", speed="SPEED")
    for given, hz in (('"900 rpm"', 15.0), ("25", 25.0), ('"150 Hz"', 150.0), ("99.5", 99.5)):
        box.write_text(text.replace('"SPEED"', given))
        assert load_gearbox(box).speed_hz == pytest.approx(hz)
    for given, said in (
        ("900", r"box.toml: \[operation\] key 'speed': a bare number is in Hz, and 900 Hz \(54,000 rpm\) is no usual"),
        ('"900"', r"key 'speed': a bare number is in Hz.*expected the unit, e.g. '900 rpm' \(15 Hz\) or '900 Hz'$"),
        ('"5 kHz"', r"box.toml: \[operation\] key 'speed': expected an input-shaft speed up to 1 kHz.*got 5000$"),
    ):
        box.write_text(text.replace('"SPEED"', given))
        with pytest.raises(GearlabInputError, match=said):
            load_gearbox(box)
    for read in (lambda v: speed_of(v, "d.toml: [target] key 'speed'"), lambda v: inspect_options(speed=v).speed_hz):
        with pytest.raises(GearlabInputError, match=r"a bare number is in Hz, and 900 Hz"):
            read(900)
        assert read("900 rpm") == pytest.approx(15.0) and read(35) == 35.0
    # validate: one line, exit 2, naming the description's file, table and key
    box.write_text(text.replace('"SPEED"', "600"))
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.c_[np.sin(np.arange(4000) * 0.3)], header="acc", comments="# fs = 5000\n")
    (tmp_path / "gap.toml").write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n[target]\nvibration = "acc"\n'
        'files = [{ file = "rec.csv", role = "history", label = "healthy" }]\n[accuracy]\nenabled = false\n'
    )
    code, _, err = cli("validate", tmp_path / "gap.toml")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "box.toml: [operation] key 'speed': a bare number is in Hz" in err and "'600 rpm' (10 Hz)" in err


def _fan(path, z1: int, revs: int = 160, seed: int = 0) -> None:
    """A one-stage z1/61 fan at 29.5 Hz in m/s², its once-per-turn tacho on the OUTPUT shaft, as
    ';'-separated text with a header 't;accel_ms2;tach': each mesh harmonic modulated by both shafts
    (the input's sidebands 1 order apart, the output's z1/61), white noise."""
    fs, f = 6000.0, 29.5
    t = np.arange(int(revs / f * fs)) / fs
    theta = 2 * np.pi * f * t
    mod = 1 + 0.2 * np.cos(theta + 0.4) + 0.15 * np.cos(z1 / 61 * theta + 1.0)
    x = sum(mod * np.cos(h * z1 * theta + 0.7 * h) / h for h in (1, 2, 3))
    x = x + np.random.default_rng(seed).normal(0, 0.05, t.size)
    tacho = np.where((z1 / 61 * theta) % (2 * np.pi) < 0.3, 5.0, 0.0)
    rows = "%.6f;%.5f;%.1f\n" * t.size % tuple(np.column_stack([t, x, tacho]).ravel().tolist())  # in one operation
    path.write_text("t;accel_ms2;tach\n" + rows)


def test_detection_refuses_history_records_whose_gearbox_differs_from_the_description(tmp_path):
    # A 23/61 fan with its tacho on the output shaft, described as 24/61: the input's angle is the
    # tacho's times the described 61/24, so the mesh reads order 24 whatever the pinion; inspect read
    # the input's sidebands 24/23 apart ('the pinion ... shows 23.0 teeth'), but the detection kind has
    # no structure check, and the gap's assumed the input's order: both ran on a simulator of another
    # gearbox. Detection now stops before any simulation with the gap's one line.
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import check_structure, read_target

    for i, name in enumerate(("h1", "h2", "t1")):
        _fan(tmp_path / f"{name}.csv", 23, seed=i)
    files = ", ".join(
        f'{{ file = "{n}.csv", role = "{r}", label = "healthy" }}' for n, r in (("h1", "history"), ("h2", "history"))
    )
    for z1 in (23, 24):
        (tmp_path / "fan.toml").write_text(
            description(stage(z1, 61, module="3 mm"), name="fan", speed="29.5 Hz", load="40 N*m", tacho="output")
        )
        (tmp_path / "detect.toml").write_text(
            '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "fan.toml"\nfaults = { chip = [20] }\n'
            f'[target]\nvibration = "accel_ms2"\ntacho = "tach"\nfiles = [{files}, '
            '{ file = "t1.csv", role = "test", label = "fault" }]\n[detection]\nblocks = [10]\n'
        )
        spec = load_scenario(tmp_path / "detect.toml").spec
        conditions = read_target(spec.target, spec.detection.blocks, lambda e: None)
        where = f"{tmp_path / 'detect.toml'}: [source] key 'gearbox'"
        line = check_structure(spec.source, spec.target, conditions, where)
        if z1 == 23:
            assert line is None  # the right description passes
            continue
        assert line.startswith(f"{where}: the history of condition ") and "\n" not in line, line
        assert re.search(
            r"the pinion shows 2[23]\.\d ± 0\.\d teeth \(its shaft's sidebands of the mesh\), 24 expected", line
        )


def _two_stage(theta: np.ndarray, seed: int = 0) -> np.ndarray:
    """A 17/44 + 21/53 reducer at input angle *theta*: each mesh's harmonics 1-3, modulated by both of
    its shafts, the second mesh at 0.6 of the first, white noise."""
    x, o = np.zeros(theta.size), 1.0
    for k, (z1, z2) in enumerate(((17, 44), (21, 53))):
        mod = 1 + 0.2 * np.cos(o * theta) + 0.1 * np.cos(o * z1 / z2 * theta + 1.0)
        x += sum(0.6**k / h * mod * np.cos(h * o * z1 * theta + 0.7 * h + k) for h in (1, 2, 3))
        o *= z1 / z2
    return x + np.random.default_rng(seed).normal(0, 0.05, theta.size)


def test_a_tacho_on_the_input_described_on_a_much_slower_shaft_is_told_by_inspect_and_the_structure_check(
    tmp_path, cli
):
    # An input tacho read as a 17/44 + 21/53 reducer's output ([sensor] tacho = "output"): every order
    # reads 1/6.532 of its own, the first mesh at 2.60, 5.21, 7.81. The tacho check read the strongest
    # lines from order 5.5 only (a pinion has 6 teeth or more), so inspect said 'no line at mesh order
    # 17' without a word of the tacho; now a faster shaft is judged on its own reading of that floor.
    from gearboxes import described_pair

    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line

    fs, f = 8192.0, 25.0
    t = np.arange(int(160 / f * fs)) / fs
    theta = 2 * np.pi * f * t
    tacho = np.where(theta % (2 * np.pi) < 0.3, 5.0, 0.0)
    np.savetxt(
        tmp_path / "rec.csv",
        np.c_[t, _two_stage(theta), tacho],
        delimiter=",",
        header="time_s,acc_ms2,tach",
        comments="",
    )
    box = description(stage(17, 44), stage(21, 53, module="3 mm"), name="r", tacho="output")
    (tmp_path / "box.toml").write_text(box)
    code, out, err = cli(
        "inspect", tmp_path / "rec.csv", "--gearbox", tmp_path / "box.toml", "--vibration", "acc_ms2", "--tacho", "tach"
    )
    assert code == 0, err
    said = "every order reads 1/6.532 x its own, as when a tacho on the input shaft is read as on the output"
    assert said in out and "--tacho-shaft input" in out
    # the gap's and detection's structure check, on revolutions cut so (the input's angle 6.532 x the tacho's)
    points, ratio = 1024, 17 * 21 / (44 * 53)
    read = 2 * np.pi * np.arange(400 * points) / points
    rows = _two_stage(ratio * read, seed=1).reshape(400, points)
    chain = Chain(fs=points * f / ratio, speed=f / ratio, tacho_shaft="output")
    line = structure_line(rows, described_pair((17, 44), (21, 53)), 400, chain, None, {})
    assert line.startswith("mesh order 2.6 measured, 17 expected") and said in line, line
    assert "give [target] tacho_shaft = 'input'" in line


def test_a_train_whose_meshes_alone_repeat_late_validates_with_damage_on_every_gear(tmp_path, cli):
    # A 19/47 + 23/59 + 29/71 mixer (hunting-tooth counts): its meshes repeat only after 2773 input
    # turns, so every gear's damage does; validate refused every gear. Such a train is simulated as a
    # stretch of steady turns (tests/test_long_period_trains.py).
    stages = (stage(19, 47), stage(23, 59, module="2.5 mm"), stage(29, 71, module="3 mm"))
    (tmp_path / "mixer.toml").write_text(description(*stages, name="m", speed="40 Hz", load="60 N*m"))
    for name in ("h", "t"):
        wave = np.c_[np.sin(np.arange(4000) * 0.3)]
        np.savetxt(tmp_path / f"{name}.csv", wave, header="acc", comments="# fs = 5000\n")
    for gear in ("input pinion", "intermediate 1 pinion", "output gear"):
        (tmp_path / "d.toml").write_text(
            '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "mixer.toml"\n'
            f'faults = {{ "chip@{gear}" = [20] }}\n[target]\nvibration = "acc"\nspeed = "40 Hz"\nfiles = ['
            '{ file = "h.csv", role = "history", label = "healthy" }, '
            '{ file = "t.csv", role = "test", label = "fault" }]\n'
        )
        code, out, err = cli("validate", tmp_path / "d.toml")
        assert code == 0 and out.startswith("OK"), err


@pytest.mark.parametrize(
    "stages, read, chain, said",
    [
        # no tacho, an 18-tooth input pinion described for 17: the speed found from the mesh lines is 17/18
        # of the shaft's, the mesh reads order 18 as described, the input's sidebands 18/17 apart
        (((18, 44), (21, 53)), 18 / 17, dict(speed_from_mesh=True), "the pinion shows 17.0 ± 0.0 teeth"),
        # a tacho on the input, the last wheel described with 52 teeth: only its shaft's sidebands tell
        (
            ((17, 44), (21, 52)),
            1.0,
            dict(tacho_shaft="input"),
            "stage 2 wheel: 53 teeth fit the recording, 52 described; read outward from the tacho on the input shaft",
        ),
    ],
)
def test_the_structure_check_reads_the_input_pinion_without_a_tacho_and_the_last_wheel(stages, read, chain, said):
    # a 17/44 + 21/53 reducer's WAVs described with one tooth more or less passed detection (no check) and
    # the gap (the input's order taken as 1 without a tacho; a later stage's wheel never read)
    from gearboxes import described_pair

    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line

    points = 1024
    rows = _two_stage(read * 2 * np.pi * np.arange(300 * points) / points, seed=2).reshape(300, points)
    line = structure_line(rows, described_pair(*stages), 400, Chain(fs=points * 25.0, speed=25.0, **chain), None, {})
    assert line is not None and line.startswith(said), line
    right = structure_line(
        _two_stage(2 * np.pi * np.arange(300 * points) / points, seed=3).reshape(300, points),
        described_pair((17, 44), (21, 53)),
        400,
        Chain(fs=points * 25.0, speed=25.0, **chain),
        None,
        {},
    )
    assert right is None, right
