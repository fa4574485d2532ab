"""Content-addressed dataset cache: `$GEARLAB_CACHE/<key>.npz`, no pickle, atomic writes.

The key hashes the canonical spec and the physics version (DatasetSpec.key; :func:`entry_key`). An entry is
written to a temporary file in the cache directory and renamed into place, so a killed
build leaves no entry. Each entry records the shape, dtype and a sha256 of every array
it holds; an entry that is unreadable or does not match them (damaged, tampered with,
written by an older gearlab) is removed and rebuilt, with a warning.

A cache that cannot be written (read-only, a full disk) does not fail a run: its datasets
go to a temporary folder of this process instead (removed when it exits), with a warning.
"""

from __future__ import annotations

import atexit
import hashlib
import io
import json
import os
import shutil
import tempfile
import time
import warnings
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

import numpy as np
import platformdirs

from ..errors import GearlabInputError, clipped
from ..events import Event
from ..files import atomic_write, write_problem
from .builder import build_dataset
from .importers import MeasuredSpec, import_measured
from .spec import Dataset, DatasetSpec

ARRAYS = ("X", "label", "fault", "intensity", "tooth", "rfa", "revolution", "domain")


def cache_dir() -> Path:
    """$GEARLAB_CACHE (else the user's cache folder); the temporary fallback when it cannot
    be made."""
    path = Path(os.environ.get("GEARLAB_CACHE") or platformdirs.user_cache_dir("gearlab"))
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        if write_problem(exc) is None:  # not a folder at all (a file of that name, ...)
            raise GearlabInputError(f"cannot create the dataset cache directory {path}: {exc.strerror}") from None
        return _fallback(path, exc)
    return path


_FALLBACK: list[Path] = []  # the temporary cache folder of this process, once one was needed


def _fallback(path: Path, exc: OSError) -> Path:
    """A temporary folder for this process's entries when the cache at *path* cannot be written;
    removed when the process exits. Workers read entries by path, so they find them there too."""
    if not _FALLBACK:
        try:
            folder = Path(tempfile.mkdtemp(prefix="gearlab-cache-"))
        except OSError as exc2:
            raise GearlabInputError(
                f"{path}: cannot write the dataset cache ({write_problem(exc) or exc.strerror}), "
                f"nor a temporary folder ({write_problem(exc2) or exc2.strerror})"
            ) from None
        atexit.register(shutil.rmtree, folder, True)
        _FALLBACK.append(folder)
        warnings.warn(
            f"dataset cache {path} cannot be written ({write_problem(exc)}); this run keeps its datasets "
            f"in {folder}, removed when it ends (set GEARLAB_CACHE to a writable folder to keep them)",
            stacklevel=3,
        )
    return _FALLBACK[0]


# Revisions of how a simulated dataset's rows are made, for the trains they change only: every other
# dataset keeps the key (and the entry) it had. "cycle": a later mesh of no whole input order, rows
# drawn over its whole cycle (builder, issue 39) instead of one revolution with the mesh at one phase.
ROWS_REVISION = "cycle"


def entry_key(spec: DatasetSpec) -> str:
    """The cache key of *spec*'s dataset: DatasetSpec.key, that key with ROWS_REVISION hashed in for
    a simulated train whose meshes repeat only after several input revolutions (placement.mesh_cycle_of)."""
    key = spec.key()
    if isinstance(spec, MeasuredSpec):
        return key
    from ..registry import get_registry
    from .placement import mesh_cycle_of, train_pairs

    where = f"dataset '{spec.name}'"
    if mesh_cycle_of(train_pairs(get_registry().get("model", spec.model, where), spec.preset, where)) == 1:
        return key
    return hashlib.sha256(f"{key}:{ROWS_REVISION}".encode()).hexdigest()[:24]


def entry_path(spec: DatasetSpec) -> Path:
    name = f"{entry_key(spec)}.npz"
    path = cache_dir() / name
    if _FALLBACK and not path.exists() and (_FALLBACK[0] / name).exists():
        return _FALLBACK[0] / name
    return path


def _digest(arrays: dict[str, np.ndarray]) -> str:
    """sha256 over every array's name, dtype, shape and bytes."""
    h = hashlib.sha256()
    for name in ARRAYS:
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape};".encode())
        h.update(memoryview(a).cast("B"))
    return h.hexdigest()


def _layout(arrays: dict[str, np.ndarray]) -> dict:
    return {name: {"shape": list(arrays[name].shape), "dtype": arrays[name].dtype.str} for name in ARRAYS}


def save(dataset: Dataset) -> Path:
    arrays = {name: np.asarray(getattr(dataset, name)) for name in ARRAYS}
    meta = {
        "key": entry_key(dataset.spec),
        "spec": asdict(dataset.spec),
        "domains": list(dataset.domains),
        "reference": list(dataset.reference),
        "meta": dataset.meta,
        "arrays": _layout(arrays),
        "sha256": _digest(arrays),
    }
    buf = io.BytesIO()
    np.savez(buf, meta=np.array(json.dumps(meta)), **arrays)
    path = entry_path(dataset.spec)
    _remove_stale_temporaries(path)
    try:
        atomic_write(path, buf.getvalue())
    except OSError as exc:
        if write_problem(exc) is None or (_FALLBACK and path.parent == _FALLBACK[0]):
            raise
        path = _fallback(path.parent, exc) / path.name
        atomic_write(path, buf.getvalue())
    return path


# A temporary file older than this was left by a writer killed before its rename (writing an
# entry takes seconds); a younger one may belong to another process writing the same entry.
STALE_S = 3600.0


def _remove_stale_temporaries(path: Path) -> None:
    now = time.time()
    for tmp in path.parent.glob(f".{path.name}.*.tmp"):
        try:
            if now - tmp.stat().st_mtime > STALE_S:
                tmp.unlink()
        except OSError:  # removed meanwhile by another process
            pass


def load(spec: DatasetSpec, path: Path | None = None) -> Dataset | None:
    """The cached dataset of *spec* (at *path*, by default its entry in the cache), or None."""
    path = path or entry_path(spec)
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if meta["key"] != entry_key(spec):
                raise ValueError("key mismatch")
            arrays = {name: data[name] for name in ARRAYS}
        _check_entry(meta, arrays)
    except FileNotFoundError:  # removed since exists() by another process: not damaged
        return None
    except Exception as exc:  # a damaged entry is not an error for the user: rebuild it
        warnings.warn(
            f"dataset cache entry {path.name} is unreadable or altered ({clipped(str(exc))}); rebuilding it",
            stacklevel=2,
        )
        try:
            path.unlink(missing_ok=True)
        except OSError:  # a read-only cache: the rebuilt entry goes to the fallback folder
            pass
        return None
    return Dataset(
        spec=spec, domains=tuple(meta["domains"]), reference=tuple(meta["reference"]), meta=meta["meta"], **arrays
    )


def _check_entry(meta: dict, arrays: dict[str, np.ndarray]) -> None:
    """Raise ValueError unless *arrays* are those the entry's writer recorded: the same
    shapes and dtypes (one row per sample in each) and the same sha256 of their bytes."""
    recorded = meta.get("arrays")
    if not isinstance(recorded, dict) or "sha256" not in meta:
        raise ValueError("written without shapes and a content digest (an older gearlab)")
    layout = _layout(arrays)
    for name in ARRAYS:
        if recorded.get(name) != layout[name]:
            raise ValueError(
                f"array {name} is {layout[name]['dtype']} {tuple(layout[name]['shape'])}, "
                f"written as {recorded.get(name)}"
            )
    rows = {layout[name]["shape"][0] if layout[name]["shape"] else None for name in ARRAYS}
    if len(rows) != 1:
        raise ValueError("its arrays do not hold one row per sample each")
    if _digest(arrays) != meta["sha256"]:
        raise ValueError("its content does not match the sha256 recorded when it was written")


def load_or_build(
    spec: DatasetSpec, executor=None, on_event: Callable[[Event], None] = lambda e: None
) -> tuple[Dataset, bool]:
    """The dataset of *spec* from the cache, or built (simulated or imported) and stored.
    Returns (dataset, was_cached)."""
    cached = load(spec)
    if cached is not None:
        on_event(Event("log", message=f"dataset {spec.name}: from cache ({entry_key(spec)})"))
        return cached, True
    if isinstance(spec, MeasuredSpec):
        dataset = import_measured(spec)
    else:
        dataset = build_dataset(spec, executor, on_event)
    save(dataset)
    return dataset, False
