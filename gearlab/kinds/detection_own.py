"""The takes a finished detection run read, known by their content (`gearlab score`; gearlab.kinds.detection):
a take of the run's own, renamed or not, is scored in the condition the run put it in, so that scoring it
again gives the scores the run gave it; the condition a new take is scored in (by speed, then level); and how far
a take scored in a condition named by hand lies off that condition's history speed."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import GearlabInputError, did_you_mean
from ..parts import scoring
from ..runs import RunDir, input_digest
from .common import SPEED_GROUP
from .detection_in_band import IN_BAND
from .detection_level import kept_level, level_ratio, take_level

# condition_by's words for a take of the run's own (the printout and the scoring history say them)
OWN_WORDS = "the run's own"
# the decision of a take `gearlab score` refused, of several given (skipped_rows): the others are scored
NOT_SCORED = "not scored"


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


def condition_of(meta: dict, path: str, speed: float, asked: str | None) -> str:
    """The condition a take at *speed* is scored in: *asked* (--condition), else the one of nearest history speed,
    within SPEED_GROUP of it (else refused: another gearbox's record, or a speed the run has no history of)."""
    names = list(meta["conditions"])
    if asked is not None:
        if asked not in names:
            raise GearlabInputError(
                f"--condition '{asked}'{did_you_mean(asked, names)}: not a condition of the run; "
                f"known: {', '.join(names)}"
            )
        return asked
    near = min(names, key=lambda c: abs(meta["conditions"][c]["speed_hz"] - speed))
    centre = meta["conditions"][near]["speed_hz"]
    if abs(speed - centre) > SPEED_GROUP * centre:
        known = ", ".join(f"'{c}' ({meta['conditions'][c]['speed_hz']:.2f} Hz)" for c in names)
        raise GearlabInputError(
            f"{path}: runs at {speed:.2f} Hz, more than {SPEED_GROUP:.0%} from every condition's history ({known}); "
            "expected a record of a trained condition, or --condition NAME"
        )
    return near


def by_level(run: RunDir, meta: dict, name: str, rec) -> tuple[str, str]:
    """(condition, why) of a steady take: of the conditions whose history runs within IN_BAND of its speed (one
    per load, grouped by hand), the one whose history level is nearest the take's (level_ratio, as the run's tables
    and the take's rows measure it); by speed alone a 29/73 box's
    heavy-load history take was scored against the light load's (24.41 Hz to 24.40): NA4 6 of 6 'fault'."""
    at = [c for c, v in meta["conditions"].items() if abs(rec.speed_hz - v["speed_hz"]) <= IN_BAND * v["speed_hz"]]
    if len(at) < 2:
        return name, ""
    level = {c: level_ratio(take_level(rec.revolutions), _kept(run, meta["conditions"][c])) for c in at}
    best = min(at, key=lambda c: abs(math.log(max(level[c], 1e-12))))
    return best, "nearest level of those at its speed: " + ", ".join(f"'{c}' {level[c]:.2f} x" for c in at)


def _kept(run: RunDir, kept: dict) -> float:
    """A condition's history level (kept_level), as `gearlab score` compares a take's with it."""
    arrays = scoring.load_arrays(run.file("scoring", kept["file"]))
    parts = np.split(arrays["history"], np.cumsum([n for _, n in kept["history"]])[:-1])
    return kept_level(kept, parts, float(arrays["standardiser"][1]))[0]


def refused_why(path: str, refused: GearlabInputError) -> str:
    """Why a take of several was not scored: the refusal's line, without the file name it starts with (the row and
    the printout name it)."""
    why = str(refused)
    return why[len(path) + 2 :] if why.startswith(f"{path}: ") else why


def skipped_rows(skipped: dict[str, str]) -> list[dict]:
    """One row per take refused, of several given to `gearlab score` ({file: why}): the others are scored and kept
    in the scoring history, these are not; their decision 'not scored', no method, no unit, *skipped* the why."""
    return [
        {"file": f, "digest": input_digest(Path(f)), "decision": NOT_SCORED, "method": None, "unit": None, "skipped": w}
        for f, w in skipped.items()
    ]
