"""`gearlab inspect --report DIR`: what the terminal shows of a recording (gearlab.inspect.render,
gearlab.inspect_history.render_localisation), as DIR/report.html with its figures as PNGs beside it:
the order spectrum with the description's mesh orders marked, and with --history the strongest
non-synchronous envelope lines against the history's threshold."""

from __future__ import annotations

import json
import sys
from html import escape
from pathlib import Path

import numpy as np

from .confined import write_file
from .signals.checks import fmt_hz

STYLE = "body{font-family:sans-serif;max-width:70em}table{border-collapse:collapse}"
STYLE += "td,th{border:1px solid #bbb;padding:2px 6px}"


def _table(title: str, head: tuple[str, ...], rows: list[tuple]) -> str:
    cells = "".join(f"<th>{escape(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{escape(str(c))}</td>" for c in row) + "</tr>" for row in rows)
    return f"<h3>{escape(title)}</h3><table><tr>{cells}</tr>{body}</table>"


def _f(x, fmt: str) -> str:
    return "-" if x is None else format(x, fmt)


def spectrum_png(report: dict, path: Path) -> Path:
    """The order spectrum (dB) to the third mesh harmonic or the strongest lines, the mesh orders marked."""
    from .plots import plt, save

    orders, amp = report["spectrum"]
    marks = [s["expected_order"] for s in report.get("check", {}).get("stages", [])]
    top = report["max_order"]
    if marks:
        top = min(top, max(3.3 * max(marks), 1.1 * max((x["order"] for x in report["lines"][:5]), default=0.0)))
    keep = (orders > 0) & (orders <= top)
    fig, ax = plt.subplots(figsize=(9, 3.5))
    ax.plot(orders[keep], 20 * np.log10(np.maximum(amp[keep], 1e-12)), lw=0.7)
    for m in marks:
        ax.axvline(m, color="red", lw=0.8, ls="--")
    ax.set_xlabel("input-shaft order")
    ax.set_ylabel("amplitude (dB)")
    ax.set_title("order spectrum" + ("; red: the description's mesh orders" if marks else ""))
    return save(fig, path)


def nonsync_png(ns: dict, path: Path) -> Path:
    """The strongest non-synchronous envelope lines' z against the history's threshold."""
    from .plots import plt, save

    fig, ax = plt.subplots(figsize=(9, 3))
    x, z = [line["order"] for line in ns["lines"]], [line["z"] for line in ns["lines"]]
    ax.stem(x, z)
    ax.axhline(ns["threshold"], color="red", lw=0.8, ls="--", label=f"threshold z {ns['threshold']:.2f}")
    ax.set_xlabel("input order of the envelope line")
    ax.set_ylabel("z against the history")
    ax.set_title("non-synchronous envelope lines (the record less every shaft's synchronous average)")
    ax.legend()
    return save(fig, path)


def _localisation(loc: dict, folder: Path) -> str:
    rows = []
    for s in loc["shafts"]:
        found = [v for k, v in s["tooth"].items() if k != "angle_deg"]
        teeth = "; ".join(f"{v['tooth']} of {v['of']} ({v['pitches']:.1f})" for v in found) or "-"
        rows.append((s["shaft"], ", ".join(s["gears"]), f"{s['z']:.2f}", f"{s['threshold']:.2f}", s["flagged"], teeth))
    out = _table(
        "which gear: localised change per shaft (against the history)",
        ("shaft", "gears", "z", "threshold", "flagged", "tooth (peak, pitches)"),
        rows,
    )
    out += f"<p>{escape(loc['method'])}</p><p><b>{escape(loc['summary'])}</b></p>"
    ns = loc["nonsync"]
    if "lines" in ns:
        title = f"non-synchronous envelope lines against the history's (threshold z {ns['threshold']:.2f}; "
        title += f"strike order {ns['order']:.2f}, {ns['hz']:.4g} Hz)"
        rows = [(f"{x['order']:.2f}", f"{x['hz']:.4g}", f"{x['z']:.2f}", x["z"] > ns["threshold"]) for x in ns["lines"]]
        out += _table(title, ("input order", "Hz", "z", "over the threshold"), rows)
        out += f'<img src="{nonsync_png(ns, folder / "nonsync_lines.png").name}" alt="{escape(title)}">'
    else:
        out += f"<p>non-synchronous: {escape(ns['note'])}</p>"
    return out + f"<p><b>call: {escape(loc['call'])}</b></p>"


def _unexplained(check: dict, f0: float) -> str:
    """The lines the description does not explain, in the terminal's words (gearlab.inspect's), or that none were."""
    from .inspect import _unexplained_words

    title = "<h3>lines the description does not explain</h3>"
    if not check["unexplained"]:
        return title + "<p>none found</p>"
    items = "".join(f"<li>{escape(_unexplained_words(u, f0))}</li>" for u in check["unexplained"])
    return title + f"<ul>{items}</ul>"


def write_report(report: dict, folder: Path) -> Path:
    """DIR/report.html (and its PNGs) of an inspect report (gearlab.inspect.inspect_record, with its
    'localisation' where read against a history)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    sp, check = report["speed"], report.get("check", {})
    parts = [
        f"<h1>{escape(report['file'])}</h1>",
        f"<p>{escape(report['format'])}: {report['samples']} samples at {escape(fmt_hz(report['fs_hz']))} "
        f"({escape(report['fs_source'])}), {report['duration_s']:.4g} s; channels: "
        f"{escape(', '.join(map(str, report['channels'])))}; vibration {escape(repr(report['vibration']))}; "
        f"values: {escape(report['units'])}</p>",
        f"<p>speed {sp['mean_hz']:.5g} Hz ({sp['mean_hz'] * 60:.5g} rpm) {escape(sp['source'])}; "
        f"{sp['min_hz']:.5g} .. {sp['max_hz']:.5g} Hz; {report['revolutions']} input revolutions</p>",
    ]
    parts += [f"<p>note: {escape(report['file'])}: {escape(w)}</p>" for w in report.get("left_out", ())]
    parts += [
        f"<p>note: vibration {escape(repr(report['vibration']))}: {escape(c)}</p>" for c in report.get("flaws", ())
    ]
    if "verdict" in report:
        parts.append(f"<p><b>{escape(report['verdict'])}</b></p>")
    if report.get("axis"):  # a triaxial sensor read on its axial axis
        parts.append(f"<p>note: {escape(report['axis']['line'])}</p>")
    parts.append(f'<img src="{spectrum_png(report, folder / "order_spectrum.png").name}" alt="order spectrum">')
    if check:
        rows = [
            (s["stage"], f"{s['z1']}/{s['z2']}", f"{s['expected_order']:.4f}", _f(s.get("measured_order"), ".4f"))
            + (_f(s.get("error_orders"), "+.4f"), "ok" if s["matched"] else "differs")
            for s in check["stages"]
        ]
        parts.append(_table("mesh orders", ("stage", "z1/z2", "expected", "measured", "error", "status"), rows))
        parts.append(_unexplained(check, sp["mean_hz"]))
    tsa = [(s["shaft"], s["revolutions"], _f(s.get("rms"), ".4g"), s.get("note", "")) for s in report["tsa"]]
    parts.append(_table("time-synchronous average per shaft", ("shaft", "revolutions", "TSA rms", "note"), tsa))
    if "localisation" in report:
        parts.append(_localisation(report["localisation"], folder))
    html = f"<!doctype html><html><head><meta charset='utf-8'><title>inspect</title><style>{STYLE}</style></head>"
    write_file(folder / "report.html", html + "<body>" + "".join(parts) + "</body></html>")
    return folder / "report.html"


def json_ready(report: dict) -> dict:
    """The report without its arrays (the spectrum, the TSA curves): what --json prints."""
    out = {k: v for k, v in report.items() if k != "spectrum"}
    out["tsa"] = [{k: v for k, v in t.items() if k != "tsa"} for t in report["tsa"]]
    return out


def show(report: dict, console, as_json: bool = False, folder: Path | None = None) -> None:
    """`gearlab inspect`'s output: the terminal view (or JSON on stdout), and DIR/report.html where asked."""
    from .inspect import render
    from .inspect_history import render_localisation

    written = None if folder is None else write_report(report, folder)
    if as_json:
        sys.stdout.write(json.dumps(json_ready(report)) + "\n")
        return
    render(report, console)
    if "localisation" in report:
        render_localisation(report["localisation"], console)
    if written:
        console.print(f"report: {written}", markup=False, highlight=False)
