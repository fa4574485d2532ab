"""A report.html checked in a real browser (issue 41): headless Chromium from the Debian packages,
the network cut off, one start per report that both dumps the page it drew and takes a screenshot.
Each kind's test that makes a run calls check_report on its report; without Chromium the check is
skipped (apt-get install chromium to run it)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest


def chromium() -> str | None:
    return next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome") if shutil.which(n)), None)


needs_chromium = pytest.mark.skipif(
    chromium() is None, reason="no Chromium installed (apt-get install chromium to run this check)"
)

# Run in the page once it has loaded: the layout basics, written into the page for --dump-dom.
LAYOUT_CHECK = """<script>addEventListener('load', () => {
  const width = document.documentElement.clientWidth, problems = [];
  for (const e of document.querySelectorAll('body *')) {
    const box = e.getBoundingClientRect();
    const inside = e.parentElement.closest('details, .scroll');  // folded, or scrolling in a box that fits
    if (box.width && box.right > width + 1 && !inside) problems.push('wider than the page: ' + e.tagName);
  }
  document.querySelectorAll('table').forEach((t, i) => {
    const c = t.querySelector('caption');
    if (!c || !c.textContent.trim()) problems.push('table ' + (i + 1) + ' has no caption');
  });
  document.querySelectorAll('img').forEach((img, i) => {
    if (!img.alt) problems.push('figure ' + (i + 1) + ' has no alt text');
    const f = img.closest('figure');
    if (!f || !f.querySelector('figcaption')) problems.push('figure ' + (i + 1) + ' has no caption');
    if (!img.naturalWidth) problems.push('figure ' + (i + 1) + ' does not decode');
  });
  const out = document.createElement('pre');
  out.id = 'layout-check';
  out.textContent = problems.length ? problems.join('; ') : 'layout ok';
  document.body.appendChild(out);
});</script>"""


def check_report(report: Path, work: Path) -> str:
    """*report* (a run's report.html) as a reader gets it, drawn by Chromium in a 1000-pixel-wide
    window with the network cut off: it fetches nothing outside itself; the verdict opens it,
    before any table; every table has a numbered caption; at least one
    figure, every one with an alt text and a caption, every image decodes; no element (the
    folded scenario and summary, a table in its scrolling box aside) is wider than the page;
    the screenshot is a drawn page. Returns the page Chromium drew."""
    html = report.read_text()
    assert not re.search(r"""(src|href)=['"]?(https?:)?//""", html), report
    assert html.count("<table><caption><b>Table ") == html.count("<table>"), report
    assert "<img" in html, report
    assert "<section id='verdict'>" in html, report
    assert "<table>" not in html or html.index("<section id='verdict'>") < html.index("<table>"), report
    work.mkdir(parents=True, exist_ok=True)
    page, shot = work / "report.html", work / "report.png"
    page.write_text(html.replace("</body>", LAYOUT_CHECK + "</body>"))
    done = subprocess.run(
        [
            chromium(),
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--window-size=1000,1400",
            "--virtual-time-budget=5000",
            "--dump-dom",
            f"--screenshot={shot}",
            "--proxy-server=127.0.0.1:9",
            "--proxy-bypass-list=<-loopback>",
            f"--user-data-dir={work / 'profile'}",
            page.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    dom = done.stdout
    found = re.search(r'<pre id="layout-check">([^<]*)</pre>', dom)
    assert found, (report, done.stderr[-2000:])
    assert found.group(1) == "layout ok", (report, found.group(1))
    assert "<figcaption>" in dom and dom.count("<img") == html.count("<img"), report
    assert '<section id="verdict">' in dom, report
    assert shot.stat().st_size > 10_000, report
    return dom
