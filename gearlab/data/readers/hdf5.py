"""HDF5: datasets by path ("group/acc", or "acc" where one dataset has that last name), or a 2-D dataset's column
by the name an attribute gives it (named_columns); the rate from an 'fs' attribute on the channel or the nearest
group above that has one, or an 'fs'/'t' dataset there."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ...errors import GearlabInputError
from .base import (
    UNIT_ATTRIBUTES,
    Contents,
    _normalise,
    _text_array,
    _time_field,
    check_size,
    column_of,
    held_to_vibration,
    is_unit_entry,
    stated_unit,
    stated_units,
    time_scale,
)
from .rates import named, rate_field


def _h5py():
    try:
        import h5py
    except ImportError:  # pragma: no cover - h5py is a dependency
        raise GearlabInputError("reading HDF5 and MATLAB v7.3 files needs h5py: pip install h5py") from None
    return h5py


def _read_hdf5(path: Path, names: Sequence[str], matlab: bool = False) -> Contents:
    """Datasets by path ("group/acc").

    Rate fields are scoped like variables: for each channel, the nearest level that has
    any wins — an 'fs' attribute on the channel itself, else an 'fs' attribute or an
    'fs'/'t' dataset in its group, else in the group above, up to the file's root. So a
    file-wide rate can be overridden per group, and groups recorded at different rates
    can share one file. The fields found for the different channels must agree.

    matlab: the file is a MATLAB v7.3 MAT-file, whose variables are HDF5 datasets stored
    transposed, with text as uint16 character codes and internals under '#refs#'.
    """
    h5py = _h5py()

    def read(ds):
        _own_data(h5py, path, ds)
        # declared, not stored: a dataset never written takes no room in the file
        check_size(path, f"dataset '{ds.name}'", (ds.size or 0) * max(ds.dtype.itemsize, 8))
        if h5py.check_string_dtype(ds.dtype) is not None:
            return _normalise(ds.asstr()[()])
        value = np.asarray(ds[()])
        if matlab:
            cls = ds.attrs.get("MATLAB_class", b"")
            cls = cls.decode() if isinstance(cls, bytes) else str(cls)
            value = value.T  # back to MATLAB's (rows, columns)
            if cls == "char" and value.dtype.kind in "iu":
                rows = np.atleast_2d(value)
                return _normalise(["".join(map(chr, row)) for row in rows.tolist()])
            value = np.squeeze(value)  # as loadmat(squeeze_me=True) gives v5 variables
        return _normalise(value)

    def level_fields(node, is_group: bool) -> tuple[list, list]:
        """(rates, times) defined at one node: its 'fs' attributes, and for a group its
        'fs' and 't'/'time' datasets."""
        rates = [  # in Hz, a unit in the name read ('fs_kHz': rates.rate_field)
            rate_field(f"attribute '{key}' of '{node.name}'", key, _normalise(value))
            for key, value in node.attrs.items()
            if named(key) is not None
        ]
        times = []
        if is_group:
            for key in node:
                if not isinstance(node.get(key, getlink=True), h5py.HardLink):
                    continue  # a link is no field of this group (an external one would open another file)
                child = node.get(key)
                if isinstance(child, h5py.Dataset) and named(key) is not None:
                    rates.append(rate_field(f"dataset '{child.name}'", key, read(child)))
                elif isinstance(child, h5py.Dataset) and time_scale(key) is not None:
                    times.append(_time_field(f"time dataset '{child.name}'", read(child), time_scale(key)))
        return rates, times

    with h5py.File(path, "r") as f:
        datasets = _hdf5_datasets(h5py, f)
        columns = named_columns(f, datasets)
        whole = named_matrices({d: f[d].shape for d in datasets}, columns)
        listed = [d for d in datasets if d not in whole] + [n for n in columns if n not in datasets]
        contents = Contents({}, listed)
        seen: set[str] = set()
        own: dict[str, tuple] = {}  # each channel's one rate field, where it has one
        at: dict[str, str] = {}  # each channel's dataset path
        values: dict[str, np.ndarray] = {}  # each dataset read, once for all its named columns
        for name in dict.fromkeys(names):
            column = columns.get(name) if name not in datasets else None
            try:
                obj = _hard_linked(h5py, path, f, column[0] if column else name)
                if obj is None and (full := leaf_match(datasets, name)) is not None:
                    obj = _hard_linked(h5py, path, f, full)
            except (KeyError, ValueError, TypeError):
                continue  # not there: reported with the list of datasets
            if obj is None:
                continue
            if not isinstance(obj, h5py.Dataset):
                continue  # a group is not a channel
            if obj.name not in values:
                values[obj.name] = read(obj)
            at[name] = obj.name.lstrip("/")
            if column is not None:
                contents.found[name] = column_of(values[obj.name], column[1], name, path)
                unit = column[2]
            else:
                contents.found[name] = values[obj.name]
                if at[name] in whole:  # asked by its name (or its last name): listed as its columns alone
                    contents.matrices.add(name)
                unit = stated_unit(obj.attrs)
                mine = (c for c in columns.values() if c[0] == at[name] and c[2])
                contents.units.update({f"{name}[{i}]": u for _, i, u in mine})  # 'data[1]': its column's unit
            if unit is not None:
                contents.units[name] = unit
            node, is_group = obj, False
            while True:  # from the channel up to the root; the nearest definition wins
                rates, times = level_fields(node, is_group)
                if rates or times or node.name == "/":
                    break
                node, is_group = node.parent, True
            if len(rates) == 1 and not times:
                own[name] = rates[0]
            for kind, fields in ((contents.rates, rates), (contents.times, times)):
                for where, value in fields:
                    if where not in seen:  # channels of one group share its fields
                        seen.add(where)
                        kind.append((where, value))
        said, texts = text_units(h5py, f, at, contents.available)
        contents.units.update({n: u for n, u in said.items() if n not in contents.units})  # its attribute's stands
        contents.available = [d for d in contents.available if d not in texts]
        held_to_vibration(contents, list(names), own)
        return contents


COLUMN_NAMES = ("channel_names", "channels", "names", "column_names", "ChannelNames", "labels")


def named_columns(f, datasets: Sequence[str]) -> dict[str, tuple[str, int, str | None]]:
    """{name: (dataset, column, unit)} of the 2-D datasets of an open *f* whose attribute names their channels, as a
    DAQ writes an (N, k) 'data' of all its inputs with channel_names = [Tacho, Accel] (read as 'data[0]', 'data[1]'
    too) and units = [V, m/s^2], k texts each; a name that is a dataset's own, or given twice, stays that dataset's."""
    out: dict[str, tuple[str, int, str | None]] = {}
    for d in datasets:
        ds = f[d]
        k = min(ds.shape) if ds.ndim == 2 else 0
        names = next((_texts(ds.attrs[a], k) for a in COLUMN_NAMES if a in ds.attrs), None)
        if k < 2 or names is None:
            continue
        units = next((_texts(ds.attrs[a], k) for a in UNIT_ATTRIBUTES if a in ds.attrs), None) or [None] * k
        for i, name in enumerate(names):
            if name and name not in datasets:
                out[name] = None if name in out else (d, i, units[i] or None)
    return {n: c for n, c in out.items() if c is not None}


def named_matrices(shapes: dict[str, tuple], columns: dict[str, tuple[str, int, str | None]]) -> set[str]:
    """The 2-D datasets (of *shapes*) each column of which a name reaches (*columns*: named_columns): listed by those
    names alone, as 'data' of acc_in, acc_out, tacho is no channel of its own (its 'data[1]' is still read)."""
    reached: dict[str, set[int]] = {}
    for matrix, i, _ in columns.values():
        reached.setdefault(matrix, set()).add(i)
    return {d for d, got in reached.items() if len(got) == min(shapes[d])}


def _texts(value, k: int) -> list[str] | None:
    """*value*, an attribute, as k texts, or None where it is not k texts: k strings, or one of k separated by commas
    or semicolons, as a DAQ's export writes channel_names = "acc_in,acc_out,tacho" (read as one channel 'data')."""
    arr = np.asarray(value).ravel()
    if arr.dtype.kind not in "SUO":
        return None
    texts = _text_array(arr).tolist()
    if len(texts) == 1 and k > 1:
        texts = [t.strip() for t in re.split("[,;]", texts[0])]
    return texts if len(texts) == k else None


def text_units(h5py, f, channels: dict[str, str], datasets: Sequence[str]) -> tuple[dict[str, str], set[str]]:
    """({channel: unit} that one-value text datasets beside the channels state (base.stated_units: a MATLAB -v7.3
    struct's 'units' field, a '<channel>_unit' dataset), the file's such text datasets: no channels) of an open *f*.
    *channels*: {channel: its dataset path}; *datasets*: the file's dataset paths."""
    texts = {}
    for d in filter(is_unit_entry, datasets):
        ds = f[d]
        if ds.size > 256:  # a unit is a short text, never a series
            continue
        if h5py.check_string_dtype(ds.dtype) is not None:
            value = np.asarray(ds.asstr()[()])
            text = str(value.ravel()[0]) if value.size == 1 else None
        elif ds.attrs.get("MATLAB_class", b"") in (b"char", "char") and ds.dtype.kind in "iu":
            text = "".join(map(chr, np.asarray(ds[()]).ravel().tolist()))  # one row of character codes
        else:
            text = None
        if text is not None:
            texts[d] = text
    said = stated_units(texts, list(channels.values()))
    return {n: said[p] for n, p in channels.items() if p in said}, set(texts)


def leaf_match(datasets: Sequence[str], name: str) -> str | None:
    """The one dataset path whose last part is *name* ("measurement/radial" for "radial"), or None:
    a logger's MAT or CSV files name the channel bare, and one scenario key names it in every file."""
    if "/" in name:
        return None
    hits = [d for d in datasets if d.rsplit("/", 1)[-1] == name]
    return hits[0] if len(hits) == 1 else None


def _hard_linked(h5py, path: Path, f, name: str):
    """The object at *name*, reached through hard links only: a soft or external link on the
    way is refused in one line (an external link opens another file, a soft link may lead
    anywhere in this one); None when there is nothing at *name*."""
    node, walked = f, ""
    for part in name.strip("/").split("/"):
        link = node.get(part, getlink=True)
        if link is None:
            return None
        walked = f"{walked}/{part}"
        if isinstance(link, h5py.ExternalLink):
            raise GearlabInputError(
                f"{path}: '{walked}' is an external link (to {link.filename}:{link.path}); expected a "
                "dataset stored in this file"
            )
        if not isinstance(link, h5py.HardLink):
            raise GearlabInputError(
                f"{path}: '{walked}' is a soft link ({type(link).__name__} to {link.path}); expected a "
                "dataset stored under its own name"
            )
        node = node[part]
    return node


def _own_data(h5py, path: Path, ds) -> None:
    """Refuse a dataset whose samples are not in this file: external raw storage (any file the
    writer named) or a virtual dataset (a view of others' data, possibly in other files)."""
    if ds.is_virtual:
        raise GearlabInputError(
            f"{path}: dataset '{ds.name}' is a virtual dataset (a view of other datasets); expected "
            "its samples stored in this file"
        )
    if ds.external:
        raise GearlabInputError(
            f"{path}: dataset '{ds.name}' keeps its samples in another file ({ds.external[0][0]!r}, "
            "external storage); expected them stored in this file"
        )


_HDF5_MAX_OBJECTS = 100_000


def _hdf5_datasets(h5py, f) -> list[str]:
    """Paths of the datasets in the file, depth first in name order (MATLAB's '#refs#' and
    the like left out). Each object is visited once, through hard links only: h5py's
    visititems loops forever in some damaged files, and an external link would open
    another file."""
    found: list[str] = []
    seen = {f.id}
    stack = [("", f)]
    while stack:
        prefix, group = stack.pop()
        children = []
        for key in group:
            if not isinstance(group.get(key, getlink=True), h5py.HardLink):
                continue
            obj = group[key]
            if obj.id in seen:
                continue
            seen.add(obj.id)
            if len(seen) > _HDF5_MAX_OBJECTS:
                raise ValueError(f"more than {_HDF5_MAX_OBJECTS} objects (a damaged file?)")
            name = f"{prefix}{key}"
            if isinstance(obj, h5py.Group):
                children.append((f"{name}/", obj))
            elif isinstance(obj, h5py.Dataset) and not name.startswith("#"):
                found.append(name)
        stack.extend(reversed(children))
    return found
