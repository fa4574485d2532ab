"""A CSV's numeric body is parsed by numpy's C reader (numeric_block), with the same numbers, bit for bit,
as the row parser (split_rows + float of each field) and the same contents and messages for every file;
files it cannot take (quotes, text cells, ragged rows, bare decimal commas) go to the row parser."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.data.readers import csv as reader
from gearlab.errors import GearlabInputError

RNG = np.random.default_rng(7)
VALUES = [
    *(repr(float(v)) for v in RNG.standard_normal(40) * 10.0 ** RNG.integers(-300, 300, 40).astype(float)),
    *(f"{v:.25e}" for v in RNG.standard_normal(20)),
    *(f"{v:.3E}" for v in RNG.standard_normal(10) * 1e-310),  # subnormal
    *(f"{v:.30f}" for v in RNG.standard_normal(20)),
    *("123456789012345678901234567890", "9007199254740993", "2.2250738585072011e-308"),
    *("-0.0", "+1", "1.", "-.5", "1e5", "00012", "1E-400", "1e400", "-inf", "nan", "Infinity", "7"),
]


def _table(columns: int, sep: str, pad: str = "") -> list[str]:
    cells = RNG.permutation(np.resize(np.array(VALUES, dtype=object), 90 * columns)).reshape(90, columns)
    return [sep.join(f"{pad}{c}{pad}" for c in row) for row in cells]


def _both(path, names):
    """(contents with the C reader, contents with the row parser alone) of one file; or their two messages."""
    out = []
    for fast in (True, False):
        saved = reader.numeric_block
        if not fast:
            reader.numeric_block = lambda *a: None
        try:
            out.append(reader._read_csv(path, names))
        except GearlabInputError as e:
            out.append(str(e))
        finally:
            reader.numeric_block = saved
    return out


def _same(a, b):
    if isinstance(a, str) or isinstance(b, str):
        assert a == b
        return
    assert list(a.found) == list(b.found) and a.available == b.available and (a.units, a.steps) == (b.units, b.steps)
    for n in a.found:
        x, y = np.asarray(a.found[n]), np.asarray(b.found[n])
        assert x.dtype == y.dtype and x.shape == y.shape
        if x.dtype.kind == "f":
            assert np.array_equal(x.view(np.int64), y.view(np.int64))  # bit for bit, NaN and -0.0 alike
        else:
            assert np.array_equal(x, y)
    assert [(w, np.asarray(v).tolist()) for w, v in a.rates] == [(w, np.asarray(v).tolist()) for w, v in b.rates]
    assert len(a.times) == len(b.times)
    for (wa, va), (wb, vb) in zip(a.times, b.times):
        assert wa == wb and np.array_equal(np.asarray(va).view(np.int64), np.asarray(vb).view(np.int64))


@pytest.mark.parametrize(
    "sep, pad, header",
    [
        (",", "", "time,acc,probe"),
        (", ", "", "t, acc, probe"),
        ("\t", "", "Time\tacc\tprobe"),
        (";", "", "time;acc;probe"),
        (" ", "", "time acc probe"),
        ("   ", "  ", ""),
        (",", " ", ""),
    ],
)
def test_numbers_bit_identical_to_the_row_parser(tmp_path, sep, pad, header):
    lines = _table(3, sep, pad)
    path = tmp_path / "r.csv"
    path.write_text("# fs = 25600\n" + (header + "\n" if header else "") + "\n".join(lines) + "\n")
    names = header.replace(",", " ").replace(";", " ").split() or ["0", "1", "2"]
    fast, rows = _both(path, [*names, "fs"])
    _same(fast, rows)
    block = reader.numeric_block(lines, reader.delimiter_of(lines[0]), 3)
    assert block is not None and block.shape == (3, 90)  # the C reader took it
    expected = np.asarray([[float(f) for f in r] for r in reader.split_rows(lines, reader.delimiter_of(lines[0]))])
    assert np.array_equal(block.view(np.int64), expected.T.view(np.int64))


def test_decimal_commas_and_a_units_row(tmp_path):
    path = tmp_path / "eu.csv"
    path.write_text("Zeit;Beschl\ns;m/s²\n0,0;-1,5e-3\n0,5;,25\n1,0;+2,0E+1\n")
    fast, rows = _both(path, ["Zeit", "Beschl"])
    _same(fast, rows)
    assert fast.units == {"Zeit": "s", "Beschl": "m/s²"} and fast.found["Beschl"].tolist() == [-1.5e-3, 0.25, 20.0]


@pytest.mark.parametrize(
    "body",
    [
        "a;b\n1,;2\n3;4\n",  # '1,' is no number with a decimal comma: text, as the row parser keeps it
        "a;b\n1,e3;2\n3;4\n",
        'a,b\n"1",2\n3,4\n',  # quoted
        "a,b\n1,2\n3\n",  # ragged
        "a,b\n1,2\n3,4,5\n",
        "a,b\n1,2\n3,x\n",  # a text cell
        "a,b\n1,\n3,4\n",  # an empty cell
        "a,b,\n1,2,\n3,4,\n",  # every line ends in the separator
        "a,a\n1,2\n",  # a name twice
        "a,b\n",  # no data rows
        "a,b\n1, ,\n",
        "a b\n1_0 2\n3 4\n",  # float() reads '1_0'; numpy's C reader does not
        "1,2\n3,4\n5,6\n",
        "# fs = 100\na,b\n\n  \n1,2\n  # a note\n3,x\n",  # comments and blank lines: the line numbers
        "a,b\n1,2\n \t\n3\n",
    ],
)
def test_files_the_c_reader_refuses_read_as_before(tmp_path, body):
    path = tmp_path / "odd.csv"
    path.write_text(body)
    fast, rows = _both(path, ["a", "b", "0", "1"])
    _same(fast, rows)
