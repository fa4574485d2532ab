"""`gearlab score`'s reading of a detection run's saved which-gear histories (scoring/localisation<i>.npz: the
synchronous averages', the envelope's, the non-synchronous residual's), written by the gearlab that made the run.

A history laid out on another grid of points a revolution than the one takes are cut to today (an older gearlab's
signals.POINTS, or its envelope's) is put on today's: its layout's orders are set by its saved band, not by its grid,
so its powers per order stand as saved, and its first record's mean revolution (the mark takes are turned to) is put
on the new grid (signals.regrid: exact below half the coarser grid, where every order read lies). A history whose
orders are not those today's layout gives its description (an older layout rule, another description), or whose
arrays or options this gearlab does not know, cannot be re-binned: which order each saved value was is not saved.
Its takes are then not localised, each score row saying so in one line with what differs, and the methods' scores
and decisions stand; an envelope's history not read leaves the averages' call, said beside it; a non-synchronous
history of other bins says so in its place (signals.nonsync.NonSyncHistory.unread).
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from ..errors import GearlabInputError
from ..signals import POINTS
from ..signals import envelope_sync as E
from ..signals import localise as L
from ..signals import nonsync as NS
from ..signals.regrid import at_points

# a saved history that cannot be read as today's gearlab reads it, in a score row
NOT_READ = "the run's saved {what} history is not read ({why}); {refresh}"


def _why(exc: Exception) -> str:
    if isinstance(exc, KeyError):
        return f"it has no array {exc.args[0]!r}"
    if isinstance(exc, TypeError):  # layout options this gearlab's layout() does not take
        return f"saved with layout options this gearlab does not take: {exc}"
    return str(exc)


def _restored(restore, arrays: dict, table, what: str) -> tuple[object | None, str]:
    """(restore(arrays, table), "") or (None, the row's line saying why not)."""
    try:
        return restore(arrays, table), ""
    except (GearlabInputError, KeyError, TypeError, ValueError) as exc:
        return None, NOT_READ.format(what=what, why=_why(exc), refresh=NS.REFRESH)


def on_grid(arrays: dict, prefix: str, points: int) -> dict:
    """*arrays* with the history saved under *prefix* ("": the averages', "envelope_") laid out at *points* a
    revolution (its layout's arguments, its reference revolution); *arrays* themselves where it is (or none is)."""
    try:
        args = json.loads(str(arrays[f"{prefix}args"]))
    except (KeyError, ValueError):  # none saved, or none this gearlab reads: restoring it says so (saved_histories)
        return arrays
    if not isinstance(args, dict) or args.get("points", points) == points:
        return arrays
    out = dict(arrays) | {f"{prefix}args": np.array(json.dumps(args | {"points": points}))}
    reference = np.asarray(arrays.get(f"{prefix}reference", np.zeros(0)))
    if reference.size:  # a tacho of several marks a turn: the first history record's mean revolution
        out[f"{prefix}reference"] = at_points(reference[None, :], points)[0]
    return out


def saved_histories(arrays: dict, table) -> tuple[L.History | None, NS.NonSyncHistory | None, str, str]:
    """(the averages' history with its envelope's where read, the residual's or None, why the averages' is not read,
    why the envelope's or the residual's is not: "" where read) of a run's saved *arrays*, for the gearbox of order
    table *table*."""
    arrays = on_grid(on_grid(arrays, "", POINTS), "envelope_", E.POINTS)  # the grids takes are cut to today
    for i in range(1, len(arrays.get("envelope_bands", ()))):  # the envelope's other bands (E.state), as its first
        arrays = on_grid(arrays, f"envelope{i}_", E.POINTS)
    hist, why = _restored(L.History.restored, arrays, table, "localisation")
    envelope, unread = _restored(E.restored, arrays, table, "envelope")  # None: a run stored before it was read
    quiet, off = _restored(NS.NonSyncHistory.restored, arrays, table, "non-synchronous")
    if hist is not None:
        hist = dataclasses.replace(hist, envelope=envelope)
    return hist, quiet, why, "; ".join(w for w in (unread, off) if w)
