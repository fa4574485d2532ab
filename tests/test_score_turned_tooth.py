"""The tooth of a take read off its tacho's mark (issue 39): outside user EY's 16/37 + 28/71 box running the other
way, its input pinion chipped 0.37 turn from its zero (tooth 6 of 16 forward), was scored 'tooth 11 of 16 (counted
from the tacho's mark on this shaft)', beside the warning that it ran the other way: its teeth pass the mark the
other way, so the count from the mark is the tooth's mirror. Where the run reads a take off its mark, the tooth is
given as its history counts it, the count the way the take turns beside it."""

import json
from pathlib import Path

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import FS, PULSES, SPEED, record, signals, text, write_zip

from gearlab.kinds import detection_scoring
from gearlab.kinds.detection_which_gear import evidence

PINION = "input pinion 16T (stage 1)"
# a take read off one of several marks a turn: turned to whichever its average matches best, its mirror is about no
# known point (the tiny box's chip, tooth 2 of 25 forward, mirrored read 19 of 25)
AMONG_MARKS = "counted the way this take turns (read off its tacho's mark: which of its 10 marks a turn its history"


def _found(pitches: float, turned: int) -> dict:
    """A localisation naming the input pinion, its tooth fixed to the tacho's mark at *pitches* from it; *turned*: read
    off that mark, of so many marks a turn (True: one)."""
    tooth = {"pitches": pitches, "tooth": int(pitches) % 16 + 1, "of": 16, "mark": True}
    shaft = {"shaft": "input", "z": 17.3, "threshold": 2.7, "gears": [PINION], "tooth": {PINION: tooth}}
    return {"named": [PINION], "named_shaft": "input", "shafts": [shaft], "summary": "", "turned": turned}


def test_a_take_read_off_its_mark_names_its_tooth_as_its_history_counts_it():
    said = evidence(_found(10.97, turned=True))
    assert "tooth 6 of 16 if the box runs the other way (" in said, said
    assert "within a tooth; 11 of 16 counted the way this take turns)" in said, said
    # read at its mark, the count is the tooth
    said = evidence(_found(5.92, turned=False))
    assert "tooth 6 of 16 (counted from the tacho's mark on this shaft)" in said and "other way" not in said, said
    said = evidence(_found(10.97, turned=10))  # off one of 10 marks a turn: no mirror claimed
    assert f"tooth 11 of 16 {AMONG_MARKS} counts from is not known)" in said and "other way" not in said, said


def _back(path: Path) -> Path:
    """A chipped take of the tiny run's box running backwards: test_score_tie's chipped take reversed in time, its
    tacho's marks 0.45 of their spacing wide (the tacho triggers on each mark's other edge, 0.45 x 1/10 turn on);
    the turn that reads it off its mark ('+0.060 turn'), where the marks' spacing does not hide it."""
    vib, _ = signals(revolutions=41, chip=4.0, seed=11, phase=0.3)
    theta = 0.3 + 2 * np.pi * SPEED * np.arange(len(vib)) / FS
    tacho = np.where(np.mod(theta * PULSES / (2 * np.pi), 1.0) < 0.45, 5.0, 0.05)
    return write_zip(path, text(vib[::-1].copy(), tacho[::-1].copy()))


@pytest.fixture(scope="module")
def made(tmp_path_factory, module_cache):
    """The tie's tiny run (test_score_tie; shared), the backwards take and the same take forward."""
    folder = tmp_path_factory.mktemp("tie")
    out = shared_run(scenario(folder, methods=("source_only",)), folder / "runs")
    takes = tmp_path_factory.mktemp("takes")
    return out, _back(takes / "back.zip"), record(takes / "fwd.zip", revolutions=41, chip=4.0, seed=11, phase=0.3)


def test_score_counts_the_tooth_of_a_take_it_reads_off_its_mark_as_its_history_does(cli, made, monkeypatch):
    """The wiring from the off-mark check to the tooth's words, through `gearlab score`: the take it reads off its
    mark, and that one alone, is localised as turned."""
    out, back, fwd = made
    real, seen = detection_scoring.localise_scored, []

    def spied(run, records, turned=None):
        seen.append(dict(turned or {}))
        return real(run, records, turned)

    monkeypatch.setattr(detection_scoring, "localise_scored", spied)
    code, stdout, err = cli("score", out, back, fwd, "--json")
    assert code == 0, err
    assert seen == [{str(back): PULSES}], seen  # at the run's 10 marks a turn
    rows = {Path(r["file"]).name: r for r in json.loads(stdout)}
    assert "off its tacho's mark" in rows["back.zip"]["level"], rows["back.zip"]["level"]
    assert AMONG_MARKS in rows["back.zip"]["evidence"], rows["back.zip"]["evidence"]
    assert "(counted from the tacho's mark on this shaft)" in rows["fwd.zip"]["evidence"], rows["fwd.zip"]["evidence"]
    assert "other way" not in rows["fwd.zip"]["level"] + rows["fwd.zip"]["evidence"]


def test_the_run_s_which_gear_table_counts_the_tooth_of_a_take_it_reads_off_its_mark_as_score_does(tmp_path):
    """The run's own which-gear table by score's rule (signals.checks.read_off_mark, turned_tooth): the tie's
    scenario with its healthy test take the backwards one, read (detection_records.read_target) and localised
    (localise_target, as the run does: no training); its tooth was counted as the take turns."""
    from gearlab.engine import load_scenario
    from gearlab.kinds.detection_records import asynchronous_orders, read_target, unit_shaft
    from gearlab.kinds.detection_which_gear import localise_target, records_md

    (tmp_path / "data").mkdir()
    _back(tmp_path / "data" / "h3.zip")
    spec = load_scenario(scenario(tmp_path, methods=("source_only",))).spec
    shaft = unit_shaft(spec.source)
    conditions = read_target(
        spec.target, spec.detection.blocks, lambda e: None, "here", shaft, bool(asynchronous_orders(spec.source, shaft))
    )
    found = localise_target(spec.source, conditions)
    turned = {Path(p).name: r["turned"] for p, r in found["records"].items()}
    assert turned == {"h3.zip": PULSES, "f1.zip": 0, "f2.zip": 0}, turned
    (line,) = [x for x in records_md(found, {}, set()).splitlines() if "h3.zip" in x]
    assert AMONG_MARKS in line and "other way" not in line, line
