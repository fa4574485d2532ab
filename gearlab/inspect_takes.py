"""`gearlab inspect FILE --takes KEY`: a logger's file of several takes (gearlab.data.takes) at a glance. Each take is
inspected as `gearlab inspect "FILE[KEY=N]"` inspects it (gearlab.notebook.inspect_recording) and given one row: its
name, duration, speed and how it was read, the description's mesh orders found (with --gearbox), its level, whether
it looks like the file's other takes (its speed and level against the takes' median), and with --history the call
`inspect --history` makes of one take (the gear its change lies on, other damage, or no change)."""

from __future__ import annotations

import json
import statistics
import sys

from .data.channel_units import LEVEL_OFF
from .data.takes import take_paths
from .errors import GearlabInputError
from .kinds.detection_records import SPEED_GROUP
from .notebook import inspect_recording
from .signals.checks import fmt_hz


def inspect_takes(file, column: str, **given) -> list[dict]:
    """A row per take of *file* under *column*, in the order they come; *given*: inspect_recording's arguments
    (gearbox, history, the options). A take that cannot be read gets its row with why ('problem'); where none can,
    the first take's error is raised (the options' fault, not a take's: one line)."""
    rows, errors = [], []
    for name in take_paths(file, column, "--takes"):
        try:
            rows.append(take_row(name, inspect_recording(name, **given)))
        except GearlabInputError as exc:
            rows.append({"take": name, "problem": str(exc)})
            errors.append(exc)
    if len(errors) == len(rows):
        raise errors[0]
    compare_takes(rows)
    return rows


def take_row(name: str, report: dict) -> dict:
    """One take's row of what its inspect *report* holds (gearlab.inspect.inspect_record's dict)."""
    speed = report["speed"]
    row = {
        "take": name,
        "duration_s": report["duration_s"],
        "revolutions": report["revolutions"],
        "speed_hz": speed["mean_hz"],
        "speed_source": speed["source"],
        "rms": report["rms"],
    }
    if "check" in report:
        keys = ("stage", "expected_order", "measured_order", "matched")
        row["mesh"] = [{k: s.get(k) for k in keys} for s in report["check"]["stages"]]
        row["matches"] = report["matches"]
        row["verdict"] = report["verdict"]
    if "localisation" in report:
        row["call"] = report["localisation"]["call"]
    return row


def compare_takes(rows: list[dict]) -> None:
    """Each read row's 'like_others': "yes", or how its speed (over SPEED_GROUP, the spread a detection run groups
    takes by) or level (over LEVEL_OFF, a level a run warns of) stands off the takes' median (of three or more, the
    odd one's own value leaves it where the others are; of two, either is as far off), or where the description
    differs on it alone."""
    read = [r for r in rows if "problem" not in r]
    speed = statistics.median(r["speed_hz"] for r in read)
    level = statistics.median(r["rms"] for r in read)
    for row in read:
        others = [r for r in read if r is not row]
        if not others:
            row["like_others"] = "no other take to compare"
            continue
        said = []
        if abs(row["speed_hz"] / speed - 1) > SPEED_GROUP:
            said.append(f"speed {100 * (row['speed_hz'] / speed - 1):+.1f} % off the takes' median {fmt_hz(speed)}")
        ratio = row["rms"] / level if level > 0 else 1.0
        if not 1 / LEVEL_OFF <= ratio <= LEVEL_OFF:
            said.append(f"level {ratio:.2g} x the takes' median")
        if row.get("matches") is False and all(r.get("matches") is not False for r in others):
            said.append("the description differs on it alone")
        row["like_others"] = "; ".join(said) or "yes"


def _mesh_words(row: dict) -> str:
    if "mesh" not in row:
        return "-"
    words = []
    for s in row["mesh"]:
        found = "not seen" if s["measured_order"] is None else f"{s['measured_order']:.3f}"
        words.append(f"{s['stage']}: {found} ({s['expected_order']:.4g}) {'ok' if s['matched'] else 'differs'}")
    return "\n".join(words)


def show_takes(rows: list[dict], console, as_json: bool = False) -> None:
    """The table of a file's takes (or its rows as JSON), then each description verdict that differs; exit 2
    (GearlabInputError's code, after the table) where a take could not be read."""
    from rich.markup import escape
    from rich.table import Table

    read = [r for r in rows if "problem" not in r]
    if as_json:
        sys.stdout.write(json.dumps(rows, indent=1) + "\n")
    else:
        sources = {r["speed_source"] for r in read}  # one: said once, under the table
        columns = [  # (heading, a read row's cell), those a take has: the mesh with --gearbox, the call with --history
            ("take", lambda r: escape(r["take"])),
            ("duration", lambda r: f"{r['duration_s']:.3g} s"),
            ("speed", lambda r: fmt_hz(r["speed_hz"])),
            ("read from", lambda r: escape(r["speed_source"])) if len(sources) > 1 else None,
            ("mesh orders: found (expected)", _mesh_words) if any("mesh" in r for r in read) else None,
            ("RMS (m/s²)", lambda r: f"{r['rms']:.3g}"),
            ("like the others", lambda r: r["like_others"] if r["like_others"] == "yes" else _said(r["like_others"])),
            ("against the history", lambda r: escape(r["call"])) if any("call" in r for r in read) else None,
        ]
        columns = [c for c in columns if c is not None]
        table = Table(title="takes", title_justify="left")
        for heading, _ in columns:  # a take's name whole, on one line
            table.add_column(heading, overflow="fold", no_wrap=heading == "take")
        for r in rows:
            if "problem" in r:  # its name, and why in the last column
                table.add_row(escape(r["take"]), *["-"] * (len(columns) - 2), _said(f"not read: {r['problem']}", "red"))
            else:
                table.add_row(*(cell(r) for _, cell in columns))
        console.print(table)
        if len(sources) == 1:
            console.print(f"speed of every take: {sources.pop()}", markup=False, highlight=False)
        for r in read:
            if r.get("matches") is False:
                console.print(f"{r['take']}: {r['verdict']}", markup=False, highlight=False)
    unread = [r["take"] for r in rows if "problem" in r]
    if unread:
        raise GearlabInputError(f"not read: {', '.join(unread)} (why: in the table); the other takes shown")


def _said(words: str, colour: str = "yellow") -> str:
    from rich.markup import escape

    return f"[{colour}]{escape(words)}[/{colour}]"
