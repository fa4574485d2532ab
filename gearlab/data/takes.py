"""A logger's file of several takes one after another, a column marking each sample's take: each take read as a
recording of its own, named "file.csv[segment=3]" (the file, the column, the take's mark) wherever a record is named
(reports, tables, score histories). The key `takes = "segment"` (kinds.common.MEASURED: a [target], a 'files'
entry, `gearlab score --key takes=segment`) turns each of its files into its takes (take_paths); a take's name is a
path every reader takes (recordings.read_contents keeps its rows alone, readers.take_rows; the time within a take
as the take's own)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import GearlabInputError
from ..files import split_take, take_file, take_name
from .readers.take_rows import marks_of, no_take_column
from .recordings import read_contents, read_header


def take_paths(file, column: str, where: str, name=None) -> list[str]:
    """The takes of *file* under *column*, in the order they first come: one name each (take_name, of *name*: the
    file as the scenario writes it). One line naming *where* where the column is missing (from the file's header,
    as `gearlab validate` checks it), or where a take's rows are not one block. A take named alone
    ("day2.npz[Take=2]", under a [target]'s takes key that splits the other files) is that take, not split again."""
    if split_take(file if name is None else name) is not None:
        return [str(file if name is None else name)]
    file, name = take_file(file), file if name is None else name
    header = read_header(file)
    if header.channels and not header.find(column):
        raise no_take_column(file, column, header.channels, where)
    try:
        contents, _ = read_contents(file, [column], {column: "takes"})
    except GearlabInputError as exc:
        if "no takes channel" in str(exc):
            raise no_take_column(file, column, read_contents(file, [])[0].available, where) from None
        raise
    marks = marks_of(np.ravel(contents.found[column]))
    starts = np.flatnonzero(np.r_[True, marks[1:] != marks[:-1]])
    order = list(dict.fromkeys(marks[starts].tolist()))
    if len(order) < starts.size:  # a take's rows split: interleaved channels, not takes one after another
        again = next(m for i, m in enumerate(marks[starts].tolist()) if m in marks[starts][:i].tolist())
        raise GearlabInputError(
            f"{where}: {file} column {column!r}: take {again!r} comes back after another take; expected each take's "
            "rows one block, takes one after another"
        )
    return [take_name(name, column, m) for m in order]


def file_takes(file, column: str | None, where: str, known: Sequence[str] = ()) -> list[str]:
    """The records *file* stands for: its takes under *column* (take_paths); *column* None, under the first of
    *known* (the take columns a run's files were read by: gearlab score) its header has, else the file itself."""
    if column is None:
        channels = read_header(file).channels
        column = next((c for c in known if c in channels), "")
    return take_paths(file, column, where) if column else [str(file)]
