"""A report.html checked in a real browser (issue 41): headless Chromium from the Debian packages,
the network cut off, each report drawn in a tab of its own that gives the page it drew and a
screenshot, several reports by one Chromium (driven over its DevTools pipe: check_reports). Each
kind's test that makes a run calls check_report on its report; without Chromium the check is
skipped (apt-get install chromium to run it)."""

from __future__ import annotations

import base64
import fcntl
import json
import os
import re
import select
import shutil
import subprocess
import tempfile
import time
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
    """check_reports of one report: the page Chromium drew."""
    return check_reports([(report, work)])[0]


def check_reports(reports: list[tuple[Path, Path]]) -> list[str]:
    """Each (report, work folder) checked (check_one) by one Chromium, ended after the last: a start
    per report was 1.1 s of CPU, and a Chromium kept for later ones idles at 1.2 s of CPU a minute."""
    browser = Chromium()
    try:
        return [check_one(report, work, browser) for report, work in reports]
    finally:
        browser.close()


def check_one(report: Path, work: Path, browser: Chromium) -> str:
    """*report* (a run's report.html) as a reader gets it, drawn by *browser* in a 1000-pixel-wide
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
    dom, png = browser.draw(page.as_uri())
    shot.write_bytes(png)
    found = re.search(r'<pre id="layout-check">([^<]*)</pre>', dom)
    assert found, report
    assert found.group(1) == "layout ok", (report, found.group(1))
    assert "<figcaption>" in dom and dom.count("<img") == html.count("<img"), report
    assert '<section id="verdict">' in dom, report
    assert shot.stat().st_size > 10_000, report
    return dom


DRAWN_S = 60.0  # s a report may take to load and draw (a hung Chromium fails the test, not the suite)


class Chromium:
    """One headless Chromium (a 1000 x 1400 window, the network cut off: every request goes to a closed
    port but the page's own file) driven over --remote-debugging-pipe: commands on its fd 3, answers on
    its fd 4, each a JSON message ended by a NUL."""

    def __init__(self):
        self.profile = tempfile.mkdtemp(prefix="gearlab-chromium-")
        to_child, self.commands = os.pipe()
        self.answers, from_child = os.pipe()

        def as_fds_3_and_4():
            # through copies above both: either end may itself be fd 3 or 4
            high = [fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (to_child, from_child)]
            os.dup2(high[0], 3)
            os.dup2(high[1], 4)

        self.process = subprocess.Popen(
            [
                chromium(),
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--window-size=1000,1400",
                "--remote-debugging-pipe",
                "--proxy-server=127.0.0.1:9",
                "--proxy-bypass-list=<-loopback>",
                f"--user-data-dir={self.profile}",
                "about:blank",
            ],
            preexec_fn=as_fds_3_and_4,
            pass_fds=(3, 4),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(to_child)
        os.close(from_child)
        self.sent, self.unread = 0, b""

    def _message(self, deadline: float) -> dict:
        while b"\0" not in self.unread:
            ready, _, _ = select.select([self.answers], [], [], max(0.0, deadline - time.monotonic()))
            chunk = os.read(self.answers, 1 << 20) if ready else b""
            assert chunk, "Chromium stopped answering" if ready else "Chromium did not draw the report in time"
            self.unread += chunk
        message, self.unread = self.unread.split(b"\0", 1)
        return json.loads(message)

    def call(self, method: str, deadline: float, session: str | None = None, **params) -> dict:
        self.sent += 1
        command = {"id": self.sent, "method": method, "params": params, **({"sessionId": session} if session else {})}
        os.write(self.commands, json.dumps(command).encode() + b"\0")
        while (answer := self._message(deadline)).get("id") != self.sent:  # events in between: not needed
            pass
        assert "error" not in answer, (method, answer["error"])
        return answer["result"]

    def draw(self, url: str) -> tuple[str, bytes]:
        """(the page Chromium drew at *url*, in a fresh tab, once its load handlers ran; its screenshot)."""
        deadline = time.monotonic() + DRAWN_S
        tab = self.call("Target.createTarget", deadline, url="about:blank")["targetId"]
        try:
            session = self.call("Target.attachToTarget", deadline, targetId=tab, flatten=True)["sessionId"]
            self.call("Page.navigate", deadline, session, url=url)
            loaded = "document.readyState === 'complete' && document.getElementById('layout-check') !== null"
            while not self.call("Runtime.evaluate", deadline, session, expression=loaded)["result"]["value"]:
                assert time.monotonic() < deadline, f"{url} did not finish loading in {DRAWN_S:.0f} s"
                time.sleep(0.02)
            dom = self.call("Runtime.evaluate", deadline, session, expression="document.documentElement.outerHTML")
            shot = self.call("Page.captureScreenshot", deadline, session)["data"]
        finally:
            self.call("Target.closeTarget", deadline, targetId=tab)
        return dom["result"]["value"], base64.b64decode(shot)

    def close(self) -> None:
        self.process.kill()
        self.process.wait()
        os.close(self.commands)
        os.close(self.answers)
        shutil.rmtree(self.profile, ignore_errors=True)
