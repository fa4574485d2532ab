"""An outside user's report (issue 39 item 3; helper L): `gearlab inspect --report DIR` wrote no list of the lines the
description does not explain, which the terminal prints; a reader of report.html missed a 50 Hz mains hum. The report
now lists them in the terminal's words, or says none were found. The recordings are made here, small, by plain numpy
(in the style of tests/test_outside_k.py)."""

from __future__ import annotations

import re
from html import unescape

import numpy as np
from gearboxes import description, stage

BOX_A = description(stage(73, 31, bores=("30 mm", "20 mm")), name="boxA", speed="20 Hz", near="input", tacho="input")


def _steady_csv(path, hum=0.0, seconds=6.0, fs=12800.0):
    """A 31/73 box driven from its 73T wheel at a steady 20 Hz, the mesh modulated at the output shaft's rate; a time
    column 'time_s', an accelerometer in g with a DC offset, a 1-mark tacho on the input shaft; a mains hum of *hum* g
    at 50 Hz (order 2.5: no shaft's harmonic). Without the hum no line is left unexplained (the speed does not swing,
    so the mesh has no skirt)."""
    rng = np.random.default_rng(7)
    t = np.arange(int(fs * seconds)) / fs
    th = 2 * np.pi * 20.0 * t
    x = (1 + 0.1 * np.cos(th * 73 / 31)) * np.cos(73 * th) + 0.5 * np.cos(146 * th) + rng.normal(0, 0.05, t.size)
    x = x + hum * np.sin(2 * np.pi * 50.0 * t + 0.3) + 0.05
    rows = np.column_stack([t, x, np.where(th / 2 / np.pi % 1 < 0.06, 5, 0)])
    path.write_text("time_s,acc [g],tacho [V]\n" + "%.7f,%.5f,%.1f\n" * len(rows) % tuple(rows.ravel().tolist()))
    return path


def _report(cli, tmp_path, hum):
    """(the terminal's words, report.html's text) of `gearlab inspect --report` on a take with *hum* g of hum."""
    (tmp_path / "boxA.toml").write_text(BOX_A)
    take = _steady_csv(tmp_path / f"take{hum}.csv", hum)
    args = ("--gearbox", tmp_path / "boxA.toml", "--vibration", "acc [g]", "--tacho", "tacho [V]")
    code, stdout, err = cli("inspect", take, *args, "--report", tmp_path / f"report{hum}")
    assert code == 0, err
    said = " ".join(stdout.split())
    assert "matches this recording" in said, said[-1500:]
    html = (tmp_path / f"report{hum}" / "report.html").read_text()
    return said, " ".join(unescape(re.sub(r"<[^>]+>", " ", html)).split())


def test_report_html_lists_the_hum_as_the_terminal_does(cli, tmp_path):
    said, page = _report(cli, tmp_path, hum=0.02)
    listed = said.split("lines the description does not explain: ")[-1].split(" time-synchronous")[0]
    assert listed.count("not a gear order") == 1, said[-1500:]
    hum = re.search(r"[\d.]+ Hz \(input order 2\.5, no shaft's harmonic: not a gear order [^)]*\); \d+ dB\)", listed)
    assert hum, listed
    section = page.split("lines the description does not explain")[-1].split("time-synchronous average")[0]
    assert hum.group(0) in section, page[-2000:]  # the same words and values as the terminal's
    assert "none found" not in section


def test_report_html_says_none_where_no_line_is_unexplained(cli, tmp_path):
    said, page = _report(cli, tmp_path, hum=0.0)
    assert "lines the description does not explain" not in said, said[-1500:]
    section = page.split("lines the description does not explain")[-1].split("time-synchronous average")[0]
    assert section.strip() == "none found", page[-2000:]
