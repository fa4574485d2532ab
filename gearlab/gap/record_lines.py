"""The search's score beside the report's gap where the rows are consecutive revolutions (docs/gap.md, "Lines below
and between the first orders").

There the search's score adds a second group, the record's lines between shaft orders (gearlab.gap.views.record_view),
which the report's gap leaves out. An effect can lower the score in that group alone while the revolutions' own
features, all the report's gap counts, move away from the target. On a two-stage box of 26/71 + 23/82 teeth
(a line at the intermediate shaft's order 26/71, -13.5 dB, where the simulator's record is at -83 dB) the group held
95 % of the plain source's score (133,174 of 139,550): sensor noise at -7.7 dB raised the source's floor there
(133,174 -> 5,496 on fresh rows) and was accepted for 90 % of the gap, while the row features' part of the score rose
6,376 -> 8,662 and the report's gap 6,052 -> 8,683 (43 % wider): nothing was named at the end, and no line said why.
Such an effect is not accepted (:func:`widened`), and its round's line says so (:func:`round_line`)."""

from __future__ import annotations

import numpy as np

from .scoring import ACCEPT_CONFIDENCE, ACCEPT_REPLICATES, Scorer


def widened(scorer: Scorer, current_X: np.ndarray, candidate_X: np.ndarray, seed: int) -> dict | None:
    """Where the score has the record's group: whether the candidate's rows (*candidate_X*) widen the gap on the
    revolutions' own features against the current source's (*current_X*), with ACCEPT_CONFIDENCE (a paired bootstrap
    of the score without the record group, the rows resampled alike) and the report's gap on them is wider too. Returns
    None where not, else the report's gap of both (``report_now``, ``report_new``) and the record group's share of the
    current score."""
    if scorer.target_record is None:
        return None
    (_, Fc, Ft), (_, Fn, _) = scorer._leveled_features(current_X), scorer._leveled_features(candidate_X)
    now, new = scorer.mismatch(Fc, Ft), scorer.mismatch(Fn, Ft)
    if not new > now:
        return None
    rc = scorer._replicates(Fc, Ft, ACCEPT_REPLICATES, np.random.default_rng([seed, 4]))
    rn = scorer._replicates(Fn, Ft, ACCEPT_REPLICATES, np.random.default_rng([seed, 4]))
    if not float(np.percentile(rn - rc, 100.0 * (1.0 - ACCEPT_CONFIDENCE))) > 0.0:
        return None
    report_now, report_new = scorer.report_gap(current_X), scorer.report_gap(candidate_X)
    if not report_new > report_now:  # the report itself finds it no worse: the search's score decides
        return None
    total = scorer.score(current_X)
    return {
        "rows_now": now,
        "rows_new": new,
        "report_now": report_now,
        "report_new": report_new,
        "record_share": (total - now) / total if total > 0 else 0.0,
    }


def round_line(r: int, name: str, share: float, ok: bool, wider: dict | None = None) -> str:
    """The progress line of round *r*'s decision. Its share is the round's fit's, on fresh revolutions: an
    outside lab's sensor_noise read '97.8 % ... (accepted)' beside the verdict's 98.2 % (round 1's search)
    and the summary's 98.8 % (final fit), with no word of which fit each was (issue 39 item 4). *wider*: the
    effect widened the report's gap (:func:`widened`): said, with where the score's share lay."""
    said = f"gap: round {r}: {name} removes {100 * share:.1f} % of the gap left, at round {r}'s fit on fresh "
    said += "revolutions"
    if wider:
        return f"{said}, but not accepted: {not_accepted_text(wider)}"
    return f"{said} ({'accepted' if ok else 'not accepted'})"


def not_accepted_text(wider: dict) -> str:
    """Why an effect that lowered the search's score was not accepted, in words (the round's line, the verdict)."""
    now, new = wider["report_now"], wider["report_new"]
    grown = f"{100 * (new / now - 1):.0f} % wider" if now > 0 else f"{new:.4g} from {now:.4g}"
    return (
        f"the search's score fell on the lines between shaft orders that consecutive revolutions show "
        f"({100 * wider['record_share']:.0f} % of that score, left out of the report's gap), while the report's gap, "
        f"on the revolutions' own features, grew {grown}"
    )
