"""Outside-user check of issue 39 (a spur gearbox and recordings made outside the project, described
as a user would from docs/your_gearbox.md): the mistakes a user makes give one line naming file, table
and key, exit 2, and what the recordings contradict is called out by every kind."""

from __future__ import annotations

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
