"""The tooth of a take read off its tacho's mark (issue 39): outside user EY's 16/37 + 28/71 box running the other
way, its input pinion chipped 0.37 turn from its zero (tooth 6 of 16 forward), was scored 'tooth 11 of 16 (counted
from the tacho's mark on this shaft)', beside the warning that it ran the other way: its teeth pass the mark the
other way, so the count from the mark is the tooth's mirror. Where the run reads a take off its mark, the tooth is
given as its history counts it, the count the way the take turns beside it."""

from gearlab.kinds.detection_which_gear import evidence

PINION = "input pinion 16T (stage 1)"


def _found(pitches: float, turned: bool) -> dict:
    """A localisation naming the input pinion, its tooth fixed to the tacho's mark at *pitches* from it."""
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
