"""Day-to-day scoring (`gearlab score RUN_DIR FILE...`): what a finished run keeps so that new
recordings are scored by its trained methods and thresholds without training again, and the
history of those scores.

    run directory
      scoring.json                 what scoring needs besides the arrays: the target's keys, the
                                   units, the threshold rule, each condition's speed and history
      scoring/condition<i>.npz     a condition's standardiser, alignment reference and history
                                   revolutions (standardised, aligned)
      scoring/models/<key>.pt      each training's model, as trained (model_key)
      scoring/history.jsonl        one line per scored record, method and unit: appended (once a take)
      scoring/not_scored.jsonl     one line per take refused among several scored at once, with why

Every file is reached through the run directory (gearlab.confined: no link followed). A model is
a whole torch module saved with torch.save and loaded with weights_only=True: the unpickler
builds only the torch.nn and gearlab module classes the file names (a file naming anything else
is refused), never runs code of the file.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import importlib
import io
import json
import threading
import zipfile
from collections.abc import Iterator, Mapping

import numpy as np

from ..confined import Confined
from ..errors import GearlabInputError
from ..runs import RunDir

SCORING_FILE = "scoring.json"
MODELS = ("scoring", "models")
HISTORY = ("scoring", "history.jsonl")
SKIPPED = ("scoring", "not_scored.jsonl")


def model_key(unit: str) -> str:
    """A training's model file name: its unit name (which holds '/', ',' and '=') hashed."""
    return hashlib.sha256(unit.encode()).hexdigest()[:20]


def save_model(folder: Confined, unit: str, model) -> None:
    """*model* (a torch module) into *folder*/<model_key(unit)>.pt, written whole."""
    import torch  # here: start-up time

    buf = io.BytesIO()
    torch.save(model.to("cpu"), buf)
    (folder / f"{model_key(unit)}.pt").write(buf.getvalue())


def _allowed(name: str):
    """The class a model file names, when it is a torch.nn or gearlab module class; else None."""
    import torch

    module, _, attr = name.rpartition(".")
    if not (module.startswith("torch.nn.modules.") or module.startswith("gearlab.")):
        return None
    try:
        cls = getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError):
        return None
    return cls if isinstance(cls, type) and issubclass(cls, torch.nn.Module) else None


def load_model(folder: Confined, unit: str):
    """The model of training *unit* (save_model), on the CPU, in evaluation mode."""
    import torch

    path = folder / f"{model_key(unit)}.pt"
    if not path.exists():
        raise GearlabInputError(
            f"{path}: missing: the trained model of '{unit}' (a run from before gearlab score kept its "
            "models); expected a run made by this version: run the scenario again"
        )
    data = path.read_bytes()
    try:
        names = torch.serialization.get_unsafe_globals_in_checkpoint(io.BytesIO(data))
        classes = [_allowed(n) for n in names]
        if any(c is None for c in classes):
            bad = next(n for n, c in zip(names, classes) if c is None)
            raise GearlabInputError(f"{path}: names {bad!r}, not a module class of torch or gearlab; refused")
        with torch.serialization.safe_globals(classes):
            model = torch.load(io.BytesIO(data), weights_only=True, map_location="cpu")
    except GearlabInputError:
        raise
    except Exception as exc:  # noqa: BLE001 - a damaged file fails in torch's own ways
        raise GearlabInputError(f"{path}: damaged model ({type(exc).__name__}); run the scenario again") from None
    if not isinstance(model, torch.nn.Module):
        raise GearlabInputError(f"{path}: not a model (a {type(model).__name__}); run the scenario again")
    return model.eval()


def save_arrays(target: Confined, **arrays) -> None:
    """*arrays* as an uncompressed npz: a history's noisy floats deflate by ~8 % at 0.16 s of CPU per
    4 MB (50 times the write's own); load_arrays reads older, compressed ones as well."""
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    target.write(buf.getvalue())


_DAMAGED = (ValueError, OSError, EOFError, zipfile.BadZipFile)


class SavedArrays(Mapping):
    """A saved npz's arrays by name (load_arrays), each read from the file's bytes at its first use and kept: a
    take that `gearlab score` localises reads the envelope's history in one band of dozens (a condition's
    localisation state: 992 arrays, 0.12 s of CPU read whole, at each call)."""

    def __init__(self, source: Confined, data):
        self._source, self._data, self._read = source, data, {}
        self._lock = threading.Lock()  # one reader of the file's bytes at a time (the envelope's bands, read aside)

    def __getitem__(self, name: str) -> np.ndarray:
        with self._lock:
            if name not in self._read:
                if name not in self._data.files:
                    raise KeyError(name)
                try:
                    self._read[name] = self._data[name]
                except _DAMAGED as exc:
                    raise GearlabInputError(f"{self._source}: damaged ({exc}); run the scenario again") from None
            return self._read[name]

    def __contains__(self, name: object) -> bool:  # without reading the array (Mapping's reads it)
        return name in self._data.files

    def __iter__(self) -> Iterator[str]:
        return iter(self._data.files)

    def __len__(self) -> int:
        return len(self._data.files)


def load_arrays(source: Confined) -> SavedArrays:
    if not source.exists():
        raise GearlabInputError(f"{source}: missing; expected the run's scoring state (run the scenario again)")
    try:
        return SavedArrays(source, np.load(io.BytesIO(source.read_bytes()), allow_pickle=False))
    except _DAMAGED as exc:
        raise GearlabInputError(f"{source}: damaged ({exc}); run the scenario again") from None


def append_history(run: RunDir, rows: list[dict]) -> None:
    """Append scored rows to the run's scoring history (one JSON line each), stamped now. A take scored before (its
    'digest' in the history, under any name) or given twice is appended once: its rows say so ('already'). A take
    scored twice was two points of the trend, and a renamed copy a third."""
    before = {h["digest"]: h for h in read_history(run) if h.get("digest")}
    first: dict[str, str] = {}
    for r in rows:
        if r.get("digest") is None:
            continue
        h, name = before.get(r["digest"]), first.setdefault(r["digest"], r["file"])
        if h is not None:
            r["already"] = f"scored before, at {h['scored_at']} as {h['file']}: not added to the history again"
        elif name != r["file"]:
            r["already"] = f"the same take as {name}: not added to the history twice"
    _append(run, HISTORY, [r for r in rows if not r.get("already")])


def append_skipped(run: RunDir, rows: list[dict]) -> None:
    """Append the rows of takes `gearlab score` refused among several (their 'skipped': why), stamped now: the
    scoring history holds the scored takes only; the trend says which were not scored (read_skipped)."""
    _append(run, SKIPPED, rows)


def _append(run: RunDir, where: tuple[str, str], rows: list[dict]) -> None:
    if not rows:
        return
    stamp = _dt.datetime.now().isoformat(timespec="seconds")
    target = run.file(*where)
    target.parent.mkdir()
    target.append("".join(json.dumps({"scored_at": stamp, **r}) + "\n" for r in rows))


def read_history(run: RunDir) -> list[dict]:
    """The scoring history (append_history), oldest first; [] when nothing was scored yet."""
    return _lines(run, HISTORY)


def read_skipped(run: RunDir) -> list[dict]:
    """The takes `gearlab score` refused among several (append_skipped), oldest first."""
    return _lines(run, SKIPPED)


def _lines(run: RunDir, where: tuple[str, str]) -> list[dict]:
    source = run.file(*where)
    if not source.exists():
        return []
    out = []
    for line in source.read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue  # a line cut short by a crash: the others stand
    return out
