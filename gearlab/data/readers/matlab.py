"""MATLAB: v5 variables (scipy) or v7.3 (an HDF5 file, read with h5py); the rate from 'fs'/'Fs'.
A scalar struct's fields are channels by path, as a v7.3 file's groups are: "rec/acc" (or "rec.acc",
or "acc" where one field has that last name), its "rec/fs" a rate field."""

from __future__ import annotations

import math
import struct
import zlib
from collections.abc import Sequence
from pathlib import Path

from .base import (
    Contents,
    _keyed,
    _normalise,
    _time_field,
    is_rate_or_time,
    is_unit_entry,
    max_record_bytes,
    stated_units,
    time_scale,
)
from .hdf5 import _read_hdf5, leaf_match
from .rates import named, own_field, rate_field


def _is_mat73(path: Path) -> bool:
    """MATLAB v7.3 files carry version 0x0200 in their 128-byte header (and are HDF5)."""
    with path.open("rb") as f:
        header = f.read(128)
    return len(header) == 128 and header[124:126] in (b"\x00\x02", b"\x02\x00")


def field_path(name: str, fields: Sequence[str]) -> str | None:
    """The struct field path *name* means ("rec/acc", "rec.acc" or a unique last name "acc"), or None."""
    if name in fields:
        return name
    dotted = name.replace(".", "/")
    if dotted in fields:
        return dotted
    return leaf_match(fields, name)


def _read_mat(path: Path, names: Sequence[str]) -> Contents:
    """MATLAB variables by name: v4/v5 through scipy, v7.3 (HDF5) through h5py.

    A v5 file's layout is checked first (_mat5_variables), and scipy reads only the
    variables asked for and the rate fields, never the others (objects, function handles).
    A scalar struct's fields (a logger's rec.acc, rec.fs) are channels by path (field_path).
    """
    if _is_mat73(path):
        alias = {n: n.replace(".", "/") for n in names}  # no MATLAB name has a dot: rec.acc is a field
        contents = _read_hdf5(path, list(dict.fromkeys(alias.values())), matlab=True)
        contents.found = {n: contents.found[a] for n, a in alias.items() if a in contents.found}
        contents.units = {n: contents.units[a] for n, a in alias.items() if a in contents.units}
        return contents
    from scipy.io import loadmat

    with path.open("rb") as f:
        v4 = 0 in f.read(4)  # how scipy tells v4 files from v5 ones
    fields: list[str] = []
    if v4:  # scipy's v4 reader is plain Python over numpy: nothing to check first
        variables = loadmat(path, squeeze_me=True, chars_as_strings=True)
        available = [k for k in variables if not k.startswith("__")]  # __header__, __version__, …
        return _keyed(available, lambda n: variables[n], names)

    def wanted(name: str) -> bool:  # the channels asked for, the rate fields (see _keyed) and the units said
        own = any(own_field(name, n) for n in names)  # a channel's own rate or time ('ACC_fs', 'Data1_time_ACC')
        return name in names or is_rate_or_time(name) or is_unit_entry(name) or own

    shapes: dict[str, tuple] = {}  # the numeric ones': a unit entry is text
    every = _mat5_variables(path.read_bytes(), wanted, fields, shapes)
    top = list(dict.fromkeys(n for n in every if n and not n.startswith("__")))
    paths = {n: field_path(n, fields) for n in names if n not in top}
    paths = {n: p for n, p in paths.items() if p is not None}
    # a struct's rate and time fields count where one of its fields is asked for (HDF5's nearest group)
    used = {p.split("/", 1)[0] for p in paths.values()}
    load = [n for n in top if wanted(n) or n in used]
    # squeeze_me: a 1×N row or N×1 column becomes a vector, a 1×1 a scalar; a struct an object
    variables = loadmat(path, squeeze_me=True, chars_as_strings=True, struct_as_record=False, variable_names=load)

    def get(name: str):
        parts = name.split("/")
        value = variables[parts[0]]
        for part in parts[1:]:
            value = getattr(value, part)
        return value

    contents = _keyed(top, get, [n for n in names if n not in paths])
    said = said_units([n for n in top if n in load] + [f for f in fields if f.split("/", 1)[0] in used], get)
    # a unit entry (text) is no channel, nor a struct whose fields are listed (rec: rec/data, rec/fs)
    structs = {f.split("/", 1)[0] for f in fields}
    listed = [n for n in top if n not in structs or n in shapes] + fields
    contents.available = [n for n in listed if not (is_unit_entry(n) and n not in shapes)]
    for name, full in paths.items():
        contents.found[name] = _normalise(get(full))
    contents.units.update({n: said[paths.get(n, n)] for n in names if paths.get(n, n) in said})
    for full in fields:
        leaf = full.rsplit("/", 1)[-1]
        if full.split("/", 1)[0] not in used:
            continue
        if named(leaf) is not None:  # in Hz, a unit in the name read (rates.rate_field)
            contents.rates.append(rate_field(f"'{full}'", leaf, _normalise(get(full))))
        elif time_scale(leaf) is not None:
            contents.times.append(_time_field(f"time '{full}'", _normalise(get(full)), time_scale(leaf)))
    return contents


def said_units(names: Sequence[str], get) -> dict[str, str]:
    """{channel: unit} that text entries of a MAT-file state (base.stated_units): MATLAB's struct('fs', 20000, 'data',
    X, 'units', 'g') had its data read as m/s² ('values: unknown'), its 'units' listed as a channel."""
    texts = {n: get(n) for n in names if is_unit_entry(n)}
    return stated_units({n: v for n, v in texts.items() if isinstance(v, str)}, [n for n in names if n not in texts])


# --- MATLAB v5 layout ----------------------------------------------------------------------
# scipy's v5 reader trusts the element types it finds, and scipy documents it as not
# hardened for untrusted files: a data element of a type it has no dtype for makes it index
# past its table of dtypes and crash the process (one flipped bit in a variable's array flags
# does it). So the elements are walked here first, as the reader will take them; a file that
# does not follow the layout is refused before scipy sees it.

_MI_INT8, _MI_INT32, _MI_UINT32, _MI_MATRIX, _MI_COMPRESSED, _MI_UTF8 = 1, 5, 6, 14, 15, 16
_MI_UINT16, _MI_UTF16 = 4, 17  # MATLAB's own characters: two bytes each
_MI_DATA = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 16, 17, 18})  # the types scipy has a dtype for
_MI_TEXT = frozenset({_MI_INT8, _MI_UTF8})  # names, class names, field names
_MI_FORMATS = {1: "b", 2: "B", 3: "h", 4: "H", 5: "i", 6: "I", 7: "f", 9: "d", 12: "q", 13: "Q"}  # struct's codes
_MX_CELL, _MX_STRUCT, _MX_OBJECT, _MX_CHAR, _MX_SPARSE, _MX_OPAQUE = 1, 2, 3, 4, 5, 17
_MX_NUMERIC = range(6, 16)  # double, single, int8 … uint64
_MAT_MAX_DEPTH = 32  # cells in cells, structs in structs


def _array_flags(order: str, kind: int, flags) -> tuple[int, bool]:
    """(class, complex) of a matrix's array-flags element."""
    if kind != _MI_UINT32 or len(flags) != 8:
        raise ValueError("a matrix without its array flags")
    word = struct.unpack_from(order + "I", flags)[0]
    return word & 0xFF, bool(word >> 11 & 1)


def _dimensions(order: str, kind: int, dims) -> tuple[tuple, int]:
    """(sizes, element count) of a matrix's dimensions element."""
    if kind not in (_MI_INT32, _MI_UINT32) or len(dims) % 4 or not 2 <= len(dims) // 4 <= 32:
        raise ValueError("a matrix without valid dimensions")
    sizes = struct.unpack(order + f"{len(dims) // 4}i", dims)
    if min(sizes) < 0:
        raise ValueError(f"a matrix of negative size {sizes}")
    return sizes, math.prod(sizes)


def _name(kind: int, raw) -> str:
    if kind not in _MI_TEXT:
        raise ValueError("a matrix without a valid name")
    return bytes(raw).decode("latin1")


class _Mat5Layout:
    """Walks MATLAB v5 elements: tag (type, size) then data padded to 8 bytes, or a small data
    element (size and type in one word, up to 4 bytes of data in the next)."""

    def __init__(self, order: str, fields: list | None = None, shapes: dict | None = None):
        self.order = order
        self.fields = fields  # collects "var/field" paths of scalar structs' numeric and text fields
        self.shapes = shapes  # collects numeric variables' and such fields' dimensions, by name or path

    def element(self, buf: memoryview, pos: int, end: int) -> tuple[int, memoryview, int]:
        """(type, data, position after it) of the element at *pos*; it must end by *end*."""
        if pos + 8 > end:
            raise ValueError(f"an element at byte {pos} runs past the end of the variable")
        first, size = struct.unpack_from(self.order + "II", buf, pos)
        if first >> 16:
            if first >> 16 > 4:
                raise ValueError(f"a small data element of {first >> 16} bytes at byte {pos}")
            return first & 0xFFFF, buf[pos + 4 : pos + 4 + (first >> 16)], pos + 8
        start = pos + 8
        if start + size > end:
            raise ValueError(f"an element of {size} bytes at byte {pos} runs past the end of the variable")
        return first, buf[start : start + size], min(end, start + (size + 7) // 8 * 8)

    def data(self, buf: memoryview, pos: int, end: int, types: frozenset = _MI_DATA) -> int:
        kind, _, pos = self.element(buf, pos, end)
        if kind not in types:
            raise ValueError(f"a data element of type {kind}, which MATLAB does not use there")
        return pos

    def matrix(self, buf: memoryview, pos: int, end: int, depth: int, path: str | None = None) -> int:
        """A matrix element inside a cell or struct (*path*: a scalar struct's field); the position after it."""
        kind, body, after = self.element(buf, pos, end)
        if kind != _MI_MATRIX:
            raise ValueError(f"a cell or field of element type {kind}, expected a matrix")
        if body:  # an empty matrix has no body at all
            self.body(body, depth, lambda name: True, path)
        return after

    def body(self, body: memoryview, depth: int, read, path: str | None = None) -> str:
        """Check a matrix: array flags, dimensions, name and, when read(name), its contents.
        A scalar struct is walked whatever read says, its fields' paths kept (self.fields).
        Returns the name."""
        if depth > _MAT_MAX_DEPTH:
            raise ValueError(f"cells or structs nested more than {_MAT_MAX_DEPTH} deep")
        end = len(body)
        kind, flags, pos = self.element(body, 0, end)
        mclass, is_complex = _array_flags(self.order, kind, flags)
        count = 0
        if mclass != _MX_OPAQUE:  # objects of classdef classes carry no dimensions
            kind, dims, pos = self.element(body, pos, end)
            sizes, count = _dimensions(self.order, kind, dims)
        kind, raw, pos = self.element(body, pos, end)
        name = _name(kind, raw)
        here = name if path is None else path
        if self.shapes is not None and mclass in _MX_NUMERIC and here and (depth == 0 or path is not None):
            self.shapes[here] = sizes
        scalar_struct = mclass == _MX_STRUCT and count == 1 and self.fields is not None
        if not read(name) and not scalar_struct:
            return name  # scipy reads no more of a variable it is not asked for
        if path is not None and self.fields is not None and mclass in (*_MX_NUMERIC, _MX_CHAR):
            self.fields.append(path)
        if mclass in _MX_NUMERIC:
            for _ in range(2 if is_complex else 1):  # real part, imaginary part
                pos = self.data(body, pos, end)
        elif mclass == _MX_CHAR:
            pos = self.data(body, pos, end)
        elif mclass == _MX_SPARSE:
            for _ in range(4 if is_complex else 3):  # row indices, column starts, values (real, imaginary)
                pos = self.data(body, pos, end)
        elif mclass == _MX_CELL:
            for _ in range(count):  # each cell takes 8 bytes at least: the walk ends with the data
                pos = self.matrix(body, pos, end, depth + 1)
        elif mclass in (_MX_STRUCT, _MX_OBJECT):
            if mclass == _MX_OBJECT:
                pos = self.data(body, pos, end, _MI_TEXT)  # the class name
            kind, length, pos = self.element(body, pos, end)
            if kind not in (_MI_INT32, _MI_UINT32) or len(length) != 4:
                raise ValueError("a struct without the length of its field names")
            length = struct.unpack(self.order + "i", length)[0]
            kind, fields, pos = self.element(body, pos, end)
            if kind not in _MI_TEXT or length <= 0:
                raise ValueError("a struct without valid field names")
            keys = [
                bytes(fields[i : i + length]).split(b"\0", 1)[0].decode("latin1") for i in range(0, len(fields), length)
            ]
            for i in range(count * (len(fields) // length)):
                sub = f"{here}/{keys[i]}" if scalar_struct and here else None
                pos = self.matrix(body, pos, end, depth + 1, sub)
        else:  # function handles, classdef objects, Java objects: no measured data
            raise ValueError(
                f"variable '{name}' is a MATLAB {('function handle' if mclass == 16 else 'object')}, "
                "not numbers or text"
            )
        return name


def _inflate(data, at: int) -> bytes:
    """A compressed MATLAB variable, refused once it inflates beyond the record size limit."""
    limit = max_record_bytes()
    inflater = zlib.decompressobj()
    out = inflater.decompress(data, limit + 1)
    if len(out) > limit:
        raise _beyond(at, limit)
    return out


def _beyond(at: int, limit: int) -> ValueError:
    return ValueError(
        f"the compressed variable at byte {at} inflates to more than the limit of "
        f"{limit / 2**20:,.0f} MB for a measured record (set GEARLAB_MAX_RECORD_MB to allow more)"
    )


def _mat5_variables(data: bytes, read, fields: list | None = None, shapes: dict | None = None) -> list[str]:
    """Names of the variables of a MATLAB v5 file, after checking their layout: every
    variable's header, and in full those for which read(name) is true. *fields*: a list that
    collects the field paths of scalar structs ("rec/acc"), walked in full; *shapes*: a dict that
    collects the numeric ones' dimensions, as MATLAB stores them (a vector is 1 x N or N x 1)."""
    if len(data) < 128 or data[126:128] not in (b"IM", b"MI"):
        raise ValueError("no MATLAB 5 header (128 bytes ending in 'IM' or 'MI')")
    layout = _Mat5Layout("<" if data[126:128] == b"IM" else ">", fields, shapes)
    data = memoryview(data)  # slices without copies of the arrays
    names = []
    pos = 128
    while pos < len(data):
        if pos + 8 > len(data):
            raise ValueError(f"{len(data) - pos} stray bytes at the end")
        kind, size = struct.unpack_from(layout.order + "II", data, pos)
        start, pos = pos + 8, pos + 8 + size  # variables follow each other unpadded
        if size == 0 or pos > len(data):
            raise ValueError(f"a variable of {size} bytes at byte {start - 8} of {len(data)}")
        if kind == _MI_COMPRESSED:
            inner = memoryview(_inflate(data[start:pos], start - 8))
            kind, body, _ = layout.element(inner, 0, len(inner))
        else:
            body = data[start:pos]
        if kind != _MI_MATRIX:
            raise ValueError(f"a variable of element type {kind}, expected a matrix")
        names.append(layout.body(body, 0, read))
    return names


# --- MATLAB v5 header, its data unread (`gearlab validate`) ----------------------------------------
# The same layout as _Mat5Layout walks, read from the file as it goes: each element's tag gives its size,
# so the data are seeked past; a compressed variable is inflated only as far as its header (a scalar
# struct's: through its fields, streamed and dropped, never held). A 1 GB record is not read to be listed.


class _Stream:
    """One variable's bytes, read forward on demand: the file's, or their inflation (*compressed*)."""

    CHUNK = 1 << 16

    def __init__(self, f, start: int, size: int, compressed: bool):
        f.seek(start)
        self.f, self.left, self.at, self.start = f, size, 0, start
        self.inflater = zlib.decompressobj() if compressed else None
        self.pending = bytearray()

    def _inflate_more(self) -> None:
        tail = self.inflater.unconsumed_tail
        if not tail and self.left:
            tail = self.f.read(min(self.CHUNK, self.left))
            self.left -= len(tail)
        out = self.inflater.decompress(tail, self.CHUNK)  # no input: what the inflater still holds
        if not out and (self.inflater.eof or not tail):
            raise ValueError(f"the compressed variable at byte {self.start - 8} ends within an element")
        self.pending += out
        if self.at + len(self.pending) > (limit := max_record_bytes()):  # as the reader refuses it (_inflate)
            raise _beyond(self.start - 8, limit)

    def read(self, n: int) -> bytes:
        if self.inflater is None:
            if n > self.left:
                raise ValueError(f"an element at byte {self.start + self.at} runs past the end of the variable")
            self.left -= n
            self.at += n
            return self.f.read(n)
        while len(self.pending) < n:
            self._inflate_more()
        out = bytes(self.pending[:n])
        del self.pending[:n]
        self.at += n
        return out

    def skip(self, n: int) -> None:
        if self.inflater is None:
            if n > self.left:
                raise ValueError(f"an element at byte {self.start + self.at} runs past the end of the variable")
            self.f.seek(n, 1)
            self.left -= n
            self.at += n
            return
        while n > 0:
            if not self.pending:
                self._inflate_more()
            step = min(n, len(self.pending))
            del self.pending[:step]
            self.at += step
            n -= step


class _Mat5Header:
    """A v5 file's variables, their shapes and a scalar struct's field paths, from the elements' tags
    (the header _Mat5Layout checks, read as _Mat5Layout.body does for a variable not asked for)."""

    def __init__(self, order: str):
        self.order, self.fields, self.shapes = order, [], {}
        self.scalars: dict[str, float] = {}  # one-number variables and fields (a rate stored as data): 8 bytes each
        self.texts: dict[str, str] = {}  # unit entries' text ('acc_unit', a struct's 'units'), by name or path

    def tag(self, s: _Stream, end: int) -> tuple[int, int, bytes | None]:
        """(type, size, the data of a small element or None) of the element at the stream's position."""
        if s.at + 8 > end:
            raise ValueError(f"an element at byte {s.at} runs past the end of the variable")
        raw = s.read(8)
        first, size = struct.unpack(self.order + "II", raw)
        if first >> 16:  # a small data element: its data in the tag's second word
            if first >> 16 > 4:
                raise ValueError(f"a small data element of {first >> 16} bytes at byte {s.at - 8}")
            return first & 0xFFFF, first >> 16, raw[4 : 4 + (first >> 16)]
        if s.at + size > end:
            raise ValueError(f"an element of {size} bytes at byte {s.at - 8} runs past the end of the variable")
        return first, size, None

    def element(self, s: _Stream, end: int, most: int) -> tuple[int, bytes]:
        """(type, data) of a header element (flags, dimensions, names) of at most *most* bytes."""
        kind, size, small = self.tag(s, end)
        if small is not None:
            return kind, small
        if size > most:
            raise ValueError(f"a header element of {size:,} bytes at byte {s.at - 8}; expected at most {most:,}")
        data = s.read(size)
        s.skip(min(end, s.at + (-size) % 8) - s.at)
        return kind, data

    def skip(self, s: _Stream, end: int, types: frozenset = _MI_DATA) -> int:
        """Past a data element (its type checked, its data unread); its type."""
        kind, size, small = self.tag(s, end)
        if kind not in types:
            raise ValueError(f"a data element of type {kind}, which MATLAB does not use there")
        if small is None:
            s.skip(min(end, s.at + (size + 7) // 8 * 8) - s.at)
        return kind

    def body(self, s: _Stream, end: int, depth: int, path: str | None = None) -> str:
        """A matrix's flags, dimensions and name (its shape kept where numeric), a scalar struct's fields
        walked (their paths kept); the stream left within the matrix. Returns the name."""
        if depth > _MAT_MAX_DEPTH:
            raise ValueError(f"cells or structs nested more than {_MAT_MAX_DEPTH} deep")
        kind, flags = self.element(s, end, 8)
        mclass, is_complex = _array_flags(self.order, kind, flags)
        count = 0
        if mclass != _MX_OPAQUE:  # objects of classdef classes carry no dimensions
            kind, dims = self.element(s, end, 4 * 32)
            sizes, count = _dimensions(self.order, kind, dims)
        kind, raw = self.element(s, end, 1 << 16)
        name = _name(kind, raw)
        here = name if path is None else path
        if mclass in _MX_NUMERIC and here and (depth == 0 or path is not None):
            self.shapes[here] = sizes
            if count == 1 and not is_complex:  # its one number read, a few bytes (an 'fs')
                kind, raw = self.element(s, end, 8)
                code = _MI_FORMATS.get(kind)
                if code is not None and len(raw) >= struct.calcsize(code):
                    self.scalars[here] = float(struct.unpack_from(self.order + code, raw)[0])
                self.fields += [] if path is None else [path]
                return name
        if mclass == _MX_CHAR and here and (depth == 0 or path is not None) and is_unit_entry(here):
            kind, raw = self.element(s, end, 1 << 16)  # a unit's few characters, as said_units reads them
            codec = ("utf-16-le" if self.order == "<" else "utf-16-be") if kind in (_MI_UINT16, _MI_UTF16) else "utf-8"
            self.texts[here] = bytes(raw).decode(codec, "replace")
            return name
        scalar_struct = mclass == _MX_STRUCT and count == 1
        if depth == 0 and not scalar_struct:
            return name  # a variable's data: unread
        if path is not None and mclass in (*_MX_NUMERIC, _MX_CHAR):
            self.fields.append(path)
        if mclass in _MX_NUMERIC:
            for _ in range(2 if is_complex else 1):  # real part, imaginary part
                self.skip(s, end)
        elif mclass == _MX_CHAR:
            self.skip(s, end)
        elif scalar_struct:
            kind, length = self.element(s, end, 4)
            if kind not in (_MI_INT32, _MI_UINT32) or len(length) != 4:
                raise ValueError("a struct without the length of its field names")
            length = struct.unpack(self.order + "i", length)[0]
            kind, names = self.element(s, end, 1 << 20)
            if kind not in _MI_TEXT or length <= 0:
                raise ValueError("a struct without valid field names")
            for i in range(0, len(names) - length + 1, length):
                key = names[i : i + length].split(b"\0", 1)[0].decode("latin1")
                self.field(s, end, depth + 1, f"{here}/{key}" if here else None)
        elif mclass not in (_MX_SPARSE, _MX_CELL, _MX_STRUCT, _MX_OBJECT):  # as _Mat5Layout refuses a field
            raise ValueError(
                f"variable '{name}' is a MATLAB {('function handle' if mclass == 16 else 'object')}, "
                "not numbers or text"
            )
        return name

    def field(self, s: _Stream, end: int, depth: int, path: str | None) -> None:
        """A scalar struct's field (a matrix element): its header read where it has a *path*, then passed."""
        kind, size, small = self.tag(s, end)
        if kind != _MI_MATRIX or small is not None:
            raise ValueError(f"a cell or field of element type {kind}, expected a matrix")
        after = min(end, s.at + (size + 7) // 8 * 8)
        if size and path is not None:  # an empty matrix has no body at all
            self.body(s, s.at + size, depth, path)
        s.skip(after - s.at)


def mat5_header(path: Path) -> tuple[list[str], list[str], dict[str, tuple], dict[str, float], dict[str, str]]:
    """(variable names, a scalar struct's field paths "rec/acc", numeric variables' and fields' shapes, the
    one-number ones' values, the unit entries' texts) of a MATLAB v5 file, as _mat5_variables lists them, from its
    elements' headers alone (and each one-number variable's and unit text's few bytes)."""
    total = path.stat().st_size
    with path.open("rb") as f:
        head = f.read(128)
        if len(head) < 128 or head[126:128] not in (b"IM", b"MI"):
            raise ValueError("no MATLAB 5 header (128 bytes ending in 'IM' or 'MI')")
        walk = _Mat5Header("<" if head[126:128] == b"IM" else ">")
        names, pos = [], 128
        while pos < total:
            if pos + 8 > total:
                raise ValueError(f"{total - pos} stray bytes at the end")
            f.seek(pos)
            kind, size = struct.unpack(walk.order + "II", f.read(8))
            start, pos = pos + 8, pos + 8 + size  # variables follow each other unpadded
            if size == 0 or pos > total:
                raise ValueError(f"a variable of {size} bytes at byte {start - 8} of {total}")
            s, end = _Stream(f, start, size, kind == _MI_COMPRESSED), size
            if kind == _MI_COMPRESSED:
                kind, inner, small = walk.tag(s, math.inf)
                end = s.at + inner
            if kind != _MI_MATRIX:
                raise ValueError(f"a variable of element type {kind}, expected a matrix")
            names.append(walk.body(s, end, 0))
    return names, walk.fields, walk.shapes, walk.scalars, walk.texts
