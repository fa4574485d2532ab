"""One self-contained report.html per run: the verdict, tables and figures inlined, nothing
to fetch. Figures are numbered and captioned, with the thesis figure each one repeats; the
resolved scenario and summary.json are folded away (<details>)."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

from .kinds.transfer_verdict import experiment
from .runs import RunDir
from .verdict import verdict_lines, verdict_table

STYLE = (
    "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
    "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
    "th{background:#eee}tr.reference td{color:#555;font-style:italic;background:#f7f7ff}"
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
    out = ["<table><thead><tr>", *(f"<th>{html.escape(c.strip())}</th>" for c in head), "</tr></thead><tbody>"]
    for r in body:
        reference = " class='reference'" if "thesis" in r[0] else ""
        out += [f"<tr{reference}>", *(f"<td>{html.escape(c.strip())}</td>" for c in r), "</tr>"]
    out.append("</tbody></table>")
    return "".join(out)


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


# figure file stem -> (the thesis figure it repeats, what it shows); the captions that depend
# on the run (k, repetitions, experiment, dataset) are made in caption()
CAPTIONS = {
    "training_curves": (
        "Figure 5.7",
        "Training curves of the first repetition at the middle k: source validation "
        "accuracy (%, left axis), domain discrepancy and λ (dimensionless, right axis) against epoch; "
        "the dashed line marks the epoch kept.",
    ),
    "latent_maps": (
        "Figure 5.9",
        "Latent features of the first repetition after adaptation: source and target "
        "training samples projected on their first two principal components (PCA, dimensionless); "
        "colour: domain, marker: class (o healthy, x fault) where the run stored the labels.",
    ),
    "accuracy_vs_intensity": (
        "Figure 4.4",
        "Test accuracy (%) per fault type against the intensity step (1-20), all "
        "faults (black) and faults predicted healthy (green, dashed); mean ± std over runs; "
        "noisy left, TSA right.",
    ),
    "accuracy_vs_rfa": (
        "Figure 4.5",
        "Test accuracy (%) per fault type against relative fault area (%, up to 50 %); mean ± std over runs.",
    ),
    "confusion": (
        "Figure 4.6",
        "Confusion matrices compiled over all runs (counts; shading: share of the true class).",
    ),
    "tvms_ladders": (
        "Figure 2.33",
        "Time-varying mesh stiffness (1e8 N/m) against pinion angle (deg) for every step "
        "of each fault ladder; colour: intensity step.",
    ),
    "rfa": (
        "Figure 2.32",
        "Relative fault area (fraction of the healthy tooth) against intensity step per fault type.",
    ),
    "tvms_cases": ("", "Time-varying mesh stiffness (1e8 N/m) against pinion angle (deg) of the scenario's cases."),
    "gap_per_view": (
        "",
        "Where the gap lies: per-view gap (sum of squared effect sizes, dimensionless) of the healthy "
        "revolutions before and after correcting the simulator, with bootstrap intervals.",
    ),
    "gap_effect_ranking": (
        "",
        "Which effect: share of the gap (%) each candidate removes when added to the "
        "simulator alone; accepted effects in blue.",
    ),
    "gap_accuracy": (
        "",
        "How far: target test accuracy (%) at k = 0 of models trained on the uncorrected and the "
        "corrected simulator; mean ± std over repetitions.",
    ),
    "gap_benchmark": (
        "",
        "The blind benchmark: gap before and after per trial, and how often each hidden effect is named first.",
    ),
    "transfer_benchmark": (
        "",
        "Random unseen targets: each method's target test accuracy (%) per trial beside the trial's Bayes "
        "bound, and its distance to the bound over the trials that have one (dotted: 5 points).",
    ),
}


# figures in the order the thesis numbers them (then any other, by name)
ORDER = [
    "rfa",
    "tvms_ladders",
    "tvms_cases",
    "accuracy_vs_intensity",
    "accuracy_vs_rfa",
    "confusion",
    "accuracy_vs_k",
    "training_curves",
    "confusion_k0",
    "latent_maps",
    "gap_per_view",
    "gap_effect_ranking",
    "gap_accuracy",
    "gap_benchmark",
    "transfer_benchmark",
]


def caption(stem: str, summary: dict) -> tuple[str, str]:
    """(thesis figure it repeats or '', what the figure shows) for a figure file of a run."""
    protocol = summary.get("protocol") or {}
    reps = protocol.get("repetitions") or protocol.get("runs")
    over = f" over {reps} repetitions" if reps else ""
    if stem == "accuracy_vs_k":
        found = experiment(summary) if summary.get("kind") == "transfer" else None
        return (
            found[2] if found else "Figures 5.5/5.6",
            f"Target test accuracy (%) against the number of target fault samples k in the training set: "
            f"mean{over}, band ± one standard deviation; solid lines supervised, dashed unsupervised.",
        )
    if stem == "confusion_k0":
        return (
            "Figure 5.8",
            f"Confusion matrices at k = {min(protocol.get('ks') or [0])}, summed{over} (counts of "
            "target test samples; rows: true class, columns: predicted class).",
        )
    if stem.startswith("signals_"):
        return (
            "Figures 2.34-2.39",
            f"Dataset {stem[len('signals_') :]}: a revolution per class at low, middle and "
            "top intensity (standardised acceleration against input-shaft angle, deg) and its order "
            "spectrum (amplitude against shaft order).",
        )
    return CAPTIONS.get(stem, ("", stem.replace("_", " ") + "."))


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
    # a kind may write several tables, separated by blank lines (the gap kind: per-view gap,
    # effect ranking, accuracy); each is rendered on its own, numbered and titled
    if text.strip():
        parts.append("<h2>Tables</h2>")
    for i, (title, block) in enumerate(table_blocks(text), start=1):
        if summary.get("kind") == "transfer" and i == 1 and not title:
            title = "Target test accuracy (%), mean ± std over the repetitions, in the layout of thesis Table 5.4" + (
                "; reference rows in italics: the thesis's values" if "(thesis" in block else ""
            )
        if not block:  # a paragraph after the last table
            parts.append(f"<p>{html.escape(title)}</p>")
            continue
        titled = f"<caption><b>Table {i}.</b> {html.escape(title or header_title(block))}</caption>"
        parts.append(markdown_table(block).replace("<table>", f"<table>{titled}", 1))
    figures = run.figures.files("*.png")
    figures.sort(key=lambda f: ORDER.index(f.stem) if f.stem in ORDER else len(ORDER))  # the thesis's order
    if figures:
        parts.append("<h2>Figures</h2>")
    for i, fig in enumerate(figures, start=1):
        data = base64.b64encode(fig.read_bytes()).decode()
        thesis, text = caption(fig.stem, summary)
        label = f"Figure {i}" + (f" (as thesis {thesis})" if thesis else "")
        parts.append(
            f"<figure id='{html.escape(fig.stem)}'><img alt='{html.escape(label)}' "
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
