"""Delimited text, plain (.txt, .dat), gzipped (.gz) or one text file in a .zip (the PHM 2009 gearbox
records, a zipped CSV export): one row per sample, columns separated by blanks, commas, semicolons (their
numbers may carry decimal commas) or tabs, as the first data line shows; a header row of names or
none.

The text is read from the archive in blocks of ``CHUNK_BYTES`` and only the asked-for columns
are kept, so a 13 MB text needs about the size of those columns (plus one block), never the
whole text and its parsed table at once. The one memory limit of every measured file
(``GEARLAB_MAX_RECORD_MB``, gearlab.data.readers.base) holds here too: a text (or a zip member)
declaring more is refused before a byte is inflated, and the text read and the columns kept are
counted while streaming, so an archive that lies about its size is stopped at the limit too.
"""

from __future__ import annotations

import gzip
import itertools
import os
import re
import zipfile
from collections.abc import Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import numpy as np

from ...errors import GearlabInputError, shown
from .base import Contents, _keyed, channel_listing, check_size, max_record_bytes, time_scale
from .csv import (
    DECIMAL_COMMA_SEPARATORS,
    column_index,
    decoded,
    delimiter_of,
    file_units,
    footer_note,
    header_names,
    is_text,
    preamble,
    split_rows,
    units_row,
)

# Bytes of text parsed at a time: large enough for numpy to parse fast, small enough that
# a block's tokens (about 60 bytes each as Python objects) stay a few tens of MB.
CHUNK_BYTES = 1 << 18

# Whether only the asked-for columns' numbers are parsed (asked_numbers_only), not every number of each row
_asked_only: ContextVar[bool] = ContextVar("asked_only", default=False)


@contextmanager
def asked_numbers_only():
    """Text records read meanwhile have only their asked-for columns' numbers parsed: a row's other fields are
    counted, not checked to be numbers, so a text in which they are not reads here where read_columns would refuse
    it. For a check that reads one column of a take and confirms with the whole parse whatever it refuses
    (kinds.detection_screen: phm09_chip's validate, 24 zipped text takes' tachos, one column of three, 11.2 -> 8.0 s
    of CPU)."""
    token = _asked_only.set(True)
    try:
        yield
    finally:
        _asked_only.reset(token)


def asked_only() -> bool:
    """Whether text records are read under asked_numbers_only (parsed() keeps such contents apart)."""
    return _asked_only.get()


# --- reading the columns -----------------------------------------------------------------


@contextmanager
def _open_text(path: Path):
    """A binary stream of the record's text: the one text member of a .zip, a .gz's text, or the file."""
    try:
        if path.suffix.lower() == ".gz":
            with path.open("rb") as raw:  # its size as the gzip trailer declares it (mod 4 GiB)
                raw.seek(max(0, os.fstat(raw.fileno()).st_size - 4))
                check_size(path, "the text (as the gzip declares it)", int.from_bytes(raw.read(4), "little"))
            with gzip.open(path, "rb") as f:
                yield f, str(path)
            return
        if path.suffix.lower() != ".zip":
            with path.open("rb") as f:
                check_size(path, "the text", os.fstat(f.fileno()).st_size)
                yield f, str(path)
            return
        with zipfile.ZipFile(path) as z:
            members = [i for i in z.infolist() if not i.is_dir() and not i.filename.startswith("__MACOSX/")]
            if len(members) != 1:
                names = ", ".join(shown(i.filename, 40) for i in members[:5]) or "none"
                raise GearlabInputError(
                    f"{path}: expected a zip archive of exactly one text file, found {len(members)} ({names})"
                )
            info = members[0]
            # declared: a few kB of deflated zeros may announce gigabytes (a zip bomb)
            check_size(path, f"member {shown(info.filename)} (as its archive declares it)", info.file_size)
            with z.open(info) as f:
                yield f, f"{path}: member {shown(info.filename)}"
    except FileNotFoundError:
        raise GearlabInputError(
            f"{path}: no such file; expected a measured record (.zip of one text file, or the text)"
        ) from None
    except IsADirectoryError:
        raise GearlabInputError(f"{path}: is a directory; expected a measured record") from None
    except zipfile.BadZipFile as exc:
        raise GearlabInputError(f"{path}: not a readable zip archive ({exc})") from None
    except gzip.BadGzipFile as exc:
        raise GearlabInputError(f"{path}: not a readable gzip file ({exc})") from None
    except (OSError, EOFError, zipfile.LargeZipFile, NotImplementedError, RuntimeError) as exc:
        # a truncated archive, an encrypted member, an unsupported compression
        raise GearlabInputError(f"{path}: cannot read ({exc})") from None


def _preamble(path: Path) -> tuple[int, dict[str, object]]:
    """(lines of a logger's preamble above the table, the rate it states): csv.preamble over the first lines."""
    with _open_text(path) as (stream, _):
        lines = []
        for raw in stream:
            text = raw.decode("utf-8-sig", "replace")
            if text.strip() and not text.lstrip().startswith("#"):
                lines.append(text)
            if len(lines) >= 100:
                break
    return preamble(lines)


def _is_number(token: bytes) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _blanks(text: bytes, delimiter: str | None) -> bytes:
    """Rows of *delimiter*-separated numbers as blank-separated ones, which numpy parses fast.
    A semicolon's or tab's fields may hold decimal commas ("0,25"): there a comma is never a separator."""
    if delimiter in DECIMAL_COMMA_SEPARATORS:
        return text.replace(b",", b".").replace(delimiter.encode(), b" ")
    if delimiter == ",":
        return text.replace(b",", b" ")
    return text  # tabs and blanks: bytes.split() takes both


def _fields(line: bytes, delimiter: str | None) -> list[str]:
    """A header line's names: delimited fields (quoted ones may hold blanks or commas), or blank-separated."""
    text = decoded(line).strip()
    return split_rows([text], delimiter)[0] if delimiter else text.split()


def _delimiter(block: bytes, skip: int = 0) -> str | None:
    """The separator the first data line of *block* after *skip* preamble lines uses (None: blanks)."""
    for line in block.split(b"\n"):
        if line.strip() and not line.lstrip().startswith(b"#"):
            if skip:
                skip -= 1
                continue
            return delimiter_of(line.decode("utf-8", "replace"))
    return None


def _resolve(columns, header: list[str] | None, width: int, where: str) -> list[int]:
    """Column indices of the asked-for columns (0-based index or header name)."""
    out = []
    for c in columns:
        if isinstance(c, bool):
            raise GearlabInputError(f"{where}: column {c!r}: expected a 0-based index or a column name")
        if isinstance(c, str) and c.strip().isdigit():
            c = int(c)
        if isinstance(c, int):
            if not 0 <= c < width:
                raise GearlabInputError(
                    f"{where}: column {c} does not exist; the file has {width} columns "
                    f"(0-based indices 0 … {width - 1})"
                )
            out.append(c)
        elif header is not None and c in header:
            out.append(header.index(c))
        else:
            known = channel_listing(header) if header else f"no header row, so indices 0 … {width - 1}"
            raise GearlabInputError(f"{where}: no column named {shown(c)}; known: {known}")
    return out


_BLANK_LINE = re.compile(rb"\n[ \t\r\f\v]*\n")  # a blank line between two others


def _rows(body: bytes) -> int:
    """The lines of *body* that hold more than blanks: its lines, counted in C, where none is blank
    (a record's block); else line by line. A line ending in "\r\n" (a Windows text, the PHM 2009
    records) is one line: bytes.split() takes the "\r" for a blank."""
    text = body.strip()  # blank lines at either end hold no row
    if not text:
        return 0
    if _BLANK_LINE.search(text) is None:
        return text.count(b"\n") + 1
    return sum(1 for line in body.split(b"\n") if line.strip())


def _first_bad(block: bytes, width: int, passed: int) -> tuple[int, int] | None:
    """(line offset in *block* (blanked: _blanks), rows above it) of its first line that is not *width* numbers,
    after its first *passed* data lines (a preamble's, the header), or None."""
    rows = 0
    for offset, line in enumerate(block.split(b"\n")):
        tokens = line.split()
        if not tokens or tokens[0].startswith(b"#"):
            continue
        if passed:
            passed -= 1
            continue
        if len(tokens) != width or not all(map(_is_number, tokens)):
            return offset, rows
        rows += 1
    return None


def _bad_line(block: bytes, first_line: int, width: int, where: str, passed: int = 0) -> GearlabInputError:
    """The error for the first line of *block* that is not *width* numbers (slow path), after its first *passed*
    data lines (a preamble's, the header: a tab text's dropout 'n/a' on line 502 was told as line 1's 'time')."""
    bad = _first_bad(block, width, passed)
    if bad is None:  # pragma: no cover
        return GearlabInputError(f"{where}: unreadable numbers near line {first_line}")
    tokens, number = block.split(b"\n")[bad[0]].split(), first_line + bad[0]
    if len(tokens) != width:
        return GearlabInputError(
            f"{where}: line {number} has {len(tokens)} fields, expected {width} (as the first data line)"
        )
    i, text = next((i, t.decode("utf-8", "replace")) for i, t in enumerate(tokens) if not _is_number(t))
    return GearlabInputError(f"{where}: line {number} column {i}: {shown(text)} is not a number")


def _footer(block: bytes, offset: int, width: int, delimiter: str | None, later) -> tuple[str, int] | None:
    """(first line, lines after it) of a logger's footer starting at line *offset* of *block* (as read, not
    blanked), or None: a footer's first line starts with text and no row of *width* numbers follows it in *block*
    or in *later* (the text's further lines, read only here). A truncated row, or one with a text cell ('4 n/a 6'),
    is no footer."""
    lines = block.split(b"\n")[offset:]
    if not is_text(split_rows([decoded(lines[0])], delimiter)[0][0]):  # as a CSV's (csv.footer_start)
        return None
    after = 0
    for line in itertools.chain(lines[1:], later):
        tokens = _blanks(line, delimiter).split()
        if not tokens or tokens[0].startswith(b"#"):
            continue
        if len(tokens) == width and all(map(_is_number, tokens)):
            return None
        after += 1
    return decoded(lines[0]).strip(), after


def _lines(rest: bytes, stream, where: str, read: int):
    """The lines of *rest* and what is left of *stream* (of which *read* bytes are read), against the size limit."""
    while data := stream.read(CHUNK_BYTES):
        read += len(data)
        if read > max_record_bytes():
            check_size(where, "the text read so far", read)
        *lines, rest = (rest + data).split(b"\n")
        yield from lines
    yield rest


def _rows_above(body: bytes, rows: int) -> bytes:
    """The first *rows* lines of *body* that hold tokens (its rows above a footer)."""
    kept = [line for line in body.split(b"\n") if line.split() and not line.lstrip().startswith(b"#")]
    return b"\n".join(kept[:rows])


def _asked_values(body: bytes, width: int, picked: list[int]) -> np.ndarray | None:
    """The *picked* columns of *body*'s rows (blanked: _blanks), only their fields parsed, as read_columns' whole
    parse gives them; None where its fields are not rows of *width* or a picked one is no number (read_columns then
    parses the block whole: a footer, or the line it refuses)."""
    tokens = body.split()
    rows = _rows(body)
    if len(tokens) != rows * width:
        return None
    try:
        return np.column_stack([np.array(tokens[c::width], dtype=np.float64) for c in picked])
    except ValueError:
        return None


def read_columns(path, columns, warnings: list[str] | None = None) -> tuple[dict, list[str] | None, int]:
    """The asked-for columns of a whitespace-separated text (or a .zip of one), streamed.

    Returns ({column as asked: float64 array}, header names or None, number of columns).
    Blank lines and lines starting with '#' are skipped; a first data line that is not all
    numbers is the header of column names; a logger's footer under the rows is left out, said in
    *warnings* (csv.footer_note).
    """
    warnings = [] if warnings is None else warnings
    path = Path(path)
    columns = list(dict.fromkeys(columns))
    parts: list[np.ndarray] = []
    header: list[str] | None = None
    width = 0
    picked: list[int] = []
    delimiter: str | None = None
    under_header = False  # the next data line follows the header: a row of units there is none of the data
    skip = _preamble(path)[0]  # a logger's lines above the table
    limit = max_record_bytes()
    text_bytes, kept_bytes = 0, 0  # of text read and of columns kept, against the limit
    with _open_text(path) as (stream, where):
        line_no = 1  # number of the first line of the pending block
        rest = b""
        while True:
            data = stream.read(CHUNK_BYTES)
            text_bytes += len(data)
            if text_bytes > limit:  # more than declared (a lying archive, a file that grows)
                check_size(where, "the text read so far", text_bytes)
            block = rest + data
            if data:
                cut = block.rfind(b"\n") + 1
                if cut == 0:  # one line longer than a block: read on
                    rest = block
                    if len(rest) > 64 * CHUNK_BYTES:
                        raise GearlabInputError(
                            f"{where}: line {line_no} is longer than {64 * CHUNK_BYTES} bytes; "
                            "expected rows of a few numbers"
                        )
                    continue
                block, rest = block[:cut], block[cut:]
            elif not block:
                break
            else:
                rest = b""
            lines_here = block.count(b"\n") + (0 if block.endswith(b"\n") else 1)
            if not width:
                delimiter = _delimiter(block, skip)
            passed = 0  # the block's lines above its rows (a preamble's, the header)
            if b"#" in block or block.count(b"\r") != block.count(b"\r\n") or not width or under_header:
                kept = []
                for line in block.split(b"\n"):
                    tokens = _blanks(line, delimiter).split()
                    if not tokens or tokens[0].startswith(b"#"):
                        continue
                    if skip:
                        skip, passed = skip - 1, passed + 1
                        continue
                    if not width:  # the first data line: a header, or the first row
                        if not all(_is_number(t) for t in tokens):
                            header = _fields(line, delimiter)
                            width, passed, under_header = len(header), passed + 1, True
                            continue
                        width = len(tokens)
                    elif under_header:
                        under_header = False
                        if not all(map(_is_number, tokens)) and units_row(_fields(line, delimiter), header):
                            passed += 1  # as first_row reads it (its units)
                            continue
                    kept.append(_blanks(line, delimiter))
                body = b"\n".join(kept)
                if width and not picked:
                    picked = _resolve(columns, header, width, where)
            else:
                body = _blanks(block, delimiter)
            asked = _asked_values(body, width, picked) if _asked_only.get() and body.strip() else None
            if asked is not None:
                parts.append(asked)
                kept_bytes += asked.nbytes
                if kept_bytes > limit:
                    check_size(where, "the columns read so far", kept_bytes)
            elif body.strip():
                try:
                    values = np.array(body.split(), dtype=np.float64)
                except ValueError:
                    values = np.empty(0)
                rows = _rows(body)
                if values.size != rows * width:
                    bad = _first_bad(_blanks(block, delimiter), width, passed)
                    later = _lines(rest, stream, where, text_bytes)
                    found = None if bad is None else _footer(block, bad[0], width, delimiter, later)
                    if found is None:
                        raise _bad_line(_blanks(block, delimiter), line_no, width, where, passed)
                    warnings.append(footer_note(line_no + bad[0], found[0], found[1]))
                    rows, data = bad[1], b""  # the rows above it, the last read
                    values = np.array(_rows_above(body, rows).split(), dtype=np.float64)
                parts.append(values.reshape(rows, width)[:, picked].copy())
                kept_bytes += parts[-1].nbytes
                if kept_bytes > limit:  # short rows of many numbers: the columns outgrow their text
                    check_size(where, "the columns read so far", kept_bytes)
            line_no += lines_here
            if not data:
                break
    if not parts:
        raise GearlabInputError(
            f"{where}: no rows of numbers; expected one row per sample, columns separated by blanks"
        )
    table = np.concatenate(parts) if len(parts) > 1 else parts[0]
    return {c: table[:, i] for i, c in enumerate(columns)}, header, width


def first_row(path) -> tuple[list[str] | None, int, dict[str, str] | None]:
    """(header names or None, number of columns, each column's unit a row of units under the header states or
    None) from the first data lines of a text record, without reading the rest."""
    path = Path(path)
    header, units = None, None
    skip = _preamble(path)[0]  # a logger's lines above the table
    with _open_text(path) as (stream, where):
        delimiter = None
        for number, line in enumerate(stream, start=1):
            if skip and line.strip() and not line.lstrip().startswith(b"#"):
                skip -= 1
                continue
            if header is None and line.strip() and not line.lstrip().startswith(b"#"):
                delimiter = delimiter_of(line.decode("utf-8", "replace"))
            tokens = _blanks(line, delimiter).split()
            if not tokens or tokens[0].startswith(b"#"):
                continue
            if all(_is_number(t) for t in tokens):
                return header, len(tokens) if header is None else len(header), units
            if header is not None and units is None and (units := units_row(_fields(line, delimiter), header)):
                continue  # a logger's row of units under the names ('s', 'V', 'm/s²'), as a CSV's
            if header is not None:  # not a record (a system file?): nothing of it is quoted
                raise GearlabInputError(
                    f"{where}: its first data row (line {number}) holds no number; expected a header row "
                    "of column names, then rows of numbers separated by blanks"
                )
            header = _fields(line, delimiter)
    raise GearlabInputError(f"{where}: no rows of numbers; expected one row per sample, columns separated by blanks")


def comment_fields(path) -> dict[str, object]:
    """The '# key = value' lines above a text record's first row ('# fs = 48000' gives a field 'fs'), as a
    CSV's are read."""
    from .csv import comment_field

    skip, fields = _preamble(Path(path))  # a logger's preamble states a rate too
    with _open_text(Path(path)) as (stream, _):
        for line in stream:
            text = line.decode("utf-8-sig", "replace").strip()
            if not text:
                continue
            if not text.startswith("#") and skip:
                skip -= 1
                continue
            if not text.startswith("#"):
                break
            if (field := comment_field(text)) is not None:
                fields[field[0]] = field[1]
    return fields


def _read_text(path: Path, names: Sequence[str]) -> Contents:
    """The asked-for columns (by header name or 0-based index), any time column and '# key = value' lines."""
    header, width, row = first_row(path)
    columns = header_names(header, width)
    fields = {k: v for k, v in comment_fields(path).items() if k not in columns}
    listed = fields.pop("units_row", None)  # a preamble's 'Units: s<TAB>g<TAB>V': each column's, as in a CSV
    wanted = [n for n in dict.fromkeys(names) if column_index(n, columns) is not None]
    wanted += [c for c in columns if time_scale(c) is not None and c not in wanted]
    found, warnings = {}, []
    if wanted:
        read, _, _ = read_columns(path, [column_index(n, columns) for n in wanted], warnings)
        found = {n: read[column_index(n, columns)] for n in wanted}
    asked = [n for n in wanted if n not in columns]
    contents = _keyed(
        [*columns, *fields, *asked], lambda n: found[n] if n in found else fields[n], names, [*columns, *fields]
    )
    contents.available = list(columns)  # a comment's or the preamble's field (its rate read above) is no channel
    contents.units.update(file_units(fields, columns, row, listed))
    contents.warnings += warnings
    return contents
