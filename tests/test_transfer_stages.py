"""The `transfer` kind tells its front-end every step (issue 41: no stage silent for more than 5 s):
the Bayes bound, which takes seconds (the target's noise-free twin, its likelihood ratios), is a
stage of its own between the datasets and the training runs; the shared states say their epochs;
the figures and report.html (every kind's last step, gearlab.events.telling_figures) are a stage."""

from __future__ import annotations

import pytest
from tiny import transfer

from gearlab.engine import run_scenario
from gearlab.parts.bound import STEPS


def test_the_bayes_bound_and_the_report_are_stages_of_their_own(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "tiny.toml"
    path.write_text(transfer('[[methods]]\nadapter = "source_only"\n', max_epochs=2))
    events = []
    run = run_scenario(path, out=tmp_path / "runs", on_event=events.append)
    assert (run.path / "bound.json").exists()  # the tiny target is simulated with noise: there is a bound
    stages = [(e.kind, e.stage) for e in events if e.kind in ("stage", "advance") and e.stage]
    assert ("stage", "bound") in stages and ("advance", "bound") in stages
    begin, end = stages.index(("stage", "bound")), stages.index(("advance", "bound"))
    done = max(i for i, s in enumerate(stages) if s == ("advance", "datasets"))
    assert done < begin < end < stages.index(("stage", "runs"))  # after the datasets, before the runs
    bound_logs = [e for e in events if e.kind == "log" and "Bayes bound" in e.message]
    assert bound_logs  # what the stage does is said while it runs
    # in steps with a total (the twin, then tenths of the target's revolutions): an ETA after the first
    bound = [e for e in events if e.stage == "bound" and e.kind in ("stage", "advance")]
    assert {e.total for e in bound} == {STEPS} and STEPS > 2
    assert [e.done for e in bound if e.kind == "advance"] == [*range(1, STEPS + 1), STEPS]
    # the run's end (its figures, then report.html) is a stage of its own too, started before
    # matplotlib loads: i of n, n the figures announced before the first is drawn, and report.html
    figures = sorted(p.name for p in (run.path / "figures").iterdir())
    report = [e for e in events if e.stage == "report"]
    n = len(figures) + 1
    assert stages.index(("stage", "report")) > max(i for i, s in enumerate(stages) if s == ("advance", "runs"))
    assert report[0].kind == "stage" and report[0].done == 0 and report[0].message == "figures and report.html"
    assert [(e.done, e.total) for e in report[1:]] == [(i, n) for i in range(n)] + [(n, n)] and n >= 3


def test_the_priming_and_the_source_model_say_how_far_they_are():
    """The shared states a repetition's first units train (the priming of the calibrated methods,
    the source-only model) took a minute of a quick run's 'priming 0/4' with no line under the bar
    (issue 41): their epochs reach the unit's progress as 'priming, epoch i of n'."""
    from test_protocol import SOURCE, TARGET, method, tiny

    from gearlab.learn.protocol import StateStore, run_unit

    p = tiny(methods=(method("source_only"), method("mmd")), prime_epochs=2, baseline_epochs=3, patience=3)
    for m, what in zip(p.methods, ("source model, epoch {} of 3", "priming, epoch {} of 2")):
        said: list[str] = []
        run_unit(p, SOURCE, TARGET, 0, 0, m, StateStore(None), on_epoch=lambda e, h, text="", to=said: to.append(text))
        shared = [t for t in said if t]  # the unit's own epochs say nothing more (text "")
        assert shared == [what.format(i) for i in range(1, 4 if m.adapter == "source_only" else 3)], (m, said)


def test_a_training_unit_says_it_started_before_it_loads_torch_and_the_data(tmp_path, monkeypatch):
    """A unit in a fresh worker imports torch and reads its datasets (seconds on a busy machine) before
    its first epoch can say anything: it says it started first."""
    from test_protocol import method, tiny

    from gearlab.confined import Confined
    from gearlab.data import cache
    from gearlab.events import UnitProgress
    from gearlab.parts import training

    said = []
    monkeypatch.setattr(UnitProgress, "__call__", lambda self, text: said.append(text))

    def load(spec, path):
        said.append("load")
        raise RuntimeError("stop here")

    monkeypatch.setattr(cache, "load", load)
    task = (tiny(), (None, None), (None, None), 0, 0, method("mmd"), Confined(tmp_path, ("states",)))
    with pytest.raises(RuntimeError, match="stop here"):
        training.train_unit(task)
    assert said == ["starting: importing torch", "starting: reading dataset 1 of 2 (source)", "load"]
