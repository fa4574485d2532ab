"""Four small user-facing defects of issue 39 (the last session's "Left (39)"): a simulator warning a
user cannot act on, where a detection takes a target's speed without a tacho, what a gap
scenario's validate counts, and which undercut criterion a description's error names."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from gearboxes import description, stage

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
