"""Signal pipeline (thesis 2.4.3, 3.2, 4.1; docs/physics.md): from a record to dataset samples.

    record (signal, tacho | pulses | speed) ─► continuous shaft angle θ        angle.py
        ─► complete revolutions, resampled to 4096 angles                     pipeline.py
        ─► start-up transient dropped (detected, not hard-coded)              pipeline.py
        ─► standardised against the healthy reference (eq. 2.112/4.6)         standardise.py
        ─► noise at an SNR in dB (eq. 4.1–4.5), TSA over J revolutions (4.7)  noise.py
    spectra in Hz and in shaft orders for the figures                         spectra.py

The same functions serve simulated records and measured data imported from files. Every
bad input raises :class:`gearlab.errors.GearlabInputError` with one line saying what is
wrong and what was expected.
"""

from .angle import angle_from_pulses, angle_from_speed, unwrap_tacho
from .checks import check_signal
from .noise import NOISE_KINDS, SNR_DB_RANGE, add_noise, tsa
from .pipeline import (
    POINTS,
    TRANSIENT_METHODS,
    CutRevolutions,
    cut_revolutions,
    first_complete,
    resample_revolutions,
    revolution_starts,
    steady_start,
    steady_start_stats,
    upsampled,
)
from .spectra import order_spectrum, spectrum
from .standardise import Standardiser, StandardiserAccumulator

__all__ = [
    "NOISE_KINDS",
    "POINTS",
    "SNR_DB_RANGE",
    "TRANSIENT_METHODS",
    "CutRevolutions",
    "Standardiser",
    "StandardiserAccumulator",
    "add_noise",
    "angle_from_pulses",
    "angle_from_speed",
    "check_signal",
    "cut_revolutions",
    "first_complete",
    "order_spectrum",
    "resample_revolutions",
    "revolution_starts",
    "spectrum",
    "steady_start",
    "steady_start_stats",
    "tsa",
    "unwrap_tacho",
    "upsampled",
]
