"""NPZ: arrays by name, loaded without pickle; the rate from a scalar 'fs' or a 't' array."""

from __future__ import annotations

import math
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .base import Contents, _keyed, check_size, is_unit_entry, stated_units


def _read_npz(path: Path, names: Sequence[str]) -> Contents:
    """Arrays by name; never unpickles (allow_pickle=False refuses object arrays)."""
    # np.load guesses from the first bytes (.npy, zip, else pickle); say what the file is instead.
    with path.open("rb") as f:
        magic = f.read(6)
    if magic == b"\x93NUMPY":
        raise ValueError("it holds a single array (.npy), not an archive of named arrays")
    if not zipfile.is_zipfile(path):
        raise ValueError("not a zip archive (an .npz file is a zip of named .npy arrays)")
    with np.load(path, allow_pickle=False) as data:  # read inside: members load lazily

        def get(name: str):
            check_size(path, f"array '{name}'", _npz_member_bytes(data.zip, f"{name}.npy"))
            return data[name]

        arrays = [n for n in data.files if f"{n}.npy" in data.zip.namelist()]
        units = npz_units({n: _member_header(data.zip, f"{n}.npy") for n in arrays}, get)
        contents = _keyed(data.files, get, names, listed=[n for n in data.files if n not in units["texts"]])
        contents.units.update(units["units"])
        return contents


def npz_units(headers: dict[str, tuple], get) -> dict:
    """{"units": {channel: unit} (base.stated_units), "texts": the unit entries} of an NPZ's arrays, by their (shape,
    dtype) headers; *get(name)* reads an entry (only the one-value text ones are read): `np.savez(f, vib=x, fs=fs,
    unit="g")` or `vib_unit="m/s^2"`."""
    texts = {n for n, (shape, dtype) in headers.items() if dtype.kind in "US" and math.prod(shape) == 1}
    said = {n: str(np.asarray(get(n)).item()) for n in texts if is_unit_entry(n)}
    return {"units": stated_units(said, [n for n in headers if n not in texts]), "texts": set(said)}


def _member_header(archive: zipfile.ZipFile, member: str) -> tuple[tuple, np.dtype]:
    """(shape, dtype) an NPZ member's .npy header declares, read without its data."""
    with archive.open(member) as f:
        version = np.lib.format.read_magic(f)
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, _, dtype = read_header(f, max_header_size=10_000)
    return tuple(shape), dtype


def _npz_member_bytes(archive: zipfile.ZipFile, member: str) -> int:
    """What an NPZ member takes once read: its .npy header's shape times its item size (what
    numpy allocates), or its declared inflated size if that is larger."""
    shape, dtype = _member_header(archive, member)
    return max(math.prod(shape) * dtype.itemsize, archive.getinfo(member).file_size)
