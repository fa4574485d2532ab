"""Issue 41: run metadata in run.json, no stale lock, `gearlab runs`, the end of a run in the
terminal (verdict, rich tables), progress with rate and ETA, the CLI's conventions (-h,
metavars, completion, gap --device) and unit messages that quote the user's text."""

import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT
from rich.console import Console

from gearlab.errors import GearlabInputError
from gearlab.events import Event
from gearlab.runs import LOCK_FILE, RunDir

STIFFNESS = ROOT / "scenarios" / "stiffness_verification.toml"


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A quick stiffness run made through the CLI (a few seconds)."""
    base = tmp_path_factory.mktemp("runinfo")
    done = subprocess.run(
        [sys.executable, "-m", "gearlab", "run", str(STIFFNESS), "--quick", "--out", str(base / "runs")],
        capture_output=True,
        text=True,
        cwd=base,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return base, Path(done.stdout.strip().splitlines()[-1].split(": ", 1)[1]), done


def test_run_json_says_who_ran_what_where_and_when(finished):
    base, run, done = finished
    run = base / run
    meta = json.loads((run / "run.json").read_text())
    assert meta["status"] == "finished" and meta["quick"] is True
    assert meta["command"].startswith("gearlab run ") and "--quick" in meta["command"]
    assert meta["gearlab_version"] and meta["host"] and meta["python"]
    assert meta["started"] <= meta["ended"] and 0 < meta["duration_s"] < 300
    assert meta["execution"] == {"executor": "local", "device": "auto"}
    assert meta["git"] is None or re.fullmatch(r"[0-9a-f]{40}", meta["git"]["revision"])
    assert [s["status"] for s in meta["sessions"]] == ["finished"]
    assert "pid" not in meta  # a finished run holds no process
    assert not (run / LOCK_FILE).exists()  # no stale lock


def test_a_resume_adds_a_session_and_sums_the_working_time(finished, cli, tmp_path, unrendered_figures):
    import shutil

    base, run, _ = finished
    copy = tmp_path / "copy"
    shutil.copytree(base / run, copy)
    lines = (copy / "results.jsonl").read_text().splitlines(keepends=True)
    (copy / "results.jsonl").write_text("".join(lines[:-1]))
    code, out, err = cli("run", "--resume", copy)
    assert code == 0, err
    meta = json.loads((copy / "run.json").read_text())
    first, second = meta["sessions"]
    assert second["command"].startswith("gearlab run --resume") and second["status"] == "finished"
    assert meta["started"] == first["started"] and meta["duration_s"] == pytest.approx(
        first["duration_s"] + second["duration_s"], abs=0.01
    )
    assert not (copy / LOCK_FILE).exists()


def test_the_end_of_a_run_prints_the_report_then_the_run_directory_last(finished):
    _, run, done = finished
    lines = done.stdout.strip().splitlines()
    assert lines[-1] == f"run directory: {run}"
    assert lines[-2] == f"report: {run / 'report.html'}"
    assert any(line.startswith("healthy TVMS: mean") for line in lines)
    # off a terminal: a line per tenth of a stage, with its rate and ETA, and its end
    assert re.search(r"^14 TVMS cases on luo2019: \d+/14, [\d.:]+/(s|step), ETA \d+:\d\d$", done.stderr, re.M)
    assert re.search(r"^14 TVMS cases on luo2019: 14/14, done$", done.stderr, re.M)


def test_gearlab_runs_lists_past_runs(finished, cli):
    base, run, _ = finished
    code, out, err = cli("runs", base / "runs", "--json")
    assert code == 0, err
    (found,) = json.loads(out)
    assert found["name"] == "stiffness_verification" and found["kind"] == "stiffness"
    assert (
        found["status"] == "finished"
        and found["duration_s"] > 0
        and found["headline"].startswith("Healthy TVMS of luo2019: mean")
    )
    assert Path(found["path"]) == base / run
    code, out, err = cli("runs", base / "runs")
    assert code == 0 and "stiffness_verification" in out and "finished" in out
    code, _, err = cli("runs", base / "nowhere")
    assert code == 2 and "no such folder of runs" in err


def test_runs_tells_a_killed_run_a_cancelled_one_and_a_damaged_one(finished, tmp_path):
    import shutil

    from gearlab.runinfo import list_runs

    base, run, _ = finished
    for name, status in (("killed", "running"), ("cancelled", "cancelled")):
        copy = tmp_path / "runs" / "s" / name
        shutil.copytree(base / run, copy)
        meta = json.loads((copy / "run.json").read_text())
        dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
        meta.update(status=status, pid=int(dead.stdout))  # a process that has ended
        (copy / "run.json").write_text(json.dumps(meta))
        (copy / LOCK_FILE).write_text(dead.stdout)
    (tmp_path / "runs" / "s" / "damaged").mkdir()
    (tmp_path / "runs" / "s" / "damaged" / "scenario.toml").write_text("")
    (tmp_path / "runs" / "s" / "damaged" / "run.json").write_text("not json")
    found = {r.path.name: r for r in list_runs(tmp_path / "runs")}
    assert found["killed"].status == "stopped" and found["cancelled"].status == "cancelled"
    assert found["damaged"].status == "damaged" and "run.json: damaged" in found["damaged"].problem


def test_cancelled_and_failed_runs_say_so_in_run_json(tmp_path, monkeypatch):
    from gearlab.engine import run_scenario
    from gearlab.kinds import stiffness

    real = stiffness.run

    def interrupted(scenario, run, on_event):
        run.append({"unit": "x"})  # a finished unit: the run is kept
        raise KeyboardInterrupt

    monkeypatch.setattr(stiffness, "run", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_scenario(STIFFNESS, out=tmp_path / "runs", quick=True)
    (run,) = (tmp_path / "runs" / "stiffness_verification").iterdir()
    meta = json.loads((run / "run.json").read_text())
    assert meta["status"] == "cancelled" and not (run / LOCK_FILE).exists()
    monkeypatch.setattr(stiffness, "run", real)


def test_the_lock_file_goes_with_the_run_and_a_stale_one_is_taken_over(tmp_path):
    run = RunDir(tmp_path)
    first = run.lock()
    with pytest.raises(GearlabInputError, match="another gearlab process"):
        run.lock()
    first.release()
    assert not (tmp_path / LOCK_FILE).exists()
    (tmp_path / LOCK_FILE).write_text("123\n")  # left by a killed run: taken over
    with run.lock():
        assert (tmp_path / LOCK_FILE).read_text() == f"{os.getpid()}\n"
    assert not (tmp_path / LOCK_FILE).exists()


def test_a_lock_file_removed_under_a_waiting_process_is_locked_afresh(tmp_path, monkeypatch):
    """Process B opened .lock, then A (ending) removed it: B's flock lands on a file no longer
    named .lock; B must see that and lock the name again, or a third process could hold the
    new file while B holds the old one."""
    from gearlab import confined

    run = RunDir(tmp_path)
    stale = tmp_path / "old"
    stale.write_text("")
    real = confined.Confined.open_own
    calls = []

    def open_own(self, flags):
        calls.append(self.name)
        if len(calls) == 1:  # the first open finds the file A is about to remove
            fd = os.open(stale, os.O_RDWR)
            os.unlink(stale)
            return fd
        return real(self, flags)

    monkeypatch.setattr(confined.Confined, "open_own", open_own)
    with run.lock() as held:
        assert len(calls) == 2 and os.fstat(held.fd).st_ino == (tmp_path / LOCK_FILE).stat().st_ino


def test_scenario_differences(tmp_path):
    from gearlab.runinfo import scenario_differences

    for name, points in (("a", 64), ("b", 128)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "scenario.toml").write_text(
            f'[scenario]\nname = "{name}"\nkind = "stiffness"\n[stiffness]\npoints = {points}\n'
            + ("[execution]\nworkers = 2\n" if name == "b" else "")
        )
    rows = dict(scenario_differences([tmp_path / "a", tmp_path / "b"]))
    assert rows == {"execution.workers": ["-", "2"], "stiffness.points": ["64", "128"]}


# ----------------------------------------------------------------------------- the terminal


def test_pace_gives_rate_and_eta_after_the_first_step():
    from gearlab.terminal import Pace, clock

    pace = Pace(done=2, now=0.0)  # a resumed stage: 2 done before
    assert pace.rate(now=5.0) is None and pace.left(10, now=5.0) is None
    pace.update(4)
    assert pace.rate(now=10.0) == pytest.approx(0.2) and pace.left(10, now=10.0) == pytest.approx(30.0)
    assert pace.rate_text(now=10.0) == "0:05/step"
    assert clock(3725) == "1:02:05" and clock(65) == "1:05" and clock(None) == "-:--"


def test_progress_bars_show_counts_rate_eta_and_the_unit_in_progress():
    from gearlab.terminal import ProgressView

    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=140, color_system=None)
    with ProgressView(console) as view:
        view.handle(Event("stage", stage="runs", total=4, message="4 training runs"))
        view.handle(Event("unit", stage="rep0/k0/mmd", message="epoch 3, source validation accuracy 80 %"))
        view.progress.refresh()
        assert "ETA after the first step" in out.getvalue() and "rep0/k0/mmd: epoch 3" in out.getvalue()
        view.handle(Event("advance", stage="runs", done=1, total=4))
        view.progress.refresh()
        assert re.search(r"1/4 .*ETA \d+:\d\d", out.getvalue())
        view.handle(Event("unit", stage="rep0/k0/mmd"))  # it ended: its line goes
        assert not view.units


def test_a_stage_met_again_starts_its_bar_over_instead_of_adding_one():
    """A transfer benchmark's trials each run a diagnosis ('gap before', 'gap round 1', ...): a bar per
    stage name, started over by each trial, not a pile of finished bars from the trials before."""
    from gearlab.terminal import ProgressView

    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=140, color_system=None)
    with ProgressView(console) as view:
        for trial in (1, 2):
            view.handle(Event("stage", stage="gap round 1", total=13, message=f"gap: round 1 of trial {trial}"))
            view.handle(Event("advance", stage="gap round 1", done=13 if trial == 1 else 2, total=13))
        (task,) = view.progress.tasks
        assert (task.description, task.completed, task.total) == ("gap: round 1 of trial 2", 2, 13)
        assert task.fields["pace"] is view.paces["gap round 1"] and task.fields["pace"].done == 2


def test_the_end_of_a_run_prints_the_verdict_and_markdown_tables_as_rich_tables():
    from gearlab.terminal import print_results

    out = io.StringIO()
    console = Console(file=out, width=60, color_system=None)
    table = "| k | mmd | dann |\n|---|---|---|\n| 0 | 97.1 ± 1.0 | 88.0 ± 2.5 |\n| 4 | 98.0 ± 0.5 | 96.2 ± 1.1 |\n"
    print_results(console, ["at k = 0: mmd best by 9.1 points."], ["accuracy [%] (Table 5.4 layout):", table, "done"])
    text = out.getvalue()
    assert text.index("Verdict") < text.index("mmd best") < text.index("accuracy [%] (Table 5.4 layout)")
    assert "┃ k " in text or "│ 0 " in text  # a drawn table, not Markdown
    assert "|---|" not in text and text.rstrip().endswith("done")


def test_a_table_too_narrow_for_its_words_on_a_terminal_is_turned():
    """At 120 columns a transfer run's eight columns cut 'matched_filt|er' and '(unsupervise|d)' (issue
    41): turned, a row per method, every word whole; a wide terminal, a log or a pipe keep the layout."""
    from gearlab.terminal import print_results

    methods = [f"{m} (unsupervised)" for m in ("source_only", "mmd", "dann", "matched_filter", "likelihood_ratio")]
    methods += ["target_only (supervised)", "Bayes bound (target's own shapes and noise law, best threshold)"]
    values = {"0": [f"{50 + i}.00 ± 0.{i}" for i in range(7)], "4": [f"{60 + i}.00 ± 1.{i}" for i in range(7)]}
    table = f"| k (target fault samples) | {' | '.join(methods)} |\n|{'---|' * 8}\n"
    table += "".join(f"| {k} | {' | '.join(v)} |\n" for k, v in values.items())

    def shown(width: int, terminal: bool = True) -> list[str]:
        out = io.StringIO()
        console = Console(file=out, width=width, force_terminal=terminal, color_system=None)
        print_results(console, [], ["accuracy [%] (Table 5.4 layout):", table])
        return out.getvalue().splitlines()

    narrow = shown(120)
    assert max(len(line) for line in narrow) <= 120
    for i, method in enumerate(methods):  # a row: the method whole, its value at each k
        (row,) = [line for line in narrow if f"│ {method} " in line]
        assert values["0"][i] in row and values["4"][i] in row and row.index(values["0"][i]) < row.index(values["4"][i])
    for lines in (shown(400), shown(120, terminal=False)):  # room for every word, or no width at all
        (row,) = [line for line in lines if line.startswith("│ 0 ")]
        assert all(v in row for v in values["0"]), lines


# ----------------------------------------------------------------------------- CLI conventions


def test_dash_h_metavars_and_completion(cli, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    code, out, _ = cli("-h")
    assert code == 0 and "--install-completion" in out and "--show-completion" in out
    commands = re.findall(r"^│ ([a-z][a-z-]+) ", out.split("Commands")[1], flags=re.M)  # every one -h lists
    assert {"run", "gap", "transfer-benchmark", "score", "simulate", "modes", "validate", "tui"} <= set(commands)
    for command in commands:
        code, out, _ = cli(command, "-h")
        assert code == 0, command
        assert "<bool>" not in out and "<list" not in out and "<str>" not in out and "{" not in out, command
        assert not re.search(r"--quick\s+--no-quick\s+\S*[A-Z<]", out), command
    code, out, _ = cli("run", "-h")
    assert "run [OPTIONS] [SCENARIO]" in out and re.search(r"--out\s+PATH", out)
    code, out, _ = cli("compare", "-h")
    assert "compare [OPTIONS] RUN_DIRS..." in out
    code, out, _ = cli("stiffness", "-h")
    assert re.search(r"--fault\s+TEXT", out) and re.search(r"--points\s+INTEGER", out)
    for command in ("gap", "transfer-benchmark"):  # both train networks, as run does
        code, out, _ = cli(command, "-h")
        assert "--device" in out, command
    code, _, err = cli("gap")
    assert code == 2 and "Missing argument 'SCENARIO'" in err
    # the completion itself, as the installed script asks the command (bash's protocol)
    for words, expected in (("gearlab ru", ["run", "runs"]), ("gearlab run --ou", ["--out"])):
        env = {**os.environ, "_GEARLAB_COMPLETE": "complete_bash", "COMP_WORDS": words}
        env["COMP_CWORD"] = str(len(words.split()) - 1)
        script = Path(sys.executable).with_name("gearlab")  # the installed command a shell completes
        done = subprocess.run([script, *words.split()[1:]], env=env, capture_output=True, text=True)
        assert done.returncode == 0 and done.stdout.split() == expected, (words, done.stdout, done.stderr)


def test_gap_takes_device(cli, tmp_path):
    # refused as an [execution] value, so it reached the scenario's table
    code, _, err = cli("gap", ROOT / "scenarios" / "gap_expB.toml", "--device", "tpu", "--out", tmp_path)
    assert code == 2 and "device" in err and "tpu" in err
    code, _, err = cli("transfer-benchmark", "--device", "tpu", "--out", tmp_path)
    assert code == 2 and "device" in err and "tpu" in err


@pytest.mark.parametrize(
    "text, unit, expected",
    [
        ("10 mv/g", None, "cannot read '10 mv/g' as a quantity; expected e.g. '10 mV/g'"),
        ("10 mv/g", None, "units are case-sensitive: mV"),
        ("25 hz", "Hz", "expected e.g. '25 Hz' (Hz); units are case-sensitive: Hz"),
        ("3 MM", "m", "'3 MM' has the wrong dimension; expected a quantity in m, e.g. '3.175 mm'"),
    ],
)
def test_unit_messages_quote_the_users_text_with_a_fitting_example(text, unit, expected):
    from gearlab.data.textzip import parse_sensitivity
    from gearlab.units import to_si

    with pytest.raises(GearlabInputError) as caught:
        parse_sensitivity(text, "--sensitivity") if unit is None else to_si(text, unit, "x")
    assert expected in str(caught.value) and "g_n" not in str(caught.value)


def test_a_tie_is_said_as_a_tie():
    from gearlab.kinds.transfer_verdict import transfer_lines

    table = {
        "a": {"0": {"mean": 97.1, "std": 1.0}, "4": {"mean": 99.0, "std": 1.0}},
        "b": {"0": {"mean": 97.1, "std": 1.0}, "4": {"mean": 90.0, "std": 1.0}},
        "c": {"0": {"mean": 80.0, "std": 1.0}, "4": {"mean": 50.0, "std": 1.0}},
    }
    (line, *_) = transfer_lines({"table": table, "protocol": {"ks": [0, 4]}}, [])
    assert line.startswith("a and b tie at k = 0 (97.10 %), 17.1 points ahead of c; a is best at k = 4")
    two = {"a": {"0": {"mean": 100.0, "std": 0.0}}, "b": {"0": {"mean": 100.0, "std": 0.0}}}
    assert transfer_lines({"table": two, "protocol": {"ks": [0]}}, [])[0] == "a and b tie at k = 0 (100.00 %)."


def test_report_tables_are_titled_by_their_paragraph_or_their_header():
    from gearlab.report import header_title, table_blocks

    text = (
        "| 16 Hz: method | AUC | det % |\n|---|---|---|\n| fm4 | 1.0 | 100 |\n\n"
        "What each learned\n\n| a | b |\n|---|---|\n| 1 | 2 |"
    )
    (t1, b1), (t2, b2) = table_blocks(text)
    assert t1 == "" and header_title(b1) == "AUC, det % per method (16 Hz)"
    assert t2 == "What each learned" and b2.startswith("| a | b |")
