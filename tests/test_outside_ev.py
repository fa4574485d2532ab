"""Outside user EU's defects (issue 39, round 23), each reproduced small: the which-gear table's last column, the
gap report's two removal figures, and inspect's sideband comb of a 2 s take whose tacho is stored at a quarter of
the vibration's rate."""

from __future__ import annotations

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
