"""The verdict of a detection run (gearlab.kinds.detection's verdict_lines): per condition, the
rows that meet the record-level goal, the best learned row against the best classical one, the
learned rows that did not learn the simulated fault, and the thresholds that rest on the history's records
differing (record_spread)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from statistics import NormalDist

from ..signals.nonsync import HUM
from .detection_level import LEVEL_WORDS, level_factor

# What a user asks of a record-level decision (docs/real_data.md): the fault found in at least
# 90 % of the faulty units at no more than 5 % false alarms, with an AUC of 0.95 or more.
GOAL_AUC, GOAL_DETECTION, GOAL_FALSE_ALARM = 0.95, 90.0, 5.0
# A learned method has learned the simulated fault when its scores rank the simulator's own
# held-out faulty revolutions above the healthy ones better than chance would, one-sided at 5 %.
CHANCE_LEVEL = 0.05


def chance_auc(n_healthy: int, n_faulty: int, level: float = CHANCE_LEVEL) -> float:
    """The AUC that scores unrelated to the labels exceed with probability *level*: the normal
    approximation of the Mann-Whitney statistic's null law, mean 1/2 and variance
    (n0 + n1 + 1) / (12 n0 n1) (ties aside); 0.67 for 16 and 16 revolutions at 5 %."""
    z = NormalDist().inv_cdf(1.0 - level)
    return 0.5 + z * math.sqrt((n_healthy + n_faulty + 1) / (12.0 * n_healthy * n_faulty))


def _merit(row: Mapping) -> tuple:
    """Ranks rows on the test labels: what their decisions got right (detection less false alarms at
    the history's threshold, what a user acts on), then the AUC."""
    auc = row["auc"] if row["auc"] is not None else -1.0
    return ((row["detection"] or 0.0) - (row["false_alarm"] or 0.0), auc)


def _said(row: Mapping) -> str:
    auc = "–" if row["auc"] is None else f"{row['auc']:.2f}"
    return f"{row['method']} (AUC {auc}, {_cell(row['detection'])} / {_cell(row['false_alarm'])} %)"


def _spread(summary: Mapping, condition: str) -> str:
    """What the run found of its history's threshold in *condition*: its warning that the history's own takes lie at
    several levels (detection_level.level_warnings: two loads or gains), as '; the run found why: FACT, ADVICE',
    else ""."""
    said = ((summary.get("conditions") or {}).get(condition) or {}).get("warnings") or []
    spread = next((w for w in said if w.startswith("the history's levels span")), None)
    if spread is None:
        return ""
    return f"; the run found why: {spread.split(': ')[0]}, {spread.split('; ')[-1]}"


# A threshold rests on the history's records differing where more than half the predictive variance of a new
# record's unit is the record effect's: sigma_a^2 (1 + 1/R) of sigma_a^2 + sigma_e^2 + Var(mu_hat) (record_effects;
# Var(mu_hat) carries sigma_a^2 / R). Then the threshold's distance from the history's mean is mostly how far its
# takes lie apart, not how a take's units scatter, and a faulty unit must exceed that difference to be called: the
# PHM 2009 rig's two history builds (healthy, eccentric idler) put the classical thresholds above the chips.
RECORD_SHARE = 0.5
# ...and where the records differ beyond chance: with two records sigma_a^2 rests on one degree of freedom. The
# one-way model's own test of sigma_a = 0: the record means' variance over what the within-record spread explains,
# mean(sigma_e^2 / m_r), an F(R - 1, sigma_e^2's degrees of freedom) where there is no record effect. Two history
# takes of textrecords' generator (40 revolutions, record10): the share alone said 3 pairs of 9 alike ones (NA4
# 1.1-2.4x), with the test 2 (1.3x, 2.4x: F 8, 24); every pair of a take twice as noisy (NA4 5.6-9.3x).
RECORD_LEVEL = 0.01


def record_share(model: Mapping | None) -> float | None:
    """The share of a new record's unit's predictive variance that the record effect makes (RECORD_SHARE), from a
    row's history_model (record_effects.RecordEffects.as_dict); None with one history record (not estimable)."""
    if model is None or model.get("record_sd") is None:
        return None
    a2, e2, r = model["record_sd"] ** 2, model["unit_sd"] ** 2, model["records"]
    total = a2 + e2 + model["mean_se"] ** 2
    return a2 * (1.0 + 1.0 / r) / total if total > 0 else None


def records_differ(model: Mapping) -> bool:
    """Whether the history's record means differ more than their units' scatter explains at RECORD_LEVEL (F test)."""
    from scipy.stats import f  # here, not at the top: start-up time (scipy.stats takes ~1 s)

    a2, r = model["record_sd"] ** 2, model["records"]
    # Var(mu_hat) = (sigma_a^2 + mean(sigma_e^2 / m_r)) / R (record_effects.fit), so the within-record part is
    explained = r * model["mean_se"] ** 2 - a2
    if explained <= 0:
        return a2 > 0
    return float(f.sf((a2 + explained) / explained, r - 1, model.get("unit_dof", float("inf")))) < RECORD_LEVEL


def record_spread(condition: str, at: list[Mapping]) -> str | None:
    """The line saying which of *at*'s rows (one condition, one unit) have thresholds that rest mostly on the spread
    between the history's records (RECORD_SHARE, RECORD_LEVEL), with sigma_a / sigma_e for each; None where none
    does."""
    rest = [
        (r, r["history_model"])
        for r in at
        if (record_share(r.get("history_model")) or 0.0) > RECORD_SHARE and records_differ(r["history_model"])
    ]
    if not rest:
        return None
    n = rest[0][1]["records"]
    ratios = ", ".join(
        f"{m['record_sd'] / m['unit_sd']:.1f}x {r['method']}" if m["unit_sd"] > 0 else r["method"] for r, m in rest
    )
    return (
        f"{condition}: the {n} history records differ (record spread over the within-record spread: {ratios}; "
        f"the record effect more than {RECORD_SHARE:.0%} of a new unit's variance): these thresholds rest on that "
        "difference, a unit must exceed it to be called; add healthy takes of this condition (role history): "
        f"{n} records measure it on {n - 1} degree{'s' if n > 2 else ''} of freedom."
    )


def _cell(x) -> str:
    return "–" if x is None else f"{x:.0f}"


def watched_calls(row: Mapping, summary: Mapping) -> Mapping:
    """*row* with its detection and false alarms counted as a user acts on them once the damaged gear is
    named (gearlab.kinds.detection_which_gear): a unit of a record whose change lies on another gear
    is other damage, neither a detection nor a false alarm of the watched gear: its units leave the
    false alarms' count and their denominator alike (counted in, an other-damage take not flagged
    diluted a healthy take's false alarms: 4 % said for 8 %); its AUC over the same takes (calls_by_label's:
    counted in, such a take flagged on every unit ranked as a healthy take's false alarms, an AUC of 0.50
    beside 0 % false alarms). A unit of a take called a level change (nothing localised, its level off its history's:
    detection_which_gear.level_call) is set aside alike: no detection, no false alarm. The row as it is when the run
    localised nothing."""
    calls = (summary.get("which_gear") or {}).get("calls") or []
    call = next(
        (
            c
            for c in calls
            if (c["condition"], c["method"], c["unit"]) == (row["condition"], row["method"], row["unit"])
        ),
        None,
    )
    if call is None or "units" not in call:
        return row
    positive = (summary.get("target") or {}).get("positive", "fault")
    negative = [k for k in call["units"] if k != positive and call["watched"].get(k) is not None]
    judged = call.get("judged", call["units"])  # a summary from before 'judged': every unit counted
    n = sum(judged[k] for k in negative)
    # a flag of no gear (a record too short for the which-gear check) is no detection of the watched gear, but an
    # alarm all the same on a healthy take
    alarms = {k: call["watched"][k] + ((call.get("undetermined") or {}).get(k) or 0.0) for k in negative}
    # every negative take set aside (other damage, a level change): no false alarm to count, not the table's
    false_alarm = (
        sum(alarms[k] * call["units"][k] for k in negative) / n if n else None if negative else row["false_alarm"]
    )
    judged_auc = {"auc": call["auc"]} if "auc" in call else {}  # a summary from before it: the row's
    return {
        **row,
        "detection": call["watched"].get(positive, row["detection"]),
        "false_alarm": false_alarm,
        **judged_auc,
    }


def left_out(summary: Mapping, condition: str, unit: str) -> str:
    """The takes of *condition* the AUC and false alarms at *unit* leave out (calls_by_label's left_out), in words
    as each take's call says it: as other damage ('; left out of AUC and false alarms as other damage: b.csv (other
    damage: output gear 58T (stage 3))'), a mains hum as no gear fault; then the takes of any label set aside as a
    level change, counted ('; set aside as a level change: 1 take (h3.zip, 2.00 x), ...'); else ""."""
    calls = [
        c
        for c in (summary.get("which_gear") or {}).get("calls") or []
        if (c["condition"], c["unit"]) == (condition, unit)
    ]
    out: dict = {}
    moved: dict = {}
    for c in calls:
        moved |= c.get("level_changes") or {}
        out |= {p: w for p, w in (c.get("left_out") or {}).items() if p not in moved}
    kinds = {"other damage": {p: w for p, w in out.items() if not w.startswith(HUM)}}
    kinds["no gear fault"] = {p: w for p, w in out.items() if w.startswith(HUM)}
    said = [f"as {k}: " + ", ".join(f"{p} ({w})" for p, w in v.items()) for k, v in kinds.items() if v]
    text = "; left out of its AUC and false alarms " + "; ".join(said) if said else ""
    if moved:
        takes = ", ".join(f"{_file(p)}, {level_factor(w)} x" for p, w in moved.items())
        text += (
            f"; set aside as a level change: {len(moved)} take{'s' * (len(moved) > 1)} ({takes}: {LEVEL_WORDS}; no "
            "detection or false alarm here, its units in the table's raw rates; record a new history)"
        )
    return text


def _file(path: str) -> str:
    return path.replace("\\", "/").rsplit("/", 1)[-1]


def detection_lines(summary: Mapping, unit: str | None) -> list[str]:
    """Per condition, at the longest TSA: which rows meet the goal, the best learned row against the
    best classical one (_merit, on the test labels, after every decision was fixed), the learned rows
    that did not learn the simulated fault (their source AUC within chance_auc of the simulator's
    held-out revolutions, training data alone; they are never counted as the best learned row), and
    those whose domain loss aligned the history with a single point (training data alone; named,
    still counted). *unit*: the
    longest TSA of the rows, at which they are judged (gearlab.kinds.detection_records.longest_tsa)."""
    rows = summary.get("rows") or []
    if unit is None:
        return []
    learned = {(r["condition"], r["method"]): r for r in summary.get("learned") or []}
    calls = (summary.get("which_gear") or {}).get("calls") or []
    localised, moved = any("units" in c for c in calls), any(c.get("level_changes") for c in calls)
    lines = [
        f"At {unit} (detected / false alarms % at the history's threshold"
        + (", a unit on a record whose change lies on another gear being other damage, neither" if localised else "")
        + (" (a level change too)" if moved else "")
        + f"; goal: AUC >= {GOAL_AUC}, >= {GOAL_DETECTION:.0f} % detected at <= {GOAL_FALSE_ALARM:.0f} % false alarms):"
    ]
    for c in dict.fromkeys(r["condition"] for r in rows):
        at = [watched_calls(r, summary) for r in rows if r["condition"] == c and r["unit"] == unit]
        short = ""
        if at and all(r.get("n_positive") == 0 == r.get("n_negative") for r in at):
            # test takes too short for the longest TSA (1 s takes at 30 Hz: 29 turns, record30 needs 30) read 'no test
            # take', beside their record10 AUC of 1.00: judged at the longest unit they fill, the length to record said
            held = [r["unit"] for r in rows if r["condition"] == c and (r.get("n_positive") or r.get("n_negative"))]
            held = [u for u in held if u.startswith("record")]
            if held:
                shorter = max(held, key=lambda u: int(u.removeprefix("record")))
                at = [watched_calls(r, summary) for r in rows if r["condition"] == c and r["unit"] == shorter]
                short = (
                    f" (its test takes are too short for {unit}: judged at {shorter}; a take of "
                    f"{unit.removeprefix('record')} turns of the watched gear's shaft or more is judged at {unit})"
                )
            else:
                # a load's history with no test take of its own (a 29/73 box's 'heavy' read 'goal met by no row; best
                # learned matched_filter (AUC –, – / – %), level with ... (AUC –, – / – %)')
                lines.append(f"{c}: no test take: its history's thresholds serve gearlab score.")
                lines += [spread] if (spread := record_spread(c, at)) else []
                lines += [alone] if (alone := one_take(c, [r.get("history_model") for r in at])) else []
                continue
        met = [
            r
            for r in at
            if r["auc"] is not None
            and r["auc"] >= GOAL_AUC
            and (r["detection"] or 0.0) >= GOAL_DETECTION
            and (r["false_alarm"] or 0.0) <= GOAL_FALSE_ALARM
        ]
        blind = [
            m
            for (cc, m), r in learned.items()
            if cc == c and r["source_auc"] is not None and r["source_auc"] <= chance_auc(*r["source_units"])
        ]
        # a row that did not learn the simulated fault is no evidence for what the simulator teaches
        nets = [r for r in at if (c, r["method"]) in learned and r["method"] not in blind]
        classical = [r for r in at if (c, r["method"]) not in learned]
        text = f"{c}{short}: goal met by " + (", ".join(r["method"] for r in met) if met else "no row")
        if nets and classical:
            best_net, best_classical = max(nets, key=_merit), max(classical, key=_merit)
            than = {1: "better than", 0: "level with", -1: "behind"}[
                (_merit(best_net) > _merit(best_classical)) - (_merit(best_net) < _merit(best_classical))
            ]
            text += f"; best learned {_said(best_net)}, {than} the best classical {_said(best_classical)}"
        # where no row meets the goal, one that ranks as the goal asks is in reach of it: the history's threshold
        # failed, not the method (box B's na4: AUC 1.00, 0 / 0 %, its threshold over a history at two loads, said
        # nothing beside fm4's 100 / 30 %). Where a row meets it, another's threshold is no news
        missed = [] if met else [r for r in nets + classical if r["auc"] is not None and r["auc"] >= GOAL_AUC]
        # a row that called the fault takes at its threshold, all localised on another gear than the watched one
        # (a 26T pinion's damage named its 87T shaft-mate: AUC 1.00, 0 / 0 %), read 'the threshold fails'
        raw = {(r["method"], r["unit"]): r for r in rows if r["condition"] == c}
        aside = [
            r for r in missed if (raw[(r["method"], r["unit"])]["detection"] or 0.0) >= GOAL_DETECTION > r["detection"]
        ]
        missed = [r for r in missed if r not in aside]
        if aside:
            text += (
                "; call the fault takes at the history's threshold, but count those whose change lies on another gear "
                "than the watched one as other damage (which gear, not the threshold, decides: the 'watched / other' "
                "table): " + ", ".join(_said(r) for r in aside)
            )
        if missed:
            text += (
                f"; rank the test's takes as the goal asks (AUC >= {GOAL_AUC}) but miss it at the history's threshold "
                "(the threshold, not the method, fails): " + ", ".join(_said(r) for r in missed) + _spread(summary, c)
            )
        if blind:
            text += (
                "; did not learn the simulated fault (source AUC within chance, one-sided 5 %), so their calls "
                "are not the simulator's teaching: " + ", ".join(blind)
            )
        # learned the simulated fault, yet ranks the test's takes no better than chance: what it learned is not what
        # the test holds (box B's source_only: source AUC 1.00, record30 AUC 0.44, said nothing)
        astray = [
            f"{r['method']} (source AUC {learned[(c, r['method'])]['source_auc']:.2f}, test AUC {r['auc']:.2f})"
            for r in nets
            if r["auc"] is not None
            and learned[(c, r["method"])]["source_auc"] is not None  # a detector (built on the history) learned none
            and r.get("n_positive")
            and r.get("n_negative")
            and r["auc"] <= chance_auc(r["n_negative"], r["n_positive"])
        ]
        if astray:
            text += (
                "; learned the simulated fault but rank the test's takes no better than chance (one-sided 5 %): "
                "the simulator's fault or healthy signal is unlike this gearbox's (a gap run says where): "
                + ", ".join(astray)
            )
        point = [m for (cc, m), r in learned.items() if cc == c and r.get("aligned_to_a_point")]
        if point:
            text += (
                "; aligned the history with a single point (the source's samples they align it with are one "
                "input, a noise-free healthy revolution), so where they put a record unlike the history is "
                "not calibrated: " + ", ".join(point)
            )
        lines.append(text + left_out(summary, c, unit) + ".")
        lines += [spread] if (spread := record_spread(c, at)) else []
        lines += [alone] if (alone := one_take(c, [r.get("history_model") for r in at])) else []
        lines += [gear] if (gear := which_gear_line(summary, c)) else []
    return lines


# A gear's takes named in the which-gear line up to this many; over it, counted
NAMED_TAKES = 3


def which_gear_line(summary: Mapping, condition: str) -> str | None:
    """The gear each of *condition*'s test takes' change lies on, the watched ones said, with the takes' counts (and
    names, up to NAMED_TAKES), from the run's which-gear table; None where the run localised nothing. A first-time
    user of the TUI, its Results opening with the verdict and an ROC chart, found it only in the table under them."""
    which = summary.get("which_gear") or {}
    takes = {f: r for f, r in (which.get("records") or {}).items() if r.get("condition") == condition}
    if not takes:
        return None
    watched, by, beside = set(which.get("watched") or ()), {}, []
    for file, record in takes.items():
        name, call = file.replace("\\", "/").rsplit("/", 1)[-1], record.get("call") or ""
        # a bearing's line is no gear's: said as such, not 'nothing localised' (a 38/103 box's outer race at z 24 over
        # 4.5 was listed with the healthy takes), and beside a gear's change too
        by.setdefault(record.get("named") or (NONSYNC if call.startswith(OTHER_NONSYNC) else NOTHING), []).append(name)
        beside += [name] if record.get("named") and ALSO_NONSYNC in call else []
    said = [
        f"{gear}{', watched' * (gear in watched)}: {len(files)}" + named(files)
        for gear, files in sorted(
            by.items(), key=lambda item: (item[0] in (NONSYNC, NOTHING), item[0] == NOTHING, -len(item[1]))
        )
    ]
    said += [f"beside a gear's change, {NONSYNC}: {len(beside)}" + named(beside)] if beside else []
    return f"{condition}, which gear each test take's change lies on: {'; '.join(said)}."


NOTHING, NONSYNC = "nothing localised", "a non-synchronous (bearing-like) line"
OTHER_NONSYNC, ALSO_NONSYNC = "other damage: non-synchronous", "also other damage: non-synchronous"


def named(files: list[str]) -> str:
    """The takes' names in brackets, up to NAMED_TAKES of them ("" over it: counted alone)."""
    return f" ({', '.join(files)})" if len(files) <= NAMED_TAKES else ""


def one_take(condition: str, models: list[Mapping | None]) -> str | None:
    """The line saying that *condition*'s thresholds rest on one history take, where one of its rows' history *models*
    (record_effects.RecordEffects.as_dict) does (a 2 s take of a 29/139 box: its verdict 'goal met' said nothing of
    it), as the run's verdict and each `gearlab score` row say it; None otherwise."""
    if not any((m or {}).get("records") == 1 for m in models):
        return None
    return (
        f"{condition}: one history take: how far takes of other days lie apart is not measured, so the thresholds "
        "rest on its own revolutions and a new healthy take may be called more often than the false alarms asked; "
        "add two or more healthy takes of this condition (role history), from different days."
    )
