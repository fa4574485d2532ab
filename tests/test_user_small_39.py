"""Four small user-facing defects of issue 39 (the last session's "Left (39)"): a simulator warning a
user cannot act on, where a detection takes a target's speed without a tacho, what a gap
scenario's validate counts, and which undercut criterion a description's error names."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from gearboxes import TWO_HISTORIES_ONE_TEST, description, stage

# a 20/31 pinion pair whose stiffest mode is ~16 kHz: 10 steps per period need ~162 kHz
STIFF = description(
    stage(20, 31), name="stiff", speed="40 Hz", load="30 N*m", near="input", direction="x", tacho="input"
)


# --- (1) the simulator picks its own integration step ---------------------------------------------


def test_a_simulated_record_integrates_fast_enough_for_its_stiffest_mode_without_a_warning(tmp_path):
    from gearlab.data import which_templates
    from gearlab.data.simulated import simulated_record

    path = tmp_path / "stiff.toml"
    path.write_text(STIFF)

    def record(sim_fs, own_step=True):
        rec = simulated_record(
            [], gearbox=str(path), fs=25_600, sim_fs=sim_fs, revolutions=8, seed=3, own_step=own_step
        )
        return rec.vibration

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # was "fs = 60000 Hz gives fewer than 10 steps ... (16238 Hz)"
        # which-gear's simulated events of a 25.6 kHz logger's records (detection, score, inspect --history)
        which_templates._revolutions(str(path), 40.0, 25_600.0, which_templates.SIM_FS, 8, None)
        coarse = record(40e3)
    fine = record(800e3)  # 49 steps per period of the stiffest mode
    # the record at 25.6 kHz is the model's, not the step's: 57 % RMS off the fine one at 40 kHz before, 6.4 % now
    assert np.sqrt(np.mean((coarse - fine) ** 2)) < 0.1 * np.sqrt(np.mean(fine**2))
    with pytest.warns(UserWarning, match="fewer than 10 steps"):  # a rate the caller chose is kept, as before
        record(40e3, own_step=False)


def test_a_too_coarse_step_names_the_rate_to_set():
    from gearlab.dynamics.newmark import Simulator
    from gearlab.registry import get_registry

    with pytest.warns(UserWarning, match=r"fewer than 10 steps.*expected fs >= \d+ Hz") as caught:
        sim = Simulator(get_registry().get("model", "ten_dof"), "luo2019", fs=20e3)
    assert f"expected fs >= {math.ceil(sim.fs_floor)} Hz" in str(caught[0].message)
    assert 40e3 < sim.fs_floor < 60e3  # 10 x the casing/bearing mode of Table 2.3, ~5 kHz


# --- (2) without a tacho, the target's speed comes from the [source]'s description in both kinds ----------


def _takes(folder, names=("h1.csv", "h2.csv", "t1.csv")):
    """Takes as a logger writes them (time and one accelerometer column, 10 kHz): validate reads their header."""
    t = np.arange(256) / 10e3
    for name in names:
        np.savetxt(
            folder / name,
            np.column_stack([t, np.sin(2 * np.pi * 600 * t)]),
            delimiter=",",
            header="time_s,acc",
            comments="",
        )


DETECTION = (
    """[scenario]
name = "d39"
kind = "detection"
[source]
gearbox = "box.toml"
faults = {{ "chip@input pinion" = [16, 18] }}
healthy = 8
[target]
{target}vibration = "acc"
sensitivity = "10 mV/(m/s^2)"
"""
    + TWO_HISTORIES_ONE_TEST
)

GAP = """[scenario]
name = "g39"
kind = "gap"
[source]
gearbox = "box.toml"
[target]
{target}vibration = "acc"
sensitivity = "10 mV/(m/s^2)"
files = [{{ file = "h1.csv", role = "history", label = "healthy" }}]
[accuracy]
enabled = false
"""

BOX = description(stage(20, 31), name="box", speed="30 Hz", load="30 N*m", near="input", direction="x")


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "box.toml").write_text(BOX)
    _takes(tmp_path)
    return tmp_path


@pytest.mark.parametrize("kind", [DETECTION, GAP])
def test_without_a_tacho_both_kinds_take_the_speed_from_the_source_description(cli, folder, kind):
    path = folder / "s.toml"
    path.write_text(kind.format(target=""))  # no tacho, no speed, no [target] gearbox: the [source]'s
    code, out, err = cli("validate", path)
    assert code == 0, err  # detection was: "[target] key 'tacho': missing; ... no tacho, speed or gearbox"


@pytest.mark.parametrize("kind", [DETECTION, GAP])
def test_a_target_gearbox_the_source_description_contradicts_is_one_line(cli, folder, kind):
    (folder / "other.toml").write_text(description(stage(21, 31), name="other", speed="30 Hz", load="30 N*m"))
    (folder / "copy.toml").write_text(BOX)
    path = folder / "s.toml"
    for same in ("box.toml", "copy.toml"):  # the same gearbox twice, or a copy of it: accepted
        path.write_text(kind.format(target=f'gearbox = "{same}"\n'))
        code, out, err = cli("validate", path)
        assert code == 0, err
    path.write_text(kind.format(target='gearbox = "other.toml"\n'))
    code, out, err = cli("validate", path)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "[target] key 'gearbox'" in err and "21/31" in err and "20/31" in err and "[source]" in err, err
    (folder / "fast.toml").write_text(description(stage(20, 31), name="fast", speed="35 Hz", load="30 N*m"))
    path.write_text(kind.format(target='gearbox = "fast.toml"\n'))
    code, out, err = cli("validate", path)
    assert code == 2 and "35 Hz" in err and "30 Hz" in err, err


# --- (3) a gap scenario's validate line counts what the diagnosis uses ----------------------------


def test_a_gap_validate_line_says_what_its_numbers_are(cli, folder):
    path = folder / "s.toml"
    path.write_text(GAP.format(target=""))
    code, out, err = cli("validate", path)
    assert code == 0, err
    # was "gap of box (540 samples: 300 healthy, 240 fault) -> measured records (measured): ...": the
    # source's fault classes, which a diagnosis without [accuracy] never simulates, and no word of the records
    assert "gap of box (simulated) -> 1 measured history record:" in out, out
    assert "samples" not in out and "40 source healthy revolutions per evaluation" in out, out
    path.write_text(GAP.format(target="").replace("enabled = false", "enabled = true"))
    code, out, err = cli("validate", path)
    assert code == 0, err
    assert "trained on the simulated box (540 samples: 300 healthy, 240 fault)" in out, out


# --- (4) the undercut error names its criterion -------------------------------------------------------


def test_the_undercut_error_names_the_practical_criterion_and_the_textbook_limit(tmp_path):
    from gearlab.errors import GearlabInputError
    from gearlab.gearbox import load_gearbox

    path = tmp_path / "fan.toml"
    path.write_text(description(stage(13, 81), name="fan", speed="29 Hz", load="30 N*m"))
    with pytest.raises(GearlabInputError) as info:
        load_gearbox(path)
    line = str(info.value)
    # 13 teeth at 20 deg: 5/6 - 13 sin²20°/2 = 0.073 (slight undercut below the active flank accepted);
    # no undercut at all, the textbook's 1 - 13 sin²20°/2 = 0.240: the user is told which is asked and why
    assert "[[stages]] #1.pinion key 'z': 13 teeth at x = 0 are undercut into the active flank" in line, line
    assert "x ≥ 5/6 h_a* - z sin²α/2" in line and "DIN 3960" in line, line
    assert "no undercut at all: x ≥ h_a* - z sin²α/2 = 0.240" in line and "'x' ≥ 0.073" in line, line
    assert len(line.splitlines()) == 1
