"""Measured records in whitespace-separated text, plain or zipped (the PHM 2009 gearbox format).

A data-acquisition system often writes one text file per record: one row per sample,
columns separated by blanks, no sampling rate in the file, voltages as measured. Such a
record reaches gearlab through three steps:

    file (.zip of one text file, or the text itself)
       ─► the asked-for columns, as float64                  read_columns (streamed, chunked)
       ─► vibration in m/s² = volts / sensitivity            parse_sensitivity (pint, "10 mV/g")
       ─► continuous input-shaft angle from a tacho with N pulses per revolution
       ─► complete revolutions at 4096 angles                signals.cut_revolutions

The text is read from the archive in blocks of ``CHUNK_BYTES`` and only the asked-for
columns are kept, so a 13 MB text needs about the size of those columns (plus one block),
never the whole text and its parsed table at once. The one memory limit of every measured
file (``GEARLAB_MAX_RECORD_MB``, gearlab.data.readers.base) holds here too: a text (or a
zip member) declaring more is refused before a byte is inflated, and the text read and the
columns kept are counted while streaming, so an archive that lies about its size is
stopped at the limit too.

Columns are chosen by 0-based index (an int, or a text of digits) or by name when the
first row is a header of names. A tacho with ``pulses_per_rev`` = N equally spaced marks
gives a pulse every 1/N revolution: the j-th rising edge is at θ = 2πj/N
(:func:`gearlab.signals.angle_from_pulses` divided by N). The revolutions start at the first
mark seen in the record, which is any one of the N marks: two records of the same shaft may
start 2πm/N apart (the chip kind aligns them, :func:`align_to`).

Every bad file raises :class:`GearlabInputError` naming the file, the line or column and
what was expected.
"""

from __future__ import annotations

import os
import re
import zipfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import GearlabInputError, shown
from ..signals import POINTS, angle_from_pulses, cut_revolutions, steady_start_stats
from ..signals.checks import fmt_hz
from ..units import to_si
from .readers.base import check_size, max_record_bytes

__all__ = ["TextRecord", "align_to", "parse_sensitivity", "read_columns", "read_record"]

# Bytes of text parsed at a time: large enough for numpy to parse fast, small enough that
# a block's tokens (about 60 bytes each as Python objects) stay a few tens of MB.
CHUNK_BYTES = 1 << 18
STANDARD_GRAVITY = 9.80665  # m/s², the "g" of accelerometer sensitivities (ISO 80000-3)
TWO_PI = 2.0 * np.pi


# --- sensor sensitivity ------------------------------------------------------------------

# "g" in a sensitivity is standard gravity, never the gram: pint's name for it is g_n.
_GRAVITY = re.compile(r"(?<![\w.])g(?![\w])")


def parse_sensitivity(value, where: str) -> float:
    """An accelerometer sensitivity ("10 mV/g", "1.02 mV/(m/s^2)", or a number in V/(m/s²))
    as volts per m/s²."""
    if isinstance(value, str):
        value = _GRAVITY.sub("g_n", value)
    try:
        s = to_si(value, "V*s^2/m", where)
    except GearlabInputError as exc:
        raise GearlabInputError(f"{exc} (volts per acceleration, e.g. '10 mV/g'; g is standard gravity)") from None
    if not s > 0:
        raise GearlabInputError(f"{where}: expected a positive sensitivity such as '10 mV/g', got {shown(value)}")
    return s


# --- reading the columns -----------------------------------------------------------------


@contextmanager
def _open_text(path: Path):
    """A binary stream of the record's text: the one text member of a .zip, or the file."""
    try:
        if path.suffix.lower() != ".zip":
            with path.open("rb") as f:
                check_size(path, "the text", os.fstat(f.fileno()).st_size)
                yield f, str(path)
            return
        with zipfile.ZipFile(path) as z:
            members = [i for i in z.infolist() if not i.is_dir() and not i.filename.startswith("__MACOSX/")]
            if len(members) != 1:
                names = ", ".join(shown(i.filename, 40) for i in members[:5]) or "none"
                raise GearlabInputError(
                    f"{path}: expected a zip archive of exactly one text file, found {len(members)} ({names})"
                )
            info = members[0]
            # declared: a few kB of deflated zeros may announce gigabytes (a zip bomb)
            check_size(path, f"member {shown(info.filename)} (as its archive declares it)", info.file_size)
            with z.open(info) as f:
                yield f, f"{path}: member {shown(info.filename)}"
    except FileNotFoundError:
        raise GearlabInputError(
            f"{path}: no such file; expected a measured record (.zip of one text file, or the text)"
        ) from None
    except IsADirectoryError:
        raise GearlabInputError(f"{path}: is a directory; expected a measured record") from None
    except zipfile.BadZipFile as exc:
        raise GearlabInputError(f"{path}: not a readable zip archive ({exc})") from None
    except (OSError, EOFError, zipfile.LargeZipFile, NotImplementedError, RuntimeError) as exc:
        # a truncated archive, an encrypted member, an unsupported compression
        raise GearlabInputError(f"{path}: cannot read ({exc})") from None


def _is_number(token: bytes) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _resolve(columns, header: list[str] | None, width: int, where: str) -> list[int]:
    """Column indices of the asked-for columns (0-based index or header name)."""
    out = []
    for c in columns:
        if isinstance(c, bool):
            raise GearlabInputError(f"{where}: column {c!r}: expected a 0-based index or a column name")
        if isinstance(c, str) and c.strip().isdigit():
            c = int(c)
        if isinstance(c, int):
            if not 0 <= c < width:
                raise GearlabInputError(
                    f"{where}: column {c} does not exist; the file has {width} columns "
                    f"(0-based indices 0 … {width - 1})"
                )
            out.append(c)
        elif header is not None and c in header:
            out.append(header.index(c))
        else:
            known = ", ".join(header) if header else f"no header row, so indices 0 … {width - 1}"
            raise GearlabInputError(f"{where}: no column named {shown(c)}; known: {known}")
    return out


def _bad_line(block: bytes, first_line: int, width: int, where: str) -> GearlabInputError:
    """The error for the first line of *block* that is not *width* numbers (slow path)."""
    for offset, line in enumerate(block.split(b"\n")):
        tokens = line.split()
        if not tokens or tokens[0].startswith(b"#"):
            continue
        number = first_line + offset
        if len(tokens) != width:
            return GearlabInputError(
                f"{where}: line {number} has {len(tokens)} fields, expected {width} (as the first data line)"
            )
        for i, t in enumerate(tokens):
            if not _is_number(t):
                text = t.decode("utf-8", "replace")
                return GearlabInputError(f"{where}: line {number} column {i}: {shown(text)} is not a number")
    return GearlabInputError(f"{where}: unreadable numbers near line {first_line}")  # pragma: no cover


def read_columns(path, columns) -> tuple[dict, list[str] | None, int]:
    """The asked-for columns of a whitespace-separated text (or a .zip of one), streamed.

    Returns ({column as asked: float64 array}, header names or None, number of columns).
    Blank lines and lines starting with '#' are skipped; a first data line that is not all
    numbers is the header of column names.
    """
    path = Path(path)
    columns = list(dict.fromkeys(columns))
    parts: list[np.ndarray] = []
    header: list[str] | None = None
    width = 0
    picked: list[int] = []
    limit = max_record_bytes()
    text_bytes, kept_bytes = 0, 0  # of text read and of columns kept, against the limit
    with _open_text(path) as (stream, where):
        line_no = 1  # number of the first line of the pending block
        rest = b""
        while True:
            data = stream.read(CHUNK_BYTES)
            text_bytes += len(data)
            if text_bytes > limit:  # more than declared (a lying archive, a file that grows)
                check_size(where, "the text read so far", text_bytes)
            block = rest + data
            if data:
                cut = block.rfind(b"\n") + 1
                if cut == 0:  # one line longer than a block: read on
                    rest = block
                    if len(rest) > 64 * CHUNK_BYTES:
                        raise GearlabInputError(
                            f"{where}: line {line_no} is longer than {64 * CHUNK_BYTES} bytes; "
                            "expected rows of a few numbers"
                        )
                    continue
                block, rest = block[:cut], block[cut:]
            elif not block:
                break
            else:
                rest = b""
            lines_here = block.count(b"\n") + (0 if block.endswith(b"\n") else 1)
            if b"#" in block or b"\r" in block or not width:
                kept = []
                for line in block.split(b"\n"):
                    tokens = line.split()
                    if not tokens or tokens[0].startswith(b"#"):
                        continue
                    if not width:  # the first data line: a header, or the first row
                        width = len(tokens)
                        if not all(_is_number(t) for t in tokens):
                            header = [t.decode("utf-8", "replace") for t in tokens]
                            continue
                    kept.append(line)
                body = b"\n".join(kept)
                if width and not picked:
                    picked = _resolve(columns, header, width, where)
            else:
                body = block
            if body.strip():
                try:
                    values = np.array(body.split(), dtype=np.float64)
                except ValueError:
                    raise _bad_line(block, line_no, width, where) from None
                rows = sum(1 for line in body.split(b"\n") if line.strip())
                if values.size != rows * width:
                    raise _bad_line(block, line_no, width, where)
                parts.append(values.reshape(rows, width)[:, picked].copy())
                kept_bytes += parts[-1].nbytes
                if kept_bytes > limit:  # short rows of many numbers: the columns outgrow their text
                    check_size(where, "the columns read so far", kept_bytes)
            line_no += lines_here
            if not data:
                break
    if not parts:
        raise GearlabInputError(
            f"{where}: no rows of numbers; expected one row per sample, columns separated by blanks"
        )
    table = np.concatenate(parts) if len(parts) > 1 else parts[0]
    return {c: table[:, i] for i, c in enumerate(columns)}, header, width


# --- a record ----------------------------------------------------------------------------


@dataclass(frozen=True)
class TextRecord:
    """One measured record cut into revolutions: *revolutions* (n, points) in m/s², not
    standardised, in record order, starting at the first tacho mark."""

    path: str
    revolutions: np.ndarray
    speed_hz: float
    fs: float
    samples: int
    transient_revolutions: int


def read_record(
    path,
    *,
    vibration,
    tacho,
    pulses_per_rev: int,
    sensitivity: float,
    fs: float,
    points: int = POINTS,
    transient: str = "none",
) -> TextRecord:
    """Read a record (``read_columns``), convert the vibration to m/s², find the shaft angle
    from the tacho's N = *pulses_per_rev* marks per revolution and cut the complete
    revolutions (*transient* "stats" drops a start-up transient, "none" keeps all)."""
    found, _, _ = read_columns(path, [vibration, tacho])
    raw = found[vibration]
    if raw.size and raw.min() == raw.max():  # refused as every other reader's import refuses it
        raise GearlabInputError(
            f"{path}: vibration column {shown(vibration)}: all {raw.size} values equal {raw[0]:g}; expected "
            "a measured vibration (a constant column: a wrong column, or a sensor not connected)"
        )
    vib = raw / sensitivity
    where = f"{path}: tacho column {shown(tacho)}"
    try:
        angle = angle_from_pulses(found[tacho], fs) / pulses_per_rev
    except GearlabInputError as exc:
        raise GearlabInputError(f"{where}: {exc}") from None
    turns = (angle[-1] - angle[0]) / TWO_PI
    if turns < 2:
        raise GearlabInputError(
            f"{where}: the {pulses_per_rev}-pulses-per-revolution tacho shows {turns:.3g} "
            f"revolutions in {vib.size} samples at {fmt_hz(fs)}; expected at least 2 (is "
            "pulses_per_rev right?)"
        )
    # the wrapped angle in [-π, π): cut_revolutions unwraps it and starts revolutions at its 2πk crossings
    wrapped = (angle + np.pi) % TWO_PI - np.pi
    try:
        cut = cut_revolutions(vib, fs, tacho=wrapped, points=points, transient="none")
        start = steady_start_stats(cut.revolutions) if transient == "stats" else 0
    except GearlabInputError as exc:
        raise GearlabInputError(f"{path}: vibration column {shown(vibration)}: {exc}") from None
    return TextRecord(str(path), cut.revolutions[start:], float(cut.speed_hz), float(fs), int(vib.size), int(start))


def align_to(reference: np.ndarray, signal: np.ndarray, marks: int) -> tuple[int, np.ndarray]:
    """(m, *signal* advanced by m/*marks* of a turn), m = 0 … marks-1 the advance whose mean
    revolution correlates best with *reference* (rows of *signal*: revolutions).

    Two records of one shaft may start at different tacho marks, i.e. 2πm/N apart; the shift
    is done in the order domain (exact for a periodic, band-limited revolution)."""
    n = reference.shape[-1]
    R = np.fft.rfft(reference)
    S = np.fft.rfft(np.mean(np.atleast_2d(signal), axis=0))
    orders = np.arange(R.size)
    best, best_corr = 0, -np.inf
    for m in range(marks):
        phase = np.exp(2j * np.pi * orders * m / marks)  # x(θ) -> x(θ + 2πm/marks)
        corr = float(np.real(np.sum(np.conj(R) * S * phase)))
        if corr > best_corr:
            best, best_corr = m, corr
    phase = np.exp(2j * np.pi * orders * best / marks)
    shifted = np.fft.irfft(np.fft.rfft(signal, axis=-1) * phase, n=n, axis=-1)
    return best, shifted.astype(signal.dtype, copy=False)
