"""NPZ: arrays by name, loaded without pickle; the rate from a scalar 'fs' or a 't' array."""

from __future__ import annotations

import math
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .base import Contents, _keyed, check_size


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

        return _keyed(data.files, get, names)


def _npz_member_bytes(archive: zipfile.ZipFile, member: str) -> int:
    """What an NPZ member takes once read: its .npy header's shape times its item size (what
    numpy allocates), or its declared inflated size if that is larger."""
    info = archive.getinfo(member)
    with archive.open(member) as f:
        version = np.lib.format.read_magic(f)
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, _, dtype = read_header(f, max_header_size=10_000)
    return max(math.prod(shape) * dtype.itemsize, info.file_size)
