"""A text record with Windows line ends (the PHM 2009 records) streams block by block as one with
Unix ends, not line by line (issue 42: half the reading time of phm09_chip's 24 records), and
gives the same columns; a block's rows are counted as its lines that hold more than blanks."""

import numpy as np
import pytest

import gearlab.data.readers.text as text


@pytest.mark.parametrize(
    "body",
    [b"1 2\n3 4\n", b"1 2\r\n3 4\r\n", b"1 2\n\n3 4\n", b"\n1 2\n", b"  \n1 2\n \t\n", b"1 2", b"1 2\r\n\r\n3 4"]
    + [b"", b"\n\n", b" \t\n", b"1\n \x0b\n2\n"],
)
def test_rows_are_the_lines_that_hold_more_than_blanks(body):
    assert text._rows(body) == sum(1 for line in body.split(b"\n") if line.strip())


def test_windows_line_ends_stream_by_blocks_with_the_same_columns(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    rows = "".join(f"  {a: .7e} {b: .7e}  {c: .7e}\n" for a, b, c in rng.standard_normal((5000, 3)))
    unix, windows = tmp_path / "unix.txt", tmp_path / "windows.txt"
    unix.write_bytes(rows.encode())
    windows.write_bytes(rows.replace("\n", "\r\n").encode())
    monkeypatch.setattr(text, "CHUNK_BYTES", 4093)  # many blocks, each cut inside a line
    calls = []
    blanks = text._blanks
    monkeypatch.setattr(text, "_blanks", lambda *a: calls.append(1) or blanks(*a))
    expected = text.read_columns(unix, [0, 2])
    calls.clear()
    got = text.read_columns(windows, [0, 2])
    assert got[1:] == expected[1:]
    for c in (0, 2):
        np.testing.assert_array_equal(got[0][c], expected[0][c])
    # one a block (60), the first block line by line (its first line may be a header); line by
    # line throughout it was two a line (10,000)
    assert len(calls) < 500
