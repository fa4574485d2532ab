"""CSV and delimited text: columns separated by commas, semicolons, tabs or blanks; a header row of
names or none (columns "0", "1", …); '#' comment lines; the rate from a time column or a comment
'# fs = 51200'."""

from __future__ import annotations

import csv
import io
import operator
import re
from collections.abc import Sequence
from itertools import compress, islice, repeat
from pathlib import Path

import numpy as np

from ...errors import GearlabInputError, shown
from .base import UNIT_KEYS, Contents, _column, _keyed, _scalar, stated_units
from .rates import in_hz, key_of, named, scale_of

_COMMENT_FIELD = re.compile(r"^#\s*([A-Za-z_][\w.-]*)\s*[=:]\s*(.*?)\s*$")
# a field that is a number written with a decimal comma (a semicolon- or tab-separated European export)
_DECIMAL_COMMA = re.compile(r"^[+-]?\d*,\d+(?:[eE][+-]?\d+)?$")


# a field of a units row under the header, as loggers export one ('s', 'V', 'm/s²', '[g]', '(mV)')
_UNIT_FIELD = re.compile(r"^[\[(]?\s*[A-Za-zµμ°%/²³^*·.\-\d ]{0,12}\s*[\])]?$")


def units_row(row: list[str], names: list[str]) -> dict[str, str] | None:
    """{column: unit} of a row of units under the header (no number in it, every field a short unit, one at
    least), or None: a logger's export ('Time,accel,probe' then 's,V,V') was refused as 'its first data row
    holds no number'."""
    fields = [f.strip() for f in row]
    if len(fields) != len(names) or not any(fields):
        return None
    if any(_column([f]).dtype.kind == "f" or not _UNIT_FIELD.match(f) for f in fields):
        return None
    return {n: f.strip("[]() ") for n, f in zip(names, fields) if f.strip("[]() ")}


# a line of a logger's preamble above the table: 'Sample rate: 25600 Hz', 'Sampling Rate (kHz) = 25.6'
_PREAMBLE_FIELD = re.compile(r"^([A-Za-z][\w .\-]*?)\s*(?:[\[(]\s*([^\])]*?)\s*[\])])?\s*[:=]\s*(.*?)\s*$")
_PREAMBLE_VALUE = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-zµμ/]*)$")


def units_line(line: str) -> list[str] | None:
    """Each column's unit a preamble line lists in the table's separators ('Units: ms, g, g, V', as a logger writes
    one above its header), or None: its commas made it the header, and the file was refused ('column 'g' appears
    twice in the header')."""
    match = _PREAMBLE_FIELD.match(line.strip())
    separator = delimiter_of(line)
    if match is None or separator is None or match.group(1).strip().lower() not in UNIT_KEYS:
        return None
    fields = [f.strip() for f in match.group(3).split(separator)]
    if len(fields) < 2 or any(_column([f]).dtype.kind == "f" or not _UNIT_FIELD.match(f) for f in fields):
        return None
    return fields


def preamble(lines: list[str]) -> tuple[int, dict[str, object]]:
    """(how many of *lines* (non-blank, no '#') are a logger's preamble above the table, the fields it states).

    A preamble line has none of the table's separators (',', ';', tab) where a later line has one (a title,
    'Date: ...'), or is 'key: value' / 'key = value' above a blank-separated table. A rate ('Sample rate:
    25600 Hz', 'Sampling Rate (kHz): 25.6') becomes the field 'sample_rate' in Hz, as does a sample
    interval ('dt: 39.0625 us'); a line listing each column's unit ('Units: ms, g, g, V') the field 'units_row';
    other keys (a device, a date) are no channels and are left out."""
    listed = [units_line(line) if delimiter_of(line) is not None else None for line in lines[:100]]
    delimited = next(
        (i for i, line in enumerate(lines[:100]) if delimiter_of(line) is not None and listed[i] is None), None
    )
    fields: dict[str, object] = {}
    count = 0
    for i, line in enumerate(lines[:100]):
        match = _PREAMBLE_FIELD.match(line.strip())
        if listed[i] is not None and delimited is not None and i < delimited:
            fields["units_row"], count = listed[i], i + 1
            continue
        if (
            delimiter_of(line) is not None
            or (delimited is None and match is None)
            or (delimited is not None and i >= delimited)
        ):
            break
        count = i + 1
        if match is None:
            continue  # a title line
        if (rate := _rate_of(match)) is not None:
            fields["sample_rate"] = rate
        elif match.group(1).strip().lower() in UNIT_KEYS and match.group(3):  # 'Units: g': every column's
            fields["unit"] = match.group(3)
    if count == len(lines):  # no table after it: no preamble (a system file of 'name:value' lines is no record)
        return 0, {}
    return count, fields


def file_units(
    fields: dict[str, object], columns: Sequence[str], row: dict[str, str] | None = None, listed: list | None = None
) -> dict[str, str]:
    """{column: unit} that comment or preamble lines (*fields*) state for *columns*, read as every reader reads a
    stated unit (base.stated_units): every column's ('# units: g', 'Units: g') or one's ('# acc_unit = g'); over
    them each column's of a units row under the header (*row*, units_row's), else of a preamble's units line
    (*listed*: its fields, read as such a row). The one merge of a CSV's and a text's, header and run alike."""
    if row is None and listed is not None:
        row = units_row(listed, columns)
    return stated_units({k: v for k, v in fields.items() if isinstance(v, str)}, columns) | (row or {})


def _rate_of(match: re.Match) -> float | None:
    """The rate in Hz a preamble field (_PREAMBLE_FIELD's match) states, or None where it states none."""
    unit = (match.group(2) or "").strip()
    value = _PREAMBLE_VALUE.match(match.group(3))
    if value is None:
        return None
    unit = unit or value.group(2)
    # the one rule of a rate's unit (readers.rates): beside its name, after its value, or in its name
    found = scale_of(key_of(match.group(1)), unit) if unit else named(match.group(1))
    return None if found is None else in_hz(found, float(value.group(1)))


def comment_field(line: str) -> tuple[str, object] | None:
    """(key, value) a '#' comment line states, or None: '# fs = 51200' gives ('fs', 51200.0); a rate named in
    words or with its unit, as a preamble states one ('# Sample rate: 20 kHz', '# Sample rate [kHz]: 20'),
    ('sample_rate', Hz): a logger's '#'-prefixed preamble was refused as stating no rate."""
    text = line.strip()
    match = _COMMENT_FIELD.match(text)
    if match:
        return match.group(1), _scalar(match.group(2))
    words = _PREAMBLE_FIELD.match(text.lstrip("#").strip())
    rate = None if words is None else _rate_of(words)
    return None if rate is None else ("sample_rate", rate)


def delimiter_of(line: str) -> str | None:
    """The field separator of a delimited line: ';' or tab (whose fields may carry decimal commas),
    ',', or None for blanks."""
    for d in (";", "\t", ","):
        if d in line:
            return d
    return None


# separators whose fields may carry decimal commas: a German spreadsheet's 'Text (Tabstopp-getrennt)' export as much
# as its semicolon CSV (a tab-separated '0,25' was refused as 'its first data row holds no number')
DECIMAL_COMMA_SEPARATORS = (";", "\t")


def decoded(raw: bytes) -> str:
    """A text file's bytes as text: UTF-8 (a BOM dropped), else Windows-1252, which a Windows export (Excel's
    'CSV (Trennzeichen-getrennt)', a European logger) writes its header in: 'Beschleunigung [m/s²]' with '²' as byte
    0xB2 was refused as "'utf-8' codec can't decode byte 0xb2"."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        if b"\0" in raw:  # no text export holds a NUL: a binary file, refused as not UTF-8 (as before)
            raise
        return raw.decode("cp1252", "replace")


def encoding_of(path: Path) -> str:
    """The encoding decoded() reads *path*'s text in, from its first 64 kB (for a header read line by line)."""
    with open(path, "rb") as stream:
        head = stream.read(1 << 16)
    try:
        head.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 3 and b"\0" not in head:  # not a character cut at 64 kB, nor a binary file
            return "cp1252"
    return "utf-8-sig"


def split_rows(lines: list[str], delimiter: str | None) -> list[list[str]]:
    if delimiter is None:
        return [line.split() for line in lines]
    rows = [[f.strip() for f in row] for row in csv.reader(lines, delimiter=delimiter)]
    if delimiter in DECIMAL_COMMA_SEPARATORS:  # "0,25" is a number with a decimal comma here
        rows = [[f.replace(",", ".") if _DECIMAL_COMMA.match(f) else f for f in row] for row in rows]
    return rows


# a decimal comma not followed by a digit ('1,', '1,e3'): split_rows keeps such a field as text
_BARE_COMMA = re.compile(r",(?!\d)")


def numeric_block(lines: list[str], delimiter: str | None, width: int) -> np.ndarray | None:
    """The rows of *lines* as float64 columns (width x rows), parsed by numpy's C reader, or None where a
    field is not a plain number or a row's width differs: the caller then splits the rows field by field,
    whose columns and messages are the reference. The numbers are those of split_rows and float() on the
    same text (both correctly rounded); only unquoted lines reach here (one line is one row)."""
    if not lines:
        return None
    source = lines  # read as they are: a joined copy held a 69 MB CSV's 3 M rows twice more (290 MB at its peak)
    if delimiter in DECIMAL_COMMA_SEPARATORS and any("," in line for line in lines):
        block = "\n".join(lines)  # decimal commas: split_rows reads '0,25' and ',5' only
        if _BARE_COMMA.search(block):
            return None
        source = io.StringIO(block.replace(",", "."))
    try:
        values = np.loadtxt(source, dtype=np.float64, delimiter=delimiter, comments=None, ndmin=2)
    except ValueError:
        return None
    if values.shape != (len(lines), width):
        return None
    return np.ascontiguousarray(values.T)


def is_text(field: str) -> bool:
    """A field that holds something and no number (a footer's 'End of data', a label)."""
    return field != "" and _column([field]).dtype.kind != "f"


def footer_start(lines: list[str], delimiter: str | None, width: int) -> int | None:
    """Index in *lines* (the data lines, the first a row) of a logger's footer under the rows ('End of data',
    'Samples: 204800'), or None: the last lines that are no row, from the first of them that starts with text. A
    row has *width* fields, a number (or nothing) where the first row has one; a truncated row or one with a text
    cell ('0.4,n/a') above a footer stays the row parser's to refuse, as does a text line with rows under it. Read
    from the end: a file without a footer costs one line."""
    numeric = [not is_text(f) for f in split_rows(lines[:1], delimiter)[0]]
    start = None
    for i in range(len(lines) - 1, 0, -1):
        fields = split_rows([lines[i]], delimiter)[0]
        if len(fields) == width and not any(is_text(f) for f, n in zip(fields, numeric) if n):
            break
        if fields and is_text(fields[0]) and (numeric[0] or len(fields) != width):
            start = i
    return start


def footer_note(number: int, line: str, after: int) -> str:
    """The one warning of a footer left out: its first line (*number*, *line*), and how many follow it."""
    more = f" and the {after} line{'s' if after > 1 else ''} under it" if after else ""
    return f"line {number} {shown(line.strip())}{more}: no row of numbers (a logger's footer?); left out"


def is_header(row: list[str]) -> bool:
    """A first row is a header unless every field is a number."""
    return _column(row).dtype.kind != "f"


def header_names(header: list[str] | None, width: int) -> list[str]:
    return header if header is not None else [str(j) for j in range(width)]


def column_index(name: str, names: list[str]) -> int | None:
    """The column *name* stands for: a name of the header, or a 0-based index written in digits."""
    if name in names:
        return names.index(name)
    text = str(name).strip()
    if text.isdigit() and int(text) < len(names):
        return int(text)
    return None


def _without(numbers: Sequence[int], lines: list[str], dropped) -> tuple[Sequence[int], list[str]]:
    """(*numbers*, *lines*) less the lines *dropped* (a flag per line) marks."""
    kept = list(map(operator.not_, dropped))
    return list(compress(numbers, kept)), list(compress(lines, kept))


def _read_csv(path: Path, names: Sequence[str]) -> Contents:
    """Delimited columns with or without a header row, '#' comments ('# fs = 51200' gives a field 'fs')."""
    text = decoded(path.read_bytes())  # a BOM from spreadsheet exports is dropped
    fields: dict[str, object] = {}
    # every line that is not blank and its line number (a record has 10^5-10^6 lines): the text's own lines and
    # a range of numbers, each line tested and dropped by C's loops (map, compress), not a pass of Python per line
    lines = text.splitlines()
    line_numbers = range(1, len(lines) + 1)
    if "" in lines or any(map(str.isspace, lines)):
        line_numbers, lines = _without(
            line_numbers, lines, map(operator.or_, map(operator.not_, lines), map(str.isspace, lines))
        )
    if "#" in text:
        comments = list(map(str.startswith, map(str.lstrip, lines), repeat("#")))
        for line in compress(lines, comments):  # a field is a comment line's ('# fs = 51200')
            if (field := comment_field(line)) is not None:
                fields[field[0]] = field[1]
        line_numbers, lines = _without(line_numbers, lines, comments)
    skipped, stated = preamble(lines[:101])  # it reads 100 lines and asks for one more
    listed = stated.pop("units_row", None)
    fields.update(stated)
    line_numbers, lines = line_numbers[skipped:], lines[skipped:]
    if not lines:
        raise GearlabInputError(f"{path}: no rows; expected a header row of column names (or none), then numbers")
    delimiter = delimiter_of(lines[0])
    # without quotes (and NULs, which csv refuses) a line is a row: the first two tell the header and units
    # quotes in the first two lines alone (a DAQ's or spreadsheet's quoted names and units) leave each line a row
    odd = any(line.count('"') % 2 for line in lines[:2])  # a quoted name running over lines
    quoted = '"' in text and (odd or any(map(operator.contains, islice(lines, 2, None), repeat('"'))))
    plain = not quoted and "\0" not in text
    rows = split_rows(lines[:2] if plain else lines, delimiter)
    header = [h.strip() for h in rows[0]] if is_header(rows[0]) else None
    units = units_row(rows[1], header) if header is not None and len(rows) > 1 else None
    first_data = 1 + bool(units) if header is not None else 0
    listed = listed if header is not None else None  # the preamble's units line, read as the row under the names
    data_lines, data_numbers = lines[first_data:], line_numbers[first_data:]
    width = len(rows[0])
    warnings = []
    if (cut := footer_start(data_lines, delimiter, width) if data_lines else None) is not None:
        warnings.append(footer_note(data_numbers[cut], data_lines[cut], len(data_lines) - cut - 1))
        data_lines, data_numbers = data_lines[:cut], data_numbers[:cut]
    numbers = None
    # every line ending in separators (a spreadsheet's empty cells, ',,'): cut off, no channel, as the rows' parser does
    empty = next((i for i, f in enumerate(reversed(rows[0])) if f != ""), width)
    ends = (delimiter or "") * empty
    if plain and empty < width and (not empty or all(map(str.endswith, data_lines, repeat(ends)))):
        numbers = numeric_block(
            [line[: -len(ends)] for line in data_lines] if empty else data_lines, delimiter, width - empty
        )
    if numbers is not None:
        header, width = (None if header is None else header[: width - empty]), width - empty
        columns = header_names(header, width)
        if header is not None and len(set(header)) != len(header):
            _twice(path, header)
        return _contents(columns, fields, names, lambda j: numbers[j], (units, listed), warnings)
    if plain:
        rows = split_rows(lines, delimiter)
    data = rows[first_data : first_data + len(data_lines)]
    # every line ends in the separator, or in empty cells (a spreadsheet's columns once used): no channel
    while width > 1 and (header is None or header[-1] == "") and all(row[-1:] == [""] for row in data):
        header = header[:-1] if header is not None else None
        data = [row[:-1] for row in data]
        width -= 1
    if header is not None and len(set(header)) != len(header):
        _twice(path, header)
    for number, row in zip(data_numbers, data):
        if len(row) != width:
            raise ragged(path, number, len(row), width, header is not None, delimiter, bool(row) and is_text(row[0]))
    if not data:
        raise GearlabInputError(f"{path}: has a header but no data rows; expected one row per sample")
    if not any(_column(data[0][j : j + 1]).dtype.kind == "f" for j in range(width)):
        # not a measured record (a system file reached through a link?): nothing of it is quoted
        raise GearlabInputError(
            f"{path}: its first data row (line {data_numbers[0]}) holds no number; expected a header "
            "row of column names, then rows of numbers"
        )
    column = lambda j: _column([row[j] for row in data])  # noqa: E731
    return _contents(header_names(header, width), fields, names, column, (units, listed), warnings)


# why a row has more or fewer fields than the header: a comma-separated row of decimal commas ('0,25,1,5') splits each
# number in two, the first thing a European user's file meets (said before: 'a truncated or ragged file?')
_RAGGED_WHY = {
    False: "a truncated or ragged file?",
    True: "decimal commas in a comma-separated file? save it with ';' or tabs between the columns",
}


def ragged(
    path: Path, number: int, fields: int, width: int, header: bool, delimiter: str | None, text: bool = False
) -> GearlabInputError:
    """The error of a row of *fields* fields where the header (or the first row) has *width*; *text*: the row
    starts with text (a note amid the rows, where footer_start leaves out only the lines under the last row)."""
    why = "a note amid the rows? only a footer under the last row is left out" if text else None
    return GearlabInputError(
        f"{path}: line {number} has {fields} fields but the {'header' if header else 'first row'} has "
        f"{width}; expected one value per column ({why or _RAGGED_WHY[delimiter == ',' and fields > width]})"
    )


def _twice(path: Path, header: list[str]) -> None:
    twice = next(h for h in header if header.count(h) > 1)
    raise GearlabInputError(f"{path}: column '{twice}' appears twice in the header; expected distinct names")


def _contents(columns: list[str], fields: dict[str, object], names: Sequence[str], column, units, warnings) -> Contents:
    """The file's channels: *column(j)* gives the j-th column's values; a comment's field by its name; *units*: (the
    units row's, the preamble's units line) as file_units reads them; *warnings*: what the reader left out
    (footer_note)."""

    def get(name: str):
        j = column_index(name, columns)
        if j is not None:
            return column(j)
        return fields[name]

    # an index asked for ("0", "2") is found as that column, under the name it was asked by
    asked = [n for n in names if n not in columns and n not in fields and column_index(n, columns) is not None]
    contents = _keyed([*columns, *fields, *asked], get, names, listed=[*columns, *fields])
    contents.available = list(columns)  # a comment's or the preamble's field (its rate read above) is no channel
    contents.units.update(file_units(fields, columns, *units))
    contents.warnings += warnings
    return contents
