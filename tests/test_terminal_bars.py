"""Issue 41, `gearlab run`'s bars in a terminal of 80 or 120 columns: every stage keeps its count,
elapsed time, rate and ETA whole on its own line whatever the units in progress say under the bars."""

import io
import re

import pytest
from rich.console import Console

from gearlab.events import Event

PRIMING = "priming: 4 shared states (primed and source-only models)"
UNIT = "source model, epoch 46 of 60, source validation accuracy 80.9 %"  # quick.toml's, 90 characters with its name


def frame(width: int, unit: bool) -> list[str]:
    """The lines the live display draws once a transfer run's two stages took their first step."""
    from gearlab.terminal import ProgressView

    console = Console(file=io.StringIO(), force_terminal=True, width=width, color_system=None)
    with ProgressView(console) as view:
        view.handle(Event("stage", stage="priming", total=4, message=PRIMING))
        view.handle(Event("stage", stage="runs", total=24, message="24 training runs"))
        if unit:
            view.handle(Event("unit", stage="rep0/k0/source_only-unsup", message=UNIT))
        view.handle(Event("advance", stage="priming", done=1, total=4))
        view.handle(Event("advance", stage="runs", done=1, total=24))
        shown = Console(file=io.StringIO(), width=width, color_system=None)
        shown.print(view.progress.get_renderable())
    return shown.file.getvalue().splitlines()


@pytest.mark.parametrize("width", [80, 120])
@pytest.mark.parametrize("unit", [False, True])
def test_each_bar_keeps_its_count_elapsed_time_and_eta_on_its_line(width, unit):
    """At 80 columns a unit's line (quick.toml: 'rep0/k0/source_only-unsup: source model, epoch 46
    ...') widened the label column until no bar, count or ETA was left; without it, or at 120
    columns, the elapsed time read '0:00:…', the rate '0:06/s…' and the ETA wrapped onto two lines."""
    lines = frame(width, unit)
    assert all(len(line) <= width for line in lines)
    for count in ("1/4", "1/24"):
        (line,) = [line for line in lines if re.search(rf"(?<![\d/]){count}(?!\d)", line)]
        assert re.search(rf"{count} +0:00:0\d +[\d:.]+/(s|step) ETA \d+:\d\d\s*$", line), lines
    if unit:
        (said,) = [line for line in lines if "rep0/k0/source_only-unsup" in line]
        assert "epoch 46 of 60" in said
    if width == 120:  # room for the labels: whole, on one line
        assert any(line.startswith(PRIMING) for line in lines), lines


def test_a_table_narrower_than_its_text_wraps_its_cells_at_their_words():
    """A detection run's 'Which gear' table at 100 columns: rich gave its eight columns like widths and
    cut words: 'matched_fil|ter', '../data/f1|.zip', 'watched-gea|r fault'. When every column can hold
    its longest word, each gets that, and the room left goes to the columns that need it."""
    from gearlab.terminal import print_results

    header = ["condition", "file", "label", "localised on", "z / threshold per shaft", "tooth", "which gear"]
    header += ["a flag is"]
    cells = ["16 Hz", "../data/f1.zip", "fault", "input pinion 25T (stage 1)", "input 78.9/2.6, output -1.6/2.6"]
    cells += ["2 of 25", "–", "watched-gear fault: input pinion 25T (stage 1)"]
    table = "| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n| " + " | ".join(cells) + " |\n"
    console = Console(file=io.StringIO(), width=100, force_terminal=True, color_system=None)
    print_results(console, [], ["Which gear:", table])
    text = console.file.getvalue()
    assert all(len(line) <= 100 for line in text.splitlines())
    words = {word for cell in header + cells for word in cell.split()}
    drawn = set(re.findall(r"[^\s│┃]+", text))
    assert words <= drawn, words - drawn
