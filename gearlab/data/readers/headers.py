"""What each format says of a file before its data is read (`gearlab validate`,
gearlab.data.recordings.check_recording): its channels, whether it carries a sampling rate (a
field or a time vector), which channels hold integers."""

from __future__ import annotations

import csv
import itertools
import math
import re
import struct
import warnings
import zipfile
from contextvars import ContextVar
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ...errors import GearlabInputError
from .base import is_rate_or_time, matrix_column, not_time, stated_units
from .rates import SECONDS_PER_DAY, in_hz, key_of, named, scale_of, serial_days, stated_hz


@dataclass(frozen=True)
class Header:
    """What a file says of itself before its data is read: its channels (rate and time fields
    included; a text's comment and preamble fields are none), whether it carries a rate (a field or a
    time vector), and its integer channels."""

    format: str
    channels: list[str]
    rate: bool
    integer: frozenset[str] = frozenset()
    indexed: bool = False  # channels may be named by 0-based column index (text formats)
    units: dict[str, str] = field(default_factory=dict)  # a unit a channel states (Contents.units)
    nested: bool = False  # channels are paths ("group/acc"), found by their last part alone too
    stated: tuple[float, str] | None = None  # the rate the header states (Hz) and where: a WAV's, an attribute
    stated_within: float = 1e-6  # relative: a rate read off a text's printed times is known to their digits
    shapes: dict[str, tuple] = field(default_factory=dict)  # each array's shape, where the header gives it
    frames: int | None = None  # samples per channel, where the header says (a WAV's data chunk)

    def seconds(self, name: str, fs: float | None) -> float | None:
        """How long channel *name* runs, from the header alone (a WAV's frames; an HDF5, npz or MAT array's shape)
        at *fs* (Hz, given) or the rate the header states; None where the header gives no length or rate (a
        text file: its rows are not counted here)."""
        fs = fs if fs is not None else (self.stated[0] if self.stated is not None else None)
        shape = self.shapes.get(self.resolve(name))
        samples = self.frames if self.frames is not None else (max(shape) if shape else None)
        return samples / fs if samples and fs and fs > 0 else None

    def check_rate(self, fs: float | None, where: str, path) -> None:
        """A rate given (*fs*, Hz) that the header's own contradicts: one line naming *where*'s 'fs'
        (a WAV at 48 kHz or an HDF5 'fs' attribute against `fs = "50 kHz"`: validate said OK); none given,
        one the header holds that cannot be a rate (check_rates)."""
        self.check_rates(fs, where, path)
        if fs is None or self.stated is None or abs(fs - self.stated[0]) <= self.stated_within * self.stated[0]:
            return
        from ...signals.checks import fmt_hz

        raise GearlabInputError(
            f"{where} key 'fs': {fmt_hz(fs)} given, but {path} says {fmt_hz(self.stated[0])} ({self.stated[1]}); "
            "expected the file's own rate, or no 'fs'"
        )

    def check_channel(self, name: str, where: str, path) -> None:
        """A channel that is the time or rate column (not_time), or that the header shows is no series (an HDF5
        (N, 2) array, a single value): one line naming *where*."""
        not_time((name,), self.channels, path, where)
        shape = self.shapes.get(name)
        if shape is not None and (sum(n > 1 for n in shape) > 1 or math.prod(shape) <= 1):
            held = "a single value" if math.prod(shape) <= 1 else f"an array of shape {shape}"
            raise GearlabInputError(
                f"{where}: {path}'s '{name}' holds {held}; expected one channel over time (a 1-D array)"
                + (f", e.g. one of its columns: '{name}[0]' … '{name}[{min(shape) - 1}]'" if len(shape) == 2 else "")
            )

    def check_rates(self, fs: float | None, where: str, path) -> None:
        """A rate the header holds that cannot be one (an 'fs' of several values, 0 Hz), where no *fs* given
        replaces it: one line naming *where*'s 'fs' (validate said OK; the run refused it)."""
        if fs is not None:
            return
        for name, shape in self.shapes.items():
            if named(name.rsplit("/", 1)[-1]) is not None and math.prod(shape) != 1:
                raise GearlabInputError(
                    f"{where} key 'fs': {path}'s rate field {name!r} holds {math.prod(shape)} values; expected one "
                    "rate in Hz (or fs = '...' here)"
                )
        if self.stated is not None and not self.stated[0] > 0:
            raise GearlabInputError(
                f"{where} key 'fs': {path} states a rate of {self.stated[0]:g} Hz ({self.stated[1]}); expected a "
                "positive rate in Hz (or fs = '...' here)"
            )

    def find(self, name: str) -> bool:
        if name in self.channels or self.resolve(name) in self.channels:
            return True
        if (column := matrix_column(name)) is not None and (self.find(column[0]) or column[0] in self.shapes):
            return self.not_a_column(name) is None
        return self.indexed and str(name).strip().isdigit() and int(name) < len(self.channels)

    def not_a_column(self, name: str) -> str | None:
        """Why *name*, a channel named as a matrix's column ('data[2]') of a channel the file has, is none,
        from the header's shapes ('its 'data' holds 2 channels ...; expected ...'), or None where it is one
        (or the header gives no shape: the run decides)."""
        array, index = matrix_column(name)
        shape = self.shapes.get(self.resolve(array))
        if shape is None and self.indexed:  # a text column, a WAV channel: one series each
            return f"'{array}' is one column, not a matrix of channels; expected '{array}'"
        if shape is None or (len(shape) == 2 and index < min(shape)):
            return None
        if len(shape) != 2:
            return f"'{array}' holds an array of shape {shape}, not a matrix of channels (N x k)"
        last = min(shape) - 1
        return f"'{array}' holds {last + 1} channels; expected '{array}[0]' … '{array}[{last}]'"

    def resolve(self, name: str) -> str:
        """The channel as the file names it: a nested file's "acc" is its one "group/acc"."""
        if name in self.channels or not self.nested:
            return name
        if self.format == "MATLAB" and str(name).replace(".", "/") in self.channels:
            return str(name).replace(".", "/")  # a struct's field as MATLAB writes it: rec.acc
        from .hdf5 import leaf_match

        return leaf_match(self.channels, str(name)) or name


# The end of a plain text record `gearlab validate` reads for a logger's footer (its summary lines under the rows),
# and the files whose footer it said (footers_said): the run's reader leaves one out with a warning, which validate,
# reading headers only, gave none of
TAIL_BYTES = 8192
_footers: ContextVar[set | None] = ContextVar("footers", default=None)


def footers_said(call):
    """*call*() with each plain CSV or text record whose header it reads read at its tail too (tail_footer): a
    footer the run's reader will leave out is warned of, once a file (`gearlab validate`)."""
    token = _footers.set(set())
    try:
        return call()
    finally:
        _footers.reset(token)


def validating() -> bool:
    """Whether a scenario is read under footers_said (`gearlab validate`, the TUI's Validate): the checks that read a
    measured file past its header run then, not where a run, the TUI's tree or a comparison reads the scenario (a
    detection history's tachos, kinds.detection_screen: 4-5 s of phm09_chip's 8 zipped text takes, which a run reads
    whole anyway)."""
    return _footers.get() is not None


def _say_footer(path: Path, width: int) -> None:
    said = _footers.get()
    if said is None or path in said:
        return
    said.add(path)
    if note := tail_footer(path, width):
        warnings.warn(f"{path}: {note}", stacklevel=2)


def tail_footer(path: Path, width: int) -> str | None:
    """The warning the reader gives a logger's footer under the rows of the plain text record *path* (csv.footer_note:
    its first line's number, the lines under it), read off its last TAIL_BYTES, or None: the rows there of *width*
    fields, the first of them the template of the numeric columns, as csv.footer_start reads the whole file."""
    from .csv import delimiter_of, encoding_of, footer_note, footer_start, is_text, split_rows

    encoding = encoding_of(path)
    size = path.stat().st_size
    start = max(0, size - TAIL_BYTES)
    with path.open("rb") as stream:
        stream.seek(start)
        block = stream.read()
    if start:  # its first line may be cut
        block = block[block.find(b"\n") + 1 :]
        start = size - len(block)
    lines = block.decode(encoding, errors="replace").splitlines()
    kept = [(i, line) for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    delimiter = delimiter_of(kept[0][1]) if kept else None
    rows = split_rows([line for _, line in kept], delimiter)
    first = next((q for q, row in enumerate(rows) if len(row) == width and not is_text(row[0])), None)
    if first is None:
        return None
    cut = footer_start([line for _, line in kept[first:]], delimiter, width)
    if cut is None:
        return None
    number, line = kept[first + cut]
    before = 0
    with path.open("rb") as stream:  # the lines above the tail, counted where there is a footer to number
        while start > 0 and (chunk := stream.read(min(1 << 20, start))):
            before, start = before + chunk.count(b"\n"), start - len(chunk)
    return footer_note(before + number + 1, line, len(kept) - first - cut - 1)


def _csv_header(path: Path) -> Header:
    from .base import _column
    from .csv import (
        comment_field,
        delimiter_of,
        encoding_of,
        file_units,
        header_names,
        is_header,
        preamble,
        ragged,
        split_rows,
        units_row,
    )

    fields, names, number, units = [], None, 0, None
    with path.open(encoding=encoding_of(path), errors="replace") as stream:
        ahead = list(itertools.islice(stream, 200))  # a logger's preamble lies within its first lines
        skipped, stated_fields = preamble([line for line in ahead if line.strip() and not line.strip().startswith("#")])
        listed = stated_fields.pop("units_row", None)  # a preamble's 'Units: ms, g, g, V': as a units row under it
        fields += [(k, v) for k, v in stated_fields.items()]
        f = itertools.chain(ahead, stream)
        for number, line in enumerate(f, start=1):
            stripped = line.strip()
            if skipped and stripped and not stripped.startswith("#"):
                skipped -= 1
                continue
            if stripped.startswith("#"):
                if (field := comment_field(stripped)) is not None:
                    fields.append(field)
                continue
            if not stripped:
                continue
            row = split_rows([line], delimiter_of(line))[0]
            if names is None and is_header(row):
                names = header_names(row, len(row))  # quoted only once a row of numbers follows
                continue
            if names is not None and units is None and (units := units_row(row, names)) is not None:
                continue  # a logger's row of units under the names ('s', 'V', 'm/s²')
            if not any(_column(row[j : j + 1]).dtype.kind == "f" for j in range(len(row))):
                # not a measured record (a system file reached through a link?): nothing of it is quoted
                raise GearlabInputError(
                    f"{path}: its first data row (line {number}) holds no number; expected a header "
                    "row of column names, then rows of numbers"
                )
            while len(row) > 1 and row[-1:] == [""]:  # every line ends in separators (a spreadsheet's): no channel
                names = names[:-1] if names is not None and names[-1:] == [""] else names
                row = row[:-1]
            if names is not None and len(row) > len(names) and delimiter_of(line) == ",":
                # decimal commas in a comma-separated export split every number: the run would refuse it
                raise ragged(path, number, len(row), len(names), True, ",")
            names = names if names is not None else header_names(None, len(row))
            stated = _stated_rate(f, line, names, _rate_fields(fields))
            break
        else:
            raise GearlabInputError(
                f"{path}: no rows of numbers; expected a header row of column names (or none), then numbers"
            )
    rate = any(is_rate_or_time(n) for n in [*names, *(k for k, _ in fields)])  # a field's rate, no channel's
    _say_footer(path, len(names))
    units = file_units(dict(fields), names, units, listed)  # as the run's reader merges them
    return Header("CSV", names, rate, indexed=True, stated=stated[0], stated_within=stated[1], units=units)


def _stated_rate(lines, first: str, names: list[str], rates: list) -> tuple:
    """(the rate a CSV states (Hz, where) or None, how closely): a '# fs = ...' line's, else its time
    column's over the first rows (*first*, then up to 2,000 more of *lines*), known to the digits its times
    are printed with (a 25.6 kHz record's times in ms to 1e-4 ms: 1e-5 of the rate over 2,000 rows)."""
    from .base import _column, time_scale
    from .csv import delimiter_of, split_rows

    for key, value in rates:
        return (None if value is None else (value, f"its '# {key}' line")), 1e-6
    column = next((j for j, n in enumerate(names) if time_scale(n) is not None), None)
    if column is None:
        return None, 1e-6
    texts = [first, *(line for _, line in zip(range(2000), lines) if line.strip() and not line.startswith("#"))]
    rows = split_rows(texts, delimiter_of(first))
    fields = [row[column] for row in rows if len(row) > column]
    t = _column(fields)
    if t.dtype.kind != "f" or t.size < 3 or not np.all(np.diff(t) > 0):
        return None, 1e-6
    day = SECONDS_PER_DAY if serial_days(t) else 1.0  # Excel's serial days, as the run reads them
    spacing = float(np.spacing(np.abs(t).max()))  # digits printed past a double's own (46357.416666666664)
    t = (t - t[0]) * day
    span = t[-1] - t[0]
    step = span / (t.size - 1)
    if np.max(np.abs(t - t[0] - step * np.arange(t.size))) > step / 2:  # not a uniform clock
        return None, 1e-6
    digits = max(len(f.partition(".")[2].partition("e")[0].partition("E")[0]) for f in fields)
    where = f"its time column {names[column]!r}{' in Excel serial days' * (day != 1)}, first {t.size} rows"
    return (1.0 / (step * time_scale(names[column])), where), max(1e-6, 2 * max(10.0**-digits, spacing) * day / span)


def _rate_fields(fields) -> list[tuple[str, float | None]]:
    """(key, the rate in Hz or None where its value is no number) of a text's comment fields that are rates or
    intervals (rates.stated_hz: '# fs = 51200', '# fs_kHz = 25.6')."""
    return [(k, stated_hz(k, v)) for k, v in fields if named(k) is not None]


def _text_header(path: Path, fmt: str) -> Header:
    from .csv import file_units, header_names
    from .text import comment_fields, first_row

    header, width, row = first_row(path)
    names = header_names(header, width)
    fields = {k: v for k, v in comment_fields(path).items() if k not in names}
    listed = fields.pop("units_row", None)  # a preamble's units line: each column's, as in a CSV
    rates = _rate_fields(fields.items())
    stated = None
    if rates and rates[0][1] is not None:
        stated = (rates[0][1], f"its '# {rates[0][0]}' line")
    if fmt == "text":  # a zipped text's tail is no cheap read
        _say_footer(path, width)
    rate = any(is_rate_or_time(n) for n in [*names, *fields])  # a comment field's rate, no channel's
    units = file_units(fields, names, row, listed)  # as the run's reader merges them
    return Header(fmt, names, rate, indexed=True, stated=stated, units=units)


def _npz_header(path: Path) -> Header:
    from .npz import _member_header, npz_units

    with zipfile.ZipFile(path) as archive:
        members = [i.filename for i in archive.infolist() if i.filename.endswith(".npy")]
        headers = {m[:-4]: _member_header(archive, m) for m in members}
    shapes = {n: shape for n, (shape, _) in headers.items()}
    integer = frozenset(n for n, (_, dtype) in headers.items() if dtype.kind in "iu")
    numbers = {n: dtype.kind in "iuf" for n, (_, dtype) in headers.items()}
    stated = _rate_variable({n: s for n, s in shapes.items() if numbers[n]}, lambda n: np.load(path)[n])
    units = npz_units(headers, lambda n: np.load(path)[n])
    names = [n for n in headers if n not in units["texts"]]
    rate = any(is_rate_or_time(n) for n in names)
    return Header("NPZ", names, rate, integer, shapes=shapes, stated=stated, units=units["units"])


def _hdf5_header(path: Path, fmt: str = "HDF5") -> Header:
    from .base import stated_unit
    from .hdf5 import _h5py, _hdf5_datasets, named_columns, named_matrices, text_units

    h5py = _h5py()
    with h5py.File(path, "r") as f:
        names = _hdf5_datasets(h5py, f)
        said, texts = text_units(h5py, f, {n: n for n in names}, names)
        names = [n for n in names if n not in texts]
        integer = {n for n in names if f[n].dtype.kind in "iu"}
        units = said | {n: unit for n in names if (unit := stated_unit(f[n].attrs)) is not None}
        rate = any(is_rate_or_time(n.rsplit("/", 1)[-1]) for n in names)
        # an 'fs' attribute anywhere (on a dataset or a group) is a rate field of what lies under it
        rate = rate or any(is_rate_or_time(k) for n in ["/", *names] for k in f[n].attrs)
        groups = set()
        for n in names:
            parts = n.split("/")[:-1]
            groups.update("/".join(parts[: i + 1]) for i in range(len(parts)))
        rate = rate or any(is_rate_or_time(k) for g in groups for k in f[g].attrs)
        stated = None
        for n in ["/", *sorted(groups), *names]:
            for k, v in f[n].attrs.items():
                if np.asarray(v).dtype.kind in "iuf" and (hz := stated_hz(str(k), v)) is not None:
                    stated = stated or (hz, f"attribute {k!r} of {n!r}")  # in Hz, a unit in its name read
        shapes = {n: tuple(f[n].shape) for n in names}
        stated = stated or _rate_variable(shapes, lambda n: f[n][()])
        columns = named_columns(f, names)
        names = [n for n in names if n not in named_matrices(shapes, columns)]  # its shape kept: 'data[1]' found
        for name, (matrix, i, unit) in columns.items():  # a DAQ's (N, k) 'data' names its columns
            names.append(name)
            shapes[name] = (max(shapes[matrix]),)
            units.update({name: unit, f"{matrix}[{i}]": unit} if unit else {})
    return Header(fmt, names, rate, frozenset(integer), units=units, nested=True, stated=stated, shapes=shapes)


WAV_CODINGS = (1, 3)  # PCM, IEEE float: what the WAV reader (scipy) decodes
WAV_CODINGS_SEEN = {2: "Microsoft ADPCM", 6: "A-law", 7: "mu-law", 17: "IMA ADPCM", 85: "MP3"}


def _wav_header(path: Path) -> Header:
    """Channels, rate and sample format from the RIFF 'fmt ' chunk; a 'data' chunk the file cuts short
    (a copy stopped early: scipy read what was there, or failed on half a frame) is refused here."""
    header = None
    with path.open("rb") as f:
        riff = f.read(12)
        if len(riff) < 12 or riff[:4] not in (b"RIFF", b"RIFX") or riff[8:12] != b"WAVE":
            raise ValueError("no RIFF/WAVE header")
        order, total = "<" if riff[:4] == b"RIFF" else ">", path.stat().st_size
        for _ in range(1000):
            head = f.read(8)
            if len(head) < 8:
                break
            kind, size = head[:4], struct.unpack(order + "I", head[4:])[0]
            if kind == b"fmt ":
                body = f.read(min(size, 64))
                tag, channels, rate = struct.unpack(order + "HHI", body[:8])
                names = [str(i) for i in range(channels)]
                if tag == 0xFFFE and len(body) >= 26:  # the extensible format's own sub-format tag
                    tag = struct.unpack(order + "H", body[24:26])[0]
                if tag not in WAV_CODINGS:  # a compressed coding (ADPCM, mu-law, MP3...): the reader has none
                    raise ValueError(
                        f"its samples are coded as {WAV_CODINGS_SEEN.get(tag, f'format tag {tag}')}; expected PCM "
                        "(integer) or IEEE float samples (convert it, e.g. to a 24-bit PCM WAV)"
                    )
                integer = frozenset(names) if tag == 1 else frozenset()  # 1: PCM (3: IEEE float)
                header = Header("WAV", names, True, integer, indexed=True, stated=(float(rate), "the WAV header"))
                align = struct.unpack(order + "H", body[12:14])[0] if len(body) >= 14 else 0  # bytes a frame
                f.seek(size + (size & 1) - len(body), 1)
                continue
            if kind == b"data" and header is not None:
                held = total - f.tell()
                if 0 < size < 0xFFFFFFFF and size > held:  # 0 / 2^32 - 1: a stream's writer left it open
                    raise ValueError(
                        f"its data chunk declares {size:,} bytes and the file holds {held:,} after it (a truncated "
                        "file?); expected the whole recording"
                    )
                if align and 0 < size < 0xFFFFFFFF:  # a stream's open chunk says no length
                    return replace(header, frames=size // align)
                return header
            f.seek(size + (size & 1), 1)
    if header is not None:
        return header
    raise ValueError("no 'fmt ' chunk in its header")


def _mat_header(path: Path) -> Header:
    from .matlab import _is_mat73, mat5_header

    if _is_mat73(path):
        return _hdf5_header(path, "MATLAB")
    with path.open("rb") as f:
        if 0 in f.read(4):  # v4 (how scipy tells it from v5)
            return _mat4_header(path)
    every, fields, shapes, scalars, texts = mat5_header(path)  # the elements' headers: the data seeked past
    names = [n for n in every if n and not n.startswith("__")]
    names += fields  # a scalar struct's fields, by path
    names = [n for n in names if n not in texts]  # a unit's text ('acc_unit', a struct's 'units') is no channel
    rate = any(is_rate_or_time(n.rsplit("/", 1)[-1]) for n in names)
    shapes = {n: tuple(shape) for n, shape in shapes.items() if n in names}
    stated = _rate_variable({n: s for n, s in shapes.items() if n in scalars}, scalars.get)
    units = stated_units(texts, names)
    return Header("MATLAB", names, rate, nested=bool(fields), shapes=shapes, stated=stated, units=units)


def _rate_variable(shapes: dict[str, tuple], read) -> tuple[float, str] | None:
    """(Hz, where) of a rate stored as data: the one number of a variable named as a rate ('fs'), read alone
    (one number, whatever the file's size), so validate knows a take's length as the run will; None if none."""
    for name, shape in shapes.items():
        if named(name.rsplit("/", 1)[-1]) is not None and math.prod(shape) == 1:
            value = np.asarray(read(name))
            if value.dtype.kind in "iuf" and (hz := stated_hz(name.rsplit("/", 1)[-1], value)) is not None:
                return hz, f"its {name!r}"
    return None


_MAT4_BYTES = {0: 8, 1: 4, 2: 4, 3: 2, 4: 2, 5: 1}  # the precision digit P: double, single, int32, int16, uint16, uint8
_MAT4_CODES = {0: "d", 1: "f", 2: "i", 3: "h", 4: "H", 5: "B"}  # the same, as struct's codes


def _mat4_header(path: Path) -> Header:
    """A MATLAB v4 file's variables and their shapes: each variable's 20-byte header and name read, its
    data skipped (its size follows from the header); the byte order as scipy guesses it (the first
    variable's type word, 0 to 5000, read little-endian or not)."""
    names, shapes, scalars, total = [], {}, {}, path.stat().st_size
    with path.open("rb") as f:
        order = "<" if 0 <= struct.unpack("<i", f.read(4))[0] <= 5000 else ">"
        f.seek(0)
        while head := f.read(20):
            at = f.tell() - len(head)
            if len(head) < 20:
                raise ValueError(f"{len(head)} stray bytes at the end")
            mopt, rows, cols, imagf, namlen = struct.unpack(order + "5i", head)
            precision, kind = mopt // 10 % 10, mopt % 10
            if not 0 <= mopt <= 5000 or mopt // 100 % 10 or precision not in _MAT4_BYTES or min(rows, cols) < 0:
                raise ValueError(f"no MATLAB 4 variable header at byte {at}")
            if not 0 < namlen <= 1024:
                raise ValueError(f"a variable name of {namlen} bytes at byte {at}")
            name = f.read(namlen).split(b"\0", 1)[0].decode("latin1")
            size = rows * cols * _MAT4_BYTES[precision] * (2 if imagf == 1 else 1)
            if f.tell() + size > total:
                raise ValueError(f"variable '{name}' declares {size:,} bytes, past the end of the file")
            if kind == 0 and rows * cols == 1 and imagf != 1:  # one number (an 'fs'): its few bytes read
                scalars[name] = float(struct.unpack(order + _MAT4_CODES[precision], f.read(size))[0])
            else:
                f.seek(size, 1)
            names.append(name)
            if kind == 0:  # a full numeric matrix (1: text, 2: sparse)
                shapes[name] = (rows, cols)
    stated = _rate_variable({n: s for n, s in shapes.items() if n in scalars}, scalars.get)
    return Header("MATLAB", names, any(is_rate_or_time(n) for n in names), shapes=shapes, stated=stated)


HEADERS = {
    "CSV": _csv_header,
    "text": lambda p: _text_header(p, "text"),
    "zipped text": lambda p: _text_header(p, "zipped text"),
    "NPZ": _npz_header,
    "HDF5": _hdf5_header,
    "WAV": _wav_header,
    "MATLAB": _mat_header,
}


INDEX_NAME = re.compile(r"(?i)^(sample|samples|sample ?(#|no\.?|nr\.?|number|index)|index|idx|n|no\.?|nr\.?|#|point)$")


# A logger's side file beside a take (take.json, take.csv.yaml) with its rate ('"sample_rate": 25600', 'fs_kHz: 25.6'),
# and a rate in the take's own name ('pump_25600Hz.csv', 'run3-51k2S/s'): both were 'no sampling rate ... (--fs / fs =
# ...)', the rate the user had not said
_SIDE_FILES = (".json", ".yaml", ".yml")
_SIDE_FIELD = re.compile(
    r"""["']?([A-Za-z][\w\-\[\]() ]*?)["']?\s*[:=]\s*["']?([-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\s*([\w/]*)"""
)
_RATE_IN_NAME = re.compile(r"(?<![A-Za-z0-9.])(\d+(?:[.p]\d+)?)\s*(k?)(?:hz|s/s|sps)(?![a-z])", re.IGNORECASE)


def _side_hint(path: Path) -> str:
    """A clause naming the rate a logger's side file beside *path*, or its name, states ('' where none does)."""
    from ...signals.checks import fmt_hz

    for side in (path.with_suffix(ext) for ext in _SIDE_FILES):
        try:
            text = side.read_text(errors="replace")[:100_000] if side.is_file() else ""
        except OSError:
            continue
        for name, number, unit in _SIDE_FIELD.findall(text):
            found = scale_of(key_of(name), unit) or named(name.strip())
            hz = in_hz(found, float(number)) if found else None
            if hz and hz > 0:
                return (
                    f"; beside it, {side.name} states {name.strip()} = {number}{' ' * bool(unit)}{unit}: give "
                    f"fs = '{fmt_hz(hz)}' (--fs '{fmt_hz(hz)}'; gearlab reads no side file)"
                )
    match = _RATE_IN_NAME.search(path.stem)
    if match:
        hz = float(match.group(1).replace("p", ".")) * (1e3 if match.group(2) else 1.0)
        return f"; its name says {fmt_hz(hz)}: give fs = '{fmt_hz(hz)}' (--fs '{fmt_hz(hz)}') if it is the rate"
    return ""


def time_hint(path, rows: int = 2000) -> str:
    """For a headerless text record whose column 0 rises by a constant step (as a time column
    does), a clause saying so and how to give the rate ('' otherwise): its first *rows* read. First, a
    rate that a logger's side file beside it or its name states (_side_hint)."""
    from ...signals.checks import fmt_hz

    side = _side_hint(Path(path))
    if side:
        return side
    from .base import _column
    from .csv import delimiter_of, is_header, split_rows
    from .text import _open_text

    lines: list[str] = []
    try:
        with _open_text(Path(path)) as (stream, _):
            for line in stream:
                if b"\x00" in line:  # a binary format (NPZ, HDF5, WAV, MATLAB): no text columns
                    return ""
                text = line.decode("utf-8-sig", "replace").strip()
                if text and not text.startswith("#"):
                    lines.append(text)
                if len(lines) >= rows:
                    break
    except (GearlabInputError, OSError):
        return ""
    try:
        table = split_rows(lines, delimiter_of(lines[0])) if lines else []
    except csv.Error:
        return ""
    if len(table) < 3 or any(not row for row in table):
        return ""
    named = is_header(table[0])
    if named and not INDEX_NAME.match(table[0][0].strip()):
        return ""
    t = _column([row[0] for row in table[named:]])
    if t.dtype.kind != "f" or t.size < 2 or not np.all(np.diff(t) > 0):
        return ""
    step = (t[-1] - t[0]) / (t.size - 1)
    if np.max(np.abs(t - t[0] - step * np.arange(t.size))) > step / 2:  # printed rounding, not a constant step
        return ""
    if step == 1 and t[0] == round(t[0]):  # 0, 1, 2, ...: the samples counted, which says no rate
        column = f"'{table[0][0].strip()}'" if named else "0"
        return (
            f"; its column {column} counts the samples ({t[0]:.0f}, {t[0] + 1:.0f}, {t[0] + 2:.0f}, ...), not the "
            "time: expected the rate the logger sampled at, e.g. fs = '51.2 kHz' (--fs '51.2 kHz')"
        )
    if named:
        return ""
    rate = fmt_hz(1 / step)
    return (
        f"; its column 0 rises by a constant {step:.6g} a row, as a time column in seconds does: expected "
        f"fs = '{rate}' (--fs '{rate}'), or a header row of column names, column 0's 'time_s'"
    )
