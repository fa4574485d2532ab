"""WAV: channels by index ("0", "1", ...); the rate from the header; integer PCM as fractions of full
scale, with its step recorded (the quantisation a comparison must reproduce)."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .base import Contents


def _read_wav(path: Path, names: Sequence[str]) -> Contents:
    """Channels "0", "1", … of a WAV file; integer PCM scaled to [-1, 1), float kept as is."""
    from scipy.io import wavfile

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            rate, data = wavfile.read(path)
        except ZeroDivisionError:  # scipy divides by the header's bytes per frame
            raise ValueError(
                "its header declares 0 channels or 0 bytes per sample; expected at least one channel of samples"
            ) from None
        except ValueError as exc:  # numpy cannot shape a last, partial frame into channels
            if "reshape" not in str(exc):
                raise
            raise ValueError("its data ends inside a sample frame (a truncated file?); expected whole frames") from None
    for w in caught:
        # scipy reads what is there of a truncated file and only warns: refuse, never half a record.
        if "EOF" in str(w.message):
            raise ValueError(str(w.message))
    data = np.asarray(data)
    if data.ndim == 1:
        data = data[:, None]
    step = 0.0
    if data.dtype.kind == "u":  # 8-bit PCM is unsigned around 128
        half = 2.0 ** (8 * data.dtype.itemsize - 1)
        data, step = (data.astype(np.float64) - half) / half, 1.0 / half
    elif data.dtype.kind == "i":  # 24-bit PCM arrives left-justified in int32
        step = 1.0 / 2.0 ** (8 * data.dtype.itemsize - 1)
        data = data.astype(np.float64) * step
    if data.ndim != 2 or data.shape[1] == 0:
        raise ValueError("it holds no channel; expected at least one")
    channels = [str(i) for i in range(data.shape[1])]
    found = {n: data[:, int(n)] for n in dict.fromkeys(names) if n in channels}
    steps = {n: step for n in found} if step else {}
    return Contents(found, channels, rates=[("the WAV header", np.asarray(rate))], steps=steps)
