"""Runs side by side: `gearlab compare RUN_DIR RUN_DIR... [--html FILE]` and the TUI's comparison.

Runs of one kind are compared: a transfer comparison puts each run's accuracy beside the
others' for every method and k (with the difference to the first run) and overlays their
accuracy-against-k curves, a detection one each run's AUC and rates per condition, method and
unit; any other kind shows each run's tables one under the other and overlays the charts that
the kind draws for each run (same title, curves named by run). Runs are lettered A, B, C ... in
the order given.
"""

from __future__ import annotations

import base64
import html
import string
from dataclasses import dataclass, replace
from pathlib import Path

from .charts import Chart, Curve
from .confined import read_file
from .engine import scenario_of
from .errors import GearlabInputError
from .kinds import SCENARIO_KINDS
from .report import STYLE, markdown_table
from .runs import RunDir
from .scenario import Scenario
from .verdict import load_summary, verdict_lines


@dataclass
class Compared:
    letter: str
    run: RunDir
    scenario: Scenario
    summary: dict

    @property
    def kind(self) -> str:
        return self.scenario.kind

    @property
    def title(self) -> str:
        quick = ", quick" if self.run.quick else ""
        state = "" if self.summary else ", unfinished"
        return f"{self.letter}: {self.scenario.name} {self.run.path.name}{quick}{state} ({self.run.path})"


def load_runs(paths) -> list[Compared]:
    """The run directories, checked: two or more, each a run directory, all of one kind."""
    paths = [Path(p) for p in paths]
    if len(paths) < 2:
        raise GearlabInputError(f"compare: expected two or more run directories, got {len(paths)}")
    if len(paths) > len(string.ascii_uppercase):
        raise GearlabInputError(f"compare: at most {len(string.ascii_uppercase)} runs, got {len(paths)}")
    runs = []
    for letter, path in zip(string.ascii_uppercase, paths):
        run = RunDir.open(path)
        runs.append(Compared(letter, run, scenario_of(run), load_summary(path)))
    kinds = {r.kind for r in runs}
    if len(kinds) > 1:
        shown = ", ".join(f"{r.run.path} is {r.kind}" for r in runs)
        raise GearlabInputError(f"compare: expected runs of one kind, got {shown}")
    return runs


def _side_by_side(runs: list[Compared]) -> tuple[str, str] | None:
    """The kind's own table of the runs side by side and its title (its compare_table), if any."""
    kind = SCENARIO_KINDS[runs[0].kind]
    return kind.compare_table([(c.letter, c.scenario, c.run.records(), c.summary) for c in runs])


def compare_markdown(runs: list[Compared]) -> str:
    """The kind's side-by-side table where it has one (transfer: a row per method and k, a column per
    run and each run's difference to A); else each run's table, lettered."""
    joined = _side_by_side(runs)
    if joined is not None:
        return joined[1]
    parts = []
    for c in runs:
        text = SCENARIO_KINDS[c.kind].records_table(c.scenario, c.run.records()).strip()
        if not text:
            continue
        blocks = []
        for block in text.split("\n\n"):  # a kind may write several tables; each gets the letter
            rows = block.strip().splitlines()
            first = rows[0].split("|")
            first[1] = f" {c.letter}: {first[1].strip()} "
            blocks.append("\n".join(["|".join(first)] + rows[1:]))
        parts.append("\n\n".join(blocks))
    return "\n\n".join(parts) + "\n"


def print_tables(console, runs: list[Compared]) -> None:
    """compare_markdown's tables as rich tables on *console* (terminal.rich_table, as at the end
    of a run: turned on a terminal too narrow for their words; a log or a pipe gets them drawn at
    their natural width), the kind's side-by-side table under its title."""
    from .terminal import markdown_tables, print_table, rich_table

    joined = _side_by_side(runs)
    text = joined[1] if joined is not None else compare_markdown(runs)
    blocks = [markdown_tables(block) or [] for block in text.split("\n\n")]  # apart: it skips blank lines
    for i, (caption, header, rows) in enumerate(table for found in blocks for table in found):
        title = caption or (joined[0] if joined is not None and i == 0 else "")
        print_table(console, rich_table(title, header, rows, console))


def compare_charts(runs: list[Compared]) -> list[Chart]:
    """Each chart the kind draws for the first run, with the same chart of every other run
    overlaid (curves named 'A: label'); bar charts join their categories."""
    per_run = [SCENARIO_KINDS[c.kind].charts(c.scenario, c.run) for c in runs]
    titles = list(dict.fromkeys(ch.title for charts in per_run for ch in charts))
    out = []
    for title in titles:
        found = [(c, next((ch for ch in charts if ch.title == title), None)) for c, charts in zip(runs, per_run)]
        found = [(c, ch) for c, ch in found if ch is not None and ch.curves]
        if not found:
            continue
        first = found[0][1]
        if first.categories is not None:
            categories = list(dict.fromkeys(n for _, ch in found for n in (ch.categories or ())))
            curves = []
            for c, ch in found:
                for curve in ch.curves:
                    by_name = dict(zip(ch.categories or (), curve.y))
                    curves.append(
                        Curve(
                            f"{c.letter}: {curve.label}",
                            list(range(len(categories))),
                            [float(by_name.get(n, 0.0)) for n in categories],
                        )
                    )
            out.append(
                replace(
                    first,
                    title=f"{title} (runs {', '.join(c.letter for c, _ in found)})",
                    curves=tuple(curves),
                    categories=categories,
                )
            )
        else:
            curves = tuple(replace(curve, label=f"{c.letter}: {curve.label}") for c, ch in found for curve in ch.curves)
            ticks = sorted({float(t) for _, ch in found for t in (ch.xticks or ())}) or None
            out.append(
                replace(
                    first, title=f"{title} (runs {', '.join(c.letter for c, _ in found)})", curves=curves, xticks=ticks
                )
            )
    return out


def compare_lines(runs: list[Compared]) -> list[str]:
    """Which run is which, then each finished run's verdict."""
    lines = [c.title for c in runs]
    for c in runs:
        said = verdict_lines(c.run) if c.summary else []
        if said:
            lines.append(f"{c.letter}: " + " ".join(said))
    return lines


def differences_text(runs: list[Compared]) -> str:
    """The scenario keys whose values differ, on one line ('scenario differences: diagnosis.budget
    A 2, B 3; ...'), or that the scenarios are the same: what `gearlab compare` prints as a table,
    for its page and the TUI's comparison (they showed the figures' differences only: issue 41)."""
    from .runinfo import scenario_differences

    rows = scenario_differences([c.run.path for c in runs])
    if not rows:
        return "scenarios: the same (apart from their names)"
    said = (f"{key} " + ", ".join(f"{c.letter} {v}" for c, v in zip(runs, values)) for key, values in rows)
    return "scenario differences: " + "; ".join(said)


def compare_html(runs: list[Compared], figures: Path) -> str:
    """A self-contained page: the runs, the table side by side, the overlaid charts (PNG,
    inlined) and each run's verdict. *figures*: a folder for the PNGs while they are drawn."""
    lines = compare_lines(runs)
    title = f"gearlab comparison: {len(runs)} {runs[0].kind} runs"
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'>",
        f"<title>{html.escape(title)}</title>",
        f"<style>{STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        "<ul>",
        *(f"<li>{html.escape(t)}</li>" for t in lines[: len(runs)]),
        "</ul>",
        f"<p id='differences'>{html.escape(differences_text(runs))}</p>",
    ]
    verdicts = lines[len(runs) :]
    if verdicts:
        parts += [
            "<section id='verdict'><h2>Verdicts</h2>",
            *(f"<p>{html.escape(v)}</p>" for v in verdicts),
            "</section>",
        ]
    blocks = [b for b in compare_markdown(runs).split("\n\n") if b.strip()]
    joined = _side_by_side(runs)
    parts += [
        "<h2>Table 1. " + (joined[0] if joined is not None else "The runs’ tables") + "</h2>",
        *map(markdown_table, blocks),
    ]
    for i, chart in enumerate(compare_charts(runs), start=1):
        from .plots import chart_figure  # here, not at the top: start-up time (matplotlib; the TUI's compare)

        png = chart_figure(chart, Path(figures) / f"compare_{i}.png")
        data = base64.b64encode(read_file(png)).decode()  # drawn just now into the caller's folder
        caption = f"Figure {i}. {chart.title}: the runs overlaid ({chart.ylabel} against {chart.xlabel or 'category'})."
        parts.append(
            f"<figure><img alt='{html.escape(chart.title)}' src='data:image/png;base64,{data}'>"
            f"<figcaption>{html.escape(caption)}</figcaption></figure>"
        )
    parts.append("</body></html>")
    return "\n".join(parts)
