"""The takes a finished detection run read, known by their content (`gearlab score`; gearlab.kinds.detection):
a take of the run's own, renamed or not, is scored in the condition the run put it in, so that scoring it
again gives the scores the run gave it; and how far a take scored in a condition named by hand lies off that
condition's history speed."""

from __future__ import annotations

from pathlib import Path

from ..runs import RunDir
from .detection_records import SPEED_GROUP

# condition_by's words for a take of the run's own (the printout and the scoring history say them)
OWN_WORDS = "the run's own"


def own_conditions(run: RunDir) -> dict[str, tuple[str, str]]:
    """{sha256 of a take's content: (the condition the run put it in, its role)} of the takes the run read:
    run.json's digests of its files, conditions.json's history and test takes (a relative path under the run's
    base). Of two conditions at one speed the level rule (detection_scoring._by_level) chose another for a take
    whose level lay nearer the other load's history (synthetic rig records, ten conditions at 35 Hz:
    likelihood_ratio's record10 median score less threshold -6.23 from score, -3.90 in the run). A content the
    run put in two conditions (one file named twice) is left out: its speed and level choose, as for a new take."""
    digests, base = run.meta().get("inputs") or {}, run.base()
    found: dict[str, set] = {}
    for name, cond in (run.read_json("conditions.json") or {}).items():
        for role in ("history", "test"):
            for path in cond.get(role, []):
                at = Path(path) if base is None or Path(path).is_absolute() else base / path
                digest = digests.get(str(at.resolve()))
                if digest:
                    found.setdefault(digest, set()).add((name, role))
    return {d: next(iter(c)) for d, c in found.items() if len({n for n, _ in c}) == 1}


def own_words(role: str) -> str:
    """condition_by's line for a take of the run's own of *role*: a history take's units are in the references
    and thresholds it is scored against, where the run scored each by the references made without it."""
    if role == "history":
        return f"{OWN_WORDS} history take: its condition in the run; in the references scored against, not left out"
    return f"{OWN_WORDS} take: its condition in the run"


def off_history(meta: dict, name: str, speed: float, whose: str = "the") -> str:
    """How far a take over SPEED_GROUP off its condition's history speed lies ("+10.0 % off the history's 33.00 Hz")."""
    centre = meta["conditions"][name]["speed_hz"]
    off = f"{100 * (speed / centre - 1):+.1f} % off {whose} history's {centre:.2f} Hz"
    return "" if abs(speed / centre - 1) <= SPEED_GROUP else off


def asked_off(meta: dict, name: str, speed: float) -> str:
    """Why a take over SPEED_GROUP off the speed of the condition --condition names is scored there (else "")."""
    off = off_history(meta, name, speed, "its")
    return off and f"--condition: {off}, beyond the {SPEED_GROUP:.0%} a run groups by: thresholds fixed there"
