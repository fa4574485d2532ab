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


def test_only_the_asked_for_columns_numbers_parsed_give_the_whole_parse_s_columns(tmp_path, monkeypatch):
    """readers.text.asked_numbers_only: the asked-for columns as the whole parse gives them, over blocks, a comment
    and a footer; a field that is no number in another column reads there (the whole parse refuses it), one in an
    asked-for column is refused in the whole parse's line."""
    from gearlab.data.readers import text

    monkeypatch.setattr(text, "CHUNK_BYTES", 4096)  # many blocks
    rows = [f"{i * 1e-3:.4e} {np.sin(i):.6f} {np.cos(i):.6f}" for i in range(3000)]
    path = tmp_path / "r.txt"
    path.write_text("t a b\n" + "\n".join(rows[:1500]) + "\n# a comment\n" + "\n".join(rows[1500:]) + "\nEnd\n")
    whole_warned, warned = [], []
    whole = read_columns(path, [2, 0], whole_warned)[0]
    with text.asked_numbers_only():
        asked = read_columns(path, [2, 0], warned)[0]
    assert all(np.array_equal(asked[c], whole[c]) for c in (0, 2)) and len(whole[0]) == 3000
    assert warned == whole_warned and "End" in warned[0]
    rows[2000] = rows[2000].replace(rows[2000].split()[1], "n/a")
    path.write_text("\n".join(rows) + "\n")
    with pytest.raises(GearlabInputError, match="line 2001 column 1: 'n/a' is not a number"):
        read_columns(path, [2])
    with text.asked_numbers_only():
        assert np.array_equal(read_columns(path, [2])[0][2], whole[2])
        with pytest.raises(GearlabInputError, match="line 2001 column 1: 'n/a' is not a number"):
            read_columns(path, [1])
