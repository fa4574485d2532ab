"""The verdict of a gap run (gearlab.kinds.gap's verdict_lines): the named effects with the
numbers that matter in one sentence, and why an effect's share alone can differ from the share it
is credited with."""

from __future__ import annotations

import math
from collections.abc import Mapping


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def _at_chance(summary: Mapping, when: str) -> str:
    """Why a p under alpha is not a significant gap: the classifier's AUC, the other half of the
    test (gearlab.gap.conclusion.gap_seen), lies within chance."""
    p, auc = summary.get(f"p_{when}"), summary.get(f"auc_{when}")
    alpha = (summary.get("settings") or {}).get("alpha", 0.05)
    if p is None or auc is None or summary.get(f"significant_{when}") or p >= alpha:
        return ""
    return f"; the classifier's AUC {auc:.2f} is within chance"


def headline(run) -> str:
    """`gearlab runs`' headline of a gap run whose structure or level differs: that line, not the gap's size (a
    25-tooth description of a 24-tooth box was listed as 'The simulator and the target differ significantly');
    else "" (the verdict's first line)."""
    said = str((run.read_json("summary.json") or {}).get("verdict") or "")
    return f"{said[0].upper()}{said[1:]}" if said.startswith(("structure differs", "level differs")) else ""


# A structure difference ends the diagnosis before the source, another gearbox, is simulated (gearlab.gap.structure)
NO_GAP = "gap not measured: the source simulates another gearbox"


def diagnosis_line(result: dict) -> str:
    """The run's log line (the CLI's): with no effect named, the simulator stays as it was, and 'gap X -> X
    (0 % removed)' read as if nothing had helped beside 'sensor_noise ... together 98.8 % of the gap' (an outside
    lab's 24/83 box): the gap alone then, and why nothing is named."""
    from ..gap.conclusion import verdict_text

    before, after = result["gap_before"], result["gap_after"]
    names = ", ".join(f"{e['name']} ({100 * e['share_removed']:.0f} %)" for e in result["effects"]) or "none"
    if result.get("dropped_effects"):  # the progress said them accepted: say why none is named
        names += f" ({dropped_text(result)})"
    gap = (
        NO_GAP
        if before is None
        else f"gap {before:.4g} -> {after:.4g} ({shrink_text(before, after)} removed)"
        if result["effects"]
        else (f"gap {before:.4g} (no effect named: the simulator left uncorrected)")
    )
    return f"{gap}; effects: {names}; {verdict_text(result)}"


# Which fit and measure the named set's share is of: the search's progress said 'casing_path removes 86.3 % ...
# (accepted)' (round 1's fit, the search's score) above 'together 79 % of the gap' (the final fit, the report's gap)
FINAL_FIT = "at the final fit by the report's gap (a round's share is at that round's fit, by the search's score)"


def dropped_text(result: Mapping) -> str:
    """Why effects the search accepted are not named (gearlab.gap.conclusion: stand-ins), with their final fit."""
    names = ", ".join(
        e["name"] + (f" (final fit: {_params(dict(sorted(e['params'].items())))})" if e.get("params") else "")
        for e in result["dropped_effects"]
    )
    share, below = 100 * result["dropped_share"], 100 * result["dropped_below"]
    # as many decimals as it takes to show the share under the level (98.7 under 99, not 99 under 99)
    digits = next((d for d in range(4) if round(share, d) < round(below, d)), 3)
    # a set that removes less than nothing at its final fit widens the gap: said so, not as '-43 % of the gap'
    part = (
        f"together {share:.{digits}f} % of the gap" if share >= 0 else f"together they widen the gap by {-share:.0f} %"
    )
    return f"{names} fitted, then not named: {part}, {FINAL_FIT}, under the {below:.{digits}f} % a named set removes"


def dropped_rows(result: Mapping) -> list[dict]:
    """The effects accepted, then not named, as the ranking's table marks them: name, round, final fit."""
    return [
        {"name": e["name"], "round": e.get("round"), "params": e.get("params", {})}
        for e in result.get("dropped_effects") or []
    ]


def not_accepted_rows(result: Mapping) -> list[dict]:
    """Each round's winner that lowered the search's score but widened the report's gap (gearlab.gap.record_lines):
    round, name, the share of the score it removed and the gaps, for the verdict's line."""
    return [
        {"round": i["round"], "name": i["best"], "share": i["share_of_remaining"], **i["widens_report"]}
        for i in result.get("rounds") or []
        if i.get("widens_report")
    ]


def _not_accepted(summary: Mapping) -> list[str]:
    from ..gap.record_lines import not_accepted_text  # here: it loads the diagnosis's scoring, which a verdict need not

    return [
        f"Round {w['round']}'s {w['name']} lowered the search's score by {_pct(w['share'])} but was not accepted: "
        f"{not_accepted_text(w)}."
        for w in summary.get("not_accepted") or []
    ]


def shrink_text(before: float, after: float) -> str:
    if before <= 0:
        return "n/a"
    share = 100 * (1 - after / before)
    return f"{share:.2f} %" if 99 <= share < 100 else f"{share:.0f} %"  # 99.99 % is not 100 %


def before_after(s: Mapping) -> str:
    """The summary's gap line: before -> after with the share removed where an effect is named; else the gap
    before alone (the corrected source is the source: '-> the same (0 % removed)' told nothing)."""
    if s["gap_before"] is None:
        return NO_GAP
    before = (
        f"gap before {s['gap_before']:.4g} (AUC {s['auc_before']:.3f}, p = {s['p_before']:.3g}, "
        f"{'significant' if s['significant_before'] else 'not significant'})"
    )
    if not s.get("effects"):
        return f"{before}; no effect named: the simulator left uncorrected"
    return (
        f"{before} -> after {s['gap_after']:.4g} (AUC {s['auc_after']:.3f}, p = {s['p_after']:.3g}); "
        f"{shrink_text(s['gap_before'], s['gap_after'])} removed"
    )


def gap_lines(summary: Mapping) -> list[str]:
    views = summary.get("views") or {}
    before, after = summary.get("gap_before"), summary.get("gap_after")
    said = summary.get("verdict") or ""  # the run's own verdict, as its log line said it (gearlab.gap.conclusion)
    if before is None and said.startswith("structure differs"):
        return [f"{said[0].upper()}{said[1:]}; no effect was searched, no gap measured.", *_unchecked(summary)]
    if before is None:
        return ["The diagnosis has not finished: there is nothing to judge."]
    where = sorted(views, key=lambda v: -(views[v].get("share_before") or 0.0))
    top = [v for v in where if (views[v].get("share_before") or 0.0) >= 0.1][:3] or where[:1]
    differ = "differ significantly" if summary.get("significant_before") else "do not differ significantly"
    lines = [
        f"The simulator and the target {differ} "
        f"(gap {before:.4g}, p = {summary.get('p_before', float('nan')):.3g}); the gap lies mostly in "
        + ", ".join(f"{v} ({_pct(views[v].get('share_before') or 0.0)})" for v in top)
        + "."
    ]
    effects = summary.get("effects") or []
    if said.startswith(("structure differs", "level differs")):  # ended before any effect was searched
        return [*lines, f"{said[0].upper()}{said[1:]}; no effect was searched.", *_unchecked(summary)]
    shrink = summary.get("shrink", 0.0)
    after_text = (
        f"gap {before:.4g} -> {after:.4g}, {_pct(shrink)} removed; "
        f"{'still significant' if summary.get('significant_after') else 'no longer significant'} "
        f"(p = {summary.get('p_after', float('nan')):.3g}{_at_chance(summary, 'after')})"
    )
    if effects:
        named = ", ".join(
            f"{e['name']} (final fit: {_params(e.get('params', {}))}; credited with {_pct(e['share_removed'])})"
            for e in effects
        )
        verdict = "UNEXPLAINED: the gap is not closed" if summary.get("unexplained") else "the gap is explained"
        if said:
            verdict = f"the gap is {said}" if said.startswith("explained") else said.upper()
        lines.append(f"Named effects: {named}; {after_text}; {verdict}.")
    else:
        ranking = summary.get("ranking") or []
        top = ranking[0] if ranking else None
        best = (
            # round 1's share, on the revolutions it was fitted to: not the report's gap that names effects (an
            # outside lab's 24/83 box: 98.1 % here, 98.8 % for the same noise's final fit in the line below)
            f" (the best candidate, {top['name']}, removes {_pct(top['share_removed'])} {beside(ranking)})"
            + " in round 1's search, on the revolutions fitted"
            if top
            else ""
        )
        lines.append(
            (
                "UNEXPLAINED: no candidate effect closes the gap"
                if summary.get("unexplained")
                else "No effect named: there is no significant gap to explain"
            )
            + f"{best}."
        )
        if summary.get("dropped"):  # the search accepted them; the progress line said so
            lines.append(
                f"Effects {summary['dropped']}: stand-ins for an effect outside the library; the simulator is "
                "left uncorrected."
            )
        if said.startswith("unexplained: "):  # why no effect can be told on this box (gearlab.gap.line_levels)
            why = said.removeprefix("unexplained: ")
            lines.append(f"{why[0].upper()}{why[1:]}.")
    lines += _not_accepted(summary)
    lines += _unchecked(summary)  # the verdict holds for the structure as far as it was checked
    level = (summary.get("structure") or {}).get("level") or {}
    if decade(level.get("factor") or 0.0):
        lines[1:1] = _level(summary)  # a decade's slip comes before the stand-ins fitted at it
    else:
        lines += _level(summary)
    lines += _alone_versus_credited(summary)
    acc = summary.get("accuracy") or {}
    pairs = [
        (n.replace(" (uncorrected)", ""), acc[n], acc.get(n.replace("(uncorrected)", "(corrected)")))
        for n in acc
        if n.endswith("(uncorrected)")
    ]
    told = [f"{m} {u['mean']:.1f} -> {c['mean']:.1f} %" for m, u, c in pairs if c is not None]
    if told:
        lines.append("Target fault detection at k = 0, uncorrected -> corrected simulator: " + ", ".join(told) + ".")
    if summary.get("corrected_description"):  # the fitted values of the gearbox, written into its description
        lines.append(f"corrected description: {summary['corrected_description']}")
    return lines


def _unchecked(summary: Mapping) -> list[str]:
    """The structure line of a check that passed with a tooth count it could not tell from the next one
    (gearlab.gap.structure.unchecked_record: inspect's 'not checked'), after the verdict it qualifies."""
    unchecked = (summary.get("structure") or {}).get("unchecked")
    if not unchecked:
        return []
    line = unchecked["line"]
    return [f"{line[0].upper()}{line[1:]}."]


# A level of the records this far from the simulator's (or its inverse), that a scale alone does not explain, is said:
# a 19/62 + 23/87 box given 100 mV/g for its 1 V/g chain read 4.29 x (0.43 x right) and fitted sensor noise at its
# bound (-20 dB), 'unexplained', the factor in summary.json alone
LEVEL_SAID = 3.0


# A factor within 10 % of a whole power of ten is said as that decade, first after the gap's line: a 27/61 + 22/53
# box's sensitivity written 500 mV/g for its 50 mV/g sensor read 0.101 x, said last, below stand-ins fitted at that
# level (a box described with defaults read 11.2 x its simulator: outside the tolerance, the plain line)
DECADE_TOL = 0.10


def decade(c: float) -> int:
    """The power of ten (not 0) that the level factor *c* lies within DECADE_TOL of, else 0."""
    if not c > 0:
        return 0
    k = round(math.log10(c))
    return k if k and abs(math.log10(c) - k) < math.log10(1 + DECADE_TOL) else 0


def _level(summary: Mapping) -> list[str]:
    """The line of a level far off the simulator's (LEVEL_SAID) that no scale alone closed, else []."""
    level = (summary.get("structure") or {}).get("level") or {}
    c = level.get("factor")
    if c is None or level.get("closes") or 1 / LEVEL_SAID < c < LEVEL_SAID:
        return []
    if k := decade(c):
        scaled, before = level.get("gap_scaled"), summary.get("gap_before")
        gap = f"; scaled by it, the gap {before:.4g} -> {scaled:.4g}" if scaled is not None and before else ""
        n = f"{10 ** abs(k):g}"
        return [
            f"Level: a scale factor of ~{n} (the records' synchronous lines stand {c:.3g} x the simulator's{gap}): "
            f"a whole decade, as a sensitivity or gain written {n} x off reads (or a box that far off its "
            "description's level): give sensitivity and gain (the values: line of gearlab inspect says how the "
            "values became m/s²); the effects here were fitted at the level as given."
        ]
    return [
        f"Level: the records' synchronous lines stand {c:.3g} x the simulator's (a scale alone does not close the "
        "gap): the description's defaults and load set its level, but a sensitivity or gain off by as much reads "
        "so too: check the values: line of gearlab inspect."
    ]


def beside(ranking: list) -> str:
    """How the ranking's best share was had: alone, or with the sensor noise fitted beside it (every other
    candidate of round 1 is fitted with it, gearlab.gap.scoring.NUISANCE). A 27/74 conveyor's gap said 'the
    best candidate, sensor_bandwidth, removes 97.2 % alone' at f_n = 72 kHz (no effect under its 10 kHz
    Nyquist): the noise beside it removed that, as it did alone (97.2 %)."""
    from ..gap.scoring import NUISANCE

    noise = next((r for r in ranking if r["name"] == NUISANCE), None)
    if noise is None or ranking[0]["name"] == NUISANCE:
        return "alone"
    return f"with {NUISANCE} fitted beside it; {NUISANCE} alone {_pct(noise['share_removed'])}"


def _params(params: Mapping) -> str:
    return ", ".join(f"{k} = {v:.3g}" if isinstance(v, float) else f"{k} = {v}" for k, v in params.items())


def _alone_versus_credited(summary: Mapping) -> list[str]:
    """An effect that removes most of the gap alone (the ranking) yet is credited with little
    (the accepted effects' shares) is no contradiction: say why, for each such effect."""
    alone = {r["name"]: r["share_removed"] for r in summary.get("ranking") or []}
    effects = summary.get("effects") or []
    out = []
    for e in effects:
        if e["name"] not in alone or alone[e["name"]] - e["share_removed"] < 0.2:
            continue
        # a round accepts one candidate and, at most, the sensor noise fitted beside it
        noise = [
            f["name"]
            for f in effects
            if f is not e and (f.get("nuisance_of") == e["name"] or f.get("round", -1) == e.get("round"))
        ]
        earlier = [
            f["name"]
            for f in effects
            if f is not e and not f.get("nuisance_of") and f.get("round", 0) < e.get("round", 0)
        ]
        said = f"{e['name']} removes {_pct(alone[e['name']])} of the gap in the ranking"
        if noise:
            why = (
                f"{said} (fitted there with {' and '.join(noise)} beside it) but is credited with "
                f"{_pct(e['share_removed'])}: {' and '.join(noise)} alone explains that part of the gap, and "
                "the credited shares split what they remove together (a Shapley value)"
            )
        elif earlier:
            why = (
                f"{said} (added alone) but is credited with {_pct(e['share_removed'])}"
                f": {', '.join(earlier)}, accepted in an "
                "earlier round, already explain that part of the gap"
            )
        else:
            why = (
                f"{said} (added alone) but is credited with {_pct(e['share_removed'])}: "
                "the credited share is measured on fresh "
                "revolutions, the ranking's on those it was fitted to"
            )
        out.append(why + ".")
    return out
