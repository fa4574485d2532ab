"""Measured target records: the [target] of the kinds that read a rig's records (detection: history
and test files; gap: the history alone), each file with its role, label and operating condition."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..data.importers import check_measured_file
from ..data.textzip import parse_sensitivity, read_record
from ..errors import GearlabInputError, shown
from ..params import did_you_mean
from ..units import to_si

ROLES = ("history", "test")
FILE_KEYS = ("path", "role", "label", "condition")


@dataclass(frozen=True)
class TargetFile:
    path: str  # as written in the scenario (scores.csv's 'file')
    resolved: str
    role: str
    label: str
    condition: str  # "" until known (the tacho speed)


@dataclass(frozen=True)
class Target:
    vibration: int | str
    tacho: int | str
    pulses_per_rev: int
    sensitivity: float  # V per m/s²
    fs: float
    transient: str
    positive: str
    files: tuple[TargetFile, ...]

    def read(self, file: TargetFile):
        """One of the target's records, read with its channels, tacho and units."""
        return read_record(
            file.resolved,
            vibration=self.vibration,
            tacho=self.tacho,
            pulses_per_rev=self.pulses_per_rev,
            sensitivity=self.sensitivity,
            fs=self.fs,
            transient=self.transient,
        )


def target_files(files, where: str, base: Path, need=ROLES) -> tuple[TargetFile, ...]:
    """The [target] 'files' list: each {path, role, label, condition?}, paths relative to *base*;
    every role in *need* must be present (the gap kind needs the history alone)."""
    if not files:
        raise GearlabInputError(f"{where}: expected a list of files, each {{ path, role = 'history' | 'test', label }}")
    out = []
    for i, f in enumerate(files):
        at = f"{where} entry {i + 1}"
        if not isinstance(f, dict):
            raise GearlabInputError(f"{at}: expected a table {{ path, role, label }}, got {shown(f)}")
        for key in f:
            if key not in FILE_KEYS:
                raise GearlabInputError(
                    f"{at}: unknown key '{key}'{did_you_mean(key, FILE_KEYS)}; known keys: {', '.join(FILE_KEYS)}"
                )
        for key in ("path", "role", "label"):
            if not isinstance(f.get(key), str) or not f[key]:
                raise GearlabInputError(f"{at}: '{key}' must be a non-empty text")
        if f["role"] not in ROLES:
            raise GearlabInputError(
                f"{at}: role '{f['role']}'{did_you_mean(f['role'], ROLES)} is not one of {', '.join(ROLES)}"
            )
        condition = f.get("condition", "")
        if not isinstance(condition, str):
            raise GearlabInputError(f"{at}: 'condition' must be a text, e.g. '30 Hz high load'")
        path = Path(f["path"])
        resolved = path if path.is_absolute() else base / path
        check_measured_file(resolved, at, "a measured record (.zip of one text file, or the text)")
        out.append(TargetFile(f["path"], str(resolved), f["role"], f["label"], condition))
    seen = {}
    for i, f in enumerate(out):
        if seen.setdefault(f.resolved, i) != i:
            raise GearlabInputError(f"{where} entry {i + 1}: {f.path} is listed twice (entry {seen[f.resolved] + 1})")
    for role in need:
        if not any(f.role == role for f in out):
            raise GearlabInputError(
                f"{where}: no file has role = '{role}'; expected at least "
                + " and ".join(f"one {r}" for r in need)
                + " file"
            )
    return tuple(out)


def target_spec(t: dict, where: str, base: Path, need=ROLES) -> Target:
    if t["fs"] is None:
        raise GearlabInputError(
            f"{where} key 'fs': missing; text records carry no sampling rate (e.g. fs = '66666.67 Hz')"
        )
    fs = to_si(t["fs"], "Hz", f"{where} key 'fs'")
    if not fs > 0:
        raise GearlabInputError(f"{where} key 'fs': expected a positive sampling rate, got {shown(t['fs'])}")
    if t["transient"] not in ("none", "stats"):
        raise GearlabInputError(f"{where} key 'transient': expected 'none' or 'stats', got {shown(t['transient'])}")
    for key in ("vibration", "tacho"):
        if isinstance(t[key], int) and t[key] < 0:
            raise GearlabInputError(f"{where} key '{key}': a column index is 0 or more, got {t[key]}")
    if t["vibration"] == t["tacho"]:
        raise GearlabInputError(f"{where} key 'tacho': the same column as the vibration ({t['tacho']!r})")
    files = target_files(t["files"], f"{where} key 'files'", base, need)
    return Target(
        t["vibration"],
        t["tacho"],
        t["pulses_per_rev"],
        parse_sensitivity(t["sensitivity"], f"{where} key 'sensitivity'"),
        fs,
        t["transient"],
        t["positive"],
        files,
    )
