"""One self-contained report.html per run: tables and figures inlined, nothing to fetch."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path


def _markdown_table(text: str) -> str:
    rows = [r.strip().strip("|").split("|") for r in text.strip().splitlines() if r.strip()]
    rows = [r for r in rows if not all(set(c.strip()) <= set("-:") for c in r)]
    if not rows:
        return ""
    head, body = rows[0], rows[1:]
    out = ["<table><thead><tr>", *(f"<th>{html.escape(c.strip())}</th>" for c in head), "</tr></thead><tbody>"]
    for r in body:
        out += ["<tr>", *(f"<td>{html.escape(c.strip())}</td>" for c in r), "</tr>"]
    out.append("</tbody></table>")
    return "".join(out)


def build_report(run_path: Path) -> str:
    run_path = Path(run_path)
    summary_file = run_path / "summary.json"
    summary = json.loads(summary_file.read_text()) if summary_file.exists() else {}
    title = f"gearlab run: {summary.get('scenario', run_path.parent.name)} ({summary.get('kind', '?')})"
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'>",
        f"<title>{html.escape(title)}</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
        "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
        "th{background:#eee}img{max-width:100%;border:1px solid #ddd;margin:0.5em 0}pre{background:#f6f6f6;padding:1em}"
        "</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        f"<p>Run directory: <code>{html.escape(str(run_path))}</code></p>",
    ]
    table = run_path / "table.md"
    if table.exists() and table.read_text().strip():
        # a kind may write several tables, separated by blank lines (the gap kind: per-view gap,
        # effect ranking, accuracy); each is rendered on its own
        blocks = [b for b in table.read_text().split("\n\n") if b.strip()]
        parts += ["<h2>Table</h2>" if len(blocks) == 1 else "<h2>Tables</h2>", *map(_markdown_table, blocks)]
    figures = sorted((run_path / "figures").glob("*.png")) if (run_path / "figures").exists() else []
    if figures:
        parts.append("<h2>Figures</h2>")
    for fig in figures:
        data = base64.b64encode(fig.read_bytes()).decode()
        parts += [f"<h3>{html.escape(fig.stem)}</h3>", f"<img alt='{html.escape(fig.stem)}' src='data:image/png;base64,{data}'>"]
    scenario = run_path / "scenario.toml"
    if scenario.exists():
        parts += ["<h2>Resolved scenario</h2>", f"<pre>{html.escape(scenario.read_text())}</pre>"]
    if summary:
        brief = {k: v for k, v in summary.items() if k not in ("cases",)}
        parts += ["<h2>Summary</h2>", f"<pre>{html.escape(json.dumps(brief, indent=1)[:20000])}</pre>"]
    parts.append("</body></html>")
    return "\n".join(parts)
