"""Which gear's tooth, in words (issue 39). A gear on the tacho's own shaft (one mark a turn) has its
tooth fixed to that mark, in every take, whichever input angle the take's first mark finds; it read
"30 of 41 (in this take only: a take starts with the shaft at any of 1927 angles)", and its count
moved with the take's turn to the first history record (41 m / 1927 teeth, m of 437). A shaft the
tacho does not fix says so plainly, not as a count of angles no user can act on (an outside user's
three-stage output gear: "any of 182776 angles"). The records: tests/test_which_gear_parity.py's
19/47 + 23/41 box with its output's tacho, cut to start at other output turns."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage
from test_which_gear_parity import TEETH, TOOTH, _detected, take

from gearlab.gearbox import resolve_gearbox

GEAR = "output gear 41T (stage 2)"
NOT_FIXED = "in this take only: the tooth is not fixed across takes; this shaft's angle"


def _cut(path, seconds: float) -> str:
    """The record at *path* less its first *seconds*: its first tacho mark a later output turn's."""
    with np.load(path) as f:
        acc, tacho, fs = f["acc"], f["tacho"], float(f["fs"])
    n = int(seconds * fs)
    np.savez(path, acc=acc[n:], tacho=tacho[n:], fs=fs)
    return str(path)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    where = tmp_path_factory.mktemp("words")
    text = description(*(stage(*z) for z in TEETH), name="words", speed="20 Hz", near="input", tacho="output")
    (where / "words.toml").write_text(text)
    out = {"box": str(where / "words.toml")}
    for name, fault, seed, slip, cut in (
        ("h1", None, 11, 0.012, 0.0),
        ("h2", None, 12, 0.016, 0.3),
        ("h3", None, 13, 0.010, 0.1),
        ("output", (1, "wheel", TOOTH), 14, 0.013, 0.5),
        ("pinion", (1, "pinion", 7), 16, 0.015, 0.2),
    ):
        out[name] = _cut(take(where / f"{name}.npz", fault, seed, slip), cut)
    return out


def _inspected(box, name) -> dict:
    from gearlab.inspect import InspectOptions
    from gearlab.inspect_history import localisation

    options = InspectOptions(vibration="acc", tacho="tacho")
    return localisation(box[name], [box[h] for h in ("h1", "h2", "h3")], resolve_gearbox(box["box"]), options)


def test_a_gear_on_the_tacho_shaft_counts_its_tooth_from_the_mark_in_every_take(box):
    found = _inspected(box, "output")  # its first mark finds the input 56/437 turn off the first history take's
    assert found["named"] == GEAR, found["summary"]
    assert "already line up" not in found["method"]  # the take is turned to the first history record's mark
    tooth = next(s for s in found["shafts"] if s["shaft"] == "output")["tooth"][GEAR]
    off = (tooth["pitches"] - (TOOTH - 0.5) + 41 / 2) % 41 - 41 / 2
    assert abs(off) < 1.0, (off, found["summary"])
    words = f"tooth {tooth['tooth']} of 41 (counted from the tacho's mark on this shaft)"
    assert words in found["summary"] and "any of" not in found["summary"], found["summary"]


def test_a_shaft_the_tacho_does_not_fix_says_so_plainly(box):
    found = _inspected(box, "pinion")
    assert found["named_shaft"] == "intermediate", found["summary"]  # 19/47 input turns a turn: not fixed
    assert f"({NOT_FIXED} relative to the tacho is not known)" in found["summary"], found["summary"]
    assert "any of" not in found["summary"]


def test_a_tooth_not_fixed_across_takes_is_said_without_a_count_of_angles():
    from gearlab.signals.localise import tooth_words

    # the outside user's three-stage output gear: a take's first mark finds it at any of 182776 angles
    said = tooth_words({"tooth": 13, "of": 80, "step": 80 / 182776, "tacho": True})
    assert said == f"13 of 80 ({NOT_FIXED} relative to the tacho is not known)"
    said = tooth_words({"tooth": 46, "of": 55, "step": 1.0, "tacho": False})  # without a tacho
    assert said == f"46 of 55 ({NOT_FIXED} at a take's start is not known)"
    assert tooth_words({"tooth": 17, "of": 96, "step": 32.0}) == "17 of 96 (up to 32-tooth steps between takes)"


def test_a_detection_run_and_score_count_the_tacho_shafts_tooth_from_its_mark_too(box, tmp_path):
    # the detection kind's which-gear records, and `gearlab score`'s against the run's stored history
    run, scored = _detected(box, tmp_path)
    for found in (run["records"][box["output"]], scored[box["output"]]):
        assert found["named"] == GEAR and "(counted from the tacho's mark on this shaft)" in found["summary"], found
    assert f"tooth {TOOTH} of 41" in run["records"][box["output"]]["summary"]
