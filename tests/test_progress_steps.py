"""No stage silent for more than 5 s, every bar with an ETA after its first step (issue 41): the
report stage counts i of n, a unit's line that stands says for how long, the Bayes bound and the
gap's "before" report count their steps, and a tiny run's stages each give a total."""

from __future__ import annotations

import re
import threading
import time
from types import SimpleNamespace

import numpy as np
from tiny import transfer

from gearlab import events as ev
from gearlab.events import REPORT, Event, UnitProgress, figure_written, figures_ahead, telling_figures


def until(condition, what: str) -> None:
    """Wait (real time) until *condition* holds: a minute is a hung thread's bound, not a speed."""
    end = time.monotonic() + 60.0
    while not condition():
        assert time.monotonic() < end, f"waited a minute for {what}"
        time.sleep(0.002)


class Clock:
    """time.monotonic of the *modules* as the test sets it (from 0): the seconds a line says it stood
    are the test's, whatever the machine's speed."""

    def __init__(self, monkeypatch, *modules):
        self.now = 0.0
        fake = SimpleNamespace(**{**vars(time), "monotonic": lambda: self.now})
        for module in modules:
            monkeypatch.setattr(module, "time", fake)


class Looks:
    """The looks of events.standing's keeper, one each time the test asks for one (not one a second of
    real time): what a line says at each look follows the test's steps, never how soon a loaded
    machine wakes a thread."""

    def __init__(self, monkeypatch):
        self.cv = threading.Condition()
        self.asked = self.made = 0
        self.looking = False
        monkeypatch.setattr(ev, "_next_look", self.next)

    def next(self, done: threading.Event) -> bool:  # the keeper thread, before each look
        with self.cv:
            if self.looking:  # the look asked before is made
                self.made, self.looking = self.made + 1, False
                self.cv.notify_all()
            while self.made == self.asked and not done.is_set():
                self.cv.wait(0.01)
            self.looking = not done.is_set()
            return done.is_set()

    def look(self) -> None:
        """One look of the keeper, waited for."""
        with self.cv:
            self.asked += 1
            self.cv.notify_all()
            assert self.cv.wait_for(lambda: self.made >= self.asked, timeout=60.0), "the keeper made no look"


def told(events: list[Event]) -> list[tuple]:
    return [(e.kind, e.done, e.total) for e in events if e.stage == REPORT]


def test_the_report_stage_counts_i_of_n_announced_figures_and_report_html():
    events: list[Event] = []
    with telling_figures(events.append) as finish:
        figures_ahead(2)  # before the first is drawn: the stage starts with its total
        figure_written("a.png")
        figure_written("b.png")
        finish()
    assert told(events) == [("stage", 0, 3), ("advance", 1, 3), ("advance", 2, 3), ("advance", 3, 3)]
    assert events[0].message == "figures and report.html"


def test_figures_announced_in_turns_add_up_and_unannounced_ones_claim_no_total():
    events: list[Event] = []
    with telling_figures(events.append) as finish:
        figures_ahead(1)
        figure_written("a.png")
        figures_ahead(2)  # a second drawing function of the same run
        figure_written("b.png")
        figure_written("c.png")
        finish()
    assert told(events) == [("stage", 0, 2), ("advance", 1, 2), ("advance", 1, 4), ("advance", 2, 4)] + [
        ("advance", 3, 4),
        ("advance", 4, 4),
    ]
    events.clear()
    with telling_figures(events.append) as finish:
        figure_written("a.png")  # a kind that did not say how many: a count, no made-up total
        finish()
    assert told(events) == [("stage", 1, 0), ("advance", 2, 2)]
    events.clear()
    with telling_figures(events.append) as finish:
        finish()  # no figure at all: report.html is the one step
    assert told(events) == [("stage", 0, 0), ("advance", 1, 1)] and events[0].message == "report.html"


def test_a_units_line_that_stands_says_for_how_long(tmp_path, monkeypatch):
    """A step that cannot count (importing torch in a fresh worker: 10 s at load 9) is not silent: its
    line is rewritten each second once it has stood STANDING_S; a report that came too soon after
    the last write is written once its time is up, not dropped."""
    monkeypatch.setattr(ev, "STANDING_S", 0.3)
    clock = Clock(monkeypatch, ev)
    written: list[str] = []
    write = UnitProgress._write
    monkeypatch.setattr(UnitProgress, "_write", lambda self, text: (written.append(text), write(self, text)))
    with UnitProgress(tmp_path, "rep0/k0/mmd-unsup", every=0.05) as progress:
        progress("starting: importing torch")
        progress("starting: reading dataset 1 of 2 (source)")  # within 0.05 s of the last write (the clock stands)
        until(lambda: len(written) >= 2, "the report that came too soon")
        clock.now = 1.0
        until(lambda: len(written) >= 3, "the line that stood 1 s")
    assert written[0] == "starting: importing torch"
    assert written[1] == "starting: reading dataset 1 of 2 (source)"
    standing = [t for t in written[2:] if t.startswith("starting: reading dataset 1 of 2 (source) (")]
    assert {"starting: reading dataset 1 of 2 (source) (1 s)"} <= set(standing), written
    assert not (tmp_path / "progress").exists() or not list((tmp_path / "progress").iterdir())


def test_a_units_line_is_written_unsynced_and_a_result_synced(tmp_path, monkeypatch):
    """Issue 42: a unit's training thread writes its line a few times a second, and each write was
    synced to disk (14 ms on a busy disk): 1.0-1.7 % of a unit's time on 40 ms epochs, 0.4 % unsynced.
    A line of the moment, gone when the unit ends, needs no sync; a result written whole still has one."""
    from gearlab import confined

    synced: list[int] = []
    monkeypatch.setattr(confined.os, "fsync", synced.append)
    with UnitProgress(tmp_path, "rep0/k0/mmd-unsup", every=0.0) as progress:
        for epoch in range(5):
            progress(f"epoch {epoch + 1}")
        assert (tmp_path / "progress" / "rep0__k0__mmd-unsup.txt").read_text() == "epoch 5"
    assert synced == []
    confined.Confined(tmp_path, ("table.md",)).write("a result")
    assert len(synced) == 1


def test_the_gap_report_tells_each_of_its_parts():
    from gearlab.gap.stats import REPORT_PARTS, gap_report

    rng = np.random.default_rng(0)
    source, target = rng.normal(size=(12, 256)), rng.normal(size=(12, 256)) * 1.2
    parts: list[int] = []
    gap_report(source, target, (25, 30), bootstrap=5, permutations=10, on_part=lambda: parts.append(1))
    assert len(parts) == REPORT_PARTS >= 4


def test_a_tiny_runs_stages_each_give_a_total_from_their_first_step(tmp_path, monkeypatch):
    """A tiny transfer run end to end (the datasets simulated, the bound, the training units, the
    figures and report.html): every stage has a total from its first step on (the ETA needs one).
    How long the run is silent is measured, not asserted (a wall-clock limit fails on a loaded
    machine): `gearlab run scenarios/quick.toml --events` prints the times."""
    from gearlab.engine import run_scenario

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "tiny.toml"
    path.write_text(transfer('[[methods]]\nadapter = "source_only"\n\n[[methods]]\nadapter = "mmd"\n', max_epochs=2))
    events: list[Event] = []
    run_scenario(path, out=tmp_path / "runs", on_event=events.append)
    totals: dict[str, int] = {}
    for e in events:
        if e.kind == "stage":
            totals[e.stage] = e.total
        elif e.kind == "advance" and e.done > 0:
            totals[e.stage] = e.total or totals.get(e.stage, 0)
            assert totals[e.stage] > 0, f"stage {e.stage!r}: step {e.done} with no total, so no ETA"
    assert {"datasets", "bound", "runs", REPORT} <= set(totals)


def test_the_bounds_scores_in_tenths_are_its_scores_at_once():
    """The Bayes bound scores the target's revolutions a tenth at a time, a step each
    (gearlab.parts.bound; its events: tests/test_transfer_stages.py): each row's score is its own."""
    from gearlab.learn.bounds import likelihood_ratio

    rng = np.random.default_rng(3)
    X = rng.laplace(size=(30, 64))
    healthy, shapes = np.zeros(64), rng.normal(size=(4, 64))
    whole = likelihood_ratio(X, healthy, shapes, "laplace")
    parts = [likelihood_ratio(X[r], healthy, shapes, "laplace") for r in np.array_split(np.arange(30), 10)]
    assert np.array_equal(whole, np.concatenate(parts))


def test_a_step_of_the_runs_own_process_that_cannot_count_says_for_how_long(monkeypatch):
    """The Bayes bound's first step loads torch in the run's process (5 s at load 11): a line under
    the bars that says for how long, gone when the step ends."""
    monkeypatch.setattr(ev, "STANDING_S", 0.5)
    clock, looks = Clock(monkeypatch, ev), Looks(monkeypatch)
    said: list[Event] = []
    with ev.standing(said.append, "bound", "loading torch"):
        looks.look()  # at 0 s: under STANDING_S, nothing new to say
        for clock.now in (1.0, 2.0):
            looks.look()
    messages = [e.message for e in said]
    assert messages[0] == "loading torch" and messages[-1] == ""
    assert {"loading torch (1 s)", "loading torch (2 s)"} <= set(messages) and {e.stage for e in said} == {"bound"}


def test_a_diagnosis_inside_a_unit_counts_its_steps_with_an_eta_on_the_units_line(monkeypatch):
    """A benchmark trial's diagnosis (stages_to_unit, minutes inside one unit) showed each stage's
    name alone: its steps now count on the unit's line, with an ETA after the first one."""
    now = iter([100.0, 130.0, 131.0, 132.0])  # the stage starts at 100 s, its first of 4 steps ends at 130 s
    monkeypatch.setattr(ev, "time", SimpleNamespace(monotonic=lambda: next(now)))
    said: list[str] = []
    with ev.saying(said.append):
        ev.stages_to_unit(Event("stage", stage="gap round 1", total=4, message="gap: round 1, fitting 4 effects"))
        ev.stages_to_unit(Event("advance", stage="gap round 1", done=1, total=4))
        ev.stages_to_unit(Event("advance", stage="gap round 1", done=4, total=4))
        ev.stages_to_unit(Event("advance", stage="another unit's stage", done=1, total=2))
    assert said == [
        "gap: round 1, fitting 4 effects: 0 of 4",
        "gap: round 1, fitting 4 effects: 1 of 4, ETA 1:30",
        "gap: round 1, fitting 4 effects: 4 of 4",
    ]


def test_a_gap_rounds_fits_say_for_how_long_they_have_run_beside_the_bar(monkeypatch):
    """A fit of a diagnosis's round takes 14-27 s on a busy machine; a transfer benchmark's trial sat
    silent that long between two steps of the round: a line beside the bar now says for how long."""
    from gearlab.gap.diagnose import run_fits

    monkeypatch.setattr(ev, "STANDING_S", 0.0)  # at once, not after 3 s
    clock, looks = Clock(monkeypatch, ev), Looks(monkeypatch)
    told: list[Event] = []

    def slow_map(work, tasks, advance):
        for clock.now in (0.0, 1.0):  # a look at 0 s and one a second later
            looks.look()
        return [work(t) for t in tasks]

    run = SimpleNamespace(on_event=told.append, executor=SimpleNamespace(map=slow_map))
    assert run_fits(run, "gap round 1", lambda t: 2 * t, [1, 2], None) == [2, 4]
    said = [e.message for e in told]
    assert {(e.kind, e.stage) for e in told} == {("unit", "gap round 1")} and len(said) >= 3
    assert said[0] == "fitting" and said[-1] == ""  # said at once, gone when the fits end
    assert all(re.fullmatch(r"fitting \(\d s\)", m) for m in said[1:-1])  # each second in between


def test_a_gap_rounds_fits_count_their_score_evaluations_on_the_line_beside_the_bar(monkeypatch):
    """The line said 'fitting (12 s)' alone through 14-27 s fits: it now counts the fits' score
    evaluations (every Scorer.score calls gearlab.gap.tally.counted) and their rate."""
    from gearlab.gap import tally
    from gearlab.gap.diagnose import run_fits

    monkeypatch.setattr(ev, "STANDING_S", 0.0)
    monkeypatch.setattr(tally, "WRITE_EVERY", 0.0)
    looks = Looks(monkeypatch)
    told: list[Event] = []

    def work(n):
        for _ in range(n):
            tally.counted()
            looks.look()  # the line looked at after each evaluation
        return n

    run = SimpleNamespace(on_event=told.append, executor=SimpleNamespace(map=lambda w, tasks, _: [w(t) for t in tasks]))
    assert run_fits(run, "gap round 1", work, [6, 8], None) == [6, 8]
    said = [e.message for e in told]
    counts = [re.fullmatch(r"fitting: (\d+) evaluations, \d+\.\d/s \(\d s\)", m) for m in said[1:-1]]
    assert said[0] == "fitting" and said[-1] == "" and counts and all(counts), said
    seen = [int(m.group(1)) for m in counts]
    assert seen == sorted(seen) and 0 < seen[0] < 14 and seen[-1] <= 14


def test_the_fits_evaluations_are_counted_across_worker_processes(tmp_path):
    """The fits run in the local pool's workers: each writes its count to a file of its own, which
    the run's process sums (gearlab.executors.FileCounts), and returns it with its result (the
    diagnosis's total); without, the workers' counts never reach the line. (Ray: test_executors.)"""
    from pool_units import evaluations

    from gearlab.executors import FileCounts, LocalExecutor
    from gearlab.gap.tally import Tallied

    with LocalExecutor(2) as pool:
        assert pool.map(Tallied(evaluations, FileCounts(str(tmp_path))), [5, 7, 9]) == [(5, 5), (7, 7), (9, 9)]
    assert FileCounts(str(tmp_path)).total() == 21 and len(list(tmp_path.glob("*.n"))) == 3


def test_the_gap_before_stage_loads_scikit_learn_under_a_line_of_its_own(monkeypatch):
    """scikit-learn's import (2.5-4.2 s on a busy machine) stood silent inside the classifier-AUC
    step of 'gap before': it now comes first, under its own line, gone when it ends."""
    import gearlab.gap.diagnose as d
    from gearlab.data.builder import build_dataset
    from gearlab.data.spec import dataset_preset
    from gearlab.gap.views import healthy_rows

    monkeypatch.setattr(d, "classifier_loaded", lambda: False)  # as in a fresh process
    source = dataset_preset("B-6-ch5").with_(faults=(), healthy=16)
    target = healthy_rows(build_dataset(source.with_(seed=5)))
    told: list[Event] = []
    settings = d.Settings(candidates=("sensor_noise",), healthy=16, bootstrap=5, permutations=19, budget=4)
    d.diagnose(source, target, settings, on_event=told.append)
    before = [(e.kind, e.done, e.message) for e in told if e.stage == "gap before"]
    loading = before.index(("unit", 0, "loading scikit-learn"))
    after = next(i for i in range(loading, len(before)) if before[i][0] != "unit")
    assert before[loading - 1][:2] == ("advance", 1) and before[after][:2] == ("advance", 2)
    assert before[after - 1] == ("unit", 0, "")  # gone before the report's first part ends


def test_a_diagnosis_inside_a_unit_shows_its_fits_evaluations_on_the_units_line(monkeypatch):
    """Inside a benchmark trial (stages_to_unit) the fits' line ('fitting: 577 evaluations, 5.8/s
    (99 s)', events.standing beside the stage's bar when the run diagnoses) was dropped: the unit's
    line showed the stage's count alone through minutes of fits. It now follows the count, and goes
    when the fits end."""
    from gearlab.gap import tally
    from gearlab.gap.diagnose import run_fits

    monkeypatch.setattr(ev, "STANDING_S", 0.0)
    monkeypatch.setattr(tally, "WRITE_EVERY", 0.0)
    looks = Looks(monkeypatch)

    def work(n):
        for _ in range(n):
            tally.counted()
            looks.look()  # the line looked at after each evaluation
        return n

    run = SimpleNamespace(
        on_event=ev.stages_to_unit, executor=SimpleNamespace(map=lambda w, tasks, _: [w(t) for t in tasks])
    )
    said: list[str] = []
    with ev.saying(said.append):
        ev.stages_to_unit(Event("stage", stage="gap round 1", total=2, message="gap: round 1, fitting 2 effects"))
        assert run_fits(run, "gap round 1", work, [6, 8], None) == [6, 8]
        ev.stages_to_unit(Event("advance", stage="gap round 1", done=2, total=2))
    head = "gap: round 1, fitting 2 effects: 0 of 2"
    assert said[:2] == [head, f"{head}; fitting"] and said[-2:] == [head, "gap: round 1, fitting 2 effects: 2 of 2"]
    counts = [
        re.fullmatch(re.escape(head) + r"; fitting: (\d+) evaluations, \d+\.\d/s \(\d s\)", m) for m in said[2:-2]
    ]
    assert counts and all(counts), said
    seen = [int(m.group(1)) for m in counts]
    assert seen == sorted(seen) and 0 < seen[0] < 14 and seen[-1] <= 14


def test_a_diagnosis_gives_its_total_of_score_evaluations(monkeypatch):
    """No total of a diagnosis's score evaluations was given anywhere (its fits' line counted them
    while they ran): the result holds it, every Scorer.score of the diagnosis and its fits, and a log
    line says it (the gap kind's log, a transfer benchmark's; a gap benchmark trial records it)."""
    import gearlab.gap.diagnose as d
    from gearlab.data.builder import build_dataset
    from gearlab.data.spec import dataset_preset
    from gearlab.effects import effect_spec
    from gearlab.gap.views import healthy_rows

    calls = []
    score = d.Scorer.score
    monkeypatch.setattr(d.Scorer, "score", lambda self, X: calls.append(1) or score(self, X))
    source = dataset_preset("B-6-ch5").with_(faults=(), healthy=16)
    noisy = source.with_(effects=(effect_spec("sensor_noise", kind="laplace", snr_db=5),), seed=11)
    told: list[Event] = []
    settings = d.Settings(
        candidates=("sensor_noise",), max_effects=1, healthy=16, bootstrap=20, permutations=99, budget=4
    )
    result = d.diagnose(source, healthy_rows(build_dataset(noisy)), settings, on_event=told.append)
    assert result["effects"] and result["evaluations"] == len(calls) > 20  # the fits' included
    logs = [e.message for e in told if e.kind == "log"]
    assert logs[-1] == f"gap: {len(calls)} score evaluations in {result['seconds']:.0f} s"


def test_the_simulations_bar_says_what_it_waits_for_before_its_first_step(monkeypatch):
    """A run's first simulation starts the workers, imports and compiles (13 s at load 6 on 2 cores):
    the bar stood at 0 of 13, 'ETA after the first step', with no sign why. Once that has stood
    STANDING_S a line says so beside the bar, gone at the first step; a quicker first step, none."""
    from collections import OrderedDict

    from gearlab.data import builder
    from gearlab.data.spec import dataset_preset

    real = builder.simulate_unit
    clock, looks = Clock(monkeypatch, ev, builder), Looks(monkeypatch)

    def slow(task):
        clock.now += 1.0  # a worker's start-up, looked at after a second
        looks.look()
        return real(task)

    def simulated(standing_s: float) -> list[tuple]:
        monkeypatch.setattr(ev, "STANDING_S", standing_s)
        monkeypatch.setattr(builder, "_SIMULATED", OrderedDict())  # simulated afresh
        told: list[Event] = []
        builder.build_dataset(dataset_preset("B-6-ch5").with_(faults=(), healthy=8), on_event=told.append)
        return [(e.kind, e.done, e.message) for e in told if e.stage == "simulate"]

    monkeypatch.setattr(builder, "simulate_unit", slow)
    seen = simulated(0.5)
    line = "the first one starts up: imports, compiled loops"
    assert seen[0] == ("stage", 0, "B-6-ch5: 1 simulations") and seen[-2:] == [("unit", 0, ""), ("advance", 1, "")]
    assert seen[1:-2] and all(re.fullmatch(re.escape(line) + r" \(\d s\)", m) for _, _, m in seen[1:-2]), seen
    assert [k for k, _, _ in simulated(1000.0)] == ["stage", "advance"]  # no line flashes by
