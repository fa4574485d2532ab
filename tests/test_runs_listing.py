"""Issue 41, `gearlab runs` as a person reads it: a detection run's headline is its first finding,
not the verdict's introduction ('At record10 (detected / false alarms % at ...):'); on a terminal
narrower than the table each run keeps its words and its directory whole. At 100 columns every row
took 5-11 lines: 'likelihood_r|atio', '(unsupervise|d)', '/tmp/helper|A/runs/quic|k/...'."""

import io
import re
from pathlib import Path

from rich.console import Console

from gearlab.runinfo import RunInfo, headline
from gearlab.terminal import print_table, runs_table

RUNS = [
    RunInfo(
        Path("/tmp/helperA/runs/quick/20261203-074111-958774"),
        "quick",
        "transfer",
        "2026-12-03T07:41:11+00:00",
        107.0,
        "finished",
        "dann (unsupervised) and likelihood_ratio (unsupervised) and mmd (unsupervised) tie at k = 0 (88.65 %), 3.0…",
    ),
    RunInfo(
        Path("/tmp/helperA/runs/stiffness_verification/20261203-071112-104275"),
        "stiffness_verification",
        "stiffness",
        "2026-12-03T07:11:12+00:00",
        5.0,
        "cancelled",
        "",
    ),
]


def shown(width: int, terminal: bool = True) -> list[str]:
    console = Console(file=io.StringIO(), width=width, force_terminal=terminal, color_system=None)
    print_table(console, runs_table(RUNS, console))
    return console.file.getvalue().splitlines()


def test_on_a_narrow_terminal_each_run_keeps_its_words_and_directory_whole():
    lines = shown(100)
    assert all(len(line) <= 100 for line in lines)
    text = "\n".join(lines)
    for run in RUNS:
        assert any(line.strip() == str(run.path) for line in lines), text  # whole, on a line of its own
        assert re.search(rf"{run.name}\s+{run.kind}\s+2026-12-03 07:\d\d\s+\S.* s\s+{run.status}", text), text
    assert "likelihood_ratio (unsupervised)" in text and "tie at k = 0" in text
    assert len(lines) <= 3 + 3 * len(RUNS)  # a header, then three lines a run at most


def test_a_wide_terminal_or_a_pipe_keeps_the_table():
    for lines in (shown(260), shown(100, terminal=False)):
        assert sum("│" in line for line in lines) == len(RUNS)  # a row a run
        assert any("headline" in line and "run directory" in line for line in lines)


def test_a_detection_runs_headline_is_its_first_finding_not_the_verdicts_introduction(monkeypatch):
    import gearlab.verdict

    said = [
        "At record10 (detected / false alarms % at the history's threshold, ...; goal: AUC >= 0.95):",
        "16 Hz: goal met by fm4, na4; best learned source_only (AUC 0.39, 0 / 0 %), behind the best classical fm4.",
    ]
    # the verdict opens with a line per take (detection_summary); the run's headline is its methods' first finding
    take = "take f1.zip: damage on the input pinion 25T (stage 1): z = 119.85 (threshold 2.58), tooth 2 of 25"
    monkeypatch.setattr(gearlab.verdict, "verdict_lines", lambda run: [take, *said])
    monkeypatch.setattr("gearlab.kinds.detection_verdict.detection_lines", lambda summary, unit: said)

    class Run:
        def read_json(self, name):
            return {"rows": [{"unit": "record10"}]}

    assert headline(Run(), "detection").startswith("16 Hz: goal met by fm4, na4; best learned source_only")
