"""Outside user EJ's rebuilt gearbox (issue 39, day-to-day scoring): a take of the box after a stage's pinion was
swapped for one a tooth more (26 -> 27) was scored against the old box's thresholds, every method calling it
'other damage' (exit 1 with --exit-code), with a warning only that its lines did not fit. Where inspect's check
reads a mesh order moved to another whole tooth count (its 'mesh_moved' difference, a tacho read as said), the
take is another gearbox's: not scored, as a take at another speed is not. A damaged take of the right box (a
chipped tooth, a cracked one) keeps its mesh where it was and is scored as before."""

from __future__ import annotations

import json

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import FS, PULSES, SPEED, TEETH, text, write_zip

from gearlab.parts import scoring
from gearlab.runs import RunDir

OTHER = "a take of another gearbox, not this run's to score"


def _take(teeth: int, seed: int, damage: str = "") -> bytes:
    """40 turns at the run's speed: the mesh at order *teeth* and its 2nd harmonic, a shaft line, noise; *damage*
    'chip' rings once a turn where the tooth meets, 'crack' dips the mesh over three pitches (a weaker tooth)."""
    rng = np.random.default_rng(seed)
    theta = 0.4 * seed + 2 * np.pi * SPEED * np.arange(int(40 * FS / SPEED)) / FS
    gap = np.angle(np.exp(1j * (theta - 1.0)))  # rad from the damaged tooth
    mesh = 1.0 - (0.4 * np.exp(-0.5 * (gap * teeth / (2 * np.pi * 1.5)) ** 2) if damage == "crack" else 0.0)
    vib = mesh * np.sin(teeth * theta) + 0.3 * np.sin(2 * teeth * theta + 0.4) + 0.2 * np.sin(theta)
    if damage == "chip":
        since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * SPEED)
        vib += 1.5 * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
    tacho = np.where(np.mod(theta * PULSES / (2 * np.pi), 1.0) < 0.3, 5.0, 0.05)
    return text(vib + 0.3 * rng.standard_normal(theta.size), tacho)


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    """The tiny detection run (a 32-tooth pinion, 16 Hz) and takes: one of a 33-tooth pinion, one chipped and one
    cracked of the run's own box."""
    folder = tmp_path_factory.mktemp("rebuilt")
    out = shared_run(scenario(folder, methods=("matched_filter",)), folder / "runs")
    takes = {}
    for name, teeth, seed, damage in (
        ("rebuilt", TEETH + 1, 31, ""),
        ("chipped", TEETH, 32, "chip"),
        ("cracked", TEETH, 33, "crack"),
    ):
        takes[name] = str(write_zip(folder / f"{name}.zip", _take(teeth, seed, damage)))
    return out, takes


def test_a_take_of_a_rebuilt_gearbox_alone_is_refused_in_one_line_nothing_written(cli, made, quiet):
    out, takes = made
    before = scoring.read_history(RunDir.open(out))
    code, _, err = cli("score", out, takes["rebuilt"], "--exit-code")
    assert code == 2 and err.startswith(f"error: {takes['rebuilt']}: ") and err.count("\n") == 1, err
    # the run's description (meng2020) holds 25 teeth, its history 32: the take is weighed against the history's
    assert f"stage 1: mesh order {TEETH + 1} measured" in err and OTHER in err, err
    assert f"the run's history shows stage 1's mesh at order {TEETH}; " in err, err
    assert scoring.read_history(RunDir.open(out)) == before


def test_of_several_the_rebuilt_take_is_not_scored_the_damaged_ones_are(cli, made, quiet):
    out, takes = made
    code, stdout, err = cli("score", out, takes["rebuilt"], takes["chipped"], takes["cracked"], "--json")
    assert code == 2, err
    rows = json.loads(stdout)
    assert rows[0]["file"] == takes["rebuilt"] and rows[0]["decision"] == "not scored", rows[0]
    assert OTHER in rows[0]["skipped"], rows[0]
    damaged = [r for r in rows[1:] if r["file"] in (takes["chipped"], takes["cracked"])]
    assert {r["file"] for r in damaged} == {takes["chipped"], takes["cracked"]}, rows
    # scored as before: the run's description (25 teeth) is not their 32 (a warning), its history is
    assert all(r["method"] and r["decision"] != "not scored" and OTHER not in r["gearbox"] for r in damaged), damaged
    assert all("its scores weigh another gearbox" in r["gearbox"] for r in damaged), damaged
    skipped = scoring.read_skipped(RunDir.open(out))
    assert [(r["file"], r["decision"]) for r in skipped] == [(takes["rebuilt"], "not scored")], skipped
