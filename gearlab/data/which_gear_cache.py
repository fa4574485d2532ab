"""What the which-gear check reads from a healthy history and simulates for a gearbox, kept between calls.

`gearlab inspect TAKE --history H...` reads every history file (resampled to revolutions, each shaft's average, the
envelope's bands, the non-synchronous residual) and, where a two-gear shaft is flagged, simulates the description's
tooth-fault events: on a three-stage box about a minute and a half of CPU, the same for each take inspected against
the same history. Both are kept in the dataset cache's folder (cache.cache_dir(): $GEARLAB_CACHE), written as its
datasets are (an npz of plain arrays, no pickle, atomic rename):

* ``which-history-<key>.npz``: the history as `gearlab score` restores a run's (signals.localise.History.state, the
  envelope's bank, the non-synchronous residual's), with the numbers inspect reads beside it;
* ``which-events-<key>.npz``: a two-gear shaft's simulated events (which_templates) at one layout, speed and rate.

A key hashes everything the result depends on: each history file's resolved path and content (a file written
again is read again), the options it is read with, the gearbox's derived values (its Gearbox: a tooth count changed
is another key), the description file's bytes for the events, and gearlab's code (a digest of its and its plugins'
source files: any change of the code is a new key, never a stale hit). An entry that cannot be read or holds
another key is ignored and written again.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
from fractions import Fraction
from functools import lru_cache
from importlib.util import find_spec
from pathlib import Path

import numpy as np

from .. import PHYSICS_VERSION
from ..files import atomic_write, take_file, write_problem
from .cache import cache_dir


@lru_cache(maxsize=1)
def code_version() -> str:
    """sha256 of gearlab's and its plugins' Python source files (names and bytes): a changed rule is a new key."""
    h = hashlib.sha256(PHYSICS_VERSION.encode())
    for package in ("gearlab", "gearlab_plugins"):
        spec = find_spec(package)
        if spec is None or not spec.submodule_search_locations:
            continue
        for root in spec.submodule_search_locations:
            for path in sorted(Path(root).resolve().rglob("*.py")):
                h.update(f"{package}/{path.relative_to(Path(root).resolve()).as_posix()}\0".encode())
                h.update(path.read_bytes())
    return h.hexdigest()


def _plain(value):
    """json.dumps's default: arrays by their digest, fractions and paths as text, dataclasses as dicts."""
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        return f"{a.dtype.str}{a.shape}:{hashlib.sha256(memoryview(a).cast('B')).hexdigest()}"
    if isinstance(value, np.generic):
        return value.item()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
    if isinstance(value, (Fraction, Path)):
        return str(value)
    if isinstance(value, (set, frozenset)):
        return sorted(map(str, value))
    return repr(value)


def key_of(kind: str, *parts) -> str:
    """The entry key of *kind* ("history", "events") for *parts* (plain data, dataclasses, arrays) and this code."""
    text = json.dumps([kind, code_version(), parts], sort_keys=True, default=_plain)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def file_identity(path: str) -> list | None:
    """(the name as given, its file's resolved path, the sha256 of its content): a file written again is another key,
    even within its file system's mtime resolution and at the same size (hashing 20 MB of history: ~20 ms); None
    where it is no file to hash (a folder of records): such a history is read each time."""
    file = take_file(path)
    try:
        with open(file, "rb") as f:
            digest = hashlib.file_digest(f, "sha256").hexdigest()
    except OSError:
        return None
    return [str(path), str(file.resolve()), digest]


def description_bytes(description: str | None) -> str:
    """A gearbox description named for a simulation: its file's sha256 where it is one, else the name itself."""
    if description is None or not Path(description).is_file():
        return str(description)
    return hashlib.sha256(Path(description).read_bytes()).hexdigest()


def _path(kind: str, key: str) -> Path:
    return cache_dir() / f"which-{kind}-{key}.npz"


def load(kind: str, key: str) -> dict[str, np.ndarray] | None:
    """The arrays of the entry *key* of *kind*; None where there is none or it cannot be read (written again)."""
    path = _path(kind, key)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError):  # none yet, or damaged: computed and written again
        return None
    return arrays if str(arrays.pop("cache_key", "")) == key else None


def save(kind: str, key: str, arrays: dict[str, np.ndarray]) -> None:
    """Keep *arrays* as the entry *key* of *kind*; a cache that cannot be written costs the next call its time only."""
    buf = io.BytesIO()
    np.savez(buf, cache_key=np.array(key), **arrays)
    try:
        atomic_write(_path(kind, key), buf.getvalue())
    except OSError as exc:
        if write_problem(exc) is None:
            raise


def events_arrays(made: dict) -> dict[str, np.ndarray]:
    """simulated_templates' layout result ({"healthy", "gears": {name: [one per kind]}}) as plain arrays."""
    out = {"healthy": np.asarray(made["healthy"]), "gears": np.array(json.dumps(list(made["gears"])))}
    for i, kinds in enumerate(made["gears"].values()):
        out |= {f"gear{i}_{k}": np.asarray(a) for k, a in enumerate(kinds)}
    return out


def events_of(arrays: dict[str, np.ndarray], kinds: int) -> dict:
    """events_arrays' result read back."""
    names = json.loads(str(arrays["gears"]))
    gears = {name: [arrays[f"gear{i}_{k}"] for k in range(kinds)] for i, name in enumerate(names)}
    return {"healthy": arrays["healthy"], "gears": gears}
