"""`gearlab runs` lists a gap run whose tooth counts differ by that line (issue 39 outside check): a 25-tooth
description of a 24-tooth box was listed as 'The simulator and the target differ significantly (gap 1.09e+05
...)', the first line of a verdict whose finding is the tooth count."""

from __future__ import annotations

from gearlab.runinfo import headline

BASE = {
    "gap_before": 1.09e5,
    "gap_after": 1.09e5,
    "p_before": 0.005,
    "significant_before": True,
    "views": {"mesh": {"share_before": 1.0}},
    "effects": [],
}


class Run:
    def __init__(self, summary: dict):
        self.summary = summary

    def read_json(self, name: str, default=None):
        return self.summary if name == "summary.json" else default

    def file(self, *parts):
        from pathlib import Path

        return Path("/nonexistent", *parts)


def test_a_gap_run_whose_structure_differs_is_listed_by_it():
    said = "structure differs: stage 1 pinion: 24 teeth fit the recording, 25 described"
    assert headline(Run({**BASE, "verdict": said}), "gap").startswith("Structure differs: stage 1 pinion: 24 teeth")
    level = "level differs: the target is 1900 x the source's level"
    assert headline(Run({**BASE, "verdict": level}), "gap").startswith("Level differs: the target is 1900")
