"""One self-contained report.html per run: the verdict, tables and figures inlined, nothing
to fetch. Figures are numbered and captioned, with the thesis figure each one repeats; the
resolved scenario and summary.json are folded away (<details>)."""

from __future__ import annotations

import base64
import html
import json
import re
from pathlib import Path

from .kinds import SCENARIO_KINDS
from .kinds.contract import VERDICT
from .runs import RunDir
from .verdict import verdict_lines, verdict_table

# .scroll: a table wider than the page (a benchmark's per-trial table, many methods) scrolls in its own box
STYLE = (
    "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
    "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
    "th{background:#eee}.scroll{overflow-x:auto}tr.reference td{color:#555;font-style:italic;background:#f7f7ff}"
    "img{max-width:100%;border:1px solid #ddd;margin:0.5em 0}pre{background:#f6f6f6;padding:1em;overflow:auto}"
    "figure{margin:1.5em 0}figcaption{font-size:0.92em;color:#333}"
    "#verdict{background:#f3f8f3;border-left:4px solid #4a4;padding:0.3em 1em}"
    "details{margin:1em 0}summary{cursor:pointer;font-weight:bold}"
)


def markdown_table(text: str) -> str:
    """A markdown pipe table as HTML; rows whose first cell names the thesis are reference rows."""
    rows = [r.strip().strip("|").split("|") for r in text.strip().splitlines() if r.strip()]
    rows = [r for r in rows if not all(set(c.strip()) <= set("-:") for c in r)]
    if not rows:
        return ""
    head, body = rows[0], rows[1:]
    out = ["<table><thead><tr>", *(f"<th>{_cell(c)}</th>" for c in head), "</tr></thead><tbody>"]
    for r in body:
        reference = " class='reference'" if "thesis" in r[0] else ""
        out += [f"<tr{reference}>", *(f"<td>{_cell(c)}</td>" for c in r), "</tr>"]
    out.append("</tbody></table>")
    return "".join(out)


def _cell(text: str) -> str:
    """A cell's text, escaped; Markdown's **bold** (the gap benchmark's 'all' row) in bold."""
    return re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", html.escape(text.strip()))


_markdown_table = markdown_table  # the name other modules used before


def _is_row(line: str) -> bool:
    return line.lstrip().startswith("|")


def table_blocks(text: str) -> list[tuple[str, str]]:
    """(title, Markdown table) of each table in *text* (blocks separated by blank lines): the
    lines of text just before a table, in its block or the block before, are its title; a
    paragraph after the last table comes back as (paragraph, '')."""
    out: list[tuple[str, str]] = []
    pending: list[str] = []
    for block in (b for b in text.split("\n\n") if b.strip()):
        lines = [line for line in block.strip().splitlines() if line.strip()]
        first = next((i for i, line in enumerate(lines) if _is_row(line)), None)
        if first is None:
            pending += lines
            continue
        out.append((" ".join(line.strip() for line in pending + lines[:first]), "\n".join(lines[first:])))
        pending = []
    if pending:
        out.append((" ".join(pending), ""))
    return out


def header_title(table: str) -> str:
    """A title made of a table's header when its kind gave none: 'view: gap before, share
    before, ... (16 Hz)' from '| 16 Hz: view | gap before | share before | ...'."""
    head = [c.strip() for c in table.strip().splitlines()[0].strip().strip("|").split("|")]
    first, rest = head[0], [c for c in head[1:] if c]
    where, _, label = first.rpartition(":") if ":" in first else ("", "", first)
    shown = ", ".join(dict.fromkeys(rest[:6])) + (", ..." if len(rest) > 6 else "")
    title = f"{shown} per {label.strip()}" if shown else label.strip()
    title = title[:1].upper() + title[1:]
    return f"{title} ({where.strip()})" if where.strip() else title


def _kind(summary: dict):
    return SCENARIO_KINDS.get(summary.get("kind"))


def figure_captions(summary: dict) -> dict[str, tuple[str, str]]:
    """The run's kind's captions of its figures by file stem, in the order it shows them
    (kinds.contract: figure_captions)."""
    kind = _kind(summary)
    return kind.figure_captions(summary) if kind is not None else {}


def caption(stem: str, summary: dict) -> tuple[str, str]:
    """(thesis figure it repeats or '', what the figure shows) for a figure file of a run."""
    return figure_captions(summary).get(stem, ("", stem.replace("_", " ") + "."))


def alt_text(label: str, text: str) -> str:
    """A figure's alt text: its number and what it shows, to the first clause of its caption."""
    first = text.split("; ")[0].split(". ")[0].rstrip(".")
    if len(first) > 160:  # cut at a word
        first = first[:160].rsplit(" ", 1)[0] + " …"
    return f"{label}: {first}"


def build_report(run: RunDir | Path) -> str:
    """report.html of a run. Every file is read through the run directory (RunDir.file): a
    link planted at a figure or a table is refused, never followed into the page."""
    run = run if isinstance(run, RunDir) else RunDir(Path(run))
    run_path = run.path
    summary = run.summary()
    title = f"gearlab run: {summary.get('scenario', run_path.parent.name)} ({summary.get('kind', '?')})"
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'>",
        f"<title>{html.escape(title)}</title>",
        f"<style>{STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        f"<p>Run directory: <code>{html.escape(str(run_path))}</code></p>",
    ]
    said = verdict_lines(run_path) if summary else []
    if said:
        parts += ["<section id='verdict'><h2>Verdict</h2>", *(f"<p>{html.escape(s)}</p>" for s in said), "</section>"]
    table = run.file("table.md")
    text = (verdict_table(run_path) if summary else None) or (table.read_text() if table.exists() else "")
    if text.startswith(VERDICT):  # table.md's verdict: the section above says it
        text = text.split("\n\n", 1)[-1]
    # a kind may write several tables, separated by blank lines (the gap kind: per-view gap,
    # effect ranking, accuracy); each is rendered on its own, numbered and titled
    if text.strip():
        parts.append("<h2>Tables</h2>")
    for i, (title, block) in enumerate(table_blocks(text), start=1):
        if block and not title and _kind(summary) is not None:
            title = _kind(summary).table_title(summary, i, block)
        if not block:  # a paragraph after the last table
            parts.append(f"<p>{html.escape(title)}</p>")
            continue
        titled = f"<caption><b>Table {i}.</b> {html.escape(title or header_title(block))}</caption>"
        parts.append(
            "<div class='scroll'>" + markdown_table(block).replace("<table>", f"<table>{titled}", 1) + "</div>"
        )
    figures = run.figures.files("*.png")
    captions = figure_captions(summary)
    order = list(captions)  # the kind's order (the thesis's where it repeats its figures), then by name
    figures.sort(key=lambda f: (order.index(f.stem) if f.stem in captions else len(order), f.name))
    if figures:
        parts.append("<h2>Figures</h2>")
    for i, fig in enumerate(figures, start=1):
        data = base64.b64encode(fig.read_bytes()).decode()
        thesis, text = captions.get(fig.stem, ("", fig.stem.replace("_", " ") + "."))
        note = run.file("figures", f"{fig.stem}.txt")  # what the figure says in words, written with it (a trend's)
        text += "".join(f" {line}." for line in note.read_text().splitlines()) if note.exists() else ""
        label = f"Figure {i}" + (f" (as thesis {thesis})" if thesis else "")
        parts.append(
            f"<figure id='{html.escape(fig.stem)}'><img alt='{html.escape(alt_text(label, text))}' "
            f"src='data:image/png;base64,{data}'><figcaption><b>{html.escape(label)}.</b> "
            f"{html.escape(text)}</figcaption></figure>"
        )
    scenario = run.file("scenario.toml")
    if scenario.exists():
        parts += [
            "<details><summary>Resolved scenario (scenario.toml)</summary>",
            f"<pre>{html.escape(scenario.read_text())}</pre></details>",
        ]
    if summary:
        brief = {k: v for k, v in summary.items() if k not in ("cases",)}
        parts += [
            "<details><summary>summary.json</summary>",
            f"<pre>{html.escape(json.dumps(brief, indent=1)[:20000])}</pre></details>",
        ]
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(run: RunDir) -> Path:
    """Write report.html into *run* (as a run ends, and `gearlab report` rebuilds it)."""
    run.write_text("report.html", build_report(run))
    return run.path / "report.html"
