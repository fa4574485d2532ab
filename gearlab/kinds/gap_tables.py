"""The tables of a gap run (gearlab.kinds.gap): per-view gap, effect ranking and downstream
accuracy, as Markdown for table.md, the report, the terminal and the TUI."""

from __future__ import annotations


def _interval(iv) -> str:
    return f" [{iv[0]:.3g}, {iv[1]:.3g}]" if iv else ""


def evaluations_text(summary: dict) -> str:
    """'; 1094 score evaluations': what the diagnosis cost (nothing from a summary before the count)."""
    n = summary.get("evaluations")
    return "" if n is None else f"; {n} score evaluations"


def percent(x) -> str:
    return f"{100 * x:.1f} %" if x is not None else ""


def views_md(views: dict) -> str:
    noise = any("gap_noise" in v for v in views.values())  # a column for the noise-alone reference
    lines = [
        "| view | gap before | share before | "
        + ("gap with noise alone | " if noise else "")
        + "gap after | share after |",
        "|---|---|---|---|---|" + ("---|" if noise else ""),
    ]
    for name, v in views.items():
        after = "" if v["gap_after"] is None else f"{v['gap_after']:.4g}{_interval(v['gap_after_interval'])}"
        share_iv = v["share_before_interval"]
        share_before = percent(v["share_before"]) + (
            f" [{100 * share_iv[0]:.0f}, {100 * share_iv[1]:.0f}]" if share_iv else ""
        )
        middle = (f"{v['gap_noise']:.4g} | " if v.get("gap_noise") is not None else " | ") if noise else ""
        lines.append(
            f"| {name} | {v['gap_before']:.4g}{_interval(v['gap_before_interval'])} | {share_before} | "
            f"{middle}{after} | {percent(v['share_after'])} |"
        )
    return "\n".join(lines) + "\n"


def params_text(params: dict, determined: dict | None = None) -> str:
    """k = v, ...; a parameter the data do not determine is marked "not identifiable" (a distant value
    fits as well: its profile, gearlab.gap.identify) or "not determined: the fit leaves a gap"."""

    def mark(k):
        if not determined or k not in determined or determined[k]["determined"]:
            return ""
        if determined[k].get("reason") == "fit leaves a gap":
            return " (not determined: the fit leaves a gap)"
        if determined[k].get("reason") == "not profiled (--quick)":  # gap.identify.CUT_SHORT
            return " (not profiled: --quick)"
        return " (not identifiable)"

    return ", ".join((f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}") + mark(k) for k, v in params.items())


def ranking_md(ranking: list[dict], accepted: list[dict], dropped: list[dict] | None = None) -> str:
    chosen = {e["name"]: e for e in accepted}
    # accepted, then not named (gap_verdict.dropped_text): an empty cell read as 'never accepted'
    gone = {e["name"]: f"round {e.get('round')}, then not named; {params_text(e['params'])}" for e in dropped or []}
    # each row is its round-1 fit: with sensor noise a candidate, every other one is fitted with the noise
    # beside it (gap.diagnose.greedy_round; 'alone' read as without it); an accepted effect's final fit,
    # next to the others, is in the verdict and the summary's effects
    noise = any(r["name"] == "sensor_noise" for r in ranking)  # gap.scoring.NUISANCE (this module imports nothing)
    fit = "round-1 fit" + (", sensor noise fitted beside each other effect" if noise else "")
    head = f"| effect | share of the gap removed (round 1) | parameters ({fit}) | accepted (final fit) |"
    lines = [head, "|---|---|---|---|"]
    for r in ranking:
        e = chosen.get(r["name"])
        mark = f"round {e.get('round')}, {percent(e['share_removed'])}; {params_text(e['params'])}" if e else ""
        mark = mark or gone.get(r["name"], "")
        lines.append(f"| {r['name']} | {percent(r['share_removed'])} | {params_text(r.get('params', {}))} | {mark} |")
    return "\n".join(lines) + "\n"


def accuracy_md(acc: dict, order: list[str] | None = None) -> str:
    lines = ["| model (k = 0) | target test accuracy (%) | repetitions |", "|---|---|---|"]
    lines += [
        f"| {label} | {acc[label]['mean']:.2f} ± {acc[label]['std']:.1f} | {acc[label]['n']} |"
        for label in (order or list(acc))
    ]
    return "\n".join(lines) + "\n"


def tables_md(summary: dict) -> str:
    """Three tables separated by blank lines: per-view gap, effect ranking, accuracy."""
    parts = [
        *([views_md(summary["views"])] if summary["views"] else []),  # none: a structure difference, no gap measured
        ranking_md(summary["ranking"], summary["effects"], summary.get("dropped_effects")),
    ]
    if summary.get("accuracy"):
        parts.append(accuracy_md(summary["accuracy"]))
    return "\n".join(parts)
