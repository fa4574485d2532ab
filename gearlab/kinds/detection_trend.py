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
        rest = [f"{m} from take {i}{_what(per[m][i - 1])}" for m, i in called.items() if i > first] + [
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
        out.append(said + ("" if take.get("localised") else _localised_later(per, first)))
    return out


def _what(row: dict) -> str:
    """' (level changed by a factor of 9.82)' where a method's first call is no fault of the watched gear (a level
    change, other damage, a gear not determined), else '': a take whose level alone changed x 9.8 read as
    'likelihood_ratio from take 3', a fault first called."""
    return "" if row["decision"] == "fault" else f" ({row['decision'].split(' (')[0].split(':')[0]})"


# the level a take's warning says against its history's ('level 0.61 x its history's (another load or gain?) ...')
_LEVEL = re.compile(r"level ([\d.]+) x")


def _localised_later(per: dict[str, list[dict]], first: int) -> str:
    """Where the first called take (number *first* of each method's rows *per*) localised nothing: the first called
    take since that is localised, on which gear and tooth, by which methods; and how many called before it localised
    nothing, off the history's level. A month of daily takes whose sensor's mount loosened (-0.1 dB a day) was first
    called on day 16 by the template methods, the level's fall; the chip of day 45, on the input pinion, went unsaid."""
    takes = max(len(rows) for rows in per.values())

    def called(i: int) -> list[str]:  # the methods calling take i (1-based)
        return [m for m, rows in per.items() if len(rows) >= i and rows[i - 1]["decision"] != "healthy"]

    def row(i: int) -> dict:
        return next(rows[i - 1] for rows in per.values() if len(rows) >= i)

    found = next((i for i in range(first + 1, takes + 1) if called(i) and row(i).get("localised")), None)
    said = ""
    if found is not None:
        tooth = _TOOTH.search(row(found).get("evidence") or "")
        said = (
            f"; first localised on take {found} ({Path(row(found)['file']).name}): {row(found)['localised']}"
            + (f", tooth {tooth.group(1)}" if tooth else "")
            + f", by {', '.join(called(found))}"
        )
    before = [i for i in range(first, found or takes + 1) if called(i)]
    levels = [float(m.group(1)) for i in before if (m := _LEVEL.search(row(i).get("level") or ""))]
    takes_called = f"{len(before)} take{'s' * (len(before) != 1)} called"
    said += f"; {takes_called} {'before it ' * (found is not None)}with no gear localised"
    if levels:
        said += f", {len(levels)} of them off the history's level ({max(levels):.2g}-{min(levels):.2g} x)"
    return said
