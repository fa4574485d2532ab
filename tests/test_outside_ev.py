"""Outside user EU's defects (issue 39, round 23), each reproduced small: the which-gear table's last column, the
gap report's two removal figures, and inspect's sideband comb of a 2 s take whose tacho is stored at a quarter of
the vibration's rate."""

from __future__ import annotations

import numpy as np

from gearlab.kinds.detection_which_gear import NOT_FLAGGED, NOT_LOCALISED, which_gear_summary


def _found(condition: str, call: str) -> dict:
    return {"condition": condition, "named": None, "named_shaft": None, "shafts": [], "summary": "", "call": call}


def test_a_take_no_method_flagged_reads_not_flagged_not_a_fault():
    # EU's healthy take, no unit over any threshold, read 'watched-gear fault (not localised)' under 'a flag is'
    loc = {
        "gearbox": "box",
        "watched": ["wheel 113T"],
        "records": {"h.csv": _found("27 Hz", NOT_LOCALISED), "f.csv": _found("27 Hz", NOT_LOCALISED)},
    }
    records = [
        {
            "condition": "27 Hz",
            "method": "fm4",
            "thresholds": {"record30": 4.0},
            "test_scores": {"h.csv": {"record30": [1.0, 3.9]}, "f.csv": {"record30": [3.0, 6.0]}},
        },
        {
            "condition": "27 Hz",
            "method": "rms",
            "thresholds": {"record30": 2.0},
            "test_scores": {"h.csv": {"record30": [1.5, 1.9]}, "f.csv": {"record30": [1.0, 1.0]}},
        },
    ]
    md = which_gear_summary(loc, records, {"h.csv": "healthy", "f.csv": "fault"})["md"]
    rows = {line.split(" | ")[1]: line for line in md.splitlines() if line.startswith("| 27 Hz")}
    assert rows["h.csv"].endswith(f"| {NOT_FLAGGED} |"), rows["h.csv"]
    assert NOT_LOCALISED not in rows["h.csv"]
    assert rows["f.csv"].endswith(f"| {NOT_LOCALISED} |"), rows["f.csv"]  # fm4 flagged its second unit
    assert "| a flag would be called |" in md


def test_the_named_set_s_share_says_its_fit_beside_the_round_s():
    # EU's box B: 'casing_path removes 86.3 % ... (accepted)' above 'together 79 % of the gap, under the 99 % a named
    # set removes': two fits (round 1's, the final) and two measures (the search's score, the report's gap), unsaid
    from gearlab.gap.diagnose import round_line
    from gearlab.kinds.gap_verdict import diagnosis_line

    params = {"k_xf": 3.16e6, "mf": 6.71}
    dropped = [{"name": "casing_path", "round": 1, "params": params}]
    result = {"gap_before": 3379.0, "gap_after": 3379.0, "effects": [], "verdict": "unexplained"}
    line = diagnosis_line({**result, "dropped_effects": dropped, "dropped_share": 0.79, "dropped_below": 0.99})
    said = "together 79 % of the gap, at the final fit by the report's gap (a round's share is at that round's fit, "
    assert f"{said}by the search's score), under the 99 % a named set removes" in line, line
    assert "at round 1's fit" in round_line(1, "casing_path", 0.863, True)


def test_a_tacho_held_from_a_quarter_of_the_rate_is_smoothed_to_its_own_quantisation(tmp_path):
    # EU: box A 37/113 at 27 Hz, a 2 s take, the tacho stored at 6.4 kHz beside 25.6 kHz: 'the wheel shows 123.9 ±
    # 8.0 teeth, 113 described'. Its edges, held onto the vibration's samples, are off by up to ±2 samples, and were
    # smoothed as if off by ±0.5: the angle 6.0 mrad rms off (1.7 read as the tacho's own samples)
    from scipy.io import savemat
    from test_outside_eu import BOX, FS, _take

    from gearlab.gearbox import load_gearbox
    from gearlab.inspect import InspectOptions, inspect_record
    from gearlab.signals.angle import _held_step, angle_from_pulses

    rng = np.random.default_rng(3)
    t = np.arange(int(2.0 * FS)) / FS
    th = 2 * np.pi * np.cumsum(27.0 * (1 + 0.002 * np.sin(2 * np.pi * 0.37 * t))) / FS + rng.uniform(0, 6)
    pulses = np.where(np.mod(th, 2 * np.pi) < 0.3, 5.0, 0.0)
    held = pulses[::4][np.arange(t.size) // 4]
    err = (angle_from_pulses(held, FS) - th)[1000:-1000]
    assert np.std(err) < 2.5e-3, np.std(err)
    assert _held_step(held, np.flatnonzero(np.diff(held) > 0) + 0.5) == 4.0
    assert _held_step(pulses, np.flatnonzero(np.diff(pulses) > 0) + 0.5) == 1.0  # at the vibration's own rate
    # a whole 1024 samples a turn, every change on a grid of 8 (pulses 40 wide), is no held tacho: no scatter
    whole = np.where(np.arange(51200) % 1024 < 40, 5.0, 0.0)
    assert _held_step(whole, np.arange(50) * 1024.0 - 0.5) == 1.0

    (tmp_path / "box.toml").write_text(BOX)
    acc, tacho = _take(2.0, 3)
    savemat(tmp_path / "own.mat", {"ACC": acc, "ACC_fs": FS, "TACHO": tacho[::4], "TACHO_fs": FS / 4})
    got = inspect_record(str(tmp_path / "own.mat"), load_gearbox(tmp_path / "box.toml"), InspectOptions("ACC", "TACHO"))
    assert "matches" in got["verdict"] and "differs" not in got["verdict"], got["verdict"]
