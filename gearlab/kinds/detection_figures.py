"""The detection kind's figures (gearlab.kinds.detection; report.html), per condition at the unit
kind its verdict judges (the longest TSA): each method's scores per record beside its threshold,
the same scores in time order, and each method's ROC on the test units.

Everything is read from the finished run (results.jsonl, summary.json, conditions.json): the
scores and thresholds were fixed before any label was read; the labels only colour the test
records and make the ROC, from the very scores the table's AUC is made of (summarise)."""

from __future__ import annotations

import contextlib
import sys
import textwrap
from collections.abc import Iterator
from contextvars import ContextVar
from pathlib import Path

import numpy as np

from ..charts import Chart, Curve
from ..events import figures_ahead, report_begins
from ..parts.roc import roc_curve
from ..runs import RunDir
from .detection_records import longest_tsa, unit_window

HISTORY = "history"
HISTORY_COLOUR = "0.55"
POSITIVE_COLOUR = "tab:red"
OTHER_COLOURS = ("tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:cyan", "tab:olive")


def headline_unit(summary: dict) -> str | None:
    """The unit kind the figures show: the verdict's (the longest TSA), else the revolution."""
    units = [r["unit"] for r in summary.get("rows") or []]
    return longest_tsa(units) or ("revolution" if "revolution" in units else None)


def conditions_of(summary: dict) -> list[str]:
    """The conditions in the tables' order."""
    return list(dict.fromkeys(r["condition"] for r in summary.get("rows") or []))


def stems(summary: dict) -> list[str]:
    """The figure files' stems, in the order the report shows them."""
    n = len(conditions_of(summary))
    return ["detection_roc"] + [f"detection_{what}_{i}" for i in range(1, n + 1) for what in ("scores", "time")]


def _main(records: list[dict]) -> dict[tuple[str, str], dict]:
    """{(condition, method): record} of the records the tables show (an ensemble's members and a crossed
    fit's folds are shown through their ensemble or fit, as summarise does)."""
    return {(r["condition"], r["method"]): r for r in records if r.get("seed") is None and r.get("fold") is None}


def _labels(summary: dict) -> tuple[dict[str, str], str]:
    target = summary.get("target") or {}
    return {f["path"]: f["label"] for f in target.get("files", [])}, target.get("positive", "fault")


def test_split(record: dict, unit: str, labels: dict, positive: str) -> tuple[np.ndarray, np.ndarray]:
    """A record's test scores of *unit* as (negatives, positives), as summarise splits them."""
    scores = record["test_scores"]
    neg = [scores[p][unit] for p in scores if labels[p] != positive]
    pos = [scores[p][unit] for p in scores if labels[p] == positive]
    return np.concatenate(neg or [np.empty(0)]), np.concatenate(pos or [np.empty(0)])


def roc_charts(summary: dict, records: list[dict]) -> list[Chart]:
    """Per condition, each method's ROC on the test's units of the headline kind: the false-alarm
    and detection rates as the threshold is lowered past each score (gearlab.parts.roc), labelled
    with the method's AUC as the table gives it; a method with no AUC (scores that are not numbers)
    has no curve and a note."""
    unit = headline_unit(summary)
    if unit is None:
        return []
    by = _main(records)
    labels, positive = _labels(summary)
    out = []
    for c in conditions_of(summary):
        curves, notes = [], []
        for row in (r for r in summary["rows"] if r["condition"] == c and r["unit"] == unit):
            record = by.get((c, row["method"]))
            roc = None if record is None else roc_curve(*test_split(record, unit, labels, positive))
            if roc is None or row["auc"] is None:
                notes.append(f"{row['method']}: no ROC (no AUC)")
                continue
            curves.append(Curve(f"{row['method']} (AUC {row['auc']:.3f})", roc[0].tolist(), roc[1].tolist()))
        if curves:
            out.append(
                Chart(
                    f"{c}: ROC on the test's {unit} units",
                    "false alarms (share of negative units called)",
                    "detection (share of positive units called)",
                    tuple(curves),
                    notes=tuple(notes),
                )
            )
    return out


def record_panels(summary: dict, records: list[dict], conditions: dict) -> dict[str, list[dict]]:
    """{condition: one panel per method (the table's order): {"method", "threshold", "records":
    [(record name, "history" or its label, (unit starts in revolutions, scores))]}} at the headline
    unit kind: the history's records (their units split by the counts conditions.json keeps; pooled
    as one for a run from before it kept them), then the test's, negatives first."""
    unit = headline_unit(summary)
    if unit is None:
        return {}
    by = _main(records)
    labels, positive = _labels(summary)
    block, stride = unit_window(unit)
    out: dict[str, list[dict]] = {}
    for c in conditions_of(summary):
        cond = conditions.get(c) or {}
        counts = (cond.get("history_units") or {}).get(unit)
        names = [Path(p).stem for p in cond.get("history", [])] if counts else [HISTORY]
        panels = []
        for row in (r for r in summary["rows"] if r["condition"] == c and r["unit"] == unit):
            record = by.get((c, row["method"]))
            if record is None:
                continue
            history = np.asarray(record["history_scores"][unit], dtype=np.float64)
            parts = np.split(history, np.cumsum(counts)[:-1]) if counts else [history]
            shown = [(name, HISTORY, (np.arange(len(s)) * stride, s)) for name, s in zip(names, parts)]
            test = sorted(record["test_scores"], key=lambda p: labels[p] == positive)  # stable: file order kept
            for p in test:
                s = np.asarray(record["test_scores"][p][unit], dtype=np.float64)
                shown.append((Path(p).stem, labels[p], (np.arange(len(s)) * block, s)))
            panels.append({"method": row["method"], "threshold": row["threshold"], "records": shown})
        out[c] = panels
    return out


def colours(summary: dict) -> dict[str, str]:
    """A colour per record kind: the history grey, the fault to detect red, every other label its own."""
    labels, positive = _labels(summary)
    others = [label for label in dict.fromkeys(labels.values()) if label != positive]
    return {
        HISTORY: HISTORY_COLOUR,
        positive: POSITIVE_COLOUR,
        **{label: OTHER_COLOURS[i % len(OTHER_COLOURS)] for i, label in enumerate(others)},
    }


def captions(summary: dict) -> dict[str, tuple[str, str]]:
    """{figure stem: ("", caption)} of a detection run's figures."""
    unit = headline_unit(summary)
    if unit is None:
        return {}
    asked = 100 * summary.get("false_alarm_asked", 0.0)
    rule = summary.get("threshold_rule", "records")
    threshold = (
        f"dashed: the method's threshold, fixed on the history's scores alone ('{rule}' rule, {asked:g} % false "
        "alarms asked)"
    )
    out = {
        "detection_roc": (
            "",
            f"ROC of each method on the test's {unit} units, per condition: detection (share of the positive "
            "units called) against false alarms (share of the negative units called) as the threshold is "
            "lowered past each score; the legend gives each method's ROC AUC, as the table does; dot: where "
            "the history's threshold put the method; dotted: chance.",
        )
    }
    for i, c in enumerate(conditions_of(summary), start=1):
        out[f"detection_scores_{i}"] = (
            "",
            f"Condition {c}: each method's {unit} scores per record; box: quartiles, whiskers: 1.5 times the "
            "interquartile range, dots: every unit; grey: the history's records, coloured: the test's, by label; "
            f"{threshold}.",
        )
        out[f"detection_time_{i}"] = (
            "",
            f"Condition {c}: each method's {unit} scores in time order (the revolution each unit starts at), a "
            f"line per record; grey: the history's records (sliding units), coloured: the test's, by label; "
            f"{threshold}.",
        )
    return out


_POOL: ContextVar = ContextVar("detection_figures_pool", default=None)
# the fewest figures drawn in a pool: a worker's first figure pays its matplotlib import (~1 s of
# CPU), about what a tiny run's three figures take here; phm09_chip's are 9 of 1-3 s each
POOLED_FROM = 5


@contextlib.contextmanager
def drawing_in(executor) -> Iterator[None]:
    """draw() inside this block draws its figures in *executor*'s worker processes, side by side,
    where it is a pool of this machine's (gearlab.executors.LocalExecutor, more than one worker):
    a phm09_chip run drew its 9 figures one after the other for ~21 s of CPU while the other core
    stood idle. Elsewhere (one worker, a cluster's nodes, which may not reach the run directory)
    they are drawn here."""
    from ..executors import LocalExecutor

    token = _POOL.set(executor if isinstance(executor, LocalExecutor) and executor.workers > 1 else None)
    try:
        yield
    finally:
        _POOL.reset(token)


def draw(run: RunDir) -> None:
    """The figures of a finished detection run, into run.figures. Their constrained layout already
    fits everything on the canvas (legends, suptitle), so they are saved without bbox_inches='tight',
    which measured every artist again (the scores figure 0.95 -> 0.64 s of CPU). In a pool's workers
    (drawing_in) when gearlab.plots.save is gearlab's own: a caller's own save (a test's, which
    writes without rendering) is called in this process."""
    report_begins()  # the run's 'report' stage, before matplotlib loads (seconds)
    summary = run.read_json("summary.json")
    if not summary or headline_unit(summary) is None:
        return
    records = run.records()
    charts = roc_charts(summary, records)
    panels = record_panels(summary, records, run.read_json("conditions.json") or {})
    figures_ahead(bool(charts) + 2 * sum(bool(panels.get(c)) for c in conditions_of(summary)))  # i of n
    jobs = [("roc", (charts, summary), run.figures / "detection_roc.png")] if charts else []
    for i, c in enumerate(conditions_of(summary), start=1):
        if panels.get(c):
            jobs.append(("scores", (c, panels[c], summary), run.figures / f"detection_scores_{i}.png"))
            jobs.append(("time", (c, panels[c], summary), run.figures / f"detection_time_{i}.png"))
    pool, loaded = _POOL.get(), sys.modules.get(f"{__package__.rpartition('.')[0]}.plots")  # (no matplotlib yet)
    own = loaded is None or getattr(loaded.save, "__module__", None) == loaded.__name__
    if pool is None or len(jobs) < POOLED_FROM or not own:
        from .. import plots  # here, not at the top: start-up time (matplotlib)

        for job in jobs:
            _draw_one(job, plots.save)
        return
    from ..events import figure_written

    pool.map(_draw_one, jobs, on_done=lambda _, name: figure_written(name))  # counted here, as they end


def _draw_one(job: tuple, saved=None) -> str:
    """Draw and write one figure of draw()'s *job* (kind, arguments, path); its file's name."""
    if saved is None:  # a worker: gearlab's own save
        from ..plots import save as saved
    kind, args, path = job
    make = {"roc": _roc_figure, "scores": _scores_figure, "time": _time_figure}[kind]
    return saved(make(*args), path, bbox_inches=None).name


def _grid(n: int, width: float = 4.2, height: float = 2.7):
    import matplotlib.pyplot as plt

    cols = min(3, n)
    rows = -(-n // cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(width * cols, height * rows + 0.9), squeeze=False, layout="constrained"
    )
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, list(axes.flat[:n])


def _legend(fig, summary: dict, kinds: list[str], line: bool) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    palette = colours(summary)
    handles = [
        Line2D([], [], color=palette.get(k, "k"), lw=1.5) if line else Patch(color=palette.get(k, "k"), alpha=0.6)
        for k in kinds
    ]
    handles.append(Line2D([], [], color="k", ls="--", lw=1))
    names = [("history (healthy, unlabelled)" if k == HISTORY else f"test: {k}") for k in kinds] + ["threshold"]
    fig.legend(handles, names, loc="outside lower center", ncols=min(len(names), 5), fontsize=8, frameon=False)


def _finite(scores: np.ndarray) -> np.ndarray:
    return scores[np.isfinite(scores)]


def _scores_figure(condition: str, panels: list[dict], summary: dict):
    palette = colours(summary)
    fig, axes = _grid(len(panels))
    rng = np.random.default_rng(0)  # the dots' horizontal jitter only
    for ax, panel in zip(axes, panels):
        names = [name for name, _, _ in panel["records"]]
        data = [_finite(s) for _, _, (_, s) in panel["records"]]
        boxes = ax.boxplot(
            [d if len(d) else [np.nan] for d in data], positions=range(len(data)), widths=0.6, showfliers=False
        )
        for i, ((_, kind, _), d) in enumerate(zip(panel["records"], data)):
            colour = palette.get(kind, "k")
            for part in ("boxes", "medians"):
                boxes[part][i].set_color(colour)
            ax.plot(i + rng.uniform(-0.2, 0.2, len(d)), d, ".", ms=2.5, alpha=0.5, color=colour)
        ax.axhline(panel["threshold"], color="k", ls="--", lw=1)
        ax.set_xticks(range(len(names)), names, rotation=90, fontsize=6)
        ax.set_title(panel["method"], fontsize=8)
        ax.set_ylabel("score", fontsize=8)
        ax.tick_params(axis="y", labelsize=7)
        ax.grid(alpha=0.3, axis="y")
    kinds = list(dict.fromkeys(kind for p in panels for _, kind, _ in p["records"]))
    _legend(fig, summary, kinds, line=False)
    fig.suptitle(f"{condition}: scores per record ({headline_unit(summary)} units) and the threshold", fontsize=10)
    return fig


def _time_figure(condition: str, panels: list[dict], summary: dict):
    palette = colours(summary)
    fig, axes = _grid(len(panels))
    for ax, panel in zip(axes, panels):
        for _, kind, (x, s) in panel["records"]:
            ax.plot(
                x, s, marker="." if kind != HISTORY else None, ms=3, lw=0.6 if kind == HISTORY else 0.9,
                color=palette.get(kind, "k"), alpha=0.6 if kind == HISTORY else 0.9,
            )  # fmt: skip
        ax.axhline(panel["threshold"], color="k", ls="--", lw=1)
        ax.set_title(panel["method"], fontsize=8)
        ax.set_xlabel("revolution (unit start)", fontsize=8)
        ax.set_ylabel("score", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    kinds = list(dict.fromkeys(kind for p in panels for _, kind, _ in p["records"]))
    _legend(fig, summary, kinds, line=True)
    fig.suptitle(f"{condition}: scores in time order ({headline_unit(summary)} units) and the threshold", fontsize=10)
    return fig


def _roc_figure(charts: list[Chart], summary: dict):
    import matplotlib.pyplot as plt

    rows = {(r["condition"], r["method"]): r for r in summary["rows"] if r["unit"] == headline_unit(summary)}
    cols = min(2, len(charts))
    grid_rows = -(-len(charts) // cols)
    # near-square axes from the figure's shape, not set_aspect: the constrained layout reserves the
    # legend's room beside the axes it placed, and an equal aspect then moved each axes within its
    # cell, its legend over the next column's axes and off the canvas (phm09_chip, four conditions)
    fig, axes = plt.subplots(
        grid_rows, cols, figsize=(6.4 * cols, 4.0 * grid_rows + 0.4), squeeze=False, layout="constrained"
    )
    for ax in axes.flat[len(charts) :]:
        ax.set_visible(False)
    colours_ = plt.get_cmap("tab10").colors
    for ax, chart in zip(axes.flat, charts):
        c = chart.title.split(": ROC")[0]
        ax.plot([0, 1], [0, 1], ":", color="0.5", lw=1)
        for i, curve in enumerate(chart.curves):
            # colour and line style both vary, so that methods whose curves coincide stay apart
            colour, style = colours_[i % len(colours_)], ("-", "--", "-.", ":")[(i // 2) % 4]
            ax.plot(curve.x, curve.y, style, lw=1.4, color=colour, label=curve.label)
            row = rows.get((c, curve.label.rsplit(" (AUC", 1)[0]))
            if row and row["detection"] is not None and row["false_alarm"] is not None:
                ax.plot(row["false_alarm"] / 100, row["detection"] / 100, "o", ms=4, color=colour)
        ax.set_xlim(-0.02, 1.02)
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel(chart.xlabel, fontsize=8)
        ax.set_ylabel(chart.ylabel, fontsize=8)
        ax.set_title(chart.title + ("; " + "; ".join(chart.notes) if chart.notes else ""), fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    return fig


TITLE_CHARS = 160  # a line of a 9 pt title across the trend's 10 in figure
TREND_PLOT_IN = 3.0  # a trend chart's plot, axes and labels (in)
TITLE_LINE_IN = 0.17  # and each line of its 9 pt title


def score_trend(charts, path: Path) -> Path:
    """The scoring history's trends (detection_scoring.score_trends; `gearlab score`): per condition,
    each method's score of the records scored in turn, less its threshold (above the line: called)."""
    from .. import plots  # here, not at the top: start-up time (matplotlib)

    # the title names every take scored and each note: wrapped to the figure's width (unwrapped, a long
    # history's title widened the PNG to 3224 px and left the plot a strip in its middle)
    titles = ["\n".join(textwrap.fill(line, TITLE_CHARS) for line in chart.title.splitlines()) for chart in charts]
    # each chart the plot's height and its title's lines: 6 of them left a month of takes' plot 0.9 in of 3.2
    heights = [TREND_PLOT_IN + TITLE_LINE_IN * (title.count("\n") + 1) for title in titles]
    fig, axes = plots.plt.subplots(
        len(charts), 1, figsize=(10, sum(heights)), squeeze=False, layout="constrained", height_ratios=heights
    )
    for ax, chart, title in zip(axes[:, 0], charts, titles):
        for curve in chart.curves:
            ax.plot(curve.x, curve.y, marker="o", ms=3, lw=0.8, label=curve.label)
        ax.axhline(0.0, color="k", lw=0.8, ls="--")
        # the records scored in turn: whole-number ticks, as the TUI's (matplotlib's own: 1.2, 1.4, ... for two)
        if chart.xticks is not None:
            ax.set_xticks(list(chart.xticks))
        else:
            ax.xaxis.set_major_locator(plots.plt.MaxNLocator(integer=True))
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(chart.xlabel)
        ax.set_ylabel(chart.ylabel)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("gearlab score: the scored records' trend per method")
    return plots.save(fig, path)
