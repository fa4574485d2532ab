"""Outside user AI (issue 39 leftovers): what outside users of the previous stop found left to do."""

from __future__ import annotations

import numpy as np
from gearboxes import description, stage

from gearlab.gearbox import load_gearbox
from gearlab.inspect import InspectOptions
from gearlab.inspect_history import localisation

FS, SPEED = 4096.0, 31.0


def _take(path, seconds: float = 1.5, seed: int = 0) -> str:
    """A 1.5 s take of a 23/59 + 19/67 box at 31 Hz as .npz (m/s²): both meshes modulated by their shafts,
    white noise, a tacho once per input turn."""
    t = np.arange(int(seconds * FS)) / FS
    theta = 2 * np.pi * SPEED * t + seed
    mid = theta * 23 / 59
    x = (1 + 0.2 * np.cos(theta)) * np.cos(23 * theta) + (1 + 0.2 * np.cos(mid)) * 0.6 * np.cos(19 * mid + 0.4)
    x = x + np.random.default_rng(seed).normal(0, 0.05, t.size)
    tacho = np.where(theta % (2 * np.pi) < 0.4, 5.0, 0.0)
    np.savez(path, acc=x, tach=tacho, fs=FS)
    return str(path)


def test_inspect_history_on_short_takes_says_why_not_instead_of_failing(tmp_path):
    # AF's 1.5 s takes of a 23/59 + 19/67 box at 31 Hz (46 input turns, 5.1 output turns each): plain inspect read
    # them, --history exited 2 'error: 22 input revolutions hold 1 complete turns of the output shaft; expected at
    # least 2' (the history's units are half takes under 4 takes). Too few output turns for the which-gear check
    # is said in one phrase, the take itself stays inspected
    (tmp_path / "box.toml").write_text(
        description(stage(23, 59), stage(19, 67, module="3 mm"), speed="31 Hz", near="input", tacho="input")
    )
    box = load_gearbox(tmp_path / "box.toml")
    history = [_take(tmp_path / f"h{i}.npz", seed=i) for i in (1, 2, 3)]
    loc = localisation(_take(tmp_path / "r.npz", seed=7), history, box, InspectOptions("acc", "tach"))
    assert loc["named"] is None and loc["shafts"] == [], loc
    assert loc["summary"].startswith("not localised: the history's takes: too short for the which-gear check: 4.97"), (
        loc["summary"]
    )
    assert "output-shaft turns (45 input revolutions), it needs 8" in loc["summary"], loc["summary"]
    assert loc["call"].startswith("not read against the history:"), loc["call"]
    assert "\n" not in loc["call"]
    # takes of 9 output turns are read, the output shaft's evidence with the others'
    history = [_take(tmp_path / f"l{i}.npz", seconds=2.7, seed=i) for i in (1, 2, 3)]
    loc = localisation(_take(tmp_path / "lr.npz", seconds=2.7, seed=7), history, box, InspectOptions("acc", "tach"))
    assert [s["shaft"] for s in loc["shafts"]] and "output" in [s["shaft"] for s in loc["shafts"]], loc["summary"]


def test_a_detection_run_s_table_md_opens_with_its_verdict(cli, tmp_path, no_figures):
    # docs/your_gearbox.md step 6: 'report.html and table.md of the run directory ... open with the verdict: which
    # methods meet the goal'. table.md opened with the first condition's AUC table; the verdict was in report.html,
    # the terminal and the TUI only. report.html says it once (its own Verdict section), not again over a table
    from test_detection import run, scenario

    from gearlab.report import build_report
    from gearlab.verdict import verdict_lines

    out = run(cli, scenario(tmp_path, methods=("matched_filter",)), tmp_path / "runs")
    said = verdict_lines(out)
    assert said and "goal met by" in said[1], said
    table = (out / "table.md").read_text()
    head, rest = table.split("\n\n", 1)
    assert head.splitlines() == [f"Verdict: {said[0]}", *(f"- {line}" for line in said[1:])], head
    assert rest.startswith("Condition "), rest[:80]
    html = build_report(out)
    assert html.count(said[1].split(":")[0] + ": goal met by") == 1, "the verdict twice in report.html"
