"""Content-addressed dataset cache: `$GEARLAB_CACHE/<key>.npz`, no pickle, atomic writes.

The key hashes the canonical spec and the physics version (DatasetSpec.key). An entry is
written to a temporary file in the cache directory and renamed into place, so a killed
build leaves no entry; an unreadable or mismatched entry is removed and rebuilt.
"""

from __future__ import annotations

import io
import json
import os
import time
import warnings
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

import numpy as np
import platformdirs

from ..errors import GearlabInputError
from ..runs import Event, atomic_write
from .spec import Dataset, DatasetSpec

ARRAYS = ("X", "label", "fault", "intensity", "tooth", "rfa", "revolution", "domain")


def cache_dir() -> Path:
    path = Path(os.environ.get("GEARLAB_CACHE") or platformdirs.user_cache_dir("gearlab"))
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise GearlabInputError(f"cannot create the dataset cache directory {path}: {exc.strerror}") from None
    return path


def entry_path(spec: DatasetSpec) -> Path:
    return cache_dir() / f"{spec.key()}.npz"


def save(dataset: Dataset) -> Path:
    meta = {
        "key": dataset.key,
        "spec": asdict(dataset.spec),
        "domains": list(dataset.domains),
        "reference": list(dataset.reference),
        "meta": dataset.meta,
    }
    buf = io.BytesIO()
    np.savez(buf, meta=np.array(json.dumps(meta)), **{name: getattr(dataset, name) for name in ARRAYS})
    path = entry_path(dataset.spec)
    _remove_stale_temporaries(path)
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
            if meta["key"] != spec.key():
                raise ValueError("key mismatch")
            arrays = {name: data[name] for name in ARRAYS}
    except FileNotFoundError:  # removed since exists() by another process: not damaged
        return None
    except Exception as exc:  # a damaged entry is not an error for the user: rebuild it
        warnings.warn(f"dataset cache entry {path.name} is unreadable ({exc}); rebuilding it", stacklevel=2)
        path.unlink(missing_ok=True)
        return None
    return Dataset(spec=spec, domains=tuple(meta["domains"]), reference=tuple(meta["reference"]),
                   meta=meta["meta"], **arrays)


def load_or_build(spec: DatasetSpec, executor=None, on_event: Callable[[Event], None] = lambda e: None
                  ) -> tuple[Dataset, bool]:
    """The dataset of *spec* from the cache, or built (simulated or imported) and stored.
    Returns (dataset, was_cached)."""
    from .builder import build_dataset
    from .importers import MeasuredSpec, import_measured

    cached = load(spec)
    if cached is not None:
        on_event(Event("log", message=f"dataset {spec.name}: from cache ({spec.key()})"))
        return cached, True
    if isinstance(spec, MeasuredSpec):
        dataset = import_measured(spec)
    else:
        dataset = build_dataset(spec, executor, on_event)
    save(dataset)
    return dataset, False
