"""A DAQ's raw binary file (float32 or int16 samples, no header of their own; the rate, channels and scale in a side
file beside it): gearlab reads no such file, and says how to make one it reads.

Its samples alone do not say their type, byte order, channel count or rate (a float32 take read as int16 is noise of
the right length), so nothing is guessed: the refusal names the side header found beside it and gives the two lines
of numpy that write the samples to an .npz with its rate, which every kind reads. A text reader's words on such a file
(a .dat of int16: "'utf-8' codec can't decode byte 0xff in position 0") said nothing of that.
"""

from __future__ import annotations

from pathlib import Path

RAW = (".bin", ".raw", ".i16", ".f32", ".pcm", ".daq")  # suffixes of raw samples, never text
SIDE = (".json", ".txt", ".hdr", ".ini", ".xml", ".yaml", ".yml", ".inf")  # a logger's side header
PROBE = 4096  # bytes a text file's start is read for control bytes
CONTROL = 0.01  # share of control bytes (not tab, CR, LF, form feed) over which a file is no text


def looks_binary(path: Path) -> bool:
    """Whether the start of *path* holds control bytes no text has (raw samples: float32's and int16's zero and
    sign bytes)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(PROBE)
    except OSError:
        return False  # the reader says why
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        return False  # UTF-16 text (Excel's 'Unicode text'): its reader's words
    control = sum(b < 32 and b not in (9, 10, 12, 13) for b in head)
    return bool(head) and control > CONTROL * len(head)


def refusal(path: Path, suffix: str, text: bool) -> str | None:
    """One line refusing *path* (its suffix *suffix*, lower case; *text*: a suffix read as text, .dat or .csv) as raw
    binary samples, naming its side header and the conversion to .npz; None where it is not raw binary (text, or
    another unknown suffix: an Excel workbook is no DAQ's samples)."""
    if not (suffix in RAW or text and looks_binary(path)):
        return None
    sides = [p.name for p in sorted(path.parent.glob(f"{path.stem}.*")) if p.suffix.lower() in SIDE and p != path]
    side = f"the rate, channels and scale in '{sides[0]}' beside it" if sides else "the rate, channels and scale"
    return (
        f"{path}: raw binary samples (no header gearlab reads; their type, byte order and channels are not guessed); "
        f"expected a format that carries its rate: with {side}, write them as an .npz: x = numpy.fromfile("
        f"'{path.name}', dtype='<f4').reshape(-1, CHANNELS) (dtype as the header says: '<f4' float32, '>i2' "
        f"big-endian int16 times its scale in V a count); numpy.savez('{path.stem}.npz', acc=x[:, 0], tacho=x[:, 1], "
        "fs=RATE)"
    )
