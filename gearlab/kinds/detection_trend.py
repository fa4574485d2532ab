"""The scoring history's trend in words (`gearlab score`, its chart's title in the report and the TUI): per
condition, at the longest unit kind its takes were scored on, the take each method first called, where that take's
change lies (the gear, the tooth) and whether the call held on every take since. A maintenance engineer scoring a
weekly take of a cracking pinion read each method's margin as a line crossing zero on the chart, and the gear and
tooth in each take's own printout only."""

from __future__ import annotations

import re
from pathlib import Path

from .detection_records import longest_tsa

# the tooth a take's evidence counts (kinds.detection_which_gear.evidence: 'tooth 9 of 41 (counted from ...)')
_TOOTH = re.compile(r"tooth (\d+ of \d+)")


def first_called(rows: list[dict]) -> list[str]:
    """One line per condition of the scoring history *rows* (gearlab.parts.scoring, oldest first): the take first
    called (its number on the trend chart, its name) and by which methods, the later methods' first takes, those
    never calling; that take's gear and tooth; whether the first methods called every take since."""
    out = []
    for condition in dict.fromkeys(r["condition"] for r in rows):
        held = [r for r in rows if r["condition"] == condition and r["median_score"] is not None]
        unit = longest_tsa(r["unit"] for r in held) or "revolution"
        per = {
            m: [r for r in held if r["unit"] == unit and r["method"] == m]
            for m in dict.fromkeys(r["method"] for r in held)
        }
        firsts = {
            m: next((i for i, r in enumerate(mine, 1) if r["decision"] != "healthy"), None) for m, mine in per.items()
        }
        head = f"{condition}, {unit}:"
        called = {m: i for m, i in firsts.items() if i is not None}
        if not called:
            out.append(f"{head} no take called ({max(len(mine) for mine in per.values())} scored)")
            continue
        first = min(called.values())
        by = [m for m, i in called.items() if i == first]
        take = per[by[0]][first - 1]
        rest = [f"{m} from take {i}" for m, i in called.items() if i > first] + [
            f"{m} never" for m in per if m not in called
        ]
        said = f"{head} first called on take {first} ({Path(take['file']).name}) by {', '.join(by)}"
        said += f" ({', '.join(rest)})" if rest else ""
        said += "" if take["decision"] == "fault" else f", {take['decision']}"
        tooth = _TOOTH.search(take.get("evidence") or "")
        said += f"; its change on {take.get('localised') or 'no gear localised'}" + (
            f", tooth {tooth.group(1)}" if tooth else ""
        )
        lapsed = next((r for r in per[by[0]][first:] if r["decision"] == "healthy"), None)
        if lapsed is None:
            said += "; called on every take since" if len(per[by[0]]) > first else ""
        else:
            number = per[by[0]].index(lapsed) + 1
            said += f"; not called again on take {number} ({Path(lapsed['file']).name}) by {by[0]}"
        out.append(said)
    return out
