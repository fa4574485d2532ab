"""One small reader per measured-file format (gearlab.data.importers uses them): each takes a path
and the asked-for channel names and returns a :class:`~gearlab.data.readers.base.Contents`."""

from .base import Contents, check_size, max_record_bytes
from .csv import _read_csv
from .hdf5 import _read_hdf5
from .matlab import _read_mat
from .npz import _read_npz
from .text import _read_text
from .wav import _read_wav

READERS = {
    "CSV": _read_csv,
    "text": _read_text,
    "zipped text": _read_text,
    "NPZ": _read_npz,
    "HDF5": _read_hdf5,
    "WAV": _read_wav,
    "MATLAB": _read_mat,
}

__all__ = ["READERS", "Contents", "check_size", "max_record_bytes"]
