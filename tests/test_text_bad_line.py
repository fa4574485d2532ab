"""A text record's bad cell is named at its own line, not at the header's.

A tab-separated take with a header 'time<TAB>acc' and a logger's dropout 'n/a' on line 501 was refused with
"line 1 column 0: 'time' is not a number": the slow path re-read the whole first block, its header too.
"""

import numpy as np
import pytest

from gearlab.data.readers.text import read_columns
from gearlab.errors import GearlabInputError


def _take(path, bad: str, preamble: str = "", rows: int = 3000):
    t = np.arange(rows) / 25600.0
    lines = [f"{a:.6f}\t{b:.6f}" for a, b in zip(t, np.sin(t * 700))]
    lines[499] = f"{t[499]:.6f}\t{bad}".rstrip()  # data line 500, file line 501 under the header
    path.write_text(preamble + "time\tacc\n" + "\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize(
    ("bad", "preamble", "said"),
    [
        ("n/a", "", "line 501 column 1: 'n/a' is not a number"),
        ("", "", "line 501 has 1 fields, expected 2"),
        ("n/a", "Logger XY-200\nSample rate: 25.6 kHz\n\n", "line 504 column 1: 'n/a' is not a number"),
    ],
    ids=["a word", "an empty cell", "under a preamble"],
)
def test_the_line_named_is_the_bad_cells(tmp_path, bad, preamble, said):
    path = _take(tmp_path / "take.txt", bad, preamble)
    with pytest.raises(GearlabInputError) as got:
        read_columns(path, ["acc"])
    assert said in str(got.value), str(got.value)


def test_a_good_take_reads_whole(tmp_path):
    path = _take(tmp_path / "take.txt", "0.5")
    columns, header, width = read_columns(path, ["acc"])
    assert header == ["time", "acc"] and width == 2 and columns["acc"].size == 3000
