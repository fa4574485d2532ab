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
    _INTERVAL_NAMES,
    _RATE_NAMES,
    Contents,
    _keyed,
    _normalise,
    _time_field,
    interval_rate,
    is_rate_or_time,
    max_record_bytes,
    time_scale,
)
from .hdf5 import _read_hdf5, leaf_match


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
        return contents
    from scipy.io import loadmat

    with path.open("rb") as f:
        v4 = 0 in f.read(4)  # how scipy tells v4 files from v5 ones
    fields: list[str] = []
    if v4:  # scipy's v4 reader is plain Python over numpy: nothing to check first
        variables = loadmat(path, squeeze_me=True, chars_as_strings=True)
        available = [k for k in variables if not k.startswith("__")]  # __header__, __version__, …
        return _keyed(available, lambda n: variables[n], names)

    def wanted(name: str) -> bool:  # the channels asked for and the rate fields (see _keyed)
        return name in names or is_rate_or_time(name)

    every = _mat5_variables(path.read_bytes(), wanted, fields)
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
    contents.available = top + fields
    for name, full in paths.items():
        contents.found[name] = _normalise(get(full))
    for full in fields:
        leaf = full.rsplit("/", 1)[-1]
        if full.split("/", 1)[0] not in used:
            continue
        if leaf.lower() in _RATE_NAMES:
            contents.rates.append((f"'{full}'", _normalise(get(full))))
        elif leaf.lower() in _INTERVAL_NAMES:
            contents.rates.append(interval_rate(f"'{full}'", _normalise(get(full))))
        elif time_scale(leaf) is not None:
            contents.times.append(_time_field(f"time '{full}'", _normalise(get(full)), time_scale(leaf)))
    return contents


# --- MATLAB v5 layout ----------------------------------------------------------------------
# scipy's v5 reader trusts the element types it finds, and scipy documents it as not
# hardened for untrusted files: a data element of a type it has no dtype for makes it index
# past its table of dtypes and crash the process (one flipped bit in a variable's array flags
# does it). So the elements are walked here first, as the reader will take them; a file that
# does not follow the layout is refused before scipy sees it.

_MI_INT8, _MI_INT32, _MI_UINT32, _MI_MATRIX, _MI_COMPRESSED, _MI_UTF8 = 1, 5, 6, 14, 15, 16
_MI_DATA = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 16, 17, 18})  # the types scipy has a dtype for
_MI_TEXT = frozenset({_MI_INT8, _MI_UTF8})  # names, class names, field names
_MX_CELL, _MX_STRUCT, _MX_OBJECT, _MX_CHAR, _MX_SPARSE, _MX_OPAQUE = 1, 2, 3, 4, 5, 17
_MX_NUMERIC = range(6, 16)  # double, single, int8 … uint64
_MAT_MAX_DEPTH = 32  # cells in cells, structs in structs


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
        if kind != _MI_UINT32 or len(flags) != 8:
            raise ValueError("a matrix without its array flags")
        word = struct.unpack_from(self.order + "I", flags)[0]
        mclass, is_complex = word & 0xFF, bool(word >> 11 & 1)
        count = 0
        if mclass != _MX_OPAQUE:  # objects of classdef classes carry no dimensions
            kind, dims, pos = self.element(body, pos, end)
            if kind not in (_MI_INT32, _MI_UINT32) or len(dims) % 4 or not 2 <= len(dims) // 4 <= 32:
                raise ValueError("a matrix without valid dimensions")
            sizes = struct.unpack(self.order + f"{len(dims) // 4}i", dims)
            if min(sizes) < 0:
                raise ValueError(f"a matrix of negative size {sizes}")
            count = math.prod(sizes)
        kind, raw, pos = self.element(body, pos, end)
        if kind not in _MI_TEXT:
            raise ValueError("a matrix without a valid name")
        name = bytes(raw).decode("latin1")
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
        raise ValueError(
            f"the compressed variable at byte {at} inflates to more than the limit of "
            f"{limit / 2**20:,.0f} MB for a measured record (set GEARLAB_MAX_RECORD_MB to allow more)"
        )
    return out


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
